"""Where the error comes from: exact light paths, then the method's approximations
swapped in one at a time, each step splatted by the method's own passes.

Steps (each a receiver map scored against the reference on receiver 0):

0. ``dense exact`` (optional): exact light paths (``harness.studies.exact_paths``)
   on a jittered lattice of ``dense_grid``² vertices per object view (one random
   sub-texel offset of the whole lattice, so the vertices still form the quads the
   triangle kernel needs), splatted with the ideal kernel. What is left is the
   reference's own noise and the splat pipeline's limit: it shows the pipeline
   converges to the reference.
1. ``exact``: exact light paths on the method's grid (the preset's object frustum,
   ``settings.grid``), splatted with the ideal kernel: flux / area triangles between
   neighbouring hits (``splat = "triangles"``). What is added is the grid's sampling
   error.
2. ``exact+kernel``: the same records splatted with the preset's kernel (``points``
   Gaussians of σ = 0.5 caustic_map / grid texels for ``paper``; ``triangles``, the
   ideal kernel itself, for ``strong``). Adds the splatting error.
3. ``image-space surfaces``: the method's own trace records (first surface from the
   front texture, exit from the back texture at ``back_resolution``, the preset's
   lookups, Wyman's image-space double refraction), with each receiver hit replaced
   by the exact hit of the same ray (v, r) on the receivers (Mitsuba, the receivers
   alone, nearest front-side hit). Adds the image-space geometry error, and what the
   exact chain drops that the method cannot see (a ray that re-enters the object
   after its exit: the exact step's ``blocked`` fate). A record the method left
   unresolved (lost, diverged, unconverged) never met the method's own tests of the
   segment to its hit (a reflected ray meeting its object again is tested at the
   estimate), so its exact hit takes the exact chain's answer: an object on the
   segment, beyond its first two grid texel widths as in the method's test, drops
   it (status ``reentered``), as the method drops it.
4. ``estimated hits``: the method itself, receiver hits from the preset's estimator
   and iteration count (its own render). With rim patches (``rim_patches`` > 1), the
   method's grid records alone, re-splatted: the method without its patches;
5. ``rim patches`` (only then): the method itself, the grid quads near the silhouette
   replaced by their patches.

Every step's records go through the same splat passes
(``renderers.caustics_mapping.record_splat``), so two steps differ only in what
their records say. The study also re-splats the method's own records through that
hook and records the largest difference from the method's map
(``notes["resplat_max_abs_difference"]``: 0 when the hook splats as the method does;
only without rim patches, whose records the hook does not take).

Numbers per step: ``relmse``, ``ssim``, ``flip`` over receiver 0's caustic region
(``harness.compare.regions``), ``flux_ratio`` over the whole map, ``peak_ratio`` (the
largest 3 × 3 box mean of the luminance, step over reference: the focus), and
``relmse_added`` = relMSE − the previous step's: the waterfall's bars, which add up
to the method's relMSE. A negative bar is a step that lowers the error (an
approximation cancelling an earlier one); the summary names every such step.

The largest error source is the step adding the most relMSE, where the ``exact``
step's share is its relMSE above the reference's own noise: above the dense step's
relMSE when step 0 ran, else above half the reference's noise floor (the truth
scores about half the relMSE an independent reference scores against the reference).

Times (``time.perf_counter``, this machine, ms): ``trace_ms`` is where the step's
records come from (exact paths: Mitsuba ray casts and the events, plus the receiver
positions pass the splat reads; image-space surfaces: the method's passes up to its
trace, plus the exact receiver casts; estimated hits: the method's passes up to its
trace), ``splat_ms`` the splat passes (caustic map, low-pass, receiver maps), each the
median of ``repeats`` runs after an untimed warm-up (step 0: one run), and
``time_ms`` their sum. The method's GL passes are timed by its own pass timer
(``ctx.finish()`` around each pass).
"""

from __future__ import annotations

import dataclasses
import math
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import uniform_filter

