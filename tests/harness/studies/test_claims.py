"""The paper's claims are stated with numbers, whichever way they fall."""

from __future__ import annotations

from harness.studies.claims import check_five_iterations, check_one_iteration


def test_five_iterations_both_ways():
    holds, text = check_five_iterations({0: 40.0, 5: 0.4})
    assert holds and text.startswith("holds") and "0.4 texels" in text
    holds, text = check_five_iterations({0: 40.0, 5: 3.0})
    assert not holds and text.startswith("does not hold")
    assert check_five_iterations({0: 1.0})[0] is False


def test_one_iteration_both_ways():
    holds, text = check_one_iteration({0: 0.5, 1: 0.105, 8: 0.1})
    assert holds and "ratio 1.050" in text
    holds, _ = check_one_iteration({0: 0.5, 1: 0.2, 8: 0.1})
    assert not holds
