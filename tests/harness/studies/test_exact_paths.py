"""Exact light paths through the method's vertex grid (``harness.studies.exact_paths``),
written as the GPU trace's records and splatted by the method's own passes.

Kinds: **physical requirements** (analytic answers: Snell's law, Fresnel at normal
incidence and its reciprocity, a view's texel solid angles summing to the frustum's,
the flux a glass sphere sends to the floor in closed form, a sphere of index 1 that
passes the light unchanged); the lattice's rays are checked against the view they
were built from.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from harness.raycast import SurfaceTracer
from harness.studies.exact_paths import (
    exact_paths,
    fresnel_transmittance,
    lattice_rays,
    refract,
    texel_measure,
)
from renderers.caustics_mapping.lights import light_setups
from renderers.caustics_mapping.record_splat import splat_records
from scenes import parse_scene
from scenes.geometry import build_geometry
from tests.conftest import MINIMAL_SCENE, REPO
from tests.renderers.caustics_mapping.test_flux import E0, RADIUS, floor_fraction

pytestmark = pytest.mark.physical_requirement


def _scene(text: str, **settings):
    text += "\n[settings]\n" + "".join(f"{k} = {v}\n" for k, v in settings.items())
    return parse_scene(text, file="exact_paths_test", base_dir=Path(REPO / "scenes"))


def test_refraction_obeys_snells_law():
    """n1 sin θi = n2 sin θt, the refracted ray in the plane of incidence and of unit
    length; leaving glass (1.5) beyond the critical angle asin(1/1.5) = 41.81° is
    total internal reflection."""
    angles = np.radians(np.arange(0.0, 89.0, 4.0))
    d = np.stack([np.sin(angles), np.zeros_like(angles), -np.cos(angles)], axis=1)
    n = np.tile([0.0, 0.0, 1.0], (len(angles), 1))
    t, tir, cos_i = refract(d, n, np.full(len(angles), 1 / 1.5))
    assert not tir.any()
    np.testing.assert_allclose(cos_i, np.cos(angles), atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(t, axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(1.5 * t[:, 0], np.sin(angles), atol=1e-12)
    np.testing.assert_allclose(t[:, 1], 0.0, atol=1e-12)
    _, tir, _ = refract(d, n, np.full(len(angles), 1.5))
    np.testing.assert_array_equal(tir, angles > math.asin(1 / 1.5))


def test_fresnel_transmittance_known_values():
    """Normal incidence: T = 1 − ((n − 1)/(n + 1))² = 0.96 for n = 1.5, either way;
    reciprocity: T(θi, air → glass) = T(θt, glass → air) for the refracted angle θt;
    0 beyond the critical angle."""
    one = np.ones(1)
    np.testing.assert_allclose(fresnel_transmittance(one, one, 1.5 * one), 0.96, atol=1e-12)
    np.testing.assert_allclose(fresnel_transmittance(one, 1.5 * one, one), 0.96, atol=1e-12)
    cos_i = np.cos(np.radians(np.arange(0.0, 89.0, 7.0)))
    cos_t = np.sqrt(1 - (1 - cos_i**2) / 1.5**2)
    np.testing.assert_allclose(fresnel_transmittance(cos_i, 1.0, 1.5),
                               fresnel_transmittance(cos_t, 1.5, 1.0), atol=1e-12)
    assert fresnel_transmittance(np.array([0.5]), 1.5, 1.0)[0] == 0.0   # 60° > 41.8°


def test_lattice_rays_pass_through_the_texel_centres():
    """Each ray of the object view's lattice projects back (through the view's own
    matrix) onto its texel's centre, moved by the lattice offset."""
    scene = _scene(MINIMAL_SCENE)
    light = light_setups(scene, build_geometry(scene), frustum_fit="tight")[0]
    view = light.object_views[0]
    grid, offset = 16, (0.3, -0.2)
    origins, directions, ndc = lattice_rays(light, view, grid=grid, offset=offset)
    points = origins + 4.0 * directions
    clip = np.hstack([points, np.ones((len(points), 1))]) @ view.view_proj.T
    np.testing.assert_allclose(clip[:, :2] / clip[:, 3:], ndc, atol=1e-9)
    tx, ty = np.meshgrid(np.arange(grid), np.arange(grid))
    expected = np.stack([(tx.ravel() + 0.5 + offset[0]) / grid,
                         (ty.ravel() + 0.5 + offset[1]) / grid], axis=1) * 2 - 1
    np.testing.assert_allclose(ndc, expected, atol=1e-12)