from harness.compare.evaluate import Exposure, exposure_for, score_value
from harness.compare.regions import caustic_region
from harness.raycast import SurfaceTracer
from harness.studies.exact_paths import ExactPaths, exact_paths
from harness.studies.runner import CAMERA_PASSES, RealtimeRunner
from harness.studies.timing import MIN_REPEATS, median_seconds
from renderers.caustics_mapping.caustic_trace import STATUS
from renderers.caustics_mapping.footprint import FALLBACK_TEXELS
from renderers.caustics_mapping.lights import light_setups
from renderers.caustics_mapping.presets import resolve_settings
from renderers.caustics_mapping.record_splat import SplattedMaps, splat_records, split_records
from reports.decomposition_records import DECOMPOSITION_COLUMNS, DecompositionRecord
from reports.records import Table
from scenes import Scene, effects_of
from scenes.colour import luminance
from scenes.errors import HarnessError
from scenes.model import ConductorMaterial, DielectricMaterial, MeshObject

__all__ = ["FIG10_CLAIM", "IDEAL_KERNEL", "SOURCES", "STEPS", "DecompositionError",
           "DecompositionOptions", "decomposition_study", "expected_noise_floor",
           "image_space_records", "peak_ratio"]

#: Step names in order (``dense exact`` only with a dense grid).
STEPS = ("dense exact", "exact", "exact+kernel", "image-space surfaces", "estimated hits",
         "rim patches")
#: What each step (but step 0) adds, in words.
SOURCES = {"exact": "grid sampling", "exact+kernel": "the splat kernel",
           "image-space surfaces": "image-space surfaces", "estimated hits": "estimated hits",
           "rim patches": "rim patches"}
#: The kernel of the exact steps: flux / area triangles between neighbouring hits.
IDEAL_KERNEL = "triangles"
#: The paper's attribution of its Fig. 10 differences (Section 5), as tested here.
FIG10_CLAIM = ("Fig. 10: the differences come mainly from the emulation of the refraction "
               "events (image-space surfaces)")
#: The passes that turn records into maps (the rest of a frame, camera and shadow map
#: aside, is where its records come from).
SPLAT_PASSES = ("caustic_map", "lowpass", "receiver_map")
#: Statuses whose records carry a ray (v, r) that left the object.
_RAY_STATUSES = ("hit", "lost", "diverged", "unconverged")


class DecompositionError(HarnessError, ValueError):
    """A scene the decomposition cannot take apart (the message says why)."""


@dataclass(frozen=True)
class DecompositionOptions:
    """How the decomposition runs.

    Attributes
    ----------
    dense_grid : int or None
        Vertices per side of step 0's lattice (≥ 1024 by default, so that exact
        paths reach the reference's noise: docs/architecture.md); None
        leaves step 0 out.
    dense_seed : int
        Seed of step 0's lattice offset.
    repeats : int
        Timed runs per step (the median is kept), after an untimed warm-up.
    """

    dense_grid: int | None = None
    dense_seed: int = 0
    repeats: int = MIN_REPEATS


@dataclass(frozen=True, eq=False)
class _Step:
    name: str
    description: str
    irradiance: np.ndarray
    trace_s: float
    splat_s: float


def peak_ratio(reference: np.ndarray, method: np.ndarray) -> float:
    """Largest 3 × 3 box mean of ``method``'s luminance over ``reference``'s (the
    focus peak; the box tames the photon noise of single texels): the measure the
    method target ``focus_peak_ratio`` uses (``harness.checks.targets``). NaN when the
    reference is black."""
    ref = float(uniform_filter(luminance(reference), 3).max())
    met = float(uniform_filter(luminance(method), 3).max())
    return met / ref if ref > 0 else float("nan")


