"""The caustics-mapping renderer: runs the passes the scene's effects call for.

``render(scene)`` returns a :class:`renderers.results.RenderResult`;
``render_frame(scene)`` also returns the per-vertex records, the positions atlases
and the caustic map, for the CLI's outputs, the NumPy mirror and convergence studies.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import moderngl
import numpy as np

from renderers.caustics_mapping.caustic_trace import (
    STATUS,
)
from renderers.caustics_mapping.context import GLError, PassTimer, create_context, pool
from renderers.caustics_mapping.estimators import MapLookup
from renderers.caustics_mapping.light_sample import (
    CHANNELS,
    Accumulator,
    FrameState,
    newton_eps,
    render_light_sample,
    scene_setup,
)
from renderers.caustics_mapping.lights import CUBE_FACES, LightSetup, light_setups
from renderers.caustics_mapping.metadata import MethodMetadata
from renderers.caustics_mapping.presets import resolve_scene
from renderers.results import ReceiverMap, RenderResult
from scenes import Scene, effects_of
from scenes.geometry import SceneGeometry, build_geometry

__all__ = ["Frame", "newton_eps", "render", "render_frame"]

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
        (K,) object view, ``channel`` (K,) (-1 all), ``light`` (K,) light sample,
        ``share`` (K,) the part of the vertex's flux its splats draw (1 but next to
        rim patches, :func:`.rim_patches.grid_shares`).
    caustic_map : ndarray (M, slots * M, 3)
        The caustic-map atlas (W/m^2), row 0 at the bottom, one slot per stored map
        view (``metadata["map_faces"]`` in order); summed over light samples.
    lookups : list of MapLookup
        The receiver positions atlas read back, per light sample (for the mirror).
    eps : float
        Newton's finite-difference step used (m).
    patches : dict of ndarray
        Per rim-patch vertex (``settings.rim_patches``; layout in
        ``caustic_trace.glsl``), the fields of ``hits`` and ``quad`` (K,), the grid
        quad its patch replaces; ``share`` from :func:`.rim_patches.patch_shares`.
        Empty without patches.
    """

    result: RenderResult
    hits: dict[str, np.ndarray]
    caustic_map: np.ndarray
    lookups: list[MapLookup] = field(default_factory=list)
    eps: float = 0.0
    patches: dict[str, np.ndarray] = field(default_factory=dict)

    def traced_records(self) -> dict[str, np.ndarray]:
        """Grid and rim-patch vertices together, for flux accounts: ``status``,
        ``origin``, ``direction``, ``receiver`` and ``flux`` (K, 3) W, each vertex's
        flux times its ``share``, so the splatted vertices' flux is what the maps
        received (the result's ``records``)."""
        return self.result.records


