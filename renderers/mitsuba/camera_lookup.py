"""The camera tracer's caustic lookup maps: their resolution, photons and lookups.

The camera tracer (:mod:`.camera_trace`) shades a receiver with the photon
tracer's caustic irradiance, looked up in maps traced for it, one set per seed.

Resolution. A pixel averages the caustic irradiance over its footprint on the
receiver; a map texel larger than that footprint blurs what the pixel would
resolve. The footprint is measured (:meth:`.camera_trace.CameraTracer.footprints`):
the rays through a pixel's centre and its right and lower neighbours' reach the
receiver at (u, v), (u, v) + J_x and (u, v) + J_y by the same chain, and
sqrt|det J| is the pixel's footprint length (receiver units). Rule
(:func:`plan_lookup`): the lookup resolution is the receiver map's
(``settings.receiver_map``) times 2^k, the smallest k >= 0 whose texel side
(geometric mean of its two sides, t_k = t_0 / 2^k) is at most f, the
:data:`FOOTPRINT_PERCENTILE`-th percentile of the receiver's footprint lengths, so
90 % of the pixels cover at least one texel; capped at :data:`LOOKUP_CAP` texels a
side (then recorded as coarser than the footprint). All receivers share one
resolution (the photon tracer has one grid), the finest any of them needs.

Photons. A pixel covering several texels averages their noise: photon counting
gives it the noise of the photons landing in its footprint, whatever the texel
size, once texels are smaller. So the photons per seed are the receiver maps'
N_0 times (t_0 / max(f, t_k))^2 (at least 1): the noise of one footprint of f
(or of one texel where the cap leaves it larger) equals the receiver map's
per-texel noise. Keeping every *texel* at that noise instead would cost 4^k N_0,
(f / t_k)^2 times more (up to 4x), for pixels that never see one texel alone.
Cost: the lookup maps trace (t_0 / f)^2 N_0 photons per seed, at a resolution 4^k
times the receiver map's (glass_sphere at 512^2: f = 1.34 cm, t_0 = 3.1 cm: 1024^2,
5.5 N_0).

Lookup (:func:`bilinear`): bilinear between the four nearest texel centres (texel
i's centre at umin + (i + 1/2) du), clamped at the map's edges, with the photon
tracer's own (u, v) -> texel mapping (row 0 at vmin).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from renderers.mitsuba import _mi

__all__ = ["FOOTPRINT_PERCENTILE", "LOOKUP_CAP", "LookupMaps", "LookupPlan", "bilinear",
           "plan_lookup"]

#: Percentile of the pixels' footprint lengths that one lookup texel must not exceed.
FOOTPRINT_PERCENTILE = 10.0
#: Largest lookup map side, in texels (2048^2 x 3 float32 = 48 MiB per receiver).
LOOKUP_CAP = 2048


@dataclass(frozen=True)
class LookupPlan:
    """The caustic lookup maps' resolution and photons, and what they came from.

    Attributes
    ----------
    resolution : (W, H)
        Texels per lookup map along u and v.
    photons : int
        Photons per seed (per channel pass) for the lookup maps.
    footprints : tuple of float or None
        Per receiver, the :data:`FOOTPRINT_PERCENTILE`-th percentile of the pixels'
        footprint lengths (receiver (u, v) units per pixel; None: no pixel sees it).
    texels : tuple of float
        Per receiver, the lookup texel's side (geometric mean), same units.
    capped : bool
        :data:`LOOKUP_CAP` kept the lookup coarser than the footprint rule asked.
    """

    resolution: tuple[int, int]
    photons: int
    footprints: tuple[float | None, ...]
    texels: tuple[float, ...]
    capped: bool


def plan_lookup(footprints, extents, *, receiver_map: tuple[int, int],
                photons: int) -> LookupPlan:
    """The lookup resolution and photons per seed by the rule of the module docstring.

    Parameters
    ----------
    footprints : sequence of ndarray
        Per receiver, the footprint lengths of the pixels that see it (any shape;
        NaN entries are ignored).
    extents : sequence of (umin, umax, vmin, vmax)
        Per receiver, its (u, v) domain.
    receiver_map : (W, H)
        The receiver maps' resolution.
    photons : int
        The receiver maps' photons per seed.
    """
    w0, h0 = receiver_map
    lengths = [np.asarray(f, float)[np.isfinite(f)] for f in footprints]
    found = [float(np.percentile(f, FOOTPRINT_PERCENTILE)) if f.size else None
             for f in lengths]
    base = [math.sqrt((e[1] - e[0]) * (e[3] - e[2]) / (w0 * h0)) for e in extents]
    seen = [(b, f) for b, f in zip(base, found, strict=True) if f is not None and f > 0]
    wanted = max([math.ceil(math.log2(b / f)) for b, f in seen] + [0])
    room = max(0, math.floor(math.log2(LOOKUP_CAP / max(w0, h0))))
    scale = 1 << min(wanted, room)
    factor = max([(b / max(f, b / scale)) ** 2 for b, f in seen] + [1.0])
    return LookupPlan(resolution=(w0 * scale, h0 * scale),
                      photons=math.ceil(int(photons) * factor), footprints=tuple(found),
                      texels=tuple(b / scale for b in base), capped=wanted > room)


@dataclass(frozen=True, eq=False)
class LookupMaps:
    """Caustic irradiance maps of every receiver, flattened for Dr.Jit lookups.

    Attributes
    ----------
    values : mi.Float
        The maps one after another, each (H, W, 3) row-major (row 0 at vmin),
        irradiance in W/m².
    resolution : (W, H)
        Texels per map along u and v (the same for every receiver).
    extents : tuple of (umin, umax, vmin, vmax)
        Per receiver, the (u, v) domain its map covers.
    """

    values: object
    resolution: tuple[int, int]
    extents: tuple[tuple[float, float, float, float], ...]

    @classmethod
    def from_arrays(cls, maps, extents) -> LookupMaps:
        """From per-receiver (H, W, 3) arrays (all of one shape) and their extents."""
        mi, _, _ = _mi.load()
        arrays = [np.ascontiguousarray(m, dtype=np.float32) for m in maps]
        h, w = arrays[0].shape[:2]
        return cls(values=mi.Float(np.concatenate([a.ravel() for a in arrays])),
                   resolution=(int(w), int(h)),
                   extents=tuple(tuple(float(x) for x in e) for e in extents))


def bilinear(maps: LookupMaps, index: int, uv):
    """Irradiance (mi.Color3f, W/m²) of receiver ``index``'s map at ``uv``
    (mi.Point2f), bilinear between texel centres, clamped at the edges."""
    mi, dr, _ = _mi.load()
    w, h = maps.resolution
    umin, umax, vmin, vmax = maps.extents[index]
    # Texel coordinates of uv, measured from the first texel's centre.
    fx = dr.clip((uv.x - umin) / (umax - umin) * w - 0.5, 0.0, w - 1.0)
    fy = dr.clip((uv.y - vmin) / (vmax - vmin) * h - 0.5, 0.0, h - 1.0)
    x0, y0 = dr.floor(fx), dr.floor(fy)
    ax, ay = fx - x0, fy - y0
    x0, y0 = mi.UInt32(x0), mi.UInt32(y0)
    x1, y1 = dr.minimum(x0 + 1, w - 1), dr.minimum(y0 + 1, h - 1)
    base = index * w * h * 3

    def texel(x, y):
        i = base + (y * w + x) * 3
        return mi.Color3f(*(dr.gather(mi.Float, maps.values, i + c) for c in range(3)))

    return ((1 - ay) * ((1 - ax) * texel(x0, y0) + ax * texel(x1, y0))
            + ay * ((1 - ax) * texel(x0, y1) + ax * texel(x1, y1)))
