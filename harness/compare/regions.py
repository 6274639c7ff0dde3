"""Regions metrics are computed over: the caustic region and the object mask."""

from __future__ import annotations

import numpy as np

from harness.raycast import MeshTracer, camera_rays
from renderers.results import CAUSTIC_FRACTION
from renderers.results import caustic_region as _reference_region
from scenes.geometry import SceneGeometry
from scenes.model import Camera

__all__ = ["CAUSTIC_FRACTION", "caustic_region", "object_mask", "object_region",
           "scene_caustic_region"]


def caustic_region(reference: np.ndarray, *, fraction: float = CAUSTIC_FRACTION) -> np.ndarray:
    """Boolean (H, W) mask where ``reference`` (H, W, 3) is bright enough to be caustic.

    The threshold is ``fraction`` × the 99.5th percentile of the luminance; an
    all-black reference gives an empty mask. The rule lives with the result types
    (:func:`renderers.results.caustic_region`), so the Mitsuba reference measures its
    noise over the same region.
    """
    return _reference_region(reference, fraction=fraction)


def scene_caustic_region(independent: np.ndarray) -> np.ndarray:
    """The caustic region a receiver map is scored over, for every method of a scene:
    :func:`caustic_region` of the *independent* reference (the K disjoint seeds).

    The region belongs to the scene, not the method: it is computed from references
    alone, once per scene and receiver, and every method, study, accuracy check
    sweep row, regression lock (the golden's ``region<i>.png``, from an independent
    reference of its own) and pytest assertion of that scene scores the
    same texels, so a method that spreads dim light
    cannot move its own denominator (light it puts outside is scored by the
    ``full`` region and by the ``stray_flux`` measure). It is not thresholded on the
    scored reference itself: that keeps the texels its noise pushed up and biases
    every noise correction (``harness.metrics.excess``); the independent reference's
    noise is independent of the scored one's.

    The paper figures (:meth:`harness.figures.common.FigureContext.region`) and the
    temporal study's frames (each frame's independent reference) threshold their
    independent references the same way.

    Parameters
    ----------
    independent : ndarray (H, W, 3)
        The independent reference's caustic irradiance (W/m²).

    Returns
    -------
    ndarray (H, W) of bool
    """
    return caustic_region(independent)


def _object_hits(camera: Camera, geometry: SceneGeometry) -> np.ndarray:
    """(H, W) bool: the pixel centre's primary ray meets a caustic object's triangles."""
    width, height = camera.resolution
    origins, directions = camera_rays(camera)
    hits = MeshTracer([o.mesh for o in geometry.objects])(origins, directions)
    return np.isfinite(hits.distance).reshape(height, width)


def _grow(mask: np.ndarray, steps: int) -> np.ndarray:
    """``mask`` dilated by ``steps`` pixels (4-neighbourhood)."""
    for _ in range(steps):
        grown = mask.copy()
        grown[1:] |= mask[:-1]
        grown[:-1] |= mask[1:]
        grown[:, 1:] |= mask[:, :-1]
        grown[:, :-1] |= mask[:, 1:]
        mask = grown
    return mask


def object_mask(camera: Camera, geometry: SceneGeometry, *, dilate: int = 1) -> np.ndarray:
    """Boolean (H, W) mask of camera pixels that see a caustic object.

    Computed by casting the camera's primary rays against the objects' triangles and
    dilated by ``dilate`` pixels, so pixels on the silhouette, where the two
    renderers' rasterisation and sampling differ, are excluded too.
    """
    return _grow(_object_hits(camera, geometry), dilate)


def object_region(camera: Camera, geometry: SceneGeometry, *, erode: int = 1) -> np.ndarray:
    """Boolean (H, W) mask of the camera pixels inside a caustic object's silhouette:
    the primary-ray hits shrunk by ``erode`` pixels, so the silhouette pixels, where
    the renderers' rasterisation and subpixel sampling differ, are scored by neither
    this region nor the one without the object (:func:`object_mask`)."""
    return ~_grow(~_object_hits(camera, geometry), erode)
