"""Golden references: Mitsuba receiver maps at 128², with per-texel variance, committed
with a SHA-256 manifest.

They serve two checks (see :mod:`harness.checks`):

* the photon tracer is held to them with a per-pixel Z-test (:mod:`harness.checks.ztest`,
  Mitsuba's render-test procedure): a fresh render on other seeds must agree texel
  by texel within the noise both carry;
* the regression locks of the caustics-mapping renderer are measured against them
  (:mod:`harness.checks.locks`), so the default test run needs no large reference render.

Layout of the golden folder (bundled: ``harness/checks/data/golden/``)::

    manifest.json            settings, versions, and per scene: photons per seed,
                             seeds, first seed, relative noise, the scale of each map,
                             each map's K per-seed totals ``seed_luminance`` (Σ over
                             the texels of the seed's luminance, W/m²: the flux
                             ratio's interval, since a stratified launch's total is far
                             less noisy than the sum of its texels' variances says)
                             and the SHA-256 of every file
    <scene>/receiver<i>.exr  half-float layers, both divided by the map's ``scale``:
                             RGB   = mean caustic irradiance E (W/m²)
                             sigma = standard error of that mean over the K seeds
    <scene>/region<i>.png    the scene's caustic region for receiver i (8-bit, 255
                             inside): ``scene_caustic_region`` of an *independent*
                             reference, :data:`REGION_SEEDS` seeds of the golden budget
                             from ``region_seed`` (disjoint from the golden's, the
                             locks' calibration and the Z-test's seeds), so that the
                             locks score the golden over texels its own noise did not
                             choose

Half floats keep the eight maps at about 400 KB: the rounding error of a stored value
is at most 2^-11 of it, and :func:`load_golden` adds its variance (ulp² / 12) to the
stored one, so the Z-test counts it. Values are divided by the map's largest value
before rounding, so nothing overflows and the dim texels keep ~1e-7 of the peak.

Every file is checked against its SHA-256 on load; a missing or unreadable manifest or
file is a :class:`GoldenError` that names the path. ``regenerate`` renders into a
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

import numpy as np
import OpenEXR
from PIL import Image

from harness.compare.regions import scene_caustic_region
from harness.compare.uncertainty import seed_luminance_totals
from renderers.exr import ExrError, read_exr
from renderers.mitsuba import mitsuba_versions
from renderers.mitsuba.reference import estimate_receivers
from renderers.results import ReceiverMap
from scenes import Scene, load_scene, with_settings
from scenes.errors import HarnessError
from scenes.files import atomic_write_bytes, dumps_strict

__all__ = ["FRESH_SEEDS", "GOLDEN_SCENES", "GOLDEN_SETTINGS", "REGION_SEEDS", "Golden",
           "GoldenError", "fresh_reference", "golden_scene", "load_golden", "read_manifest",
           "regenerate"]

FORMAT = 4
#: Paper scenes with golden references.
GOLDEN_SCENES = ("glass_sphere", "bunny", "colored_bunny", "dispersion_sphere", "water_pool",
                 "seabed", "metal_ring")
#: Settings of golden references and of the renders held against them: 128² maps,
#: 16 seeds of 4 M photons each, every photon aimed at the caustic objects
#: (``caustic_only``, as ``caustics compare`` renders its reference). The 16 seeds
#: give each texel's variance 15 degrees of freedom, so the Z-test's scale is known
#: to about ±37 % (2σ of a χ²₁₅ / 15) rather than ±100 % with 4 seeds.
GOLDEN_SETTINGS = {"receiver_map": [128, 128], "photons": 4_000_000, "seeds": 16,
                   "seed": 1000}
#: Per-scene budgets where 4 M photons per seed leave too much noise: the seabed's
#: rock receiver is small, so its texels catch few photons.
GOLDEN_OVERRIDES = {"seabed": {"photons": 40_000_000}}
#: Seeds of a fresh render held against a golden reference (the golden's budget per
#: seed, a quarter of its seeds): the golden carries 1/5 of the Z-test's variance.
FRESH_SEEDS = 4
#: The region's independent reference: this many seeds of the golden budget, from the
#: golden's first seed + :data:`REGION_SEED_OFFSET` (1500..1503 by default; the golden
#: takes 1000..1015, the locks' calibration 1016 on, the Z-test 1100..1103).
REGION_SEEDS = 4
REGION_SEED_OFFSET = 500


class GoldenError(HarnessError):
    """A golden reference is missing, altered (SHA-256 mismatch) or unreadable."""


@dataclass(frozen=True)
class Golden:
    """One scene's golden receiver maps (variance = that of the stored mean, rounding
    included), each receiver's caustic region (H, W) bool from the independent
    reference, each receiver's (K,) per-seed luminance totals (W/m² summed over the
    texels), and its manifest entry."""

    scene: str
    receivers: tuple[ReceiverMap, ...]
    entry: dict
    regions: tuple[np.ndarray, ...] = ()
    seed_luminance: tuple[np.ndarray, ...] = ()

    @property
    def photons(self) -> int:
        """Photons over all seeds."""
        return int(self.entry["photons"]) * int(self.entry["seeds"])


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def golden_scene(scenes_dir: Path, name: str) -> Scene:
    """The committed scene ``name`` with :data:`GOLDEN_SETTINGS` (and its overrides).

    Raises the loader's SceneError (naming the file) when the scene file is missing.
    """
    settings = {**GOLDEN_SETTINGS, **GOLDEN_OVERRIDES.get(name, {})}
    return with_settings(load_scene(Path(scenes_dir) / f"{name}.toml"), settings)


def read_manifest(golden_dir: Path) -> dict:
    """The manifest, or GoldenError naming the file."""
    path = Path(golden_dir) / "manifest.json"
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise GoldenError(f"{path}: unreadable manifest ({error})") from None
    if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
        found = manifest.get("format") if isinstance(manifest, dict) else None
        raise GoldenError(f"{path}: format {found!r}, expected {FORMAT}")
    if not isinstance(manifest.get("scenes"), dict):
        raise GoldenError(f"{path}: no 'scenes' table")
    return manifest


def _rounding_variance(stored: np.ndarray, scale: float) -> np.ndarray:
    """Variance of rounding to half floats: ulp² / 12 of each stored value."""
    ulp = np.spacing(np.abs(stored).astype(np.float16)).astype(np.float64)
    return (ulp * scale) ** 2 / 12.0


def load_golden(golden_dir: Path, name: str) -> Golden:
    """Receiver maps of scene ``name``, each file checked against its SHA-256."""
    golden_dir = Path(golden_dir)
    entry = read_manifest(golden_dir)["scenes"].get(name)
    if entry is None:
        raise GoldenError(f"{golden_dir / 'manifest.json'}: no golden reference for {name}")
    receivers, regions = [], []
    for i, (extent, scale) in enumerate(zip(entry["receiver_extent"], entry["scale"],
                                            strict=True)):
        path = _checked(golden_dir, entry, f"{name}/receiver{i}.exr")
        region = _checked(golden_dir, entry, f"{name}/region{i}.png")
        try:
            layers = read_exr(path)
            with Image.open(region) as image:
                regions.append(np.asarray(image.convert("L")) > 127)
        except (ExrError, OSError) as error:
            raise GoldenError(f"{error}") from None
        stored = layers["RGB"]
        variance = (layers["sigma"].astype(np.float64) * scale) ** 2 + _rounding_variance(
            stored, scale)
        receivers.append(ReceiverMap((stored.astype(np.float64) * scale).astype(np.float32),
                                     tuple(extent), variance.astype(np.float32)))
        if regions[-1].shape != stored.shape[:2]:
            raise GoldenError(f"{region}: {regions[-1].shape} texels, the map has "
                              f"{stored.shape[:2]}")
    return Golden(name, tuple(receivers), entry, tuple(regions),
                  _seed_luminance(golden_dir, name, entry, len(receivers)))


def _seed_luminance(golden_dir: Path, name: str, entry: dict, receivers: int):
    """The entry's per-seed luminance totals, K finite numbers per receiver, or
    GoldenError naming the manifest, the scene and the field."""
    totals = entry.get("seed_luminance")
    where = f"{golden_dir / 'manifest.json'}: {name}: seed_luminance"
    try:
        arrays = tuple(np.asarray(t, np.float64) for t in totals)
    except (TypeError, ValueError):
        raise GoldenError(f"{where}: missing or not lists of numbers") from None
    seeds = int(entry["seeds"])
    if len(arrays) != receivers or any(a.shape != (seeds,) or not np.isfinite(a).all()
                                       for a in arrays):
        raise GoldenError(f"{where}: expected {receivers} lists of {seeds} finite totals")
    return arrays


def _checked(golden_dir: Path, entry: dict, rel: str) -> Path:
    """``golden_dir / rel``, present and matching the manifest's SHA-256."""
    path = golden_dir / rel
    if not path.is_file():
        raise GoldenError(f"{path}: missing")
    digest = _sha256(path)
    if digest != entry["sha256"].get(rel):
        raise GoldenError(f"{path}: SHA-256 {digest} does not match the manifest")
    return path


