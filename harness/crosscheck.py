"""An independent check of the reference: the same scene's receiver caustic from a
second renderer (LuxCore's light tracer), compared three ways, each with its noise.

Both sides render **full transport**: every L S+ D path (``all_specular_paths``) with
exact dielectric Fresnel on every dielectric, the transport LuxCore's glass
simulates. A scene LuxCore cannot render faithfully is refused
(:class:`renderers.luxcore.UnsupportedScene`), never approximated.

Quantities, with F(S) = sum over texels in S of E (RGB mean) times the texel area (W),
and Var F(S) the sum of the texels' variances of the mean times the area squared
(a photon lands in one texel, so texels are independent to first order):

* **total**: r = F_ref(all) / F_other(all);
* **encircled**: about the reference's flux centroid, for the radii within which
  the reference holds 5, 10, 25, 50, 75, 90, 95 % of its flux, r(R) likewise;
* **regions**: the receiver split into 8 x 8 equal blocks (1/64 each); r per block
  holding at least 1 % of the reference's flux.

The standard error of a ratio is r sqrt(Var_ref / F_ref^2 + Var_other / F_other^2).
A comparison agrees when |r - 1| is within its tolerance: 0.5 % total, 1 %
encircled, 2 % per region (docs/reference.md, "The LuxCore cross-check").
``z = (r - 1) / sigma`` says whether a miss is above noise.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from renderers.luxcore import check_supported, luxcore_version, render_receiver_caustic
from renderers.mitsuba import mitsuba_versions
from renderers.mitsuba.reference import estimate_receivers
from renderers.results import ReceiverMap, texel_centers
from reports.records import Table
from scenes import Scene, with_settings
from scenes.model import DielectricMaterial

__all__ = ["ENCIRCLED_SHARES", "REGION_GRID", "TOLERANCES", "CrossCheck", "FluxRatio",
           "compare_maps", "full_transport", "run_crosscheck"]

#: Shares of the reference's caustic flux that set the encircled-flux radii.
ENCIRCLED_SHARES = (0.05, 0.10, 0.25, 0.50, 0.75, 0.90, 0.95)
#: Blocks per side of the per-region comparison, and the smallest share compared.
REGION_GRID, REGION_MIN_SHARE = 8, 0.01
#: |ratio - 1| accepted per kind of comparison.
TOLERANCES = {"total": 0.005, "encircled": 0.01, "region": 0.02}


@dataclass(frozen=True)
class FluxRatio:
    """One flux comparison: reference over the other renderer.

    Attributes
    ----------
    kind : {"total", "encircled", "region"}
    label : str
        ``"all"``, ``"r=0.123 m"`` or ``"block (i, j)"`` (row i from vmin).
    reference, other : float
        Flux in watts (RGB mean).
    ratio, sigma : float
        reference / other and its standard error.
    share : float
        Fraction of the reference's caustic flux in this set.
    agrees : bool
        |ratio - 1| <= ``TOLERANCES[kind]``.
    """

    kind: str
    label: str
    reference: float
    other: float
    ratio: float
    sigma: float
    share: float
    agrees: bool

    @property
    def z(self) -> float:
        """(ratio - 1) / sigma: the miss in units of its noise."""
        return (self.ratio - 1.0) / self.sigma if self.sigma > 0 else float("inf")


@dataclass(frozen=True)
class CrossCheck:
    """Every comparison of one receiver, plus what was rendered and how long it took."""

    scene: str
    renderer: str
    ratios: tuple[FluxRatio, ...]
    provenance: dict

    def table(self) -> Table:
        """The comparisons as a report table (see ``SceneComparison.crosscheck``)."""
        columns = ("kind", "label", "share", "reference_w", "other_w", "ratio",
                   "deviation_pct", "sigma_pct", "z", "tolerance_pct", "agrees")
        return Table(columns, tuple(
            (r.kind, r.label, r.share, r.reference, r.other, r.ratio, 100 * (r.ratio - 1),
             100 * r.sigma, r.z, 100 * TOLERANCES[r.kind], r.agrees) for r in self.ratios))

    def of_kind(self, kind: str) -> tuple[FluxRatio, ...]:
        return tuple(r for r in self.ratios if r.kind == kind)

    @property
    def agrees(self) -> bool:
        return all(r.agrees for r in self.ratios)


def full_transport(scene: Scene) -> Scene:
    """``scene`` with every L S+ D path counted and Fresnel on every dielectric."""
    objects = tuple(
        dataclasses.replace(o, material=dataclasses.replace(o.material, fresnel=True))
        if isinstance(getattr(o, "material", None), DielectricMaterial) else o
        for o in scene.objects)
    return with_settings(dataclasses.replace(scene, objects=objects),
                         {"all_specular_paths": True})


def _flux(rmap: ReceiverMap, mask: np.ndarray) -> tuple[float, float]:
    """F(mask) in W and its variance (W^2), from the RGB mean of E and its variance."""
    area = rmap.texel_area()
    value = float(rmap.irradiance.mean(axis=-1)[mask].sum() * area)
    if rmap.variance is None:
        return value, 0.0
    # Var of the RGB mean per texel: channels come from the same photons, so they
    # are fully correlated; the mean's variance is at most the mean of variances.
    var = float(rmap.variance.mean(axis=-1)[mask].sum() * area * area)
    return value, var


def _ratio(kind: str, label: str, reference: ReceiverMap, other: ReceiverMap, *,
           mask: np.ndarray, total: float) -> FluxRatio:
    a, va = _flux(reference, mask)
    b, vb = _flux(other, mask)
    ratio = a / b if b > 0 else float("inf")
    sigma = abs(ratio) * float(np.sqrt(va / a**2 + vb / b**2)) if a > 0 and b > 0 \
        else float("inf")
    return FluxRatio(kind, label, a, b, ratio, sigma, a / total if total > 0 else 0.0,
                     bool(abs(ratio - 1.0) <= TOLERANCES[kind]))


def compare_maps(reference: ReceiverMap, other: ReceiverMap) -> tuple[FluxRatio, ...]:
    """Total, encircled and per-region flux ratios of two maps over the same extent.

    Raises
    ------
    ValueError
        The maps differ in shape or extent, or the reference holds no caustic flux.
    """
    if reference.irradiance.shape != other.irradiance.shape or not np.allclose(
            reference.extent, other.extent):
        raise ValueError(f"maps differ: {reference.irradiance.shape} over {reference.extent} "
                         f"vs {other.irradiance.shape} over {other.extent}")
    everything = np.ones(reference.irradiance.shape[:2], bool)
    total, _ = _flux(reference, everything)
    if not total > 0:
        raise ValueError("the reference holds no caustic flux")
    ratios = [_ratio("total", "all", reference, other, mask=everything, total=total)]

    u, v = np.meshgrid(*texel_centers(reference.extent, reference.irradiance.shape[:2]))
    weight = reference.irradiance.mean(axis=-1)
    cu, cv = float((weight * u).sum() / weight.sum()), float((weight * v).sum() / weight.sum())
    radius = np.hypot(u - cu, v - cv)
    order = np.argsort(radius, axis=None)
    cumulative = np.cumsum(weight.ravel()[order]) / weight.sum()
    for share in ENCIRCLED_SHARES:
        r = float(radius.ravel()[order][np.searchsorted(cumulative, share)])
        ratios.append(_ratio("encircled", f"r={r:.4g}", reference, other, mask=radius <= r,
                             total=total))

    h, w = weight.shape
    rows, cols = np.arange(h) * REGION_GRID // h, np.arange(w) * REGION_GRID // w
    block = rows[:, None] * REGION_GRID + cols[None, :]
    for index in range(REGION_GRID * REGION_GRID):
        mask = block == index
        if weight[mask].sum() / weight.sum() >= REGION_MIN_SHARE:
            ratios.append(_ratio("region", f"block ({index // REGION_GRID}, "
                                 f"{index % REGION_GRID})", reference, other, mask=mask,
                                 total=total))
    return tuple(ratios)


def run_crosscheck(scene, *, photons: int, seeds: int, other_photons: int) -> CrossCheck:
    """Render ``scene`` (full transport) with Mitsuba's photon tracer and LuxCore, and
    compare receiver 0. LuxCore's units are checked on the bare receiver first.

    Parameters
    ----------
    photons
        Mitsuba photons per seed (aimed at the caustic objects).
    seeds
        Independent seeds K on each side (variance of the mean).
    other_photons
        LuxCore light paths per film (two films, glass and black, per seed).
    """
    full = full_transport(scene)
    check_supported(full)  # one line per field LuxCore cannot render faithfully
    start = time.perf_counter()
    estimate = estimate_receivers(full, photons=photons, seeds=seeds, caustic_only=True,
                                  target_noise=1e-12)
    reference_seconds = time.perf_counter() - start
    start = time.perf_counter()
    other = render_receiver_caustic(full, photons=other_photons, seeds=seeds)
    other_seconds = time.perf_counter() - start
    ratios = compare_maps(estimate.caustic[0], other[0])
    provenance = {
        "transport": "full: all L S+ D paths, exact Fresnel on every dielectric",
        "reference": {"renderer": "mitsuba photon tracer", **mitsuba_versions(),
                      "photons_per_seed": estimate.photons, "seeds": seeds,
                      "cut_flux_fraction": estimate.cut_fraction,
                      "seconds": reference_seconds},
        "other": {"renderer": "luxcore LIGHTCPU (one thread)",
                  "pyluxcore": luxcore_version(), "photons_per_film": other_photons,
                  "seeds": seeds, "seconds": other_seconds},
        "tolerances": TOLERANCES,
    }
    return CrossCheck(scene.name, "luxcore", ratios, provenance)
