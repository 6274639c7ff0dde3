"""One light sample of a caustics-mapping frame: the passes in order, summed.

For each point sample of the light: receiver positions from the light, object
surfaces (front; back for double refraction), one caustic trace per channel, the
caustic maps (:mod:`.splat_maps`: the receivers' (u, v) maps and the map the camera
reads, optionally low-passed), the shadow map,
the back faces from the camera (once per frame, for double refraction) and the
camera pass. Each pass is a module of its own with its GLSL beside it;
this module only orders them and keeps the sums (:class:`Accumulator`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import moderngl
import numpy as np

from renderers.caustics_mapping.camera import CameraInputs, camera_matrix, render_camera
from renderers.caustics_mapping.camera_backfaces import (
    CameraBackFaces,
    render_camera_backfaces,
)
from renderers.caustics_mapping.caustic_trace import (
    Trace,
    material_table,
    run_caustic_trace,
    trace_options,
)
from renderers.caustics_mapping.context import PassTimer, pool
from renderers.caustics_mapping.estimators import MapLookup
from renderers.caustics_mapping.lights import LightSetup
from renderers.caustics_mapping.meshes import convex, upload_mesh
from renderers.caustics_mapping.object_positions import render_object_surfaces
from renderers.caustics_mapping.receiver_positions import render_receiver_positions
from renderers.caustics_mapping.receiver_splat import uv_mapping
from renderers.caustics_mapping.rim_patches import (
    RimPatches,
    find_rim_patches,
    grid_shares,
    patch_shares,
)
from renderers.caustics_mapping.shadow_map import render_shadow_map
from renderers.caustics_mapping.splat_maps import read_rgba, splat_maps
from scenes import Scene
from scenes.geometry import SceneGeometry

__all__ = ["CHANNELS", "Accumulator", "FrameState", "SceneSetup", "newton_eps",
           "render_light_sample", "scene_setup"]

#: Channel names of a dispersive trace (index 0, 1, 2; -1 traces all three at once).
CHANNELS = "rgb"


@dataclass(frozen=True, eq=False)
class SceneSetup:
    """What every light sample of one render shares: uploaded meshes, materials,
    the channels traced, and the receivers' (u, v) mappings."""

    receivers: list
    objects: list
    materials: object
    caustic_objects: list[int]
    closed: list[int]
    channels: tuple[int, ...]
    paper: bool
    eps: float
    mappings: list
    points: np.ndarray
    paths: str


@dataclass(eq=False)
class Accumulator:
    """Sums over light samples: camera image (H, W, 3) W m^-2 sr^-1, receiver maps
    (H, W, 3) W/m^2, caustic-map atlas, per-vertex records, passes run."""

    camera: np.ndarray
    maps: list[np.ndarray]
    passes: list[str] = field(default_factory=list)
    caustic_total: np.ndarray | None = None
    hits: list[dict[str, np.ndarray]] = field(default_factory=list)
    patches: list[dict[str, np.ndarray]] = field(default_factory=list)
    lookups: list[MapLookup] = field(default_factory=list)
    covered_total: int = 0
    map_faces: set[int] = field(default_factory=set)
    splat_sigma: list[float] = field(default_factory=list)
    rim_patches: int = 0

    def ran(self, name: str) -> None:
        if name not in self.passes:
            self.passes.append(name)


@dataclass(eq=False)
class FrameState:
    """One render in progress: its inputs, shared set-up, timer and sums."""

    scene: Scene
    ctx: moderngl.Context
    geometry: SceneGeometry
    effects: tuple[str, ...]
    timer: PassTimer
    setup: SceneSetup
    acc: Accumulator
    #: The back faces from the camera (pass 5a), rendered once per frame on first use.
    camera_back: CameraBackFaces | None = None


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


