"""Pass 3c, end: the receivers' maps scored where their triangles went to a finer
atlas (``caustic_lookup = "receivers"``): each coarse texel plus the mean of the
finer texels over it, summed on the GL side so that only the coarse atlas is read
back (reading the finer atlas and taking the means in NumPy cost strong about 4 ms
a frame on llvmpipe at 2 x 256^2, after a NumPy ``mean`` over a reshaped view had
cost 10.4 ms)."""

from __future__ import annotations

import moderngl

from renderers.caustics_mapping.context import load_program, pool
from renderers.caustics_mapping.uniforms import set_uniform

__all__ = ["scored_maps"]


def scored_maps(ctx: moderngl.Context, coarse: moderngl.Texture, fine: moderngl.Texture,
                *, factor: int) -> moderngl.Texture:
    """``coarse`` plus the means of ``fine``'s ``factor`` x ``factor`` blocks of texels
    (both RGBA32F atlases, ``fine`` ``factor`` times as many texels per side): a
    texture of ``coarse``'s size from the context's pool (rgb W/m^2, a weight)."""
    if fine.size != (factor * coarse.size[0], factor * coarse.size[1]):
        raise ValueError(f"the finer atlas is {fine.size}, not {factor} x {coarse.size}")
    resources = pool(ctx)
    target = resources.texture(coarse.size)
    fbo = resources.framebuffer([target])
    # The whole atlas (a pooled framebuffer keeps the slot a splat pass last set).
    fbo.viewport = (0, 0, *target.size)
    fbo.scissor = None
    fbo.use()
    program = load_program(ctx, "scored_maps.glsl")
    coarse.use(location=0)
    fine.use(location=1)
    set_uniform(program, "u_coarse", 0)
    set_uniform(program, "u_fine", 1)
    set_uniform(program, "u_factor", int(factor))
    ctx.disable(moderngl.DEPTH_TEST | moderngl.BLEND | moderngl.CULL_FACE)
    vao = ctx.vertex_array(program, [])
    vao.render(moderngl.TRIANGLES, vertices=3)
    vao.release()
    return target
