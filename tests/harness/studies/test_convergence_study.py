"""The convergence study on the real renderer: the table is complete, the paper's
estimator converges on glass_sphere, and the safeguard holds on every hard case."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest

from harness.studies.convergence_study import CONFIGS, convergence_study
from harness.studies.runner import RealtimeRunner
from scenes import load_scene, with_settings
from tests.conftest import SCENES

#: Small but not degenerate: 64² grid, 256² maps (texel footprints of ~3 cm).
SMALL = {"grid": 64, "caustic_map": 256, "positions_map": 256, "shadow_map": 128,
         "receiver_map": [64, 64]}


def _scene(path):
    scene = with_settings(load_scene(path), SMALL)
    return dataclasses.replace(scene, camera=dataclasses.replace(scene.camera,
                                                                 resolution=(32, 32)))


def _rows(table):
    return [dict(zip(table.columns, row, strict=True)) for row in table.rows]


def _study(path, configs, iterations=8):
    flat = np.ones((64, 64, 3))  # image error is not under test here
    with RealtimeRunner(_scene(path), repeats=1) as runner:
        return _rows(convergence_study(runner, flat, np.ones((64, 64), bool),
                                       max_iterations=iterations, configs=configs))


def test_glass_sphere_table_is_complete_and_modified_converges():
    """Rows for every estimator, plain and safeguarded, at every iteration 0..8; the
    modified estimator's mean and p95 hit error fall at each of iterations 0 → 3
    (the paper's fixed-point update contracts on a sphere over a plane)."""
    rows = _study(SCENES / "glass_sphere.toml", CONFIGS)
    keys = {(r["estimator"], r["safeguarded"], r["iteration"]) for r in rows}
    assert keys == {(e, s, k) for e, s in CONFIGS for k in range(9)}
    modified = {r["iteration"]: r for r in rows
                if r["estimator"] == "modified" and not r["safeguarded"]}
    for metric in ("mean_error_texels", "p95_error_texels"):
        values = [modified[k][metric] for k in range(4)]
        assert all(b < a for a, b in itertools.pairwise(values)), (metric, values)
    assert all(np.isfinite(r["time_ms"]) and r["time_ms"] > 0 for r in rows)
    assert modified[0]["lookups_per_vertex"] == 1 and modified[3]["lookups_per_vertex"] == 4


HARD = sorted((SCENES / "hard").glob("*.toml"))


@pytest.mark.parametrize("path", HARD, ids=lambda p: p.stem)
def test_safeguarded_newton_never_diverges_on_hard_cases(path):
    """Physical requirement (numerical stability): safeguarded Newton on every hard
    case, 0..8 iterations: no vertex diverges or oscillates at any iteration count,
    judged from the history of its estimates against exact ray casts
    (harness.studies.convergence.classify; the safeguarded renderer never assigns
    the status "diverged" itself). The judgement can fail: the plain form oscillates
    on the oscillation hard case (test_plain_newton_oscillation_is_detected)."""
    for row in _study(path, (("newton", True),)):
        assert row["diverged"] == 0.0, row
        assert row["oscillating"] == 0.0, row


def test_plain_newton_oscillation_is_detected():
    """On the oscillation hard case the plain Newton-Raphson update jumps between two
    estimates for a sizeable share of vertices (measured 28 % at 8 iterations on
    this 64² grid; asserted > 5 %), and the safeguard removes all of it."""
    rows = _study(SCENES / "hard" / "newton_oscillation.toml",
                  (("newton", False), ("newton", True)), iterations=8)
    last = {r["safeguarded"]: r for r in rows if r["iteration"] == 8}
    assert last[False]["oscillating"] > 0.05
    assert last[True]["oscillating"] == 0.0