def scene_setup(scene: Scene, ctx: moderngl.Context, geometry: SceneGeometry, *,
                effects: tuple[str, ...]) -> SceneSetup:
    """Upload the meshes and build what every light sample shares."""
    materials = material_table(
        [g.material for g in geometry.objects], [g.mesh.closed for g in geometry.objects],
        effects, extent=tuple(float(np.linalg.norm(np.ptp(g.mesh.positions, axis=0)))
                              for g in geometry.objects),
        # Only verified hits test re-entry, so only they need to know convexity.
        convex=tuple(bool(scene.settings.verify_hits) and convex(g.mesh)
                     for g in geometry.objects),
        bounds=tuple((g.mesh.positions.min(axis=0), g.mesh.positions.max(axis=0))
                     for g in geometry.objects))
    return SceneSetup(
        receivers=[upload_mesh(ctx, g.mesh) for g in geometry.receivers],
        objects=[upload_mesh(ctx, g.mesh) for g in geometry.objects],
        materials=materials,
        caustic_objects=[i for i, code in enumerate(materials.code) if code != 0],
        closed=[i for i, code in enumerate(materials.code) if code == 1],
        channels=(0, 1, 2) if "dispersion" in effects else (-1,),
        paper=scene.settings.normalization == "paper",
        eps=newton_eps(scene, geometry),
        mappings=[uv_mapping(g) for g in geometry.receivers],
        points=_sample_points(geometry),
        paths=_paths(scene, effects),
    )


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


def light_faces(light: LightSetup, points: np.ndarray) -> tuple[int, ...]:
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


def render_light_sample(state: FrameState, sample: LightSetup, *, light_index: int,
                        want_lookups: bool, want_atlas: bool) -> None:
    """Every pass for one light sample, summed into ``state.acc``; resources go back
    to the pool before returning."""
    scene, ctx, geometry, setup, acc, timer = (state.scene, state.ctx, state.geometry,
                                               state.setup, state.acc, state.timer)
    s = scene.settings
    resources = pool(ctx)
    faces = light_faces(sample, setup.points)
    light = dataclasses.replace(sample, map_faces=faces)
    acc.map_faces.update(faces)
    with timer.measure("receiver_positions"):
        positions = render_receiver_positions(
            ctx, light, setup.receivers, size=s.positions_map, faces=faces)
    acc.ran("receiver_positions")
    if want_lookups:
        acc.lookups.append(MapLookup(
            positions.read_positions().copy(),
            np.stack([v.view_proj for v in light.map_views]), s.positions_map,
            light.cube, light.position.copy(), np.array(light.slots),
            rect=light.map_views[0].bounds, perspective=light.map_views[0].perspective))
    front, back, traces, (rim, patches) = _trace_objects(state, light, positions=positions)
    caustic = splat_maps(state, light, faces=faces, traces=traces + patches,
                         positions=positions, light_map=want_atlas)
    shadow = None
    if "shadows" in state.effects:
        with timer.measure("shadow_map"):
            shadow = render_shadow_map(ctx, light, setup.objects, size=s.shadow_map,
                                       faces=faces)
        acc.ran("shadow_map")
    diag = float(np.linalg.norm(np.ptp(setup.points, axis=0)))
    reads_light = caustic.receivers is None
    inputs = CameraInputs(
        shadow_map=shadow, shadow_size=s.shadow_map,
        caustic_map=caustic.light if reads_light else None, caustic_size=s.caustic_map,
        receiver_maps=caustic.receivers, receiver_triangles=caustic.triangles,
        receiver_size=s.receiver_map,
        uv_mappings=setup.mappings, positions=positions, back=_camera_back(state),
        materials=setup.materials, options=trace_options(s, setup.eps),
        direct=scene.info.direct_lighting, shadow_bias=1e-3 * diag,
        dispersion="dispersion" in state.effects, all_paths=s.all_specular_paths)
    with timer.measure("camera"):
        acc.camera += render_camera(ctx, light, camera=scene.camera, geometry=geometry,
                                    receivers=setup.receivers, objects=setup.objects,
                                    inputs=inputs)
    acc.ran("camera")
    if want_atlas:
        atlas = read_rgba(caustic.light)[:, :, :3]
        acc.caustic_total = atlas.copy() if acc.caustic_total is None \
            else acc.caustic_total + atlas
    _read_records(state, traces, rim, patches, light_index=light_index)
    for resource in (front, back, positions, rim, *patches):
        if resource is not None:
            resource.give_back(resources)
    caustic.give_back(resources)
    if shadow is not None:
        resources.give_back(shadow)


