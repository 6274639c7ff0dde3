"""Method targets: what a method should reach on a scene, each with the reason for
its number (``data/method_targets.toml``). A target the method misses today carries a
``gap`` naming what is missing: it is reported as a known gap (an ``xfail`` in the
test suite), never loosened. Targets hold at the scene's own settings against a
reference at its own budget: ``caustics compare`` checks them only for a committed
scene run without setting overrides.

Measures (the keys of :data:`harness.checks.bounds.MEASURES`), each of the receiver
map named by the target's ``view``:

``relmse``
    The excess relMSE (against the noise-free image, ``harness.metrics.excess``) over
    the scene's caustic region, with its 95 % interval: the comparison's own
    ``receiver0 / caustic / relmse`` record, so the check quotes the page's number.
    The check is judged from the interval (:func:`harness.checks.bounds.judge`).
``flux_ratio``
    Σ E(method) / Σ E(reference) over the map, per channel; the channel furthest
    from 1.
``focus_peak_ratio``
    Largest 3 × 3 box mean of the method's luminance over the reference's (the box
    tames the photon noise of single texels).
``focus_share_difference``
    |share of the method's luminance within 5 cm of the reference's focus − the
    reference's share|; the focus is the reference's largest 3 × 3 box mean.
``tir_flux_fraction``, ``off_receiver_flux_fraction``
    Share of the traced flux lost to total internal reflection, and splatted by
    vertices whose exact ray meets no receiver (``harness.checks.stability``).
``object_vertices``
    Grid vertices that traced an object (every status but ``empty``).
``camera_black_fraction_difference``, ``camera_object_radiance_ratio``
    The camera over a sphere against its exact lens image (view ``camera``;
    :mod:`harness.checks.camera`).
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import uniform_filter

from harness.checks.bounds import Target, judge
from harness.compare.evaluate import score_value
from harness.compare.uncertainty import ExcessInputs, metric_excess
from reports.records import Check, MetricValue
from scenes.colour import luminance

__all__ = ["TARGET", "caustic_relmse", "check_targets", "focus_measures", "target_measures"]

TARGET = "method target"
#: Radius (m) of the focus share.
FOCUS_RADIUS = 0.05


def focus_measures(reference: np.ndarray, method: np.ndarray, extent, *,
                   radius: float = FOCUS_RADIUS) -> tuple[float, float, float, float]:
    """(reference peak, method peak, reference share, method share) (module docstring)."""
    ref, met = luminance(reference), luminance(method)
    ref_box, met_box = uniform_filter(ref, 3), uniform_filter(met, 3)
    iy, ix = np.unravel_index(np.argmax(ref_box), ref.shape)
    h, w = ref.shape
    u = extent[0] + (np.arange(w) + 0.5) / w * (extent[1] - extent[0])
    v = extent[2] + (np.arange(h) + 0.5) / h * (extent[3] - extent[2])
    near = np.hypot(*np.meshgrid(u - u[ix], v - v[iy])) <= radius
    return (float(ref_box.max()), float(met_box.max()), float(ref[near].sum() / ref.sum()),
            float(met[near].sum() / met.sum()))


def caustic_relmse(reference, method, region: np.ndarray, *, seeds: int,
                   channel_correlation: float = 1.0, view: str = "receiver0") -> MetricValue:
    """The ``caustic / relmse`` record of one receiver map, as the comparison scores it
    (the same estimator, :func:`harness.compare.uncertainty.metric_excess`), for a
    check made outside a comparison.

    Parameters
    ----------
    reference, method : ReceiverMap
        The reference (with its variance of the mean) and the method's map.
    region : ndarray (H, W) of bool
        The scene's caustic region (``harness.compare.regions.scene_caustic_region``).
    seeds : int
        K, the seeds behind the reference's variance.
    channel_correlation : float
        1 when the same photons carry all three channels, 0 for one pass per channel.
    """
    ref, met = np.asarray(reference.irradiance), np.asarray(method.irradiance)
    mask = np.asarray(region, bool)
    inputs = ExcessInputs(np.asarray(reference.variance), int(seeds), channel_correlation,
                          1.0, 0.0, 0.0, seed_estimates=reference.seed_maps)
    excess = metric_excess("relmse", met, ref, mask, inputs, maps={})
    return MetricValue(view, "caustic", "relmse",
                       score_value("relmse", met, ref, mask=mask, exposure=None),
                       pixels=int(mask.sum()), **excess)


def target_measures(reference, method, *, relmse: MetricValue | None = None,
                    stability: dict | None = None, status_counts: dict | None = None
                    ) -> tuple[dict[str, float], dict[str, tuple[float, float]]]:
    """Every measure of one receiver map (ReceiverMaps ``reference`` and ``method``)
    that the inputs allow, and the 95 % intervals of those that have one.

    Parameters
    ----------
    relmse : MetricValue, optional
        The comparison's ``caustic / relmse`` record of this map (or
        :func:`caustic_relmse`): the ``relmse`` measure is its excess and interval;
        without it (or without an excess) there is no ``relmse`` measure.
    """
    ref, met = np.asarray(reference.irradiance), np.asarray(method.irradiance)
    out, intervals = {}, {}
    if relmse is not None and relmse.excess is not None:
        out["relmse"] = float(relmse.excess)
        if relmse.excess_ci95 is not None:
            intervals["relmse"] = tuple(float(x) for x in relmse.excess_ci95)
    ref_flux, met_flux = reference.total_flux(), method.total_flux()
    lit = ref_flux > 0
    if lit.any():
        ratio = met_flux[lit] / ref_flux[lit]
        out["flux_ratio"] = float(ratio[np.argmax(np.abs(ratio - 1))])
    ref_peak, peak, ref_share, share = focus_measures(ref, met, reference.extent)
    out["focus_peak_ratio"] = peak / ref_peak if ref_peak > 0 else float("nan")
    out["focus_share_difference"] = abs(share - ref_share)
    for key in ("tir_flux_fraction", "off_receiver_flux_fraction"):
        if stability and key in stability:
            out[key] = float(stability[key])
    if status_counts:
        out["object_vertices"] = float(sum(v for k, v in status_counts.items() if k != "empty"))
    return out, intervals


def _provenance(t: Target) -> str:
    return t.reason + (f" (the {t.contrast} preset misses it)" if t.contrast else "")


def check_targets(targets, *, scene: str, method: str, measures: dict[str, float],
                  intervals: dict[str, tuple[float, float]] | None = None) -> list[Check]:
    """The targets of ``scene`` and ``method``, each judged from its measure's 95 %
    interval where ``intervals`` has one (:func:`harness.checks.bounds.judge`: holds,
    fails or undecided), else from the value; a measure the inputs did not allow is
    NaN, which fails."""
    checks = []
    intervals = intervals or {}
    for t in targets:
        if t.scene != scene or t.method != method:
            continue
        value = measures.get(t.metric, float("nan"))
        interval = intervals.get(t.metric)
        verdict = judge(t.kind, t.bound, value, interval)
        checks.append(Check(
            metric=t.metric, region=t.region, view=t.view, bound=t.bound, relation=t.kind,
            value=value, passed=verdict == "holds", origin=_provenance(t),
            kind=TARGET, gap=t.gap, interval=interval,
            verdict=verdict if interval is not None else ""))
    return checks
