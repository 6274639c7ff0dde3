"""Every scene in scenes/ and scenes/hard/ renders with every estimator: no NaN or Inf
in any output and no GL error (the ``ctx`` fixture checks GL_NO_ERROR)."""

from __future__ import annotations

import numpy as np
import pytest

from harness.checks.stability import estimate_outcomes
from renderers.caustics_mapping import render_frame
from renderers.caustics_mapping.caustic_trace import STATUS
from scenes.geometry import build_geometry

from .conftest import SCENES, small_scene


def _finite(name, array):
    assert np.all(np.isfinite(array)), f"{name} holds NaN or Inf"


@pytest.mark.parametrize("estimator", ["modified", "newton", "secant"])
@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.stem)
def test_scene_renders_finite(ctx, path, estimator):
    """Camera image, receiver maps, caustic map and every hits array are finite, the
    receiver maps are non-negative, the splatted flux is the receiver maps' flux
    on planar receivers (conservation; rtol 1e-3 = float32 accumulation over ~1e4
    splats) and bounds it on curved ones (maps are per m² of surface), and lost
    splats are counted in the metadata, never splatted."""
    frame = render_frame(small_scene(path, estimator=estimator), ctx=ctx)
    result = frame.result
    _finite("camera", result.camera)
    _finite("caustic map", frame.caustic_map)
    for key, array in frame.hits.items():
        _finite(f"hits[{key}]", array)
    for receiver in result.receivers:
        _finite("receiver map", receiver.irradiance)
        assert receiver.irradiance.min() >= 0
    assert result.camera.min() >= 0
    # Maps hold irradiance per m² of surface; integrated over (u, v) area they give
    # Σ flux / J with J = dA / (du dv) ≥ 1, equal to 1 on planes only.
    total = sum(r.total_flux() for r in result.receivers)
    splatted = np.asarray(result.metadata["splatted_flux"])
    if all(r.kind == "plane" for r in small_scene(path, estimator=estimator).receivers):
        np.testing.assert_allclose(total, splatted, rtol=1e-3, atol=1e-12)
    else:
        assert np.all(total <= splatted * (1 + 1e-3) + 1e-12)
    assert result.metadata["lost_splats"] == int(np.sum(frame.hits["status"] == STATUS["lost"]))


def test_safeguarded_runs_on_newton_oscillation(ctx):
    """Physical requirement (numerical stability) on the Newton-oscillation hard case,
    judged from the history of the estimates against exact ray casts
    (``harness.checks.stability.estimate_outcomes``), not from the status the
    renderer assigns (which never says "diverged" for a run that oscillates): plain
    Newton oscillates on a sizeable share of vertices (measured 35 % of 1,100 at
    grid 48 and 8 iterations; asserted > 5 %, so the judgement can fail), and the
    safeguarded form leaves no vertex diverged or oscillating. Both finite."""
    path = next(p for p in SCENES if p.stem == "newton_oscillation")
    outcomes = {}
    for safeguarded in (False, True):
        scene = small_scene(path, safeguarded=safeguarded)
        frame = render_frame(scene, ctx=ctx)
        for key, array in frame.hits.items():
            _finite(f"hits[{key}]", array)
        outcomes[safeguarded] = estimate_outcomes(scene, build_geometry(scene), frame.hits)
    assert outcomes[True]["count"] > 500 and outcomes[False]["count"] > 500
    assert outcomes[False]["oscillating"] + outcomes[False]["diverged"] > 0.05, outcomes[False]
    assert outcomes[True]["diverged"] == 0.0 and outcomes[True]["oscillating"] == 0.0, \
        outcomes[True]


def test_receiver_edge_counts_lost_splats(ctx):
    """Rays leaving the small floor of receiver_edge are dropped and counted."""
    path = next(p for p in SCENES if p.stem == "receiver_edge")
    frame = render_frame(small_scene(path), ctx=ctx)
    assert frame.result.metadata["lost_splats"] > 0
    assert frame.result.metadata["lost_flux"][0] > 0
