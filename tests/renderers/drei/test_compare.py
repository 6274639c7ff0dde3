"""drei-caustics through the whole comparison pipeline (``harness.api.compare``, as
``caustics compare --method drei-caustics`` runs it): it writes ``metrics.json`` and a
page, and the flux ratio there is the method's map against the reference's.

Slow: it traces a (small) reference. Kind: physical requirement (flux accounted)."""

from __future__ import annotations

import json

import pytest

from harness import api
from renderers.drei.method import DreiMethod

pytestmark = [pytest.mark.slow, pytest.mark.physical_requirement]

#: A small reference.
SETTINGS = {"photons": 2**18, "seeds": 2}


def test_compare_writes_metrics_and_a_page(tmp_path, chromium, drei, small_sun):
    method = DreiMethod(browser=chromium, repeats=1)
    done = api.compare(small_sun, [method], studies=("metrics",), quick=True,
                       settings=SETTINGS, output=tmp_path / "out")
    comparison = done.get("drei-caustics")
    folder = comparison.page.parent
    metrics = json.loads((folder / "metrics.json").read_text())
    assert (folder / "index.html").is_file()
    assert metrics["method"]["name"] == "drei-caustics"
    # The ratio is the method's map flux (the texture's, the same page render as the
    # `drei` fixture's) over the reference's own, read from the cache.
    reference = api.render_reference(small_sun, settings=SETTINGS)
    expected = (drei.result.receivers[0].total_flux()[0]
                / reference.receivers[0].total_flux()[0])
    assert comparison.metric("flux_ratio", region="full").value == pytest.approx(
        expected, rel=1e-5)
