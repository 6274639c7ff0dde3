"""Splatting records made elsewhere with the method's own splat passes
(``renderers.caustics_mapping.record_splat``, the hook the error decomposition uses).

Kinds: the method's own records, read back and splatted through the hook, give the
method's own maps bit for bit (a **regression lock** with an exact bound: 0 is what
"the same splat passes" means, not a calibrated number); every kernel keeps the flux
of the records it splats (**physical requirement**); the record layout is the trace
pass's own, and records that do not fit the scene are refused.
"""

from __future__ import annotations

import numpy as np
import pytest

from renderers.caustics_mapping import render_frame
from renderers.caustics_mapping.caustic_trace import STATUS, Trace
from renderers.caustics_mapping.methods import PAPER, STRONG
from renderers.caustics_mapping.presets import resolve_scene
from renderers.caustics_mapping.record_splat import (
    RecordError,
    pack_records,
    splat_records,
    split_records,
)
from scenes import parse_scene
from scenes.geometry import build_geometry
from tests.conftest import MINIMAL_SCENE, REPO

from .conftest import small_scene


@pytest.mark.regression_lock
@pytest.mark.parametrize(("name", "method", "kernel"), [
    ("glass_sphere", PAPER, None),            # points, nearest lookups
    ("glass_sphere", STRONG, None),           # triangles (+ footprint leftovers)
    ("glass_sphere", STRONG, "footprint"),
    ("seabed", STRONG, None),                 # a rock mesh: (u, v) from the positions pass
    ("dispersion_sphere", PAPER, None),       # three channels, a directional light
    ("metal_ring", STRONG, None),             # a reflector under a cube of map views
])
def test_hook_splats_the_methods_records_into_the_methods_maps(ctx, name, method, kernel):
    """Read back, split per light sample and channel, and splat through the hook, a
    frame's records give that frame's receiver maps exactly. The hook takes the
    grid's records, so the frames here trace no rim patches (``rim_patches = 1``)."""
    scene = method.configure(small_scene(REPO / "scenes" / f"{name}.toml", rim_patches=1,
                                         **({"splat": kernel} if kernel else {})))
    geometry = build_geometry(scene)
    frame = render_frame(scene, ctx=ctx, geometry=geometry)
    again = splat_records(scene, split_records(frame.hits), ctx=ctx, geometry=geometry)
    assert len(again.receivers) == len(frame.result.receivers)
    for mine, theirs in zip(again.receivers, frame.result.receivers, strict=True):
        assert theirs.irradiance.max() > 0          # every receiver, seabed's rock too
        np.testing.assert_array_equal(mine.irradiance, theirs.irradiance)
        assert mine.extent == theirs.extent
    # The light-space caustic map is drawn where the camera would read it (paper);
    # strong's camera reads the receivers' maps.
    light_map = resolve_scene(scene, geometry).settings.caustic_lookup == "light"
    assert set(again.timings) >= {"receiver_positions", "receiver_map"}
    assert ("caustic_map" in again.timings) == light_map


def _plane_records(grid: int, flux: float) -> np.ndarray:
    """A grid² lattice of hits on the floor (z = 0) over [−1, 1]² m, each of ``flux`` W
    per channel, on receiver 0 with its normal +z (the minimal scene's floor)."""
    t = (np.arange(grid) + 0.5) / grid * 2 - 1
    x, y = np.meshgrid(t, t)                                # row ty, column tx
    hit = np.stack([x.ravel(), y.ravel(), np.zeros(grid * grid)], axis=1)
    count = grid * grid
    return pack_records(
        origin=np.tile([0.0, 0.0, 1.0], (count, 1)), view=np.zeros(count),
        direction=np.tile([0.0, 0.0, -1.0], (count, 1)), distance=np.ones(count), hit=hit,
        status=np.full(count, STATUS["hit"]), flux=np.full((count, 3), flux),
        receiver=np.zeros(count), normal=np.tile([0.0, 0.0, 1.0], (count, 1)))


@pytest.mark.physical_requirement
@pytest.mark.parametrize("kernel", ["points", "footprint", "triangles"])
def test_every_kernel_keeps_the_records_flux(ctx, kernel):
    """Σ E A over the receiver map equals the flux of the splatted records (every
    kernel conserves each vertex's flux, ``splat_kernels.glsl``); 0.1 % for float32
    sums over 64² texels."""
    grid, flux = 32, 1e-3
    scene = parse_scene(MINIMAL_SCENE + f'\n[settings]\ngrid = {grid}\nsplat = "{kernel}"\n'
                        'receiver_map = [64, 64]\n', file="plane_records")
    maps = splat_records(scene, [[_plane_records(grid, flux)]], ctx=ctx)
    receiver = maps.receivers[0]
    umin, umax, vmin, vmax = receiver.extent
    texel = (umax - umin) * (vmax - vmin) / (64 * 64)
    total = receiver.irradiance.astype(np.float64).sum(axis=(0, 1)) * texel
    np.testing.assert_allclose(total, grid * grid * flux, rtol=1e-3)


def test_packed_records_read_back_as_the_trace_reads_them(ctx):
    """:func:`pack_records` writes the layout :meth:`Trace.read` reads (the trace
    pass's own): every field comes back."""
    rng = np.random.default_rng(1)
    count = 50
    fields = {"origin": rng.normal(size=(count, 3)), "view": rng.integers(0, 6, count),
              "direction": rng.normal(size=(count, 3)), "distance": rng.uniform(0, 9, count),
              "hit": rng.normal(size=(count, 3)), "status": rng.integers(0, 7, count),
              "flux": rng.uniform(0, 1, (count, 3)), "receiver": rng.integers(-1, 3, count),
              "normal": rng.normal(size=(count, 3))}
    packed = pack_records(**fields)
    trace = Trace(ctx.buffer(packed.tobytes()), ctx.buffer(np.zeros(count, "f4").tobytes()),
                  count, 0)
    back = trace.read()
    for key, value in fields.items():
        np.testing.assert_allclose(back[key], value, rtol=1e-6, err_msg=key)
    trace.records.release()
    trace.history.release()


def test_records_that_do_not_fit_are_refused(ctx):
    """Wrong record count for the grid, wrong channel count, wrong light samples:
    each a :class:`RecordError` naming what is expected."""
    scene = parse_scene(MINIMAL_SCENE + "\n[settings]\ngrid = 8\n", file="fit")
    good = _plane_records(8, 1e-3)
    with pytest.raises(RecordError, match=r"needs \(64, 5, 4\)"):
        splat_records(scene, [[good[:10]]], ctx=ctx)
    with pytest.raises(RecordError, match="traces 1 channel"):
        splat_records(scene, [[good, good]], ctx=ctx)
    with pytest.raises(RecordError, match="has 1"):
        splat_records(scene, [[good], [good]], ctx=ctx)
