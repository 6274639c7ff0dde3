"""Slow: the reference agrees with LuxCore, an independent light tracer, on the
caustic of glass_sphere and the bunny with full transport (physical requirement:
the same light paths, rendered twice, give the same flux within noise).

Bounds from the issue "The reference keeps all the light": total flux within 0.5 %,
encircled flux within 1 % at every radius holding >= 5 % of the flux, every 1/64
region holding >= 1 % of the flux within 2 %. Budgets: measured single-seed noise of
LuxCore's total flux is 0.47 % (glass_sphere, 4M photons) and 0.85 % (bunny, 10M),
so 8 x 8M and 12 x 10M photons put the total's standard error near 0.12 % and
0.25 %: at most half the 0.5 % bound, so a real miss of the bound is seen.
"""

from __future__ import annotations

import importlib.util

import pytest

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
    assert total.sigma <= TOLERANCES["total"] / 2, "too noisy to test the bound"
    misses = [(r.kind, r.label, round(r.ratio, 4), round(r.sigma, 4), round(r.share, 3))
              for r in check.ratios if not r.agrees]
    assert not misses, misses
    assert check.provenance["reference"]["cut_flux_fraction"] <= 1e-4
