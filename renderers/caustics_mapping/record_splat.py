"""Splat per-vertex records made elsewhere with the method's own splat passes.

The trace pass (:mod:`.caustic_trace`) writes one record per grid vertex into a
storage buffer, and the splat passes (:mod:`.caustic_splat`, :mod:`.receiver_splat`)
read only that buffer. This module lets a caller hand in such records from any
source (exact light paths from a ray tracer, the method's own records with some
fields replaced) and runs the very passes a frame runs on them: per light sample the
receiver positions (the (u, v) of hits on receivers whose (u, v) is not affine),
then ``splat_maps.splat_maps``: the caustic map the camera would read (the
light-space one or, with ``caustic_lookup = "receivers"``, none besides the receivers'
own) with the kernel the settings name and, from the same records, each receiver's
(u, v) irradiance map. Nothing is
splatted differently, so two record sets differ in their maps only by what their
records say. The records are the grid's: a frame's rim patches (``rim_patches``
> 1) are traced from its grid, not handed in, so the hook splats every quad as a
frame with ``rim_patches = 1`` does.

Record layout (``caustic_trace.glsl``), ``float32``, shape (views * grid * grid, 5, 4),
record ``(view * grid + ty) * grid + tx`` for grid vertex (tx, ty) of object view
``view`` (the splat kernels find a vertex's neighbours by this index):

====  ===========================================  =====================================
row   xyz                                          w
====  ===========================================  =====================================
0     ray origin v (m)                             object view index
1     unit ray direction r                         distance d to the hit (m)
2     hit P (m)                                    status (:data:`.caustic_trace.STATUS`)
3     flux Φ (W, RGB)                              receiver index (−1: none)
4     receiver normal at P                         0
====  ===========================================  =====================================

The splat passes read rows 2 to 4 (and ``settings.splat_unconverged``): a record is
splatted when its status is ``hit`` (or ``unconverged`` on a receiver, with that
setting), onto receiver ``row 3 w``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import moderngl
import numpy as np

from renderers.caustics_mapping.caustic_trace import RECORD_FLOATS, Trace
from renderers.caustics_mapping.context import GLError, PassTimer, create_context, pool
from renderers.caustics_mapping.light_sample import (
    Accumulator,
    FrameState,
    light_faces,
    scene_setup,
)
from renderers.caustics_mapping.lights import LightSetup, light_setups
from renderers.caustics_mapping.presets import resolve_scene
from renderers.caustics_mapping.receiver_positions import render_receiver_positions
from renderers.caustics_mapping.splat_maps import splat_maps
from renderers.results import ReceiverMap
from scenes import Scene, effects_of
from scenes.errors import HarnessError
from scenes.geometry import SceneGeometry, build_geometry

__all__ = [
    "RECORD_SHAPE",
    "RecordError",
    "SplattedMaps",
    "pack_records",
    "splat_records",
    "split_records",
]

#: One record: five vec4 (``caustic_trace.glsl``).
RECORD_SHAPE = (5, 4)


class RecordError(HarnessError, ValueError):
    """Records that do not fit the scene's grid, light samples or channels."""


@dataclass(frozen=True, eq=False)
class SplattedMaps:
    """The receiver maps of a set of splatted records.

    Attributes
    ----------
    receivers : tuple of ReceiverMap
        Caustic irradiance (W/m²) per receiver over its (u, v), row 0 at vmin.
    timings : dict of str to float
        Seconds per pass (``receiver_positions``, ``caustic_map``, ``receiver_map``),
        summed over light samples; ``timer`` names the clock.
    timer : str
    splat_sigma : tuple of float
        The Gaussian width each light sample used (caustic-map texels).
    """

    receivers: tuple[ReceiverMap, ...]
    timings: dict[str, float]
    timer: str
    splat_sigma: tuple[float, ...]


def pack_records(*, origin, view, direction, distance, hit, status, flux, receiver,
                 normal) -> np.ndarray:
    """Fields (the keys of :meth:`.caustic_trace.Trace.read`) into the record layout.

    Parameters
    ----------
    origin, direction, hit, flux, normal : array (K, 3)
        Metres, unit vector, metres, W (RGB), unit vector.
    view, status, receiver : array (K,)
        Integers (status codes of :data:`.caustic_trace.STATUS`, receiver −1: none).
    distance : array (K,)
        Metres.

    Returns
    -------
    ndarray (K, 5, 4) float32
    """
    count = len(np.asarray(status))
    out = np.zeros((count, *RECORD_SHAPE), np.float32)
    out[:, 0, :3], out[:, 0, 3] = origin, view
    out[:, 1, :3], out[:, 1, 3] = direction, distance
    out[:, 2, :3], out[:, 2, 3] = hit, status
    out[:, 3, :3], out[:, 3, 3] = flux, receiver
    out[:, 4, :3] = normal
    return out


