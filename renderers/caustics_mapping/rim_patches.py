"""Pass 3a, rim patches: the grid quads the caustic trace traces again, finer.

``rim_patches.glsl`` reads a trace's records and marks every grid quad near an
object's silhouette seen from the light, or where a conductor reflects the light
near grazing (``handoff``, one int per quad: 1 patched),
then lists the marked quads in increasing order; the count is read back, and the
caustic trace runs once more over the patches' vertices
(:func:`.caustic_trace.run_caustic_trace` with ``patches``). The splat passes draw
the patches in place of their quads.
"""

from __future__ import annotations

from dataclasses import dataclass

import moderngl
import numpy as np

from renderers.caustics_mapping.caustic_trace import Trace
from renderers.caustics_mapping.context import ResourcePool, load_program, pool
from renderers.caustics_mapping.uniforms import set_uniform

__all__ = ["RimPatches", "find_rim_patches", "grid_shares", "patch_shares"]

#: Only rim quads with a corner whose light leaves the object are patched
#: (``rim_patches.glsl``, ``leaves``). False patches every rim quad that shows the
#: object, TIR and no-exit corners alone included (tests compare the two).
EXITS_ONLY = True
#: Neighbouring patches' shared vertices are traced once, by one of them, and copied
#: to the others (``rim_patches.glsl``): the same records, a third fewer traced on
#: glass_sphere and bunny. False traces every copy (tests compare the two).
SHARE_VERTICES = True
#: A quad with a corner that reflects off a conductor at |l . n| below this is in the
#: band wherever it lies (``rim_patches.glsl``, ``grazing``; 0: none, which tests
#: compare). 0.3: the floor caustic of ``scenes/hard/concave``'s bowls starts at
#: |l . n| < 0.3 on the outer wall, none above. strong's flux ratio on
#: bowl_deep_sun75 (grid 128, 4 x 2^20 reference photons) with the band at 0 (the
#: silhouette alone), 0.12, 0.2, 0.3, 0.5: 1.026, 1.026, 1.029, 1.011, 1.011: a band
#: short of the source leaves the quads across its inner part to the grid.
GRAZING_COS = 0.3