def test_texel_solid_angles_sum_to_the_frustum():
    """The texels' solid angles of a square perspective view of half-tangent t sum to
    the pyramid's solid angle 4 asin(t² / (1 + t²)) (midpoint rule: error O(grid⁻²),
    below 1e-5 at grid 128)."""
    scene = _scene(MINIMAL_SCENE)
    light = light_setups(scene, build_geometry(scene), frustum_fit="square")[0]
    view = light.object_views[0]
    _, _, ndc = lattice_rays(light, view, grid=128)
    t = view.half_size
    assert view.rect is None and view.perspective
    total = texel_measure(view, 128, ndc).sum()
    np.testing.assert_allclose(total, 4 * math.asin(t * t / (1 + t * t)), rtol=1e-5)


def test_sphere_sends_the_closed_form_flux_to_the_floor():
    """Vertical sun (E0 = 10 W/m²) through the glass sphere (R = 1 m, IOR 1.5): the
    exact paths that reach the floor carry E0 π R² F, with F = 0.9678 the share of
    parallel rays through an exact sphere that land on the 8 m floor (closed form,
    ``test_flux.floor_fraction``). Tolerance 0.3 %: the icosphere's silhouette
    against the circle and the grid's coverage of it (measured at grid 128, strong
    preset's tight frustum: +0.10 %, of which the traced flux, E0 times the covered
    texels' area, is +0.08 % above E0 π R² and the adjoint shading factor +0.02 %)."""
    text = (REPO / "scenes" / "glass_sphere.toml").read_text()
    light = text[text.index("[light]"):text.index("[[receivers]]")]
    text = text.replace(light, f'[light]\ntype = "directional"\ndirection = [0.0, 0.0, -1.0]\n'
                               f"irradiance = [{E0}, {E0}, {E0}]\n\n")
    scene = _scene(text, preset='"strong"', grid=128)
    geometry = build_geometry(scene)
    paths = exact_paths(scene, geometry, SurfaceTracer(scene, geometry))
    records = paths.records[0][0]
    hit = records[:, 2, 3] == 1
    flux = records[hit, 3, :3].astype(np.float64).sum(axis=0)
    np.testing.assert_allclose(flux, E0 * math.pi * RADIUS**2 * floor_fraction(), rtol=3e-3)
    assert paths.fates["tir"] == 0 and paths.fates["blocked"] == 0   # a sphere traps nothing
    np.testing.assert_allclose(paths.fates["hit"] + paths.fates["missed"], 1.0, atol=1e-3)


def test_index_one_sphere_passes_the_light_unchanged(ctx):
    """A sphere of IOR 1 bends nothing: the exact paths, splatted by the method's own
    triangle kernel, give the direct irradiance I cos θ / r² inside the sphere's
    shadow on the floor (light 6 m above the floor, sphere of radius 1 m at 2 m: the
    shadow's radius is 6 tan(asin(1/4)) = 1.549 m). Every texel whose centre is
    within 1.45 m agrees within 1 % (the kernel's piecewise-constant irradiance over
    quads of about 2 cm, where I cos θ / r² changes by under 0.5 %)."""
    text = MINIMAL_SCENE.replace("ior = 1.5", "ior = 1.0")
    scene = _scene(text, preset='"strong"', grid=128, receiver_map="[128, 128]")
    geometry = build_geometry(scene)
    paths = exact_paths(scene, geometry, SurfaceTracer(scene, geometry))
    maps = splat_records(scene, paths.records, ctx=ctx, geometry=geometry)
    image = maps.receivers[0].irradiance[..., 0].astype(np.float64)
    umin, umax, vmin, vmax = maps.receivers[0].extent
    h, w = image.shape
    u = umin + (np.arange(w) + 0.5) / w * (umax - umin)
    v = vmin + (np.arange(h) + 0.5) / h * (vmax - vmin)
    x, y = np.meshgrid(u, v)
    r2 = x**2 + y**2 + 36.0
    direct = 30.0 * (6.0 / np.sqrt(r2)) / r2             # I cos θ / r², I = 30 W/sr
    inside = np.hypot(x, y) < 1.45
    error = np.abs(image[inside] / direct[inside] - 1)
    print(f"max relative error {error.max():.2e}, mean {error.mean():.2e} "
          f"over {inside.sum()} texels")
    assert error.max() < 0.01
