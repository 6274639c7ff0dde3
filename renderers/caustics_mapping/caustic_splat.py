"""Pass 3b: the caustic map, the trace records splatted with one of three kernels.

Output: an RGBA32F map atlas of ``settings.caustic_map`` texels per face side;
rgb caustic irradiance E (W/m^2; paper units in paper mode) on the receiver seen
from the light through that texel, a = accumulated kernel weight. The kernels
(``points``, ``footprint``, ``triangles``) are described in ``splat_kernels.glsl``;
:func:`draw_splats` draws them for this pass and for the receiver maps.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import moderngl

from renderers.caustics_mapping.caustic_trace import Trace
from renderers.caustics_mapping.context import load_program, pool
from renderers.caustics_mapping.lights import LightSetup
from renderers.caustics_mapping.uniforms import set_light_uniforms, set_uniform

__all__ = ["SPLAT_MODES", "SplatOptions", "TrianglesApart", "draw_splats",
           "splat_caustic_map"]

#: Kernel names and their shader codes (``splat_kernels.glsl``).
SPLAT_MODES = {"points": 0, "footprint": 1, "triangles": 2}
#: Widest triangle drawn (pixels); wider quads fall back to Gaussians.
MAX_TRIANGLE_PX = 64.0
#: With :class:`TrianglesApart`, rim patches' quads wider than this many pixels of the
#: Gaussians' target are drawn there instead of in the finer one (see its doc).
PATCH_ROUTE_PX = 1.0
#: Long Gaussians and quads are drawn in boxes along their own axes, not in
#: axis-aligned ones (``splat_kernels.glsl``): the same pixels get a share, fewer are
#: visited. False draws every kernel axis-aligned (tests compare the two).
TIGHT_BOXES = True


@dataclass(frozen=True, eq=False, kw_only=True)
class TrianglesApart:
    """Triangles drawn into a target ``scale`` times finer per side than the
    Gaussians' (whose pixels decide which quads are triangles: ``u_max_triangle``
    and the rim-sliver length scale with it, so the same quads are drawn).

    Rim patches' quads wider than :data:`PATCH_ROUTE_PX` of the Gaussians' pixels are
    drawn into the Gaussians' target instead, at its pixels. Near glass_sphere's
    silhouette they are the halo's long slivers: 163,600 fragments of the finer
    target, where the coarser one takes 70,900 (the patches' triangles 12 -> 8.6 ms
    a frame on llvmpipe). A patch's sub-texel quads (metal_ring's cusp) stay finer.
    Camera excess relMSE, strong: glass_sphere 3.767e-4 -> 3.793e-4, metal_ring
    4.407e-3 both ways, the bunny 3.823e-3 -> 3.825e-3 (95 % intervals +-0.09e-4,
    +-0.03e-3, +-0.11e-3). The maps scored are the same sums either way.

    Attributes
    ----------
    scale : int
    uniforms : callable
        ``uniforms(program)`` sets the finer target's uniforms on the triangles'
        programs (after the pass's own).
    target : callable
        ``target(kind)`` binds the framebuffer for ``"triangles"`` or
        ``"gaussians"`` before a trace's kernels of that kind are drawn.
    """

    scale: int
    uniforms: Callable[[moderngl.Program], None]
    target: Callable[[str], None]


@dataclass(frozen=True)
class SplatOptions:
    """How records are splatted.

    Attributes
    ----------
    mode : {"points", "footprint", "triangles"}
    sigma : float
        ``points`` standard deviation (caustic-map texels); the width of Gaussians
        that have no neighbour to size them.
    cut : float
        Gaussian cut-off radius (sigmas).
    footprint_scale : float
        ``footprint`` covariance scale.
    unconverged : bool
        Splat ``unconverged`` records that lie on a receiver.
    grid : int
        Vertex grid per object view (neighbour addressing).
    """

    mode: str
    sigma: float
    cut: float
    footprint_scale: float
    unconverged: bool
    grid: int


def draw_splats(ctx: moderngl.Context, name: str, traces: list[Trace], options: SplatOptions,
                *, max_radius: float, uniforms: Callable[[moderngl.Program], None],
                passes: int = 1,
                before_pass: Callable[[int, list[moderngl.Program]], None] | None = None,
                triangles_apart: TrianglesApart | None = None) -> None:
    """Draw every trace's kernels with program ``name`` into the bound framebuffer,
    additively. ``uniforms(program)`` sets the pass's own uniforms;
    ``before_pass(k, programs)`` runs before each of ``passes`` repeats (the caustic
    map's faces); ``triangles_apart``: the triangles go to a finer target of their own
    (:class:`TrianglesApart`).
    """
    gaussians = load_program(ctx, name)
    # The records that have a Gaussian are listed (flags, then a one-group scan), set
    # up by a compute pass over that list, and drawn as sprites or, listed again, as
    # rectangles (splat_gaussians.glsl).
    setup = load_program(ctx, name, compute=True)
    flags, listing, compact = (load_program(ctx, name, defines={stage: 1}, compute=True)
                               for stage in ("FLAGS", "LIST", "COMPACT"))
    boxed = load_program(ctx, name, defines={"BOXED": 1})
    programs = [gaussians, setup, flags, listing, compact, boxed]
    stages, triangle_programs = (), []
    if options.mode == "triangles":
        # The quads' and the corners' data first (compute), then the triangles.
        stages = tuple(load_program(ctx, name, defines={"TRIANGLES": 1, stage: 1},
                                    compute=True) for stage in ("QUAD_PASS", "CORNER_PASS"))
        triangle_programs = [*stages, load_program(ctx, name, defines={"TRIANGLES": 1},
                                                   geometry=True)]
        programs += triangle_programs
    for program in programs:
        uniforms(program)
        set_uniform(program, "u_splat_mode", SPLAT_MODES[options.mode])
        set_uniform(program, "u_footprint_scale", float(options.footprint_scale))
        set_uniform(program, "u_max_triangle", MAX_TRIANGLE_PX)
        set_uniform(program, "u_splat_unconverged", int(options.unconverged))
        set_uniform(program, "u_sigma", float(options.sigma))
        set_uniform(program, "u_cut", float(options.cut))
        set_uniform(program, "u_max_radius", float(max_radius))
        set_uniform(program, "u_tight_boxes", int(TIGHT_BOXES))
        set_uniform(program, "u_px_scale", 1.0)
    if triangles_apart is not None:
        for program in triangle_programs:
            triangles_apart.uniforms(program)
            set_uniform(program, "u_max_triangle", MAX_TRIANGLE_PX * triangles_apart.scale)
            set_uniform(program, "u_px_scale", float(triangles_apart.scale))
    ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
    ctx.enable(moderngl.BLEND | moderngl.PROGRAM_POINT_SIZE)
    ctx.blend_func = moderngl.ONE, moderngl.ONE
    ctx.blend_equation = moderngl.FUNC_ADD
    resources = pool(ctx)
    arrays = []
    for trace in traces:
        grid = trace.grid or options.grid
        views = trace.count // (grid * grid)
        quads = views * (grid - 1) ** 2
        triangles, buffers = None, ()
        if stages and quads > 0:
            triangles = ctx.vertex_array(programs[-1], [])
            # quad_flags, quad_data, quad_means, corner_data (splat_triangles.glsl)
            buffers = tuple(resources.buffer(n) for n in
                            (4 * quads, 16 * quads, 32 * quads, 48 * trace.count))
        # Three vec4 per record, the boxed records' list and their draw command, the
        # records' flags, their list, its dispatch and the sprites' draw command
        # (splat_gaussians.glsl, bindings 5 to 7 and 9 to 12).
        splats = (resources.buffer(48 * trace.count), resources.buffer(4 * trace.count),
                  resources.buffer(16), resources.buffer(4 * trace.count),
                  resources.buffer(4 * trace.count), resources.buffer(16), resources.buffer(16))
        arrays.append((trace, (ctx.vertex_array(gaussians, []), ctx.vertex_array(boxed, [])),
                       quads, triangles, buffers, splats))
    for k in range(passes):
        if before_pass is not None:
            before_pass(k, programs)
        for trace, points, quads, triangles, buffers, splats in arrays:
            trace.records.bind_to_storage_buffer(0)
            # The trace's own lattice: the grid (its patched quads left to the
            # patches) or rim patches.
            for program in programs:
                set_uniform(program, "u_grid", trace.grid or options.grid)
                set_uniform(program, "u_patches", int(trace.patches))
                set_uniform(program, "u_handoff", int(trace.handoff is not None))
            if trace.handoff is not None:
                trace.handoff.bind_to_storage_buffer(8)
            if triangles is not None:
                # The triangles first: they record which quads they draw, and a
                # vertex's Gaussian carries the quarters of the others.
                if triangles_apart is not None:
                    triangles_apart.target("triangles")
                for binding, buffer in enumerate(buffers, start=1):
                    buffer.bind_to_storage_buffer(binding)
                routed = triangles_apart is not None and trace.patches
                for program in stages:
                    set_uniform(program, "u_route_px", PATCH_ROUTE_PX if routed else 0.0)
                for stage, count in zip(stages, (quads, trace.count), strict=True):
                    set_uniform(stage, "u_count", count)
                    stage.run(group_x=-(-count // 64))
                    ctx.memory_barrier()
                draw = triangle_programs[-1]
                set_uniform(draw, "u_route", 1 if routed else 0)
                triangles.render(moderngl.POINTS, vertices=quads)
                if routed:
                    # The wide ones into the Gaussians' target, at its own pixels.
                    triangles_apart.target("gaussians")
                    uniforms(draw)
                    set_uniform(draw, "u_route", 2)
                    triangles.render(moderngl.POINTS, vertices=quads)
                    triangles_apart.uniforms(draw)
            if triangles_apart is not None:
                triangles_apart.target("gaussians")
            for binding, buffer in zip((5, 6, 7, 9, 10, 11, 12), splats, strict=True):
                buffer.bind_to_storage_buffer(binding)
            for program in (flags, listing):
                set_uniform(program, "u_count", trace.count)
            flags.run(group_x=-(-trace.count // 64))
            ctx.memory_barrier()
            listing.run(group_x=1)
            ctx.memory_barrier()
            setup.run_indirect(splats[5])
            ctx.memory_barrier()
            compact.run(group_x=1)
            ctx.memory_barrier()
            points[0].render_indirect(splats[6], moderngl.POINTS, count=1)
            points[1].render_indirect(splats[2], moderngl.TRIANGLE_STRIP, count=1)
    ctx.disable(moderngl.BLEND | moderngl.PROGRAM_POINT_SIZE)
    for _, points, _, triangles, buffers, splats in arrays:
        for array in (*points, triangles):
            if array is not None:
                array.release()
        for buffer in (*buffers, *splats):
            resources.give_back(buffer)


def splat_caustic_map(
    ctx: moderngl.Context, light: LightSetup, traces: list[Trace], target: moderngl.Texture,
    *, size: int, faces: tuple[int, ...], options: SplatOptions,
) -> None:
    """Accumulate every trace's splats into ``target`` (cleared first; a texture of
    the context's pool), one stored map face at a time."""
    fbo = pool(ctx).framebuffer([target])
    fbo.use()
    fbo.clear(0.0, 0.0, 0.0, 0.0)

    def uniforms(program: moderngl.Program) -> None:
        set_light_uniforms(program, light)
        set_uniform(program, "u_size", size)

    def face(k: int, programs: list[moderngl.Program]) -> None:
        slot, index = k, light.map_faces[k]
        fbo.viewport = (slot * size, 0, size, size)
        fbo.scissor = (slot * size, 0, size, size)
        for program in programs:
            set_uniform(program, "u_face", index)

    draw_splats(ctx, "caustic_splat.glsl", traces, options, max_radius=32.0,
                uniforms=uniforms, passes=len(light.map_faces), before_pass=face)
    fbo.scissor = None
