"""The caustics-mapping presets: which choice each unset setting takes.

A setting the scene file or the command line gives always wins; a setting left at
``None`` takes its preset's value (:func:`resolve_settings`).

* ``paper``: the paper's choices, as published: point splats of one width (the
  width is today's ``0.5 x caustic_map / grid`` texels, so the paper's claims are
  tested on unchanged numbers), the modified estimator from the receiver start,
  nearest-texel lookups, the exit surface at the grid's resolution, a square object
  frustum, and every estimate splatted.
* ``strong``: the best known implementation: bilinear lookups within one surface
  with renormalised normals, the exit surface at 4x the grid's resolution (2x where
  every closed dielectric bounds a convex body: see :func:`resolve_scene`), verified
  hits (a reflected ray they leave unverified searched again on the signed depth
  along the light, and a reflected hit where the object rests on the receiver
  dropped: ``caustic_trace.TraceOptions``), a tight rectangular object frustum, the
  safeguarded secant estimator with 5 iterations (verified hits drop what has not
  converged: on glass_sphere the modified estimator leaves 17 % of the flux
  unconverged after 3 iterations and 3.2 % after 8; the secant 0.05 % after 5) and
  Veach's adjoint shading-normal factor at every specular event, as the reference's
  photons carry it (``caustic_trace.TraceOptions.shading_correction``), and
  triangle splats (flux / area between neighbouring hits; Ernst et al. 2005,
  webgl-water), which measured better than footprint Gaussians (caustic relMSE
  0.0009 against 0.0019 on glass_sphere), with rim patches of 3 x 3 (the quads at
  the silhouette traced again, finer: whole-receiver excess relMSE on glass_sphere
  5.6e-4 -> 2.4e-4, metal_ring's caustic region 1.3e-2 -> 2.2e-3; docs/method.md),
  5 x 5 where the scene has a conductor (:data:`_CONDUCTOR_RIM_PATCHES`).
"""

from __future__ import annotations

import dataclasses

from renderers.caustics_mapping.meshes import convex
from scenes import Scene
from scenes.geometry import SceneGeometry, build_geometry
from scenes.model import ConductorMaterial, DielectricMaterial, Settings

__all__ = ["PRESETS", "resolve_scene", "resolve_settings"]

#: Each preset's value of every setting whose default is ``None`` (``back_resolution``
#: and ``splat_sigma`` are functions of the grid and map sizes; see
#: :func:`resolve_settings`).
PRESETS: dict[str, dict[str, object]] = {
    "paper": {"estimator": "modified", "iterations": 3, "safeguarded": False,
              "lookup": "nearest", "frustum": "square", "verify_hits": False,
              "splat": "points", "rim_patches": 1, "caustic_lookup": "light"},
    "strong": {"estimator": "secant", "iterations": 5, "safeguarded": True,
               "lookup": "filtered", "frustum": "tight", "verify_hits": True,
               "splat": "triangles", "rim_patches": 3, "caustic_lookup": "receivers"},
}
_BACK_FACTOR = {"paper": 1, "strong": 4}
#: strong's exit surface where every closed dielectric bounds a convex body: one
#: smooth sheet, which the bilinear reads follow at 2x as well as at 4x (glass_sphere,
#: receiver excess relMSE 5.61e-4 at both; caustic region 4.8e-5 against 5.0e-5),
#: for 8 ms less a frame on llvmpipe. The bunny's folds need 4x (2x: caustic excess
#: 0.0930 -> 0.0955).
_CONVEX_BACK_FACTOR = 2
#: strong's rim patches where the scene has a conductor. A mirror's reflection turns
#: twice as fast as its normal, so near grazing its rays fan out twice as fast as a
#: refraction's across the same patch (``rim_patches.py``). Against the cached
#: references of ``compare``'s default budgets (each scene's own settings, llvmpipe),
#: the caustic region's excess relMSE with patches of 3 -> 5: metal_ring 2.12e-3 ->
#: 1.58e-3, ring_point 2.85e-3 -> 1.98e-3, bowl_sun 1.98e-2 -> 1.77e-2, cup_sun
#: 6.98e-3 -> 7.00e-3 (intervals overlap); and the shallow bowl under a 45 deg sun
#: (scenes/hard/concave), whose floor light comes from a sliver under one grid step
#: wide, flux ratio 0.977 -> 0.9995 (grid 128). A frame takes 1.46 to 1.61 times as
#: long (tests/benchmarks/test_bench_conductor_patches.py).
_CONDUCTOR_RIM_PATCHES = 5


def resolve_settings(settings: Settings, *, convex_bodies: bool = False,
                     conductors: bool = False) -> Settings:
    """``settings`` with every unset (``None``) choice filled from its preset.

    ``splat_sigma`` stays ``None`` outside the paper preset: the renderer then derives
    it from the hits (one mean spacing of neighbouring hits, in caustic-map texels).
    ``convex_bodies``: every closed dielectric of the scene bounds a convex body (strong's
    exit surface is then at 2x the grid, else at 4x); ``conductors``: the scene has a
    conductor (strong's rim patches are then :data:`_CONDUCTOR_RIM_PATCHES`);
    :func:`resolve_scene` finds both.
    """
    preset = settings.preset
    values = {k: v for k, v in PRESETS[preset].items() if getattr(settings, k) is None}
    if settings.rim_patches is None and (settings.normalization == "paper"
                                         or values.get("splat", settings.splat) != "triangles"):
        values["rim_patches"] = 1       # patches replace triangles; Eq. 6 counts grid texels
    elif settings.rim_patches is None and conductors and preset == "strong":
        values["rim_patches"] = _CONDUCTOR_RIM_PATCHES
    if settings.back_resolution is None:
        factor = _BACK_FACTOR[preset]
        if convex_bodies and preset == "strong":
            factor = _CONVEX_BACK_FACTOR
        values["back_resolution"] = min(settings.grid * factor, 8192)
    if settings.splat_sigma is None and preset == "paper":
        values["splat_sigma"] = 0.5 * settings.caustic_map / settings.grid
    return dataclasses.replace(settings, **values) if values else settings


def convex_exits(geometry: SceneGeometry) -> bool:
    """Whether the scene has closed dielectrics and each bounds a convex body
    (:func:`.meshes.convex`): its exit surface is then one smooth sheet."""
    closed = [g.mesh for g in geometry.objects
              if isinstance(g.material, DielectricMaterial) and g.mesh.closed]
    return bool(closed) and all(convex(mesh) for mesh in closed)


def resolve_scene(scene: Scene, geometry: SceneGeometry | None = None) -> Scene:
    """``scene`` with its settings resolved (:func:`resolve_settings`), the exit
    surface's convexity read from ``geometry`` (built from ``scene`` if not given)."""
    settings = scene.settings
    bodies = False
    if settings.back_resolution is None and settings.preset == "strong":
        bodies = convex_exits(geometry or build_geometry(scene))
    conductors = any(isinstance(o.material, ConductorMaterial) for o in scene.objects)
    return dataclasses.replace(scene, settings=resolve_settings(
        settings, convex_bodies=bodies, conductors=conductors))