def expected_noise_floor(reference, *, mask: np.ndarray) -> float | None:
    """The relMSE an independent reference of the same budget is expected to score
    against ``reference`` (a ``ReceiverMap`` with ``variance``, the variance of its
    mean per texel) over ``mask``: the mean of 2 var / (ref² + ε), ε = 0.01 (both
    means have that variance). Measured on glass_sphere: 0.00090 against 0.00087
    from an independent reference; bunny 0.0035 against 0.0034. None without a
    variance."""
    if reference.variance is None or not np.asarray(mask).any():
        return None
    ref = np.asarray(reference.irradiance, np.float64)
    var = np.asarray(reference.variance, np.float64)
    return float((2.0 * var / (ref**2 + 0.01))[np.asarray(mask, bool)].mean())


def _with(scene: Scene, **settings) -> Scene:
    return dataclasses.replace(scene, settings=dataclasses.replace(scene.settings, **settings))


def _splat_clock(timings: dict[str, float]) -> float:
    return float(sum(v for k, v in timings.items() if k in SPLAT_PASSES))


def _trace_clock(timings: dict[str, float]) -> float:
    return float(sum(v for k, v in timings.items()
                     if k not in SPLAT_PASSES and k not in CAMERA_PASSES))


def _splat_timed(runner: RealtimeRunner, scene: Scene, records, repeats: int
                 ) -> tuple[SplattedMaps, float, float]:
    """(maps, median splat-pass seconds, median receiver-positions seconds) over
    ``repeats`` runs after an untimed one (``repeats`` = 0: one run, timed)."""
    runs = [splat_records(scene, records, ctx=runner.ctx, geometry=runner.geometry)
            for _ in range(1 + repeats)]
    timed = runs[1:] or runs
    return (runs[-1], statistics.median(_splat_clock(r.timings) for r in timed),
            statistics.median(r.timings.get("receiver_positions", 0.0) for r in timed))


def image_space_records(hits: dict[str, np.ndarray], tracer: SurfaceTracer, scene: Scene,
                        geometry, *, blockers: SurfaceTracer | None = None
                        ) -> list[list[np.ndarray]]:
    """The method's records (``Frame.hits``) with every receiver hit exact.

    Each record whose ray (v, r) left the object (status hit, lost, diverged or
    unconverged) gets the nearest front-side receiver hit of that ray from
    ``tracer`` (built on the receivers alone): status ``hit`` there, else ``lost``.
    With ``blockers`` (a tracer with the objects), a record the method left
    unresolved whose segment from v to that hit meets an object is ``reentered``
    instead (not splatted): the method's own tests of that segment ran only on its
    verified estimates (:func:`_blocked`). Fluxes stay the method's, but for
    Beer-Lambert below an absorbing water surface, which the method takes over its
    estimated distance: it is moved to the exact one.

    Raises
    ------
    DecompositionError
        An absorbing open dielectric beside other caustic objects (the records do
        not say which object a vertex traced, so the distance correction has no K).
    """
    status = np.asarray(hits["status"])
    traced = np.isin(status, [STATUS[s] for s in _RAY_STATUSES])
    origin = np.asarray(hits["origin"], np.float64)
    direction = np.asarray(hits["direction"], np.float64)
    found = tracer(origin[traced], direction[traced])
    front = np.einsum("ij,ij->i", direction[traced], found.shading_normal) < 0
    ok = (found.kind == SurfaceTracer.RECEIVER) & front
    idx = np.flatnonzero(traced)
    dropped = np.zeros_like(ok)
    if blockers is not None:
        check = ok & (status[traced] != STATUS["hit"])
        rows = idx[check]
        skip = 2.0 * _texel_widths(scene, geometry, hits, rows, origin[rows])
        dropped[check] = _blocked(blockers, origin[rows], found.position[check],
                                  found.geometric_normal[check], skip=skip)
        ok &= ~dropped
    out = {k: np.array(v, copy=True) for k, v in hits.items()}
    out["status"][idx] = np.where(ok, STATUS["hit"],
                                  np.where(dropped, STATUS["reentered"], STATUS["lost"]))
    out["hit"][idx] = np.where(ok[:, None], found.position, origin[traced])
    out["distance"][idx] = np.where(ok, found.distance, 0.0)
    out["receiver"][idx] = np.where(ok, found.index, -1)
    out["normal"][idx] = np.where(ok[:, None], found.shading_normal, 0.0)
    sigma = _water_absorption(scene, geometry)
    if sigma is not None:
        estimated = np.maximum(np.asarray(hits["distance"], np.float64)[traced], 0.0)
        moved = np.exp(-sigma[None, :] * (out["distance"][idx] - estimated)[:, None])
        out["flux"][idx] = out["flux"][idx] * np.where(ok[:, None], moved, 1.0)
    return split_records(out)


