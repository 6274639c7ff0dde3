"""Setting the uniforms shared through ``common.glsl`` (light and view matrices)."""

from __future__ import annotations

import moderngl
import numpy as np

from renderers.caustics_mapping.lights import LightSetup, LightView

__all__ = ["set_light_uniforms", "set_object_view_uniforms", "set_uniform"]


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
