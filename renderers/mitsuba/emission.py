"""Where photons leave the light: focused, unbiased emission sampling.

Only photons that reach a caustic object (or, for the direct term, a receiver)
can contribute, so directions are drawn from a mixture over *targets*, one per
bounding sphere of those shapes, instead of the light's whole emission:

* point and spot lights: a direction uniform in the cone that subtends target j,
  pdf_j(w) = 1[w in cone j] / Omega_j with Omega_j = 2 pi (1 - cos theta_j);
  the photon's weight is I(w) / pdf(w) with the mixture pdf
  pdf(w) = sum_j q_j pdf_j(w), so overlapping cones stay unbiased;
* directional lights: a point uniform in the disk that target j's bounding sphere
  casts on a plane perpendicular to the light, pdf_j = 1[in disk j] / (pi r_j^2)
  (area measure), weight E0 / pdf;
* area lights: a point uniform on the rectangle and a cosine-weighted direction;
  each photon carries the emitter's total flux pi * I (Lambertian: Phi = pi L A,
  L = I / A), no focusing.

A photon's weight is "flux times N": the caller divides by the photon count N.

Stratified, coherent lanes
--------------------------
The two uniform numbers (u1, u2) that place a photon in its cone, disk or
rectangle come from :func:`stratified_square`, stratified at the launch's own
lane count n, whatever n is: the unit square is cut into n strata of area 1 / n
each, and lane i draws one point uniformly in stratum i. The strata are n equal
pieces of a Morton (Z-order) curve through a fine 2^15 x 2^15 grid of M = 2^30
cells: lane i draws a position t uniformly in [i M / n, (i + 1) M / n) along the
curve, takes the cell floor(t) the curve visits there, and a point uniform in that
cell. Lane i's point then has the density
p_i(x) = n * |stratum i meets cell(x)| / |cell(x)| (lengths along the curve), and
sum_i p_i(x) = n for every x: the strata tile the curve, so the sum over the lanes
of f(u) has expectation n * (integral of f over [0, 1)^2), exactly what n
independent uniform samples have. Every estimate keeps its expectation with the
same pdf and weight per photon; only the photons of one launch are no longer
independent (they are spread more evenly, which lowers the variance). When n is a
power of four, 4^k, stratum i is exactly cell i of a 2^k x 2^k grid in Morton order
(a 2^(15 - k) x 2^(15 - k) block of fine cells), and the point is uniform in it. No
lane is unstratified, so a launch of any size (a partial last launch of a budget
too) is stratified at its own size. Launches, seeds and streams stay independent,
so the K-seed variance of the mean is still an unbiased variance estimate.
Neighbouring lanes leave in neighbouring directions, which makes the ray packets
coherent: the ray casts, most of the kernel's time, are much faster.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from renderers.mitsuba import _mi
from renderers.mitsuba.exporter import area_light_frame
from scenes.geometry import TriangleMesh
from scenes.model import AreaLight, DirectionalLight, PointLight, SpotLight

__all__ = ["MAX_STRATIFIED_LANES", "Target", "bounding_sphere", "sample_photons",
           "stratified_square"]

#: Share of photons aimed at caustic objects when the direct term is also sampled
#: (the caustic region is where the reference must be least noisy).
OBJECT_SHARE = 0.75


@dataclass(frozen=True)
class Target:
    """A bounding sphere photons are aimed at: centre (m), radius (m), group."""

    center: tuple[float, float, float]
    radius: float
    group: str  # "object" or "receiver"


def bounding_sphere(mesh: TriangleMesh, group: str) -> Target:
    """Sphere around the mesh's bounding-box centre holding every vertex (+0.1 %)."""
    p = mesh.positions.astype(np.float64)
    center = (p.min(axis=0) + p.max(axis=0)) / 2
    radius = float(np.sqrt(((p - center) ** 2).sum(axis=1).max())) * 1.001 + 1e-6
    return Target(tuple(center.tolist()), radius, group)


def _mixture(sizes: list[float], groups: list[str]) -> np.ndarray:
    """q_j: groups split OBJECT_SHARE / rest; within a group proportional to size."""
    sizes = np.asarray(sizes, float)
    groups = np.asarray(groups)
    has_obj, has_rec = (groups == "object").any(), (groups == "receiver").any()
    share = {"object": OBJECT_SHARE if has_rec else 1.0,
             "receiver": 1.0 - OBJECT_SHARE if has_obj else 1.0}
    q = np.zeros(len(sizes))
    for g in ("object", "receiver"):
        sel = groups == g
        if sel.any():
            q[sel] = share[g] * sizes[sel] / sizes[sel].sum()
    return q


def _choose(dr, mi, u, q):
    """Index j with probability q_j from one uniform number (python-unrolled)."""
    index = mi.UInt32(0)
    cdf = np.cumsum(q)[:-1]
    for c in cdf:
        index += mi.UInt32(dr.select(u >= float(c), 1, 0))
    return index


def _pick(dr, index, values, cls):
    """Per-lane select of constant ``values[index]`` (few targets: unrolled)."""
    out = cls(values[0])
    for j in range(1, len(values)):
        out = dr.select(index == j, cls(values[j]), out)
    return out


