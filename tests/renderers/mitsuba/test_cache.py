"""The reference cache: hits, and recovery from truncated files, corrupt sidecars,
a writer killed mid-write, and two processes rendering the same key at once.
All renders are tiny (16 x 16 camera and map, 2^14 photons, 2 seeds)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from renderers.mitsuba import _mi
from renderers.mitsuba.cache import cache_key, load_entry
from renderers.mitsuba.reference import render_reference
from scenes import load_scene

ROOT = Path(__file__).resolve().parents[3]

TINY = """
[scene]
name = "tiny"

[light]
type = "directional"
direction = [0.2, 0.1, -1.0]
irradiance = [3.0, 3.0, 3.0]

[[receivers]]
type = "plane"
center = [0.0, 0.0, 0.0]
size = [4.0, 4.0]
albedo = [0.5, 0.5, 0.5]

[[objects]]
type = "sphere"
center = [0.0, 0.0, 1.5]
radius = 0.5
subdivisions = 2
material = { type = "dielectric", ior = 1.5 }

[camera]
position = [0.0, -5.0, 4.0]
look_at = [0.0, 0.0, 0.5]
fov = 40.0
resolution = [16, 16]

[settings]
receiver_map = [16, 16]
photons = 16384
spp = 2
seeds = 2
"""


@pytest.fixture
def tiny(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(TINY)
    return load_scene(path)


def _env():
    return dict(os.environ, PYTHONPATH=str(ROOT))


def test_second_call_hits_and_returns_the_same_arrays(tiny, tmp_path):
    """A stored entry is read back bit-for-bit, with its sidecar metadata."""
    first = render_reference(tiny, cache=tmp_path / "c", progress=False)
    second = render_reference(tiny, cache=tmp_path / "c", progress=False)
    assert first.metadata["cache"].startswith("miss")
    assert second.metadata["cache"] == "hit"
    np.testing.assert_array_equal(first.camera, second.camera)
    np.testing.assert_array_equal(first.receivers[0].irradiance, second.receivers[0].irradiance)
    np.testing.assert_array_equal(first.receivers[0].variance, second.receivers[0].variance)
    assert second.metadata["photons"] == first.metadata["photons"]
    assert second.metadata["event_chains"] == ["L D", "L T T D (objects[0])"]


def test_truncated_exr_is_detected_and_rerendered(tiny, tmp_path):
    root = tmp_path / "c"
    render_reference(tiny, cache=root, progress=False)
    key = cache_key(tiny, _mi.versions())
    exr = root / key / "receiver_irradiance.exr"
    exr.write_bytes(exr.read_bytes()[: exr.stat().st_size // 2])
    result, why = load_entry(root, key)
    assert result is None and why.startswith("invalid")
    again = render_reference(tiny, cache=root, progress=False)
    assert again.metadata["cache"].startswith("miss (invalid")
    assert load_entry(root, key)[1] == "hit"


def test_corrupt_sidecar_is_detected_and_rerendered(tiny, tmp_path):
    root = tmp_path / "c"
    render_reference(tiny, cache=root, progress=False)
    key = cache_key(tiny, _mi.versions())
    (root / key / "result.json").write_text("{not json")
    assert load_entry(root, key)[0] is None
    assert render_reference(tiny, cache=root, progress=False).metadata["cache"].startswith("miss")
    document = json.loads((root / key / "result.json").read_text())
    assert document["hash"] == key


def test_writer_killed_mid_write_leaves_a_miss_not_a_corrupt_hit(tiny, tmp_path):
    """A child process renders, writes its first EXR, then is SIGKILLed before the
    sidecar exists. The entry must read as a miss, the lock must be free, and a
    new render must succeed."""
    root = tmp_path / "c"
    script = textwrap.dedent(f"""
        import sys, time
        from scenes import load_scene
        import renderers.mitsuba.cache as cache
        from renderers.mitsuba.reference import render_reference
        real = cache.write_exr
        def slow_write(path, layers):
            real(path, layers)
            print("WROTE", path, flush=True)
            time.sleep(120)
        cache.write_exr = slow_write
        render_reference(load_scene({str(tmp_path / "tiny.toml")!r}), cache={str(root)!r},
                         progress=False)
    """)
    child = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE,
                             env=_env(), text=True)
    try:
        line = child.stdout.readline()
        assert line.startswith("WROTE"), line
    finally:
        child.send_signal(signal.SIGKILL)
        child.wait(timeout=30)
    key = cache_key(tiny, _mi.versions())
    assert (root / key / "camera.exr").exists()
    result, why = load_entry(root, key)
    assert result is None and why.startswith("invalid")
    again = render_reference(tiny, cache=root, progress=False)  # would hang on a stuck lock
    assert again.metadata["cache"].startswith("miss")
    assert load_entry(root, key)[1] == "hit"


def test_two_processes_rendering_the_same_key(tiny, tmp_path):
    """Both succeed; one renders (miss), the other waits on the lock and reads the
    finished entry (hit); the entry is valid afterwards."""
    root = tmp_path / "c"
    script = textwrap.dedent(f"""
        from scenes import load_scene
        from renderers.mitsuba.reference import render_reference
        r = render_reference(load_scene({str(tmp_path / "tiny.toml")!r}), cache={str(root)!r},
                             progress=False)
        print(r.metadata["cache"])
    """)
    children = [subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE,
                                 env=_env(), text=True) for _ in range(2)]
    outputs = [c.communicate(timeout=300)[0].strip() for c in children]
    assert all(c.returncode == 0 for c in children)
    assert sorted(o.split()[0] for o in outputs) == ["hit", "miss"], outputs
    assert load_entry(root, cache_key(tiny, _mi.versions()))[1] == "hit"
