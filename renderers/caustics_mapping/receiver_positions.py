"""Pass 1: receiver positions, normals and (u, v) from the light (paper Section 3.2).

Output: three map atlases of ``settings.positions_map`` texels per face side (layout
in ``common.glsl``), attachment 0 (RGBA32F) ``xyz`` world position (m), ``w`` receiver
index + 1 (0 = none); attachment 1 (RGBA32F) the receiver normal; attachment 2
(RG32F) its (u, v).
"""

from __future__ import annotations

from dataclasses import dataclass

import moderngl
import numpy as np

from renderers.caustics_mapping.context import ResourcePool, load_program, pool
from renderers.caustics_mapping.lights import LightSetup
from renderers.caustics_mapping.meshes import GpuMesh
from renderers.caustics_mapping.uniforms import map_view_passes

__all__ = ["ReceiverPositions", "render_receiver_positions"]


@dataclass(eq=False)
class ReceiverPositions:
    """The receiver positions atlas and its companions (RGBA32F; ``uvs`` RG32F)."""

    positions: moderngl.Texture
    normals: moderngl.Texture
    uvs: moderngl.Texture
    size: int
    faces: tuple[int, ...]

    def read_positions(self) -> np.ndarray:
        """Attachment 0 as an array (size, views*size, 4), row 0 at the bottom."""
        data = np.frombuffer(self.positions.read(), np.float32)
        return data.reshape(self.size, -1, 4)

    def give_back(self, resources: ResourcePool) -> None:
        """Return the textures to the context's pool."""
        for tex in (self.positions, self.normals, self.uvs):
            resources.give_back(tex)


def render_receiver_positions(
    ctx: moderngl.Context, light: LightSetup, receivers: list[GpuMesh], *, size: int,
    faces: tuple[int, ...],
) -> ReceiverPositions:
    """Render every receiver into the map views ``light.map_faces``, one atlas slot
    each (``faces`` must equal them). Cube faces not stored report "no receiver"."""
    width = len(light.map_faces) * size
    resources = pool(ctx)
    textures = [resources.texture((width, size), components) for components in (4, 4, 2)]
    depth = resources.depth_texture((width, size))
    fbo = resources.framebuffer(textures, depth)
    program = load_program(ctx, "receiver_positions.glsl")
    vaos = [mesh.vertex_array(program) for mesh in receivers]
    for _ in map_view_passes(ctx, fbo, program, light, size=size):
        for index, vao in enumerate(vaos):
            program["u_index"] = index
            vao.render(moderngl.TRIANGLES)
    for vao in vaos:
        vao.release()
    resources.give_back(depth)
    return ReceiverPositions(*textures, size=size, faces=faces)