@dataclass(eq=False)
class RimPatches:
    """The patched quads of one trace.

    Attributes
    ----------
    handoff : moderngl.Buffer
        One int32 per grid quad ``(view * (grid - 1) + qy) * (grid - 1) + qx``: its
        patch's index + 1 where the quad's patch is drawn instead of it, else 0.
    quads : moderngl.Buffer
        int32 grid-quad index of patch k, for k < ``count``, in increasing order.
    count : int
        Patches.
    factor : int
        Patch quads per grid quad side (``settings.rim_patches``).
    owner : moderngl.Buffer or None
        int32 per patch vertex (record order): the record of the same vertex in the
        patch that traces it (itself where that is its own; ``rim_patches.glsl``).
    unique : moderngl.Buffer or None
        The records the trace traces (owned ones), int32 in increasing order.
    dispatch : moderngl.Buffer or None
        The trace's indirect dispatch over ``unique``: uint32 groups x, y, z, then
        their count.
    """

    handoff: moderngl.Buffer
    quads: moderngl.Buffer
    count: int
    factor: int = 1
    owner: moderngl.Buffer | None = None
    unique: moderngl.Buffer | None = None
    dispatch: moderngl.Buffer | None = None

    @property
    def vertices(self) -> int:
        """Patch vertices (records), ``(factor + 1)^2`` per patch."""
        return self.count * (self.factor + 1) ** 2

    def give_back(self, resources: ResourcePool) -> None:
        """Return the buffers to the context's pool."""
        for buffer in (self.handoff, self.quads, self.owner, self.unique, self.dispatch):
            if buffer is not None:
                resources.give_back(buffer)

    def copy_shared(self, ctx: moderngl.Context, trace: Trace) -> None:
        """Fill the records (and histories) of ``trace``, the patches' trace, that
        another patch traced: each from its owner's (``rim_patches.glsl``, COPY)."""
        if self.owner is None:
            return
        trace.records.bind_to_storage_buffer(0)
        trace.history.bind_to_storage_buffer(7)
        self.owner.bind_to_storage_buffer(4)
        program = load_program(ctx, "rim_patches.glsl", defines={"COPY": 1}, compute=True)
        set_uniform(program, "u_count", self.vertices)
        set_uniform(program, "u_history", trace.iterations + 1)
        program.run(group_x=-(-self.vertices // 64))
        ctx.memory_barrier()

    def read_quads(self) -> np.ndarray:
        """The patched grid quads (``count``,) int32, in increasing order."""
        if self.count == 0:
            return np.zeros(0, np.int32)
        return np.frombuffer(self.quads.read(size=4 * self.count), np.int32).copy()


def grid_shares(quads: np.ndarray, *, views: int, grid: int) -> np.ndarray:
    """Share of each grid vertex's flux its splats draw when the grid ``quads`` have
    patches (``(views * grid * grid,)`` float32, record order): a quarter for each
    of its quads that is not patched (the triangles' or, where they cannot be drawn,
    its Gaussian's), the patched quads' quarters being their patches'."""
    patched = np.zeros((views, grid - 1, grid - 1), bool)
    patched.reshape(-1)[np.asarray(quads, np.int64)] = True
    around = np.zeros((views, grid, grid), np.float32)
    for dy in (0, 1):
        for dx in (0, 1):
            around[:, dy:dy + grid - 1, dx:dx + grid - 1] += patched
    return (1.0 - 0.25 * around).reshape(-1)


def patch_shares(factor: int) -> np.ndarray:
    """Share of a patch vertex's flux its splats draw (``((factor + 1)^2,)`` float32,
    record order): a quarter for each of its quads in the patch (its copies in the
    neighbouring patches, or the neighbouring quad's corner, carry the others)."""
    edge = np.minimum(np.arange(factor + 1), 1) + np.minimum(factor - np.arange(factor + 1), 1)
    return (0.25 * np.outer(edge, edge)).astype(np.float32).reshape(-1)


def find_rim_patches(ctx: moderngl.Context, trace: Trace, *, grid: int,
                     factor: int) -> RimPatches:
    """The quads of ``trace`` (a grid of ``grid`` x ``grid`` vertices per view) that
    get rim patches of ``factor`` x ``factor`` quads, and which patch traces each of
    their vertices."""
    views = trace.count // (grid * grid)
    quads = views * (grid - 1) ** 2
    resources = pool(ctx)
    handoff = resources.buffer(4 * max(quads, 1))
    listed = resources.buffer(4 * max(quads, 1))
    count = resources.buffer(4)
    trace.records.bind_to_storage_buffer(0)
    for binding, buffer in enumerate((handoff, listed, count), start=1):
        buffer.bind_to_storage_buffer(binding)
    for stage, groups in (("BAND", -(-quads // 64)), ("LIST", 1)):
        program = load_program(ctx, "rim_patches.glsl", defines={stage: 1}, compute=True)
        set_uniform(program, "u_grid", grid)
        set_uniform(program, "u_count", quads)
        set_uniform(program, "u_exits_only", int(EXITS_ONLY))
        set_uniform(program, "u_grazing", float(GRAZING_COS))
        if groups:
            program.run(group_x=groups)
        ctx.memory_barrier()
    found = int(np.frombuffer(count.read(), np.int32)[0])
    resources.give_back(count)
    patches = RimPatches(handoff, listed, found, factor)
    if found:
        vertices = patches.vertices
        patches.owner = resources.buffer(4 * vertices)
        patches.unique = resources.buffer(4 * vertices)
        patches.dispatch = resources.buffer(16)
        for binding, buffer in ((4, patches.owner), (5, patches.unique),
                                (6, patches.dispatch)):
            buffer.bind_to_storage_buffer(binding)
        for stage, groups in (("OWNED", -(-vertices // 64)), ("UNIQUE", 1)):
            program = load_program(ctx, "rim_patches.glsl", defines={stage: 1}, compute=True)
            set_uniform(program, "u_grid", grid)
            set_uniform(program, "u_count", vertices)
            set_uniform(program, "u_factor", factor)
            set_uniform(program, "u_share", int(SHARE_VERTICES))
            program.run(group_x=groups)
            ctx.memory_barrier()
    return patches
