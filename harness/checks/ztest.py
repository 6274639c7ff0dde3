"""Per-pixel test of a Monte Carlo render against a reference with variance, as
Mitsuba's render tests do it (``src/render/tests/test_renders.py``), with Student t
quantiles because both variances are estimated from few seeds.

For each texel and channel, with the reference's variance of its mean ``var_ref``
(from K_ref seeds) and budgets ``N_ref`` and ``N_test`` (photons over all seeds):

    var_test = var_ref · N_ref / N_test        (per-photon variance, the test's budget)
    t        = (test − reference) / √(var_test + var_ref)
    p        = 2 P(T_df > |t|)                 (two-sided, Student t)

Mitsuba takes the variance from the reference alone (its 32 000-spp reference gives a
precise per-sample variance) and treats the reference as exact; ours has K = 16
seeds, so its own variance ``var_ref`` is added. Texels with no variance (no photon
in any seed) get a floor: the smallest positive variance of the map, the variance of
a texel that one photon reached.

Degrees of freedom: an estimated variance with K − 1 degrees of freedom makes the
statistic t-distributed, whose tails are far heavier than the normal's at the tiny
per-test levels a family-wise rule needs (normal quantiles at 6.1e-7 per test let
noise alone fail 1.6e-4 of the tests at K = 16 and 1.6 % at K = 4). Where the
denominator is the scaled reference variance it is var_ref (1 + N_ref/N_test), one
estimate, df = K_ref − 1; where it is the test's own variance plus the reference's,
Welch–Satterthwaite gives df = (a + b)² / (a²/(K_test − 1) + b²/(K_ref − 1)). Without
seed counts the variances are taken as exact (df = ∞, normal quantiles).

Sanitising (Mitsuba floors its variance image too): photons carry unequal weights
(the adjoint shading-normal correction, absorption), so a texel that the reference
saw rarely can catch one heavy photon in the test, far outside a normal law built
from the reference's few photons there (measured: |z| up to 880 on the bunny's dim
fringe, 1 % of the texels, none of it bias). Given the test's own variance of its
mean (``test_variance``, from its seeds), ``var_test`` is the larger of the two
estimates: the test's own spread then covers a heavy photon it caught, while the
reference's 15-degree-of-freedom estimate still sets the scale where the test's
spread is small. Power is kept: light 3 % too bright still fails (97.6 % of the
texels pass at 4 x 4 M photons on glass_sphere, 99.3 % at 4 x 1 M). Taking the larger
of two estimates makes the test conservative where both are noisy: under Gaussian
noise with K_ref = 16, K_test = 4 the family-wise false-failure rate is about a fifth
of its nominal level (measured in the tests). ``variance_rule="pooled"`` pools the
two into one per-photon variance instead (Student's two-sample test: exact when the
test is the reference's estimator on other seeds, as a fresh render against its golden
reference is), ``"welch"`` takes the test's own; Welch–Satterthwaite's approximation
is poor in the far tails a family-wise level reaches when one side has few seeds
(measured: 6x its nominal rate at K_ref = 16, K_test = 4).

Multiplicity: p-values are per texel and channel, the family is the image. A texel's
channels are one unit when the same photons carry them (white or absorbed light:
``channel_correlation = 1``, the three tests are one), independent for a dispersion
scene's per-channel passes (0). The effective tests per texel are
m = 1 + (C − 1)(1 − ρ²) (C at ρ = 0, 1 at ρ = 1), and Šidák over the n·m effective
tests at a family-wise significance of 1 % gives the per-test level
α = 1 − (1 − 0.01)^(1/(n m)) (6.1e-7 for 128² at ρ = 1, i.e. |z| < 4.99 at df = ∞).

Verdicts (:class:`ZTest`):

* ``passed``: Mitsuba's rule, at least 99.75 % of the texels pass (counted over
  channels, as Mitsuba counts ``count_nonzero(success) / 3``): a bias shows as a
  cluster of failures, while noise alone fails a texel with probability α;
* ``family_wise_passed``: no texel-channel fails at α; noise alone fails this with
  probability ``significance`` (measured by simulation in the tests);
* ``global_p_value``: Σ z*² over texel-channels, z* the normal score of each p-value
  (so a t statistic counts as the normal one of the same tail probability); under the
  null each z*² is χ²₁, and with channel correlation ρ the sum has mean C n and
  variance 2 n Σ_cc' ρ_cc'², matched by a scaled χ² (Satterthwaite: g χ²_h with
  g = variance / (2 mean), h = 2 mean² / variance). It sees a bias spread thinly over
  many texels that no single texel shows.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.special import chdtrc, erfc, erfcinv, stdtr, stdtrit

from renderers.exr import write_exr

__all__ = ["PASS_FRACTION", "SIGNIFICANCE", "ZTest", "effective_tests",
           "welch_degrees_of_freedom", "write_failure_images", "z_test"]

#: Family-wise significance level of the per-texel tests (Mitsuba: 0.01).
SIGNIFICANCE = 0.01
#: Share of texels that must pass (Mitsuba: 0.9975).
PASS_FRACTION = 0.9975


@dataclass(frozen=True, eq=False)
class ZTest:
    """Outcome of :func:`z_test`.

    Attributes
    ----------
    z, p_value : ndarray (H, W, C)
        Signed statistic (a t statistic when seeds are given) and two-sided p-value of
        every texel and channel.
    alpha : float
        Šidák-corrected per-test significance level.
    pass_fraction : float
        Share of texels that pass (texel-channels passing / C / texels).
    passed : bool
        ``pass_fraction >= PASS_FRACTION`` (Mitsuba's rule).
    degrees_of_freedom : ndarray (H, W, C)
        Of each statistic (inf where the variances were taken as exact).
    family_wise_passed : bool
        No texel-channel's p-value is at or below ``alpha``.
    global_p_value : float
        p-value of Σ z*² against its null distribution (module docstring).
    """

    z: np.ndarray
    p_value: np.ndarray
    alpha: float
    pass_fraction: float
    passed: bool
    degrees_of_freedom: np.ndarray | None = None
    family_wise_passed: bool = True
    global_p_value: float = 1.0

    @property
    def failed_texels(self) -> np.ndarray:
        """(H, W) bool: a channel of the texel failed."""
        return np.any(self.p_value <= self.alpha, axis=-1)

    def summary(self) -> str:
        """One line: pass fraction, bound, α, the largest |z|, family-wise and global."""
        df = self.degrees_of_freedom
        low = float(np.min(df)) if df is not None and df.size else float("inf")
        return (f"{self.pass_fraction:.4%} of texels pass (need {PASS_FRACTION:.2%}); "
                f"alpha {self.alpha:.3g} (|z| < {_z_of(self.alpha):.2f} at df = inf, "
                f"< {_t_of(self.alpha, low):.2f} at the lowest df {low:.3g}); "
                f"max |z| {float(np.max(np.abs(self.z))):.2f}; "
                f"family-wise {'pass' if self.family_wise_passed else 'FAIL'}; "
                f"global p {self.global_p_value:.3g}")


def _z_of(alpha: float) -> float:
    """|z| at which the two-sided p-value equals ``alpha``: p = erfc(|z| / √2)
    (as :func:`z_test` computes it), so |z| = √2 erfcinv(alpha)."""
    return float(np.sqrt(2.0) * erfcinv(alpha))


def _t_of(alpha: float, df: float) -> float:
    """|t| at which the two-sided Student-t p-value with ``df`` equals ``alpha``."""
    return float(-stdtrit(df, alpha / 2)) if np.isfinite(df) else _z_of(alpha)


def effective_tests(channels: int, channel_correlation: float) -> float:
    """Effective independent tests per texel, m = 1 + (C − 1)(1 − ρ²)."""
    if not 0.0 <= channel_correlation <= 1.0:
        raise ValueError(f"channel_correlation must be in [0, 1], got {channel_correlation}")
    return 1.0 + (channels - 1) * (1.0 - channel_correlation**2)


def welch_degrees_of_freedom(a, b, df_a, df_b):
    """Welch–Satterthwaite degrees of freedom of a + b, two independent variance
    estimates with ``df_a`` and ``df_b`` degrees of freedom (inf: exact)."""
    a = np.asarray(a, np.float64)
    b = np.asarray(b, np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        spread = a * a / df_a + b * b / df_b
        df = np.where(spread > 0, (a + b) ** 2 / np.where(spread > 0, spread, 1.0), np.inf)
    return df


def _two_sided_p(z: np.ndarray, df: np.ndarray) -> np.ndarray:
    """Two-sided p-values, Student t where df is finite, normal elsewhere."""
    p = erfc(np.abs(z) / np.sqrt(2.0))
    finite = np.isfinite(df)
    if finite.any():
        p[finite] = 2.0 * stdtr(df[finite], -np.abs(z[finite]))
    return p


def _global_p(p_value: np.ndarray, channel_correlation: float) -> float:
    """p-value of Σ z*² (normal scores of the p-values) under the null, a scaled χ²."""
    channels = p_value.shape[-1] if p_value.ndim == 3 else 1
    texels = p_value.size // channels
    z_star = np.sqrt(2.0) * erfcinv(np.clip(p_value, 1e-300, 1.0))
    total = float(np.sum(z_star**2))
    rho2 = np.full((channels, channels), channel_correlation**2)
    np.fill_diagonal(rho2, 1.0)
    mean = channels * texels
    var = 2.0 * texels * float(rho2.sum())
    g, h = var / (2.0 * mean), 2.0 * mean**2 / var
    return float(chdtrc(h, total / g))


def z_test(test: np.ndarray, reference: np.ndarray, reference_variance: np.ndarray, *,
           test_photons: float, reference_photons: float,
           test_variance: np.ndarray | None = None,
           significance: float = SIGNIFICANCE,
           reference_seeds: int | None = None, test_seeds: int | None = None,
           channel_correlation: float = 1.0, variance_rule: str = "max") -> ZTest:
    """Test ``test`` against ``reference`` texel by texel (see the module docstring).

    Parameters
    ----------
    test, reference : ndarray (H, W, C)
        Mean irradiance of the render under test and of the reference (W/m²).
    reference_variance : ndarray (H, W, C)
        Variance of the reference's mean (W²/m⁴).
    test_photons, reference_photons : float
        Photons over all seeds of each (the ratio scales the variance).
    test_variance : ndarray (H, W, C), optional
        The test's own variance of its mean; where larger than the scaled
        reference variance it is used instead (module docstring).
    significance : float
        Family-wise significance level before the Šidák correction.
    reference_seeds, test_seeds : int, optional
        Seeds behind ``reference_variance`` and ``test_variance`` (K − 1 degrees of
        freedom each); None takes that variance as exact.
    channel_correlation : float
        Correlation of a texel's channel noises: 1 when one photon carries all
        three channels, 0 for one pass per channel (dispersion).
    variance_rule : {"max", "pooled", "welch"}
        With ``test_variance``: ``"max"`` takes the larger of it and the scaled
        reference variance (robust to heavy photons, conservative under Gaussian
        noise); ``"pooled"`` pools both into one per-photon variance (Student's
        two-sample test, exact when test and reference are the same estimator on
        other seeds, df = K_test + K_ref − 2); ``"welch"`` takes the test's own
        (Welch–Satterthwaite df).
    """
    test = np.asarray(test, np.float64)
    reference = np.asarray(reference, np.float64)
    var_ref = np.asarray(reference_variance, np.float64)
    if test.shape != reference.shape or var_ref.shape != reference.shape:
        raise ValueError(f"shapes differ: test {test.shape}, reference {reference.shape}, "
                         f"variance {var_ref.shape}")
    for name, seeds in (("reference_seeds", reference_seeds), ("test_seeds", test_seeds)):
        if seeds is not None and seeds < 2:
            raise ValueError(f"{name} must be at least 2 (a variance needs two seeds)")
    df_ref = float(reference_seeds - 1) if reference_seeds is not None else np.inf
    df_test = float(test_seeds - 1) if test_seeds is not None else np.inf
    positive = var_ref[var_ref > 0]
    floor = float(positive.min()) if positive.size else 1e-300
    var_ref = np.maximum(var_ref, floor)
    var_test = var_ref * (reference_photons / test_photons)
    # Where the scaled reference variance is the test's, the whole denominator is one
    # estimate, var_ref (1 + ratio), with the reference's degrees of freedom.
    df = np.full(test.shape, df_ref)
    if variance_rule not in ("max", "pooled", "welch"):
        raise ValueError(f"variance_rule must be max, pooled or welch, got {variance_rule!r}")
    if test_variance is not None:
        own = np.asarray(test_variance, np.float64)
        if variance_rule == "pooled":
            # One per-photon variance from both, in the test's units:
            # ((K_t − 1) own + (K_r − 1) var_test) / (K_t + K_r − 2).
            weight_ref = df_ref / (df_ref + df_test) if np.isfinite(df_ref + df_test) else 0.5
            var_test = (1.0 - weight_ref) * own + weight_ref * var_test
            var_ref = var_test * (test_photons / reference_photons)
            df = np.full(test.shape, df_ref + df_test)
        else:
            larger = own > var_test if variance_rule == "max" else np.ones(own.shape, bool)
            var_test = np.where(larger, own, var_test)
            df = np.where(larger, welch_degrees_of_freedom(own, var_ref, df_test, df_ref),
                          df)
    var = var_test + var_ref
    z = (test - reference) / np.sqrt(var)
    p_value = _two_sided_p(z, df)
    texels = test.shape[0] * test.shape[1]
    channels = test.shape[2] if test.ndim == 3 else 1
    tests = texels * effective_tests(channels, channel_correlation)
    alpha = 1.0 - (1.0 - significance) ** (1.0 / tests)
    fraction = float(np.count_nonzero(p_value > alpha)) / channels / texels
    return ZTest(z, p_value, alpha, fraction, fraction >= PASS_FRACTION,
                 degrees_of_freedom=df,
                 family_wise_passed=bool(np.all(p_value > alpha)),
                 global_p_value=_global_p(p_value, channel_correlation))


def write_failure_images(folder: str | Path, prefix: str, *, test: np.ndarray,
                         reference: np.ndarray, result: ZTest | None = None,
                         labels: tuple[str, str] = ("method", "reference")) -> list[Path]:
    """Write what a developer needs to see why a comparison failed, Mitsuba style:
    ``<prefix>_<label>.exr`` for both images, ``_difference.exr`` (test − reference,
    signed), and with a Z-test ``_pvalue.exr`` and ``_error.exr`` (2 % of the test
    image, failed texels set to 1, as Mitsuba writes it) plus ``_error.png`` (failed
    texels red over the grey test image). Returns the paths written."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    test = np.asarray(test, np.float32)
    reference = np.asarray(reference, np.float32)
    written = []

    def exr(name: str, image: np.ndarray) -> None:
        path = folder / f"{prefix}_{name}.exr"
        write_exr(path, {"RGB": np.asarray(image, np.float32)})
        written.append(path)

    exr(labels[0], test)
    exr(labels[1], reference)
    exr("difference", test - reference)
    if result is not None:
        exr("pvalue", result.p_value)
        error = 0.02 * test
        error[result.failed_texels] = 1.0
        exr("error", error)
        written.append(_error_png(folder / f"{prefix}_error.png", test, result.failed_texels))
    return written


def _error_png(path: Path, test: np.ndarray, failed: np.ndarray) -> Path:
    import matplotlib.image  # noqa: PLC0415 - matplotlib loads only for a failure's picture

    grey = test.mean(axis=-1)
    top = float(np.percentile(grey, 99.5)) or 1.0
    base = np.clip(grey / top, 0, 1) ** (1 / 2.2)
    rgb = np.stack([base] * 3, axis=-1)
    rgb[failed] = (1.0, 0.0, 0.0)
    matplotlib.image.imsave(path, rgb[::-1], origin="upper")  # row 0 at vmin: flip for viewing
    return path
