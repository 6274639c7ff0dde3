"""Light views: the frusta the passes render from, and the scene's light as point lights.

Two kinds of view per light:

* **map views** hold the receiver positions, the caustic map and the shadow map.
  A point light uses a cube of six 90-degree faces (the paper's environment caustic
  map, Section 3.6), in the order ``+x, -x, +y, -y, +z, -z``; a spot light one
  perspective face whose half-angle is the cutoff; a directional light one
  orthographic face fitted to the whole scene.
* **object views** hold the caustic object's positions and normals at the vertex
  grid resolution: one frustum fitted tightly around the caustic objects (so the
  grid is spent on the object, not the empty sky), or the six cube faces when the
  light is inside or very close to the objects' bounding sphere. The fitted view is
  a square around the objects' bounding sphere (``frustum = "square"``) or a
  rectangle fitted to their projection, rotated about the view axis to the smallest
  area (``frustum = "tight"``). Both are fitted to the points on the objects' convex
  hull, which give the views every vertex gives (:func:`_extreme_points`).

Views are rectangles on the view plane (square and symmetric but for the tight
object view), so a texel's solid angle (perspective) or area (orthographic) has a
closed form that the shaders evaluate (``texel_measure`` in ``common.glsl``).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from renderers.caustics_mapping.meshes import ContentCache
from scenes.geometry import SceneGeometry
from scenes.model import AreaLight, DirectionalLight, PointLight, Scene, SpotLight

__all__ = ["CUBE_FACES", "LightSetup", "LightView", "light_setups"]

#: Cube face names, in atlas order; a direction's face is its major axis.
CUBE_FACES = ("+x", "-x", "+y", "-y", "+z", "-z")
_CUBE_AXES = (
    ((1, 0, 0), (0, 0, 1)), ((-1, 0, 0), (0, 0, 1)),
    ((0, 1, 0), (0, 0, 1)), ((0, -1, 0), (0, 0, 1)),
    ((0, 0, 1), (0, 1, 0)), ((0, 0, -1), (0, 1, 0)),
)
#: Largest half-angle of a fitted perspective object view before the cube is used.
_MAX_FITTED_HALF_ANGLE = math.radians(60.0)
#: The objects' hull points seen so far (:func:`_extreme_points`).
_HULLS = ContentCache(8)


@dataclass(frozen=True, eq=False)
class LightView:
    """One square, symmetric frustum seen from the light.

    Attributes
    ----------
    name : str
        ``"+x"`` .. ``"-z"`` for cube faces, ``"spot"``, ``"sun"`` or ``"fitted"``.
    view_proj : ndarray, (4, 4), float64
        World -> clip matrix (OpenGL conventions, column vectors).
    perspective : bool
        Perspective (point and spot lights) or orthographic (directional).
    half_size : float
        tan(half field of view) for a perspective view; half-width in metres for an
        orthographic one (the larger half-extent of a rectangular view).
    rect : tuple of float, optional
        (x0, x1, y0, y1): the view's extent on the plane at unit distance (tangents,
        perspective) or in metres (orthographic); None: (-h, h, -h, h).
    """

    name: str
    view_proj: np.ndarray
    perspective: bool
    half_size: float
    rect: tuple[float, float, float, float] | None = None

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(x0, x1, y0, y1) of :attr:`rect`, or of the square view."""
        h = self.half_size
        return self.rect if self.rect is not None else (-h, h, -h, h)


