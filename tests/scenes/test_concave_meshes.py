"""The concave hard cases' meshes (``scenes/meshes/make_shallow_bowl_halfpipe.py``):
the committed files are what the script writes, byte for byte (regression lock), and
their vertices lie on the surfaces the scene descriptions state (physical
requirement: the shallow bowl is a cap of rim radius 1 and depth 0.5 of a sphere of
radius 1.25; the half-pipe the lower half of a unit cylinder about y, 3 m long)."""

from __future__ import annotations

import runpy

import numpy as np

from tests.conftest import SCENES

MESHES = SCENES / "meshes"


def _vertices(path):
    rows = [line.split()[1:] for line in path.read_text().splitlines() if line.startswith("v ")]
    return np.array(rows, float)


def test_the_committed_meshes_are_the_script_s_output(tmp_path, monkeypatch):
    """Regression lock: the script, run in an empty folder, writes both files again."""
    monkeypatch.chdir(tmp_path)
    runpy.run_path(str(MESHES / "make_shallow_bowl_halfpipe.py"), run_name="__main__")
    for name in ("bowl_shallow.obj", "halfpipe.obj"):
        assert (tmp_path / name).read_bytes() == (MESHES / name).read_bytes(), name


def test_the_meshes_lie_on_their_surfaces():
    """Physical requirement: distances to the stated surfaces within the files'
    6-decimal rounding (5e-7 m per coordinate, so at most sqrt(3) × 5e-7 m off the
    surface; bound 1e-6 m)."""
    cap = _vertices(MESHES / "bowl_shallow.obj")
    centre = np.array([0.0, 0.0, 1.25 - 0.5])
    assert np.abs(np.linalg.norm(cap - centre, axis=1) - 1.25).max() < 1e-6
    assert np.isclose(cap[:, 2].min(), -0.5) and np.isclose(cap[:, 2].max(), 0.0, atol=1e-6)
    assert np.isclose(np.hypot(cap[:, 0], cap[:, 1]).max(), 1.0, atol=1e-6)
    pipe = _vertices(MESHES / "halfpipe.obj")
    assert np.abs(np.hypot(pipe[:, 0], pipe[:, 2]) - 1.0).max() < 1e-6
    assert pipe[:, 2].max() <= 1e-6 and np.isclose(np.ptp(pipe[:, 1]), 3.0)
