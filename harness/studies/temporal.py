"""Temporal stability: an animated scene rendered frame by frame on both sides and
compared over time (``caustics compare SCENE --studies temporal [--frames N]``).

Steps, for the frames of the scene's ``[animation]`` (``scenes.animation``; ``frames``
overrides the count):

1. the method renders every frame (one GL context for the caustics-mapping presets,
   an untimed warm-up of frame 0 first, so shader compilation is not a frame cost);
   its frame time is the sum of its passes (``harness.studies.runner.frame_seconds``,
   on llvmpipe ``ctx.finish()`` and ``time.perf_counter``), and the CPU time of
   building each frame's meshes is recorded apart;
2. the reference renders every frame with common random numbers
   (``renderers.mitsuba.sequence``: the same seeds, streams and photon count each
   frame, so its noise largely cancels in frame differences), and an independent
   reference sequence on disjoint seeds gives every metric's noise floor;
3. receiver 0's caustic irradiance is scored per frame (relMSE, SSIM, FLIP over the
   full map and the frame's caustic region, the flux ratio; the exposure fixed over
   the whole sequence), and over time: the flicker F per frame pair and overall, its
   noise floor and its excess over the noise, and the ratio of temporal
   high-frequency energy, raw and noise-corrected, overall and per pixel
   (``harness.metrics.temporal`` holds the formulas); :func:`compare_sequences` is
   this step alone, on sequences from anywhere.

The caustic region of a frame is the scene's, as every comparison has it
(:func:`harness.compare.regions.scene_caustic_region`): thresholded on the independent
reference's frame, never on the scored reference's, so its noise does not choose the
texels it is scored on; over time, a frame pair scores the union of its two frames'
regions, and the energy ratio the union over every frame.
"""

from __future__ import annotations

import os
import statistics
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from harness.compare.evaluate import exposure_for
from harness.compare.regions import scene_caustic_region
from harness.compare.timed import render_method
from harness.metrics import (
    MetricInputError,
    flicker_map,
    flicker_series,
    flip_error,
    flux_ratio,
    high_frequency_energy_ratio,
    high_frequency_energy_ratio_map,
    luminance,
    relative_mse,
    structural_similarity,
)
from harness.studies.runner import frame_seconds
from renderers.methods import Method, has_gl_runner
from renderers.mitsuba.sequence import render_reference_frames
from renderers.results import RenderResult
from reports.records import Table
from reports.temporal_records import TEMPORAL_FORMULAS, TemporalComparison
from scenes import Scene
from scenes.animation import animation_frames, animation_of
from scenes.geometry import build_geometry

__all__ = ["COLUMNS", "REGIONS", "TemporalOptions", "compare_sequences", "temporal_study"]

#: Columns of ``temporal.csv``: one row per frame; the flicker columns hold the pair
#: (frame − 1, frame) and are empty for frame 0.
COLUMNS = ("frame", "time_s",
           "relmse_caustic", "relmse_caustic_floor", "ssim_caustic", "ssim_caustic_floor",
           "flip_caustic", "flip_caustic_floor", "relmse_full", "relmse_full_floor",
           "flux_ratio", "flicker_caustic", "flicker_caustic_floor", "flicker_full",
           "flicker_full_floor", "method_ms", "geometry_ms", "reference_s",
           "reference_cache")
REGIONS = ("caustic", "full")
VIEW = "receiver0"


@dataclass(frozen=True)
class TemporalOptions:
    """How the temporal study runs.

    Attributes
    ----------
    frames : int or None
        Frames of the sequence; None: the scene's ``[animation] frames`` (24 without).
    common_random_numbers : bool
        The reference's frames share their random numbers (the default; off only to
        show what reference noise does to the flicker without them).
    cache, use_cache
        The reference cache root (None: the default) and whether to use it.
    progress : callable or None
        Called once per rendered frame (method, reference, independent reference).
    """

    frames: int | None = None
    common_random_numbers: bool = True
    cache: str | None = None
    use_cache: bool = True
    progress: Callable[[], None] | None = None


