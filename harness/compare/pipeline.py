"""One scene, both renderers, every comparison: ``compare_scene`` builds the
:class:`~reports.records.SceneComparison` the outputs and the report use.

Steps: the method configures the scene (a caustics-mapping preset fills the unset
settings); the Mitsuba reference (from the cache when present, shared by every
method) and an independent reference on disjoint seeds (the noise floor); the
method's render (median frame time over repeats after a warm-up); metrics per view
and region; for the caustics-mapping presets, the convergence table, the
cost-versus-accuracy sweep with the equal-error speedup, and the paper's claims
with their uncertainties (``harness.studies.claims``); both sides' flux budgets
(``harness.compare.budget``: the reference's from a separate caustic-only trace);
provenance; the page's headlines, which withhold a speedup that means nothing
(``harness.compare.headlines``).
"""

from __future__ import annotations

import os
import platform
import statistics
import time
from dataclasses import asdict, dataclass
from typing import NamedTuple

import numpy as np
from tqdm import tqdm

from harness.checks.stability import stability_summary
from harness.compare.budget import flux_budget, side_budgets
from harness.compare.evaluate import exposure_for, score_view
from harness.compare.headlines import with_headlines
from harness.compare.regions import caustic_region, object_mask, object_region
from harness.studies.claims import paper_claims
from harness.studies.convergence_study import convergence_study
from harness.studies.cost_study import cost_study, sweep_size
from harness.studies.decomposition import DecompositionOptions, decomposition_study
from harness.studies.runner import RealtimeRunner, caustic_seconds, frame_seconds
from harness.studies.temporal import TemporalOptions, temporal_study
from harness.studies.timing import MIN_REPEATS
from harness.terminal import plain
from renderers.methods import Method, load_method
from renderers.mitsuba.reference import render_reference
from reports.display import luminance
from reports.records import SceneComparison
from scenes import Scene, effects_of, with_settings
from scenes.animation import animation_of
from scenes.geometry import build_geometry

__all__ = ["KNOWN_STUDIES", "OPTIONAL_STUDIES", "STUDIES", "CompareOptions", "compare_scene"]

STUDIES = ("metrics", "convergence", "cost")
#: Studies run only when named (``--studies ...,temporal``): the animation's frames;
#: the error decomposition (exact light paths, then the method's approximations).
OPTIONAL_STUDIES = ("temporal", "decomposition")
KNOWN_STUDIES = STUDIES + OPTIONAL_STUDIES
REFERENCE_KEYS = ("photons", "photon_budget", "spp", "seed", "seeds", "relative_noise",
                  "target_noise", "stopped_by", "event_chains", "variant", "versions",
                  "camera_integrator", "camera_max_depth", "camera_limits", "cache", "hash")


@dataclass(frozen=True)
class CompareOptions:
    """How much to compute.

    Attributes
    ----------
    studies : tuple of str
        Any of ``metrics`` (always computed), ``convergence``, ``cost``, ``temporal``
        (the scene's animation frame by frame, ``harness.studies.temporal``),
        ``decomposition`` (where the error comes from, ``harness.studies.decomposition``).
    frames : int or None
        Frames of the temporal study (None: the scene's ``[animation] frames``).
    max_iterations : int
        Iterations 0..N of the convergence table.
    quick : bool
        Smaller sweeps and one timing repeat (a quick look, not for reporting);
        otherwise :data:`~harness.studies.timing.MIN_REPEATS`.
    cache, use_cache
        Reference cache root (None: the default) and whether to use it.
    progress : bool
        Progress bars on stderr.
    dense_grid : int or None
        Lattice side of the decomposition's step 0 (dense exact paths); None, or
        ``quick``, leaves the step out.
    """

    studies: tuple[str, ...] = STUDIES
    max_iterations: int = 8
    quick: bool = False
    cache: str | None = None
    use_cache: bool = True
    progress: bool = True
    frames: int | None = None
    dense_grid: int | None = 1024

    @property
    def repeats(self) -> int:
        """Timed renders per configuration (the median is kept)."""
        return 1 if self.quick else MIN_REPEATS


def _references(scene: Scene, options: CompareOptions):

    s = scene.settings
    reference = render_reference(scene, cache=options.cache, use_cache=options.use_cache,
                                 progress=options.progress)
    # Seeds s.seed + K .. s.seed + 2K - 1: disjoint from the reference's.
    other = with_settings(scene, {"seed": s.seed + s.seeds})
    independent = render_reference(other, cache=options.cache, use_cache=options.use_cache,
                                   progress=options.progress)
    return reference, independent


