"""Per-pixel Z-test of a Monte Carlo render against a reference with variance, as
Mitsuba's render tests do it (``src/render/tests/test_renders.py``).

For each texel and channel, with the reference's variance of its mean ``var_ref``
(from K seeds) and budgets ``N_ref`` and ``N_test`` (photons over all seeds):

    var_test = var_ref · N_ref / N_test        (per-photon variance, the test's budget)
    z        = (test − reference) / √(var_test + var_ref)
    p        = 2 (1 − Φ(|z|))                  (two-sided)

Mitsuba takes the variance from the reference alone (its 32 000-spp reference gives a
precise per-sample variance) and treats the reference as exact; ours has K = 16
seeds, so its own variance ``var_ref`` is added. Texels with no variance (no photon
in any seed) get a floor: the smallest positive variance of the map, the variance of
a texel that one photon reached.

Sanitising (Mitsuba floors its variance image too): photons carry unequal weights
(the adjoint shading-normal correction, absorption), so a texel that the reference
saw rarely can catch one heavy photon in the test, far outside a normal law built
from the reference's few photons there (measured: |z| up to 880 on the bunny's dim
fringe, 1 % of the texels, none of it bias). Given the test's own variance of its
mean (``test_variance``, from its seeds), ``var_test`` is the larger of the two
estimates: the test's own spread then covers a heavy photon it caught, while the
reference's 15-degree-of-freedom estimate still sets the scale where the test's
spread is small. Power is kept: light 3 % too bright still fails (97.6 % of the
texels pass at 4 x 4 M photons on glass_sphere, 99.3 % at 4 x 1 M).

Šidák correction: n = H·W independent tests at a family-wise significance of 1 %
each pass at α = 1 − (1 − 0.01)^(1/n) (6.1e-7 for 128², i.e. |z| < 4.99). The
render passes when at least 99.75 % of the texels pass (counted over channels, as
Mitsuba counts ``count_nonzero(success) / 3``): a bias shows as a cluster of
failures, while noise alone fails a texel with probability α.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.special import erfc, erfcinv

from renderers.exr import write_exr

__all__ = ["PASS_FRACTION", "SIGNIFICANCE", "ZTest", "write_failure_images", "z_test"]

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
        Signed z-score and two-sided p-value of every texel and channel.
    alpha : float
        Šidák-corrected per-texel significance level.
    pass_fraction : float
        Share of texels that pass (texel-channels passing / C / texels).
    passed : bool
        ``pass_fraction >= PASS_FRACTION``.
    """

    z: np.ndarray
    p_value: np.ndarray
    alpha: float
    pass_fraction: float
    passed: bool

    @property
    def failed_texels(self) -> np.ndarray:
        """(H, W) bool: a channel of the texel failed."""
        return np.any(self.p_value <= self.alpha, axis=-1)

    def summary(self) -> str:
        """One line: pass fraction, bound, α and the largest |z|."""
        return (f"{self.pass_fraction:.4%} of texels pass (need {PASS_FRACTION:.2%}); "
                f"alpha {self.alpha:.3g} (|z| < {_z_of(self.alpha):.2f}); "
                f"max |z| {float(np.max(np.abs(self.z))):.2f}")


def _z_of(alpha: float) -> float:
    """|z| at which the two-sided p-value equals ``alpha``: p = erfc(|z| / √2)
    (as :func:`z_test` computes it), so |z| = √2 erfcinv(alpha)."""
    return float(np.sqrt(2.0) * erfcinv(alpha))


def z_test(test: np.ndarray, reference: np.ndarray, reference_variance: np.ndarray, *,
           test_photons: float, reference_photons: float,
           test_variance: np.ndarray | None = None,
           significance: float = SIGNIFICANCE) -> ZTest:
    """Z-test ``test`` against ``reference`` (see the module docstring).

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
    """
    test = np.asarray(test, np.float64)
    reference = np.asarray(reference, np.float64)
    var_ref = np.asarray(reference_variance, np.float64)
    if test.shape != reference.shape or var_ref.shape != reference.shape:
        raise ValueError(f"shapes differ: test {test.shape}, reference {reference.shape}, "
                         f"variance {var_ref.shape}")
    positive = var_ref[var_ref > 0]
    floor = float(positive.min()) if positive.size else 1e-300
    var_ref = np.maximum(var_ref, floor)
    var_test = var_ref * (reference_photons / test_photons)
    if test_variance is not None:
        var_test = np.maximum(var_test, np.asarray(test_variance, np.float64))
    var = var_test + var_ref
    z = (test - reference) / np.sqrt(var)
    p_value = erfc(np.abs(z) / np.sqrt(2.0))
    texels = test.shape[0] * test.shape[1]
    alpha = 1.0 - (1.0 - significance) ** (1.0 / texels)
    channels = test.shape[2] if test.ndim == 3 else 1
    fraction = float(np.count_nonzero(p_value > alpha)) / channels / texels
    return ZTest(z, p_value, alpha, fraction, fraction >= PASS_FRACTION)


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
