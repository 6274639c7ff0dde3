"""The method's own relMSE against the noise-free image, with its uncertainty.

A real-time image M is scored against a Monte Carlo reference R, the mean of K seeds,
whose per-texel, per-channel variance of the mean v is estimated from those seeds by
v̂ (unbiased, K − 1 degrees of freedom). The raw relMSE of M against R mixes the
method's error with the reference's noise: even the noise-free image T scores about
mean w v. What the method is accountable for is its *excess* error

    e = (1 / 3n) Σ_texels Σ_channels  w_T (M − T)²,      w_T = 1 / (T² + ε), ε = 0.01,

over the n texels of the scored region (the relMSE of :mod:`harness.metrics.scores`
with the noise-free image in place of the reference). e is conditional on the method
image: M and T are fixed, the randomness is the reference's noise. A stochastic
method's own noise is part of M and therefore part of its error.

Estimators (per texel and channel; D = M − R, D' = M − R', derivatives of
w(x) = 1 / (x² + ε) are w' = −2x / (x² + ε)², w'' = (6x² − 2ε) / (x² + ε)³)
-------------------------------------------------------------------------------

=================  ==========================================  ========================
inputs             term                                        bias left
=================  ==========================================  ========================
R, v̂ ("taylor")    h(R) − ½ h''(R) v̂ + ⅛ h''''(R) v̂² (K−1)/(K+1)  −⅓ h''' μ₃ + O(w v³/T⁴)
                   h(x) = w(x) (M − x)²
+ per-seed maps    the same + ⅓ h'''(R) k̂₃ / K²                O(h'''' κ₄ + w v³/T⁴)
R, v̂, R', v̂'       ½ [w̃(R') (D² − v̂) + w̃(R) (D'² − v̂')],      O(w v²/T²)
("split")          w̃(X) = w(X) − ½ w''(X) v̂_X
baseline           w(R) v̂ + w''(R) v̂² (K − 1)/(K + 1)            O(w'' κ₄ + w v³/T⁴)
=================  ==========================================  ========================

Why: (M − R)² has expectation (M − T)² + v, so v̂ removes the noise, but a weight taken
from the same noisy R correlates with its noise (E[w(R) (M − R)²] − w_T b² ≈
−2 b w' v + ½ w'' b² v with b = M − T: 2 % of e for a 2 % bias at 1 % relative
noise, growing as the noise does). The Taylor term removes it to second order: for
h(x) = w(x)(M − x)², E[h(R)] = h(T) + ½ h''(T) v + O(μ₃), and E[h''(R) v̂] = h''(T) v +
O(v²) because v̂ is independent of R (exactly so for Gaussian noise). The split term
takes each weight from the *other*, independent reference, so weight and residual are
independent and only the weight's curvature, E[w(X)] = w_T + ½ w'' v_X, needs the w̃
correction; averaging both halves halves the noise.

Skew: μ₃ is the third central moment of the reference's mean, ~T³/N² for N photons per
texel. E[h(R)] carries ⅙ h''' μ₃, and v̂ is not independent of R for skewed noise:
Cov(R, v̂) = μ₃ (the sample mean and variance of K seeds), so E[h''(R) v̂] carries
h''' μ₃ and the taylor term is biased by (⅙ − ½) h''' μ₃ = −⅓ h''' μ₃: for a perfect
method h''' = 6 w' ≈ −12/T³, a bias of 4/N² against a baseline of 1/N, relatively 4/N.
With the K per-seed maps (``seed_estimates``), k̂₃ = K Σ_k (x_k − x̄)³ / ((K − 1)(K − 2))
(Fisher) gives k̂₃ / K², unbiased for μ₃ (:func:`noise_structure`), and ⅓ h'''(R) k̂₃ / K²
is added. The baseline needs no such term: E[w(R) v̂] = w v + w' μ₃ + …, and a perfect
method's E[w(R) (T − R)²] carries the same w' μ₃.

Standard error (model-based, not design-based): the spread of the per-texel terms over
the region is the spread of the *bias pattern*, which is fixed, not noise; the
variance that matters is that of the estimator under the reference's noise. Linearised
in the noise η (variance v, Gaussian), a term is e_i + α η + β (η² − v) − β (v̂ − v) with
α = h'(T), β = ½ h''(T) for taylor (α = ½ h'(T) on η and on η', β = ½ w on each for
split), so

    Var = α² v + 2 β² v² K / (K − 1)        (Var v̂ = 2 v² / (K − 1), Gaussian).

At b = 0 this is the 2 v² (1 + 1/(K − 1)) of the brief's (M − R)² − v̂; at b ≠ 0 the
4 b² v term dominates. The coefficients are known only at R, and each plug-in is
corrected to second order in R's noise (E[a(R) b(R)] = a b + a' b' Cov + ½ (a'' b v_a +
a b'' v_b)): α(R)² = h'(R)² overstates α² by (h''² + h' h''') v, the first part a 100 %
error at b = 0; h''(R)² overstates h''² by (h'''² + h'' h'''') v, 72 v/T² of it at
b = 0 (h'' moves with −6η/T through d = M − R), 72 % at 10 % relative noise. Both are
subtracted, each product of variance estimates divided by its Gaussian expectation
ratio: E[v̂ v̂] / (v v) = f = 1 + 2ρ² / (K − 1), E[v̂³] / v³ = f₃ = (K + 1)(K + 3) /
(K − 1)² (3.89 at K = 4). With the per-seed maps, k̂₃'s variance (⅓ h''')² 6 v³ /
((K − 1)(K − 2) f₃) (Gaussian seeds) joins the quadratic part, and skewed noise's
covariance of the plug-ins with the variance estimates they multiply (Cov(η, v̂) = μ₃:
E[h'(R)² v̂] carries 2 h' h'' μ₃, E[h''(R)² v̂²] 4 h'' h''' v μ₃, their sign the bias's)
is removed, μ₃ taken as κ v² / T with κ pooled over the region
(:attr:`NoiseStructure.skew_ratio`; each texel's own k̂₃ is too noisy at K = 4 to
multiply into a variance). What is left is the variance's own third order (about
+20 v/T² at b = 0, Gaussian; in a one-texel simulation, model over true variance 0.97 to
1.01 under Poisson and compound-Poisson noise at 5 and 10 %, up to 1.12 for
Gaussian noise at 10 %; docs/statistics.md).

Texels and channels: the photon tracer deposits each photon in the one texel its
(u, v) falls in (nearest texel, ``renderers.mitsuba.photons``), but one launch's photons
are stratified (``renderers.mitsuba.emission``): neighbouring strata land in
neighbouring texels, so neighbouring texels' noise anticorrelates (about −0.25 at lag 1).
With the per-seed maps the pooled correlation ρ_o of each offset o within
:data:`NEIGHBOUR_RADIUS` (:func:`noise_structure`) gives the pairs' covariances,
c_ij = ρ_o σ_i σ_j, and the variance adds, over the region's pairs (both orders),
ρ_o (α_i σ_i)(α_j σ_j) − h''_i h''_j c_ij² (the linear plug-in's excess) +
2 β_i β_j c_ij² K/(K − 1) (:func:`_neighbour_variance`); without them texels are taken as
independent. A texel's channels are one unit: a white or absorbed light's photons carry
all three channels, so their noise is perfectly correlated (ρ = 1, the default); a
dispersion scene traces one pass per channel (ρ = 0). Per texel the channels' terms are
summed with covariance ρ α_c α_c' σ_c σ_c' + ρ² 2 β_c β_c' v_c v_c' K/(K − 1) (η² and v̂
of two channels correlate as ρ²), then texels are summed.

Interval: e ± t₀.₉₇₅(df) SE with Satterthwaite's df = (Σ V_i)² / Σ (V_i² / (K − 1))
(K + K' − 2 with two references), i.e. normal unless a few texels carry the variance.
``distinguishable`` when the 95 % interval excludes 0: above 0 the method is measurably
off; an interval wholly below 0 cannot come from a method (e ≥ 0) and says the
reference's variance is overstated.

Region: the scored region must come from a reference *independent* of the one scored
(:func:`harness.compare.regions.scene_caustic_region` thresholds the independent
reference). A region thresholded on R itself keeps texels where R's noise happened to
be high and drops those where it was low, so E[η | selected] ≠ 0 there and
neither v̂ nor the weight corrections see it: the excess is biased by the selection.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import gammaln, stdtrit

from harness.metrics.scores import RELMSE_EPSILON, MetricInputError, relative_mse

__all__ = ["CONFIDENCE", "ExcessError", "excess_relative_mse", "relmse_covariance",
           "relmse_variance_terms", "t_interval"]

#: Two-sided confidence of the reported interval.
CONFIDENCE = 0.95


def t_interval(estimate: float, stderr: float, dof: float = float("inf")
               ) -> tuple[float, float]:
    """The :data:`CONFIDENCE` interval estimate ± t_(1+c)/2(dof) · stderr (Student t;
    normal for infinite ``dof``)."""
    half = float(stdtrit(dof, 0.5 + CONFIDENCE / 2)) * stderr
    return estimate - half, estimate + half


@dataclass(frozen=True)
class ExcessError:
    """The method's relMSE, the reference noise's share of it, and the excess.

    Attributes
    ----------
    value : float
        Raw relMSE of the method against the reference (:func:`relative_mse`).
    baseline : float
        Expected raw relMSE of a perfect method (M = T) against this reference:
        the reference noise's share of ``value``.
    excess : float
        Unbiased estimate of the method's relMSE against the noise-free image
        (module docstring); may be slightly negative for a near-perfect method.
    excess_stderr : float
        Its model-based standard error (the reference's noise, not the bias pattern).
    excess_ci95 : tuple of float
        95 % interval (low, high), Student t with ``degrees_of_freedom``.
    distinguishable : bool
        The interval excludes 0 (above it: measurably off).
    degrees_of_freedom : float
        Satterthwaite degrees of freedom of the standard error.
    estimator : str
        ``"taylor"`` (one reference) or ``"split"`` (two independent references).
    """

    value: float
    baseline: float
    excess: float
    excess_stderr: float
    excess_ci95: tuple[float, float]
    distinguishable: bool
    degrees_of_freedom: float
    estimator: str

    def as_dict(self) -> dict:
        """Plain JSON-able fields (the names users script against in metrics.json)."""
        return {"value": self.value, "baseline": self.baseline, "excess": self.excess,
                "excess_stderr": self.excess_stderr,
                "excess_ci95": list(self.excess_ci95),
                "distinguishable": self.distinguishable,
                "degrees_of_freedom": self.degrees_of_freedom,
                "estimator": self.estimator}


def _w(x, eps):
    return 1.0 / (x * x + eps)


def _dw(x, eps):
    return -2.0 * x / (x * x + eps) ** 2


def _d2w(x, eps):
    return (6.0 * x * x - 2.0 * eps) / (x * x + eps) ** 3


def _d3w(x, eps):
    return 24.0 * x * (eps - x * x) / (x * x + eps) ** 4


def _d4w(x, eps):
    x2 = x * x
    return 24.0 * (5.0 * x2 * x2 - 10.0 * eps * x2 + eps * eps) / (x2 + eps) ** 5


def _h_derivatives(method, x, eps):
    """h(x) = w(x) (M − x)², its first, second and fourth derivatives in x
    (Leibniz: (M − x)² has derivatives −2(M − x), 2, then 0)."""
    d = method - x
    w, dw, d2w = _w(x, eps), _dw(x, eps), _d2w(x, eps)
    h = w * d * d
    h1 = dw * d * d - 2.0 * w * d
    h2 = d2w * d * d - 4.0 * dw * d + 2.0 * w
    h4 = _d4w(x, eps) * d * d - 8.0 * _d3w(x, eps) * d + 12.0 * d2w
    return h, h1, h2, h4


def _h3(method, x, eps):
    """h'''(x) = w''' d² − 6 w'' d + 6 w', d = M − x (Leibniz, as above)."""
    d = method - x
    return _d3w(x, eps) * d * d - 6.0 * _d2w(x, eps) * d + 6.0 * _dw(x, eps)


def _c4(seeds: float) -> float:
    """E[√v̂] / √v for a Gaussian variance with K − 1 degrees of freedom:
    √(2 / (K − 1)) Γ(K / 2) / Γ((K − 1) / 2) (0.921 at K = 4, 0.983 at K = 16)."""
    k = float(seeds)
    return float(np.sqrt(2.0 / (k - 1.0)) * np.exp(gammaln(k / 2.0) - gammaln((k - 1.0) / 2.0)))


@dataclass(frozen=True, eq=False)
class NoiseStructure:
    """What the per-seed maps say about the reference's noise beyond its variance.

    Attributes
    ----------
    third_moment : ndarray (H, W, C) or None
        Unbiased estimate of the third central moment (cumulant) of the reference's
        *mean* per texel and channel, k̂₃ / K² with Fisher's
        k₃ = K Σ_k (x_k − x̄)³ / ((K − 1)(K − 2)) over the K seed estimates x_k (cubed
        image units); None below K = 3 seeds.
    correlation : dict of (int, int) to float
        Pooled correlation of the noise at texel offset (dy, dx) (one of each
        ± pair, dy ≥ 0): Σ ĉ_ij / √(Σ v̂_i Σ v̂_j) over the pairs (i, j = i + offset)
        of the region and over channels, ĉ_ij = Σ_k (x_ik − x̄_i)(x_jk − x̄_j) /
        (K (K − 1)) the unbiased covariance of the two texels' means.
    seeds : int
        K.
    skew_ratio : float
        κ of the photon-noise relation μ₃ = κ v² / T (1 for unit-weight Poisson
        photons, E[w³] E[w] / E[w²]² for weighted ones), pooled over the region:
        Σ k̂₃ / Σ (v̂² / (R f)) with f = E[v̂²] / v² = 1 + 2 / (K − 1) (0 below K = 3
        seeds or where R has no light). The standard error takes the skew from it,
        κ v̂² / (R f), rather than from each texel's k̂₃, which at K = 4 is too noisy
        to multiply into a variance.
    """

    third_moment: np.ndarray | None
    correlation: dict
    seeds: int
    skew_ratio: float = 0.0


#: Radius (texels) of the square window of neighbour offsets whose noise covariance
#: enters the standard error. A photon lands in one texel, so the only source of
#: covariance between texels is the stratified emission of one launch: neighbouring
#: strata land in neighbouring texels, and a stratum that lands in one cannot land in
#: the next (negative correlation: about −0.25 at lag 1 in the calibration's
#: simulation, below 0.01 past one texel there; −0.16 along u and −0.24 along v on the
#: photon tracer's small glass sphere, within 0.1 of 0 at two texels). Offsets past the
#: radius are taken as uncorrelated.
NEIGHBOUR_RADIUS = 2


def _offsets(radius: int):
    """Offsets (dy, dx) of the half window: dy > 0, or dy = 0 and dx > 0."""
    return [(dy, dx) for dy in range(radius + 1) for dx in range(-radius, radius + 1)
            if dy > 0 or dx > 0]


def _pairs(array: np.ndarray, dy: int, dx: int):
    """The views (a_i, a_j) of ``array`` (H, W, ...) with j = i + (dy, dx), dy ≥ 0."""
    h, w = array.shape[:2]
    if dy >= h or abs(dx) >= w:
        return None
    xa = slice(0, w - dx) if dx >= 0 else slice(-dx, w)
    xb = slice(dx, w) if dx >= 0 else slice(0, w + dx)
    return array[0:h - dy, xa], array[dy:h, xb]


def noise_structure(seed_estimates, *, mask=None,
                    radius: int = NEIGHBOUR_RADIUS) -> NoiseStructure:
    """The reference's noise structure from its K per-seed maps (:class:`NoiseStructure`).

    Parameters
    ----------
    seed_estimates : ndarray (K, H, W, C)
        Each seed's estimate of the image (the reference is their mean; its variance
        of the mean is their unbiased variance / K).
    mask : ndarray (H, W) of bool, optional
        The region the correlations are pooled over (both texels of a pair inside it;
        default every texel). The same region the excess is scored over.
    radius : int
        Offsets up to ``radius`` texels in each direction.
    """
    x = np.asarray(seed_estimates, np.float64)
    if x.ndim != 4 or x.shape[0] < 2:
        raise MetricInputError(f"seed estimates must be (K >= 2, H, W, C), got {x.shape}")
    if not np.isfinite(x).all():
        raise MetricInputError("seed estimates must be finite")
    k = x.shape[0]
    sel = np.ones(x.shape[1:3], bool) if mask is None else np.asarray(mask, bool)
    if sel.shape != x.shape[1:3]:
        raise MetricInputError(f"mask {sel.shape} does not match {x.shape[1:3]}")
    dev = x - x.mean(axis=0)
    third = None
    if k >= 3:
        third = k * (dev**3).sum(axis=0) / ((k - 1.0) * (k - 2.0)) / (k * k)
    var = (dev * dev).sum(axis=0) / (k * (k - 1.0))  # v̂ of the mean, (H, W, C)
    correlation = {}
    for dy, dx in _offsets(int(radius)):
        pair = _pairs(np.moveaxis(dev, 0, -1), dy, dx)  # (.., C, K)
        if pair is None:
            continue
        inside = _pairs(sel, dy, dx)
        both = inside[0] & inside[1]
        if not both.any():
            continue
        va, vb = _pairs(var, dy, dx)
        cov = (pair[0][both] * pair[1][both]).sum() / (k * (k - 1.0))
        scale = np.sqrt(float(va[both].sum()) * float(vb[both].sum()))
        correlation[(dy, dx)] = float(cov / scale) if scale > 0 else 0.0
    skew = 0.0
    if third is not None:
        mean = x.mean(axis=0)
        lit = sel[..., None] & (mean > 0)
        scale = float((var[lit] ** 2 / mean[lit]).sum()) / (1.0 + 2.0 / (k - 1.0))
        skew = float(third[lit].sum()) / scale if scale > 0 else 0.0
    return NoiseStructure(third_moment=third, correlation=correlation, seeds=k,
                          skew_ratio=skew)


def _neighbour_variance(g, hh, h3, v, sel, *, noise: NoiseStructure, rho, k: float):
    """Σ over texel pairs i ≠ j of the region of the terms' covariances (both orders):
    linear ρ_o Σ_cc' P_cc' (g_ic σ_ic)(g_jc' σ_jc') with the plug-in's excess
    E[g(R_i) g(R_j)] − g_i g_j = h''_i h''_j c_ij + ½ (h'''_i g_j v_i + g_i h'''_j v_j)
    removed (h3: h''' per texel and channel), and quadratic
    2 β_i β_j c_ij² K / (K − 1) per channel pair (β = ½ h'', Cov of η² − v̂ for
    Gaussian noise), c_ij = ρ_o P_cc' σ_ic σ_jc' with ρ_o the pooled correlation of the
    offset and P the channels' correlation. E[σ̂_i σ̂_j] = c₄² σ_i σ_j (independent
    variance estimates) is divided out."""
    s = np.sqrt(v)
    c4sq = _c4(k) ** 2
    linear = quadratic = 0.0
    for (dy, dx), r in noise.correlation.items():
        if r == 0.0:
            continue
        inside = _pairs(sel, dy, dx)
        both = inside[0] & inside[1]
        gs_a, gs_b = (a[both] for a in _pairs(g * s, dy, dx))  # (n, C)
        hv_a, hv_b = (a[both] for a in _pairs(hh * v, dy, dx))
        cross = np.einsum("nc,cd,nd->", gs_a, rho, gs_b) / c4sq
        # E[g(R_i) g(R_j)] − g_i g_j also carries ½ (h'''_i g_j v_i + g_i h'''_j v_j),
        # as a texel's own g(R)² does (E[σ̂³ σ̂] = c₃ c₄ σ³ σ).
        hs_a, hs_b = (a[both] for a in _pairs(h3 * s * v, dy, dx))
        cross = cross - 0.5 * (np.einsum("nc,cd,nd->", hs_a, rho, gs_b)
                               + np.einsum("nc,cd,nd->", gs_a, rho, hs_b)) / (_c3(k) * _c4(k))
        plug = np.einsum("nc,cd,nd->", hv_a, rho * rho, hv_b)
        linear += 2.0 * (r * cross - r * r * plug)
        quadratic += 2.0 * 0.5 * r * r * plug * k / (k - 1.0)
    return float(linear), float(quadratic)


def _c3(seeds: float) -> float:
    """E[v̂^(3/2)] / v^(3/2) for a Gaussian variance with n = K − 1 degrees of freedom:
    (2 / n)^(3/2) Γ((n + 3) / 2) / Γ(n / 2) (1.228 at K = 4)."""
    n = float(seeds) - 1.0
    return float((2.0 / n) ** 1.5 * np.exp(gammaln((n + 3.0) / 2.0) - gammaln(n / 2.0)))


def _triple_ratio(k: float, rho2):
    """E[v̂_a v̂_b v̂_c] / (v_a v_b v_c) for Gaussian variance estimates of K − 1 degrees
    of freedom: E[χ³_n] / n³ = (n + 2)(n + 4) / n², n = K − 1, for one channel (3.89 at
    K = 4), taken to 1 as the channels' squared correlation ρ² goes to 0 (the products
    that enter are a channel's own or those of ρ = 1 channels)."""
    return 1.0 + rho2 * ((k + 1.0) * (k + 3.0) / (k - 1.0) ** 2 - 1.0)


def _outer(a, b=None):
    """(..., C, C) products a_c b_d of two (..., C) arrays (b defaults to a)."""
    return a[..., :, None] * (a if b is None else b)[..., None, :]


def _taylor_parts(m, r, v, *, k: float, rho, epsilon: float,
                  noise: NoiseStructure | None, other=None):
    """The one-reference ("taylor") terms of method ``m`` and the model covariance of
    its terms with those of ``other`` (default ``m`` itself: their variance), per
    texel and channel pair (..., C, C), in two parts, linear and quadratic, before the
    channels' correlations are applied (module docstring, "Standard error")."""
    h, g, hh, h4 = _h_derivatives(m, r, epsilon)
    h3 = _h3(m, r, epsilon)
    # Second order removes ½ h'' v; the fourth-order remainder, E[h(R)] −
    # E[½ h''(R) v̂] − h(T) = (1/24 − 1/4) h · 3v²/3 = −⅛ h v² (Gaussian
    # μ₄ = 3v²), is added back with E[v̂²] = v² (K + 1)/(K − 1).
    terms = h - 0.5 * hh * v + 0.125 * h4 * v * v * (k - 1.0) / (k + 1.0)
    if other is None:
        g_o, hh_o, h4_o, h3_o = g, hh, h4, h3
    else:
        _, g_o, hh_o, h4_o = _h_derivatives(other, r, epsilon)
        h3_o = _h3(other, r, epsilon)
    rho2 = rho * rho
    f = 1.0 + 2.0 * rho2 / (k - 1.0)  # E[v̂_c v̂_d] / (v_c v_d), Gaussian
    f3 = _triple_ratio(k, rho2)        # E[v̂ v̂ v̂] / v³
    s = np.sqrt(v)
    ss, vv = _outer(s), _outer(v)
    va = np.broadcast_to(v[..., :, None], vv.shape)  # the first channel's v
    vb = np.broadcast_to(v[..., None, :], vv.shape)  # the second's
    # The coefficients are taken at R, not T. To second order in R's noise
    # E[a(R) b(R)] = a b + a' b' Cov + ½ (a'' b v_a + a b'' v_b): g(R)² overstates
    # g² by (h''² + g h''') v and h''(R)² overstates h''² by (h'''² + h'' h'''') v
    # (72 v/T² of h''² at b = 0, 72 % at 10 % relative noise). Both are removed.
    hh_excess = (rho * ss * _outer(h3, h3_o)
                 + 0.5 * (_outer(h4, hh_o) * va + _outer(hh, h4_o) * vb))
    g_curve = 0.5 * (_outer(h3, g_o) * va + _outer(g, h3_o) * vb)
    hh_sq = _outer(hh, hh_o) * vv / f - hh_excess * vv / f3  # h''_c h''_d v_c v_d
    linear = _outer(g, g_o) * ss - g_curve * ss / f - rho * hh_sq
    quadratic = 0.5 * hh_sq * k / (k - 1.0)
    if noise is not None and noise.third_moment is not None:
        # Skewed noise: E[h(R)] carries ⅙ h''' μ₃ and E[h''(R) v̂] carries h''' μ₃
        # (Cov(R, v̂) = μ₃ of the mean), so the term above is biased by −⅓ h''' μ₃;
        # k̂₃ is unbiased for μ₃. Its own variance, 6 v³ / ((K − 1)(K − 2)) for
        # Gaussian seeds, scaled by (⅓ h''')², joins the quadratic part.
        k3 = np.asarray(noise.third_moment, np.float64)
        if k3.shape != r.shape:
            raise MetricInputError(f"third moment {k3.shape} differs from {r.shape}")
        terms = terms + h3 * k3 / 3.0
        k3_sd = np.sqrt(6.0 * v**3 / ((k - 1.0) * (k - 2.0) * _triple_ratio(k, 1.0)))
        quadratic = quadratic + _outer(h3 / 3.0 * k3_sd, h3_o / 3.0 * k3_sd)
        # The plug-ins correlate with the variance estimates they multiply:
        # Cov(η, v̂) = μ₃, so E[g(R)² v̂] carries 2 g h'' μ₃ and E[h''(R)² v̂²]
        # 4 h'' h''' v μ₃ (their sign follows the bias: ±10 % of a texel's variance at
        # 10 % Poisson noise). μ₃ is taken as κ v² / T (NoiseStructure.skew_ratio);
        # with channels carrying the same photons (η_c = a_c ξ) the mixed moments
        # are products of the channels' cube roots q = ∛μ₃.
        lit = r > 0
        f_own = 1.0 + 2.0 / (k - 1.0)  # E[v̂²] / v² of one channel
        q = np.cbrt(np.where(lit, noise.skew_ratio * v * v
                             / (np.where(lit, r, 1.0) * f_own), 0.0))
        qa, qb = q[..., :, None], q[..., None, :]
        g_skew = _outer(g, hh_o) * qa * qb * qb + _outer(hh, g_o) * qa * qa * qb
        hh_skew = (_outer(hh, h3_o) * (va * qb**3 + vb * qb * qa * qa)
                   + _outer(h3, hh_o) * (vb * qa**3 + va * qa * qb * qb)) / f
        linear = linear - g_skew + rho * hh_skew
        quadratic = quadratic - 0.5 * hh_skew * k / (k - 1.0)
    if other is None:
        # A variance: where R's noise is so large that the corrections exceed the
        # plug-in (about 1.5 % of the texels at 10 % relative noise) the part is 0.
        quadratic = np.maximum(quadratic, 0.0)
    return terms, linear, quadratic


def _channel_rho(channels: int, rho: float) -> np.ndarray:
    """(C, C) correlation of the channels' noise: 1 on the diagonal, ρ elsewhere."""
    r = np.full((channels, channels), float(rho))
    np.fill_diagonal(r, 1.0)
    return r


def relmse_variance_terms(method, reference, variance, *, seeds: int,
                          independent=None, independent_variance=None,
                          independent_seeds: int | None = None,
                          channel_correlation: float = 1.0,
                          epsilon: float = RELMSE_EPSILON,
                          noise: NoiseStructure | None = None):
    """Per-texel excess terms and their model variances (the parts of
    :func:`excess_relative_mse`, exposed for maps and for pooling regions).

    Returns
    -------
    terms : ndarray (H, W, C)
        Per texel and channel unbiased estimates of w_T (M − T)².
    texel_variance : tuple of ndarray (H, W)
        Estimated variance of Σ_c terms at each texel, in two parts: the linear
        (α² v, after its plug-in correction; may be negative at a texel, sums are what
        count) and the quadratic (β² v² terms, positive).
    baseline : ndarray (H, W, C)
        Per texel and channel expected raw relMSE term of a perfect method.
    dof_per_texel : int
        Degrees of freedom of each texel's variance estimate.
    """
    m = np.asarray(method, np.float64)
    r = np.asarray(reference, np.float64)
    v = np.asarray(variance, np.float64)
    if seeds < 2:
        raise MetricInputError(f"a variance needs at least 2 seeds, got {seeds}")
    if not 0.0 <= channel_correlation <= 1.0:
        raise MetricInputError(f"channel_correlation must be in [0, 1], got "
                               f"{channel_correlation}")
    if v.shape != r.shape or m.shape != r.shape or r.ndim != 3:
        raise MetricInputError(f"expected equal (H, W, C) arrays, got method {m.shape}, "
                               f"reference {r.shape}, variance {v.shape}")
    if (v < 0).any() or not np.isfinite(v).all():
        raise MetricInputError("variance must be finite and non-negative")
    k = float(seeds)
    rho = _channel_rho(r.shape[2], channel_correlation)
    rho2 = rho * rho
    baseline = _w(r, epsilon) * v + _d2w(r, epsilon) * v * v * (k - 1.0) / (k + 1.0)

    if independent is None:
        terms, linear, quadratic = _taylor_parts(m, r, v, k=k, rho=rho,
                                                 epsilon=epsilon, noise=noise)
        dof = seeds - 1
    else:
        f = 1.0 + 2.0 * rho2 / (k - 1.0)  # E[v̂_c v̂_c'] / (v_c v_c'), Gaussian
        vv, ss = _outer(v), _outer(np.sqrt(v))
        if independent_variance is None:
            raise MetricInputError("an independent reference needs its variance too")
        r2 = np.asarray(independent, np.float64)
        v2 = np.asarray(independent_variance, np.float64)
        if r2.shape != r.shape or v2.shape != r.shape:
            raise MetricInputError(f"independent reference {r2.shape} or its variance "
                                   f"{v2.shape} differ from {r.shape}")
        if (v2 < 0).any() or not np.isfinite(v2).all():
            raise MetricInputError("independent variance must be finite and non-negative")
        k2 = float(independent_seeds if independent_seeds is not None else seeds)
        if k2 < 2:
            raise MetricInputError(f"a variance needs at least 2 seeds, got {k2:g}")
        f2 = 1.0 + 2.0 * rho2 / (k2 - 1.0)

        def w_tilde(x, vx):
            return _w(x, epsilon) - 0.5 * _d2w(x, epsilon) * vx

        d, d2 = m - r, m - r2
        terms = 0.5 * (w_tilde(r2, v2) * (d * d - v) + w_tilde(r, v) * (d2 * d2 - v2))
        mean_ref = 0.5 * (r + r2)
        _, g, hh, _ = _h_derivatives(m, mean_ref, epsilon)
        g = 0.5 * g  # coefficient of η and of η'
        s2 = np.sqrt(v2)
        ss2 = s2[..., :, None] * s2[..., None, :]
        vv2 = v2[..., :, None] * v2[..., None, :]
        gg = g[..., :, None] * g[..., None, :]
        hhhh = hh[..., :, None] * hh[..., None, :]
        # Var of the mean reference's noise, squared: ((σσ + σ'σ') / 4)², estimated
        # without the bias of v̂ v̂ and v̂' v̂'.
        mean_noise2 = (vv / f + 2.0 * ss * ss2 + vv2 / f2) / 16.0
        linear = gg * (ss + ss2) - rho * hhhh * mean_noise2
        w = _w(mean_ref, epsilon)
        ww = w[..., :, None] * w[..., None, :]
        quadratic = 0.5 * ww * (vv * k / ((k - 1.0) * f) + vv2 * k2 / ((k2 - 1.0) * f2))
        dof = seeds + int(k2) - 2
    texel_linear = np.einsum("...cd,cd->...", linear, rho)
    texel_quadratic = np.einsum("...cd,cd->...", quadratic, rho2)
    return terms, (texel_linear, texel_quadratic), baseline, dof


def relmse_covariance(method_a, method_b, reference, variance, *, seeds: int, mask,
                      channel_correlation: float = 1.0,
                      epsilon: float = RELMSE_EPSILON) -> float:
    """Model covariance of the one-reference excesses of two method images scored
    against the same reference over ``mask`` (squared relMSE units): the standard
    error model of :func:`excess_relative_mse` with one method's coefficients on each
    side, without the per-seed maps' terms and before the floors that keep a variance
    positive. Its diagonal is the squared standard error of texels taken as
    independent and noise as symmetric."""
    a = np.asarray(method_a, np.float64)
    b = np.asarray(method_b, np.float64)
    r = np.asarray(reference, np.float64)
    v = np.asarray(variance, np.float64)
    sel = np.asarray(mask, bool)
    if not a.shape == b.shape == r.shape == v.shape or r.ndim != 3 or sel.shape != r.shape[:2]:
        raise MetricInputError(f"expected equal (H, W, C) arrays and an (H, W) mask, got "
                               f"{a.shape}, {b.shape}, {r.shape}, {v.shape}, {sel.shape}")
    if seeds < 2:
        raise MetricInputError(f"a variance needs at least 2 seeds, got {seeds}")
    rho = _channel_rho(r.shape[2], channel_correlation)
    _, linear, quadratic = _taylor_parts(a[sel], r[sel], v[sel], k=float(seeds), rho=rho,
                                         epsilon=epsilon, noise=None, other=b[sel])
    total = (np.einsum("ncd,cd->", linear, rho) + np.einsum("ncd,cd->", quadratic, rho * rho))
    return float(total) / float(r[sel].size) ** 2


def excess_relative_mse(method, reference, variance, *, seeds: int, mask=None,
                        independent=None, independent_variance=None,
                        independent_seeds: int | None = None,
                        channel_correlation: float = 1.0,
                        epsilon: float = RELMSE_EPSILON,
                        seed_estimates=None,
                        neighbour_radius: int = NEIGHBOUR_RADIUS) -> ExcessError:
    """The method's relMSE against the noise-free image, unbiased, with its standard
    error and 95 % interval (module docstring).

    Parameters
    ----------
    method, reference : ndarray (H, W, 3)
        The method's image and the K-seed reference mean, same linear units.
    variance : ndarray (H, W, 3)
        Unbiased estimate of the variance of the reference's mean, per channel
        (squared image units), from its ``seeds`` seeds.
    seeds : int
        K, the seeds behind ``variance`` (its degrees of freedom are K − 1).
    mask : ndarray (H, W) of bool, optional
        The scored region; it must not be derived from ``reference``
        (:func:`harness.compare.regions.scene_caustic_region`). Default: every texel.
    independent, independent_variance : ndarray (H, W, 3), optional
        A second reference on disjoint seeds and its variance of the mean: the split
        estimator (half the variance, no third-moment bias).
    independent_seeds : int, optional
        Its seeds (default ``seeds``).
    channel_correlation : float
        Correlation of one texel's channel noises: 1 when the same photons carry all
        three channels (white or absorbed light), 0 for one pass per channel
        (dispersion).
    epsilon : float
        relMSE's regulariser (squared image units).
    seed_estimates : ndarray (K, H, W, 3), optional
        The reference's K per-seed images (their mean is ``reference``, their unbiased
        variance / K is ``variance``). With them (one reference only) the term's
        third-moment bias is removed and the standard error includes the covariance
        of neighbouring texels' noise (:func:`noise_structure`, pooled over ``mask``);
        without them the noise is taken as symmetric and texels as independent.
    neighbour_radius : int
        Offsets (texels) whose covariance is included (:data:`NEIGHBOUR_RADIUS`).
    """
    value = relative_mse(method, reference, mask=mask, epsilon=epsilon)
    sel = (np.ones(np.shape(reference)[:2], bool) if mask is None
           else np.asarray(mask, bool))
    noise = None
    if seed_estimates is not None and independent is None:
        seed_estimates = np.asarray(seed_estimates)
        if seed_estimates.shape[1:] != np.shape(reference) or seed_estimates.shape[0] != seeds:
            raise MetricInputError(f"seed estimates {seed_estimates.shape} are not {seeds} "
                                   f"images of {np.shape(reference)}")
        noise = noise_structure(seed_estimates, mask=sel, radius=neighbour_radius)
    terms, (linear, quadratic), baseline, dof = relmse_variance_terms(
        method, reference, variance, seeds=seeds, independent=independent,
        independent_variance=independent_variance, independent_seeds=independent_seeds,
        channel_correlation=channel_correlation, epsilon=epsilon, noise=noise)
    count = terms[sel].size  # texels x channels, as relMSE averages
    excess = float(terms[sel].sum()) / count
    cross_linear = cross_quadratic = 0.0
    if noise is not None and noise.correlation:
        m = np.asarray(method, np.float64)
        r = np.asarray(reference, np.float64)
        _, g, hh, _ = _h_derivatives(m, r, epsilon)
        cross_linear, cross_quadratic = _neighbour_variance(
            g, hh, _h3(m, r, epsilon), np.asarray(variance, np.float64), sel, noise=noise,
            rho=_channel_rho(r.shape[2], channel_correlation), k=float(seeds))
    # The linear part's plug-in correction assumes the stated channel correlation; if
    # the channels are in fact less correlated it overshoots and the part's sum goes
    # negative, about −100 % of the quadratic part for a wrong ρ = 1 at b = 0; with a
    # correct one it is about 0 there. So the sum (not each texel, which would bias a
    # correct specification upwards) is floored at −½ of the quadratic part: a wrong
    # ρ = 1 keeps half the quadratic part's (then overstated) variance rather than none.
    texel_var = linear[sel] + quadratic[sel]
    quadratic_total = float(quadratic[sel].sum()) + cross_quadratic
    total = (max(float(linear[sel].sum()) + cross_linear, -0.5 * quadratic_total)
             + quadratic_total)
    stderr = float(np.sqrt(max(total, 0.0))) / count
    spread = float(np.sum(texel_var**2))
    df = total**2 / (spread / dof) if spread > 0 and total > 0 else float("inf")
    low, high = t_interval(excess, stderr, df)
    return ExcessError(
        value=value, baseline=float(baseline[sel].sum()) / count, excess=excess,
        excess_stderr=stderr, excess_ci95=(low, high),
        distinguishable=bool(stderr > 0 and (low > 0 or high < 0)),
        degrees_of_freedom=float(df),
        estimator="taylor" if independent is None else "split")
