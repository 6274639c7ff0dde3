"""Frames of an exported scene: the axis conversion, node rotations, and the frame that
maps an orthographic image of a receiver onto its (u, v) irradiance map.

Axes
----
Scenes are right-handed with +z up; glTF 2.0 is right-handed with +y up. A point or
direction p of the scene is written as ``GLTF_FROM_SCENE @ p``:

    (x, y, z)_scene -> (x, z, -y)_glTF,

a rotation by -90 degrees about x (determinant +1, so handedness, winding and normals
keep their meaning). Its inverse (the transpose) reads a glTF file back.

Receiver frame
--------------
A receiver's (u, v) parameter domain is its irradiance map's domain
(``extent = (umin, umax, vmin, vmax)``, :class:`scenes.geometry.ReceiverGeometry`).
For every receiver kind the harness has, (u, v) is an orthographic projection:

    p(u, v, h) = origin + u U + v V + h N

with U, V, N orthonormal (U x V = N): planes (``u_axis``, ``normal x u_axis``,
``normal``, origin the centre), heightfields and meshes without texture coordinates
(x, y, z, origin the heightfield's centre or the world origin). A camera looking along
-N with image right = U and image up = V therefore sees the receiver's texel (u, v) at
image position (u, v): pixel (row i from the top, column j) of a W x H image has its
centre at

    u = umin + (j + 1/2) (umax - umin) / W,   v = vmax - (i + 1/2) (vmax - vmin) / H,

which is texel (row H - 1 - i, column j) of the irradiance map (whose row 0 is at
vmin): the map is the image flipped upside down. The camera sits ``margin`` above the
receiver's highest point and sees only the slab of heights [lowest - margin,
highest + margin / 2] (its near and far planes), so caustic objects above the receiver
do not hide it from the camera while they still cast their caustics on it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from scenes.geometry import ReceiverGeometry
from scenes.model import HeightfieldReceiver, MeshReceiver, PlaneReceiver, Receiver

__all__ = ["GLTF_FROM_SCENE", "SLAB_MARGIN", "ReceiverFrame", "any_up", "look_rotation",
           "quaternion", "receiver_frame", "to_gltf"]

#: Scene (+z up) to glTF (+y up) coordinates: a rotation by -90 degrees about x.
GLTF_FROM_SCENE = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
#: Receiver cameras' clearance above the receiver's highest point, as a fraction of the
#: receiver's larger (u, v) side (see the module docstring).
SLAB_MARGIN = 1e-3


def to_gltf(vectors) -> np.ndarray:
    """Scene points or directions (..., 3) in glTF coordinates (float64)."""
    return np.asarray(vectors, np.float64) @ GLTF_FROM_SCENE.T


def look_rotation(forward, up) -> np.ndarray:
    """3x3 rotation whose local -z is ``forward`` and local +y lies along ``up``'s part
    perpendicular to it: the orientation of a glTF camera or light node (both look
    along their local -z). Columns: right, image up, backward."""
    f = np.asarray(forward, np.float64)
    f = f / np.linalg.norm(f)
    right = np.cross(f, np.asarray(up, np.float64))
    right /= np.linalg.norm(right)
    return np.stack([right, np.cross(right, f), -f], axis=1)


def quaternion(rotation: np.ndarray) -> list[float]:
    """glTF's unit quaternion (x, y, z, w) of a 3x3 rotation matrix."""
    return [float(q) for q in Rotation.from_matrix(rotation).as_quat()]


def any_up(direction) -> np.ndarray:
    """An up vector not parallel to ``direction`` (+y, else +z), in glTF coordinates:
    the roll of a light's node, which a punctual light does not depend on."""
    d = np.asarray(direction, np.float64)
    return np.array([0.0, 0.0, 1.0]) if abs(d[1]) > 0.99 * np.linalg.norm(d) else np.array(
        [0.0, 1.0, 0.0])


