"""Triangle meshes uploaded once per render as vertex and index buffers."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import moderngl
import numpy as np

from scenes.geometry import TriangleMesh
from scenes.geometry.mesh import is_convex

__all__ = ["ContentCache", "GpuMesh", "back_faces_hidden", "convex", "upload_mesh"]


class ContentCache:
    """Values computed from arrays, remembered by the arrays' content (a render
    builds its meshes anew every frame, so their identity says nothing): at most
    ``kept`` values, the oldest dropped first."""

    def __init__(self, kept: int):
        self.kept = kept
        self._values: dict[bytes, object] = {}

    def get(self, arrays, compute):
        """``compute()``'s value for the content of ``arrays`` (a sequence of
        array-likes), computed on the first call for that content."""
        digest = hashlib.blake2b(digest_size=16)
        for array in arrays:
            digest.update(np.ascontiguousarray(array).tobytes())
        key = digest.digest()
        if key not in self._values:
            if len(self._values) >= self.kept:
                self._values.pop(next(iter(self._values)))
            self._values[key] = compute()
        return self._values[key]


#: Convexity of meshes seen so far.
_CONVEX = ContentCache(64)


@dataclass(frozen=True, eq=False)
class GpuMesh:
    """A mesh on the GPU: interleaved ``3f position (m), 3f normal, 2f (u, v)``;
    ``source`` the mesh it was uploaded from."""

    vbo: moderngl.Buffer
    ibo: moderngl.Buffer
    source: TriangleMesh | None = None

    def vertex_array(self, program: moderngl.Program) -> moderngl.VertexArray:
        """A VAO binding the attributes ``program`` uses (others are skipped)."""
        names = ("in_position", "in_normal", "in_uv")
        sizes = (12, 12, 8)
        fmt, attrs = [], []
        for name, size in zip(names, sizes, strict=False):
            if name in program:
                fmt.append(f"{size // 4}f")
                attrs.append(name)
            else:
                fmt.append(f"{size}x")
        return program.ctx.vertex_array(
            program, [(self.vbo, " ".join(fmt), *attrs)], index_buffer=self.ibo,
            index_element_size=4,
        )

    def release(self) -> None:
        self.vbo.release()
        self.ibo.release()


def back_faces_hidden(mesh: TriangleMesh, view_proj: np.ndarray) -> bool:
    """Whether no back face of ``mesh`` can be the nearest surface in view ``view_proj``
    (world -> clip; row-major, column vectors): the mesh is closed (outward normals,
    counter-clockwise faces) and lies wholly in front of the near plane, so the eye
    is outside it. Every ray from the eye that meets the mesh then enters it through
    a front face first, so with the depth test culling back faces (half the
    triangles to set up, rasterise and shade) leaves the image as it was, except
    where a back face ties the front face in depth at a silhouette (the depth test
    keeps the first drawn). Used by the shadow map only, where such a texel's
    distance differs by rounding and the biased visibility test does not flip (no
    output of any committed scene changed); the object-positions and camera passes
    do not cull, as it changed a grid record (high_ior_tir) and 1-3 camera pixels.
    """
    if not mesh.closed:
        return False
    p = mesh.positions.astype(np.float64)
    clip = p @ view_proj[:3, :3].T + view_proj[:3, 3]
    w = p @ view_proj[3, :3] + view_proj[3, 3]
    return bool(np.all(clip[:, 2] + w > 1e-6 * np.abs(w) + 1e-300))


def convex(mesh: TriangleMesh) -> bool:
    """:func:`scenes.geometry.mesh.is_convex`, remembered by the mesh's content: the
    test takes 25 ms on a 20,480-face sphere and 0.1 s on the bunny, and a render
    rebuilds its meshes every frame."""
    return _CONVEX.get((mesh.positions, mesh.faces, np.array([mesh.closed])),
                       lambda: is_convex(mesh))


def upload_mesh(ctx: moderngl.Context, mesh: TriangleMesh) -> GpuMesh:
    """Upload ``mesh``; a mesh without (u, v) gets zeros."""
    uvs = mesh.uvs if mesh.uvs is not None else np.zeros((len(mesh.positions), 2), np.float32)
    data = np.hstack([mesh.positions, mesh.normals, uvs]).astype(np.float32)
    return GpuMesh(ctx.buffer(data.tobytes()), ctx.buffer(mesh.faces.astype(np.uint32).tobytes()),
                   mesh)