def _blocked(blockers: SurfaceTracer, origin: np.ndarray, hit: np.ndarray,
             receiver_normal: np.ndarray, *, skip: np.ndarray) -> np.ndarray:
    """Whether an object lies on each segment from ``origin`` (on an object's
    image-space surface, m) to its receiver ``hit`` (m), farther than ``skip`` (m)
    from the origin: a ray cast back from the hit towards the origin, spawned off the
    receiver (``receiver_normal``: its geometric normal there), meets an object
    first. The origin is read from the light's textures, so it lies off the mesh by
    up to about a texel; the method's own test skips the segment's first two texel
    widths for the same reason, and so does this one."""
    segment = origin - hit
    length = np.linalg.norm(segment, axis=1)
    back = blockers(hit, segment / length[:, None], leaving=receiver_normal)
    return (back.kind == SurfaceTracer.OBJECT) & (back.distance < length - skip)


def _texel_widths(scene: Scene, geometry, hits: dict[str, np.ndarray], rows: np.ndarray,
                  origin: np.ndarray) -> np.ndarray:
    """The width (m) of one grid texel of each record's object view at its origin, as
    the trace's ``reflection_blocked`` takes it: the view's larger extent over the grid,
    times the distance from the light for a perspective view."""
    settings = resolve_settings(scene.settings)
    lights = light_setups(scene, geometry, frustum_fit=settings.frustum)
    light = np.asarray(hits["light"])[rows]
    view = np.asarray(hits["view"])[rows]
    widths = np.empty(len(rows))
    for li, vi in set(zip(light.tolist(), view.tolist(), strict=True)):
        setup = lights[li]
        frustum = setup.object_views[vi]
        x0, x1, y0, y1 = frustum.bounds
        here = (light == li) & (view == vi)
        widths[here] = max(x1 - x0, y1 - y0) / settings.grid
        if frustum.perspective:
            widths[here] *= np.linalg.norm(origin[here] - setup.position, axis=1)
    return widths


def _water_absorption(scene: Scene, geometry) -> np.ndarray | None:
    """K_a (1/m) of the one absorbing open dielectric, None without one."""
    if "absorption" not in effects_of(scene):
        return None
    caustic = [g for g in geometry.objects
               if isinstance(g.material, DielectricMaterial | ConductorMaterial)]
    water = [g for g in caustic if isinstance(g.material, DielectricMaterial)
             and not g.mesh.closed and any(k > 0 for k in g.material.absorption)]
    if not water:
        return None
    if len(caustic) > 1:
        raise DecompositionError(
            "an absorbing water surface beside other caustic objects: the image-space "
            "step cannot tell which object a record traced")
    return np.asarray(water[0].material.absorption, np.float64)


