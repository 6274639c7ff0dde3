"""Pass 3a, rim patches: the grid quads the caustic trace traces again, finer.

``rim_patches.glsl`` reads a trace's records and marks every grid quad near an
object's silhouette seen from the light (``handoff``, one int per quad: 1 patched),
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


@dataclass(eq=False)
class RimPatches:
    """The patched quads of one trace.

    Attributes
    ----------
    handoff : moderngl.Buffer
        One int32 per grid quad ``(view * (grid - 1) + qy) * (grid - 1) + qx``: 1 where
        the quad's patch is drawn instead of it.
    quads : moderngl.Buffer
        int32 grid-quad index of patch k, for k < ``count``, in increasing order.
    count : int
        Patches.
    """

    handoff: moderngl.Buffer
    quads: moderngl.Buffer
    count: int

    def give_back(self, resources: ResourcePool) -> None:
        """Return the buffers to the context's pool."""
        resources.give_back(self.handoff)
        resources.give_back(self.quads)

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


def find_rim_patches(ctx: moderngl.Context, trace: Trace, *, grid: int) -> RimPatches:
    """The quads of ``trace`` (a grid of ``grid`` x ``grid`` vertices per view) that
    get rim patches."""
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
        if groups:
            program.run(group_x=groups)
        ctx.memory_barrier()
    found = int(np.frombuffer(count.read(), np.int32)[0])
    resources.give_back(count)
    return RimPatches(handoff, listed, found)