def spot_falloff(dr, mi, light: SpotLight, cos_theta):
    """Relative intensity of the spot light at angle theta from its axis.

    Mitsuba 3's ``spot`` emitter (``falloff_curve`` in ``src/emitters/spot.cpp``),
    with theta_b the beam width and theta_c the cutoff (radians)::

        f(theta) = 1                                         theta <= theta_b
                 = (theta_c - theta) / (theta_c - theta_b)   theta_b < theta < theta_c
                 = 0                                         theta >= theta_c

    i.e. linear in the angle, continuous, from 1 at the beam width to 0 at the
    cutoff. Without ``beam_width`` the beam is the whole cone (a hard edge). The
    caustics-mapping shaders evaluate the same curve (``light_falloff`` in
    ``renderers/caustics_mapping/common.glsl``).

    Parameters
    ----------
    cos_theta : mi.Float
        Cosine of the angle between the emitted direction and the spot axis.

    Returns
    -------
    mi.Float
        f(theta), dimensionless in [0, 1].
    """
    # Python floats, not NumPy float64 scalars: float64 scalars would promote the
    # Dr.Jit Float lanes to Float64, which dr.scatter_reduce cannot add into the
    # float32 receiver maps.
    cutoff = math.radians(float(light.cutoff_angle))
    beam = math.radians(float(light.beam_width if light.beam_width is not None
                              else light.cutoff_angle))
    angle = dr.acos(dr.clip(cos_theta, -1.0, 1.0))
    ramp = (cutoff - angle) / max(cutoff - beam, 1e-12)
    value = dr.select(angle <= beam, 1.0, ramp)
    return mi.Float(dr.select(angle < cutoff, value, 0.0))


def _morton_compact(v):
    """Even bits of a UInt32 packed into the low 16 bits."""
    v = v & 0x55555555
    v = (v | (v >> 1)) & 0x33333333
    v = (v | (v >> 2)) & 0x0F0F0F0F
    v = (v | (v >> 4)) & 0x00FF00FF
    return (v | (v >> 8)) & 0x0000FFFF


def _fixed_to_unit(q):
    """q / 2^31 as a float32 in [0, 1), for a UInt32 q < 2^31, rounded toward zero."""
    mi, dr, _ = _mi.load()
    length = 32 - dr.lzcnt(q)  # significant bits of q
    drop = dr.maximum(length, 24) - 24
    return mi.Float((q >> drop) << drop) * (1.0 / (1 << 31))


#: Morton bits per axis of the fine grid the strata are cut from (M = 4^15 cells).
_CURVE_BITS = 15
#: Most lanes a launch may stratify (one stratum per lane: at least one fine cell each).
MAX_STRATIFIED_LANES = 1 << (2 * _CURVE_BITS)


def stratified_square(rng, n: int):
    """Per-lane (u1, u2), each uniform on [0, 1)^2, stratified over the ``n`` lanes.

    Lane i draws a point uniformly in stratum i of n equal strata along a Morton
    curve (see the module docstring): from ``rng``, one float64 per lane (the position
    along the curve) and one 32-bit integer (the point in the fine cell, 16 bits per
    axis).

    Raises
    ------
    ValueError
        ``n`` is not in 1 .. :data:`MAX_STRATIFIED_LANES`.
    """
    mi, dr, _ = _mi.load()
    if not 1 <= int(n) <= MAX_STRATIFIED_LANES:
        raise ValueError(f"a stratified launch has 1 to {MAX_STRATIFIED_LANES} lanes, got {n}")
    # M / n, the stratum's length in fine cells, enters as an opaque variable, not a
    # literal: one compiled kernel then serves every launch size (the cost study times
    # budgets from 1/256 to 1/4 of the reference's, and must not time a compile for
    # each).
    cells = 1 << (2 * _CURVE_BITS)
    stride = dr.opaque(mi.Float64, cells / int(n))
    lane = dr.arange(mi.UInt32, n)
    # t = (i + j) M / n in float64, j uniform with 52 bits: i + j < n resolves steps
    # of n 2^-53 strata, i.e. 2^-23 fine cells whatever n, and the product's rounding
    # (2^-53 relative, t < 2^30) is as small: the cell floor(t) is uniform over the
    # stratum's cells to that precision.
    t = (mi.Float64(lane) + rng.next_float64()) * stride
    cell = dr.minimum(mi.UInt32(dr.floor(t)), cells - 1)
    x, y = _morton_compact(cell), _morton_compact(cell >> 1)
    # The point inside the fine cell: 16 bits per axis below the cell's 15, a 31-bit
    # fixed-point coordinate q / 2^31. It is truncated to the 24 significant bits a
    # float32 holds before the conversion, which is then exact: rounding to nearest
    # could carry a point across its cell's upper edge (or to 1.0).
    bits = rng.next_uint32()
    u = _fixed_to_unit((x << 16) | (bits & 0xFFFF))
    v = _fixed_to_unit((y << 16) | (bits >> 16))
    return u, v


