"""Slow: the reference agrees with LuxCore, an independent light tracer, on the
caustic of glass_sphere and the bunny with full transport (physical requirement:
the same light paths, rendered twice, give the same flux within noise).

Two demands (docs/reference.md, "The LuxCore cross-check"):

* agreement within noise: every comparison's z = (ratio - 1) / sigma within the
  two-sided critical value at a family-wise 1 % (Sidak over all comparisons);
* the bounds (total 0.5 %, encircled 1 % at radii holding >= 5 % of the flux, 1/64
  regions holding >= 1 % within 2 %) wherever the noise is at most half the bound,
  so that a real miss would be seen. The total always qualifies: measured
  single-seed noise of LuxCore's total is 0.47 % (glass_sphere, 4M photons) and
  0.85 % (bunny, 10M), so 8 x 8M and 12 x 10M photons give about 0.12 % and 0.25 %.
  Small regions and the bunny's innermost radii stay noisier than half their bound
  at these budgets (about 1 % at the 5 % radius); they are printed as not tested
  against the bound, and the within-noise demand still holds for them.
"""

from __future__ import annotations

import importlib.util

import pytest
from scipy import stats

from harness.commands.crosscheck import run_crosscheck
from harness.crosscheck import TOLERANCES
from scenes import load_scene, resolve_scene

pytestmark = pytest.mark.slow

BUDGETS = {"glass_sphere": (8_000_000, 8), "bunny": (10_000_000, 12)}


@pytest.mark.parametrize("name", sorted(BUDGETS))
def test_reference_agrees_with_luxcore(name):
    if importlib.util.find_spec("pyluxcore") is None:
        pytest.skip("the `crosscheck` extra (pyluxcore) is not installed")
    if name == "bunny" and importlib.util.find_spec("pymeshlab") is None:
        pytest.skip("the `bunny` extra (pymeshlab) is not installed")
    photons, seeds = BUDGETS[name]
    check = run_crosscheck(load_scene(resolve_scene(name)), photons=4_000_000, seeds=seeds,
                           other_photons=photons)
    total = check.of_kind("total")[0]
    print(f"\n{name}: total {total.ratio:.4f} ± {total.sigma:.4f}")
    assert total.sigma <= TOLERANCES["total"] / 2, "too noisy to test the total's bound"
    critical = stats.norm.isf((1 - (1 - 0.01) ** (1 / len(check.ratios))) / 2)
    beyond_noise = [(r.kind, r.label, round(r.z, 2)) for r in check.ratios
                    if abs(r.z) > critical]
    assert not beyond_noise, (critical, beyond_noise)
    testable = [r for r in check.ratios if r.sigma <= TOLERANCES[r.kind] / 2]
    untested = [(r.kind, r.label, round(r.sigma, 4)) for r in check.ratios if r not in testable]
    print(f"bounds not testable at this budget (sigma > bound / 2): {untested}")
    misses = [(r.kind, r.label, round(r.ratio, 4), round(r.sigma, 4)) for r in testable
              if not r.agrees]
    assert not misses, misses
    assert check.provenance["reference"]["cut_flux_fraction"] <= 1e-4