def split_records(hits: dict[str, np.ndarray]) -> list[list[np.ndarray]]:
    """The merged per-vertex arrays of a frame (``Frame.hits``) back into record
    arrays: one list per light sample, one array per traced channel, in the order
    the frame traced them (light samples outer, channels inner)."""
    light, channel = np.asarray(hits["light"]), np.asarray(hits["channel"])
    out: list[list[np.ndarray]] = []
    start = 0
    while start < len(light):
        # Each trace is a contiguous run of one (light, channel) pair.
        key = (light[start], channel[start])
        stop = start
        while stop < len(light) and (light[stop], channel[stop]) == key:
            stop += 1
        fields = {k: np.asarray(hits[k])[start:stop] for k in (
            "origin", "view", "direction", "distance", "hit", "status", "flux", "receiver",
            "normal")}
        if not out or int(light[start]) != len(out) - 1:
            out.append([])
        out[-1].append(pack_records(**fields))
        start = stop
    return out


def splat_records(scene: Scene, records: Sequence[Sequence[np.ndarray]], *,
                  ctx: moderngl.Context | None = None,
                  geometry: SceneGeometry | None = None) -> SplattedMaps:
    """Splat ``records`` with the splat passes and settings of ``scene``.

    Parameters
    ----------
    scene : Scene
        Its settings choose the kernel (``splat``, ``splat_sigma``, ``splat_radius``,
        ``footprint_scale``, ``splat_unconverged``), the grid the records were laid
        out on (``grid``), the object frustum (``frustum``: the light samples' views,
        :func:`.lights.light_setups`) and the map sizes; unset choices take the
        preset's, as in a render.
    records : sequence of sequences of ndarray
        Per light sample (in :func:`.lights.light_setups` order), one record array
        (module docstring) per traced channel (three for a dispersive scene, else
        one), each of ``len(object_views) * grid * grid`` records.
    ctx, geometry
        A context (one is made and released if None) and the scene's meshes.

    Raises
    ------
    RecordError
        The records do not match the scene's light samples, channels or grid.
    GLError
        A pass left a GL error.
    """
    own = ctx is None
    ctx = ctx or create_context()
    try:
        with ctx:
            try:
                return _splat(scene, records, ctx, geometry or build_geometry(scene))
            finally:
                pool(ctx).end_frame()
    finally:
        if own:
            ctx.release()


def _splat(scene: Scene, records, ctx: moderngl.Context,
           geometry: SceneGeometry) -> SplattedMaps:
    scene = resolve_scene(scene, geometry)
    s = scene.settings
    effects = effects_of(scene)
    setup = scene_setup(scene, ctx, geometry, effects=effects)
    lights = light_setups(scene, geometry, frustum_fit=s.frustum)
    _check(records, lights, len(setup.channels), s.grid)
    timer = PassTimer(ctx)
    acc = Accumulator(camera=np.zeros((1, 1, 3), np.float32),
                      maps=[np.zeros((s.receiver_map[1], s.receiver_map[0], 3), np.float32)
                            for _ in geometry.receivers])
    state = FrameState(scene, ctx, geometry, effects, timer, setup, acc)
    resources = pool(ctx)
    for sample, arrays in zip(lights, records, strict=True):
        faces = light_faces(sample, setup.points)
        light = dataclasses.replace(sample, map_faces=faces)
        with timer.measure("receiver_positions"):
            positions = render_receiver_positions(ctx, light, setup.receivers,
                                                  size=s.positions_map, faces=faces)
        traces = [_upload(ctx, array) for array in arrays]
        caustic = splat_maps(state, light, faces=faces, traces=traces, positions=positions)
        for trace in traces:
            trace.give_back(resources)
        positions.give_back(resources)
        caustic.give_back(resources)
    error = ctx.error
    for mesh in setup.receivers + setup.objects:
        mesh.release()
    if error != "GL_NO_ERROR":
        raise GLError(f"OpenGL error after splatting records of {scene.name}: {error}")
    return SplattedMaps(
        receivers=tuple(ReceiverMap(m, g.extent)
                        for m, g in zip(acc.maps, geometry.receivers, strict=True)),
        timings=dict(timer.timings), timer=timer.timer, splat_sigma=tuple(acc.splat_sigma))


def _check(records, lights: tuple[LightSetup, ...], channels: int, grid: int) -> None:
    if len(records) != len(lights):
        raise RecordError(f"records for {len(records)} light samples; the scene has "
                          f"{len(lights)}")
    for index, (arrays, light) in enumerate(zip(records, lights, strict=True)):
        if len(arrays) != channels:
            raise RecordError(f"light sample {index}: {len(arrays)} record arrays; the "
                              f"scene traces {channels} channel(s)")
        expected = len(light.object_views) * grid * grid
        for array in arrays:
            shape = np.shape(array)
            if shape != (expected, *RECORD_SHAPE):
                raise RecordError(f"light sample {index}: records of shape {shape}; grid "
                                  f"{grid} over {len(light.object_views)} object view(s) "
                                  f"needs ({expected}, 5, 4)")


def _upload(ctx: moderngl.Context, array: np.ndarray) -> Trace:
    """A :class:`.caustic_trace.Trace` whose record buffer holds ``array`` (its
    history buffer is a placeholder: the splat passes never read it)."""
    resources = pool(ctx)
    data = np.ascontiguousarray(array, np.float32)
    count = len(data)
    records = resources.buffer(count * RECORD_FLOATS * 4)
    records.write(data.tobytes())
    history = resources.buffer(4)
    return Trace(records, history, count, 0)
