"""Pass 3b: the caustic map, Gaussian point sprites of the trace records.

Output: an RGBA32F map atlas of ``settings.caustic_map`` texels per face side;
rgb caustic irradiance E (W/m^2; paper units in paper mode) on the receiver seen
from the light through that texel, a = accumulated splat weight.
"""

from __future__ import annotations

import moderngl

from renderers.caustics_mapping.caustic_trace import Trace
from renderers.caustics_mapping.context import load_program, pool
from renderers.caustics_mapping.lights import LightSetup
from renderers.caustics_mapping.uniforms import set_light_uniforms, set_uniform

__all__ = ["record_vertex_array", "splat_caustic_map"]


def record_vertex_array(program: moderngl.Program, trace: Trace) -> moderngl.VertexArray:
    """The record buffer as point vertices: ``in_hit, in_flux, in_normal``."""
    return program.ctx.vertex_array(
        program, [(trace.records, "32x 4f 4f 4f", "in_hit", "in_flux", "in_normal")]
    )


def splat_caustic_map(
    ctx: moderngl.Context, light: LightSetup, traces: list[Trace], target: moderngl.Texture,
    *, size: int, faces: tuple[int, ...], sigma: float, cut: float,
) -> None:
    """Accumulate every trace's splats into ``target`` (cleared first; a texture of
    the context's pool)."""
    fbo = pool(ctx).framebuffer([target])
    fbo.use()
    fbo.clear(0.0, 0.0, 0.0, 0.0)
    program = load_program(ctx, "caustic_splat.glsl")
    set_light_uniforms(program, light)
    set_uniform(program, "u_size", size)
    set_uniform(program, "u_sigma", float(sigma))
    set_uniform(program, "u_cut", float(cut))
    ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
    ctx.enable(moderngl.BLEND | moderngl.PROGRAM_POINT_SIZE)
    ctx.blend_func = moderngl.ONE, moderngl.ONE
    ctx.blend_equation = moderngl.FUNC_ADD
    vaos = [record_vertex_array(program, trace) for trace in traces]
    for slot, face in enumerate(light.map_faces):
        fbo.viewport = (slot * size, 0, size, size)
        fbo.scissor = (slot * size, 0, size, size)
        set_uniform(program, "u_face", face)
        for vao, trace in zip(vaos, traces, strict=False):
            vao.render(moderngl.POINTS, vertices=trace.count)
    fbo.scissor = None
    ctx.disable(moderngl.BLEND | moderngl.PROGRAM_POINT_SIZE)
    for vao in vaos:
        vao.release()