def _renderer(method: Method, ctx) -> Callable[[Scene], RenderResult]:
    """One frame of the method, through its protocol's ``render``
    (:func:`harness.compare.timed.render_method`): a method with a GL runner draws in
    the study's GL context ``ctx`` (one context for the sequence) on the frame's
    meshes (any other method ignores ``ctx``)."""
    ctx = ctx if has_gl_runner(method) else None

    def render_frame(frame: Scene) -> RenderResult:
        geometry = build_geometry(frame) if ctx is not None else None
        return render_method(method, frame, ctx=ctx, geometry=geometry)

    return render_frame


def _method_frames(frames: list[Scene], render: Callable[[Scene], RenderResult], tick):
    """(sequence (T, H, W, 3), frame seconds per frame, geometry seconds per frame).

    Each frame's meshes are built (and timed) before its render, which reuses the
    build (``build_geometry`` keeps it); frame 0's before the warm-up render."""
    geometry = []

    def built(frame: Scene) -> None:
        start = time.perf_counter()
        build_geometry(frame)
        geometry.append(time.perf_counter() - start)

    built(frames[0])
    render(frames[0])  # warm-up: shader compilation and kernel set-up are not frame costs
    maps, seconds = [], []
    for index, frame in enumerate(frames):
        if index > 0:
            built(frame)
        start = time.perf_counter()
        result = render(frame)
        wall = time.perf_counter() - start
        seconds.append(frame_seconds(result.timings) if result.timings else wall)
        maps.append(np.asarray(result.receivers[0].irradiance, np.float32))
        tick()
    return np.stack(maps), seconds, geometry


def _nan_if_undefined(function, *args, **kwargs) -> float:
    try:
        return function(*args, **kwargs)
    except MetricInputError:
        return float("nan")


def _frame_scores(method, reference, independent, caustic, exposure) -> dict[str, float]:
    """relMSE, SSIM, FLIP (caustic and full) and the flux ratio of one frame, each
    with its noise floor (the independent reference against the reference)."""
    scores: dict[str, float] = {}
    full = np.ones(caustic.shape, bool)
    regions = {"caustic": caustic, "full": full}
    for suffix, other in (("", method), ("_floor", independent)):
        ssim_map = structural_similarity(other, reference, white=exposure.white,
                                         return_map=True)[1]
        flip_map = flip_error(other, reference, start_exposure=exposure.flip_start,
                              stop_exposure=exposure.flip_stop, return_map=True)[1]
        for region, mask in regions.items():
            if not mask.any():
                scores[f"relmse_{region}{suffix}"] = float("nan")
                continue
            scores[f"relmse_{region}{suffix}"] = relative_mse(other, reference, mask=mask)
            scores[f"ssim_{region}{suffix}"] = float(ssim_map[mask].mean())
            scores[f"flip_{region}{suffix}"] = float(flip_map[mask].mean())
    scores["flux_ratio"] = _nan_if_undefined(flux_ratio, method, reference)
    return scores


def _value(value: float, floor: float, **extra) -> dict[str, float]:
    return {"value": value, "noise_floor": floor, **extra}


def _flicker(reference, method, independent, caustic) -> dict[str, tuple[np.ndarray, ...]]:
    """Per region, F_t of every frame pair for the method and for the independent
    reference (the floor); NaN where the region is empty in a pair."""
    out = {}
    for region, mask in (("caustic", caustic), ("full", None)):
        try:
            out[region] = (flicker_series(reference, method, mask=mask),
                           flicker_series(reference, independent, mask=mask))
        except MetricInputError:
            out[region] = (np.full(len(reference) - 1, np.nan),) * 2
    return out


