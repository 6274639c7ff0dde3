"""Golden references: small Mitsuba receiver maps committed with a manifest.

The default test run compares the caustics-mapping renderer against these instead
of re-rendering Mitsuba at high photon counts. Layout of the golden folder
(bundled: ``harness/checks/data/golden/``)::

    manifest.json            settings, versions, and per scene: photons, seeds,
                             seed, relative noise, and the SHA-256 of every file
    <scene>/receiver<i>.exr  RGB = mean caustic irradiance (W/m²), variance = the
                             variance of that mean over the K seeds

Every file is checked against its SHA-256 on load. ``regenerate`` renders into a
staging folder beside the golden one and swaps it in with renames, so a failed or
interrupted run leaves the committed references untouched.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from renderers.exr import read_exr, write_exr
from renderers.mitsuba._mi import versions
from renderers.mitsuba.reference import estimate_receivers
from renderers.results import ReceiverMap
from scenes import Scene, load_scene, with_settings
from scenes.errors import HarnessError
from scenes.files import atomic_write_bytes, dumps_strict

__all__ = ["GOLDEN_SCENES", "GOLDEN_SETTINGS", "GoldenError", "golden_scene", "load_golden",
           "read_manifest", "regenerate"]

FORMAT = 1
#: Paper scenes with golden references.
GOLDEN_SCENES = ("glass_sphere", "bunny", "colored_bunny", "dispersion_sphere", "water_pool",
                 "seabed", "metal_ring")
#: Settings of golden references and of the renders held against them: 64² maps, so
#: 4 M photons x 4 seeds give about 0.5 % relative noise per caustic texel.
GOLDEN_SETTINGS = {"receiver_map": [64, 64], "photons": 4_000_000, "seeds": 4, "seed": 1000}
#: Per-scene budgets where 4 M photons leave too much noise: the seabed's rock
#: receiver is small, so its texels catch few photons (7.6 % noise at 4 M).
GOLDEN_OVERRIDES = {"seabed": {"photons": 40_000_000}}


class GoldenError(HarnessError):
    """A golden reference is missing, altered (SHA-256 mismatch) or unreadable."""


@dataclass(frozen=True)
class Golden:
    """One scene's golden receiver maps and its manifest entry."""

    scene: str
    receivers: tuple[ReceiverMap, ...]
    entry: dict


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def golden_scene(scenes_dir: Path, name: str) -> Scene:
    """The committed scene ``name`` with :data:`GOLDEN_SETTINGS` (and its overrides)."""
    settings = {**GOLDEN_SETTINGS, **GOLDEN_OVERRIDES.get(name, {})}
    return with_settings(load_scene(Path(scenes_dir) / f"{name}.toml"), settings)


def read_manifest(golden_dir: Path) -> dict:
    """The manifest, or GoldenError naming the file."""
    path = Path(golden_dir) / "manifest.json"
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as error:
        raise GoldenError(f"{path}: unreadable manifest ({error})") from None
    if manifest.get("format") != FORMAT:
        raise GoldenError(f"{path}: format {manifest.get('format')!r}, expected {FORMAT}")
    return manifest


def load_golden(golden_dir: Path, name: str) -> Golden:
    """Receiver maps of scene ``name``, each file checked against its SHA-256."""
    golden_dir = Path(golden_dir)
    entry = read_manifest(golden_dir)["scenes"].get(name)
    if entry is None:
        raise GoldenError(f"{golden_dir}: no golden reference for {name}")
    receivers = []
    for i, extent in enumerate(entry["receiver_extent"]):
        rel = f"{name}/receiver{i}.exr"
        path = golden_dir / rel
        if not path.is_file():
            raise GoldenError(f"{path}: missing")
        digest = _sha256(path)
        if digest != entry["sha256"][rel]:
            raise GoldenError(f"{path}: SHA-256 {digest} does not match the manifest")
        layers = read_exr(path)
        receivers.append(ReceiverMap(layers["RGB"], tuple(extent), layers["variance"]))
    return Golden(name, tuple(receivers), entry)


def _render(scene: Scene, out: Path, rel_dir: str) -> dict:

    start = time.perf_counter()
    estimate = estimate_receivers(scene, target_noise=1e-12)  # spend the whole budget
    seconds = time.perf_counter() - start
    hashes = {}
    for i, rmap in enumerate(estimate.caustic):
        rel = f"{rel_dir}/receiver{i}.exr"
        write_exr(out / rel, {"RGB": rmap.irradiance, "variance": rmap.variance})
        hashes[rel] = _sha256(out / rel)
    s = scene.settings
    return {"photons": estimate.photons, "seeds": s.seeds, "seed": s.seed,
            "relative_noise": estimate.relative_noise, "seconds": seconds,
            "receiver_extent": [list(m.extent) for m in estimate.caustic],
            "resolution": list(s.receiver_map), "sha256": hashes, "versions": versions()}


def regenerate(golden_dir: Path, scenes_dir: Path, *, names=GOLDEN_SCENES,
               progress=print) -> dict:
    """Render every golden reference into a staging folder, then swap it in.

    Returns the new manifest. The old folder is kept as ``<dir>.old`` until the new
    one is in place, then removed.
    """
    golden_dir = Path(golden_dir)
    golden_dir.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{golden_dir.name}.staging-",
                                    dir=golden_dir.parent))
    try:
        scenes = {}
        for name in names:
            scene = golden_scene(scenes_dir, name)
            scenes[name] = _render(scene, staging, name)
            progress(f"{name}: {scenes[name]['photons']} photons x "
                     f"{scenes[name]['seeds']} seeds, relative noise "
                     f"{scenes[name]['relative_noise']:.4f}, {scenes[name]['seconds']:.1f} s")
        manifest = {"format": FORMAT, "settings": GOLDEN_SETTINGS,
                    "overrides": GOLDEN_OVERRIDES, "scenes": scenes,
                    "created": time.strftime("%Y-%m-%d")}
        atomic_write_bytes(staging / "manifest.json",
                           (dumps_strict(manifest, indent=2) + "\n").encode("utf-8"))
        os.chmod(staging, 0o755)
        old = golden_dir.with_name(golden_dir.name + ".old")
        if old.exists():
            shutil.rmtree(old)
        if golden_dir.exists():
            os.replace(golden_dir, old)
        os.replace(staging, golden_dir)
        if old.exists():
            shutil.rmtree(old)
        return manifest
    finally:
        if staging.exists():
            shutil.rmtree(staging)
