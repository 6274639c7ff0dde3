"""EXR files: atomic writes with the default file mode, checked reads.

Kind: regression locks of the file contract (no accuracy is measured here)."""

from __future__ import annotations

import os

import numpy as np
import pytest

from renderers import exr
from renderers.exr import ExrError, read_exr, write_exr


@pytest.fixture
def umask_022():
    previous = os.umask(0o022)
    yield
    os.umask(previous)


def test_layers_round_trip_bit_for_bit(tmp_path):
    rng = np.random.default_rng(1)
    rgb = rng.random((5, 7, 3), dtype=np.float32)
    var = rng.random((5, 7, 3), dtype=np.float32)
    write_exr(tmp_path / "a.exr", {"RGB": rgb, "variance": var})
    layers = read_exr(tmp_path / "a.exr")
    np.testing.assert_array_equal(layers["RGB"], rgb)
    np.testing.assert_array_equal(layers["variance"], var)


def test_half_layers_hold_the_half_rounded_values(tmp_path):
    """A ``half`` file holds each value rounded to half precision (what a bounded map
    such as SSIM keeps), in fewer bytes; a value beyond half's range is an error, never
    an infinity in the file."""
    values = np.random.default_rng(2).random((64, 64), dtype=np.float32)
    write_exr(tmp_path / "h.exr", {"Y": values}, half=True)
    write_exr(tmp_path / "f.exr", {"Y": values})
    np.testing.assert_array_equal(read_exr(tmp_path / "h.exr")["Y"],
                                  values.astype(np.float16).astype(np.float32))
    assert (tmp_path / "h.exr").stat().st_size < (tmp_path / "f.exr").stat().st_size
    with pytest.raises(ValueError, match="half precision"):
        write_exr(tmp_path / "big.exr", {"Y": values * 1e5}, half=True)
    assert not (tmp_path / "big.exr").exists()


@pytest.mark.usefixtures("umask_022")
def test_an_exr_gets_the_mode_of_a_normally_written_file(tmp_path):
    """Not mkstemp's 0600: the mode open() gives under the umask (0644 here)."""
    write_exr(tmp_path / "a.exr", {"RGB": np.zeros((2, 2, 3), np.float32)})
    (tmp_path / "plain").write_bytes(b"")
    plain = (tmp_path / "plain").stat().st_mode & 0o777
    assert plain == 0o644
    assert (tmp_path / "a.exr").stat().st_mode & 0o777 == plain


def test_an_exr_follows_a_stricter_umask(tmp_path):
    previous = os.umask(0o077)
    try:
        write_exr(tmp_path / "a.exr", {"RGB": np.zeros((2, 2, 3), np.float32)})
    finally:
        os.umask(previous)
    assert (tmp_path / "a.exr").stat().st_mode & 0o777 == 0o600


def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path, monkeypatch):
    path = tmp_path / "a.exr"
    write_exr(path, {"RGB": np.ones((2, 2, 3), np.float32)})
    before = path.read_bytes()

    class Broken:
        def __init__(self, *args):
            pass

        def write(self, name):
            with open(name, "wb") as handle:
                handle.write(b"half an image")
            raise RuntimeError("disk full")

    monkeypatch.setattr(exr.OpenEXR, "File", Broken)
    with pytest.raises(RuntimeError, match="disk full"):
        write_exr(path, {"RGB": np.zeros((2, 2, 3), np.float32)})
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.exr"]


def test_truncated_file_is_an_exr_error(tmp_path):
    path = tmp_path / "a.exr"
    write_exr(path, {"RGB": np.ones((16, 16, 3), np.float32)})
    path.write_bytes(path.read_bytes()[:40])
    with pytest.raises(ExrError, match="unreadable EXR"):
        read_exr(path)
