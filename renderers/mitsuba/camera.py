"""Camera image by Mitsuba's particle tracer (``ptracer``).

ptracer traces light paths from the emitter and connects each diffuse vertex to
the camera, so it renders light-specular-diffuse-camera paths that ``path``
cannot with a point light. ``max_depth`` counts path segments: L D E is 2, and a
chain of k specular events before the receiver needs k + 2; we use the longest
chain the effects name (MAX_SPECULAR_EVENTS + 2 in all-paths mode), no more, so
the image holds the same light paths as the photon tracer's maps (the
``chain_dielectric`` BSDF makes TIR absorb and Fresnel optional in the same way).
Russian roulette is disabled (rr_depth > max_depth).

ptracer does not say how much light its ``max_depth`` stopped, so in all-paths
mode :func:`camera_cut_fraction` measures it: the same seed rendered again with
twice the event limit traces the same paths (each particle draws from its own
stream, so the shorter render's paths are prefixes of the longer one's), and the
difference of the two images is the light of the paths the cap cut.

Limits, recorded in the result's metadata: specular objects seen directly are
black, and so is anything seen only through one, e.g. a pool floor under the
water surface (ptracer cannot connect through a delta BSDF to the pinhole; the
receiver maps are unaffected); ``shadows =
false`` cannot be expressed (objects always occlude); absorption applies on
closed objects only (see :mod:`.bsdf`).
"""

from __future__ import annotations

import numpy as np

from renderers.mitsuba import _mi
from renderers.mitsuba.exporter import export_scene, sensor_dict
from renderers.mitsuba.photons import ROULETTE_FROM
from scenes import effects_of, event_chain
from scenes.geometry import SceneGeometry, build_geometry
from scenes.model import Scene

__all__ = ["CAMERA_LIMITS", "MAX_SPECULAR_EVENTS", "camera_cut_fraction", "camera_max_depth",
           "render_camera"]

#: Specular events a camera path may have in all-paths mode (ptracer and the camera
#: tracer): the events the photon tracer follows for certain before its Russian
#: roulette. The camera integrators cut there; what they cut is measured and recorded
#: (:func:`camera_cut_fraction`, the camera tracer's stopped samples).
MAX_SPECULAR_EVENTS = ROULETTE_FROM

CAMERA_LIMITS = (
    "specular objects seen directly render black (ptracer)",
    "receivers seen through a specular surface (a pool floor under water) render black: "
    "ptracer cannot connect a diffuse vertex to the pinhole through a delta BSDF",
    "objects always occlude direct light (shadows=false not expressible)",
    "absorption only inside closed objects",
)


def camera_max_depth(scene: Scene) -> int:
    """ptracer ``max_depth``: longest counted specular chain + 2 (light and camera)."""
    if scene.settings.all_specular_paths:
        return MAX_SPECULAR_EVENTS + 2
    longest = max([len(event_chain(o).split()) - 2 for o in scene.objects if event_chain(o)]
                  or [0])
    return longest + 2


def render_camera(scene: Scene, *, spp: int, seed: int, sensor: dict | None = None,
                  geometry: SceneGeometry | None = None,
                  max_depth: int | None = None) -> np.ndarray:
    """One seed of the ptracer camera image.

    Parameters
    ----------
    spp
        Particles per pixel (ptracer traces ``spp * W * H`` light paths).
    sensor
        A Mitsuba sensor dict; default the scene camera (:func:`.exporter.sensor_dict`).
    max_depth
        ptracer's path limit in segments; default :func:`camera_max_depth`.

    Returns
    -------
    ndarray, (H, W, 3), float32
        Linear radiance in W m^-2 sr^-1, row 0 at the top of the image.
    """
    mi, _, _ = _mi.load()
    geometry = geometry or build_geometry(scene)
    depth = max_depth if max_depth is not None else camera_max_depth(scene)
    integrator = {"type": "ptracer", "max_depth": depth, "rr_depth": depth + 1}
    channels = [0, 1, 2] if "dispersion" in effects_of(scene) else [None]
    image = None
    for c in channels:
        exported = export_scene(
            scene, geometry=geometry, channel=c,
            tir_reflects=scene.settings.all_specular_paths,
            sensor=sensor or sensor_dict(scene.camera, spp=spp), integrator=integrator,
        )
        pass_seed = seed * 3 + (0 if c is None else c)
        out = np.asarray(mi.render(exported.scene, spp=spp, seed=pass_seed), dtype=np.float64)
        image = out if image is None else image + out
    return image[..., :3].astype(np.float32)


def camera_cut_fraction(scene: Scene, *, spp: int, seed: int, image: np.ndarray,
                        geometry: SceneGeometry | None = None) -> float:
    """Fraction of the camera image's light on paths longer than the event cap.

    Renders seed ``seed`` again with twice the specular events
    (2 x MAX_SPECULAR_EVENTS + 2 segments); its paths extend those of ``image``,
    rendered with the same seed and ``spp`` at :func:`camera_max_depth`, so
    ``(longer - image) / longer``, summed over pixels, is what the cap cut from the
    image (max over RGB). Paths longer than twice the cap are not counted; the
    photon tracer shows none survive that long on the bundled scenes.

    Parameters
    ----------
    image : ndarray, (H, W, 3)
        :func:`render_camera` of the same scene, ``spp`` and ``seed``.

    Returns
    -------
    float
        0 in chain mode (ptracer's limit is then the chains' own length: nothing is
        cut that the chains count); otherwise the measured fraction, >= 0 up to
        float rounding of the splats' order.
    """
    if not scene.settings.all_specular_paths:
        return 0.0
    longer = render_camera(scene, spp=spp, seed=seed, geometry=geometry,
                           max_depth=2 * MAX_SPECULAR_EVENTS + 2).astype(np.float64)
    total = longer.reshape(-1, 3).sum(axis=0)
    cut = total - np.asarray(image, dtype=np.float64).reshape(-1, 3).sum(axis=0)
    fractions = np.divide(cut, total, out=np.zeros(3), where=total > 0)
    return float(fractions.max())
