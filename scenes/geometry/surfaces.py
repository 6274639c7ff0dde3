"""Height functions (receivers, water) and the triangle grids built from them."""

from __future__ import annotations

import numpy as np

from scenes.model import (
    FileHeight,
    Height,
    RuggedHeight,
    SinesHeight,
    StepHeight,
    WaterSurface,
)

__all__ = ["evaluate_height", "grid_mesh_arrays", "water_height"]


def _unit2(v) -> np.ndarray:
    v = np.asarray(v, np.float64)
    return v / np.linalg.norm(v)


def _value_noise(x: np.ndarray, y: np.ndarray, cell: float, seed: int) -> np.ndarray:
    """Smooth value noise in [-1, 1]: random values on a lattice of spacing ``cell``,
    blended with the C1 smoothstep s(t) = t² (3 - 2t)."""
    gx, gy = x / cell, y / cell
    ix, iy = np.floor(gx).astype(np.int64), np.floor(gy).astype(np.int64)
    fx, fy = gx - ix, gy - iy
    sx, sy = fx * fx * (3 - 2 * fx), fy * fy * (3 - 2 * fy)

    def lattice(i, j):
        # Hash integer lattice coordinates into [-1, 1) deterministically per seed.
        h = (i * 374761393 + j * 668265263 + seed * 2147483647) & 0xFFFFFFFF
        h = ((h ^ (h >> 13)) * 1274126177) & 0xFFFFFFFF
        return (h ^ (h >> 16)) / 2**31 - 1.0

    v00, v10 = lattice(ix, iy), lattice(ix + 1, iy)
    v01, v11 = lattice(ix, iy + 1), lattice(ix + 1, iy + 1)
    return (v00 * (1 - sx) + v10 * sx) * (1 - sy) + (v01 * (1 - sx) + v11 * sx) * sy


def evaluate_height(height: Height, x: np.ndarray, y: np.ndarray, size) -> np.ndarray:
    """Height in metres at local coordinates (x, y) (metres from the receiver centre).

    ``size`` is the receiver's (width, depth), used by file heightfields to map the
    array over the rectangle.
    """
    x, y = np.asarray(x, np.float64), np.asarray(y, np.float64)
    if isinstance(height, SinesHeight):
        d = _unit2(height.direction)
        return height.amplitude * np.sin(
            2 * np.pi * (d[0] * x + d[1] * y) / height.wavelength + height.phase
        )
    if isinstance(height, StepHeight):
        return height.step_height * np.floor(x / height.step_width)
    if isinstance(height, RuggedHeight):
        total = np.zeros_like(x)
        norm = 0.0
        for octave in range(height.octaves):
            weight = 0.5**octave
            total += weight * _value_noise(x, y, height.feature_size * 0.5**octave,
                                           height.seed + 101 * octave)
            norm += weight
        return height.amplitude * total / norm
    if isinstance(height, FileHeight):
        return _bilinear(load_height_array(height.file), x, y, size)
    raise TypeError(f"unknown height {height!r}")


def load_height_array(path: str) -> np.ndarray:
    """Load a 2-D finite float array of heights (metres) from ``.npy``.

    Raises
    ------
    ValueError
        Not a readable 2-D array of at least 2x2 finite numbers.
    """
    try:
        arr = np.load(path, allow_pickle=False)
    except Exception as error:  # numpy raises several types for bad files
        raise ValueError(f"not a readable .npy array ({error})") from None
    if arr.ndim != 2 or min(arr.shape) < 2:
        raise ValueError(f"must be a 2-D array of at least 2x2, got shape {arr.shape}")
    if not np.issubdtype(arr.dtype, np.number) or not np.all(np.isfinite(arr)):
        raise ValueError("must hold finite numbers")
    return arr.astype(np.float64)


def _bilinear(arr: np.ndarray, x: np.ndarray, y: np.ndarray, size) -> np.ndarray:
    rows, cols = arr.shape
    fx = np.clip((x / size[0] + 0.5) * (cols - 1), 0, cols - 1)
    fy = np.clip((y / size[1] + 0.5) * (rows - 1), 0, rows - 1)
    ix, iy = np.minimum(fx.astype(int), cols - 2), np.minimum(fy.astype(int), rows - 2)
    tx, ty = fx - ix, fy - iy
    top = arr[iy, ix] * (1 - tx) + arr[iy, ix + 1] * tx
    bottom = arr[iy + 1, ix] * (1 - tx) + arr[iy + 1, ix + 1] * tx
    return top * (1 - ty) + bottom * ty


def water_height(water: WaterSurface, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Water height (metres above ``center``) at local (x, y) and time ``water.time``.

    Waves: A sin(k (d·p) - k c t + phase) with k = 2π/λ. A plop started at t0 is a
    ring packet travelling outward at speed c: A e^{-γ τ} cos(k (r - c τ))
    exp(-((r - c τ)/w)²) for τ = t - t0 ≥ 0, nothing before the impact.
    """
    x, y = np.asarray(x, np.float64), np.asarray(y, np.float64)
    h = np.zeros_like(x)
    t = water.time
    for wave in water.waves:
        d = _unit2(wave.direction)
        k = 2 * np.pi / wave.wavelength
        h += wave.amplitude * np.sin(k * (d[0] * x + d[1] * y) - k * wave.speed * t + wave.phase)
    for plop in water.plops:
        tau = t - plop.start
        if tau < 0:
            continue
        r = np.hypot(x - plop.position[0], y - plop.position[1])
        front = r - plop.speed * tau
        k = 2 * np.pi / plop.wavelength
        h += (plop.amplitude * np.exp(-plop.damping * tau) * np.cos(k * front)
              * np.exp(-((front / plop.width) ** 2)))
    return h


def grid_mesh_arrays(size, resolution, height_fn):
    """A (nx, ny) vertex grid over a centred rectangle, displaced along +z.

    Returns local positions (N, 3), normals (N, 3), faces (M, 3) and uvs (N, 2) in
    metres. Normals are (-∂h/∂x, -∂h/∂y, 1) normalised, with the derivatives taken
    by central differences of ``height_fn`` at a step of 1e-4 of the grid spacing,
    so they are smooth even where the grid is coarse.
    """
    nx, ny = resolution
    xs = np.linspace(-size[0] / 2, size[0] / 2, nx)
    ys = np.linspace(-size[1] / 2, size[1] / 2, ny)
    x, y = np.meshgrid(xs, ys)  # rows follow y
    z = height_fn(x, y)
    hx = 1e-4 * size[0] / (nx - 1)
    hy = 1e-4 * size[1] / (ny - 1)
    dzdx = (height_fn(x + hx, y) - height_fn(x - hx, y)) / (2 * hx)
    dzdy = (height_fn(x, y + hy) - height_fn(x, y - hy)) / (2 * hy)
    positions = np.stack([x, y, z], axis=-1).reshape(-1, 3)
    normals = np.stack([-dzdx, -dzdy, np.ones_like(z)], axis=-1).reshape(-1, 3)
    idx = np.arange(nx * ny).reshape(ny, nx)
    a, b = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel()
    c, d = idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    faces = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    uvs = np.stack([x, y], axis=-1).reshape(-1, 2)
    return positions, normals, faces, uvs