def fresh_reference(scene: Scene, *, seed: int, seeds: int = FRESH_SEEDS):
    """The photon tracer's caustic maps of ``scene`` (golden settings) on ``seeds``
    seeds from ``seed``: what the Z-test holds against a golden reference. Returns
    ``(maps, photons over all seeds)``."""
    fresh = with_settings(scene, {"seed": seed, "seeds": seeds})
    estimate = estimate_receivers(fresh, target_noise=1e-12, caustic_only=True)
    return estimate.caustic, int(estimate.photons) * seeds


def _write_half(path: Path, irradiance: np.ndarray, variance: np.ndarray) -> float:
    """Write one golden map (see the module docstring); returns its scale."""
    scale = float(np.max(irradiance)) or 1.0
    layers = {"RGB": (irradiance / scale).astype(np.float16),
              "sigma": (np.sqrt(np.maximum(variance, 0.0)) / scale).astype(np.float16)}
    path.parent.mkdir(parents=True, exist_ok=True)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    OpenEXR.File(header, layers).write(str(path))
    os.chmod(path, 0o644)
    return scale


def _render(scene: Scene, out: Path, rel_dir: str) -> dict:
    start = time.perf_counter()
    # Spend the whole budget: no noise target stops it early.
    estimate = estimate_receivers(scene, target_noise=1e-12, caustic_only=True)
    seconds = time.perf_counter() - start
    hashes, scales = {}, []
    totals = []
    for i, rmap in enumerate(estimate.caustic):
        rel = f"{rel_dir}/receiver{i}.exr"
        scales.append(_write_half(out / rel, rmap.irradiance, rmap.variance))
        hashes[rel] = _sha256(out / rel)
        totals.append([float(x) for x in seed_luminance_totals(rmap.seed_maps)])
    s = scene.settings
    # The region from an independent reference (module docstring).
    region_seed = s.seed + REGION_SEED_OFFSET
    independent = estimate_receivers(
        with_settings(scene, {"seed": region_seed, "seeds": REGION_SEEDS}),
        target_noise=1e-12, caustic_only=True)
    for i, rmap in enumerate(independent.caustic):
        rel = f"{rel_dir}/region{i}.png"
        mask = scene_caustic_region(np.asarray(rmap.irradiance))
        Image.fromarray((mask * 255).astype(np.uint8), mode="L").save(out / rel)
        os.chmod(out / rel, 0o644)
        hashes[rel] = _sha256(out / rel)
    return {"photons": int(estimate.photons), "seeds": s.seeds, "seed": s.seed,
            "region_seed": region_seed, "region_seeds": REGION_SEEDS,
            "relative_noise": estimate.relative_noise, "seconds": seconds,
            "receiver_extent": [list(m.extent) for m in estimate.caustic],
            "resolution": list(s.receiver_map), "scale": scales, "seed_luminance": totals,
            "sha256": hashes,
            "caustic_only": True, "versions": mitsuba_versions()}


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
