"""The reference cache: hits, and recovery from truncated files, corrupt sidecars,
a writer killed mid-write, and two processes rendering the same key at once; the
key is the scene's physics, not its name; an entry is checked against its schema
(types, sizes, the digest over its JSON) and an invalid one is re-rendered with a
one-line warning; writes leave no temporary files. All renders are tiny (16 x 16
camera and map, 2^14 photons, 2 seeds); the schema checks share one rendered entry.

Kind: regression locks of the cache's contract (no accuracy is measured here)."""

from __future__ import annotations

import dataclasses
import json
import os
import shutil
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from renderers.exr import write_exr
from renderers.mitsuba import cache, mitsuba_versions
from renderers.mitsuba.cache import (
    InvalidCacheEntryWarning,
    cache_key,
    load_entry,
    read_result_dir,
    write_result_dir,
)
from renderers.mitsuba.reference import render_reference
from renderers.store import document_digest, file_sha256
from scenes import load_scene, parse_scene

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
    # The K seeds' own maps travel too, and are what the mean and variance came from.
    seeds = second.receivers[0].seed_maps
    np.testing.assert_array_equal(first.receivers[0].seed_maps, seeds)
    assert seeds.shape == (2, 16, 16, 3)
    np.testing.assert_allclose(seeds.mean(axis=0), second.receivers[0].irradiance,
                               rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(seeds.var(axis=0, ddof=1) / 2, second.receivers[0].variance,
                               rtol=1e-4, atol=1e-9)
    assert second.metadata["photons"] == first.metadata["photons"]
    assert second.metadata["event_chains"] == ["L D", "L T T D (objects[0])"]


def _temporaries(root: Path) -> list[str]:
    """Everything in the cache folder that is neither an entry nor a lock file."""
    return sorted(p.name for p in root.rglob("*")
                  if p.name.startswith(".") or ".tmp" in p.name)


def test_truncated_exr_is_detected_and_rerendered(tiny, tmp_path):
    root = tmp_path / "c"
    render_reference(tiny, cache=root, progress=False)
    key = cache_key(tiny, mitsuba_versions())
    exr = root / key / "receiver_irradiance.exr"
    exr.write_bytes(exr.read_bytes()[: exr.stat().st_size // 2])
    with pytest.warns(InvalidCacheEntryWarning):
        result, why = load_entry(root, key)
    assert result is None and why.startswith("invalid")
    with pytest.warns(InvalidCacheEntryWarning):
        again = render_reference(tiny, cache=root, progress=False)
    assert again.metadata["cache"].startswith("miss (invalid")
    assert load_entry(root, key)[1] == "hit"


def test_corrupt_sidecar_is_detected_and_rerendered(tiny, tmp_path):
    """Unparsable JSON: a miss with one warning line naming the file, then a
    re-render that replaces the entry whole (nothing of the old one, nothing
    temporary, is left)."""
    root = tmp_path / "c"
    render_reference(tiny, cache=root, progress=False)
    key = cache_key(tiny, mitsuba_versions())
    (root / key / "result.json").write_text("{not json")
    (root / key / "receiver_irradiance_1.exr").write_bytes(b"left by an older entry")
    with pytest.warns(InvalidCacheEntryWarning) as caught:
        assert load_entry(root, key)[0] is None
    message = str(caught[0].message)
    assert "\n" not in message and "result.json" in message and "unreadable" in message
    with pytest.warns(InvalidCacheEntryWarning):
        result = render_reference(tiny, cache=root, progress=False)
    assert result.metadata["cache"].startswith("miss (invalid")
    document = json.loads((root / key / "result.json").read_text())
    assert document["hash"] == key
    assert sorted(p.name for p in (root / key).iterdir()) == [
        "camera.exr", "receiver_irradiance.exr", "result.json"]
    assert _temporaries(root) == []


def test_writer_killed_mid_write_leaves_a_miss_not_a_corrupt_hit(tiny, tmp_path):
    """A child process renders, writes its first EXR, then is SIGKILLed before the
    sidecar exists. The entry must read as a miss (the files are still in the
    writer's temporary folder, never in the entry), the lock must be free, a new
    render must succeed, and the next write removes the dead writer's folder once
    it is older than STALE_AFTER."""
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
    key = cache_key(tiny, mitsuba_versions())
    assert not (root / key).exists()
    leftovers = [p for p in root.iterdir() if p.name.startswith(f".{key}.tmp-")]
    assert len(leftovers) == 1 and (leftovers[0] / "camera.exr").exists()
    assert load_entry(root, key) == (None, "absent")
    again = render_reference(tiny, cache=root, progress=False)  # would hang on a stuck lock
    assert again.metadata["cache"] == "miss (absent)"
    assert load_entry(root, key)[1] == "hit"
    assert leftovers[0].exists()  # young: it might belong to a live writer
    old = time.time() - cache.STALE_AFTER - 60
    os.utime(leftovers[0], (old, old))
    write_result_dir(root / key, again)
    assert not leftovers[0].exists()
    assert _temporaries(root) == []
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
    assert load_entry(root, cache_key(tiny, mitsuba_versions()))[1] == "hit"


# ------------------------------------------------------------------ the key


def _renamed(scene, name: str, description: str):
    return dataclasses.replace(scene, info=dataclasses.replace(
        scene.info, name=name, description=description))


def test_renaming_a_scene_hits_its_cached_reference(tiny, tmp_path):
    """The key is the physics: a new name and description find the same entry; a
    change of the light (or of the camera the reference renders) does not."""
    root = tmp_path / "c"
    render_reference(tiny, cache=root, progress=False)
    renamed = _renamed(tiny, "tiny_renamed", "the same scene under another name")
    assert cache_key(renamed, mitsuba_versions()) == cache_key(tiny, mitsuba_versions())
    assert render_reference(renamed, cache=root, progress=False).metadata["cache"] == "hit"
    brighter = parse_scene(TINY.replace("irradiance = [3.0, 3.0, 3.0]",
                                        "irradiance = [3.0, 3.0, 3.5]"))
    wider = parse_scene(TINY.replace("fov = 40.0", "fov = 41.0"))
    for other in (brighter, wider):
        assert cache_key(other, mitsuba_versions()) != cache_key(tiny, mitsuba_versions())


def test_a_mesh_keys_by_its_content_not_by_where_it_lies(tmp_path):
    """The same scene and mesh in two folders (two checkouts) share one key; a mesh
    with one vertex moved does not (before, the mesh's absolute path entered the
    key, and every checkout rendered its own reference of a mesh scene)."""
    root = Path(__file__).resolve().parents[3] / "scenes"
    keys = {}
    for name in ("a", "b", "moved"):
        folder = tmp_path / name
        (folder / "meshes").mkdir(parents=True)
        shutil.copy(root / "bowl_sun.toml", folder / "bowl_sun.toml")
        text = (root / "meshes" / "bowl.obj").read_text()
        if name == "moved":
            text = text.replace("v 1.000000 0.000000 0.000000", "v 1.000000 0.000000 0.010000", 1)
        (folder / "meshes" / "bowl.obj").write_text(text)
        keys[name] = cache_key(load_scene(folder / "bowl_sun.toml"), mitsuba_versions())
    assert keys["a"] == keys["b"]
    assert keys["moved"] != keys["a"]


# ------------------------------------------------------------ schema of an entry


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    """(root, key) of one rendered entry, rendered once for the schema tests."""
    folder = tmp_path_factory.mktemp("cache_template")
    (folder / "tiny.toml").write_text(TINY)
    scene = load_scene(folder / "tiny.toml")
    render_reference(scene, cache=folder / "c", progress=False)
    return folder / "c", cache_key(scene, mitsuba_versions())


@pytest.fixture
def entry(rendered, tmp_path):
    """A private copy of the rendered entry: (root, key, entry folder)."""
    root, key = rendered
    shutil.copytree(root / key, tmp_path / "c" / key)
    return tmp_path / "c", key, tmp_path / "c" / key


def _rewrite(folder: Path, edit, *, fix_digest: bool) -> None:
    """Edit result.json; with ``fix_digest`` also re-sign it (as a buggy writer
    would), so only the schema can catch the edit."""
    path = folder / "result.json"
    document = json.loads(path.read_text())
    edit(document)
    if fix_digest:
        document["document_sha256"] = document_digest(document)
    path.write_text(json.dumps(document, indent=2, sort_keys=True))


def _invalid(root: Path, key: str) -> str:
    with pytest.warns(InvalidCacheEntryWarning) as caught:
        result, why = load_entry(root, key)
    assert result is None and why.startswith("invalid: ")
    assert len(caught) == 1 and "\n" not in str(caught[0].message)
    return why


def test_the_written_entry_records_sizes_and_its_own_digest(entry):
    root, key, folder = entry
    document = json.loads((folder / "result.json").read_text())
    assert document["shapes"] == {"camera.exr": [16, 16], "receiver_irradiance.exr": [16, 16]}
    assert document["document_sha256"] == document_digest(document)
    assert load_entry(root, key)[1] == "hit"


def test_an_edited_json_value_is_a_miss(entry):
    """Content covered by the digest: a hand edit with the right type is caught."""
    root, key, folder = entry
    _rewrite(folder, lambda d: d.update(photons=d["photons"] + 1), fix_digest=False)
    assert "does not match its recorded SHA-256" in _invalid(root, key)


@pytest.mark.parametrize(("edit", "message"), [
    (lambda d: d.update(photons="many"), "'photons' has the wrong type"),
    (lambda d: d.update(photons=True), "'photons' has the wrong type"),
    (lambda d: d.update(timings=[1.0]), "'timings' has the wrong type"),
    (lambda d: d.update(receiver_extent=[[2.0, -2.0, -2.0, 2.0]]), "receiver_extent[0]"),
    (lambda d: d.pop("shapes"), "no 'shapes'"),
    (lambda d: d["shapes"].update({"camera.exr": [16]}), "shapes['camera.exr']"),
    (lambda d: d["files"].update({"../elsewhere.exr": "0" * 64}), "must list exactly"),
    (lambda d: d["files"].update({"camera.exr": "not a digest"}), "is not a SHA-256"),
])
def test_a_wrongly_typed_json_is_a_miss(entry, edit, message):
    """Schema, even where the digest was re-signed: wrong types and shapes miss."""
    root, key, folder = entry
    _rewrite(folder, edit, fix_digest=True)
    assert message in _invalid(root, key)


def test_a_json_array_instead_of_an_object_is_a_miss(entry):
    root, key, folder = entry
    (folder / "result.json").write_text("[1, 2, 3]")
    assert "not a JSON object" in _invalid(root, key)


def test_unknown_extra_keys_are_allowed_and_kept(entry):
    """Other metadata may be added by newer writers: a signed extra key still hits."""
    root, key, folder = entry
    _rewrite(folder, lambda d: d.update(provenance={"host": "x"}), fix_digest=True)
    result, why = load_entry(root, key)
    assert why == "hit" and result.metadata["provenance"] == {"host": "x"}


def test_a_missing_exr_is_a_miss(entry):
    root, key, folder = entry
    (folder / "receiver_irradiance.exr").unlink()
    assert "missing or does not match" in _invalid(root, key)


def test_an_exr_of_the_wrong_size_is_a_miss(entry):
    """A well-formed EXR with its SHA-256 recorded, but not the size the entry says."""
    root, key, folder = entry
    exr = folder / "receiver_irradiance.exr"
    write_exr(exr, {"RGB": np.zeros((8, 8, 3), np.float32)})
    digest = file_sha256(exr)
    _rewrite(folder, lambda d: d["files"].update({"receiver_irradiance.exr": digest}),
             fix_digest=True)
    assert "layer RGB is (8, 8, 3), expected (16, 16, 3)" in _invalid(root, key)


def test_per_seed_layers_with_a_gap_are_a_miss(entry):
    """Per-seed layers must be seed0 … seed(K-1): an EXR holding seed0 and seed2 is
    refused (its SHA-256 re-recorded, so only the layer check can catch it)."""
    root, key, folder = entry
    exr = folder / "receiver_irradiance.exr"
    zeros = np.zeros((16, 16, 3), np.float32)
    write_exr(exr, {"RGB": zeros, "variance": zeros, "seed0": zeros, "seed2": zeros})
    digest = file_sha256(exr)
    _rewrite(folder, lambda d: d["files"].update({"receiver_irradiance.exr": digest}),
             fix_digest=True)
    assert "per-seed layers ['seed0', 'seed2']" in _invalid(root, key)


def test_an_entry_under_another_key_is_a_miss(entry):
    root, _, folder = entry
    other = "0" * 64
    folder.rename(root / other)
    assert "stored under another key" in _invalid(root, other)


def test_an_empty_entry_folder_is_a_miss(tmp_path):
    (tmp_path / "c" / "k").mkdir(parents=True)
    with pytest.raises(cache.CacheEntryError, match=r"result\.json: unreadable"):
        read_result_dir(tmp_path / "c" / "k")
    assert "unreadable" in _invalid(tmp_path / "c", "k")


# ---------------------------------------------------------------- writing


def test_a_write_that_raises_midway_leaves_no_files(tiny, tmp_path, monkeypatch):
    """A writer failing after its first EXR (disk full, interrupt) removes its
    temporary folder: no entry, no temporary file, and the next call renders."""
    root = tmp_path / "c"
    real, calls = cache.write_exr, []

    def failing(path, layers):
        calls.append(path)
        if len(calls) == 2:
            raise KeyboardInterrupt
        real(path, layers)

    monkeypatch.setattr(cache, "write_exr", failing)
    with pytest.raises(KeyboardInterrupt):
        render_reference(tiny, cache=root, progress=False)
    key = cache_key(tiny, mitsuba_versions())
    assert len(calls) == 2 and not (root / key).exists()
    assert sorted(p.name for p in root.iterdir()) == [f"{key}.lock"]
    monkeypatch.setattr(cache, "write_exr", real)
    assert render_reference(tiny, cache=root, progress=False).metadata["cache"] == "miss (absent)"


def test_stale_temporary_folders_are_removed_and_young_ones_kept(rendered, tmp_path):
    """Folders a killed writer left (older than STALE_AFTER) go on the next write;
    a young one may be a live writer's and stays."""
    root, key = rendered
    result = read_result_dir(root / key)
    target = tmp_path / "c"
    target.mkdir()
    stale, young = target / ".dead.tmp-abcdefgh", target / ".alive.tmp-abcdefgh"
    for folder in (stale, young):
        folder.mkdir()
        (folder / "camera.exr").write_bytes(b"half")
    old = time.time() - cache.STALE_AFTER - 60
    os.utime(stale, (old, old))
    write_result_dir(target / key, result)
    assert not stale.exists() and young.exists()
    assert load_entry(target, key)[1] == "hit"


def test_entry_files_get_the_default_mode(rendered, tmp_path):
    """EXRs, the JSON and the entry folder get the modes a plain open() / mkdir()
    give under the umask (mkstemp / mkdtemp alone would leave 0600 / 0700)."""
    root, key = rendered
    result = read_result_dir(root / key)
    previous = os.umask(0o022)
    try:
        write_result_dir(tmp_path / "out", result)
        (tmp_path / "plain").write_bytes(b"")
        (tmp_path / "plain_dir").mkdir()
    finally:
        os.umask(previous)
    mode = (tmp_path / "plain").stat().st_mode & 0o777
    assert mode == 0o644
    for name in ("camera.exr", "receiver_irradiance.exr", "result.json"):
        assert (tmp_path / "out" / name).stat().st_mode & 0o777 == mode, name
    folder_mode = (tmp_path / "plain_dir").stat().st_mode & 0o777
    assert (tmp_path / "out").stat().st_mode & 0o777 == folder_mode


def test_writing_into_a_folder_with_other_files_keeps_them(rendered, tmp_path):
    """``caustics reference -o DIR`` into a folder holding other things: the result
    files are moved in (JSON last), nothing else is touched, nothing is left over."""
    root, key = rendered
    result = read_result_dir(root / key)
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    write_result_dir(out, result)
    assert (out / "notes.txt").read_text() == "mine"
    assert read_result_dir(out).receivers[0].irradiance.shape == (16, 16, 3)
    assert _temporaries(tmp_path) == []
