"""Content-addressed cache of Mitsuba references, and the result-directory format.

A result directory holds ``camera.exr``, ``receiver_irradiance.exr`` (receiver 0),
``receiver_irradiance_1.exr``, ... (further receivers), each with an ``RGB`` layer
(mean) and a ``variance`` layer (variance of the mean over K seeds), and
``result.json``: the metadata plus the SHA-256 of every EXR. The JSON is written
last and atomically, so an entry whose JSON parses and whose files match their
hashes is complete; anything else (truncated EXR, killed writer, garbage) is a
miss and is re-rendered.

The key is the SHA-256 of the scene's fields (less its file path), the bytes of
every mesh both renderers get, Mitsuba and Dr.Jit versions and variant, and
:data:`FORMAT_VERSION`. Two processes rendering the same key serialise on an
exclusive ``fcntl`` lock on ``KEY.lock``; the second finds the first's entry.
"""

from __future__ import annotations

import contextlib
import dataclasses
import fcntl
import hashlib
import json
import os
from pathlib import Path

import numpy as np

from renderers.exr import ExrError, read_exr, write_exr
from renderers.results import ReceiverMap, RenderResult
from scenes.files import atomic_write_bytes
from scenes.geometry import build_geometry
from scenes.model import Scene

__all__ = ["FORMAT_VERSION", "cache_dir", "cache_key", "entry_lock", "load_entry",
           "read_result_dir", "receiver_file_name", "write_result_dir"]

#: Bump when the renderer's output or the directory format changes meaning.
#: 2: receiver maps hold caustic irradiance only; 3: traced with caustic-only
#: emission (every photon aimed at the caustic objects), stratified lanes and
#: TEA-hashed PCG32 seeding (same expectation, new samples, less noise); 4: all-paths
#: mode follows paths up to a 64-event safety cap (was 8) and records the cut flux
FORMAT_VERSION = 4
RESULT_JSON = "result.json"


def cache_dir(override: str | Path | None = None) -> Path:
    """``override``, else ``$CAUSTICS_CACHE_DIR``, else ~/.cache/caustics-harness/reference."""
    if override is not None:
        return Path(override)
    env = os.environ.get("CAUSTICS_CACHE_DIR")
    if env:
        return Path(env)
    return Path.home() / ".cache" / "caustics-harness" / "reference"


def _jsonable(value):
    if dataclasses.is_dataclass(value):
        return {"_type": type(value).__name__,
                **{f.name: _jsonable(getattr(value, f.name)) for f in dataclasses.fields(value)}}
    if isinstance(value, (tuple, list)):
        return [_jsonable(v) for v in value]
    return value


#: The settings the reference depends on; the method's (grid, preset, estimator, ...)
#: do not enter its key, so every method and setting of a scene shares one reference.
REFERENCE_SETTINGS = ("receiver_map", "photons", "spp", "seed", "seeds", "target_noise",
                      "all_specular_paths")


def cache_key(scene: Scene, versions: dict[str, str]) -> str:
    """Hex SHA-256 naming the reference of ``scene`` under these versions: the scene
    (without its file path) with only :data:`REFERENCE_SETTINGS` of its settings."""
    fields = _jsonable(dataclasses.replace(scene, source=""))
    fields["settings"] = {k: fields["settings"][k] for k in REFERENCE_SETTINGS}
    digest = hashlib.sha256()
    digest.update(json.dumps({"scene": fields, "versions": versions,
                              "format": FORMAT_VERSION}, sort_keys=True).encode())
    geometry = build_geometry(scene)
    for mesh in [r.mesh for r in geometry.receivers] + [o.mesh for o in geometry.objects]:
        for arr in (mesh.positions, mesh.normals, mesh.faces, mesh.uvs):
            if arr is not None:
                digest.update(np.ascontiguousarray(arr).tobytes())
    return digest.hexdigest()


@contextlib.contextmanager
def entry_lock(root: Path, key: str):
    """Exclusive lock on one key (released on exit, or by the OS if we are killed)."""
    root.mkdir(parents=True, exist_ok=True)
    with open(root / f"{key}.lock", "a+b") as handle:
        fcntl.flock(handle.fileno(), fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle.fileno(), fcntl.LOCK_UN)


def receiver_file_name(index: int) -> str:
    """``receiver_irradiance.exr`` for receiver 0, ``receiver_irradiance_I.exr`` after."""
    return "receiver_irradiance.exr" if index == 0 else f"receiver_irradiance_{index}.exr"


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def write_result_dir(directory: str | Path, result: RenderResult,
                     camera_variance: np.ndarray | None = None) -> dict:
    """Write a result directory (EXRs first, then ``result.json``); return the JSON."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    files = {}
    cam_layers = {"RGB": result.camera}
    if camera_variance is None:
        camera_variance = result.metadata.get("camera_variance")
    if camera_variance is not None:
        cam_layers["variance"] = camera_variance
    write_exr(directory / "camera.exr", cam_layers)
    files["camera.exr"] = _sha256(directory / "camera.exr")
    for i, rmap in enumerate(result.receivers):
        name = receiver_file_name(i)
        layers = {"RGB": rmap.irradiance}
        if rmap.variance is not None:
            layers["variance"] = rmap.variance
        write_exr(directory / name, layers)
        files[name] = _sha256(directory / name)
    # Arrays (the camera variance) live in the EXRs, not the JSON.
    document = {k: v for k, v in result.metadata.items() if not isinstance(v, np.ndarray)}
    document.update({
        "renderer": result.renderer,
        "effects": list(result.effects),
        "timings": result.timings,
        "timer": result.timer,
        "receiver_extent": [list(r.extent) for r in result.receivers],
        "files": files,
    })
    atomic_write_bytes(directory / RESULT_JSON,
                       json.dumps(document, indent=2, sort_keys=True).encode())
    return document


def read_result_dir(directory: str | Path) -> RenderResult:
    """Read and verify a result directory.

    Raises
    ------
    ExrError
        Missing or unparsable ``result.json``, a file whose SHA-256 differs from
        the recorded one (truncated, replaced), or an unreadable EXR.
    """
    directory = Path(directory)
    try:
        document = json.loads((directory / RESULT_JSON).read_text())
        files = document["files"]
        extents = document["receiver_extent"]
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise ExrError(f"{directory / RESULT_JSON}: unreadable ({error})") from None
    for name, digest in files.items():
        path = directory / name
        if not path.is_file() or _sha256(path) != digest:
            raise ExrError(f"{path}: missing or does not match its recorded SHA-256")
    camera = read_exr(directory / "camera.exr")
    receivers = []
    for i, extent in enumerate(extents):
        layers = read_exr(directory / receiver_file_name(i))
        receivers.append(ReceiverMap(layers["RGB"], tuple(extent), layers.get("variance")))
    metadata = {k: v for k, v in document.items()
                if k not in ("renderer", "effects", "timings", "timer")}
    metadata["camera_variance"] = camera.get("variance")
    return RenderResult(
        renderer=document.get("renderer", "mitsuba"), camera=camera["RGB"],
        receivers=tuple(receivers), effects=tuple(document.get("effects", ())),
        timings=document.get("timings", {}), timer=document.get("timer", ""),
        metadata=metadata,
    )


def load_entry(root: Path, key: str) -> tuple[RenderResult | None, str]:
    """The cached result for ``key`` and ``"hit"``, or None and why it missed."""
    directory = root / key
    if not directory.exists():
        return None, "absent"
    try:
        result = read_result_dir(directory)
    except ExrError as error:
        return None, f"invalid: {error}"
    if result.metadata.get("hash") != key:
        return None, "invalid: key mismatch"
    return result, "hit"