def _summary(reference, method, independent, *, caustic, flicker, rows) -> dict:
    """The flicker metrics of the whole sequence (``metrics.json``'s numbers)."""
    union = caustic.any(axis=0)
    out = {"flicker": {}, "hf_energy_ratio": {}, "per_frame_mean": {}}
    for region, (values, floors) in flicker.items():
        value, floor = float(np.mean(values)), float(np.mean(floors))
        out["flicker"][region] = _value(value, floor, excess=value - floor / 2)
    for region, mask in (("caustic", union), ("full", None)):
        if region == "caustic" and not union.any():
            continue
        value = _nan_if_undefined(high_frequency_energy_ratio, reference, method, mask=mask)
        floor = _nan_if_undefined(high_frequency_energy_ratio, reference, independent,
                                  mask=mask)
        corrected = _nan_if_undefined(high_frequency_energy_ratio, reference, method,
                                      mask=mask, independent=independent)
        out["hf_energy_ratio"][region] = _value(value, floor, noise_corrected=corrected)
    for name in ("relmse_caustic", "ssim_caustic", "flip_caustic", "relmse_full"):
        values = [r[name] for r in rows if np.isfinite(r[name])]
        floors = [r[f"{name}_floor"] for r in rows if np.isfinite(r[f"{name}_floor"])]
        out["per_frame_mean"][name] = _value(float(np.mean(values)) if values else float("nan"),
                                             float(np.mean(floors)) if floors else float("nan"))
    return out


def compare_sequences(reference: np.ndarray, method: np.ndarray, independent: np.ndarray, *,
                      times, fps: float, columns: dict[str, list] | None = None
                      ) -> TemporalComparison:
    """Score a method's sequence against the reference's, frame by frame and over
    time (step 3 of the module docstring); no rendering.

    Parameters
    ----------
    reference, method, independent : ndarray, (T, H, W, 3)
        Receiver 0's caustic irradiance (W/m²) per frame: the reference, the method
        and an independent reference of disjoint seeds (the noise floors).
    times : sequence of float
        τ of each frame (s).
    fps : float
        Frames per second.
    columns : dict of str to list, optional
        Further per-frame columns of the table (frame and reference times), T values
        each.

    Returns
    -------
    TemporalComparison
        The table (every :data:`COLUMNS`; those neither scored nor given are NaN),
        the summary's flicker metrics (no run times: :func:`temporal_study` adds
        them), the per-pixel maps and the display exposure.
    """
    reference = np.asarray(reference, np.float32)
    method = np.asarray(method, np.float32)
    independent = np.asarray(independent, np.float32)
    count = len(reference)
    exposure = exposure_for(np.concatenate(list(reference), axis=0))
    caustic = np.stack([scene_caustic_region(r) for r in independent])
    # FLIP is the cost here (about 2 s a 256² frame on one core); its C++ releases the
    # GIL, so the frames are scored on a thread per core.
    with ThreadPoolExecutor(max_workers=max(1, min(count, os.cpu_count() or 1))) as pool:
        scores = list(pool.map(
            lambda t: _frame_scores(method[t], reference[t], independent[t], caustic[t],
                                    exposure), range(count)))
    rows = []
    for t in range(count):
        extra = {name: values[t] for name, values in (columns or {}).items()}
        rows.append({column: float("nan") for column in COLUMNS}
                    | {"frame": t, "time_s": float(times[t]), **scores[t], **extra})
    flicker = _flicker(reference, method, independent, caustic)
    for region, (values, floors) in flicker.items():
        rows[0][f"flicker_{region}"] = rows[0][f"flicker_{region}_floor"] = None
        for t in range(1, count):
            rows[t][f"flicker_{region}"] = float(values[t - 1])
            rows[t][f"flicker_{region}_floor"] = float(floors[t - 1])
    summary = _summary(reference, method, independent, caustic=caustic, flicker=flicker,
                       rows=rows)
    summary.update({"view": VIEW, "frames": count, "fps": float(fps),
                    "times_s": [float(t) for t in times], "formulas": TEMPORAL_FORMULAS})
    maps = {"flicker": flicker_map(reference, method).astype(np.float32),
            "flicker_floor": flicker_map(reference, independent).astype(np.float32)}
    if count >= 3:
        maps["hf_ratio"] = high_frequency_energy_ratio_map(reference, method).astype(np.float32)
    difference = np.abs(luminance(method.astype(np.float64) - reference))
    limit = float(np.percentile(difference, 99.5)) if difference.size else 0.0
    return TemporalComparison(
        view=VIEW, times=tuple(float(t) for t in times), fps=float(fps), method=method,
        reference=reference, table=Table.from_records(COLUMNS, rows), summary=summary,
        maps=maps, white=exposure.white, diff_range=limit if limit > 0 else 1.0,
        files={"table": "temporal.csv", "flicker": "temporal_flicker.exr",
               "flicker_floor": "temporal_flicker_floor.exr",
               **({"hf_ratio": "temporal_hf_ratio.exr"} if "hf_ratio" in maps else {})})


