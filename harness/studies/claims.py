"""The paper's two convergence claims, checked against measured numbers.

Shah et al. 2007, Section 3.4: "For a fairly uniform topology, the error is
negligible after only five iterations. For the purpose of rendering caustics, we
observed that only a single iteration is sufficient."

We make both testable:

* **five iterations**: after 5 iterations of the modified estimator, the 95th
  percentile of the hit-distance error is at most one caustic-map texel
  (``NEGLIGIBLE_TEXELS``): below what the caustic map can resolve.
* **one iteration**: the image error (relMSE of the receiver map against the
  reference) after one iteration is within ``ONE_ITERATION_MARGIN`` (10 %) of the
  error after the most iterations measured: more iterations no longer change what
  one sees.

Each check returns a sentence stating the numbers and whether the claim holds,
whichever way it falls.
"""

from __future__ import annotations

import math

__all__ = ["NEGLIGIBLE_TEXELS", "ONE_ITERATION_MARGIN", "check_five_iterations",
           "check_one_iteration"]

NEGLIGIBLE_TEXELS = 1.0
ONE_ITERATION_MARGIN = 0.10


def check_five_iterations(p95_error_texels_by_iteration: dict[int, float]) -> tuple[bool, str]:
    """Does the p95 hit error fall to ≤ 1 texel by iteration 5?"""
    if 5 not in p95_error_texels_by_iteration:
        return False, "not measured: fewer than 5 iterations were run"
    value = p95_error_texels_by_iteration[5]
    holds = math.isfinite(value) and value <= NEGLIGIBLE_TEXELS
    verdict = "holds" if holds else "does not hold"
    return holds, (f"{verdict}: p95 hit-distance error after 5 iterations is "
                   f"{value:.3g} texels (negligible means <= {NEGLIGIBLE_TEXELS:g} texel)")


def check_one_iteration(relmse_by_iteration: dict[int, float]) -> tuple[bool, str]:
    """Is the image error after 1 iteration within 10 % of the most-iterated one?"""
    if 1 not in relmse_by_iteration or len(relmse_by_iteration) < 2:
        return False, "not measured: need iteration 1 and a later one"
    last = max(relmse_by_iteration)
    one, best = relmse_by_iteration[1], relmse_by_iteration[last]
    holds = math.isfinite(one) and one <= (1 + ONE_ITERATION_MARGIN) * best
    verdict = "holds" if holds else "does not hold"
    ratio = one / best if best > 0 else math.inf
    return holds, (f"{verdict}: receiver relMSE after 1 iteration is {one:.4g}, after {last} "
                   f"it is {best:.4g} (ratio {ratio:.3f}; claim allows "
                   f"{1 + ONE_ITERATION_MARGIN:.2f})")
