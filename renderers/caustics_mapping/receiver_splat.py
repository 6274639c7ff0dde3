"""Pass 3c: receiver irradiance maps over each receiver's (u, v) domain.

The same splats as the caustic map, drawn into one RGBA32F atlas with a slot per
receiver, side by side (receiver i's slot starts at texel column i * W; row 0 at
vmin, as :class:`renderers.results.ReceiverMap` requires): rgb caustic irradiance
in W per m² of receiver surface (flux per (u, v) area divided by the surface area
per (u, v) area), a = splat weight. A slot has ``settings.receiver_map`` texels;
where the camera reads its caustics from these maps (``caustic_lookup =
"receivers"``: :func:`.splat_maps.splat_maps`) the triangles go to a second atlas
with twice as many texels per side.
"""

from __future__ import annotations

from dataclasses import dataclass

import moderngl
import numpy as np

from renderers.caustics_mapping.caustic_splat import SplatOptions, TrianglesApart, draw_splats
from renderers.caustics_mapping.caustic_trace import Trace
from renderers.caustics_mapping.context import pool
from renderers.caustics_mapping.lights import LightSetup
from renderers.caustics_mapping.receiver_positions import ReceiverPositions
from renderers.caustics_mapping.uniforms import set_light_uniforms, set_uniform
from scenes.geometry import ReceiverGeometry

__all__ = ["UvMapping", "splat_receiver_map", "uv_mapping"]

#: Largest splat radius in receiver-map pixels (bounds the per-splat loop).
MAX_RADIUS_PX = 16.0


@dataclass(frozen=True)
class UvMapping:
    """How a world position maps to a receiver's (u, v).

    Attributes
    ----------
    affine : bool
        (u, v) = rows @ (x, y, z, 1) reproduces the mesh's (u, v) at every vertex
        (to 1e-5 of the extent): planes and heightfields.
    rows : ndarray (2, 4)
    uv_per_metre : float
        sqrt((u, v) area / surface area): converts a splat's size in metres.
    """

    affine: bool
    rows: np.ndarray
    uv_per_metre: float


def uv_mapping(receiver: ReceiverGeometry) -> UvMapping:
    """Fit (u, v) as an affine function of position; measure (u, v) per metre."""
    mesh = receiver.mesh
    p = mesh.positions.astype(np.float64)
    uv = (mesh.uvs if mesh.uvs is not None else p[:, :2]).astype(np.float64)
    design = np.hstack([p, np.ones((len(p), 1))])
    rows, *_ = np.linalg.lstsq(design, uv, rcond=None)
    umin, umax, vmin, vmax = receiver.extent
    scale = max(umax - umin, vmax - vmin, 1e-30)
    affine = bool(np.abs(design @ rows - uv).max() <= 1e-5 * scale)
    f = mesh.faces
    e1, e2 = uv[f[:, 1]] - uv[f[:, 0]], uv[f[:, 2]] - uv[f[:, 0]]
    uv_area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]).sum()
    ratio = float(np.sqrt(uv_area / max(mesh.area(), 1e-30)))
    return UvMapping(affine, rows.T.copy(), ratio if ratio > 0 else 1.0)


def splat_receiver_map(
    ctx: moderngl.Context, light: LightSetup, traces: list[Trace], atlas: moderngl.Texture,
    *, index: int, size: tuple[int, int], receiver: ReceiverGeometry, mapping: UvMapping,
    positions: ReceiverPositions, caustic_size: int, options: SplatOptions,
    fine: moderngl.Texture | None = None, oversample: int = 1,
) -> None:
    """Add the splats that landed on receiver ``index`` into its slot of ``atlas``
    (``size`` = (W, H) texels, from column ``index * W``; the caller clears the
    atlases). ``fine``: an atlas of ``oversample`` x ``size`` slots that takes the
    triangles instead (the Gaussians, smooth at the map's own texels, stay in
    ``atlas``)."""
    resources = pool(ctx)

    def bind(fbo: moderngl.Framebuffer, slot: tuple[int, int, int, int]) -> None:
        fbo.use()
        fbo.viewport = slot
        fbo.scissor = slot      # a kernel past the slot's edge stays out of its neighbour

    coarse = resources.framebuffer([atlas])
    slot = (index * size[0], 0, size[0], size[1])
    bind(coarse, slot)
    apart, framebuffers = None, [coarse]
    if fine is not None:
        fine_fbo = resources.framebuffer([fine])
        framebuffers.append(fine_fbo)
        fine_size = (oversample * size[0], oversample * size[1])
        fine_slot = (index * fine_size[0], 0, *fine_size)

        def fine_uniforms(program: moderngl.Program) -> None:
            set_uniform(program, "u_map_size", fine_size)
            set_uniform(program, "u_map_origin", fine_slot[0])

        apart = TrianglesApart(
            scale=oversample, uniforms=fine_uniforms,
            target=lambda kind: bind(fine_fbo, fine_slot) if kind == "triangles"
            else bind(coarse, slot))

    def uniforms(program: moderngl.Program) -> None:
        set_light_uniforms(program, light)
        positions.uvs.use(location=0)
        set_uniform(program, "u_uv_texture", 0)
        set_uniform(program, "u_receiver", index)
        set_uniform(program, "u_caustic_size", caustic_size)
        set_uniform(program, "u_positions_size", positions.size)
        set_uniform(program, "u_uv_affine", int(mapping.affine))
        set_uniform(program, "u_row_u", tuple(float(x) for x in mapping.rows[0]))
        set_uniform(program, "u_row_v", tuple(float(x) for x in mapping.rows[1]))
        set_uniform(program, "u_uv_per_metre", mapping.uv_per_metre)
        set_uniform(program, "u_extent", tuple(float(x) for x in receiver.extent))
        set_uniform(program, "u_map_size", size)
        set_uniform(program, "u_map_origin", slot[0])

    draw_splats(ctx, "receiver_splat.glsl", traces, options, max_radius=MAX_RADIUS_PX,
                uniforms=uniforms, triangles_apart=apart)
    for fbo in framebuffers:
        fbo.scissor = None