def sample_photons(light, targets: list[Target], rng, scene_center, scene_radius, *,
                   square=None):
    """Draw one photon per lane.

    ``square``: the lanes' (u1, u2) (e.g. :func:`stratified_square`); default two
    independent numbers from ``rng``.

    Returns
    -------
    ray : mi.Ray3f
    weight : mi.Color3f
        Flux times N (W), per channel, before the channel mask.
    """
    mi, dr, _ = _mi.load()
    u0, u1, u2 = rng.next_float32(), rng.next_float32(), rng.next_float32()
    if square is not None:
        u1, u2 = square
    if isinstance(light, AreaLight):
        m = area_light_frame(light)
        local = mi.Point2f(2 * u1 - 1, 2 * u2 - 1)
        origin = mi.Point3f(*[float(m[i, 3]) + float(m[i, 0]) * local.x + float(m[i, 1]) * local.y
                              for i in range(3)])
        frame = mi.Frame3f(mi.Vector3f(*map(float, m[:3, 2])))
        d = frame.to_world(mi.warp.square_to_cosine_hemisphere(
            mi.Point2f(u0, rng.next_float32())))
        weight = mi.Color3f(*map(float, np.pi * np.asarray(light.intensity, float)))
        return mi.Ray3f(origin, d), weight

    if isinstance(light, DirectionalLight):
        w = np.asarray(light.direction, float)
        w /= np.linalg.norm(w)
        frame = mi.Frame3f(mi.Vector3f(*map(float, w)))
        areas = [np.pi * t.radius**2 for t in targets]
        q = _mixture(areas, [t.group for t in targets])
        j = _choose(dr, mi, u0, q)
        centers = [mi.Point3f(*t.center) for t in targets]
        center = centers[0]
        for k in range(1, len(targets)):
            center = dr.select(j == k, centers[k], center)
        radius = _pick(dr, j, [t.radius for t in targets], mi.Float)
        disk = mi.warp.square_to_uniform_disk_concentric(mi.Point2f(u1, u2)) * radius
        x = center + frame.s * disk.x + frame.t * disk.y
        back = dr.dot(x - mi.Point3f(*scene_center), frame.n) + 2.0 * scene_radius
        origin = x - frame.n * back
        pdf = mi.Float(0.0)
        for k, t in enumerate(targets):
            rel = origin - mi.Point3f(*t.center)
            perp = rel - frame.n * dr.dot(rel, frame.n)
            # The disk a ray was drawn from holds it even where float rounding puts it
            # a hair outside (a boundary of measure zero: no bias, no infinite weight).
            inside = (dr.squared_norm(perp) <= t.radius**2) | (j == k)
            pdf += dr.select(inside, q[k] / areas[k], 0.0)
        weight = mi.Color3f(*light.irradiance) / pdf
        return mi.Ray3f(origin, frame.n), weight

    if not isinstance(light, (PointLight, SpotLight)):
        raise TypeError(f"unknown light {light!r}")
    p = np.asarray(light.position, float)
    axes, cosines, omegas = [], [], []
    for t in targets:
        rel = np.asarray(t.center) - p
        dist = float(np.linalg.norm(rel))
        if dist <= t.radius:  # light inside the bounding sphere: whole sphere
            axes.append(np.array([0.0, 0.0, 1.0]))
            cosines.append(-1.0)
        else:
            axes.append(rel / dist)
            cosines.append(float(np.sqrt(1.0 - (t.radius / dist) ** 2)))
        omegas.append(2 * np.pi * (1 - cosines[-1]))
    q = _mixture(omegas, [t.group for t in targets])
    j = _choose(dr, mi, u0, q)
    axis = mi.Vector3f(*map(float, axes[0]))
    for k in range(1, len(targets)):
        axis = dr.select(j == k, mi.Vector3f(*map(float, axes[k])), axis)
    cos_max = _pick(dr, j, cosines, mi.Float)
    local = mi.warp.square_to_uniform_cone(mi.Point2f(u1, u2), cos_max)
    d = mi.Frame3f(axis).to_world(local)
    pdf = mi.Float(0.0)
    for k in range(len(targets)):
        # The cone a direction was drawn from holds it even where float rounding puts
        # it a hair outside: otherwise the mixture pdf could be 0 and the weight
        # I / 1e-30 (about once per million photons; the boundary has measure zero,
        # so counting it inside biases nothing).
        inside = (dr.dot(d, mi.Vector3f(*map(float, axes[k]))) >= cosines[k]) | (j == k)
        pdf += dr.select(inside, q[k] / omegas[k], 0.0)
    intensity = mi.Color3f(*light.intensity)
    if isinstance(light, SpotLight):
        axis_s = np.asarray(light.direction, float)
        axis_s /= np.linalg.norm(axis_s)
        intensity *= spot_falloff(dr, mi, light, dr.dot(d, mi.Vector3f(*map(float, axis_s))))
    weight = intensity / dr.maximum(pdf, 1e-30)
    return mi.Ray3f(mi.Point3f(*map(float, p)), d), weight
