"""The caustics-mapping renderer: runs the passes the scene's effects call for.

``render(scene)`` returns a :class:`harness.results.RenderResult`;
``render_frame(scene)`` also returns the per-vertex records, the positions atlases
and the caustic map, for the CLI's outputs, the NumPy mirror and convergence studies.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import moderngl
import numpy as np

from harness.geometry import SceneGeometry, build_geometry
from harness.results import ReceiverMap, RenderResult
from harness.scene import Scene, effects_of
from renderers.caustics_mapping.camera import CameraInputs, render_camera
from renderers.caustics_mapping.caustic_splat import splat_caustic_map
from renderers.caustics_mapping.caustic_trace import (
    STATUS,
    Trace,
    material_table,
    run_caustic_trace,
)
from renderers.caustics_mapping.context import GLError, PassTimer, create_context, pool
from renderers.caustics_mapping.estimators import MapLookup
from renderers.caustics_mapping.lights import CUBE_FACES, LightSetup, light_setups
from renderers.caustics_mapping.lowpass import lowpass_filter
from renderers.caustics_mapping.meshes import upload_mesh
from renderers.caustics_mapping.object_positions import render_object_surfaces
from renderers.caustics_mapping.receiver_positions import render_receiver_positions
from renderers.caustics_mapping.receiver_splat import splat_receiver_map, uv_mapping
from renderers.caustics_mapping.shadow_map import render_shadow_map

__all__ = ["Frame", "newton_eps", "render", "render_frame"]

_CHANNELS = "rgb"


@dataclass(eq=False)
class Frame:
    """Everything one render produced.

    Attributes
    ----------
    result : RenderResult
    hits : dict of ndarray
        Per grid vertex of every trace pass, concatenated: ``origin`` (K, 3) v (m),
        ``direction`` (K, 3) r, ``history`` (K, iterations + 1) estimated d (m) after
        each iteration, ``distance`` (K,) final d, ``hit`` (K, 3), ``status`` (K,)
        (:data:`.caustic_trace.STATUS`), ``flux`` (K, 3), ``receiver`` (K,), ``view``
        (K,) object view, ``channel`` (K,) (-1 all), ``light`` (K,) light sample.
    caustic_map : ndarray (M, slots * M, 3)
        The caustic-map atlas (W/m^2), row 0 at the bottom, one slot per stored map
        view (``metadata["map_faces"]`` in order); summed over light samples.
    lookups : list of MapLookup
        The receiver positions atlas read back, per light sample (for the mirror).
    eps : float
        Newton's finite-difference step used (m).
    """

    result: RenderResult
    hits: dict[str, np.ndarray]
    caustic_map: np.ndarray
    lookups: list[MapLookup] = field(default_factory=list)
    eps: float = 0.0


def newton_eps(scene: Scene, geometry: SceneGeometry) -> float:
    """``settings.newton_eps``, or 1e-3 of the light-to-receiver distance (for a
    directional light, of the caustic-object-to-receiver distance)."""
    if scene.settings.newton_eps is not None:
        return float(scene.settings.newton_eps)
    rec = np.concatenate([g.mesh.positions for g in geometry.receivers]).astype(float)
    target = (rec.min(axis=0) + rec.max(axis=0)) / 2
    if hasattr(scene.light, "position"):
        source = np.asarray(scene.light.position, float)
    elif hasattr(scene.light, "center"):
        source = np.asarray(scene.light.center, float)
    else:
        obj = np.concatenate([g.mesh.positions for g in geometry.objects]).astype(float)
        source = (obj.min(axis=0) + obj.max(axis=0)) / 2
    return max(1e-3 * float(np.linalg.norm(target - source)), 1e-12)


def _sample_points(geometry: SceneGeometry) -> np.ndarray:
    """Receiver vertices plus a barycentric lattice on coarse meshes (face culling)."""
    parts = []
    lattice = np.array([(a, b) for a in np.linspace(0, 1, 9) for b in np.linspace(0, 1, 9)
                        if a + b <= 1])
    for rec in geometry.receivers:
        p = rec.mesh.positions.astype(float)
        parts.append(p)
        if len(rec.mesh.faces) < 5000:
            tri = p[rec.mesh.faces]
            parts.append((tri[:, None, 0] * (1 - lattice.sum(1))[None, :, None]
                          + tri[:, None, 1] * lattice[None, :, :1]
                          + tri[:, None, 2] * lattice[None, :, 1:]).reshape(-1, 3))
    return np.concatenate(parts)


def _faces(light: LightSetup, points: np.ndarray) -> tuple[int, ...]:
    """Map views that see any of ``points``: all of a single view, the cube faces hit."""
    if not light.cube:
        return (0,)
    d = points - light.position
    a = np.abs(d)
    face = np.where((a[:, 0] >= a[:, 1]) & (a[:, 0] >= a[:, 2]), np.where(d[:, 0] >= 0, 0, 1),
                    np.where(a[:, 1] >= a[:, 2], np.where(d[:, 1] >= 0, 2, 3),
                             np.where(d[:, 2] >= 0, 4, 5)))
    return tuple(int(f) for f in np.unique(face))


def _paths(scene: Scene, effects: tuple[str, ...]) -> str:
    return "+".join(e for e in ("reflection", "refraction.single", "refraction.double")
                    if e in effects)


def _read_rgba(texture: moderngl.Texture) -> np.ndarray:
    w, h = texture.size
    return np.frombuffer(texture.read(), np.float32).reshape(h, w, 4)


def render_frame(
    scene: Scene, *, ctx: moderngl.Context | None = None,
    geometry: SceneGeometry | None = None, lookups: bool = True,
) -> Frame:
    """Render ``scene`` with caustics mapping; see :class:`Frame`.

    Parameters
    ----------
    ctx : moderngl.Context, optional
        A context from :func:`.create_context` (one is made and released if None).
    geometry : SceneGeometry, optional
        The scene's meshes (``build_geometry(scene)`` if None).
    lookups : bool
        Read the receiver positions atlases back into ``Frame.lookups`` (for the
        NumPy mirror); off in :func:`render`, where nothing needs them.

    Raises
    ------
    GLError
        A pass left a GL error.
    """
    return _frame(scene, ctx, geometry, want_lookups=lookups, want_atlas=True)


def render(scene: Scene, *, ctx: moderngl.Context | None = None,
           geometry: SceneGeometry | None = None) -> RenderResult:
    """Render ``scene``; the :class:`RenderResult` of :func:`render_frame` (without
    reading back what only the :class:`Frame` holds: the caustic-map atlas and the
    positions atlases)."""
    return _frame(scene, ctx, geometry, want_lookups=False, want_atlas=False).result


def _frame(scene: Scene, ctx: moderngl.Context | None, geometry: SceneGeometry | None, *,
           want_lookups: bool, want_atlas: bool) -> Frame:
    own = ctx is None
    ctx = ctx or create_context()
    try:
        # Make ``ctx`` current: another standalone context created (or released)
        # since would otherwise receive these GL calls.
        with ctx:
            try:
                return _render(scene, ctx, geometry or build_geometry(scene), want_lookups,
                               want_atlas)
            finally:
                pool(ctx).end_frame()
    finally:
        if own:
            ctx.release()


def _render(scene: Scene, ctx: moderngl.Context, geometry: SceneGeometry,
            want_lookups: bool, want_atlas: bool) -> Frame:
    s = scene.settings
    effects = effects_of(scene)
    timer = PassTimer(ctx)
    resources = pool(ctx)
    passes: list[str] = []

    def ran(name: str) -> None:
        if name not in passes:
            passes.append(name)

    receivers = [upload_mesh(ctx, g.mesh) for g in geometry.receivers]
    objects = [upload_mesh(ctx, g.mesh) for g in geometry.objects]
    materials = material_table([g.material for g in geometry.objects],
                               [g.mesh.closed for g in geometry.objects], effects)
    caustic_objects = [i for i, code in enumerate(materials.code) if code != 0]
    closed = [i for i, code in enumerate(materials.code) if code == 1]
    channels = (0, 1, 2) if "dispersion" in effects else (-1,)
    paper = s.normalization == "paper"
    eps = newton_eps(scene, geometry)
    mappings = [uv_mapping(g) for g in geometry.receivers]
    points = _sample_points(geometry)
    w, h = scene.camera.resolution
    camera = np.zeros((h, w, 3), np.float32)
    maps = [np.zeros((s.receiver_map[1], s.receiver_map[0], 3), np.float32)
            for _ in geometry.receivers]
    caustic_total = None
    hits: list[dict[str, np.ndarray]] = []
    lookups: list[MapLookup] = []
    covered_total = 0
    map_faces: set[int] = set()
    lights = light_setups(scene, geometry)
    paths = _paths(scene, effects)

    for light_index, sample in enumerate(lights):
        faces = _faces(sample, points)
        light = dataclasses.replace(sample, map_faces=faces)
        map_faces.update(faces)
        with timer.measure("receiver_positions"):
            positions = render_receiver_positions(
                ctx, light, receivers, size=s.positions_map, faces=faces)
        ran("receiver_positions")
        if want_lookups:
            lookups.append(MapLookup(
                positions.read_positions().copy(),
                np.stack([v.view_proj for v in light.map_views]), s.positions_map,
                light.cube, light.position.copy(), np.array(light.slots)))
        traces: list[Trace] = []
        front = back = None
        if caustic_objects:
            with timer.measure("object_positions.front"):
                front = render_object_surfaces(ctx, light, objects, grid=s.grid,
                                               which=caustic_objects, count=paper)
            ran("object_positions.front")
            covered_total += front.covered
            if "refraction.double" in effects:
                with timer.measure("object_positions.back"):
                    back = render_object_surfaces(ctx, light, objects, grid=s.grid, back=True,
                                                  which=closed)
                ran("object_positions.back")
            for channel in channels:
                name = f"caustic_trace.{paths}" + (
                    f".{_CHANNELS[channel]}" if channel >= 0 else "")
                with timer.measure(name):
                    trace = run_caustic_trace(
                        ctx, light, positions=positions, front=front, back=back,
                        materials=materials, grid=s.grid,
                        estimator=s.estimator, iterations=s.iterations,
                        safeguarded=s.safeguarded, eps=eps, channel=channel, paper=paper,
                        covered=front.covered)
                ran(name)
                traces.append(trace)
        csize = s.caustic_map
        caustic = resources.texture((len(faces) * csize, csize))
        with timer.measure("caustic_map"):
            splat_caustic_map(ctx, light, traces, caustic, size=csize, faces=faces,
                              sigma=s.splat_sigma_texels, cut=s.splat_radius)
        ran("caustic_map")
        if s.lowpass:
            with timer.measure("lowpass"):
                filtered = lowpass_filter(ctx, caustic, size=csize)
            resources.give_back(caustic)
            caustic = filtered
            ran("lowpass")
        with timer.measure("receiver_map"):
            for index, rec in enumerate(geometry.receivers):
                target = resources.texture(s.receiver_map)
                splat_receiver_map(ctx, light, traces, target, index=index, receiver=rec,
                                   mapping=mappings[index], positions=positions,
                                   caustic_size=csize, sigma=s.splat_sigma_texels,
                                   cut=s.splat_radius)
                maps[index] += _read_rgba(target)[:, :, :3]
                resources.give_back(target)
        ran("receiver_map")
        shadow = None
        if "shadows" in effects:
            with timer.measure("shadow_map"):
                shadow = render_shadow_map(ctx, light, objects, size=s.shadow_map, faces=faces)
            ran("shadow_map")
        diag = float(np.linalg.norm(np.ptp(points, axis=0)))
        inputs = CameraInputs(shadow, s.shadow_map, caustic, csize, positions.positions,
                              s.positions_map, scene.info.direct_lighting, 1e-3 * diag)
        with timer.measure("camera"):
            camera += render_camera(ctx, light, camera=scene.camera, geometry=geometry,
                                    receivers=receivers, objects=objects, inputs=inputs)
        ran("camera")
        if want_atlas:
            atlas = _read_rgba(caustic)[:, :, :3]
            caustic_total = atlas.copy() if caustic_total is None else caustic_total + atlas
        for channel, trace in zip(channels, traces, strict=False):
            data = trace.read()
            data["channel"] = np.full(trace.count, channel, np.int32)
            data["light"] = np.full(trace.count, light_index, np.int32)
            hits.append(data)
            trace.give_back(resources)
        for resource in (front, back, positions):
            if resource is not None:
                resource.give_back(resources)
        for texture in (caustic, shadow):
            if texture is not None:
                resources.give_back(texture)
    error = ctx.error
    for mesh in receivers + objects:
        mesh.release()
    if error != "GL_NO_ERROR":
        raise GLError(f"OpenGL error after rendering {scene.name}: {error}")

    merged = _merge(hits, s.iterations)
    status = merged["status"]
    counts = {name: int(np.sum(status == code)) for name, code in STATUS.items()}
    lost_flux = merged["flux"][status == STATUS["lost"]].sum(axis=0)
    metadata = {
        "passes": passes,
        "lost_splats": counts["lost"],
        "status_counts": counts,
        "lost_flux": [float(x) for x in lost_flux],
        "splatted_flux": [float(x) for x in merged["flux"][status == STATUS["hit"]].sum(axis=0)],
        "light_views": "cube" if lights[0].cube else lights[0].map_views[0].name,
        "map_faces": [CUBE_FACES[f] if lights[0].cube else lights[0].map_views[f].name
                      for f in sorted(map_faces)],
        "object_views": [v.name for v in lights[0].object_views],
        "light_samples": len(lights),
        "covered_texels": covered_total if paper else None,
        "estimator": s.estimator, "safeguarded": s.safeguarded, "iterations": s.iterations,
        "grid": s.grid, "caustic_map": s.caustic_map, "positions_map": s.positions_map,
        "normalization": s.normalization, "newton_eps": eps,
        "channels": [_CHANNELS[c] if c >= 0 else "rgb" for c in channels],
        "receiver_extent": [list(g.extent) for g in geometry.receivers],
        "gl_renderer": ctx.info["GL_RENDERER"],
        "timer": timer.timer,
    }
    result = RenderResult(
        renderer="caustics_mapping", camera=camera,
        receivers=tuple(ReceiverMap(m, g.extent)
                        for m, g in zip(maps, geometry.receivers, strict=True)),
        effects=effects, timings=dict(timer.timings), timer=timer.timer, metadata=metadata,
    )
    if caustic_total is None:
        caustic_total = np.zeros((s.caustic_map, s.caustic_map, 3), np.float32)
    return Frame(result, merged, caustic_total, lookups, eps)


def _merge(hits: list[dict[str, np.ndarray]], iterations: int) -> dict[str, np.ndarray]:
    if not hits:
        empty3 = np.zeros((0, 3), np.float32)
        return {"origin": empty3, "direction": empty3, "distance": np.zeros(0, np.float32),
                "hit": empty3, "status": np.zeros(0, np.int32), "flux": empty3,
                "receiver": np.zeros(0, np.int32), "normal": empty3,
                "view": np.zeros(0, np.int32), "history": np.zeros((0, iterations + 1), np.float32),
                "channel": np.zeros(0, np.int32), "light": np.zeros(0, np.int32)}
    return {key: np.concatenate([h[key] for h in hits]) for key in hits[0]}