def decomposition_study(runner: RealtimeRunner, reference, *, caustic: np.ndarray | None = None,
                        noise_floor: float | None = None,
                        noise_floor_kind: str = "measured",
                        options: DecompositionOptions = DecompositionOptions(),
                        progress: Callable[[], None] | None = None) -> DecompositionRecord:
    """The decomposition of ``runner``'s scene and preset (module docstring).

    Parameters
    ----------
    runner : RealtimeRunner
        The method's scene (a preset configured), context and meshes.
    reference : ReceiverMap
        The reference's receiver 0 (irradiance W/m², (H, W, 3), and its variance).
    caustic : ndarray (H, W) of bool, optional
        The scene's caustic region (``harness.compare.regions.scene_caustic_region``),
        scored by every step; default: the reference's own (a figure with no
        independent reference).
    noise_floor : float, optional
        The reference's caustic-region relMSE noise floor; default: expected from
        the reference's variance (:func:`expected_noise_floor`).
    noise_floor_kind : str
        What ``noise_floor`` is (``measured`` or ``expected``), for the record.
    options : DecompositionOptions
    progress : callable, optional
        Advanced once per step.
    """
    start = time.perf_counter()
    tick = progress or (lambda: None)
    scene, settings, geometry = runner.scene, runner.settings, runner.geometry
    ref = np.asarray(reference.irradiance, np.float64)
    mask = caustic_region(ref) if caustic is None else np.asarray(caustic, bool)
    if noise_floor is None:
        noise_floor, noise_floor_kind = expected_noise_floor(reference, mask=mask), "expected"
    exposure = exposure_for(ref)
    repeats = max(int(options.repeats), 1)
    objects = SurfaceTracer(scene, geometry)
    receivers = SurfaceTracer(scene, geometry, objects=False)
    ideal = _with(scene, splat=IDEAL_KERNEL, splat_sigma=FALLBACK_TEXELS)
    steps: list[_Step] = []
    notes: dict = {"timer": "time.perf_counter (GL passes: ctx.finish around each)",
                   "repeats": repeats, "grid": settings.grid, "ideal_kernel": IDEAL_KERNEL,
                   "gl_renderer": runner.ctx.info.get("GL_RENDERER", "unknown")}

    paths: ExactPaths
    paths, _, trace_s = median_seconds(
        lambda: exact_paths(scene, geometry, objects), repeats=repeats)
    maps, splat_s, positions_s = _splat_timed(runner, ideal, paths.records, repeats)
    steps.append(_Step("exact", f"exact light paths on the method's {settings.grid}² grid "
                       f"({settings.frustum} object frustum), ideal kernel ({IDEAL_KERNEL})",
                       maps.receivers[0].irradiance, trace_s + positions_s, splat_s))
    tick()
    if options.dense_grid:
        n = int(options.dense_grid)
        offset = tuple(float(x) for x in np.random.default_rng(options.dense_seed)
                       .uniform(-0.5, 0.5, 2))
        dense_scene = _with(ideal, grid=n)
        dense_start = time.perf_counter()
        dense = exact_paths(dense_scene, geometry, objects, grid=n, offset=offset)
        dense_trace_s = time.perf_counter() - dense_start
        dense_maps, dense_splat_s, dense_positions_s = _splat_timed(
            runner, dense_scene, dense.records, 0)
        # Run after the exact step, whose runs compiled the kernels it reuses (its
        # one run is then warm); listed first.
        steps.insert(0, _Step(
            "dense exact", f"exact paths on a jittered {n}² lattice (offset "
            f"{offset[0]:+.3f}, {offset[1]:+.3f} texels), ideal kernel ({IDEAL_KERNEL}): "
            "reference noise and the pipeline's limit", dense_maps.receivers[0].irradiance,
            dense_trace_s + dense_positions_s, dense_splat_s))
        notes["dense"] = {"grid": n, "offset_texels": list(offset), "timed_runs": 1,
                          "fates": dense.fates,
                          "wall_s": time.perf_counter() - dense_start}
        tick()

    maps, splat_s, positions_s = _splat_timed(runner, scene, paths.records, repeats)
    kernel = settings.splat + (f", σ = {maps.splat_sigma[0]:.3g} caustic-map texels"
                               if settings.splat == "points" else "")
    steps.append(_Step("exact+kernel", f"the same exact paths, the preset's kernel ({kernel})",
                       maps.receivers[0].irradiance, trace_s + positions_s, splat_s))
    tick()

    frame, _ = runner.timed()
    method_trace_s = runner.median(clock=_trace_clock)
    method_splat_s = runner.median(clock=_splat_clock)
    image_space, _, cast_s = median_seconds(
        lambda: image_space_records(frame.hits, receivers, scene, geometry, blockers=objects),
        repeats=repeats)
    maps, splat_s, _ = _splat_timed(runner, scene, image_space, repeats)
    lookup = f"{settings.lookup} lookups, exit surface at {settings.back_resolution}²"
    steps.append(_Step("image-space surfaces", f"the method's first and exit surfaces from "
                       f"the light-space textures ({lookup}), exact receiver hits",
                       maps.receivers[0].irradiance, method_trace_s + cast_s, splat_s))
    tick()
    method_map = frame.result.receivers[0].irradiance
    estimated = (f"receiver hits from the {settings.estimator} estimator "
                 f"({'safeguarded, ' if settings.safeguarded else ''}"
                 f"{settings.iterations} iterations)")
    resplat, resplat_s, _ = _splat_timed(runner, scene, split_records(frame.hits), repeats)
    if frame.patches:
        # The grid's records alone are the method without its rim patches; the
        # patches' own trace pass is the time they add.
        rim_s = runner.median(clock=lambda timings: timings.get("rim_patches", 0.0))
        steps.append(_Step("estimated hits", f"{estimated}, the grid's records alone (no rim "
                           "patches)", resplat.receivers[0].irradiance,
                           method_trace_s - rim_s, resplat_s))
        n = settings.rim_patches
        steps.append(_Step("rim patches", f"the quads at the silhouette traced again as "
                           f"{n} x {n} patches: the method", method_map, method_trace_s,
                           method_splat_s))
        notes["rim_patches"] = {"factor": n,
                                "traced": frame.result.metadata.get("rim_patches_traced")}
    else:
        steps.append(_Step("estimated hits", f"{estimated}: the method", method_map,
                           method_trace_s, method_splat_s))
        notes["resplat_max_abs_difference"] = float(
            np.abs(resplat.receivers[0].irradiance - method_map).max())
    tick()

    table = _table(steps, ref, mask=mask, exposure=exposure)
    largest, shares = _largest(table, noise_floor)
    lower = tuple(r["step"] for r in table.records()[1:] if r["relmse_added"] < 0)
    notes |= {"shading_factor_change": paths.shading_factor_change, "exact_casts": paths.casts,
              "source_shares": shares}
    if settings.all_specular_paths:
        notes["reference_paths"] = ("the reference counts every L S+ D path; the exact "
                                    "steps follow the effects' event chains only, so the "
                                    "paths they leave out count as error of the exact step")
    claims = {}
    if _fig10_like(scene):
        claims[FIG10_CLAIM] = _fig10_verdict(table, shares, largest, settings.preset)
    return DecompositionRecord(
        table=table, summary=_summary(scene.name, settings.preset, table, shares=shares,
                                      largest=largest, lower=lower, noise_floor=noise_floor),
        largest=largest, lower=lower, noise_floor=noise_floor,
        noise_floor_kind=noise_floor_kind, run_time_s=time.perf_counter() - start,
        claims=claims, fates=paths.fates, notes=notes)


