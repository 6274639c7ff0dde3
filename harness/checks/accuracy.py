"""Accuracy against golden references: the metrics the thresholds bound, and the
calibration that sets each bound from measured spread.

For every golden scene and receiver i the bounded metrics are (``THRESHOLD_METRICS``):
relMSE, SSIM (tone-mapped) and FLIP over the reference's caustic region, and the
total-flux ratio over the whole map. The caustics-mapping render is deterministic;
what varies is the reference, so calibration scores the render against the golden
reference and against ``extra`` independent references (disjoint seeds, the same
budget) and sets

    max bounds (relMSE, FLIP):  worst + max(3σ, 5 % of worst)
    min bounds (SSIM):          worst − max(3σ, 5 % of (1 − worst))
    band bounds (flux ratio):   worst |v − 1| + max(3σ, 0.005)

where σ is the standard deviation over those references and "worst" the least
favourable value: a bound that reference noise alone cannot break, and that a real
regression (shifted splats, flux off by 10 %, too few iterations) does.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np

from harness.checks.golden import (
    GOLDEN_SETTINGS,
    GoldenError,
    golden_scene,
    load_golden,
    read_manifest,
)
from harness.checks.thresholds import Bound, check_bounds
from harness.compare.evaluate import exposure_for, score_value
from harness.compare.regions import caustic_region
from renderers.caustics_mapping import render
from renderers.mitsuba._mi import versions
from renderers.mitsuba.reference import estimate_receivers
from reports.records import MetricValue
from scenes import Scene, with_settings
from scenes.files import atomic_write_bytes

__all__ = ["THRESHOLD_METRICS", "accuracy_metrics", "calibrate", "golden_checks",
           "realtime_maps", "write_thresholds"]

#: (region, metric, kind) bounded for every receiver of every golden scene.
THRESHOLD_METRICS = (("caustic", "relmse", "max"), ("caustic", "ssim", "min"),
                     ("caustic", "flip", "max"), ("full", "flux_ratio", "band"))


def realtime_maps(scene: Scene, *, ctx=None) -> list[np.ndarray]:
    """Caustics-mapping receiver maps of ``scene`` (camera shrunk: it is not scored)."""

    small = dataclasses.replace(scene, camera=dataclasses.replace(scene.camera,
                                                                  resolution=(16, 16)))
    return [m.irradiance for m in render(small, ctx=ctx).receivers]


def accuracy_metrics(test_maps, reference_maps) -> list[MetricValue]:
    """The bounded metrics of each receiver map against its reference."""
    values = []
    for i, (method, reference) in enumerate(zip(test_maps, reference_maps, strict=True)):
        regions = {"caustic": caustic_region(reference),
                   "full": np.ones(reference.shape[:2], bool)}
        exposure = exposure_for(reference)
        for region, metric, _ in THRESHOLD_METRICS:
            values.append(MetricValue(f"receiver{i}", region, metric, score_value(
                metric, method, reference, mask=regions[region], exposure=exposure)))
    return values


def golden_checks(scene: Scene, *, scenes_dir: Path, golden_dir: Path, bounds, ctx=None):
    """The accuracy bounds of ``scene``, checked as the test suite checks them.

    Bounds hold at the golden settings, against the golden references, so the
    render is repeated at the golden receiver-map resolution, keeping this run's
    other settings (estimator, iterations, grid, ...): a configuration that breaks a
    bound shows it. Applies only to a scene whose file is byte-identical to the
    committed ``scenes_dir/<name>.toml``; returns None otherwise (or without a golden
    reference for it).
    """

    committed = Path(scenes_dir) / f"{scene.name}.toml"
    try:
        same = Path(scene.source).read_bytes() == committed.read_bytes()
        known = scene.name in read_manifest(golden_dir)["scenes"]
    except (OSError, GoldenError):
        return None
    if not (same and known):
        return None

    golden = load_golden(golden_dir, scene.name)
    at_golden = with_settings(scene, {"receiver_map": GOLDEN_SETTINGS["receiver_map"]})
    method = realtime_maps(at_golden, ctx=ctx)
    metrics = accuracy_metrics(method, [m.irradiance for m in golden.receivers])
    return check_bounds(scene.name, metrics, bounds)


def _bound(kind: str, values: np.ndarray) -> tuple[float, float]:
    sigma = float(np.std(values))
    if kind == "max":
        worst = float(values.max())
        return worst + max(3 * sigma, 0.05 * worst), worst
    if kind == "min":
        worst = float(values.min())
        return worst - max(3 * sigma, 0.05 * (1 - worst)), worst
    worst = float(np.abs(values - 1).max())
    return worst + max(3 * sigma, 0.005), worst


def calibrate(scenes_dir: Path, golden_dir: Path, names, *, extra: int = 3,
              ctx=None, progress=print) -> list[Bound]:
    """Bounds for ``names`` from the golden reference plus ``extra`` independent ones."""

    bounds = []
    today = time.strftime("%Y-%m-%d")
    v = versions()
    for name in names:
        scene = golden_scene(scenes_dir, name)
        method = realtime_maps(scene, ctx=ctx)
        runs = [accuracy_metrics(method, [m.irradiance for m in load_golden(golden_dir,
                                                                            name).receivers])]
        k = GOLDEN_SETTINGS["seeds"]
        for r in range(extra):
            other = with_settings(scene, {"seed": GOLDEN_SETTINGS["seed"] + k * (r + 1)})
            estimate = estimate_receivers(other, target_noise=1e-12)
            runs.append(accuracy_metrics(method, [m.irradiance for m in estimate.caustic]))
        for j, first in enumerate(runs[0]):
            values = np.array([run[j].value for run in runs], float)
            kind = next(k for reg, met, k in THRESHOLD_METRICS
                        if (reg, met) == (first.region, first.metric))
            bound, worst = _bound(kind, values)
            provenance = (f"{len(values)} references (golden + {extra} disjoint seeds): "
                          f"{values.min():.4g}..{values.max():.4g}, sd {values.std():.2g}; "
                          f"worst {worst:.4g}; margin max(3 sd, 5 %); {today}; "
                          f"mitsuba {v.get('mitsuba')}, drjit {v.get('drjit')}")
            bounds.append(Bound(scene=name, view=first.view, region=first.region,
                                metric=first.metric, kind=kind, bound=round(bound, 6),
                                provenance=provenance))
        progress(f"{name}: {len(runs[0])} bounds")
    return bounds


def write_thresholds(path: Path, bounds: list[Bound]) -> None:
    """The reviewed thresholds file, each bound with its provenance as a comment."""

    lines = [
        "# Accuracy bounds of the caustics-mapping renderer against the golden Mitsuba",
        "# references (harness/checks/data/golden), checked by",
        "# tests/harness/checks/test_accuracy_thresholds.py.",
        "# Generated by `caustics calibrate`; review changes like code.",
        f"# Settings: {GOLDEN_SETTINGS}; bounds from harness/checks/accuracy.py.",
        "",
    ]
    for b in bounds:
        lines += [f"# {b.provenance}", "[[bound]]", f'scene = "{b.scene}"',
                  f'view = "{b.view}"', f'region = "{b.region}"', f'metric = "{b.metric}"',
                  f'kind = "{b.kind}"', f"bound = {b.bound!r}",
                  f'provenance = "{b.provenance}"', ""]
    atomic_write_bytes(path, "\n".join(lines).encode("utf-8"))
