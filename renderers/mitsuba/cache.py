"""Content-addressed cache of Mitsuba references, and the result-directory format.

A result directory holds ``camera.exr``, ``receiver_irradiance.exr`` (receiver 0),
``receiver_irradiance_1.exr``, ... (further receivers), each with an ``RGB`` layer
(mean) and a ``variance`` layer (variance of the mean over K seeds), the receivers'
also with the K seeds' own maps (layers ``seed0`` … ``seed{K-1}``), and
``result.json``: the metadata, the SHA-256 and (H, W) of every EXR (``files``,
``shapes``), and ``document_sha256``, the SHA-256 of the rest of the JSON itself
(canonical form: keys sorted, no whitespace), so the manifest covers the JSON as
well as the images.

A result directory is an entry of the content-addressed store
(:mod:`renderers.store`, ``result.json`` its manifest), which writes and verifies it.

Writing: everything goes into a fresh temporary folder beside the target
(``.NAME.tmp-XXXXXXXX``), which is renamed into place in one step; an existing
folder holding only result files (a cache entry being replaced) is swapped out
whole, any other folder (``caustics reference -o DIR``) has the files moved in with
``result.json`` last. A writer that raises removes its temporary folder; one that is
killed leaves it behind, and the next write beside it removes temporary folders
older than :data:`STALE_AFTER`.

Reading checks the entry against its schema (:func:`read_result_dir`): the JSON
parses, its digest matches, the known keys have their types (unknown extra keys
are allowed), every EXR is present with its recorded SHA-256 and size (files other
than the listed ones may sit beside them in a ``-o`` folder). Anything else
(truncated EXR, killed writer, garbage, a hand-edited JSON) is a miss:
:func:`load_entry` says why, warns in one line, and the caller re-renders.

The key is the SHA-256 of the scene's physics: its fields less its file path and
its name and description (renaming a scene re-uses its reference), only the
reference's own settings (:data:`REFERENCE_SETTINGS`), the bytes of every mesh
both renderers get, Mitsuba and Dr.Jit versions and variant, the camera integrator
(:data:`CAMERA_INTEGRATORS`: the camera tracer or ptracer) and :data:`FORMAT_VERSION`.
An entry whose recorded ``camera_integrator`` is not the one asked for is a miss too
(:func:`load_entry`), so the two camera images never stand in for each other. Two
processes rendering the same key serialise on an exclusive ``fcntl`` lock on
``KEY.lock``; the second finds the first's entry.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
import re
import warnings
from pathlib import Path

import numpy as np

from renderers.exr import ExrError, read_exr, write_exr
from renderers.results import ReceiverMap, RenderResult
from renderers.store import STALE_AFTER, StoreError, entry_lock, read_entry, write_entry
from scenes.errors import HarnessError
from scenes.geometry import build_geometry
from scenes.model import Scene

__all__ = ["CACHE_ENV", "CAMERA_INTEGRATORS", "FORMAT_VERSION", "STALE_AFTER", "CacheEntryError",
           "CameraIntegratorError", "InvalidCacheEntryWarning", "cache_dir", "cache_key",
           "check_camera", "entry_lock", "load_entry", "read_result_dir", "receiver_file_name",
           "write_result_dir"]

#: Bump when the renderer's output or the directory format changes meaning.
#: 2: receiver maps hold caustic irradiance only; 3: traced with caustic-only
#: emission (every photon aimed at the caustic objects), stratified lanes and
#: TEA-hashed PCG32 seeding (same expectation, new samples, less noise); 4: all-paths
#: mode follows paths up to a 64-event safety cap (was 8) and records the cut flux;
#: 5: the key leaves out the scene's name and description, result.json records each
#: EXR's size and its own digest (``shapes``, ``document_sha256``); 6: the camera image
#: is the camera tracer's by default (``camera_integrator``, part of the key); 7: a
#: photon drawn on its emission cone's or disk's edge no longer gets an infinite weight;
#: 8: every launch stratified at its own size (Morton-curve strata), the default budget
#: two whole launches, the noise per RGB channel over the comparison's caustic region
#: with launches past the budget until the target (``relative_noise_per_channel``,
#: ``reference_time_cap``, ``stopped_by`` ``time_cap``), and all-paths mode plays
#: Russian roulette past 64 events up to a 4096-event safety cap; 9: each receiver EXR
#: also holds the K seeds' own maps (layers ``seed0`` … ``seed{K-1}``); 10: a photon
#: whose last segment leaked through a mesh edge is not deposited
#: (``photons.PhotonTracer._leaked``)
FORMAT_VERSION = 10
RESULT_JSON = "result.json"
#: Camera integrators of the reference (``render_reference(camera=...)``), and the name
#: each records as ``camera_integrator`` in its metadata.
CAMERA_INTEGRATORS = {"trace": "camera_trace", "ptracer": "ptracer"}
#: Fields of ``[scene]`` that name or describe the scene but do not change its light.
NON_PHYSICAL = ("name", "description")


class CacheEntryError(ExrError, StoreError):
    """A result directory or cache entry is incomplete or fails its schema."""


class CameraIntegratorError(HarnessError, ValueError):
    """A camera integrator that is not one of :data:`CAMERA_INTEGRATORS`."""


def check_camera(camera: str) -> str:
    """``camera`` if it names a camera integrator, else :class:`CameraIntegratorError`."""
    if camera not in CAMERA_INTEGRATORS:
        raise CameraIntegratorError(f"camera integrator {camera!r}: expected one of "
                                    f"{', '.join(sorted(CAMERA_INTEGRATORS))}")
    return camera


class InvalidCacheEntryWarning(UserWarning):
    """A cache entry was invalid (corrupt, incomplete, edited) and is re-rendered."""


#: The environment variable naming the cache root.
CACHE_ENV = "CAUSTICS_CACHE_DIR"


def cache_dir(override: str | Path | None = None) -> Path:
    """``override``, else ``$CAUSTICS_CACHE_DIR``, else ~/.cache/caustics-harness/reference."""
    if override is not None:
        return Path(override)
    env = os.environ.get(CACHE_ENV)
    if env:
        return Path(env)
    return Path.home() / ".cache" / "caustics-harness" / "reference"


def _jsonable(value):
    """A dataclass tree as JSON values, without its file paths (fields declared with
    ``path=True``): where a file lives is not physics, and what it holds enters the
    key as the bytes of the meshes built from it (:func:`cache_key`)."""
    if dataclasses.is_dataclass(value):
        return {"_type": type(value).__name__,
                **{f.name: _jsonable(getattr(value, f.name)) for f in dataclasses.fields(value)
                   if not f.metadata.get("path")}}
    if isinstance(value, (tuple, list)):
        return [_jsonable(v) for v in value]
    return value


#: The settings the reference depends on; the method's (grid, preset, estimator, ...)
#: do not enter its key, so every method and setting of a scene shares one reference.
REFERENCE_SETTINGS = ("receiver_map", "photons", "spp", "seed", "seeds", "target_noise",
                      "all_specular_paths")


def cache_key(scene: Scene, versions: dict[str, str], *, camera: str = "trace") -> str:
    """Hex SHA-256 naming the reference of ``scene`` under these versions.

    The scene's physics only: its fields without file paths (the scene's, its
    meshes' and height arrays') and without
    ``[scene]`` :data:`NON_PHYSICAL` (name, description), with only
    :data:`REFERENCE_SETTINGS` of its settings, and the bytes of every mesh; and
    ``camera``, the camera integrator (a key of :data:`CAMERA_INTEGRATORS`).
    """
    check_camera(camera)
    fields = _jsonable(dataclasses.replace(scene, source=""))
    for name in NON_PHYSICAL:
        fields["info"].pop(name, None)
    # ``[animation]`` says how the scene moves over a sequence; a reference renders one
    # frame, whose physics is the scene itself (``scenes.animation``): keys unchanged.
    fields.pop("animation", None)
    fields["settings"] = {k: fields["settings"][k] for k in REFERENCE_SETTINGS}
    digest = hashlib.sha256()
    digest.update(json.dumps({"scene": fields, "versions": versions, "format": FORMAT_VERSION,
                              "camera": CAMERA_INTEGRATORS[camera]}, sort_keys=True).encode())
    geometry = build_geometry(scene)
    for mesh in [r.mesh for r in geometry.receivers] + [o.mesh for o in geometry.objects]:
        for arr in (mesh.positions, mesh.normals, mesh.faces, mesh.uvs):
            if arr is not None:
                digest.update(np.ascontiguousarray(arr).tobytes())
    return digest.hexdigest()


def receiver_file_name(index: int) -> str:
    """``receiver_irradiance.exr`` for receiver 0, ``receiver_irradiance_I.exr`` after."""
    return "receiver_irradiance.exr" if index == 0 else f"receiver_irradiance_{index}.exr"


# ------------------------------------------------------------------------- writing


#: Files a result directory may hold: the EXRs, the JSON, and the temporary files
#: of their atomic writes (``.camera.exr.XXXX.exr``, ``.result.json.XXXX.tmp``).
_RESULT_FILE = re.compile(r"\.?(camera|receiver_irradiance(_\d+)?)\.exr(\..+\.exr)?"
                          r"|\.?result\.json(\..+\.tmp)?")


def _only_result_files(directory: Path) -> bool:
    """Whether ``directory`` holds nothing but result-directory files (a cache
    entry), so replacing it whole loses nothing of anyone's."""
    return all(_RESULT_FILE.fullmatch(p.name) and p.is_file() for p in directory.iterdir())