def _scores(method: np.ndarray, ref: np.ndarray, *, mask: np.ndarray,
            exposure: Exposure) -> dict[str, float]:
    method = np.asarray(method, np.float64)
    out = {m: score_value(m, method, ref, mask=mask, exposure=exposure)
           for m in ("relmse", "ssim", "flip")}
    out["flux_ratio"] = score_value("flux_ratio", method, ref, mask=np.ones(mask.shape, bool),
                                    exposure=exposure)
    out["peak_ratio"] = peak_ratio(ref, method)
    return out


def _table(steps: list[_Step], ref: np.ndarray, *, mask: np.ndarray,
           exposure: Exposure) -> Table:
    rows, previous = [], 0.0
    for step in steps:
        s = _scores(step.irradiance, ref, mask=mask, exposure=exposure)
        trace_ms, splat_ms = step.trace_s * 1e3, step.splat_s * 1e3
        rows.append({"step": step.name, "description": step.description, **s,
                     "time_ms": trace_ms + splat_ms, "relmse_previous": previous,
                     "relmse_added": s["relmse"] - previous, "trace_ms": trace_ms,
                     "splat_ms": splat_ms})
        previous = s["relmse"]
    return Table.from_records(DECOMPOSITION_COLUMNS, rows)


def _largest(table: Table, noise_floor: float | None) -> tuple[str, dict[str, float]]:
    """The step adding the most relMSE, and each source step's share (module
    docstring: the exact step counted above the reference's own noise)."""
    rows = {r["step"]: r for r in table.records()}
    if "dense exact" in rows:
        base = rows["dense exact"]["relmse"]
    else:
        base = 0.5 * noise_floor if noise_floor is not None and math.isfinite(noise_floor) \
            else 0.0
    shares = {name: (rows[name]["relmse"] - base if name == "exact"
                     else rows[name]["relmse_added"]) for name in SOURCES if name in rows}
    finite = {k: v for k, v in shares.items() if math.isfinite(v)}
    largest = max(finite, key=finite.get) if finite else "exact"
    return largest, shares


