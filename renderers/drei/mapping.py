"""From drei's caustic texture to the receiver's (u, v) irradiance map.

The texture
-----------
The component renders its caustic into a square float texture of ``res`` x ``res``
texels seen by its orthographic light camera (projection P, view V). Texel (row k,
column l) (row 0 at the texture's t = 0, as WebGL's ``readPixels`` returns it) covers
light-space coordinates s in [l, l + 1) / res, t in [k, k + 1) / res, and holds

    T_kl = intensity * A_near / A_far                                  (W/m²)

for the beam that enters the objects there. Its projection material draws, at a point
p of the ground, the texel that P V p falls in: ``(s, t) = (P V p).xy / w * 1/2 + 1/2``
(w = 1: orthographic). So the component's caustic irradiance on the ground is the
texture carried along the light's direction onto the plane.

The mapping
-----------
On the receiver plane, p(u, v) = O + u U + v V (the receiver frame of
``docs/export.md``, in the drei frame of :mod:`renderers.drei.params`), and (s, t) is an
affine function of (u, v):

    (s, t) = A (u, v) + c,   A = d(s, t) / d(u, v)   (2 x 2, per metre).

A texel covers 1 / res² of (s, t) and therefore ``a = 1 / (res² |det A|)`` m² of
the ground, and holds the flux ``T_kl a`` (W). The component's whole caustic flux on
the ground is

    Phi = sum_kl T_kl a                                               (W per channel)

:func:`receiver_map` carries it into the receiver's map without losing any: each
texel's flux is split among n x n points spread evenly over the texel's ground
parallelogram, (u, v) = A^-1 ((s, t) - c), and each point's share lands in the map
texel that contains it; dividing by the map texel's area gives irradiance. The flux
the map holds is Phi less what lands outside the receiver (``outside``), to float
rounding; n is chosen so that neighbouring points are at most half a map texel apart.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from scenes.export import ReceiverFrame, to_gltf

__all__ = ["LightCamera", "MappedCaustic", "light_affine", "receiver_map", "texture_flux"]

#: Largest number of points per texel side (a texel far larger than a map texel).
MAX_POINTS = 32


@dataclass(frozen=True)
class LightCamera:
    """The component's orthographic light camera, as the page reports it.

    Attributes
    ----------
    projection, view : ndarray, (4, 4)
        P and V (V = the camera's world matrix inverse), drei frame, row-major.
    left, right, bottom, top : float
        The orthographic extent, m (``right - left`` is the texture's side on a plane
        perpendicular to the light).
    """

    projection: np.ndarray
    view: np.ndarray
    left: float
    right: float
    bottom: float
    top: float

    @classmethod
    def from_page(cls, data: dict) -> LightCamera:
        """From the page's ``lightCamera`` (three.js's column-major ``elements``)."""
        def matrix(elements):
            return np.asarray(elements, np.float64).reshape(4, 4).T
        return cls(matrix(data["projection"]), matrix(data["view"]), float(data["left"]),
                   float(data["right"]), float(data["bottom"]), float(data["top"]))


@dataclass(frozen=True, eq=False)
class MappedCaustic:
    """A caustic texture carried onto a receiver's map.

    Attributes
    ----------
    irradiance : ndarray, (H, W, 3), float64
        E in W/m², row 0 at vmin (``renderers.results`` layout).
    texture_flux : ndarray, (3,)
        Phi: the flux the texture puts on the whole ground plane, W.
    outside : ndarray, (3,)
        The part of it that lands outside the receiver's extent, W.
    points : int
        n: points per texel side.
    texel_area : float
        a: ground area of one texture texel, m².
    """

    irradiance: np.ndarray
    texture_flux: np.ndarray
    outside: np.ndarray
    points: int
    texel_area: float


def _plane_point(frame: ReceiverFrame, u, v, height: float) -> np.ndarray:
    """Drei-frame points of the receiver at (u, v) (arrays of equal shape) -> (..., 3)."""
    scene = (np.asarray(frame.origin)[None, :] + np.multiply.outer(u, frame.u_axis)
             + np.multiply.outer(v, frame.v_axis))
    return to_gltf(scene) - np.array([0.0, height, 0.0])


def light_affine(camera: LightCamera, frame: ReceiverFrame, *, height: float
                 ) -> tuple[np.ndarray, np.ndarray]:
    """(A, c) with (s, t) = A (u, v) + c on the receiver plane (module docstring).

    Raises
    ------
    ValueError
        The light camera is not orthographic (its w depends on the point).
    """
    corners = _plane_point(frame, np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0]),
                           height)
    clip = (camera.projection @ camera.view @ np.c_[corners, np.ones(3)].T).T
    if not np.allclose(clip[:, 3], 1.0, rtol=0, atol=1e-9):
        raise ValueError("the light camera is not orthographic: clip w = "
                         f"{clip[:, 3].tolist()}")
    st = clip[:, :2] * 0.5 + 0.5
    c = st[0]
    return np.stack([st[1] - c, st[2] - c], axis=1), c


def texture_flux(texture: np.ndarray, affine: tuple[np.ndarray, np.ndarray]) -> float:
    """Phi of one channel: sum of ``texture`` (res, res) times a texel's ground area, W."""
    a_matrix, _ = affine
    res = texture.shape[0]
    area = 1.0 / (res * res * abs(float(np.linalg.det(a_matrix))))
    return float(np.sum(texture, dtype=np.float64) * area)


