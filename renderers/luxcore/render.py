"""One LuxCore film: a LIGHTCPU render of a receiver seen by an orthographic camera,
as irradiance (the method of the caustic maps is in :mod:`.caustic`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from renderers.luxcore import _worker
from renderers.luxcore.translate import OrthoView, Variant, translate_scene
from scenes.geometry import SceneGeometry
from scenes.model import Scene

__all__ = [
    "RECEIVER_ALBEDO",
    "FilmRender",
    "luxcore_version",
    "render_film",
    "seed_list",
]

#: Albedo every receiver gets in the caustic renders (dimensionless).
RECEIVER_ALBEDO = 1e-3
@dataclass(frozen=True, eq=False)
class FilmRender:
    """One LIGHTCPU render of one receiver.

    Attributes
    ----------
    irradiance : ndarray, (H, W, 3), float64
        pi L / (rho cos_o) per texel, W/m², row 0 at vmin (everything the receiver got,
        direct light included, for the variant rendered).
    photons : int
        Light paths traced.
    seconds : float
        Wall time of the render alone (scene translation excluded), seconds.
    """

    irradiance: np.ndarray
    photons: int
    seconds: float


def render_film(scene: Scene, view: OrthoView, *, variant: Variant, photons: int, seed: int,
                receiver_albedo: float = RECEIVER_ALBEDO,
                geometry: SceneGeometry | None = None) -> FilmRender:
    """Render one film with LIGHTCPU on one thread, in the worker process
    (:mod:`renderers.luxcore._worker`).

    Parameters
    ----------
    photons
        Light paths to trace (LuxCore stops at the first film update past this).
    seed
        LuxCore ``renderengine.seed`` (>= 1).
    """
    if seed < 1:
        raise ValueError("LuxCore seeds start at 1")
    lux_scene = translate_scene(scene, variant=variant, receiver_albedo=receiver_albedo,
                                view=view, geometry=geometry)
    w, h = view.film
    spp = max(1, -(-int(photons) // (w * h)))
    config = "\n".join([
        "renderengine.type = LIGHTCPU",
        f"renderengine.seed = {int(seed)}",
        "native.threads.count = 1",
        "sampler.type = SOBOL",
        f"film.width = {w}", f"film.height = {h}",
        "film.filter.type = NONE",
        "film.outputs.0.type = RGB", "film.outputs.0.filename = unused.exr",
        # Every bounce (Russian roulette past depth 3 keeps this unbiased).
        "path.pathdepth.total = 1024", "path.pathdepth.diffuse = 1024",
        "path.pathdepth.glossy = 1024", "path.pathdepth.specular = 1024",
        f"batch.haltspp = {spp}",
    ]) + "\n"
    raw, traced, seconds = _worker.run(_worker.render, lux_scene, config, view.film)
    radiance = raw[: h - 1].astype(np.float64)
    irradiance = np.pi * radiance / (receiver_albedo * view.cos_to_origin()[..., None])
    return FilmRender(irradiance, traced, seconds)


def luxcore_version() -> str:
    """pyluxcore's version, asked of the render worker (raises
    :class:`~renderers.luxcore._lux.LuxCoreUnavailable` if it cannot import it)."""
    return _worker.run(_worker.version)


def seed_list(seeds: int | Sequence[int], *, first: int = 1) -> list[int]:
    """``seeds`` as a list: a count K gives ``first, first + 1, ..., first + K - 1``."""
    if isinstance(seeds, int):
        return list(range(first, first + seeds))
    return [int(s) for s in seeds]