def _of_method(part: float, whole: float) -> str:
    """``70 % of the method's 0.0427`` (or just the method's value)."""
    if not (math.isfinite(part) and math.isfinite(whole)) or whole <= 0:
        return f"the method's {whole:.3g}"
    return f"{100 * part / whole:.0f} % of the method's {whole:.3g}"


def _summary(scene: str, preset: str, table: Table, *, shares: dict[str, float], largest: str,
             lower: tuple[str, ...], noise_floor: float | None) -> str:
    rows = table.records()
    total = rows[-1]["relmse"]
    chain = " → ".join(
        f"{r['step']} {r['relmse']:.3g}" + (f" ({r['relmse_added']:+.2g})" if i else "")
        for i, r in enumerate(rows))
    text = (f"{scene}, {preset} preset: the largest error source is {SOURCES[largest]} "
            f"(step '{largest}'), which adds {shares[largest]:.3g} to the caustic-region "
            f"relMSE ({_of_method(shares[largest], total)}). "
            f"Step by step: {chain}.")
    if lower:
        by_step = {r["step"]: r for r in rows}
        text += " Lower than the step before: " + "; ".join(
            _lower_text(by_step[s]) for s in lower) + "."
    else:
        text += " No step lowers the error of the step before."
    if noise_floor is not None and math.isfinite(noise_floor):
        text += f" Reference noise floor {noise_floor:.3g}"
        text += (": the method is within it, so no source is resolved above the "
                 "reference's own noise." if total <= noise_floor else ".")
    return text


def _lower_text(row: dict) -> str:
    """One step that lowers the error: by how much, and whether that is material
    (at least 1 % of the step before's relMSE)."""
    text = f"{row['step']} ({row['relmse']:.4g} after {row['relmse_previous']:.4g}"
    if abs(row["relmse_added"]) < 0.01 * abs(row["relmse_previous"]):
        return text + ", by less than 1 %: no material change)"
    return text + "; the approximations partly cancel)"


def _fig10_like(scene: Scene) -> bool:
    """The claim is the paper's about a complex refractive object (the bunny): a
    closed dielectric mesh refracting twice. (On spheres the paper says the opposite,
    that the refraction events are emulated accurately.)"""
    return "refraction.double" in effects_of(scene) and any(
        isinstance(o, MeshObject) and isinstance(o.material, DielectricMaterial)
        for o in scene.objects)


def _fig10_verdict(table: Table, shares: dict[str, float], largest: str, preset: str) -> str:
    total = table.records()[-1]["relmse"]
    mine = shares.get("image-space surfaces", float("nan"))
    if largest == "image-space surfaces" and mine > 0:
        return (f"holds ({preset} preset): image-space surfaces add {mine:.3g} to the "
                f"relMSE ({_of_method(mine, total)}), more than any other step")
    return (f"does not hold ({preset} preset): image-space surfaces add {mine:.3g} "
            f"({_of_method(mine, total)}); the largest source is {SOURCES[largest]} "
            f"({shares[largest]:+.3g}, {_of_method(shares[largest], total)})")