def _camera_is_blind(reference: np.ndarray, method: np.ndarray) -> bool:
    """A ``ptracer`` reference camera image is black where the real-time one is lit:
    ptracer cannot connect receivers seen only through a specular surface
    (everything under a water surface). Blind when, over the pixels the real-time
    image lights (above 1 % of its 99th-percentile luminance), the reference holds
    under 10 % of the real-time image's energy. ptracer is unbiased, so this holds at
    any sample count (at 2 spp most pixels are still black), while a few stray
    particles (seabed: about 1 % of the energy) do not make a usable reference. The
    default camera tracer sees through specular surfaces and is never blind."""
    rt = luminance(method)
    top = float(np.percentile(rt, 99))
    if top <= 0:
        return False
    lit = rt > 0.01 * top
    return float(luminance(reference)[lit].sum()) < 0.1 * float(rt[lit].sum())


def _progress_bar(total: int, enabled: bool, label: str):
    if not enabled:
        return None, (lambda: None)

    bar = tqdm(total=total, desc=plain(label), unit="render", leave=False)
    return bar, (lambda: bar.update(1))


class _View(NamedTuple):
    """One scored image: the camera or a receiver map, with its regions."""

    name: str
    method: np.ndarray
    reference: np.ndarray
    independent: np.ndarray
    regions: dict[str, np.ndarray]
    masks: dict[str, np.ndarray]
    exposure_mask: np.ndarray | None


def _views(scene: Scene, geometry, method, reference, independent):
    """The views to score, and why the camera is left out (None if it is not).

    The camera view has three regions: ``full``; ``object``, the pixels inside a
    caustic object's silhouette (the object seen through, scored like any other
    region); and ``object_masked``, the rest of the frame. The silhouette's own
    pixels, where the renderers' rasterisation and sampling differ, are in neither
    of the last two. A ``ptracer`` reference renders the object black, so its
    ``object`` region is not scored.
    """
    views, note = [], None
    ptracer = reference.metadata.get("camera_integrator") == "ptracer"
    if ptracer and _camera_is_blind(reference.camera, method.camera):
        note = ("camera not compared: the reference camera image is black "
                "(ptracer cannot see receivers through a specular surface)")
    else:
        obj = object_mask(scene.camera, geometry)
        regions = {"full": np.ones(obj.shape, bool), "object_masked": ~obj}
        if not ptracer:
            regions["object"] = object_region(scene.camera, geometry)
        views.append(_View("camera", method.camera, reference.camera, independent.camera,
                           regions, {"mask_object": obj}, ~obj if ptracer else None))
    for i, (method_map, ref_map, ind_map) in enumerate(zip(
            method.receivers, reference.receivers, independent.receivers, strict=True)):
        caustic = caustic_region(ref_map.irradiance)
        views.append(_View(f"receiver{i}", method_map.irradiance, ref_map.irradiance,
                           ind_map.irradiance,
                           {"full": np.ones(caustic.shape, bool), "caustic": caustic},
                           {"mask_caustic": caustic}, None))
    return views, note


def _score_views(views: list[_View]):
    """Metrics, images, per-view exposure and EXR file names of every view."""
    metrics, images, files = [], {}, {}
    exposure = {"white": {}, "flip_start": {}, "flip_stop": {}, "diff_range": {}}
    for view in views:
        expo = exposure_for(view.reference, mask=view.exposure_mask)
        values, maps = score_view(view.name, view.method, view.reference, view.independent,
                                  regions=view.regions, exposure=expo)
        metrics += values
        images.update(maps)
        images[f"{view.name}/method"] = np.asarray(view.method, np.float32)
        images[f"{view.name}/reference"] = np.asarray(view.reference, np.float32)
        for name, mask in view.masks.items():
            images[f"{view.name}/{name}"] = mask
        exposure["white"][view.name] = expo.white
        exposure["flip_start"][view.name] = expo.flip_start
        exposure["flip_stop"][view.name] = expo.flip_stop
        signed = np.abs(maps[f"{view.name}/signed"])
        signed = signed[np.isfinite(signed)]
        limit = float(np.percentile(signed, 99.5)) if signed.size else 0.0
        # A colour bar needs a positive range: no difference (or none finite) gets 1.
        exposure["diff_range"][view.name] = limit if limit > 0 else 1.0
        for kind in ("method", "reference", "signed", "ssim", "flip"):
            files[f"{view.name}/{kind}"] = f"{view.name}_{kind}.exr"
    return metrics, images, exposure, files


