"""Pass 5: the final camera pass. Output (H, W, 3) float32 linear radiance, row 0
at the top of the image.

Receivers seen directly are shaded from the light's maps (direct light with the
shadow test) and from the caustic map: the light-space one (the paper's), or each
receiver's own (u, v) map (``caustic_lookup = "receivers"``). A caustic object is
seen along the event chain the photon tracer counts through it, traced from the eye
(``camera.glsl`` states the maths): one reflection (conductor), one refraction (water
surface), or two (closed dielectric: the exit is estimated in the back faces from the
camera of pass 5a, :mod:`.camera_backfaces`, after Wyman 2005), with Fresnel,
absorption and dispersion as the effects say. The ray leaving the object meets the
receivers where the preset's estimator finds the hit in the light's receiver
positions atlas.

Why the light's atlas and not receivers rendered from the camera: it exists already,
it shows the receivers under the object (the object is not drawn in it), and the
caustic pass's estimators and reads then decide both where light lands and where the
eye looks through the object. Its limits: a receiver the light does not see (the
side of a rock turned away from the sun) is not seen through the object either, and
a hit is located to one positions-map texel, not one camera pixel.

Per preset (the estimator settings of the resolved scene settings, for the exit and
for the receiver hit alike):

* ``paper``: the paper renders "double surface refraction (both for the appearance
  of the bunny as well as for the caustics)" with Wyman's technique (its Fig. 1 and
  Section 5). Wyman's distance blends d_V (the back face along the view ray) with a
  per-vertex d_N that he precomputes by ray casting, which the paper's "no
  precomputation" (Section 3.2) rules out; so the exit starts from d_V and is refined
  by the paper's own estimator (modified, 3 iterations, nearest reads), as the
  caustic pass refines its exit. Every estimate is shaded (no verification), as every
  caustic estimate is splatted.
* ``strong``: the safeguarded secant, 5 iterations, bilinear reads within one
  surface, verified receiver hits (a residual above one positions-map texel is the
  empty sky: black). For camera rays, which may run at any angle to the light's
  projection rays, the secant runs on the signed depth along the projection ray
  instead of the caustic pass's distance function (``surface_estimate.glsl``: on
  metal_ring the latter left 78 % of the ring's floor reflections unconverged).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import moderngl
import numpy as np

from renderers.caustics_mapping.camera_backfaces import CameraBackFaces
from renderers.caustics_mapping.caustic_trace import ESTIMATORS, MaterialTable, TraceOptions
from renderers.caustics_mapping.context import load_program, pool
from renderers.caustics_mapping.lights import LightSetup, look_at
from renderers.caustics_mapping.meshes import GpuMesh
from renderers.caustics_mapping.receiver_positions import ReceiverPositions
from renderers.caustics_mapping.receiver_splat import UvMapping
from renderers.caustics_mapping.uniforms import set_light_uniforms, set_uniform
from scenes.camera import half_fov_tangents
from scenes.geometry import SceneGeometry
from scenes.model import Camera

__all__ = ["CameraInputs", "camera_matrix", "pixel_width", "render_camera"]


def camera_matrix(camera: Camera) -> np.ndarray:
    """World -> clip of the scene camera (OpenGL conventions)."""
    eye = np.asarray(camera.position, float)
    view = look_at(eye, np.asarray(camera.look_at) - eye, camera.up)
    tx, ty = half_fov_tangents(camera)  # the pinhole of scenes.camera
    dist = np.linalg.norm(np.asarray(camera.look_at) - eye)
    near, far = dist * 1e-3, dist * 1e2
    proj = np.zeros((4, 4))
    proj[0, 0], proj[1, 1] = 1 / tx, 1 / ty
    proj[2, 2] = -(far + near) / (far - near)
    proj[2, 3] = -2 * far * near / (far - near)
    proj[3, 2] = -1
    return proj @ view


def pixel_width(camera: Camera) -> float:
    """Width of one camera pixel at unit distance along the view axis (a tangent)."""
    return 2 * half_fov_tangents(camera)[0] / camera.resolution[0]


@dataclass(frozen=True, eq=False, kw_only=True)
class CameraInputs:
    """What the camera pass reads (None where the pass that makes it did not run).

    Attributes
    ----------
    shadow_map : moderngl.Texture or None
        RG32F shadow-map atlas (``shadow_map.glsl``), ``shadow_size`` texels per face.
    caustic_map : moderngl.Texture or None
        RGBA32F caustic-map atlas, rgb irradiance (W/m^2), ``caustic_size`` per face;
        None where the camera reads ``receiver_maps`` instead (or nothing).
    receiver_maps : moderngl.Texture or None
        With ``caustic_lookup = "receivers"``: RGBA32F atlas of the receivers' (u, v)
        maps, rgb irradiance (W/m^2), receiver i in the ``receiver_size`` = (W, H)
        slot from column i * W (:func:`.splat_maps.splat_maps`).
    receiver_triangles : moderngl.Texture or None
        Their triangles' part, drawn apart in an atlas of finer slots (a whole
        multiple of ``receiver_size``); the camera reads the sum of the two.
    uv_mappings : sequence of UvMapping
        Each receiver's (u, v) as a function of position (with ``receiver_maps``).
    positions : ReceiverPositions
        The light's receiver positions, normals (and (u, v)) atlases.
    back : CameraBackFaces or None
        Pass 5a's back faces from the camera (with ``refraction.double``).
    materials : MaterialTable
        Per-object material codes, IORs, absorption, reflectance, Fresnel flags (the
        caustic trace's table: absorption and Fresnel already gated by the effects).
    options : TraceOptions
        The estimator settings (``caustic_trace.trace_options`` of the settings).
    direct : bool
        The scene has direct lighting.
    shadow_bias : float
        Shadow-test bias (m).
    dispersion : bool
        One path per channel, each with its channel's IOR.
    all_paths : bool
        ``settings.all_specular_paths``: total internal reflection reflects inside
        (else the chain ends there: black).
    """

    shadow_map: moderngl.Texture | None
    shadow_size: int
    caustic_map: moderngl.Texture | None
    caustic_size: int
    positions: ReceiverPositions
    receiver_maps: moderngl.Texture | None = None
    receiver_triangles: moderngl.Texture | None = None
    receiver_size: tuple[int, int] = (0, 0)
    uv_mappings: Sequence[UvMapping] = ()
    back: CameraBackFaces | None
    materials: MaterialTable
    options: TraceOptions
    direct: bool
    shadow_bias: float
    dispersion: bool = False
    all_paths: bool = False


def _albedo_table(ctx: moderngl.Context, geometry: SceneGeometry) -> moderngl.Texture:
    """RGBA32F (receivers, 1): rgb albedo of each receiver (a pooled texture)."""
    albedos = np.zeros((1, len(geometry.receivers), 4), np.float32)
    albedos[0, :, :3] = [g.albedo for g in geometry.receivers]
    table = pool(ctx).texture((len(geometry.receivers), 1))
    table.write(albedos.tobytes())
    return table


def _uv_table(ctx: moderngl.Context, geometry: SceneGeometry,
              mappings: Sequence[UvMapping]) -> moderngl.Texture:
    """RGBA32F (receivers, 4) (a pooled texture): per receiver its affine (u, v) rows,
    its (u, v) extent (umin, umax, vmin, vmax) and 1 where (u, v) is affine
    (``camera.glsl``, ``u_receiver_uv``)."""
    table = np.zeros((4, len(geometry.receivers), 4), np.float32)
    for i, (mapping, receiver) in enumerate(zip(mappings, geometry.receivers, strict=True)):
        table[0, i], table[1, i] = mapping.rows
        table[2, i] = receiver.extent
        table[3, i, 0] = float(mapping.affine)
    texture = pool(ctx).texture((len(geometry.receivers), 4))
    texture.write(table.tobytes())
    return texture


def _set_common(program: moderngl.Program, light: LightSetup, camera: Camera,
                inputs: CameraInputs) -> None:
    set_light_uniforms(program, light)
    set_uniform(program, "u_vp", camera_matrix(camera).T.astype(np.float32))
    set_uniform(program, "u_eye", tuple(float(x) for x in camera.position))
    set_uniform(program, "u_direct", int(inputs.direct))
    set_uniform(program, "u_shadows", int(inputs.shadow_map is not None))
    receivers = inputs.receiver_maps is not None
    set_uniform(program, "u_caustics", int(inputs.caustic_map is not None or receivers))
    set_uniform(program, "u_receiver_size", tuple(int(x) for x in inputs.receiver_size))
    fine = inputs.receiver_triangles
    set_uniform(program, "u_triangles_scale",
                fine.size[1] // inputs.receiver_size[1] if fine is not None else 0)
    set_uniform(program, "u_shadow_size", inputs.shadow_size)
    set_uniform(program, "u_shadow_bias", inputs.shadow_bias)
    set_uniform(program, "u_caustic_size", inputs.caustic_size)
    set_uniform(program, "u_positions_size", inputs.positions.size)


def _ray_scale(geometry: SceneGeometry) -> float:
    """First probe (m) of the bracketed secant where a ray's origin sees no receiver:
    1/8 of the receivers' bounding-box diagonal (doubled up to 128 times it)."""
    points = np.concatenate([g.mesh.positions for g in geometry.receivers]).astype(float)
    return float(np.linalg.norm(np.ptp(points, axis=0))) / 8


def _set_object(program: moderngl.Program, camera: Camera, inputs: CameraInputs,
                ray_scale: float) -> None:
    o = inputs.options
    for name, value in (
        ("u_ray_scale", ray_scale),
        ("u_viewport", tuple(int(x) for x in camera.resolution)),
        ("u_pixel_width", pixel_width(camera)),
        ("u_iterations", o.iterations), ("u_eps", float(o.eps)),
        ("u_start", int(o.start == "fixed")),
        ("u_start_distance", float(o.start_distance)), ("u_verify", int(o.verify)),
        ("u_converged", float(o.converged)),
        ("u_hit_tolerance", float(o.hit_tolerance or 0.0)),
    ):
        set_uniform(program, name, value)


def render_camera(
    ctx: moderngl.Context, light: LightSetup, *, camera: Camera, geometry: SceneGeometry,
    receivers: list[GpuMesh], objects: list[GpuMesh], inputs: CameraInputs,
) -> np.ndarray:
    """Render the camera image (W m^-2 sr^-1), row 0 at the top."""
    w, h = camera.resolution
    resources = pool(ctx)
    color = resources.texture((w, h))
    depth = resources.depth_texture((w, h))
    albedos = _albedo_table(ctx, geometry)
    uv_table = _uv_table(ctx, geometry, inputs.uv_mappings) \
        if inputs.receiver_maps is not None else None
    fbo = resources.framebuffer([color], depth)
    fbo.use()
    fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
    ctx.enable(moderngl.DEPTH_TEST)
    ctx.disable(moderngl.CULL_FACE | moderngl.BLEND)
    back = inputs.back
    ray_scale = _ray_scale(geometry)
    textures = (("u_shadow_map", inputs.shadow_map), ("u_caustic_map", inputs.caustic_map),
                ("u_positions", inputs.positions.positions),
                ("u_receiver_normals", inputs.positions.normals), ("u_albedos", albedos),
                ("u_back_positions", back.positions if back else None),
                ("u_back_normals", back.normals if back else None),
                ("u_receiver_maps", inputs.receiver_maps),
                ("u_receiver_triangles", inputs.receiver_triangles), ("u_receiver_uv", uv_table),
                ("u_uvs", inputs.positions.uvs))
    for unit, (_, tex) in enumerate(textures):
        if tex is not None:
            tex.use(location=unit)

    table, options = inputs.materials, inputs.options
    # Compile-time, like the object's material (camera.glsl): which caustic map is
    # read, and how.
    lookup = {"CAUSTIC_LOOKUP": int(inputs.receiver_maps is not None),
              "FILTERED": int(options.filtered)}

    def program_for(defines: dict[str, int]) -> moderngl.Program:
        program = load_program(ctx, "camera.glsl", defines=lookup | defines)
        _set_common(program, light, camera, inputs)
        for unit, (name, tex) in enumerate(textures):
            if tex is not None:
                set_uniform(program, name, unit)
        if "OBJECT" in defines:
            _set_object(program, camera, inputs, ray_scale)
        return program

    receiver_program = program_for({})
    for index, (mesh, geo) in enumerate(zip(receivers, geometry.receivers, strict=False)):
        set_uniform(receiver_program, "u_receiver", index)
        set_uniform(receiver_program, "u_albedo", tuple(float(x) for x in geo.albedo))
        vao = mesh.vertex_array(receiver_program)
        vao.render(moderngl.TRIANGLES)
        vao.release()
    # Depth pre-pass of the objects, then each object pixel is shaded only by the
    # nearest fragments (depth test <=; the shading was 1.8x the pixels on the
    # sphere without it). Back faces are drawn in both: culling them
    # (meshes.back_faces_hidden) changed 1-3 silhouette pixels per image where a
    # back face ties the front face in depth (bunny 700 x 700, high_ior_tir); at such
    # a tie the fragment drawn last is kept.
    depth_program = load_program(ctx, "camera.glsl", defines={"DEPTH_ONLY": 1})
    set_uniform(depth_program, "u_vp", camera_matrix(camera).T.astype(np.float32))
    for mesh in objects:
        vao = mesh.vertex_array(depth_program)
        vao.render(moderngl.TRIANGLES)
        vao.release()
    ctx.depth_func = "<="
    for index, mesh in enumerate(objects):
        program = program_for({"OBJECT": 1, "MATERIAL": table.code[index],
                               "DISPERSION": int(inputs.dispersion),
                               "ALL_PATHS": int(inputs.all_paths),
                               "ESTIMATOR": ESTIMATORS[options.estimator],
                               "SAFEGUARDED": int(options.safeguarded)})
        set_uniform(program, "u_object", index)
        set_uniform(program, "u_ior", tuple(float(x) for x in table.ior[index]))
        set_uniform(program, "u_absorption", tuple(float(x) for x in table.absorption[index]))
        set_uniform(program, "u_reflectance",
                    tuple(float(x) for x in table.reflectance[index]))
        set_uniform(program, "u_fresnel", int(table.fresnel[index]))
        vao = mesh.vertex_array(program)
        vao.render(moderngl.TRIANGLES)
        vao.release()
    ctx.depth_func = "<"
    image = np.frombuffer(color.read(), np.float32).reshape(h, w, 4)[::-1, :, :3].copy()
    for texture in (color, depth, albedos, uv_table):
        if texture is not None:
            resources.give_back(texture)
    return image
