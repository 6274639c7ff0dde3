"""Triangle meshes as both renderers receive them, and the transforms that place them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scenes.model import Transform

__all__ = ["TriangleMesh", "apply_transform", "is_convex", "make_mesh", "transform_matrix"]


@dataclass(frozen=True, eq=False)
class TriangleMesh:
    """An indexed triangle mesh in world space.

    Attributes
    ----------
    positions : ndarray, shape (N, 3), float32
        Vertex positions in metres.
    normals : ndarray, shape (N, 3), float32
        Unit smooth vertex normals (area-weighted for loaded meshes, analytic for
        primitives). They point outward for closed meshes.
    faces : ndarray, shape (M, 3), uint32
        Counter-clockwise vertex indices seen from the normal side.
    uvs : ndarray, shape (N, 2), float32, or None
        Receiver parameter coordinates (metres for planes and heightfields).
    closed : bool
        The mesh bounds a volume (double refraction applies). False for open
        surfaces (water, rings, meshes that are not watertight): renderers draw
        them two-sided and never cull their back faces.
    """

    positions: np.ndarray
    normals: np.ndarray
    faces: np.ndarray
    uvs: np.ndarray | None = None
    closed: bool = False

    def __post_init__(self) -> None:
        for name in ("positions", "normals"):
            arr = getattr(self, name)
            if arr.ndim != 2 or arr.shape[1] != 3:
                raise ValueError(f"{name} must have shape (N, 3), got {arr.shape}")
        if self.normals.shape != self.positions.shape:
            raise ValueError("normals and positions differ in shape")
        if self.faces.ndim != 2 or self.faces.shape[1] != 3:
            raise ValueError(f"faces must have shape (M, 3), got {self.faces.shape}")
        for arr in (self.positions, self.normals, self.faces, self.uvs):
            if arr is not None:
                arr.setflags(write=False)

    @property
    def bounds(self) -> np.ndarray:
        """Axis-aligned bounds, shape (2, 3): min row, max row, metres."""
        return np.stack([self.positions.min(axis=0), self.positions.max(axis=0)])

    def area(self) -> float:
        """Total surface area in m²."""
        p = self.positions.astype(np.float64)
        a, b, c = p[self.faces[:, 0]], p[self.faces[:, 1]], p[self.faces[:, 2]]
        return float(0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum())


def is_convex(mesh: TriangleMesh, *, tolerance: float = 1e-5) -> bool:
    """Whether a closed mesh bounds a convex body: no ray that leaves it meets it again.

    A connected, closed surface that is convex at every edge bounds a convex body
    (Tietze's theorem). At each edge the vertex opposite it in the neighbouring face
    must lie on or behind the face's plane, within ``tolerance`` times the bounding
    box's diagonal (float32 rounding of coplanar vertices, e.g. a latitude band of a
    tessellated sphere). An open, non-manifold or disconnected mesh is not convex.
    """
    from scipy.sparse import coo_matrix  # noqa: PLC0415 - scipy loads only here
    from scipy.sparse.csgraph import connected_components  # noqa: PLC0415

    faces = np.asarray(mesh.faces, np.int64)
    if not mesh.closed or len(faces) < 4:
        return False
    p = mesh.positions.astype(np.float64)
    count = len(p)
    # Directed edges a -> b of every face (counter-clockwise), with the face's third
    # vertex; in a closed manifold mesh each has exactly one twin b -> a.
    a = faces.ravel()
    b = np.roll(faces, -1, axis=1).ravel()
    third = np.roll(faces, -2, axis=1).ravel()
    keys = a * count + b
    order = np.argsort(keys)
    twins = b * count + a
    at = np.searchsorted(keys, twins, sorter=order)
    at = np.minimum(at, len(keys) - 1)
    match = order[at]
    if np.unique(keys).size != keys.size or not np.all(keys[match] == twins):
        return False
    normal = np.repeat(np.cross(p[faces[:, 1]] - p[faces[:, 0]],
                                p[faces[:, 2]] - p[faces[:, 0]]), 3, axis=0)
    length = np.linalg.norm(normal, axis=1)
    diagonal = float(np.linalg.norm(np.ptp(p, axis=0)))
    height = np.einsum("ij,ij->i", p[third[match]] - p[a], normal)
    if np.any(height > tolerance * diagonal * np.maximum(length, 1e-300)):
        return False
    graph = coo_matrix((np.ones(len(a)), (a, b)), shape=(count, count))
    used = np.unique(faces)
    _, labels = connected_components(graph, directed=False)
    return len(np.unique(labels[used])) == 1


def make_mesh(positions, normals, faces, uvs=None, *, closed: bool = False) -> TriangleMesh:
    """Build a :class:`TriangleMesh` with the canonical dtypes and unit normals."""
    normals = np.asarray(normals, np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        length = np.linalg.norm(normals, axis=1, keepdims=True)
        usable = (length > 0) & np.isfinite(length)
        normals = np.where(usable, normals / np.maximum(length, 1e-30), [0.0, 0.0, 1.0])
        # Beyond float32's range a position becomes inf; geometry checks report it.
        positions = np.ascontiguousarray(positions, np.float32)
    return TriangleMesh(
        positions=positions,
        normals=np.ascontiguousarray(normals, np.float32),
        faces=np.ascontiguousarray(faces, np.uint32),
        uvs=None if uvs is None else np.ascontiguousarray(uvs, np.float32),
        closed=closed,
    )


def transform_matrix(t: Transform) -> np.ndarray:
    """4x4 matrix of scale, then rotation about x, y, z (degrees), then translation."""
    rx, ry, rz = np.radians(t.rotate)
    cx, sx, cy, sy, cz, sz = np.cos(rx), np.sin(rx), np.cos(ry), np.sin(ry), np.cos(rz), np.sin(rz)
    rot_x = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    rot_y = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rot_z = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    m = np.eye(4)
    m[:3, :3] = rot_z @ rot_y @ rot_x * t.scale
    m[:3, 3] = t.translate
    return m


def apply_transform(mesh: TriangleMesh, m: np.ndarray) -> TriangleMesh:
    """Transform positions by ``m`` and normals by its inverse transpose."""
    p = mesh.positions.astype(np.float64) @ m[:3, :3].T + m[:3, 3]
    n = mesh.normals.astype(np.float64) @ np.linalg.inv(m[:3, :3])
    return make_mesh(p, n, mesh.faces, mesh.uvs, closed=mesh.closed)
