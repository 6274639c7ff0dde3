"""Regression locks: the caustics-mapping renderer's metrics against the golden
references, calibrated from today's output. They guard against change, not accuracy:
a lock that holds says the method renders as it did when it was calibrated, nothing
about whether that is right (the physical requirements and method targets say that).

For every golden scene, both presets and receiver i the locked metrics are
(``LOCKED_METRICS``): the excess relMSE (against the noise-free image, with its 95 %
interval from the golden's variance: :func:`harness.checks.targets.caustic_relmse`, the
comparison's own estimator), SSIM (tone-mapped) and FLIP over the scene's caustic
region (the golden's ``region<i>.png``, thresholded on an independent reference, as
every comparison thresholds it), and the total-flux ratio over the whole map, locked
from above and from below (a lock guards today's value, which need not be 1: a change
toward 1 is a change too). The excess and flux-ratio locks are judged from their 95 %
intervals (holds, fails or undecided: :func:`harness.checks.bounds.judge`; the flux
ratio's from the reference's per-seed totals, the golden's ``seed_luminance``); SSIM
and FLIP, descriptive measures (``docs/statistics.md``), from the value. The render
is deterministic on one machine; what varies is

* the reference: calibration scores the render against the golden reference and
  against ``extra`` independent references (disjoint seeds, the golden budget);
  σ is the standard deviation over them;
* the platform (another Mesa, an NVIDIA driver): rounding that differs by a few ulps
  moves a nearest-texel lookup or a splat across a texel edge. Calibration renders
  the scene with the light moved by ``JITTER`` (1e-5 m, about 20 float32 ulps at 6 m)
  along ±x and ±y, and takes Δ, the largest change of the metric against the golden.

The bound is then

    max (relMSE, FLIP):   worst + max(3σ, 3Δ, 5 % of worst)   (relMSE: the worst is the
                          largest upper end of the excess's interval)
    min (SSIM):           worst − max(3σ, 3Δ, 5 % of (1 − worst))
    flux ratio:           highest + max(3σ, 3Δ, 0.005) and lowest − max(3σ, 3Δ, 0.005)
                          (the highest upper and the lowest lower end of its interval)

with "worst" the least favourable value over references and jitters: a bound that
reference noise and benign rounding cannot break, and that a real change (splats
shifted by a few texels, flux off by 10 %, no iterations) does. Calibrate on a GPU as
well when one is available and keep the wider bound.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np

from harness.checks.bounds import Bound, check_locks, locked_quantity
from harness.checks.golden import (
    GOLDEN_SETTINGS,
    Golden,
    golden_scene,
    load_golden,
    read_manifest,
)
from harness.checks.targets import caustic_relmse
from harness.compare.evaluate import exposure_for, score_value
from harness.compare.scoring import channel_correlation
from harness.compare.uncertainty import flux_ratio_interval, seed_luminance_totals
from renderers.caustics_mapping import render
from renderers.mitsuba import mitsuba_versions
from renderers.mitsuba.reference import estimate_receivers
from renderers.results import ReceiverMap
from reports.records import MetricValue
from scenes import Scene, with_settings
from scenes.files import atomic_write_bytes

__all__ = ["JITTER", "LOCKED_METHODS", "LOCKED_METRICS", "accuracy_metrics", "calibrate",
           "golden_applies", "golden_metrics", "jittered", "lock_checks", "not_committed",
           "realtime_maps", "write_locks"]

#: (region, metric, kind) locked for every receiver of every golden scene.
LOCKED_METRICS = (("caustic", "relmse", "max"), ("caustic", "ssim", "min"),
                  ("caustic", "flip", "max"), ("full", "flux_ratio", "max"),
                  ("full", "flux_ratio", "min"))
#: Presets with locks.
LOCKED_METHODS = ("paper", "strong")
#: Light displacement (m) that stands in for another platform's rounding.
JITTER = 1e-5


def realtime_maps(scene: Scene, *, ctx=None) -> list[np.ndarray]:
    """Caustics-mapping receiver maps of ``scene`` (camera shrunk: it is not scored)."""
    small = dataclasses.replace(scene, camera=dataclasses.replace(scene.camera,
                                                                  resolution=(16, 16)))
    return [m.irradiance for m in render(small, ctx=ctx).receivers]


def accuracy_metrics(test_maps, references, regions, *, seeds: int,
                     channel_correlation: float = 1.0,
                     seed_luminance=None) -> list[MetricValue]:
    """The locked metrics of each receiver map against its reference (each once): the
    caustic relMSE's excess and the full map's flux ratio with their 95 % intervals,
    SSIM and FLIP as values.

    Parameters
    ----------
    test_maps : list of ndarray (H, W, 3)
        The method's receiver irradiance, W/m².
    references : list of ReceiverMap
        The references, with their variance of the mean (K = ``seeds`` seeds).
    regions : list of ndarray (H, W) of bool
        The scene's caustic region of each receiver (the golden's ``region<i>.png``).
    channel_correlation : float
        1 when the same photons carry all three channels, 0 for one pass per channel.
    seed_luminance : list of ndarray (K,), optional
        Each reference's per-seed luminance totals over its map (the golden's
        ``seed_luminance``); default: from each reference's ``seed_maps``.
    """
    values = []
    for i, (method, reference, region) in enumerate(zip(test_maps, references, regions,
                                                       strict=True)):
        ref = np.asarray(reference.irradiance)
        regions_of = {"caustic": np.asarray(region, bool), "full": np.ones(ref.shape[:2], bool)}
        exposure = exposure_for(ref)
        for name, metric in dict.fromkeys((r, m) for r, m, _ in LOCKED_METRICS):
            if metric == "relmse":
                values.append(caustic_relmse(
                    reference, ReceiverMap(np.asarray(method), reference.extent),
                    regions_of[name], seeds=seeds, channel_correlation=channel_correlation,
                    view=f"receiver{i}"))
                continue
            value = score_value(metric, method, ref, mask=regions_of[name], exposure=exposure)
            fields = {}
            if metric == "flux_ratio":
                totals = (seed_luminance[i] if seed_luminance is not None
                          else seed_luminance_totals(reference.seed_maps))
                fields = flux_ratio_interval(value, totals)
            values.append(MetricValue(f"receiver{i}", name, metric, value,
                                      pixels=int(regions_of[name].sum()), **fields))
    return values


def golden_metrics(scene: Scene, maps, golden: Golden) -> list[MetricValue]:
    """:func:`accuracy_metrics` of ``maps`` against ``golden`` over its regions."""
    return accuracy_metrics(maps, list(golden.receivers), list(golden.regions),
                            seeds=int(golden.entry["seeds"]),
                            channel_correlation=channel_correlation(scene),
                            seed_luminance=list(golden.seed_luminance))


def _lock_name(scene: str, method: str) -> str:
    """Locks are keyed ``<scene>`` for the paper preset, ``<scene>@<method>`` else."""
    return scene if method == "paper" else f"{scene}@{method}"


def not_committed(scene: Scene, scenes_dir: Path) -> str | None:
    """Why ``scene`` is not a committed scene (None when its file is byte-identical
    to ``scenes_dir/<name>.toml``)."""
    committed = Path(scenes_dir) / f"{scene.name}.toml"
    try:
        same = Path(scene.source).read_bytes() == committed.read_bytes()
    except OSError:
        same = False
    return None if same else f"{scene.source} is not the committed {committed.name}"


def golden_applies(scene: Scene, scenes_dir: Path, golden_dir: Path) -> str | None:
    """Why the golden checks do not apply to ``scene`` (None when they do): only a
    committed scene (:func:`not_committed`) with a golden reference. An unreadable
    manifest is an error, never "no golden"."""
    if scene.name not in read_manifest(golden_dir)["scenes"]:
        return f"no golden reference for {scene.name}"
    return not_committed(scene, scenes_dir)


def lock_checks(scene: Scene, method: str, maps, golden, locks):
    """The locks of ``scene`` and ``method`` for the method's ``maps`` at the golden
    settings against ``golden`` (:class:`harness.checks.golden.Golden`)."""
    return check_locks(_lock_name(scene.name, method), golden_metrics(scene, maps, golden),
                       locks)


def jittered(scene: Scene, offset) -> Scene:
    """``scene`` with its light moved by ``offset`` (m, 3-vector); a directional light
    has its direction turned by the same amount per unit length instead."""
    light = scene.light
    if hasattr(light, "position"):
        moved = tuple(float(a + b) for a, b in zip(light.position, offset, strict=True))
        return dataclasses.replace(scene, light=dataclasses.replace(light, position=moved))
    turned = tuple(float(a + b) for a, b in zip(light.direction, offset, strict=True))
    return dataclasses.replace(scene, light=dataclasses.replace(light, direction=turned))


def _locked(value: MetricValue) -> tuple[float, float, float]:
    """The locked number of a metric record and its 95 % interval (low, high)
    (:func:`harness.checks.bounds.locked_quantity`; the number itself at both ends
    where it has none)."""
    number, interval = locked_quantity(value)
    low, high = interval if interval is not None else (number, number)
    return number, low, high


def _bound(metric: str, kind: str, values: np.ndarray, jitter: float) -> tuple[float, float]:
    sigma = float(np.std(values))
    if metric == "flux_ratio":
        margin = max(3 * sigma, 3 * jitter, 0.005)
        if kind == "max":
            return float(values.max()) + margin, float(values.max())
        return float(values.min()) - margin, float(values.min())
    if kind == "max":
        worst = float(values.max())
        return worst + max(3 * sigma, 3 * jitter, 0.05 * worst), worst
    worst = float(values.min())
    return worst - max(3 * sigma, 3 * jitter, 0.05 * (1 - worst)), worst


def calibrate(scenes_dir: Path, golden_dir: Path, names, *, extra: int = 3,
              methods=LOCKED_METHODS, ctx=None, progress=print) -> list[Bound]:
    """Locks for ``names`` and ``methods`` (module docstring)."""
    bounds = []
    today = time.strftime("%Y-%m-%d")
    v = mitsuba_versions()
    k = GOLDEN_SETTINGS["seeds"]
    for name in names:
        scene = golden_scene(scenes_dir, name)
        golden = load_golden(golden_dir, name)
        # (maps, per-seed totals): the golden's totals are in its manifest, the
        # others' in their seed maps.
        references = [(list(golden.receivers), list(golden.seed_luminance))]
        for r in range(extra):
            other = with_settings(scene, {"seed": golden.entry["seed"] + k * (r + 1)})
            estimate = estimate_receivers(other, target_noise=1e-12, caustic_only=True)
            references.append((list(estimate.caustic), None))
        rho = channel_correlation(scene)

        def metrics(maps, reference, rho=rho, golden=golden):
            return accuracy_metrics(maps, reference[0], list(golden.regions), seeds=k,
                                    channel_correlation=rho, seed_luminance=reference[1])

        for method in methods:
            configured = with_settings(scene, {"preset": method})
            maps = realtime_maps(configured, ctx=ctx)
            runs = [metrics(maps, ref) for ref in references]
            jitters = [metrics(realtime_maps(jittered(configured, offset), ctx=ctx),
                               references[0])
                       for offset in ((JITTER, 0, 0), (-JITTER, 0, 0), (0, JITTER, 0),
                                      (0, -JITTER, 0))]
            for j, first in enumerate(runs[0]):
                locked = np.array([_locked(run[j]) for run in runs], float)
                moved = np.array([_locked(run[j]) for run in jitters], float)
                delta = float(np.max(np.abs(moved[:, 0] - locked[0, 0])))
                # A lock from above keeps the intervals' upper ends, from below their
                # lower ends (the value itself where there is no interval).
                for kind in (kd for reg, met, kd in LOCKED_METRICS
                             if (reg, met) == (first.region, first.metric)):
                    end = 2 if kind == "max" else 1
                    bounds.append(_lock(name, method, first, kind=kind,
                                        values=locked[:, end], moved=moved[:, end],
                                        delta=delta, extra=extra, today=today, v=v))
            progress(f"{name} ({method}): {len(bounds)} locks so far")
    return bounds


def _lock(name, method, first, *, kind, values, moved, delta, extra, today, v) -> Bound:
    bound, worst = _bound(first.metric, kind, np.concatenate([values, moved]), delta)
    margin = "max(3 sd, 3 jitter, 0.005)" if first.metric == "flux_ratio" else \
        "max(3 sd, 3 jitter, 5 %)"
    end = "upper" if kind == "max" else "lower"
    what = {"relmse": f"excess relMSE's 95 % {end} ends",
            "flux_ratio": f"flux ratio's 95 % {end} ends"}.get(first.metric, "values")
    provenance = (
        f"{len(values)} references (golden + {extra} disjoint seeds), {what}: "
        f"{values.min():.4g}..{values.max():.4g}, sd {values.std():.2g}; light "
        f"jitter {JITTER:g} m (platform rounding): change up to {delta:.2g}; "
        f"worst {worst:.4g}; margin {margin}; {today}; "
        f"llvmpipe; mitsuba {v.get('mitsuba')}, drjit {v.get('drjit')}")
    return Bound(scene=_lock_name(name, method), view=first.view, region=first.region,
                 metric=first.metric, kind=kind, bound=_outward(bound, kind),
                 provenance=provenance)


def _outward(bound: float, kind: str, digits: int = 4) -> float:
    """``bound`` to ``digits`` significant digits, rounded away from the calibrated
    values (up for ``max``, down for ``min``): a strong preset's excess of 8e-6 keeps
    its margin, which rounding to a fixed number of decimals would take away."""
    if bound == 0 or not np.isfinite(bound):
        return float(bound)
    scale = 10.0 ** (np.floor(np.log10(abs(bound))) - (digits - 1))
    step = np.ceil if kind == "max" else np.floor
    return float(f"{step(bound / scale) * scale:.{digits}g}")


def write_locks(path: Path, bounds: list[Bound]) -> None:
    """The reviewed locks file, each lock with its provenance as a comment."""
    lines = [
        "# Regression locks of the caustics-mapping presets against the golden Mitsuba",
        "# references (harness/checks/data/golden), checked by",
        "# tests/harness/checks/test_regression_locks.py and `caustics compare`.",
        "# They are calibrated from today's output and guard against change, NOT accuracy:",
        "# see method_targets.toml and harness/checks/physical.py for that.",
        "# Scene keys: <scene> for the paper preset, <scene>@<method> for another.",
        "# Generated by `caustics calibrate`; review changes like code.",
        f"# Settings: {GOLDEN_SETTINGS}; margins from harness/checks/locks.py.",
        "",
    ]
    for b in bounds:
        lines += [f"# {b.provenance}", "[[lock]]", f'scene = "{b.scene}"',
                  f'view = "{b.view}"', f'region = "{b.region}"', f'metric = "{b.metric}"',
                  f'kind = "{b.kind}"', f"bound = {b.bound!r}",
                  f'provenance = "{b.provenance}"', ""]
    atomic_write_bytes(Path(path), "\n".join(lines).encode("utf-8"))

