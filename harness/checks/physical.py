"""Physical requirements: checks that do not depend on the method's output being
right, only on physics and on numbers derived from the scene.

On the method (each check name is what ``data/known_gaps.toml`` refers to):

``finite``
    Every output (camera image, receiver maps) is finite. Irradiance and radiance are
    finite by definition; a NaN or Inf is a division by zero or a lookup outside the
    receiver that reached the image. Bound: value 1 (all finite).
``non-negative``
    No output (camera image, receiver maps) holds a negative value: radiance and
    irradiance are sums of non-negative terms, so a negative value is an error in the
    method (e.g. a falloff or filter that goes negative), never noise. Bound: 0
    negative values. A method that fails it is still scored: HDR-FLIP, defined on
    non-negative images only, scores a copy of its image clamped at 0
    (:func:`harness.compare.evaluate.score_value`).
``energy``
    Caustic flux on the receivers ≤ the flux the light sends through the caustic
    objects' bounding spheres (:func:`harness.checks.stability.incident_flux_bound`).
    Bound 1 + 1e-3: float32 accumulation of ~1e4 splats (relative error ~1e-4 each,
    summed).
``flux agreement``
    Total caustic flux per channel within ``FLUX_TOLERANCE`` of the reference's, judged
    from the ratio's 95 % interval under the reference's noise (holds when the whole
    interval lies within 1 ± 2 %, fails when none of it does, else undecided; the
    channel furthest from 1 is reported). 2 %: luminance differences below
    about 1–2 % are not visible (the Weber fraction of brightness discrimination),
    while discretising the light's solid angle into G × G grid cells moves the flux
    only at the silhouette, whose cells are hit or missed at random: an expected
    relative error of about 1 / (√π D^1.5) for an object D cells across (< 0.1 % at
    D ≥ 32). A method that conserves energy has room; a method that splats rays whose
    exact path misses the receivers, or traps light the scene cannot trap, does not.
``estimator found the receiver``
    The share of the traced flux whose search ended without a verified hit although
    its exact ray meets a receiver first (``estimator_failed_flux_fraction`` of
    :func:`harness.checks.stability.search_outcomes`) is at most
    ``ESTIMATOR_FAILED_BOUND`` (1 %, half the flux agreement's tolerance): light that
    truly leaves the scene or meets the object again is physics the reference does not
    count either; light whose receiver the estimator did not find is the method's loss.
``no TIR in a sphere``
    A ray entering a sphere leaves it at the angle it was refracted to on entry,
    below the critical angle, so a sphere traps no light. Both renderers see an
    icosphere: its faces lie between the inradius r and R, so a ray entering with
    sin θ_i > r / R may be trapped; the share of the entering flux with such rays is
    the tessellation deficit (:func:`harness.checks.analytic.tessellation_deficit`),
    the bound. Applies when every object is a dielectric sphere.

On the reference (scenes the ideal-sphere answer describes, :mod:`harness.checks.analytic`):

``reference energy``
    As ``energy``, for the reference's maps.
``reference flux``
    Total flux per channel equals the ideal sphere's within 4 standard errors of the
    reference's total plus the tessellation deficit (the flux the icosphere's faces
    may miss).
``reference focus``
    The flux-weighted centroid within ``FOCUS_WINDOW`` texels of the ideal sphere's
    axis point equals the ideal sphere's centroid over the same window, within 4
    standard errors plus 0.1 texel (the icosphere's facets; measured 6e-5 texel on
    glass_sphere at 128²).
``reference profile (r texels)``
    The share of the flux within r = 1, 2, 4, 8 texels of the axis point equals the
    ideal sphere's, within 4 standard errors plus the tessellation deficit.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy.special import stdtrit

from harness.checks.analytic import (
    IdealSphereCaustic,
    ideal_sphere_caustic,
    not_applicable,
    tessellation_deficit,
)
from harness.checks.bounds import judge
from harness.checks.stability import incident_flux_bound
from reports.records import Check
from scenes.geometry import SceneGeometry
from scenes.model import DielectricMaterial, Scene, SphereObject

__all__ = [
    "CHECK_NAMES",
    "FLUX_TOLERANCE",
    "FOCUS_WINDOW",
    "PHYSICAL",
    "PROFILE_RADII",
    "apply_gaps",
    "flux_standard_error",
    "method_requirements",
    "ratio_interval",
    "reference_requirements",
    "seed_flux_interval",
    "sphere_deficit",
]

PHYSICAL = "physical requirement"
#: Allowed relative flux difference between method and reference (module docstring).
FLUX_TOLERANCE = 0.02
#: Largest share of the traced flux the estimator may leave unfound while its exact ray
#: meets a receiver: half of :data:`FLUX_TOLERANCE`.
ESTIMATOR_FAILED_BOUND = 0.01
#: Two-sided 95 % normal quantile of the flux ratio's interval.
Z95 = 1.959963984540054
#: Energy bound's allowance for float32 accumulation.
ENERGY_SLACK = 1e-3
#: Half-width (texels) of the window of the focus centroid.
FOCUS_WINDOW = 4.0
#: Allowance (texels) of the focus centroid for the icosphere's facets.
FOCUS_SLACK = 0.1
#: Radii (texels) of the encircled-flux profile.
PROFILE_RADII = (1, 2, 4, 8)
CHECK_NAMES = ("finite", "non-negative", "energy", "flux agreement", "estimator found the receiver",
               "no TIR in a sphere",
               "reference energy", "reference flux", "reference focus", "reference profile")


def _check(name: str, value: float, bound: float, kind: str, provenance: str, *,
           subject: str = "method", view: str = "all", region: str = "full",
           interval: tuple[float, float] | None = None) -> Check:
    verdict = judge(kind, bound, value, interval)
    return Check(metric=name, region=region, view=view, bound=float(bound), relation=kind,
                 value=float(value), passed=verdict == "holds", origin=provenance,
                 kind=PHYSICAL, subject=subject, interval=interval,
                 verdict=verdict if interval is not None else "")


def flux_standard_error(maps) -> np.ndarray | None:
    """Relative standard error (3,) of the total flux over ``maps`` (ReceiverMaps with
    variance; None when any lacks it): texels are independent, so the variances add."""
    if any(m.variance is None for m in maps):
        return None
    total = sum(m.total_flux() for m in maps)
    var = sum(m.variance.reshape(-1, 3).astype(np.float64).sum(axis=0) * m.texel_area() ** 2
              for m in maps)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(total > 0, np.sqrt(var) / total, np.inf)


def seed_flux_interval(maps) -> tuple[np.ndarray, float] | None:
    """Relative standard error (3,) of the total flux over ``maps`` from the spread of
    the K per-seed totals, and its K − 1 degrees of freedom; None unless every map
    keeps its per-seed maps (``ReceiverMap.seed_maps``).

    A seed's photons are stratified, so its texels' noises anticorrelate and summing
    per-texel variances overstates the total's variance (5x on glass_sphere's caustic
    region); the seeds are independent, so their totals' spread is the total's noise.
    """
    if any(getattr(m, "seed_maps", None) is None for m in maps):
        return None
    totals = sum(np.asarray(m.seed_maps, np.float64).sum(axis=(1, 2)) * m.texel_area()
                 for m in maps)
    seeds = totals.shape[0]
    if seeds < 2:
        return None
    mean = totals.mean(axis=0)
    stderr = totals.std(axis=0, ddof=1) / math.sqrt(seeds)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(mean > 0, stderr / mean, np.inf), float(seeds - 1)


def ratio_interval(ratio: float, relative_se: float, quantile: float) -> tuple[float, float]:
    """The 95 % interval of method / reference flux ``ratio`` when the reference's
    total R has relative standard error ``relative_se`` σ (the method's total fixed)
    and ``quantile`` q is the two-sided 95 % quantile of its distribution.

    The reference's own interval R (1 ± q σ) covers its mean μ as often as it says;
    the ratio's interval is its image under M / R, [r / (1 + q σ), r / (1 − q σ)],
    which covers M / μ exactly as often (its upper end unbounded where q σ ≥ 1: the
    reference's interval reaches 0). To first order in σ it is r (1 ∓ q σ); where σ is
    large the symmetric r (1 ± q σ) covers far less than 95 %
    (``tests/harness/checks/test_flux_interval.py``), and for a method that puts no
    light where the reference's few photons put some it claimed a failure the
    reference cannot show."""
    spread = quantile * relative_se
    low = ratio / (1.0 + spread)
    high = ratio / (1.0 - spread) if spread < 1.0 else math.inf
    return float(low), float(high)


def sphere_deficit(scene: Scene, geometry: SceneGeometry) -> float | None:
    """Largest tessellation deficit over the scene's objects when every one is a
    dielectric sphere (a sphere traps no light); None otherwise."""
    deficits = []
    for obj, geo in zip(scene.objects, geometry.objects, strict=True):
        if not (isinstance(obj, SphereObject) and isinstance(obj.material, DielectricMaterial)):
            return None
        deficits.append(tessellation_deficit(scene, geo.mesh.positions, geo.mesh.faces,
                                             sphere=obj))
    return max(deficits) if deficits else None


def method_requirements(scene: Scene, geometry: SceneGeometry, *, method_maps, reference_maps,
                        stability: dict, flux_se: np.ndarray | None = None,
                        flux_se_note: str = "") -> list[Check]:
    """The physical requirements on one method render (module docstring).

    ``method_maps`` and ``reference_maps`` are ReceiverMaps (the reference's with
    variance, or ``flux_se`` giving its relative standard error per channel);
    ``stability`` is :func:`harness.checks.stability.stability_summary` of the render.
    """
    checks = [
        _check("finite", 1.0 if stability.get("finite") else 0.0, 1.0, "min",
               "irradiance and radiance are finite by definition: a NaN or Inf is a "
               "division by zero or an off-receiver lookup that reached the image"),
        _check("non-negative", stability.get("negative_values", 0), 0.0, "max",
               "radiance and irradiance are sums of non-negative terms: a negative value "
               f"is the method's error (least value {stability.get('min_value', 0.0):.3g}); "
               "FLIP scores the image clamped at 0"),
        _check("energy", stability["flux_over_bound"], 1 + ENERGY_SLACK, "max",
               "receiver caustic flux / flux the light sends through the objects' bounding "
               "spheres (harness.checks.stability); 1e-3: float32 accumulation"),
    ]
    ref_flux = sum(m.total_flux() for m in reference_maps)
    met_flux = sum(m.total_flux() for m in method_maps)
    quantile = Z95
    seeded = seed_flux_interval(reference_maps)
    if seeded is not None:
        se, dof = seeded
        quantile = float(stdtrit(dof, 0.975))
        note = f"the spread of the reference's {int(dof) + 1} per-seed totals, t({dof:g})"
    else:
        se = flux_standard_error(reference_maps)
        note = "the reference's per-texel variance"
    if se is None:
        se, note = flux_se, flux_se_note or "an independent reference"
    if se is not None and np.any(ref_flux > 0):
        lit = np.flatnonzero(ref_flux > 0)
        ratio = met_flux[lit] / ref_flux[lit]
        worst = int(np.argmax(np.abs(ratio - 1)))
        interval = ratio_interval(float(ratio[worst]), float(np.asarray(se, float)[lit[worst]]),
                                  quantile)
        checks.append(_check(
            "flux agreement", ratio[worst], FLUX_TOLERANCE, "band",
            f"channel {'RGB'[lit[worst]]}: 2 % (Weber fraction of brightness; grid "
            f"discretisation < 0.1 %), judged from the ratio's 95 % interval (the "
            f"reference total's standard error {np.asarray(se, float)[lit[worst]]:.2g}, "
            f"from {note})", interval=interval))
    if "estimator_failed_flux_fraction" in stability:
        checks.append(_check(
            "estimator found the receiver", stability["estimator_failed_flux_fraction"],
            ESTIMATOR_FAILED_BOUND, "max",
            "share of the traced flux left without a verified hit although its exact ray "
            "meets a receiver first (the budget's 'estimator failed' row); 1 %: half the "
            "flux agreement's 2 %"))
    deficit = sphere_deficit(scene, geometry)
    if deficit is not None and "tir_flux_fraction" in stability:
        checks.append(_check(
            "no TIR in a sphere", stability["tir_flux_fraction"], deficit, "max",
            f"a sphere traps no light; the icosphere may trap rays entering with "
            f"sin θ_i > r_in / R: {deficit:.2g} of the entering flux (tessellation deficit)"))
    return checks


def _centre_grid(extent, shape):
    umin, umax, vmin, vmax = extent
    h, w = shape
    u = umin + (np.arange(w) + 0.5) / w * (umax - umin)
    v = vmin + (np.arange(h) + 0.5) / h * (vmax - vmin)
    return np.meshgrid(u, v), (umax - umin) / w


def _centroid(image, variance, uu, vv, window):
    """Windowed centroid (u, v) and its standard error (m) of one channel."""
    w = image * window
    total = w.sum()
    if total <= 0:
        return np.array([np.nan, np.nan]), np.inf
    c = np.array([(w * uu).sum(), (w * vv).sum()]) / total
    var = (((uu - c[0]) ** 2 + (vv - c[1]) ** 2) * variance * window).sum() / total**2
    return c, float(np.sqrt(var))


def _share(image, variance, inside):
    """Share of the flux inside the mask and its standard error."""
    a, b = image[inside].sum(), image[~inside].sum()
    t = a + b
    if t <= 0:
        return np.nan, np.inf
    var = (b * b * variance[inside].sum() + a * a * variance[~inside].sum()) / t**4
    return float(a / t), float(np.sqrt(var))


def reference_requirements(scene: Scene, geometry: SceneGeometry, reference_maps, *,
                           analytic: IdealSphereCaustic | None = None,
                           rays: int = 1536) -> list[Check]:
    """The physical requirements on a reference render (module docstring).

    ``reference_maps`` must carry variance. The ideal-sphere checks apply when
    :func:`harness.checks.analytic.not_applicable` says so; ``analytic`` may be
    passed in (it is computed at the maps' extents and sizes otherwise).
    """
    if any(m.variance is None for m in reference_maps):
        raise ValueError("the reference's checks need its variance")
    bound = incident_flux_bound(scene, geometry)
    flux = sum(m.total_flux() for m in reference_maps)
    ratio = float(np.max(np.where(bound > 0, flux / np.maximum(bound, 1e-300), 0.0)))
    checks = [_check("reference energy", ratio, 1 + ENERGY_SLACK, "max",
                     "receiver caustic flux / flux the light sends through the objects' "
                     "bounding spheres; 1e-3: float32 accumulation", subject="reference")]
    if not_applicable(scene) is not None:
        return checks
    if analytic is None:
        analytic = ideal_sphere_caustic(scene, [m.extent for m in reference_maps],
                                        [m.irradiance.shape[:2] for m in reference_maps],
                                        n=rays)
    obj = geometry.objects[0].mesh
    deficit = tessellation_deficit(scene, obj.positions, obj.faces)
    se = flux_standard_error(reference_maps)
    total_an = analytic.flux.sum(axis=0)
    lit = np.flatnonzero(total_an > 0)
    if lit.size:
        r = flux[lit] / total_an[lit]
        b = 4 * se[lit] + deficit
        k = int(np.argmax(np.abs(r - 1) / b))
        checks.append(_check(
            "reference flux", r[k], b[k], "band",
            f"channel {'RGB'[lit[k]]}: ideal sphere by ray optics "
            f"({analytic.flux.sum(axis=0)[lit[k]]:.5g} W of {analytic.entering[lit[k]]:.5g} W "
            f"entering, {analytic.rays} rays); 4 standard errors ({4 * se[lit[k]]:.2g}) + "
            f"tessellation deficit ({deficit:.2g})", subject="reference"))
    # Focus and profile on the receiver the axis meets inside its map.
    for i, (m, (fu, fv)) in enumerate(zip(reference_maps, analytic.focus, strict=True)):
        umin, umax, vmin, vmax = m.extent
        if not (math.isfinite(fu) and umin <= fu <= umax and vmin <= fv <= vmax):
            continue
        (uu, vv), texel = _centre_grid(m.extent, m.irradiance.shape[:2])
        dist = np.hypot(uu - fu, vv - fv) / texel
        window = (dist <= FOCUS_WINDOW).astype(float)
        ref, var, an = (np.asarray(a, np.float64) for a in (m.irradiance, m.variance,
                                                             analytic.maps[i]))
        worst = None
        for ch in range(3):
            if an[..., ch].sum() <= 0:
                continue
            c_ref, s_ref = _centroid(ref[..., ch], var[..., ch], uu, vv, window)
            c_an, _ = _centroid(an[..., ch], np.zeros_like(an[..., ch]), uu, vv, window)
            offset = float(np.hypot(*(c_ref - c_an))) / texel
            b = 4 * s_ref / texel + FOCUS_SLACK
            if worst is None or offset / b > worst[0] / worst[1]:
                worst = (offset, b, ch)
        if worst is None:
            continue
        checks.append(_check(
            "reference focus", worst[0], worst[1], "max",
            f"channel {'RGB'[worst[2]]}: texels between the flux centroids within "
            f"{FOCUS_WINDOW:g} texels of the ideal sphere's axis point ({fu:.4g}, {fv:.4g}) m; "
            f"4 standard errors + {FOCUS_SLACK} texel (facets)",
            subject="reference", view=f"receiver{i}", region="focus"))
        for radius in PROFILE_RADII:
            inside = dist <= radius
            worst = None
            for ch in range(3):
                if an[..., ch].sum() <= 0:
                    continue
                s_ref, s_se = _share(ref[..., ch], var[..., ch], inside)
                s_an = float(an[..., ch][inside].sum() / an[..., ch].sum())
                b = 4 * s_se + deficit
                if worst is None or abs(s_ref - s_an) / b > abs(worst[0] - worst[1]) / worst[2]:
                    worst = (s_ref, s_an, b, ch)
            s_ref, s_an, b, ch = worst
            texels = f"{radius} texel{'s' if radius > 1 else ''}"
            checks.append(_check(
                f"reference profile ({texels})", abs(s_ref - s_an), b, "max",
                f"channel {'RGB'[ch]}: |share of the flux within {texels} of the axis "
                f"point − ideal sphere's ({s_an:.4f})|; 4 standard errors + tessellation "
                f"deficit ({deficit:.2g})", subject="reference", view=f"receiver{i}",
                region="focus"))
        break
    return checks


def apply_gaps(checks, gaps, *, scene: str, method: str) -> list[Check]:
    """``checks`` with each known gap (of this scene and method) marked."""
    out = []
    for c in checks:
        reason = next((g.reason for g in gaps if g.check == c.metric and g.scene == scene
                       and g.method in (method, "*")), "")
        out.append(dataclasses.replace(c, gap=reason) if reason else c)
    return out
