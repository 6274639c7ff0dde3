"""Pass 4: shadow map of the caustic objects from the light (paper Section 3.2).

Runs only with the ``shadows`` effect. Output: an RG32F map atlas of
``settings.shadow_map`` texels per face (layout in ``shadow_map.glsl``).
"""

from __future__ import annotations

import moderngl

from renderers.caustics_mapping.context import load_program, pool
from renderers.caustics_mapping.lights import LightSetup
from renderers.caustics_mapping.meshes import GpuMesh, back_faces_hidden
from renderers.caustics_mapping.uniforms import map_view_passes

__all__ = ["render_shadow_map"]


def render_shadow_map(
    ctx: moderngl.Context, light: LightSetup, objects: list[GpuMesh], *, size: int,
    faces: tuple[int, ...],
) -> moderngl.Texture:
    """Nearest caustic-object distance per texel of the map views in ``faces``
    (a texture of the context's pool: give it back, do not release it)."""
    views = len(light.map_faces)
    resources = pool(ctx)
    target = resources.texture((views * size, size), 2)      # r, g: all the camera reads
    depth = resources.depth_texture((views * size, size))
    fbo = resources.framebuffer([target], depth)
    program = load_program(ctx, "shadow_map.glsl")
    vaos = [mesh.vertex_array(program) for mesh in objects]
    for view in map_view_passes(ctx, fbo, program, light, size=size):
        view_proj = view.view_proj
        for mesh, vao in zip(objects, vaos, strict=True):
            # Never for an open mesh (water, rings, a mesh that is not watertight:
            # ``closed`` false, the ``open_mesh`` effect): the light sees its inner
            # side as back faces, and culling them shrinks its shadow to a crescent.
            cull = mesh.source is not None and back_faces_hidden(mesh.source, view_proj)
            if cull:
                ctx.enable(moderngl.CULL_FACE)
            vao.render(moderngl.TRIANGLES)
            if cull:
                ctx.disable(moderngl.CULL_FACE)
    for vao in vaos:
        vao.release()
    resources.give_back(depth)
    return target