@dataclass(frozen=True, eq=False)
class LightSetup:
    """One point-like light (an area light becomes ``samples`` of these).

    Attributes
    ----------
    kind : str
        ``"point"``, ``"spot"`` or ``"directional"``.
    position : ndarray (3,)
        Light position (m); for a directional light a point far up the beam, unused.
    direction : ndarray (3,)
        Unit travel direction (directional), spot axis (spot), emitter normal (a
        sample of an area light), else zeros.
    power : ndarray (3,)
        Intensity I (W/sr) for point and spot, irradiance E0 (W/m^2) for directional.
    cos_cutoff, cos_beam, cutoff, beam : float
        Spot cone (cosines and radians); the intensity falls linearly in angle from
        the beam width to the cutoff, as Mitsuba's spot emitter does.
    lambertian : bool
        Intensity scales with max(cos, 0) about ``direction`` (area-light samples).
    map_views, object_views : tuple of LightView
    map_faces : tuple of int
        The map views stored in the atlases, in slot order (cube faces that see no
        receiver are left out).
    cube : bool
        The map views are the six cube faces (face chosen by major axis).
    """

    kind: str
    position: np.ndarray
    direction: np.ndarray
    power: np.ndarray
    map_views: tuple[LightView, ...]
    object_views: tuple[LightView, ...]
    cube: bool
    cos_cutoff: float = -1.0
    cos_beam: float = -1.0
    cutoff: float = math.pi
    beam: float = math.pi
    lambertian: bool = False
    map_faces: tuple[int, ...] = (0,)

    @property
    def slots(self) -> tuple[int, ...]:
        """Atlas slot of each map view (-1: not stored), for ``u_map_slot``."""
        return tuple(self.map_faces.index(f) if f in self.map_faces else -1 for f in range(6))

    @property
    def type_code(self) -> int:
        """0 point, 1 spot, 2 directional (the shaders' ``u_light_type``)."""
        return {"point": 0, "spot": 1, "directional": 2}[self.kind]


def _normalize(v) -> np.ndarray:
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def _up_for(forward) -> tuple[float, float, float]:
    """An up vector that keeps world x along the view's x for steep views, so the
    square frustum's edges line up with axis-aligned scenes (no 45-degree waste)."""
    f = _normalize(forward)
    return (0.0, 1.0, 0.0) if abs(f[2]) > 0.7 else (0.0, 0.0, 1.0)


def look_at(eye, forward, up) -> np.ndarray:
    """World -> view matrix looking along ``forward`` (the view's -z)."""
    f = _normalize(forward)
    up = np.asarray(up, float)
    if abs(f @ _normalize(up)) > 0.999:
        up = np.array([1.0, 0, 0]) if abs(f[0]) < 0.9 else np.array([0, 1.0, 0])
    s = _normalize(np.cross(f, up))
    u = np.cross(s, f)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = s, u, -f
    m[:3, 3] = -m[:3, :3] @ np.asarray(eye, float)
    return m


def perspective(t: float, near: float, far: float) -> np.ndarray:
    """Square symmetric perspective with tan(half-angle) ``t``."""
    m = np.zeros((4, 4))
    m[0, 0] = m[1, 1] = 1.0 / t
    m[2, 2] = -(far + near) / (far - near)
    m[2, 3] = -2 * far * near / (far - near)
    m[3, 2] = -1.0
    return m


def frustum(rect: tuple[float, float, float, float], near: float, far: float, *,
            perspective_view: bool) -> np.ndarray:
    """Asymmetric projection of the view-plane rectangle ``rect`` = (x0, x1, y0, y1):
    tangents at unit distance (perspective) or metres (orthographic)."""
    x0, x1, y0, y1 = rect
    m = np.zeros((4, 4))
    m[0, 0], m[1, 1] = 2.0 / (x1 - x0), 2.0 / (y1 - y0)
    if perspective_view:
        m[0, 2], m[1, 2] = (x1 + x0) / (x1 - x0), (y1 + y0) / (y1 - y0)
        m[2, 2] = -(far + near) / (far - near)
        m[2, 3] = -2 * far * near / (far - near)
        m[3, 2] = -1.0
    else:
        m[0, 3], m[1, 3] = -(x1 + x0) / (x1 - x0), -(y1 + y0) / (y1 - y0)
        m[2, 2] = -2.0 / (far - near)
        m[2, 3] = -(far + near) / (far - near)
        m[3, 3] = 1.0
    return m


