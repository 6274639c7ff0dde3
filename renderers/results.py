"""Result types both renderers produce (the radiometric contract, docs/architecture.md).

Map layout: a receiver irradiance map is a float32 array of shape (H, W, 3) over the
receiver's (u, v) domain ``extent = (umin, umax, vmin, vmax)``; column i covers
u in [umin + i Δu, umin + (i+1) Δu) with Δu = (umax - umin) / W, row j covers
v likewise, **row 0 at vmin**. Values are caustic irradiance E in W/m² (RGB). Camera
images are radiance in W m⁻² sr⁻¹, shape (H, W, 3), row 0 at the top of the image.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from scenes.colour import luminance

__all__ = ["CAUSTIC_FRACTION", "ReceiverMap", "RenderResult", "caustic_region",
           "texel_centers"]

#: A texel is in the caustic region when the reference's luminance exceeds this
#: fraction of its 99.5th percentile (a robust maximum that ignores fireflies).
CAUSTIC_FRACTION = 0.1


@dataclass(frozen=True, eq=False)
class ReceiverMap:
    """Caustic irradiance over one receiver's (u, v) domain.

    Attributes
    ----------
    irradiance : ndarray, (H, W, 3), float32
        E in W/m², row 0 at vmin.
    extent : tuple of float
        (umin, umax, vmin, vmax) in the receiver's (u, v) units.
    variance : ndarray, (H, W, 3), float32, or None
        Per-texel variance of the mean (references rendered with K seeds).
    seed_maps : ndarray, (K, H, W, 3), float32, or None
        The K seeds' own estimates of E (references): ``irradiance`` is their mean and
        ``variance`` their unbiased variance over K. They carry what the variance
        does not: the noise's skew and the covariance of neighbouring texels.
    """

    irradiance: np.ndarray
    extent: tuple[float, float, float, float]
    variance: np.ndarray | None = None
    seed_maps: np.ndarray | None = None

    def texel_area(self) -> float:
        """Area of one texel in (u, v) units squared (m² for planes and heightfields)."""
        umin, umax, vmin, vmax = self.extent
        h, w = self.irradiance.shape[:2]
        return (umax - umin) * (vmax - vmin) / (w * h)

    def total_flux(self) -> np.ndarray:
        """Σ E · texel area, per channel: watts for planar receivers."""
        return self.irradiance.reshape(-1, 3).sum(axis=0) * self.texel_area()


@dataclass(frozen=True, eq=False)
class RenderResult:
    """One render of a scene by either renderer.

    Attributes
    ----------
    renderer : str
        ``"caustics_mapping"`` or ``"mitsuba"``.
    camera : ndarray, (H, W, 3), float32, or None
        Linear radiance from the scene camera; None: the method gave no camera image
        (an external render of the receivers alone), and the camera is not scored.
    receivers : tuple of ReceiverMap
        One per ``scene.receivers`` entry, in order; empty: the method gave no
        receiver map (an external render of the camera alone), and none is scored.
    effects : tuple of str
        The effects simulated (``scenes.effects_of``).
    timings : dict
        Seconds per stage, e.g. ``{"caustic_map": 0.004}``.
    timer : str
        Which clock produced ``timings`` (e.g. ``"ctx.finish + perf_counter"``).
    metadata : dict
        JSON-serialisable extras: passes run, event chains, photons, seeds, versions.
    records : dict of str to ndarray or None
        Per-vertex light-path records of a renderer that traces light from a vertex
        grid (caustics mapping; None for the others): ``status`` (K,), ``origin``
        (K, 3) m, ``direction`` (K, 3), ``receiver`` (K,) and ``flux`` (K, 3) W, each
        vertex's flux at the share its splats draw, so the splatted vertices' flux is
        what the maps received. The stability checks and the method's flux budget read
        them.
    """

    renderer: str
    camera: np.ndarray | None
    receivers: tuple[ReceiverMap, ...]
    effects: tuple[str, ...]
    timings: dict[str, float] = field(default_factory=dict)
    timer: str = ""
    metadata: dict[str, Any] = field(default_factory=dict)
    records: dict[str, np.ndarray] | None = field(default=None, repr=False)  # large arrays


def caustic_region(reference: np.ndarray, *, fraction: float = CAUSTIC_FRACTION) -> np.ndarray:
    """Boolean (H, W) mask where ``reference`` (H, W, 3, linear RGB; or (H, W)
    luminance) is bright enough to be caustic: the region a comparison scores, and
    the region the Mitsuba reference measures its own noise over.

    The threshold is ``fraction`` x the 99.5th percentile of the luminance
    (:func:`scenes.colour.luminance`, Rec. 709); an all-black reference gives an
    empty mask.
    """
    lum = luminance(reference)
    top = float(np.percentile(lum, 99.5))
    if top <= 0:
        return np.zeros(lum.shape, bool)
    return lum > fraction * top


def texel_centers(extent, shape) -> tuple[np.ndarray, np.ndarray]:
    """(u, v) of texel centres for a map of ``shape`` = (H, W): arrays of W and H."""
    umin, umax, vmin, vmax = extent
    h, w = shape[:2]
    u = umin + (np.arange(w) + 0.5) * (umax - umin) / w
    v = vmin + (np.arange(h) + 0.5) * (vmax - vmin) / h
    return u, v
