"""Setting the uniforms shared through ``common.glsl`` (light and view matrices) and
``mesh_vertex.glsl`` (``u_vp``), and the loop of the passes drawn into the light's
map views."""

from __future__ import annotations

from collections.abc import Iterator

import moderngl
import numpy as np

from renderers.caustics_mapping.lights import LightSetup, LightView

__all__ = ["map_view_passes", "set_light_uniforms", "set_object_view_uniforms", "set_uniform"]


def set_uniform(program: moderngl.Program, name: str, value) -> None:
    """Set ``name`` if the program uses it (the GLSL compiler drops unused ones)."""
    if name not in program:
        return
    uniform = program[name]
    if isinstance(value, np.ndarray):
        dtype = np.int32 if value.dtype.kind in "iub" else np.float32
        uniform.write(np.ascontiguousarray(value, dtype).tobytes())
    else:
        uniform.value = value


def _matrices(views: tuple[LightView, ...]) -> np.ndarray:
    """Six column-major float32 matrices (missing views padded with identity)."""
    mats = [v.view_proj.T for v in views] + [np.eye(4)] * (6 - len(views))
    return np.stack(mats).astype(np.float32)


def set_light_uniforms(program: moderngl.Program, light: LightSetup) -> None:
    """The light and its map views (``u_light_*``, ``u_spot``, ``u_map_*``)."""
    set_uniform(program, "u_light_type", light.type_code)
    set_uniform(program, "u_light_pos", tuple(float(x) for x in light.position))
    set_uniform(program, "u_light_dir", tuple(float(x) for x in light.direction))
    set_uniform(program, "u_light_power", tuple(float(x) for x in light.power))
    set_uniform(program, "u_spot", (light.cos_cutoff, light.cos_beam, light.cutoff, light.beam))
    set_uniform(program, "u_lambertian", int(light.lambertian))
    set_uniform(program, "u_map_vp", _matrices(light.map_views))
    set_uniform(program, "u_map_cube", int(light.cube))
    set_uniform(program, "u_map_slot", np.array(light.slots, np.int32))
    set_uniform(program, "u_map_persp", int(light.map_views[0].perspective))
    set_uniform(program, "u_map_rect", tuple(float(x) for x in light.map_views[0].bounds))


def set_object_view_uniforms(program: moderngl.Program, light: LightSetup) -> None:
    """The object views (``u_obj_*``) of the vertex grid."""
    views = light.object_views
    set_uniform(program, "u_obj_vp", _matrices(views))
    set_uniform(program, "u_obj_cube", int(len(views) == 6))
    set_uniform(program, "u_obj_views", len(views))
    set_uniform(program, "u_obj_persp", int(views[0].perspective))
    set_uniform(program, "u_obj_rect", tuple(float(x) for x in views[0].bounds))


def map_view_passes(
    ctx: moderngl.Context, fbo: moderngl.Framebuffer, program: moderngl.Program,
    light: LightSetup, *, size: int,
) -> Iterator[LightView]:
    """Draw with ``program`` into each stored map view of ``light`` in turn.

    Sets the light uniforms, binds ``fbo`` and clears it (colour 0, depth 1), and
    enables the depth test with face culling and blending off. Then, for each view of
    ``light.map_faces`` (atlas slot s holds the s-th), sets the viewport to that slot
    (``size`` texels a side, x from s * size) and ``u_vp`` to the view's world -> clip
    matrix, and yields the view for the caller to draw its meshes.
    """
    set_light_uniforms(program, light)
    fbo.use()
    fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
    ctx.enable(moderngl.DEPTH_TEST)
    ctx.disable(moderngl.CULL_FACE | moderngl.BLEND)
    for slot, face in enumerate(light.map_faces):
        view = light.map_views[face]
        fbo.viewport = (slot * size, 0, size, size)
        program["u_vp"].write(view.view_proj.T.astype("f4").tobytes())
        yield view
