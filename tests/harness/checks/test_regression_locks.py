"""Regression locks (harness/checks/data/regression_locks.toml) of both presets against
the golden references. Kind: **regression lock** — each number is calibrated from
today's output (golden + disjoint reference seeds, and a light jitter standing in
for another platform's rounding; ``harness.checks.locks``), so these tests guard
against change, not accuracy. Every lock holds for the renderer as it is, and every
lock fails for some deliberately broken render, so none is vacuous. On failure the
method, reference and difference images are written and the path printed."""

from __future__ import annotations

import numpy as np
import pytest

from harness.checks import LOCKS_FILE
from harness.checks.bounds import load_locks, locked_quantity
from harness.checks.golden import GOLDEN_SCENES, golden_scene
from harness.checks.locks import LOCKED_METHODS, golden_metrics, lock_checks, realtime_maps
from harness.checks.ztest import write_failure_images
from harness.compare.regions import caustic_region
from renderers.caustics_mapping import context as gl_context
from scenes import with_settings
from tests.conftest import SCENES

pytestmark = pytest.mark.regression_lock

LOCKS = load_locks(LOCKS_FILE)
CASES = [(name, method) for name in GOLDEN_SCENES for method in LOCKED_METHODS]


def _ids(case):
    return f"{case[0]}-{case[1]}"


def test_regression_lock_file_covers_every_golden_scene_and_preset():
    """Every (golden scene, locked preset) has locks on every receiver, each with its
    calibration recorded."""
    keys = {b.scene for b in LOCKS}
    expected = {name if method == "paper" else f"{name}@{method}" for name, method in CASES}
    assert keys == expected
    assert all("references" in b.provenance and "jitter" in b.provenance for b in LOCKS)


@pytest.mark.parametrize("case", CASES, ids=_ids)
def test_regression_lock(golden_renders, failure_dir, record_property, case):
    """The render at the golden settings meets every lock of the scene and preset."""
    name, method = case
    golden = golden_renders.golden(name)
    scene = golden_renders.scene(name, method)
    maps = golden_renders.maps(name, method)
    checks = lock_checks(scene, method, maps, golden, LOCKS)
    record_property("checks", len(checks))
    assert checks, f"no locks for {name} ({method})"
    failed = [c for c in checks if not c.passed]
    if failed:
        written = []
        for i, (m, g) in enumerate(zip(maps, golden.receivers, strict=True)):
            written += write_failure_images(failure_dir, f"lock-{name}-{method}-receiver{i}",
                                            test=m, reference=g.irradiance)
        pytest.fail("\n".join(f"{c.view}.{c.region}.{c.metric} = {c.value:.5g} "
                              f"{c.interval_text} {c.decision} against {c.bound_text}"
                              for c in failed)
                    + f"\nimages: {written[0].parent}")


def _shift(maps, texels=3):
    """Splats displaced by a few texels: every map rolled along u."""
    return [np.roll(m, texels, axis=1) for m in maps]


def _scale(maps, factor=1.1):
    """Flux off by 10 %."""
    return [m * factor for m in maps]


@pytest.mark.parametrize("case", CASES, ids=_ids)
def test_every_lock_fails_on_some_broken_render(golden_renders, ctx_module, record_property,
                                                case):
    """Breaks: splats shifted by 3 texels (19 cm at 128²), flux scaled by 1.1 and by
    0.9 (the flux ratio is locked from both sides), and the estimator stopped at its
    start estimate (0 iterations) where the preset uses 3 or 5. Each lock of the
    scene must fail under at least one of them."""
    name, method = case
    golden = golden_renders.golden(name)
    scene = golden_renders.scene(name, method)
    maps = golden_renders.maps(name, method)
    broken = {"shift": _shift(maps), "flux up": _scale(maps), "flux down": _scale(maps, 0.9),
              "iterations": realtime_maps(with_settings(scene, {"iterations": 0}),
                                          ctx=ctx_module)}
    caught = {}
    for label, candidate in broken.items():
        for check in lock_checks(scene, method, candidate, golden, LOCKS):
            if not check.passed:
                key = (check.view, check.region, check.metric, check.kind)
                caught.setdefault(key, []).append(label)
    keys = {(c.view, c.region, c.metric, c.kind)
            for c in lock_checks(scene, method, maps, golden, LOCKS)}
    record_property("checks", len(keys))
    assert keys <= set(caught), f"never fails: {sorted(keys - set(caught))}"


def _broken_source(monkeypatch, ctx, old, new):
    """Patch one line of the shader source for the rest of the test, on the session
    context with an empty program cache (restored afterwards), so no broken program
    outlives the test and no second GL context is made current."""
    original = gl_context._source.__wrapped__

    def patched(filename):
        text = original(filename)
        if filename == "caustic_trace.glsl":
            assert old in text, f"{old!r} not in the shader"
            text = text.replace(old, new)
        return text

    monkeypatch.setattr(gl_context, "_source", patched)
    monkeypatch.setattr(ctx, "extra", {})


@pytest.mark.parametrize(("old", "new", "what"), [
    ("prop = g;                               // modified: d <- g(d)",
     "prop = -g;", "sign flip in the modified update"),
    ("flux *= mask;", "flux *= mask * 1.1;", "flux normalisation 10 % off"),
])
def test_shader_breaks_fail_a_regression_lock(golden_renders, monkeypatch, ctx, *, old, new,
                                              what):
    """Breaking the estimator or the flux normalisation in the shader itself makes at
    least one glass_sphere lock of the paper preset fail."""
    _broken_source(monkeypatch, ctx, old, new)
    scene = golden_scene(SCENES, "glass_sphere")
    maps = realtime_maps(scene, ctx=ctx)
    golden = golden_renders.golden("glass_sphere")
    failed = [c for c in lock_checks(scene, "paper", maps, golden, LOCKS) if not c.passed]
    assert failed, f"{what}: every lock still holds"


def test_accuracy_metrics_are_the_locked_ones(golden_renders):
    """Four metrics per receiver, in the order of ``LOCKED_METRICS``, over the golden's
    regions (the independent reference's, not the golden's own: they differ, and the
    caustic records count the region's texels); the relMSE carries its excess and
    interval, the flux ratio its interval from the golden's per-seed totals, which a
    lock judges on the ratio itself (the excess ratio − 1 moved back by 1)."""
    golden = golden_renders.golden("seabed")
    values = golden_metrics(golden_renders.scene("seabed", "paper"),
                            golden_renders.maps("seabed", "paper"), golden)
    assert [(v.view, v.region, v.metric) for v in values][:4] == [
        ("receiver0", "caustic", "relmse"), ("receiver0", "caustic", "ssim"),
        ("receiver0", "caustic", "flip"), ("receiver0", "full", "flux_ratio")]
    for i, region in enumerate(golden.regions):
        caustic = [v for v in values if v.view == f"receiver{i}" and v.region == "caustic"]
        assert {v.pixels for v in caustic} == {int(region.sum())}
        own = caustic_region(np.asarray(golden.receivers[i].irradiance))
        assert (own != region).any()
    relmse = values[0]
    assert relmse.excess is not None and relmse.excess_ci95[0] < relmse.excess \
        < relmse.excess_ci95[1]
    flux = values[3]
    assert flux.excess == pytest.approx(flux.value - 1.0)
    value, (low, high) = locked_quantity(flux)
    assert value == flux.value and low < value < high
    # SSIM and FLIP are descriptive: a lock judges their value alone.
    assert locked_quantity(values[1]) == (values[1].value, None)
    assert len(values) == 8