def _traced_records(hits: dict[str, np.ndarray],
                   patches: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """:meth:`Frame.traced_records` of a frame's ``hits`` and ``patches``."""
    parts = [hits] + ([patches] if patches and len(patches["status"]) else [])
    out = {key: np.concatenate([np.asarray(p[key]) for p in parts])
           for key in ("status", "origin", "direction", "receiver")}
    share = np.concatenate([np.asarray(p.get("share", np.ones(len(p["status"]))), np.float64)
                            for p in parts])
    out["flux"] = np.concatenate([np.asarray(p["flux"], np.float64) for p in parts]) \
        * share[:, None]
    return out


def render_frame(
    scene: Scene, *, ctx: moderngl.Context | None = None,
    geometry: SceneGeometry | None = None, lookups: bool = True, atlas: bool = True,
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
    atlas : bool
        Splat and read back the light-space caustic-map atlas (``Frame.caustic_map``)
        also where the camera does not read it (``caustic_lookup = "receivers"``): an
        extra pass, off in :func:`render`, which draws only the passes the method needs.

    Raises
    ------
    GLError
        A pass left a GL error.
    """
    return _frame(scene, ctx, geometry, want_lookups=lookups, want_atlas=atlas)


def render(scene: Scene, *, ctx: moderngl.Context | None = None,
           geometry: SceneGeometry | None = None) -> RenderResult:
    """Render ``scene``; the :class:`RenderResult` of :func:`render_frame` (its
    ``records`` included), drawing and reading back only what the result needs (no
    caustic-map atlas where the camera does not read it, no positions atlases)."""
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
    scene = resolve_scene(scene, geometry)
    s = scene.settings
    effects = effects_of(scene)
    timer = PassTimer(ctx)
    setup = scene_setup(scene, ctx, geometry, effects=effects)
    w, h = scene.camera.resolution
    acc = Accumulator(
        camera=np.zeros((h, w, 3), np.float32),
        maps=[np.zeros((s.receiver_map[1], s.receiver_map[0], 3), np.float32)
              for _ in geometry.receivers])
    state = FrameState(scene, ctx, geometry, effects, timer, setup, acc)
    lights = light_setups(scene, geometry, frustum_fit=s.frustum)
    for light_index, sample in enumerate(lights):
        render_light_sample(state, sample, light_index=light_index,
                            want_lookups=want_lookups, want_atlas=want_atlas)
    error = ctx.error
    for mesh in setup.receivers + setup.objects:
        mesh.release()
    if error != "GL_NO_ERROR":
        raise GLError(f"OpenGL error after rendering {scene.name}: {error}")

    merged = _merge(acc.hits, s.iterations)
    patches = _merge(acc.patches, s.iterations) if acc.patches else {}
    records = _traced_records(merged, patches)
    metadata = _metadata(state, merged=merged, records=records, lights=lights)
    result = RenderResult(
        renderer="caustics_mapping", camera=acc.camera,
        receivers=tuple(ReceiverMap(m, g.extent)
                        for m, g in zip(acc.maps, geometry.receivers, strict=True)),
        effects=effects, timings=dict(timer.timings), timer=timer.timer,
        # GPU time per pass from GL timer queries, where they are valid (hardware).
        metadata=metadata.as_dict() | ({"gpu_timings": dict(timer.gpu_timings)}
                                       if timer.gpu_timings else {}),
        records=records,
    )
    caustic_total = acc.caustic_total
    if caustic_total is None:
        caustic_total = np.zeros((s.caustic_map, s.caustic_map, 3), np.float32)
    return Frame(result, merged, caustic_total, acc.lookups, setup.eps, patches)


def _metadata(state: FrameState, *, merged: dict[str, np.ndarray],
              records: dict[str, np.ndarray], lights: list[LightSetup]) -> MethodMetadata:
    """Counts of the grid's vertices (``merged``); flux parts of every traced vertex,
    rim patches included, each at its share (``records``)."""
    scene, ctx, geometry, setup, acc = (state.scene, state.ctx, state.geometry, state.setup,
                                        state.acc)
    s = scene.settings
    counts = {name: int(np.sum(merged["status"] == code)) for name, code in STATUS.items()}
    status = records["status"]
    lost_flux = records["flux"][status == STATUS["lost"]].sum(axis=0)
    per_vertex = records["flux"].sum(axis=1)
    traced = float(per_vertex[status != STATUS["empty"]].sum())
    fractions = {name: float(per_vertex[status == code].sum()) / traced if traced > 0 else 0.0
                 for name, code in STATUS.items() if name != "empty"}
    first = lights[0]
    return MethodMetadata(
        passes=acc.passes,
        lost_splats=counts["lost"],
        status_counts=counts,
        lost_flux=[float(x) for x in lost_flux],
        splatted_flux=[float(x) for x in records["flux"][status == STATUS["hit"]].sum(axis=0)],
        status_flux_fraction=fractions,
        light_views="cube" if first.cube else first.map_views[0].name,
        map_faces=[CUBE_FACES[f] if first.cube else first.map_views[f].name
                   for f in sorted(acc.map_faces)],
        object_views=[v.name for v in first.object_views],
        light_samples=len(lights),
        covered_texels=acc.covered_total if setup.paper else None,
        preset=s.preset, estimator=s.estimator, safeguarded=bool(s.safeguarded),
        iterations=s.iterations, grid=s.grid, caustic_map=s.caustic_map,
        positions_map=s.positions_map, normalization=s.normalization, lookup=s.lookup,
        back_resolution=s.back_resolution, rim_patches=s.rim_patches,
        rim_patches_traced=acc.rim_patches, frustum=s.frustum,
        verify_hits=bool(s.verify_hits), start=s.start, splat=s.splat,
        splat_sigma=list(acc.splat_sigma), newton_eps=setup.eps,
        channels=[CHANNELS[c] if c >= 0 else "rgb" for c in setup.channels],
        receiver_extent=[list(g.extent) for g in geometry.receivers],
        gl_renderer=ctx.info["GL_RENDERER"],
        timer=state.timer.timer,
    )


def _merge(hits: list[dict[str, np.ndarray]], iterations: int) -> dict[str, np.ndarray]:
    if not hits:
        empty3 = np.zeros((0, 3), np.float32)
        return {"origin": empty3, "direction": empty3, "distance": np.zeros(0, np.float32),
                "hit": empty3, "status": np.zeros(0, np.int32), "flux": empty3,
                "receiver": np.zeros(0, np.int32), "normal": empty3,
                "view": np.zeros(0, np.int32), "history": np.zeros((0, iterations + 1), np.float32),
                "channel": np.zeros(0, np.int32), "light": np.zeros(0, np.int32),
                "share": np.zeros(0, np.float32)}
    return {key: np.concatenate([h[key] for h in hits]) for key in hits[0]}


