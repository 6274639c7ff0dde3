"""Receiver caustic irradiance maps from LuxCore's light tracer (LIGHTCPU).

Method
------
One receiver at a time is watched by an orthographic camera along its normal
(:func:`~renderers.luxcore.translate.receiver_view`). LIGHTCPU emits photons from
the light, follows every specular and diffuse bounce, and at each diffuse vertex
splats into the film pixel straight above it (the objects are camera-invisible). A
Lambertian receiver of albedo rho reflects radiance L = rho E / pi, so a pixel's
irradiance is

    E = pi L / (rho cos_o),

with cos_o the cosine toward the camera's origin that LuxCore's adjoint BSDF puts on
every splat (:meth:`OrthoView.cos_to_origin`, 1 - O(1e-5)).

Caustic only: for each seed two single-threaded renders share the seed, one with the
objects as glass and one with the same triangles black. Their light paths are the
same photon for photon up to the first object hit, so the direct light (and the
shadow) cancels path by path and ``glass - black`` is the light that reached the
receiver through the objects: every L S+ D path. Each film is normalised by its own
photon count (LuxCore stops within a few thousand photons of the target, not at an
exact count); the photons one run has beyond the other add a little noise and no
bias. The receivers get albedo 1e-3 so that light the floor scatters back through
the glass stays below 1e-4 of the caustic; the result is divided by that albedo.

Noise: K seeds; the map is their mean and ``variance`` the per-texel variance of the
mean (sample variance / K).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from renderers.luxcore.render import render_film, seed_list
from renderers.luxcore.translate import check_supported, receiver_view
from renderers.luxcore.units import require_units
from renderers.results import ReceiverMap
from scenes.geometry import SceneGeometry, build_geometry
from scenes.model import Scene

__all__ = ["render_receiver_caustic"]


def render_receiver_caustic(scene: Scene, *, photons: int, seeds: int | Sequence[int] = 4,
                            first_seed: int = 1, resolution: tuple[int, int] | None = None,
                            geometry: SceneGeometry | None = None,
                            check_units: bool = True) -> list[ReceiverMap]:
    """Caustic irradiance over every receiver, LuxCore's full light transport.

    Parameters
    ----------
    scene
        Must pass :func:`~renderers.luxcore.translate.check_supported`.
    photons
        Light paths per film (each seed renders two films per receiver).
    seeds
        Number K of independent seeds, or the seeds themselves (each >= 1).
    resolution
        Map (W, H); default ``scene.settings.receiver_map``.
    check_units
        First run :func:`renderers.luxcore.units.check_units` on the bare receivers
        and refuse (:class:`~renderers.luxcore.units.UnitsCheckFailed`) if it fails.

    Returns
    -------
    list of ReceiverMap
        Per receiver: mean caustic irradiance over the seeds (W/m², float32, row 0 at
        vmin) and the per-texel variance of that mean (None for one seed).
    """
    check_supported(scene)
    geometry = geometry or build_geometry(scene)
    if check_units:
        require_units(scene, geometry=geometry)
    maps = []
    for index in range(len(scene.receivers)):
        view = receiver_view(scene, index, resolution=resolution, geometry=geometry)
        samples = []
        for seed in seed_list(seeds, first=first_seed):
            glass = render_film(scene, view, variant="glass", photons=photons, seed=seed,
                                geometry=geometry)
            black = render_film(scene, view, variant="black", photons=photons, seed=seed,
                                geometry=geometry)
            samples.append(glass.irradiance - black.irradiance)
        stack = np.stack(samples)
        k = len(samples)
        variance = (stack.var(axis=0, ddof=1) / k).astype(np.float32) if k > 1 else None
        maps.append(ReceiverMap(stack.mean(axis=0).astype(np.float32), view.extent, variance))
    return maps