def _tight_rect(x: np.ndarray, y: np.ndarray, *, grid: int) -> tuple[float, tuple[float, ...]]:
    """The rotation about the view axis (radians, 1-degree steps over a quarter
    turn) whose axis-aligned bounding rectangle of the points (x, y) on the view
    plane is smallest, and that rectangle (x0, x1, y0, y1) widened on each side by half
    a texel of a ``grid`` x ``grid`` view plus 0.1 % (the vertices bound the projection
    of the triangles exactly; the 0.1 % is for rounding).

    The border: grid vertices sit at texel centres, so the strip between the
    rectangle's edge and the outer row of vertices, half a texel wide, lies in no grid
    quad and is sampled by that row alone, whatever its patches (``rim_patches``).
    Fitted without a border the objects' outline lies in that strip on every side;
    where the light reaching a receiver comes from a sliver there (the outer wall of
    ``scenes/hard/concave``'s shallow bowl under a 45 deg sun), 13 vertices of the row
    carried 14 % of the reference's floor flux at the grid's spacing (strong, grid 128:
    flux ratio 1.076). With the border the strip holds nothing, the outer row sees
    nothing, and the outline lies inside the quads, at (grid - 1)^2 / grid^2 of the
    vertices on the objects (1.6 % fewer at grid 128).

    A linear function's extremes over the points lie on their convex hull, so the
    search runs over the hull's vertices only (234 of a sphere's 10,242: 2 ms a frame
    instead of 6)."""
    x, y = _hull_points(np.asarray(x, float), np.asarray(y, float))
    angles = np.radians(np.arange(0.0, 90.0, 1.0))
    c, s = np.cos(angles)[:, None], np.sin(angles)[:, None]
    xr, yr = c * x - s * y, s * x + c * y
    area = np.ptp(xr, axis=1) * np.ptp(yr, axis=1)
    best = int(np.argmin(area))
    lo = np.array([xr[best].min(), yr[best].min()])
    hi = np.array([xr[best].max(), yr[best].max()])
    # A border b of the width W + 2 b is half a texel when b = W / (2 (grid - 1)).
    pad = (0.5 / max(grid - 1, 1) + 1e-3) * (hi - lo) + 1e-9
    lo, hi = lo - pad, hi + pad
    return float(angles[best]), (float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1]))


