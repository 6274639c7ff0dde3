"""Only the passes the effects call for run, and the result lists them."""

from __future__ import annotations

from renderers.caustics_mapping import render

from .conftest import SCENES, small_scene


def _meta(ctx, name):
    path = next(p for p in SCENES if p.stem == name)
    result = render(small_scene(path), ctx=ctx)
    return result.effects, result.metadata


def test_water_pool_has_no_shadow_map_and_no_back_faces(ctx):
    """water_pool: one refraction at an open surface, no direct light, no shadows."""
    effects, meta = _meta(ctx, "water_pool")
    assert "refraction.single" in effects
    assert "shadow_map" not in meta["passes"]
    assert "object_positions.back" not in meta["passes"]
    assert "caustic_trace.refraction.single" in meta["passes"]


def test_glass_sphere_runs_back_faces(ctx):
    """glass_sphere: a closed dielectric needs the exit surfaces (double refraction)
    and has shadows."""
    _, meta = _meta(ctx, "glass_sphere")
    assert "object_positions.back" in meta["passes"]
    assert "caustic_trace.refraction.double" in meta["passes"]
    assert "shadow_map" in meta["passes"]


def test_metal_ring_runs_reflection_and_cube_faces(ctx):
    """metal_ring: a conductor under a point light: the reflection path on the cube
    of map views; the low light sees the floor through more than one face."""
    _, meta = _meta(ctx, "metal_ring")
    assert "caustic_trace.reflection" in meta["passes"]
    assert "object_positions.back" not in meta["passes"]
    assert meta["light_views"] == "cube"
    assert len(meta["map_faces"]) >= 2
    assert set(meta["map_faces"]) <= {"+x", "-x", "+y", "-y", "+z", "-z"}


def test_dispersion_runs_one_trace_per_channel(ctx):
    """dispersion_sphere: one caustic pass per channel IOR."""
    _, meta = _meta(ctx, "dispersion_sphere")
    traces = [p for p in meta["passes"] if p.startswith("caustic_trace")]
    assert traces == [f"caustic_trace.refraction.double.{c}" for c in "rgb"]