def _read_records(state: FrameState, traces: list[Trace], rim: RimPatches | None,
                  patches: list[Trace], *, light_index: int) -> None:
    """The traces' records into ``state.acc.hits`` (grid) and ``.patches`` (rim
    patches), each with its ``share`` (:func:`.rim_patches.grid_shares`,
    :func:`.rim_patches.patch_shares`) and the patches' ``quad``; the grid's traces
    go back to the pool (the patches' with the frame's other resources)."""
    setup, acc, s = state.setup, state.acc, state.scene.settings
    quads = rim.read_quads() if rim is not None else np.zeros(0, np.int32)
    # Every channel's grid has the same views and patches: one share per vertex.
    shares = grid_shares(quads, views=traces[0].count // s.grid**2, grid=s.grid) \
        if traces else None
    for channel, trace in zip(setup.channels, traces, strict=False):
        data = trace.read()
        data["share"] = shares
        data["channel"] = np.full(trace.count, channel, np.int32)
        data["light"] = np.full(trace.count, light_index, np.int32)
        acc.hits.append(data)
        trace.give_back(pool(state.ctx))
    side = (s.rim_patches + 1) ** 2
    for channel, trace in zip(setup.channels, patches, strict=False):
        data = trace.read()
        data["quad"] = np.repeat(quads, side)
        data["share"] = np.tile(patch_shares(s.rim_patches), len(quads))
        data["channel"] = np.full(trace.count, channel, np.int32)
        data["light"] = np.full(trace.count, light_index, np.int32)
        acc.patches.append(data)


def _camera_back(state: FrameState) -> CameraBackFaces | None:
    """Pass 5a, the closed dielectrics' back faces from the camera (with
    ``refraction.double``): rendered on the frame's first light sample, kept for the
    others (the camera does not move between them); the frame's end returns it."""
    if "refraction.double" not in state.effects or not state.setup.closed:
        return None
    if state.camera_back is None:
        camera = state.scene.camera
        with state.timer.measure("camera_backfaces"):
            state.camera_back = render_camera_backfaces(
                state.ctx, view_proj=camera_matrix(camera), size=camera.resolution,
                objects=state.setup.objects, which=state.setup.closed)
        state.acc.ran("camera_backfaces")
    return state.camera_back


def _trace_objects(state: FrameState, light: LightSetup, *, positions):
    """Object surfaces from the light (front, at ``rim_patches`` texels per grid step;
    back for double refraction), then one caustic trace per channel, and the rim
    patches' traces. Returns (front, back, traces, (rim patches, their traces))."""
    ctx, setup, acc, timer = state.ctx, state.setup, state.acc, state.timer
    s = state.scene.settings
    traces: list[Trace] = []
    if not setup.caustic_objects:
        return None, None, traces, (None, [])
    stride = s.rim_patches
    with timer.measure("object_positions.front"):
        front = render_object_surfaces(ctx, light, setup.objects, grid=s.grid * stride,
                                       which=setup.caustic_objects, count=setup.paper)
    acc.ran("object_positions.front")
    acc.covered_total += front.covered
    back = None
    if "refraction.double" in state.effects:
        with timer.measure("object_positions.back"):
            back = render_object_surfaces(ctx, light, setup.objects, grid=s.back_resolution,
                                          back=True, which=setup.closed)
        acc.ran("object_positions.back")
    # The conductors' farthest surfaces: with the front ones, the two layers a
    # reflected ray is tested against for meeting its object again (caustic_trace.glsl).
    conductors = [i for i in setup.caustic_objects if setup.materials.code[i] == 3]
    far = None
    if conductors and s.verify_hits:
        with timer.measure("object_positions.far"):
            far = render_object_surfaces(ctx, light, setup.objects, grid=s.grid,
                                         which=conductors, farthest=True)
        acc.ran("object_positions.far")
    def trace(channel: int, patches: RimPatches | None = None) -> Trace:
        return run_caustic_trace(
            ctx, light, positions=positions, front=front, back=back,
            materials=setup.materials, grid=s.grid, back_size=s.back_resolution,
            options=trace_options(s, setup.eps), channel=channel, paper=setup.paper,
            covered=front.covered, far=far, front_stride=stride, patches=patches)

    for channel in setup.channels:
        name = f"caustic_trace.{setup.paths}" + (
            f".{CHANNELS[channel]}" if channel >= 0 else "")
        with timer.measure(name):
            traces.append(trace(channel))
        acc.ran(name)
    rim, patches = None, []
    if stride > 1:
        # The quads near the silhouette, from the first trace (which vertices show an
        # object does not depend on the channel), traced again as patches.
        with timer.measure("rim_patches"):
            rim = find_rim_patches(ctx, traces[0], grid=s.grid, factor=stride)
            for channel, coarse in zip(setup.channels, traces, strict=True):
                coarse.handoff = rim.handoff
                if rim.count:
                    patches.append(trace(channel, rim))
        acc.ran("rim_patches")
        acc.rim_patches += rim.count
    if far is not None:
        far.give_back(pool(ctx))
    return front, back, traces, (rim, patches)
