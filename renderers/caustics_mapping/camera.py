"""Pass 5: the final camera pass. Output (H, W, 3) float32 linear radiance, row 0
at the top of the image."""

from __future__ import annotations

import math
from dataclasses import dataclass

import moderngl
import numpy as np

from renderers.caustics_mapping.context import load_program, pool
from renderers.caustics_mapping.lights import LightSetup, look_at
from renderers.caustics_mapping.meshes import GpuMesh
from renderers.caustics_mapping.uniforms import set_light_uniforms, set_uniform
from scenes.geometry import SceneGeometry
from scenes.model import Camera, ConductorMaterial, DielectricMaterial

__all__ = ["CameraInputs", "camera_matrix", "render_camera"]


def camera_matrix(camera: Camera) -> np.ndarray:
    """World -> clip of the scene camera (OpenGL conventions)."""
    w, h = camera.resolution
    eye = np.asarray(camera.position, float)
    view = look_at(eye, np.asarray(camera.look_at) - eye, camera.up)
    t = math.tan(math.radians(camera.fov) / 2)
    tx, ty = (t, t * h / w) if camera.fov_axis == "x" else (t * w / h, t)
    dist = np.linalg.norm(np.asarray(camera.look_at) - eye)
    near, far = dist * 1e-3, dist * 1e2
    proj = np.zeros((4, 4))
    proj[0, 0], proj[1, 1] = 1 / tx, 1 / ty
    proj[2, 2] = -(far + near) / (far - near)
    proj[2, 3] = -2 * far * near / (far - near)
    proj[3, 2] = -1
    return proj @ view


@dataclass(eq=False)
class CameraInputs:
    """What the camera pass reads (None where the pass that makes it did not run)."""

    shadow_map: moderngl.Texture | None
    shadow_size: int
    caustic_map: moderngl.Texture | None
    caustic_size: int
    positions: moderngl.Texture | None
    positions_size: int
    direct: bool
    shadow_bias: float


def _plane(geometry: SceneGeometry) -> tuple[float, float, float, float]:
    """Least-squares plane of receiver 0 (normal along its mean vertex normal)."""
    mesh = geometry.receivers[0].mesh
    p = mesh.positions.astype(np.float64)
    c = p.mean(axis=0)
    n = np.linalg.svd(p - c, full_matrices=False)[2][-1]
    if n @ mesh.normals.mean(axis=0) < 0:
        n = -n
    return (*n.tolist(), float(n @ c))


def render_camera(
    ctx: moderngl.Context, light: LightSetup, *, camera: Camera, geometry: SceneGeometry,
    receivers: list[GpuMesh], objects: list[GpuMesh], inputs: CameraInputs,
) -> np.ndarray:
    """Render the camera image (W m^-2 sr^-1), row 0 at the top."""
    w, h = camera.resolution
    resources = pool(ctx)
    color = resources.texture((w, h))
    depth = resources.depth_texture((w, h))
    fbo = resources.framebuffer([color], depth)
    fbo.use()
    fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
    ctx.enable(moderngl.DEPTH_TEST)
    ctx.disable(moderngl.CULL_FACE | moderngl.BLEND)
    vp = camera_matrix(camera).T.astype(np.float32)
    programs = [load_program(ctx, "camera.glsl"),
                load_program(ctx, "camera.glsl", defines={"OBJECT": 1})]
    for program in programs:
        set_light_uniforms(program, light)
        set_uniform(program, "u_camera_vp", vp)
        set_uniform(program, "u_eye", tuple(float(x) for x in camera.position))
        set_uniform(program, "u_direct", int(inputs.direct))
        set_uniform(program, "u_shadows", int(inputs.shadow_map is not None))
        set_uniform(program, "u_caustics", int(inputs.caustic_map is not None))
        set_uniform(program, "u_shadow_size", inputs.shadow_size)
        set_uniform(program, "u_shadow_bias", inputs.shadow_bias)
        set_uniform(program, "u_caustic_size", inputs.caustic_size)
        set_uniform(program, "u_positions_size", inputs.positions_size)
        for unit, (name, tex) in enumerate((("u_shadow_map", inputs.shadow_map),
                                            ("u_caustic_map", inputs.caustic_map),
                                            ("u_positions", inputs.positions))):
            if tex is not None:
                tex.use(location=unit)
                set_uniform(program, name, unit)
    receiver_program, object_program = programs
    for index, (mesh, geo) in enumerate(zip(receivers, geometry.receivers, strict=False)):
        set_uniform(receiver_program, "u_receiver", index)
        set_uniform(receiver_program, "u_albedo", tuple(float(x) for x in geo.albedo))
        vao = mesh.vertex_array(receiver_program)
        vao.render(moderngl.TRIANGLES)
        vao.release()
    set_uniform(object_program, "u_plane", _plane(geometry))
    set_uniform(object_program, "u_plane_albedo",
                tuple(float(x) for x in geometry.receivers[0].albedo))
    for mesh, geo in zip(objects, geometry.objects, strict=False):
        material = geo.material
        if isinstance(material, DielectricMaterial):
            set_uniform(object_program, "u_material", 1)
            set_uniform(object_program, "u_ior", float(material.iors[1]))
        elif isinstance(material, ConductorMaterial):
            set_uniform(object_program, "u_material", 3)
            set_uniform(object_program, "u_reflectance",
                        tuple(float(x) for x in material.reflectance))
        else:
            set_uniform(object_program, "u_material", 3)
            set_uniform(object_program, "u_reflectance", (0.0, 0.0, 0.0))
        # Back faces are drawn too: culling them (meshes.back_faces_hidden) would
        # halve this draw's cost but changed 1-3 silhouette pixels per image where a
        # back face ties the front face in depth (bunny 700 x 700, high_ior_tir).
        vao = mesh.vertex_array(object_program)
        vao.render(moderngl.TRIANGLES)
        vao.release()
    image = np.frombuffer(color.read(), np.float32).reshape(h, w, 4)[::-1, :, :3].copy()
    resources.give_back(color)
    resources.give_back(depth)
    return image
