"""The concave reflectors' hard cases (``scenes/hard/concave``): a polished
hemispherical bowl (deep) and a spherical cap of half its depth (shallow) under suns
15 to 75 deg high, and a half-pipe under a 20 deg sun; the reference counts one chain,
``L R D`` (objects[0]). Physical requirements on the strong preset, per member:

* flux agreement: the receiver-map flux / a fresh photon-traced reference's, per RGB
  channel, within ``FLUX_TOLERANCE`` (2 %), judged from the ratio's 95 % interval as
  ``caustics compare`` judges it (``harness.checks.bounds.judge``; the reference
  total's standard error from its per-seed totals,
  ``harness.checks.physical.seed_flux_interval``; grid 128, small maps, 4 seeds of
  2^20 photons): the whole interval within 1 ± 2 %;
* the estimator found the receiver: the share of the traced flux whose search ended
  without a verified hit while its exact ray meets a receiver first
  (``estimator_failed_flux_fraction`` of ``harness.checks.stability.search_outcomes``)
  is at most 1 % (the bound the budget's "estimator failed" row is held to).

A member that misses either today is a known gap (a strict xfail: it fails once the gap
closes, until the entry goes), with its measured numbers (llvmpipe, these settings)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.special import stdtrit

from harness.checks.bounds import judge
from harness.checks.physical import ESTIMATOR_FAILED_BOUND, FLUX_TOLERANCE, seed_flux_interval
from harness.checks.stability import search_outcomes
from harness.raycast import SurfaceTracer
from renderers.caustics_mapping import caustic_trace, light_sample, render_frame
from renderers.mitsuba.reference import estimate_receivers
from scenes.geometry import build_geometry

from .conftest import ROOT, small_scene

CONCAVE = ROOT / "scenes" / "hard" / "concave"
#: Photons per seed of the reference: one whole launch (relative standard error of the
#: total ~0.1 % where the floor's caustic is not small).
PHOTONS = 1 << 20
#: Largest share of the traced flux the estimator may leave unfound while its exact
#: ray meets a receiver: 1 %, half the flux agreement's 2 % tolerance.
FAILED_BOUND = 0.01

#: Members missing a requirement today: what is wrong, measured (flux ratio, G channel;
#: estimator-failed share of the traced flux).
GAPS = {
    "bowl_shallow_sun45": (
        "flux 1.076 (bound: the 95 % interval within 1 ± 0.02): the floor gets 0.4 % of the "
        "traced flux, from the outer wall's lit sliver between the rim and the terminator "
        "(|l.n| < 0.14), under one grid step wide along the light view's outline. Two "
        "errors: the lattice, whose vertices' exact rays at their own flux put 1.099, "
        "1.031, 0.998 of the reference's flux on the floor at grid 128, 256, 512 (exact "
        "paths through the method's view at 1, 3 and 9 times the grid: 1.052, 1.013, 1.004 "
        "with sd 0.157, 0.032, 0.009 over 5 random phases); and grazing reflections the "
        "crossing test still ends as re-entered though their exact rays reach the floor, "
        "2.7 %, 1.7 %, 6.2 % of the method's floor flux (6.0 % at grid 128 before its "
        "direction rule): the method's flux 1.076, 1.019, 0.948. Missing: the sliver sampled "
        "as at grid 512, and a crossing test that resolves a ray running within a texel of "
        "an edge-on sheet"),
    "bowl_shallow_sun60": (
        "flux 0: the reference puts 7.2e-6 W (5.5e-7 of the method's traced flux) on 6 "
        "floor texels, the method nothing. That total rests on a few photons: its relative "
        "standard error from 4 seeds of 2^20 photons is 1.0 (0.33 from 4 of 2^22), so no "
        "method's ratio can be shown within 2 % short of some 5e10 photons; at grid 256 "
        "the method puts 44 times the reference's flux there, all of it from vertices "
        "whose exact rays meet the bowl first"),
}
#: The deep bowl under a 30 deg sun (the case that first showed the loss) and the member
#: the grazing band of the rim patches closed (75 deg, rim_patches.GRAZING_COS) run by
#: default, about a second each; the rest of the family is slow.
DEFAULT = {"bowl_deep_sun30", "bowl_deep_sun75"}
MEMBERS = sorted(p.stem for p in CONCAVE.glob("*.toml"))


def _param(name):
    marks = []
    if name in GAPS:
        marks.append(pytest.mark.xfail(strict=True, reason=GAPS[name]))
    if name not in DEFAULT:
        marks.append(pytest.mark.slow)
    return pytest.param(name, marks=marks, id=name)


@pytest.mark.regression_lock
def test_the_family_is_what_the_docs_list():
    """Regression lock: 5 elevations x 2 depths of bowl and one half-pipe."""
    assert len(MEMBERS) == 11 and set(GAPS) <= set(MEMBERS)


@pytest.mark.physical_requirement
@pytest.mark.parametrize("name", [_param(n) for n in MEMBERS])
def test_strong_finds_the_concave_reflection(context_factory, name):
    """Physical requirements: flux agreement per channel and the estimator-failed share
    at most 1 % (before the reflected search the 30 deg deep bowl was at flux 0.47,
    estimator failed 17.5 %)."""
    scene = small_scene(CONCAVE / f"{name}.toml", preset="strong", grid=128,
                        caustic_map=256, positions_map=256, receiver_map=[128, 128], seeds=4)
    geometry = build_geometry(scene)
    frame = render_frame(scene, ctx=context_factory(), geometry=geometry)
    failed = search_outcomes(scene, geometry, frame.traced_records())[
        "estimator_failed_flux_fraction"]
    method = sum(m.total_flux() for m in frame.result.receivers)
    reference = estimate_receivers(scene, photons=PHOTONS, seeds=4, time_cap=1e-3,
                                   caustic_only=True)
    expected = sum(m.total_flux() for m in reference.caustic)
    relative, dof = seed_flux_interval(reference.caustic)
    quantile = float(stdtrit(dof, 0.975))
    assert failed <= FAILED_BOUND, f"estimator failed on {failed:.4f} of the traced flux"
    for channel in range(3):
        if expected[channel] <= 0:
            # A channel the reference leaves dark (the shallow bowl under a high sun)
            # allows no flux at all.
            assert method[channel] == 0, f"channel {'RGB'[channel]}: {method[channel]} W"
            continue
        ratio = method[channel] / expected[channel]
        half = quantile * relative[channel] * ratio
        verdict = judge("band", FLUX_TOLERANCE, ratio, (ratio - half, ratio + half))
        assert verdict == "holds", (
            f"channel {'RGB'[channel]}: flux ratio {ratio:.4f} [{ratio - half:.4f}, "
            f"{ratio + half:.4f}] is {verdict} against 1 ± {FLUX_TOLERANCE}")


@pytest.mark.regression_lock
def test_the_search_changes_only_what_the_estimator_left_unverified(context_factory,
                                                                      monkeypatch):
    """Regression lock: with the reflected search and the contact test off
    (``TraceOptions``), every vertex the estimator verified as a hit on the 30 deg
    deep bowl keeps its record bit for bit with them on, but for the hits the contact
    test ends (status ``reentered``, the estimate kept); and the search turns a part of
    the unconverged vertices into hits (17.5 % of the traced flux on these settings)."""
    scene = small_scene(CONCAVE / "bowl_deep_sun30.toml", preset="strong", grid=64)
    on = render_frame(scene, ctx=context_factory()).hits
    options = caustic_trace.trace_options
    monkeypatch.setattr(light_sample, "trace_options", lambda s, e: dataclasses.replace(
        options(s, e), reflected_search=False, contact_test=False))
    off = render_frame(scene, ctx=context_factory()).hits
    hit, reentered = caustic_trace.STATUS["hit"], caustic_trace.STATUS["reentered"]
    kept = off["status"] == hit
    assert kept.sum() > 100
    assert np.isin(on["status"][kept], [hit, reentered]).all()
    same = kept & (on["status"] == hit)
    for key in ("distance", "hit", "flux", "receiver"):
        np.testing.assert_array_equal(on[key][same], off[key][same], err_msg=key)
    np.testing.assert_array_equal(on["distance"][kept], off["distance"][kept])
    found = (off["status"] == caustic_trace.STATUS["unconverged"]) & (on["status"] == hit)
    assert found.sum() > 0.1 * kept.sum()


def _with_and_without(context_factory, monkeypatch, name, option):
    """The member ``name`` (strong, grid 128, 256² maps), its geometry, and its frames
    with the trace option ``option`` on (the preset's) and off."""
    scene = small_scene(CONCAVE / f"{name}.toml", preset="strong", grid=128,
                        caustic_map=256, positions_map=256, receiver_map=[128, 128])
    geometry = build_geometry(scene)
    on = render_frame(scene, ctx=context_factory(), geometry=geometry)
    options = caustic_trace.trace_options
    monkeypatch.setattr(light_sample, "trace_options", lambda s, e: dataclasses.replace(
        options(s, e), **{option: False}))
    return scene, geometry, on, render_frame(scene, ctx=context_factory(), geometry=geometry)


@pytest.mark.physical_requirement
def test_a_reflection_below_its_own_triangle_meets_the_bowl_again(context_factory,
                                                                   monkeypatch):
    """Physical requirement: the vertices the facet-side test ends (a reflected ray
    that leaves below the plane of its own triangle; ``TraceOptions.facet_side_test``,
    on in the strong preset) are light the reference does not count. On the 75 deg
    deep bowl (grid 128) their exact rays (Mitsuba's, from 0.1 mm along the ray: the
    records' float32 origins lie on the surface; the nearest second hit measured was
    4.5 mm away) meet the bowl again for at least 0.5 % of the floor's flux (measured
    1.11 %: without the test these were splatted as floor hits), and reach the floor
    for at most 1 % of it (``ESTIMATOR_FAILED_BOUND``, the allowance for light the
    method wrongly leaves unsplatted; measured 0.09 %)."""
    scene, geometry, on, off = _with_and_without(context_factory, monkeypatch,
                                                 "bowl_deep_sun75", "facet_side_test")
    hit, reentered = caustic_trace.STATUS["hit"], caustic_trace.STATUS["reentered"]
    tracer = SurfaceTracer(scene, geometry)
    floor = meets_bowl = meets_floor = 0.0
    for part in ("hits", "patches"):
        before, after = getattr(off, part), getattr(on, part)
        flux = before["flux"].sum(axis=1) * before["share"]
        floor += flux[before["status"] == hit].sum()
        ended = (after["status"] == reentered) & (before["status"] != reentered)
        direction = before["direction"][ended].astype(np.float64)
        direction /= np.linalg.norm(direction, axis=1, keepdims=True)
        exact = tracer(before["origin"][ended] + 1e-4 * direction, direction)
        meets_bowl += flux[ended][exact.kind == SurfaceTracer.OBJECT].sum()
        meets_floor += flux[ended][exact.kind == SurfaceTracer.RECEIVER].sum()
    assert meets_bowl >= 0.005 * floor, f"{meets_bowl / floor:.4f} of the floor's flux"
    assert meets_floor <= ESTIMATOR_FAILED_BOUND * floor, f"{meets_floor / floor:.4f}"


@pytest.mark.physical_requirement
def test_the_crossing_test_keeps_only_grazing_light_that_reaches_the_floor(context_factory,
                                                                          monkeypatch):
    """Physical requirement: the reflected vertices that the crossing test's direction
    rule keeps (``TraceOptions.crossing_direction``, on in the strong preset: ended as
    re-entered without it, splatted with it) are light the reference counts. On the
    shallow bowl under a 45 deg sun (grid 128) they carry at least 1 % of the floor's
    flux (measured 3.1 %: grazing reflections off the outer wall, judged crossing the
    wall they leave), and their exact rays (Mitsuba's, from 0.1 mm along the ray) meet
    the bowl first for at most 1 % of what they carry (``ESTIMATOR_FAILED_BOUND``, the
    allowance for light the method wrongly splats; measured 0). Every other vertex
    keeps its status and record, but for re-entered reflections of the receiver
    search that its stricter test then holds back (``stays_in_front``: unconverged)."""
    scene, geometry, on, off = _with_and_without(context_factory, monkeypatch,
                                                 "bowl_shallow_sun45", "crossing_direction")
    status = caustic_trace.STATUS
    tracer = SurfaceTracer(scene, geometry)
    floor = kept = meets_bowl = 0.0
    for part in ("hits", "patches"):
        before, after = getattr(off, part), getattr(on, part)
        flux = after["flux"].sum(axis=1) * after["share"]
        floor += flux[after["status"] == status["hit"]].sum()
        now_hit = (after["status"] == status["hit"]) & (before["status"] == status["reentered"])
        held = (after["status"] == status["unconverged"]) & (
            before["status"] == status["reentered"])
        same = after["status"] == before["status"]
        assert (same | now_hit | held).all()
        for key in ("distance", "hit", "flux", "receiver"):
            np.testing.assert_array_equal(after[key][same], before[key][same], err_msg=key)
        direction = after["direction"][now_hit].astype(np.float64)
        direction /= np.linalg.norm(direction, axis=1, keepdims=True)
        exact = tracer(after["origin"][now_hit] + 1e-4 * direction, direction)
        kept += flux[now_hit].sum()
        meets_bowl += flux[now_hit][exact.kind == SurfaceTracer.OBJECT].sum()
    assert kept >= 0.01 * floor, f"kept {kept / floor:.4f} of the floor's flux"
    assert meets_bowl <= ESTIMATOR_FAILED_BOUND * kept, f"{meets_bowl / kept:.4f}"
