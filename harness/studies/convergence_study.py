"""Convergence table: each estimator × iteration count, measured on the shader.

For every estimator (plain and safeguarded) and every iteration count 0..N, the
scene is rendered once per count; each render's per-vertex hit distances are held
against the exact ray-cast distance along the same (v, r) (``harness.raycast``),
and its receiver map against the reference. Iteration 0 is the start estimate
d = g(0): the receiver seen along the light ray through v.
"""

from __future__ import annotations

import numpy as np

from harness.compare.evaluate import score_value
from harness.metrics import MetricInputError
from harness.metrics.excess import excess_relative_mse
from harness.raycast import ReceiverTracer
from harness.studies import convergence
from harness.studies.convergence import iteration_stats, lookups_per_vertex
from harness.studies.runner import RealtimeRunner
from renderers.caustics_mapping.caustic_trace import STATUS
from renderers.caustics_mapping.lights import light_setups
from reports.records import Table

__all__ = ["COLUMNS", "CONFIGS", "convergence_study", "texel_footprint"]

CONFIGS = tuple((e, s) for e in ("modified", "newton", "secant") for s in (False, True))
COLUMNS = ("estimator", "safeguarded", "iteration", "mean_error_m", "p95_error_m",
           "max_error_m", "mean_error_texels", "p95_error_texels", "max_error_texels",
           "converged", "diverged", "oscillating", "stalled", "lost", "lookups_per_vertex",
           "relmse", "excess_relmse", "excess_low", "excess_high", "time_ms")


def texel_footprint(runner: RealtimeRunner, hits: dict, points: np.ndarray) -> np.ndarray:
    """Width (m) of one caustic-map texel at each point (:func:`.convergence.texel_footprint`
    for the runner's scene and its light setups)."""
    return convergence.texel_footprint(light_setups(runner.scene, runner.geometry),
                                       hits["light"].astype(int), points,
                                       size=runner.scene.settings.caustic_map)


def _excess(method, reference, caustic, *, variance, seeds, rho, seed_maps
            ) -> tuple[float, float, float]:
    """(excess relMSE, its 95 % interval's low and high end), NaN where it cannot be
    estimated (no variance, fewer than two seeds, an empty region)."""
    if variance is None or seeds is None or seeds < 2 or not np.asarray(caustic).any():
        return (float("nan"),) * 3
    try:
        e = excess_relative_mse(method, reference, variance, seeds=seeds, mask=caustic,
                                channel_correlation=rho, seed_estimates=seed_maps)
    except MetricInputError:
        return (float("nan"),) * 3
    return e.excess, *e.excess_ci95


def convergence_study(runner: RealtimeRunner, reference: np.ndarray, caustic: np.ndarray, *,
                      max_iterations: int = 8, configs=CONFIGS, exposure=None,
                      variance: np.ndarray | None = None, seeds: int | None = None,
                      channel_correlation: float = 1.0, seed_maps: np.ndarray | None = None,
                      progress=None) -> Table:
    """The convergence table (columns :data:`COLUMNS`).

    Parameters
    ----------
    reference
        Reference caustic irradiance of receiver 0, (H, W, 3) W/m².
    caustic
        Boolean (H, W): the scene's caustic region of receiver 0
        (``harness.compare.regions.scene_caustic_region``), where relMSE is scored;
        the same texels as the comparison's ``receiver0 / caustic`` records.
    variance, seeds
        The reference's variance of the mean per texel and channel ((W/m²)²) and its
        K seeds: the excess relMSE (``harness.metrics.excess``) and its 95 % interval
        (``excess_low``, ``excess_high``); NaN without them.
    channel_correlation
        1 when the same photons carry all three channels, 0 for one pass per channel.
    seed_maps
        The reference's per-seed maps (K, H, W, 3), used by the excess as by the
        comparison's records (``harness.metrics.excess``); None: without.
    progress
        Optional callable advanced once per render.
    """

    tracer = ReceiverTracer(runner.geometry)
    rows = []
    for estimator, safeguarded in configs:
        for k in range(max_iterations + 1):
            frame, seconds = runner.timed(estimator=estimator, safeguarded=safeguarded,
                                          iterations=k)
            hits = frame.hits
            status = hits["status"].astype(int)
            # Vertices the estimator worked on: a ray left the object (no TIR, no
            # missing exit surface) and was followed to a hit, a loss, a divergence
            # or (verified hits) an estimate that failed verification.
            traced = np.isin(status, [STATUS["hit"], STATUS["lost"], STATUS["diverged"],
                                      STATUS["unconverged"]])
            exact = tracer(hits["origin"][traced], hits["direction"][traced])
            history = hits["history"][traced].astype(np.float64)
            history[status[traced] == STATUS["diverged"], -1] = np.nan
            lost = status[traced] == STATUS["lost"]
            points = np.where(np.isfinite(exact.position), exact.position,
                              hits["origin"][traced])
            footprint = texel_footprint(runner, {"light": hits["light"][traced]}, points)
            stats = iteration_stats(history, lost, exact.distance, footprint, iteration=k)
            method_map = frame.result.receivers[0].irradiance
            relmse = score_value("relmse", method_map, reference, mask=caustic,
                                 exposure=exposure)
            excess = _excess(method_map, reference, caustic, variance=variance, seeds=seeds,
                             rho=channel_correlation, seed_maps=seed_maps)
            rows.append((estimator, safeguarded, k, stats.mean_error_m, stats.p95_error_m,
                         stats.max_error_m, stats.mean_error_texels, stats.p95_error_texels,
                         stats.max_error_texels, stats.converged, stats.diverged,
                         stats.oscillating, stats.stalled, stats.lost,
                         lookups_per_vertex(estimator, k, safeguarded=safeguarded), relmse,
                         *excess, seconds * 1e3))
            if progress is not None:
                progress()
    return Table(COLUMNS, tuple(rows))