def _hull_points(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The vertices of the convex hull of the points (x, y), or all of them where they
    have no hull of positive area (fewer than three, or all on one line)."""
    from scipy.spatial import ConvexHull, QhullError  # noqa: PLC0415 - scipy loads only here

    if len(x) < 4:
        return x, y
    try:
        index = ConvexHull(np.column_stack([x, y])).vertices
    except QhullError:       # collinear or coincident points: every point is extreme
        return x, y
    return x[index], y[index]


def _rotate_about_view_axis(view: np.ndarray, angle: float) -> np.ndarray:
    rot = np.eye(4)
    c, s = math.cos(angle), math.sin(angle)
    rot[0, :2], rot[1, :2] = (c, -s), (s, c)
    return rot @ view


def _sphere_seen_from(eye: np.ndarray, points: np.ndarray):
    """(centre, radius, distance from ``eye``) of the points' bounding sphere (about
    their box's centre), or None when ``eye`` is inside or within 5 % of it."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    center = (lo + hi) / 2
    radius = float(np.linalg.norm(points - center, axis=1).max())
    dist = float(np.linalg.norm(center - eye))
    return None if dist <= radius * 1.05 else (center, radius, dist)


def _tight_perspective(eye: np.ndarray, points: np.ndarray, name: str, *, grid: int):
    """A rectangular, asymmetric frustum fitted to the points' projection, or None
    when the light is too close (the cube is used then)."""
    sphere = _sphere_seen_from(eye, points)
    if sphere is None:
        return None
    center, _, dist = sphere
    base = look_at(eye, center - eye, _up_for(center - eye))
    local = points @ base[:3, :3].T + base[:3, 3]
    depth = -local[:, 2]
    if depth.min() <= 0:
        return None
    angle, rect = _tight_rect(local[:, 0] / depth, local[:, 1] / depth, grid=grid)
    if math.atan(max(abs(v) for v in rect)) > _MAX_FITTED_HALF_ANGLE:
        return None
    near, far = max(depth.min() * 0.9, dist * 1e-4), depth.max() * 1.1
    view = _rotate_about_view_axis(base, angle)
    return LightView(name, frustum(rect, near, far, perspective_view=True) @ view, True,
                     max(abs(v) for v in rect), rect)


def _tight_orthographic(direction: np.ndarray, points: np.ndarray, name: str, *,
                        grid: int) -> LightView:
    """An orthographic view along ``direction`` fitted to the points like
    :func:`_tight_perspective` (metres instead of tangents)."""
    base = look_at(np.zeros(3), direction, _up_for(direction))
    local = points @ base[:3, :3].T
    angle, rect = _tight_rect(local[:, 0], local[:, 1], grid=grid)
    depth = local[:, 2].max() - local[:, 2].min()
    # Eye on the light side of every point, looking along the rays.
    eye_local = np.array([0.0, 0.0, local[:, 2].max() + 0.05 * depth + 1e-6])
    eye = base[:3, :3].T @ eye_local
    near, far = 0.025 * depth + 1e-7, 1.1 * depth + 0.05 * depth + 2e-6
    view = _rotate_about_view_axis(look_at(eye, direction, _up_for(direction)), angle)
    return LightView(name, frustum(rect, near, far, perspective_view=False) @ view, False,
                     max(abs(v) for v in rect), rect)


def orthographic(h: float, near: float, far: float) -> np.ndarray:
    """Square symmetric orthographic projection of half-width ``h``."""
    m = np.eye(4)
    m[0, 0] = m[1, 1] = 1.0 / h
    m[2, 2] = -2.0 / (far - near)
    m[2, 3] = -(far + near) / (far - near)
    return m


def _depth_range(points: np.ndarray, eye: np.ndarray) -> tuple[float, float]:
    dist = np.linalg.norm(points - eye, axis=1)
    far = float(dist.max()) * 1.05 + 1e-9
    near = max(float(dist.min()) * 0.5, far * 1e-4)
    return near, far


def _cube(eye: np.ndarray, points: np.ndarray) -> tuple[LightView, ...]:
    near, far = _depth_range(points, eye)
    near = min(near, far * 1e-3)
    proj = perspective(1.0, near, far)
    return tuple(
        LightView(name, proj @ look_at(eye, fwd, up), True, 1.0)
        for name, (fwd, up) in zip(CUBE_FACES, _CUBE_AXES, strict=False)
    )


def _fitted_perspective(eye: np.ndarray, points: np.ndarray, name: str):
    """A frustum around the points' bounding sphere, or None if it would be too wide."""
    sphere = _sphere_seen_from(eye, points)
    if sphere is None:
        return None
    center, radius, dist = sphere
    half = math.asin(radius / dist)
    if half > _MAX_FITTED_HALF_ANGLE:
        return None
    t = math.tan(half) * 1.02
    near = max((dist - radius) * 0.9, dist * 1e-4)
    far = dist + radius * 1.1
    view = look_at(eye, center - eye, _up_for(center - eye))
    return LightView(name, perspective(t, near, far) @ view, True, t)


def _orthographic_fit(direction: np.ndarray, points: np.ndarray, name: str) -> LightView:
    """An orthographic view along ``direction`` enclosing ``points``."""
    view = look_at(np.zeros(3), direction, _up_for(direction))
    local = points @ view[:3, :3].T
    lo, hi = local.min(axis=0), local.max(axis=0)
    center_xy = (lo[:2] + hi[:2]) / 2
    h = float(max(hi[0] - lo[0], hi[1] - lo[1])) / 2 * 1.02 + 1e-9
    depth = hi[2] - lo[2]
    # Eye on the light side of every point, looking along the rays.
    eye_local = np.array([center_xy[0], center_xy[1], hi[2] + 0.05 * depth + 1e-6])
    eye = view[:3, :3].T @ eye_local
    near, far = 0.025 * depth + 1e-7, 1.1 * depth + 0.05 * depth + 2e-6
    return LightView(name, orthographic(h, near, far) @ look_at(eye, direction, _up_for(direction)),
                     False, h)


def _points(geometry: SceneGeometry, receivers: bool, objects: bool) -> np.ndarray:
    parts = []
    if receivers:
        parts += [g.mesh.positions for g in geometry.receivers]
    if objects:
        parts += [g.mesh.positions for g in geometry.objects]
    return np.concatenate(parts).astype(np.float64)


def _extreme_points(points: np.ndarray) -> np.ndarray:
    """The points on their convex hull: its vertices, and the points qhull finds
    within rounding of a facet (all of them where the hull has no volume).

    The object views depend on the objects' points only through extremes of linear
    functions (their box, depths along a direction, the rectangle of their
    projection: a perspective projection of points in front of the eye keeps the
    image of each inner point inside that of the hull) and through the largest
    distance from a centre (a convex function), which the hull's points attain: the
    same views from fewer points (the bunny's 28,088 vertices: 1,640; the light
    views took 8 ms of strong's frame on llvmpipe's 2 cores, 4 ms of paper's).
    Remembered by the points' content, as a frame's meshes are built anew.
    """
    return _HULLS.get((points,), lambda: _hull_of(points))


def _hull_of(points: np.ndarray) -> np.ndarray:
    """:func:`_extreme_points` computed, read-only."""
    from scipy.spatial import ConvexHull, QhullError  # noqa: PLC0415 - loads only here

    try:
        hull = ConvexHull(points)
        kept = points[np.union1d(hull.vertices, hull.coplanar[:, 0])]
    except (QhullError, ValueError):     # flat, or too few points: all of them
        kept = points.copy()
    kept.flags.writeable = False
    return kept


def _hammersley(n: int) -> np.ndarray:
    """n deterministic, well-spread points in [0, 1)^2 (Hammersley set)."""
    i = np.arange(n)
    bits = np.zeros(n)
    base, k = 0.5, i.copy()
    while np.any(k):
        bits += (k & 1) * base
        k >>= 1
        base /= 2
    return np.stack([(i + 0.5) / n, bits], axis=1)


def light_setups(scene: Scene, geometry: SceneGeometry, *,
                 frustum_fit: str = "square") -> tuple[LightSetup, ...]:
    """The scene's light as point-like lights with their views.

    ``frustum_fit`` is ``settings.frustum``: ``"square"`` or ``"tight"`` object views
    (a tight view keeps a border of half a texel of the scene's ``settings.grid``).

    An area light becomes ``samples`` Lambertian point lights of intensity
    ``intensity / samples`` on a Hammersley set over the rectangle (paper Section 3.1:
    "area lights can be accommodated by sampling a number of point lights").
    """
    light = scene.light
    everything = _points(geometry, True, True)
    objects = _extreme_points(_points(geometry, False, True))
    tight = frustum_fit == "tight"
    grid = scene.settings.grid
    fit = functools.partial(_tight_perspective, grid=grid) if tight else _fitted_perspective
    if isinstance(light, DirectionalLight):
        d = _normalize(light.direction)
        return (LightSetup(
            kind="directional", position=np.zeros(3), direction=d,
            power=np.asarray(light.irradiance, float),
            map_views=(_orthographic_fit(d, everything, "sun"),),
            object_views=(_tight_orthographic(d, objects, "fitted", grid=grid) if tight
                          else _orthographic_fit(d, objects, "fitted"),), cube=False,
        ),)
    if isinstance(light, SpotLight):
        eye = np.asarray(light.position, float)
        axis = _normalize(light.direction)
        cutoff = math.radians(light.cutoff_angle)
        beam = math.radians(light.beam_width or light.cutoff_angle)
        near, far = _depth_range(everything, eye)
        view = LightView("spot", perspective(math.tan(cutoff), near, far)
                         @ look_at(eye, axis, _up_for(axis)), True, math.tan(cutoff))
        fitted = fit(eye, objects, "fitted")
        return (LightSetup(
            kind="spot", position=eye, direction=axis, power=np.asarray(light.intensity, float),
            map_views=(view,), object_views=(fitted,) if fitted else (view,), cube=False,
            cos_cutoff=math.cos(cutoff), cos_beam=math.cos(beam), cutoff=cutoff, beam=beam,
        ),)
    if isinstance(light, PointLight):
        eyes = [(np.asarray(light.position, float), np.asarray(light.intensity, float), None)]
    elif isinstance(light, AreaLight):
        n = _normalize(light.normal)
        helper = np.array([1.0, 0, 0]) if abs(n[0]) < 0.9 else np.array([0, 1.0, 0])
        e1 = _normalize(np.cross(n, helper))
        e2 = np.cross(n, e1)
        uv = (_hammersley(light.samples) - 0.5) * np.asarray(light.size)
        power = np.asarray(light.intensity, float) / light.samples
        eyes = [(np.asarray(light.center) + a * e1 + b * e2, power, n) for a, b in uv]
    else:
        raise TypeError(f"unknown light {light!r}")
    setups = []
    for eye, power, normal in eyes:
        fitted = fit(eye, objects, "fitted")
        cube = _cube(eye, everything)
        setups.append(LightSetup(
            kind="point", position=eye,
            direction=np.zeros(3) if normal is None else normal, power=power,
            map_views=cube, object_views=(fitted,) if fitted else cube, cube=True,
            lambertian=normal is not None,
        ))
    return tuple(setups)
