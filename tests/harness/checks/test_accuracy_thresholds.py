"""Accuracy thresholds (harness/checks/data/thresholds.toml) against the golden references: every
bound holds for the renderer as it is, and every bound fails for deliberately
broken renders, so none of them is vacuous."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from harness.checks import GOLDEN_DIR, THRESHOLDS_FILE
from harness.checks.accuracy import accuracy_metrics, realtime_maps
from harness.checks.golden import GOLDEN_SCENES, GoldenError, golden_scene, load_golden
from harness.checks.thresholds import check_bounds, load_thresholds
from renderers.caustics_mapping import context as gl_context
from scenes import with_settings
from tests.conftest import SCENES

GOLDEN = GOLDEN_DIR
BOUNDS = load_thresholds(THRESHOLDS_FILE)


@pytest.fixture(scope="module")
def renders(ctx_module):
    """Each golden scene's caustics-mapping maps and golden reference maps."""
    out = {}
    for name in GOLDEN_SCENES:
        scene = golden_scene(SCENES, name)
        out[name] = (scene, realtime_maps(scene, ctx=ctx_module),
                     [m.irradiance for m in load_golden(GOLDEN, name).receivers])
    return out


@pytest.fixture(scope="module")
def ctx_module(context_factory):
    """The session's GL context, error-free after this module's renders."""
    ctx = context_factory()
    yield ctx
    assert ctx.error == "GL_NO_ERROR"


def _checks(name, method, reference):
    return check_bounds(name, accuracy_metrics(method, reference), BOUNDS)


def test_every_golden_scene_has_its_bounds():
    scenes = {b.scene for b in BOUNDS}
    assert scenes == set(GOLDEN_SCENES)
    assert all(b.provenance for b in BOUNDS)


@pytest.mark.parametrize("name", GOLDEN_SCENES)
def test_bounds_hold(renders, name):
    """The caustics-mapping render meets every bound of the scene."""
    _, method, reference = renders[name]
    checks = _checks(name, method, reference)
    assert checks, f"no bounds for {name}"
    failed = [c for c in checks if not c.passed]
    assert not failed, "\n".join(f"{c.view}.{c.region}.{c.metric} = {c.value:.5g} "
                                 f"violates {c.kind} {c.bound}" for c in failed)


def _shift(maps, texels=3):
    """Splats displaced by a few texels: every map rolled along u."""
    return [np.roll(m, texels, axis=1) for m in maps]


def _scale(maps, factor=1.1):
    """Flux off by 10 %."""
    return [m * factor for m in maps]


@pytest.mark.parametrize("name", GOLDEN_SCENES)
def test_every_bound_fails_on_some_broken_render(renders, ctx_module, name):
    """Breaks: splats shifted by 3 texels, flux scaled by 1.1, and the estimator
    stopped at its start estimate (0 iterations) where the scene uses 3. Each bound
    of the scene must fail under at least one of them."""
    scene, method, reference = renders[name]
    broken = {"shift": _shift(method), "flux": _scale(method),
              "iterations": realtime_maps(with_settings(scene, {"iterations": 0}),
                                          ctx=ctx_module)}
    caught = {}
    for label, maps in broken.items():
        for check in _checks(name, maps, reference):
            key = (check.view, check.region, check.metric)
            if not check.passed:
                caught.setdefault(key, []).append(label)
    keys = {(b.view, b.region, b.metric) for b in BOUNDS if b.scene == name}
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
def test_shader_breaks_fail_a_threshold(monkeypatch, ctx, old, new, what):
    """Breaking the estimator or the flux normalisation in the shader itself makes
    at least one glass_sphere bound fail."""
    _broken_source(monkeypatch, ctx, old, new)
    method = realtime_maps(golden_scene(SCENES, "glass_sphere"), ctx=ctx)
    reference = [m.irradiance for m in load_golden(GOLDEN, "glass_sphere").receivers]
    failed = [c for c in _checks("glass_sphere", method, reference) if not c.passed]
    assert failed, f"{what}: every bound still holds"


def test_golden_references_are_checked_on_load(tmp_path):
    """An altered golden file is refused (SHA-256 mismatch), naming the file."""
    copy = tmp_path / "golden"
    shutil.copytree(GOLDEN, copy)
    target = copy / "glass_sphere" / "receiver0.exr"
    data = bytearray(target.read_bytes())
    data[-10] ^= 0xFF
    target.write_bytes(bytes(data))
    with pytest.raises(GoldenError, match=r"receiver0\.exr: SHA-256"):
        load_golden(copy, "glass_sphere")


