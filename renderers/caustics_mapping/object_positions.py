"""Pass 2: caustic-object positions and normals from the light (paper Section 3.2).

The object atlas has ``grid`` x ``grid`` texels per object view, so each texel is one
vertex of the paper's refractive vertex grid. Front surfaces always; back (exit)
surfaces when the effects include ``refraction.double`` (Wyman 2005); the farthest
surfaces of conductors with verified hits (the reflected rays' occlusion test). The front
pass runs inside an occlusion (samples) query: its count is the paper's V, the
number of grid texels the object covers (Eq. 6).
"""

from __future__ import annotations

from dataclasses import dataclass

import moderngl

from renderers.caustics_mapping.context import GLError, ResourcePool, load_program, pool
from renderers.caustics_mapping.lights import LightSetup
from renderers.caustics_mapping.meshes import GpuMesh
from renderers.caustics_mapping.uniforms import set_light_uniforms

__all__ = ["ObjectSurfaces", "render_object_surfaces"]


@dataclass(eq=False)
class ObjectSurfaces:
    """Object-atlas textures (RGBA32F, layout in ``object_positions.glsl``).

    Attributes
    ----------
    positions, normals, geometric : moderngl.Texture
        Attachments 0, 1 and 2: world positions, stored (shading) normals and the
        triangles' geometric normals.
    covered : int
        Samples that passed the depth test (the paper's V), counted by an occlusion
        query; only set for the front surfaces.
    """

    positions: moderngl.Texture
    normals: moderngl.Texture
    geometric: moderngl.Texture
    covered: int

    def give_back(self, resources: ResourcePool) -> None:
        """Return the textures to the context's pool."""
        for texture in (self.positions, self.normals, self.geometric):
            resources.give_back(texture)


def render_object_surfaces(
    ctx: moderngl.Context, light: LightSetup, objects: list[GpuMesh], *, grid: int,
    back: bool = False, which: list[int] | None = None, count: bool = False,
    farthest: bool = False,
) -> ObjectSurfaces:
    """Render the caustic objects (indices ``which``, default all) into the object views.

    Parameters
    ----------
    back : bool
        Render the exit surfaces (facing away from the light) instead of the front.
    count : bool
        Count the covered grid texels with an occlusion query (the paper's V): the
        surfaces are drawn a second time with depth test ``==`` inside the query, so
        fragments later hidden by nearer ones (overdraw) are not counted.
    farthest : bool
        Keep the farthest surface along each light ray instead of the nearest (depth
        test ``>``): the layer behind the front one where a ray meets the objects
        twice (a ring's far wall behind its near wall, a bowl's inside behind its
        rim).

    Raises
    ------
    GLError
        The atlas (``grid`` texels per view, the views side by side) would be wider
        than the context's ``GL_MAX_TEXTURE_SIZE``.
    """
    views = light.object_views
    limit = int(ctx.info["GL_MAX_TEXTURE_SIZE"])
    if len(views) * grid > limit:
        raise GLError(f"the object atlas would be {len(views)} views x {grid} = "
                      f"{len(views) * grid} texels wide, past this GL's "
                      f"GL_MAX_TEXTURE_SIZE of {limit}: lower settings.grid (or "
                      "rim_patches, whose front atlas has that many texels per grid "
                      "step, or back_resolution)")
    resources = pool(ctx)
    textures = [resources.texture((len(views) * grid, grid)) for _ in range(3)]
    depth = resources.depth_texture((len(views) * grid, grid))
    fbo = resources.framebuffer(textures, depth)
    program = load_program(
        ctx, "object_positions.glsl", defines={"BACK_FACES": 1} if back else None
    )
    set_light_uniforms(program, light)
    fbo.use()
    fbo.clear(0.0, 0.0, 0.0, 0.0, depth=0.0 if farthest else 1.0)
    ctx.enable(moderngl.DEPTH_TEST)
    if farthest:
        ctx.depth_func = ">"
    ctx.disable(moderngl.CULL_FACE | moderngl.BLEND)
    indices = range(len(objects)) if which is None else which
    # No back-face culling here (unlike the shadow map and camera passes): at a
    # silhouette a back face can tie the front face in depth at a grid texel, and the
    # depth test then keeps the first drawn; culling changed one grid record of
    # scenes/hard/high_ior_tir at its default settings (a cube edge).
    vaos = {i: objects[i].vertex_array(program) for i in indices}

    def draw() -> None:
        for face, view in enumerate(views):
            fbo.viewport = (face * grid, 0, grid, grid)
            program["u_vp"].write(view.view_proj.T.astype("f4").tobytes())
            for index, vao in vaos.items():
                program["u_index"] = index
                vao.render(moderngl.TRIANGLES)

    draw()
    ctx.depth_func = "<"
    covered = 0
    if count:
        query = ctx.query(samples=True)
        ctx.depth_func = "=="
        with query:
            draw()
        ctx.depth_func = "<"
        covered = int(query.samples)
    for vao in vaos.values():
        vao.release()
    resources.give_back(depth)
    return ObjectSurfaces(*textures, covered=covered)