@dataclass(frozen=True)
class ReceiverFrame:
    """How an orthographic image of a receiver maps onto its (u, v) irradiance map.

    All vectors are in scene coordinates (metres, +z up); :func:`to_gltf` converts them.

    Attributes
    ----------
    origin : tuple of float
        The point of (u, v, h) = (0, 0, 0), m.
    u_axis, v_axis, normal : tuple of float
        Unit U, V, N (U x V = N); N is the side the receiver is lit and seen from.
    extent : tuple of float
        ``(umin, umax, vmin, vmax)`` of the irradiance map, m.
    resolution : tuple of int
        The map's (W, H) texels (the scene's ``settings.receiver_map``).
    eye : tuple of float
        The orthographic camera's position: above the extent's centre, ``margin`` over
        the highest point, m.
    znear, zfar : float
        Its clip distances along -N, m: the slab it sees.
    """

    origin: tuple[float, float, float]
    u_axis: tuple[float, float, float]
    v_axis: tuple[float, float, float]
    normal: tuple[float, float, float]
    extent: tuple[float, float, float, float]
    resolution: tuple[int, int]
    eye: tuple[float, float, float]
    znear: float
    zfar: float

    @property
    def half_size(self) -> tuple[float, float]:
        """Half the extent along u and v (glTF's ``xmag``, ``ymag``), m."""
        umin, umax, vmin, vmax = self.extent
        return (umax - umin) / 2, (vmax - vmin) / 2

    def image_to_uv(self, column, row) -> tuple[np.ndarray, np.ndarray]:
        """(u, v) of film positions (column, row) in pixels from the image's left and
        top edges (a pixel's centre is at + 1/2)."""
        umin, umax, vmin, vmax = self.extent
        width, height = self.resolution
        u = umin + np.asarray(column, np.float64) * (umax - umin) / width
        v = vmax - np.asarray(row, np.float64) * (vmax - vmin) / height
        return u, v


def _axes(receiver: Receiver, geometry: ReceiverGeometry):
    """(origin, U, V, N, projected): ``projected`` is False where (u, v) are a mesh's
    own texture coordinates, which no orthographic camera reproduces."""
    if isinstance(receiver, PlaneReceiver):
        n = np.asarray(receiver.normal, float) / np.linalg.norm(receiver.normal)
        u = np.asarray(receiver.u_axis, float)
        u = u - n * (u @ n)
        u /= np.linalg.norm(u)
        return np.asarray(receiver.center, float), u, np.cross(n, u), n, True
    x, y, z = np.eye(3)
    if isinstance(receiver, HeightfieldReceiver):
        return np.asarray(receiver.center, float), x, y, z, True
    if isinstance(receiver, MeshReceiver):
        mesh = geometry.mesh
        projected = bool(np.array_equal(mesh.uvs, mesh.positions[:, :2]))
        return np.zeros(3), x, y, z, projected
    raise TypeError(f"unknown receiver {receiver!r}")


def receiver_frame(receiver: Receiver, geometry: ReceiverGeometry,
                   resolution: tuple[int, int]) -> tuple[ReceiverFrame, bool]:
    """The receiver's frame, and whether its (u, v) is the frame's projection (False:
    a mesh with its own texture coordinates; the camera then shows the projection along
    z, not the map)."""
    origin, u, v, n, projected = _axes(receiver, geometry)
    umin, umax, vmin, vmax = geometry.extent
    heights = (geometry.mesh.positions.astype(np.float64) - origin) @ n
    top, bottom = float(heights.max()), float(heights.min())
    margin = SLAB_MARGIN * max(umax - umin, vmax - vmin)
    eye = origin + u * (umin + umax) / 2 + v * (vmin + vmax) / 2 + n * (top + margin)
    frame = ReceiverFrame(
        origin=_tuple(origin), u_axis=_tuple(u), v_axis=_tuple(v), normal=_tuple(n),
        extent=tuple(float(e) for e in geometry.extent),
        resolution=(int(resolution[0]), int(resolution[1])), eye=_tuple(eye),
        znear=margin / 2, zfar=top - bottom + 2 * margin,
    )
    return frame, projected


def _tuple(v) -> tuple[float, float, float]:
    return tuple(float(x) for x in v)