def write_result_dir(directory: str | Path, result: RenderResult,
                     camera_variance: np.ndarray | None = None) -> dict:
    """Write a result directory atomically; return the JSON document.

    The EXRs and ``result.json`` are written into a temporary folder beside
    ``directory`` and moved into place at the end (see the module docstring);
    temporary folders left there by killed writers, older than
    :data:`STALE_AFTER`, are removed first.
    """
    def fill(staging: Path) -> dict:
        shapes = {}
        cam_layers = {"RGB": result.camera}
        variance = (result.metadata.get("camera_variance") if camera_variance is None
                    else camera_variance)
        if variance is not None:
            cam_layers["variance"] = variance
        layers_of = {"camera.exr": cam_layers}
        for i, rmap in enumerate(result.receivers):
            layers = {"RGB": rmap.irradiance}
            if rmap.variance is not None:
                layers["variance"] = rmap.variance
            if rmap.seed_maps is not None:
                layers.update({f"seed{k}": m for k, m in enumerate(rmap.seed_maps)})
            layers_of[receiver_file_name(i)] = layers
        for name, layers in layers_of.items():
            write_exr(staging / name, layers)
            shapes[name] = [int(n) for n in layers["RGB"].shape[:2]]
        # Arrays (the camera variance) live in the EXRs, not the JSON.
        document = {k: v for k, v in result.metadata.items() if not isinstance(v, np.ndarray)}
        document.update({
            "renderer": result.renderer,
            "effects": list(result.effects),
            "timings": result.timings,
            "timer": result.timer,
            "receiver_extent": [list(r.extent) for r in result.receivers],
            "shapes": shapes,
        })
        return document

    return write_entry(directory, fill, manifest=RESULT_JSON, replace_whole=_only_result_files)


