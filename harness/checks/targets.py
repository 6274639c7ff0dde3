"""Method targets: what a method should reach on a scene, each with the reason for
its number (``data/method_targets.toml``). A target the method misses today carries a
``gap`` naming what is missing: it is reported as a known gap (an ``xfail`` in the
test suite), never loosened. Targets hold at the scene's own settings against a
reference at its own budget: ``caustics compare`` checks them only for a committed
scene run without setting overrides.

Measures (the keys of :data:`harness.checks.bounds.MEASURES`), each of the receiver
map named by the target's ``view``:

``relmse``
    relMSE over the reference's caustic region (``reports.records.METRIC_FORMULAS``).
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

from harness.checks.bounds import Target, holds
from harness.compare.evaluate import score_value
from harness.compare.regions import caustic_region
from reports.display import luminance
from reports.records import Check

__all__ = ["TARGET", "check_targets", "focus_measures", "target_measures"]

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


def target_measures(reference, method, *, stability: dict | None = None,
                    status_counts: dict | None = None) -> dict[str, float]:
    """Every measure of one receiver map (ReceiverMaps ``reference`` and ``method``)
    that the inputs allow."""
    ref, met = np.asarray(reference.irradiance), np.asarray(method.irradiance)
    out = {"relmse": score_value("relmse", met, ref, mask=caustic_region(ref), exposure=None)}
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
    return out


def _provenance(t: Target) -> str:
    return t.reason + (f" (the {t.contrast} preset misses it)" if t.contrast else "")


def check_targets(targets, *, scene: str, method: str,
                  measures: dict[str, float]) -> list[Check]:
    """The targets of ``scene`` and ``method``; a measure the inputs did not allow
    is NaN, which fails."""
    checks = []
    for t in targets:
        if t.scene != scene or t.method != method:
            continue
        value = measures.get(t.metric, float("nan"))
        checks.append(Check(
            metric=t.metric, region=t.region, view=t.view, bound=t.bound, relation=t.kind,
            value=value, passed=holds(t.kind, t.bound, value), origin=_provenance(t),
            kind=TARGET, gap=t.gap))
    return checks