def receiver_map(textures: np.ndarray, affine: tuple[np.ndarray, np.ndarray],
                 frame: ReceiverFrame) -> MappedCaustic:
    """Carry the caustic textures onto the receiver's map, conserving flux.

    Parameters
    ----------
    textures : ndarray, (3, res, res)
        T per RGB channel (W/m², row 0 at t = 0).
    affine : tuple
        (A, c) from :func:`light_affine`.
    frame : ReceiverFrame
        The receiver's extent and map resolution (W, H).

    Returns
    -------
    MappedCaustic
    """
    textures = np.asarray(textures, np.float64)
    _, res, res_t = textures.shape
    if res != res_t:
        raise ValueError(f"the caustic texture must be square, got {res} x {res_t}")
    a_matrix, c = affine
    inverse = np.linalg.inv(a_matrix)
    umin, umax, vmin, vmax = frame.extent
    width, height = frame.resolution
    du, dv = (umax - umin) / width, (vmax - vmin) / height
    texel_area = 1.0 / (res * res * abs(float(np.linalg.det(a_matrix))))
    # A texel's ground parallelogram has sides inverse[:, 0] / res and inverse[:, 1] / res;
    # points 1/n of a side apart are at most half a map texel apart along u and v.
    reach = np.abs(inverse).sum(axis=1) / res
    points = int(min(MAX_POINTS, max(1, math.ceil(2 * max(reach[0] / du, reach[1] / dv)))))
    rows, cols = np.nonzero(textures.max(axis=0) > 0)
    offsets = (np.arange(points) + 0.5) / points
    sub_s = ((cols[:, None, None] + offsets[None, None, :]) / res).repeat(points, axis=1)
    sub_t = ((rows[:, None, None] + offsets[None, :, None]) / res).repeat(points, axis=2)
    st = np.stack([sub_s.ravel(), sub_t.ravel()], axis=1) - c
    uv = st @ inverse.T
    column = np.floor((uv[:, 0] - umin) / du).astype(np.int64)
    row = np.floor((uv[:, 1] - vmin) / dv).astype(np.int64)
    inside = (column >= 0) & (column < width) & (row >= 0) & (row < height)
    index = row[inside] * width + column[inside]
    irradiance = np.zeros((height * width, 3))
    flux = np.zeros(3)
    outside = np.zeros(3)
    for channel in range(3):
        share = np.repeat(textures[channel, rows, cols] * texel_area / points**2, points**2)
        irradiance[:, channel] = np.bincount(index, weights=share[inside],
                                             minlength=height * width) / (du * dv)
        flux[channel] = float(textures[channel].sum(dtype=np.float64) * texel_area)
        outside[channel] = float(share[~inside].sum())
    return MappedCaustic(irradiance.reshape(height, width, 3), flux, outside, points,
                         texel_area)
