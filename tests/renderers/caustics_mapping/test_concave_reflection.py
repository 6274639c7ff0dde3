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
from harness.checks.physical import (
    ESTIMATOR_FAILED_BOUND,
    FLUX_TOLERANCE,
    ratio_interval,
    seed_flux_interval,
)
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
#: estimator-failed share of the traced flux). None: the last two closed with the tight
#: view's border, patches of 5 on conductors and the reference's leak test
#: (bowl_shallow_sun45: 1.076 -> 0.9995; bowl_shallow_sun60, whose reference floor light
#: was photons leaking through the bowl: now dark, like the method's).
GAPS: dict[str, str] = {}
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
        low, high = ratio_interval(ratio, relative[channel], quantile)
        verdict = judge("band", FLUX_TOLERANCE, ratio, (low, high))
        assert verdict == "holds", (
            f"channel {'RGB'[channel]}: flux ratio {ratio:.4f} [{low:.4f}, {high:.4f}] "
            f"is {verdict} against 1 ± {FLUX_TOLERANCE}")


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


def _exact_changes(scene, geometry, on, off):
    """How the vertices whose status an option changes fare on their exact rays
    (Mitsuba's, from 0.1 mm along the ray): the floor's flux with the option on, and
    the flux (summed over RGB) of the vertices it splats that were not splatted
    without it, and of those it no longer splats, whose exact ray meets the object
    or a receiver first. Every vertex whose status it keeps keeps its record."""
    hit = caustic_trace.STATUS["hit"]
    tracer = SurfaceTracer(scene, geometry)
    out = {"floor": 0.0, "gained object": 0.0, "gained floor": 0.0,
           "lost object": 0.0, "lost floor": 0.0}
    for part in ("hits", "patches"):
        before, after = getattr(off, part), getattr(on, part)
        flux = after["flux"].sum(axis=1) * after["share"]
        out["floor"] += flux[after["status"] == hit].sum()
        same = after["status"] == before["status"]
        for key in ("distance", "hit", "flux", "receiver"):
            np.testing.assert_array_equal(after[key][same], before[key][same], err_msg=key)
        for label, changed in (("gained", ~same & (after["status"] == hit)),
                               ("lost", ~same & (before["status"] == hit))):
            direction = after["direction"][changed].astype(np.float64)
            direction /= np.linalg.norm(direction, axis=1, keepdims=True)
            exact = tracer(after["origin"][changed] + 1e-4 * direction, direction)
            out[f"{label} object"] += flux[changed][exact.kind == SurfaceTracer.OBJECT].sum()
            out[f"{label} floor"] += flux[changed][exact.kind == SurfaceTracer.RECEIVER].sum()
    return out


def _gains_floor_light(context_factory, monkeypatch, name, option):
    """:func:`_exact_changes` of ``option`` on the member ``name``, having checked
    that the vertices it splats carry at least 1 % of the floor's flux whose exact
    rays reach the floor, and meet the object first for at most
    ``ESTIMATOR_FAILED_BOUND`` of it (the allowance for light the method wrongly
    splats or drops)."""
    scene, geometry, on, off = _with_and_without(context_factory, monkeypatch, name, option)
    fate = _exact_changes(scene, geometry, on, off)
    floor = fate["floor"]
    assert fate["gained floor"] >= 0.01 * floor, f"{fate['gained floor'] / floor:.4f}"
    assert fate["gained object"] <= ESTIMATOR_FAILED_BOUND * floor
    return fate


@pytest.mark.physical_requirement
def test_the_depth_spread_keeps_grazing_light_and_ends_light_at_the_contact(context_factory,
                                                                          monkeypatch):
    """Physical requirement: the vertices whose fate the depth spread changes
    (``TraceOptions.depth_spread``, on in the strong preset: the crossing test takes a
    sample behind a sheet by less than the sheet's depth across half a texel as on
    neither side; the contact test takes that spread as its tolerance) go where their
    exact rays go. On the shallow bowl under a 45 deg sun (grid 128) those it splats
    carry at least 1 % of the floor's flux (measured 3.3 %: grazing reflections off
    the outer wall, judged crossing the wall they run along), and at most 1 % of the
    floor's flux (``ESTIMATOR_FAILED_BOUND``, the allowance for light the method
    wrongly splats or drops) meets the bowl first (measured 0); those it no longer
    splats (reflections off the inside landing a few centimetres from where the bowl
    rests on the floor) reach the floor first for at most 1 % of it (measured 0) and
    meet the bowl for some of it (measured 0.5 %)."""
    fate = _gains_floor_light(context_factory, monkeypatch, "bowl_shallow_sun45",
                              "depth_spread")
    assert fate["lost floor"] <= ESTIMATOR_FAILED_BOUND * fate["floor"]
    assert fate["lost object"] > 0


@pytest.mark.physical_requirement
def test_a_reflection_under_the_near_wall_leaves_by_the_open_end(context_factory,
                                                                monkeypatch):
    """Physical requirement: on the half-pipe under a 20 deg sun (grid 128), the
    reflected-search hits that pass behind the near wall the light sees and leave the
    pipe's bounding box through its open end (``TraceOptions.open_escape``, on in the
    strong preset; held back as unconverged without it) carry at least 1 % of the
    floor's flux (measured 1.6 %: without them the flux ratio was 0.985), and meet the
    pipe first for at most 1 % of the floor's flux (``ESTIMATOR_FAILED_BOUND``;
    measured 0.015 %); no vertex it leaves alone changes."""
    fate = _gains_floor_light(context_factory, monkeypatch, "halfpipe_sun20", "open_escape")
    assert fate["lost object"] + fate["lost floor"] == 0


@pytest.mark.physical_requirement
def test_crossings_are_sampled_where_the_object_is(context_factory, monkeypatch):
    """Physical requirement: a reflection off the shallow bowl's rim under a 60 deg
    sun runs nearly level across the bowl to its far wall and on 5 to 8 m to the
    floor; sampled over that whole length (48 samples, 14 cm apart) the crossing of
    the far wall falls between two samples, the second already off the bowl's
    silhouette. Sampled over the ray's part inside the bowl's bounding box
    (``TraceOptions.box_samples``, on in the strong preset) it is seen: the vertices
    the option no longer splats (grid 128: measured 10) meet the bowl first on their
    exact rays, and none reaches the floor first."""
    scene, geometry, on, off = _with_and_without(context_factory, monkeypatch,
                                                 "bowl_shallow_sun60", "box_samples")
    fate = _exact_changes(scene, geometry, on, off)
    assert fate["lost object"] > 0
    assert fate["lost floor"] == 0
    assert fate["gained object"] + fate["gained floor"] == 0