def temporal_study(scene: Scene, method: Method, *, options: TemporalOptions = TemporalOptions(),
                   ctx=None) -> TemporalComparison:
    """Render ``scene``'s animation with ``method`` and the reference and compare them
    frame by frame and over time (see the module docstring).

    Parameters
    ----------
    scene : Scene
        The scene as the method configured it (its settings hold the preset's choices).
    method : Method
        The method; one with a GL runner (a caustics-mapping preset) renders in
        ``ctx`` when given.
    options : TemporalOptions
    ctx : moderngl.Context, optional
        The GL context of the comparison, shared by every frame.

    Returns
    -------
    TemporalComparison
        Sequences, per-frame table, summary (flicker metrics, frame times, the
        reference's seeds, run time) and per-pixel maps of receiver 0.
    """
    start = time.perf_counter()
    tick = options.progress or (lambda: None)
    animation = animation_of(scene, frames=options.frames)
    sequence = animation_frames(scene, frames=options.frames)
    frames = [f.scene for f in sequence]

    method_start = time.perf_counter()
    method_maps, method_seconds, geometry_seconds = _method_frames(
        frames, _renderer(method, ctx), tick)
    method_wall = time.perf_counter() - method_start

    s = scene.settings
    reference_start = time.perf_counter()
    common = dict(common_random_numbers=options.common_random_numbers, cache=options.cache,
                  use_cache=options.use_cache, progress=tick)
    reference_frames = render_reference_frames(frames, seed=s.seed, **common)
    # Disjoint from the reference's seeds: K of them with common random numbers, T K
    # without (every frame then has its own K).
    independent_seed = s.seed + s.seeds * (1 if options.common_random_numbers else len(frames))
    independent_frames = render_reference_frames(frames, seed=independent_seed, **common)
    reference_wall = time.perf_counter() - reference_start

    metrics_start = time.perf_counter()
    result = compare_sequences(
        np.stack([f.receivers[0].irradiance for f in reference_frames]), method_maps,
        np.stack([f.receivers[0].irradiance for f in independent_frames]),
        times=[f.time for f in sequence], fps=animation.fps,
        columns={"method_ms": [x * 1e3 for x in method_seconds],
                 "geometry_ms": [x * 1e3 for x in geometry_seconds],
                 "reference_s": [f.seconds for f in reference_frames],
                 "reference_cache": [f.cache for f in reference_frames]})
    metrics_wall = time.perf_counter() - metrics_start

    cached = [f.cache for f in (*reference_frames, *independent_frames)]
    result.summary.update({
        "method": {
            "frame_time_ms": {"median": statistics.median(method_seconds) * 1e3,
                              "max": max(method_seconds) * 1e3},
            "geometry_ms": {"median": statistics.median(geometry_seconds) * 1e3},
            "timer": "sum of the method's passes, after an untimed warm-up of frame 0; "
                     "geometry: time.perf_counter around build_geometry",
        },
        "reference": {
            "common_random_numbers": options.common_random_numbers,
            "seed": s.seed, "seeds": s.seeds, "independent_seed": independent_seed,
            "photons_per_seed": reference_frames[0].photons,
            "relative_noise_median": statistics.median(f.relative_noise
                                                       for f in reference_frames),
            "cache": {"hit": sum(c == "hit" for c in cached),
                      "rendered": sum(c != "hit" for c in cached)},
            "frame_seconds_median": statistics.median(f.seconds for f in reference_frames),
        },
        "run_time_s": {"total": time.perf_counter() - start, "method": method_wall,
                       "reference": reference_wall, "metrics": metrics_wall,
                       "timer": "time.perf_counter"},
    })
    return result
