"""Pass 5a: the closed dielectrics' back faces from the camera (Wyman 2005).

Wyman's image-space double refraction ("An Approximate Image-Space Approach for
Interactive Refraction", SIGGRAPH 2005) renders the refractive object's back faces
from the eye into a texture; the final pass refracts the view ray at the front
surface and looks up where it leaves the object there. This pass makes that
texture; the camera pass (:mod:`.camera`) reads it. It runs only with the
``refraction.double`` effect, once per frame (the camera does not move between the
samples of an area light).

Output: two RGBA32F textures of the camera's resolution, row 0 at the bottom
(layout in ``camera_backfaces.glsl``): ``positions`` xyz world position (m) of the
nearest back face, w object index + 1 (0: none); ``normals`` xyz unit outward
normal, w 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import moderngl
import numpy as np

from renderers.caustics_mapping.context import ResourcePool, load_program, pool
from renderers.caustics_mapping.meshes import GpuMesh
from renderers.caustics_mapping.uniforms import set_uniform

__all__ = ["CameraBackFaces", "render_camera_backfaces"]


@dataclass(frozen=True, eq=False)
class CameraBackFaces:
    """The back-face textures from the camera (pooled: give them back, never release).

    Attributes
    ----------
    positions : moderngl.Texture
        RGBA32F, (W, H): xyz world position (m), w object index + 1 (0: none).
    normals : moderngl.Texture
        RGBA32F, (W, H): xyz unit outward normal, w 0.
    size : tuple of int
        (W, H), the camera's resolution (px).
    """

    positions: moderngl.Texture
    normals: moderngl.Texture
    size: tuple[int, int]

    def read_positions(self) -> np.ndarray:
        """Attachment 0 as an array (H, W, 4), row 0 at the bottom."""
        w, h = self.size
        return np.frombuffer(self.positions.read(), np.float32).reshape(h, w, 4)

    def give_back(self, resources: ResourcePool) -> None:
        """Return the textures to the context's pool."""
        resources.give_back(self.positions)
        resources.give_back(self.normals)


def render_camera_backfaces(
    ctx: moderngl.Context, *, view_proj: np.ndarray, size: tuple[int, int],
    objects: list[GpuMesh], which: list[int],
) -> CameraBackFaces:
    """Render the back faces of the objects ``which`` (closed dielectrics) from the camera.

    Parameters
    ----------
    view_proj : ndarray, (4, 4)
        World -> clip of the scene camera (:func:`.camera.camera_matrix`).
    size : tuple of int
        (W, H) of the camera image (px).
    objects : list of GpuMesh
        Every object of the scene, indexed as the scene's objects.
    which : list of int
        Indices of the closed dielectrics (those with an exit surface).
    """
    resources = pool(ctx)
    textures = [resources.texture(tuple(size)) for _ in range(2)]
    depth = resources.depth_texture(tuple(size))
    fbo = resources.framebuffer(textures, depth)
    program = load_program(ctx, "camera_backfaces.glsl")
    set_uniform(program, "u_vp", np.asarray(view_proj).T.astype(np.float32))
    fbo.use()
    fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
    ctx.enable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
    ctx.disable(moderngl.BLEND)
    ctx.cull_face = "front"          # keep the faces turned away from the eye
    for index in which:
        set_uniform(program, "u_index", index)
        vao = objects[index].vertex_array(program)
        vao.render(moderngl.TRIANGLES)
        vao.release()
    ctx.cull_face = "back"           # GL's default, which the other passes assume
    ctx.disable(moderngl.CULL_FACE)
    resources.give_back(depth)
    return CameraBackFaces(*textures, size=(int(size[0]), int(size[1])))
