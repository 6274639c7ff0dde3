"""Optional pass: low-pass filter of the caustic map the camera reads
(``settings.lowpass``): the light-space atlas, or the receivers' (u, v) atlas."""

from __future__ import annotations

import moderngl

from renderers.caustics_mapping.context import load_program, pool
from renderers.caustics_mapping.uniforms import set_uniform

__all__ = ["lowpass_filter"]


def lowpass_filter(
    ctx: moderngl.Context, source: moderngl.Texture, *, size: tuple[int, int]
) -> moderngl.Texture:
    """A 3x3 binomial blur of the atlas ``source`` (RGBA32F), per slot of ``size``
    = (W, H) texels, the slots side by side (every texel is written; a texture of
    the context's pool)."""
    resources = pool(ctx)
    target = resources.texture(source.size)
    fbo = resources.framebuffer([target])
    fbo.use()
    program = load_program(ctx, "lowpass.glsl")
    source.use(location=0)
    set_uniform(program, "u_source", 0)
    set_uniform(program, "u_size", tuple(int(x) for x in size))
    ctx.disable(moderngl.DEPTH_TEST | moderngl.BLEND | moderngl.CULL_FACE)
    vao = ctx.vertex_array(program, [])
    vao.render(moderngl.TRIANGLES, vertices=3)
    vao.release()
    return target