# ------------------------------------------------------------------------- reading

_SHA256 = re.compile(r"[0-9a-f]{64}")
_EXR_NAME = re.compile(r"(camera|receiver_irradiance(_[1-9]\d*)?)\.exr")


def _is_int(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _is_number_or_null(value) -> bool:
    return value is None or _is_number(value)


def _is_str_list(value) -> bool:
    return isinstance(value, list) and all(isinstance(v, str) for v in value)


def _is_timings(value) -> bool:
    return isinstance(value, dict) and all(_is_number_or_null(v) for v in value.values())


#: Keys every result.json has, and the test each value passes.
_REQUIRED = {
    "renderer": lambda v: isinstance(v, str),
    "effects": _is_str_list,
    "timings": _is_timings,
    "timer": lambda v: isinstance(v, str),
    "receiver_extent": lambda v: isinstance(v, list) and len(v) >= 1,
    "files": lambda v: isinstance(v, dict),
    "shapes": lambda v: isinstance(v, dict),
    "document_sha256": lambda v: isinstance(v, str),
}
#: Keys the reference writes and its readers use, checked when present; any other
#: key is allowed and passed through as metadata.
_OPTIONAL = {
    "hash": lambda v: isinstance(v, str),
    "variant": lambda v: isinstance(v, str),
    "versions": lambda v: isinstance(v, dict),
    "photons": _is_int,
    "photon_budget": _is_int,
    "channel_passes": _is_int,
    "spp": _is_int,
    "seed": _is_int,
    "seeds": _is_int,
    "relative_noise": _is_number_or_null,
    "relative_noise_per_channel": lambda v: v is None or (
        isinstance(v, list) and len(v) == 3 and all(_is_number_or_null(x) for x in v)),
    "noise_region_texels": lambda v: v is None or (
        isinstance(v, list) and all(_is_int(x) for x in v)),
    "target_noise": _is_number_or_null,
    "reference_time_cap": _is_number_or_null,
    "roulette_from": _is_int,
    "roulette_survival": _is_number_or_null,
    "stopped_by": lambda v: isinstance(v, str),
    "noise_history": lambda v: isinstance(v, list) and all(
        isinstance(row, list) and len(row) == 3 and all(_is_number_or_null(x) for x in row)
        for row in v),
    "event_chains": _is_str_list,
    "cut_flux_fraction": _is_number_or_null,
    "max_specular_events": _is_int,
    "camera_max_depth": _is_int,
    "camera_integrator": lambda v: isinstance(v, str),
    "camera_limits": _is_str_list,
    "camera_lookup": lambda v: isinstance(v, dict),
    "scene": lambda v: isinstance(v, str),
}


def _check_document(document: dict, path: Path) -> None:
    """Raise :class:`CacheEntryError` unless ``document`` (a JSON object whose digest
    the store has checked) fits the schema."""
    def bad(message: str) -> CacheEntryError:
        return CacheEntryError(f"{path}: {message}")

    for key, test in _REQUIRED.items():
        if key not in document:
            raise bad(f"no {key!r}")
        if not test(document[key]):
            raise bad(f"{key!r} has the wrong type or shape")
    for key, test in _OPTIONAL.items():
        if key in document and not test(document[key]):
            raise bad(f"{key!r} has the wrong type or shape")
    for i, extent in enumerate(document["receiver_extent"]):
        if not (isinstance(extent, list) and len(extent) == 4
                and all(_is_number(x) and math.isfinite(x) for x in extent)
                and extent[0] < extent[1] and extent[2] < extent[3]):
            raise bad(f"receiver_extent[{i}] is not (umin < umax, vmin < vmax)")
    expected = {"camera.exr"} | {receiver_file_name(i)
                                 for i in range(len(document["receiver_extent"]))}
    files, shapes = document["files"], document["shapes"]
    if set(files) != expected or set(shapes) != expected:
        raise bad(f"files and shapes must list exactly {sorted(expected)}")
    for name in sorted(expected):
        if not (isinstance(files[name], str) and _SHA256.fullmatch(files[name])):
            raise bad(f"files[{name!r}] is not a SHA-256")
        shape = shapes[name]
        if not (isinstance(shape, list) and len(shape) == 2
                and all(_is_int(n) and n >= 1 for n in shape)):
            raise bad(f"shapes[{name!r}] is not [height, width]")


def _seed_layers(layers: dict) -> list[str]:
    """The per-seed layers' names, ``seed0``, ``seed1``, … in seed order."""
    return sorted((n for n in layers if re.fullmatch(r"seed\d+", n)), key=lambda n: int(n[4:]))


def _check_layers(layers: dict, shape: list[int], path: Path) -> None:
    """The EXR holds an (H, W, 3) ``RGB`` layer and, if any, a same-sized variance and
    per-seed layers ``seed0`` … ``seed{K-1}`` (none, or K >= 2 without a gap)."""
    want = (*shape, 3)
    seeds = _seed_layers(layers)
    for name in ("RGB", "variance", *seeds):
        if name == "RGB" and name not in layers:
            raise CacheEntryError(f"{path}: no RGB layer")
        if name in layers and layers[name].shape != want:
            raise CacheEntryError(f"{path}: layer {name} is {layers[name].shape}, "
                                  f"expected {want}")
    if seeds and (len(seeds) < 2 or seeds != [f"seed{k}" for k in range(len(seeds))]):
        raise CacheEntryError(f"{path}: per-seed layers {seeds} are not seed0 … seed(K-1), "
                              f"K >= 2")


def read_result_dir(directory: str | Path) -> RenderResult:
    """Read and verify a result directory against its schema.

    Raises
    ------
    ExrError
        (:class:`CacheEntryError` for the directory's own checks) missing,
        unparsable or mistyped ``result.json``, JSON content that does not match
        its ``document_sha256``, a file missing or not matching its recorded
        SHA-256 or size, or an unreadable EXR.
    """
    directory = Path(directory)
    try:
        # Files beside the listed ones are allowed: a ``-o`` folder may hold others.
        document = read_entry(directory, manifest=RESULT_JSON, exact=False,
                              check=_check_document)
    except CacheEntryError:
        raise
    except StoreError as error:
        raise CacheEntryError(str(error)) from None
    layers_of = {}
    for name in document["files"]:
        exr = directory / name
        layers_of[name] = read_exr(exr)
        _check_layers(layers_of[name], document["shapes"][name], exr)
    camera = layers_of["camera.exr"]
    receivers = []
    for i, extent in enumerate(document["receiver_extent"]):
        layers = layers_of[receiver_file_name(i)]
        seeds = _seed_layers(layers)
        receivers.append(ReceiverMap(layers["RGB"], tuple(extent), layers.get("variance"),
                                     np.stack([layers[n] for n in seeds]) if seeds else None))
    metadata = {k: v for k, v in document.items()
                if k not in ("renderer", "effects", "timings", "timer")}
    metadata["camera_variance"] = camera.get("variance")
    return RenderResult(
        renderer=document["renderer"], camera=camera["RGB"],
        receivers=tuple(receivers), effects=tuple(document["effects"]),
        timings=document["timings"], timer=document["timer"],
        metadata=metadata,
    )


def load_entry(root: Path, key: str, *, camera: str | None = None
               ) -> tuple[RenderResult | None, str]:
    """The cached result for ``key`` and ``"hit"``, or None and why it missed.

    A missing entry is ``"absent"``; an entry that fails :func:`read_result_dir`, was
    stored under another key, or (``camera`` given, a key of
    :data:`CAMERA_INTEGRATORS`) records another camera integrator is
    ``"invalid: ..."`` and also warns (:class:`InvalidCacheEntryWarning`, one line),
    since the caller re-renders it and the new entry replaces it.
    """
    directory = root / key
    if not directory.exists():
        return None, "absent"
    try:
        result = read_result_dir(directory)
        if result.metadata.get("hash") != key:
            raise CacheEntryError(f"{directory}: stored under another key")
        recorded = result.metadata.get("camera_integrator")
        if camera is not None and recorded != CAMERA_INTEGRATORS[check_camera(camera)]:
            raise CacheEntryError(f"{directory}: camera image by {recorded}, expected "
                                  f"{CAMERA_INTEGRATORS[camera]}")
    except ExrError as error:
        reason = " ".join(str(error).split())  # one line, whatever the error held
        warnings.warn(f"invalid cached reference, re-rendering: {reason}",
                      InvalidCacheEntryWarning, stacklevel=2)
        return None, f"invalid: {reason}"
    return result, "hit"