def _reference_variance(reference, views: list[_View]) -> dict[str, np.ndarray]:
    """``<view>/reference_variance``: the variance of the reference's mean per texel
    (receivers) or pixel (the camera, when it is compared), which the physical
    requirements (``harness.checks``) and the report's probes need; not written."""
    out = {f"receiver{i}/reference_variance": np.asarray(m.variance, np.float32)
           for i, m in enumerate(reference.receivers) if m.variance is not None}
    camera = reference.metadata.get("camera_variance")
    if camera is not None and any(v.name == "camera" for v in views):
        out["camera/reference_variance"] = np.asarray(camera, np.float32)
    return out


def _timed_method(method: Method, scene: Scene, repeats: int):
    """(result, warm seconds, timer) over ``repeats`` renders after a warm-up render.

    The same scope as the presets' frame time where the method reports its passes:
    the median of the sum of its per-pass timings (its own timer). Otherwise the
    median wall time of ``method.render`` (``time.perf_counter``), which also holds
    whatever set-up the method repeats per call, and the timer says so.
    """
    method.render(scene)
    walls, sums, result = [], [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = method.render(scene)
        walls.append(time.perf_counter() - start)
        sums.append(frame_seconds(result.timings))
    if result.timings:
        return result, statistics.median(sums), f"sum of the method's passes ({result.timer})"
    return result, statistics.median(walls), "time.perf_counter around render() (whole call)"


def _compare_other(scene: Scene, method: Method, options: CompareOptions) -> SceneComparison:
    """A method outside caustics mapping: metrics, stability and timing only."""
    reference, independent = _references(scene, options)
    result, seconds, timer = _timed_method(method, scene, options.repeats)
    geometry = build_geometry(scene)
    views, camera_note = _views(scene, geometry, result, reference, independent)
    metrics, images, exposure, files = _score_views(views)
    images.update(_reference_variance(reference, views))
    provenance = {
        "scene_file": scene.source,
        "method": {"name": method.name, "renderer": result.renderer,
                   "timings_ms": {k: v * 1e3 for k, v in result.timings.items()},
                   "frame_time_ms": seconds * 1e3,
                   "timer": f"{timer}, median after a warm-up",
                   "metadata": result.metadata},
        **_reference_provenance(reference, independent),
    }
    if camera_note:
        provenance["camera_note"] = camera_note
    stability = stability_summary(scene, geometry, result, None)
    return with_headlines(SceneComparison(
        name=scene.name, description=scene.info.description, source=scene.source,
        effects=effects_of(scene), settings=asdict(scene.settings), metrics=tuple(metrics),
        images=images, exposure=exposure, provenance=provenance, files=files,
        stability=stability, method=method.name, method_description=method.description,
        flux_budget=flux_budget(result.metadata, stability, result.receivers,
                                reference.receivers),
        **side_budgets(scene, result, stability, reference, geometry=geometry),
        temporal=_temporal(scene, method, options)))


def _temporal(scene: Scene, method: Method, options: CompareOptions, ctx=None):
    """The temporal study when ``options.studies`` names it, else None."""
    if "temporal" not in options.studies:
        return None
    count = animation_of(scene, frames=options.frames).frames
    bar, tick = _progress_bar(3 * count, options.progress, f"{scene.name}: temporal")
    try:
        return temporal_study(scene, method, ctx=ctx, options=TemporalOptions(
            frames=options.frames, cache=options.cache, use_cache=options.use_cache,
            progress=tick))
    finally:
        if bar is not None:
            bar.close()


def _reference_provenance(reference, independent) -> dict:
    return {
        "reference": {**{k: reference.metadata.get(k) for k in REFERENCE_KEYS},
                      "timings_s": reference.timings, "timer": reference.timer},
        "independent_reference": {k: independent.metadata.get(k)
                                  for k in ("seed", "seeds", "relative_noise", "cache")},
        "machine": {"platform": platform.platform(), "processor": platform.processor(),
                    "cpus": os.cpu_count(), "python": platform.python_version()},
    }


def compare_scene(scene: Scene, *, method: Method | None = None,
                  options: CompareOptions = CompareOptions()) -> SceneComparison:
    """Render ``scene`` with ``method`` (default: the ``paper`` preset) and the
    reference, and compare (see the module docstring)."""
    method = method or load_method("paper")
    scene = method.configure(scene)
    if not method.studies:
        return _compare_other(scene, method, options)
    reference, independent = _references(scene, options)
    with RealtimeRunner(scene, repeats=options.repeats) as runner:
        frame, frame_time = runner.timed()
        result = frame.result
        gl_renderer = runner.ctx.info.get("GL_RENDERER", "unknown")
        views, camera_note = _views(scene, runner.geometry, result, reference, independent)
        metrics, images, exposure, files = _score_views(views)
        images.update(_reference_variance(reference, views))

        convergence = cost = speedup = speedup_point = speedup_cold = timing = None
        claims, verdicts = {}, ()
        ref0 = reference.receivers[0].irradiance
        caustic0 = caustic_region(ref0)
        studies = set(options.studies)
        max_iterations = min(options.max_iterations, 4) if options.quick else options.max_iterations
        if "convergence" in studies:
            total = 6 * (max_iterations + 1)
            bar, tick = _progress_bar(total, options.progress, f"{scene.name}: convergence")
            convergence = convergence_study(runner, ref0, caustic0, max_iterations=max_iterations,
                                            exposure=exposure_for(ref0), progress=tick)
            if bar is not None:
                bar.close()
            claims, verdicts = paper_claims(convergence, runner=runner,
                                            reference=reference.receivers[0], caustic=caustic0)
        if "cost" in studies:
            total = sweep_size(runner.settings, quick=options.quick)
            bar, tick = _progress_bar(total, options.progress, f"{scene.name}: cost sweep")
            outcome = cost_study(
                runner, ref0, caustic0, reference_photons=int(reference.metadata["photons"]),
                quick=options.quick, progress=tick)
            cost, speedup, speedup_point = outcome.table, outcome.warm, outcome.point
            speedup_cold, timing = outcome.cold, outcome.timing()
            if bar is not None:
                bar.close()
        temporal = _temporal(scene, method, options, runner.ctx)
        decomposition = _decomposition(runner, reference, metrics, options)
        if decomposition is not None:
            claims |= decomposition.claims

    stability = stability_summary(scene, runner.geometry, result, convergence,
                                  hits=frame.hits)
    provenance = {
        "scene_file": scene.source,
        "caustics_mapping": {
            "preset": result.metadata.get("preset"),
            "passes": result.metadata.get("passes"),
            "timings_ms": {k: v * 1e3 for k, v in result.timings.items()},
            "frame_time_ms": frame_time * 1e3,
            # The scope the cost study and its speedup use: the passes producing
            # the receiver maps (camera and shadow map excluded), same frames.
            "maps_time_ms": runner.median(clock=caustic_seconds) * 1e3,
            "timer": result.timer,
            "lost_splats": result.metadata.get("lost_splats"),
            "status_counts": result.metadata.get("status_counts"),
            "status_flux_fraction": result.metadata.get("status_flux_fraction"),
            "gl_renderer": gl_renderer,
        },
        **_reference_provenance(reference, independent),
    }
    if camera_note:
        provenance["camera_note"] = camera_note
    return with_headlines(SceneComparison(
        name=scene.name, description=scene.info.description, source=scene.source,
        effects=effects_of(scene), settings=asdict(scene.settings), metrics=tuple(metrics),
        images=images, exposure=exposure, convergence=convergence, cost=cost,
        speedup=speedup, speedup_cold=speedup_cold, timing=timing, claims=claims,
        provenance=provenance, files=files,
        stability=stability, speedup_point=speedup_point, method=method.name,
        method_description=method.description,
        flux_budget=flux_budget(result.metadata, stability, result.receivers,
                                reference.receivers),
        **side_budgets(scene, result, stability, reference, hits=frame.hits,
                       geometry=runner.geometry),
        claim_verdicts=verdicts, temporal=temporal, decomposition=decomposition))


def _decomposition(runner: RealtimeRunner, reference, metrics, options: CompareOptions):
    """The decomposition study when ``options.studies`` names it, else None (so a
    compare without it pays nothing); its noise floor is the measured one."""
    if "decomposition" not in options.studies:
        return None
    floor = next((m.noise_floor for m in metrics if (m.view, m.region, m.metric)
                  == ("receiver0", "caustic", "relmse")), None)
    dense = None if options.quick else options.dense_grid
    total = 4 + (dense is not None)
    bar, tick = _progress_bar(total, options.progress, f"{runner.scene.name}: decomposition")
    try:
        return decomposition_study(
            runner, reference.receivers[0], noise_floor=floor,
            options=DecompositionOptions(dense_grid=dense, repeats=options.repeats),
            progress=tick)
    finally:
        if bar is not None:
            bar.close()


