"""Flux budgets of both sides (harness/compare/budget.py, the reference's from
harness/compare/probe.py's caustic-only trace): every watt each side sends toward
the object is accounted for, on real renders of the bundled glass_sphere and bunny."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from harness.compare.budget import budget_closure, method_budget, reference_budget_table
from harness.compare.headlines import BUDGET_CLOSURE
from harness.compare.probe import BUDGET_PHOTONS, probe_caustic, reference_budget
from renderers.caustics_mapping import render_frame
from renderers.methods import load_method
from renderers.mitsuba import load_mitsuba
from renderers.mitsuba.emission import bounding_sphere
from renderers.mitsuba.photons import BUDGET_ITEMS, PhotonTracer
from scenes import load_scene, with_settings
from scenes.geometry import build_geometry
from tests.conftest import SCENES

#: Small method renders: a 48-vertex grid and 128-texel maps keep one render under
#: two seconds on llvmpipe; the budget's closure does not depend on the sizes.
SMALL = {"grid": 48, "caustic_map": 128, "positions_map": 128, "shadow_map": 128,
         "receiver_map": [48, 48]}


def _scene(name: str, **settings):
    scene = load_scene(SCENES / f"{name}.toml")
    scene = dataclasses.replace(scene, camera=dataclasses.replace(scene.camera,
                                                                  resolution=(16, 16)))
    return with_settings(scene, settings) if settings else scene


@pytest.mark.parametrize("preset", ["paper", "strong"])
@pytest.mark.parametrize("name", ["glass_sphere", "bunny"])
def test_method_budget_adds_up_to_the_emitted_flux(name, preset):
    """Physical requirement: the flux the method traces through its object grid
    (the vertices' flux, I dω each) is lost, reflected totally, held back, diverged,
    left without an exit, or splatted, and the splats put exactly their flux on
    the receiver maps (the kernels integrate to one over receiver area): so the
    non-hit statuses (from the per-vertex records) plus the flux measured on the
    maps (Σ E · texel area, from the images) add up to the emitted flux within
    BUDGET_CLOSURE (1e-3; measured 1e-5 to 1e-6 on both scenes and presets at grid
    64). A kernel that lost or gained flux, or a status left out, fails it. Not
    vacuous: the maps hold over half of the emitted flux, and the bunny's paper
    preset loses a tenth or more to total internal reflection. The records are the
    grid's and the strong preset's rim patches', each at the share of its flux its
    splats draw (``Frame.traced_records``, as the comparison passes them)."""
    method = load_method(preset)
    scene = method.configure(_scene(name, **SMALL))
    frame = render_frame(scene)
    assert bool(frame.patches) == (preset == "strong")
    budget = method_budget(frame.result.metadata, None, frame.result.receivers,
                           frame.traced_records())
    rows = {r["item"]: r for r in budget.records()}
    emitted = next(r for r in rows.values() if r["role"] == "emitted")
    on_maps = next(r for r in rows.values() if r["item"].startswith("splatted: on the"))
    closure = budget_closure(budget)
    print(f"{name} {preset}: emitted {emitted['flux_w']:.5f} W, on maps "
          f"{on_maps['flux_w']:.5f} W, closure {closure:.2e}")
    assert closure <= BUDGET_CLOSURE
    assert on_maps["fraction"] > 0.5
    if name == "bunny":
        tir = rows["total internal reflection at the exit"]
        assert tir["fraction"] > 0.1


@pytest.fixture(scope="module")
def reference_budgets():
    """The reference budget of glass_sphere and bunny, as compare traces it
    (BUDGET_PHOTONS photons, the default seed)."""
    return {name: reference_budget(_scene(name)) for name in ("glass_sphere", "bunny")}


@pytest.mark.parametrize("name", ["glass_sphere", "bunny"])
def test_reference_budget_adds_up_to_the_emitted_flux(reference_budgets, name):
    """Physical requirement: every photon the reference aims at the object ends in
    exactly one item (missed, TIR, cut, left, uncounted, Fresnel, back side,
    deposited) and loses weight only to the absorption and shading items, so the
    items add up to the emitted weight within BUDGET_CLOSURE (1e-3; measured ~2e-5,
    float32 sums). Independently of the tallies: ``deposited`` (a lane tally) is the
    flux on the trace's own caustic maps (Σ E · texel area, the maps' scatter_reduce)
    to 1e-4, and the emitted flux is the analytic I Ω of the bounding sphere's cone
    (a point light and one target: every photon carries I Ω) to 1e-4. Not vacuous:
    the deposited share is over 20 %, and the bunny's chain rule drops over 5 % to
    total internal reflection and cuts over 1 % (chains longer than L T T D)."""
    budget = reference_budgets[name]
    table = reference_budget_table(budget)
    closure = budget_closure(table)
    deposited = budget.items_w["deposited"]
    scene = _scene(name)
    geometry = build_geometry(scene)
    target = bounding_sphere(geometry.objects[0].mesh, "object")
    distance = np.linalg.norm(np.subtract(target.center, scene.light.position))
    omega = 2 * np.pi * (1 - np.sqrt(1 - (target.radius / distance) ** 2))
    expected = np.asarray(scene.light.intensity) * omega
    print(f"{name}: emitted {budget.emitted_w} W (I Ω = {expected}), deposited {deposited}, "
          f"maps {budget.maps_flux_w}, closure {closure:.2e}, {budget.seconds:.2f} s, "
          f"screened {budget.screened}")
    assert budget.photons == BUDGET_PHOTONS
    assert closure <= BUDGET_CLOSURE
    np.testing.assert_allclose(deposited, budget.maps_flux_w, rtol=1e-4)
    np.testing.assert_allclose(budget.emitted_w, expected, rtol=1e-4)
    assert budget.share["deposited"] > 0.2
    if name == "bunny":
        assert budget.share["tir"] > 0.05 and budget.share["cap"] > 0.01


def test_reference_deposited_flux_is_the_reference_caustic(reference_budgets):
    """Physical requirement: the budget trace's deposited flux and the caustic probe's
    flux (the same tracer and chains, other seeds: 4 x 65,536 photons) estimate the
    same caustic flux; they agree within 4 combined standard errors (the budget's
    from its launches, the probe's from its 4 seeds)."""
    budget = reference_budgets["bunny"]
    scene = _scene("bunny")
    fluxes = np.array([probe_caustic(scene, seed=100 + s).caustic_flux_w for s in range(4)])
    emitted = float(budget.emitted_w.sum())
    deposited = float(budget.items_w["deposited"].sum())
    se = np.hypot(budget.share_se["deposited"] * emitted, fluxes.std(ddof=1) / 2)
    print(f"deposited {deposited:.5f} W vs probe {fluxes.mean():.5f} W, σ {se:.2e}")
    assert abs(deposited - fluxes.mean()) < 4 * se


@pytest.mark.parametrize(("name", "settings", "item"), [
    ("bunny", {"all_specular_paths": True}, "left"),
    ("colored_bunny", {}, "absorbed_medium"),
    ("metal_ring", {}, "absorbed_surface"),
    ("dispersion_sphere", {}, "deposited"),
])
def test_reference_budget_closes_in_every_mode(name, settings, item):
    """Physical requirement: the budget closes (within BUDGET_CLOSURE) in all-paths
    mode (the tail loop's registers), with Beer-Lambert absorption, at a conductor,
    and with dispersion (three channel passes); each case's own item is not zero
    (so the mode's tally is exercised). 2^18 photons each."""
    budget = reference_budget(_scene(name, **settings), photons=1 << 18)
    closure = budget_closure(reference_budget_table(budget))
    print(f"{name} {settings}: closure {closure:.2e}, {item} {budget.items_w[item]}")
    assert closure <= BUDGET_CLOSURE
    assert np.all(budget.items_w[item] > 0)


def test_share_errors_match_the_spread_of_independent_traces():
    """Physical requirement (statistics): the reported standard error of a share is
    the spread of that share over independent traces. Eight traces of glass_sphere
    (2^16 photons, seeds 0..7): Σ z² of the shares ``left`` and ``deposited`` about
    their pooled mean, z = deviation / reported SE, follows χ² with 7 degrees of
    freedom each; both must lie in [0.6, 24.3] (the χ²(7) 0.1 % and 99.9 %
    quantiles), which fails an SE off by a factor of ~2 either way."""
    scene = _scene("glass_sphere")
    geometry = build_geometry(scene)
    runs = [reference_budget(scene, photons=1 << 16, seed=s, geometry=geometry)
            for s in range(8)]
    for item in ("left", "deposited"):
        shares = np.array([r.share[item] for r in runs])
        errors = np.array([r.share_se[item] for r in runs])
        chi2 = float((((shares - shares.mean()) / errors) ** 2).sum())
        print(f"{item}: shares {shares.mean():.5f} ± {errors.mean():.1e}, χ² {chi2:.2f}")
        assert 0.6 <= chi2 <= 24.3, item


def test_budget_leaves_the_maps_unchanged():
    """Regression lock (the tallies only watch): single-threaded (so that the
    scatter_reduce's order, and with it float32 rounding, is fixed), the caustic
    maps traced with the budget are bit-identical to those traced without it, in
    chain and all-paths mode."""
    _, dr, _ = load_mitsuba()
    threads = dr.thread_count()
    dr.set_thread_count(1)
    try:
        for settings in ({}, {"all_specular_paths": True}):
            scene = _scene("bunny", **settings)
            geometry = build_geometry(scene)
            plain, tallied = (PhotonTracer(scene, geometry=geometry, resolution=(32, 32),
                                           caustic_only=True, budget=b)
                              .trace(1 << 16, seed=3) for b in (False, True))
            assert tallied.budget.shape == (1, len(BUDGET_ITEMS), 3)
            for a, b in zip(plain.caustic, tallied.caustic, strict=True):
                assert np.array_equal(a, b), settings
            assert plain.casts == tallied.casts
    finally:
        dr.set_thread_count(threads)
