"""Mitsuba reference speed on glass_sphere at 256 x 256: photons per second, and the
wall time for the K-seed photon tracer to reach 1 % relative noise in the caustic
region, traced as ``render_reference`` does (caustic maps only; goal: under 10 s
on the 2-core CI machine). Numbers are printed and stored in pytest-benchmark's
extra_info; nothing is asserted about time."""

from __future__ import annotations

import time

import numpy as np
import pytest

from harness.crosscheck import full_transport
from renderers.mitsuba import photons as module
from renderers.mitsuba.photons import PhotonTracer
from renderers.mitsuba.reference import estimate_receivers
from scenes import load_scene, with_settings

pytestmark = pytest.mark.bench


@pytest.fixture(scope="module")
def glass_sphere(request):
    return load_scene(request.config.rootpath / "scenes" / "glass_sphere.toml")


def test_photons_per_second(benchmark, glass_sphere):
    tracer = PhotonTracer(glass_sphere, resolution=(256, 256))
    tracer.trace(1 << 20, seed=99)  # compile once
    photons = 1 << 22
    benchmark.pedantic(tracer.trace, args=(photons,), kwargs={"seed": 0}, rounds=3,
                       iterations=1)
    rate = photons / benchmark.stats.stats.mean
    benchmark.extra_info["photons_per_second"] = rate
    print(f"\nglass_sphere 256x256: {rate / 1e6:.2f} M photons/s")


def test_time_to_one_percent_noise(benchmark, glass_sphere):
    def run():
        start = time.perf_counter()
        est = estimate_receivers(glass_sphere, photons=1 << 27, resolution=(256, 256),
                                 target_noise=0.01, caustic_only=True)
        return est, time.perf_counter() - start

    est, seconds = benchmark.pedantic(run, rounds=1, iterations=1)
    benchmark.extra_info.update(seconds=seconds, photons_per_seed=est.photons,
                                relative_noise=est.relative_noise, seeds=est.seeds)
    print(f"\nglass_sphere 256x256: {est.relative_noise:.4f} relative noise after "
          f"{seconds:.1f} s ({est.photons} photons x {est.seeds} seeds, {est.stopped_by})")
    assert est.stopped_by == "target_noise"


def test_cost_of_the_path_limit(request, monkeypatch):
    """Bunny, full transport (all L S+ D paths, Fresnel): photons per second with the
    old 8-event cap and the 64-event safety cap, warm (each compiled once first),
    same seeds, rounds alternating between the two so that load and clock drift hit
    both alike. The time ratio is the cost of keeping the light that long TIR chains
    carry; beside it, the extra work those chains are (ray casts with the 64-event
    cap over ray casts with the 8-event cap, counted by the tracer) and the cut flux
    fraction of each cap. The time ratio should exceed 1 by no more than the extra
    work does (docs/reference.md, "Where a path stops")."""
    pytest.importorskip("pymeshlab")
    scene = full_transport(with_settings(
        load_scene(request.config.rootpath / "scenes" / "bunny.toml"),
        {"receiver_map": [256, 256]}))
    n, caps, tracers = 1 << 21, (8, module.MAX_SPECULAR_EVENTS), {}
    for cap in caps:
        monkeypatch.setattr(module, "MAX_SPECULAR_EVENTS", cap)
        tracers[cap] = module.PhotonTracer(scene, caustic_only=True)  # reads the cap here
        tracers[cap].trace(1 << 20, seed=99)  # compile once
    times, cut, casts = {cap: [] for cap in caps}, {}, {cap: 0 for cap in caps}
    for seed in range(7):
        for cap in caps:
            start = time.perf_counter()
            sums = tracers[cap].trace(n, seed=seed)
            times[cap].append(time.perf_counter() - start)
            cut[cap] = float((sums.cut / sums.emitted).max())
            casts[cap] += sums.casts
    for cap in caps:
        rate = n / float(np.median(times[cap]))
        print(f"\nbunny full transport, cap {cap}: {rate / 1e6:.3f} M photons/s (median of 7, "
              f"warm), {casts[cap] / (7 * n):.4f} ray casts per photon, "
              f"cut flux fraction {cut[cap]:.2e}")
    ratios = np.array(times[caps[1]]) / np.array(times[caps[0]])
    work = casts[caps[1]] / casts[caps[0]]
    print(f"cap {caps[1]} / cap {caps[0]}: time ratio per round median {np.median(ratios):.3f} "
          f"(range {ratios.min():.3f}..{ratios.max():.3f}); ray-cast ratio {work:.4f}")
    benchmark_info = request.node.user_properties
    benchmark_info.append(("time_ratio_median", float(np.median(ratios))))
    benchmark_info.append(("ray_cast_ratio", work))


@pytest.mark.parametrize("name", ["glass_sphere", "bowl_sun", "bunny"])
def test_cost_of_the_leak_test(request, monkeypatch, name):
    """Caustic-only photons per second with and without the leak test
    (``photons.LEAK_TEST``: one shadow ray back along each deposited segment), warm
    (each compiled once first), same seeds, 7 rounds alternating the two; and the
    share of the caustic flux it removes (docs/reference.md, "Leaks")."""
    scene = load_scene(request.config.rootpath / "scenes" / f"{name}.toml")
    tracer, n, tests = PhotonTracer(scene, caustic_only=True), 1 << 21, (False, True)
    for test in tests:
        monkeypatch.setattr(module, "LEAK_TEST", test)
        tracer.trace(1 << 20, seed=99)  # compile once
    times, flux = {test: [] for test in tests}, {test: 0.0 for test in tests}
    for seed in range(7):
        for test in tests:
            monkeypatch.setattr(module, "LEAK_TEST", test)
            start = time.perf_counter()
            sums = tracer.trace(n, seed=seed)
            times[test].append(time.perf_counter() - start)
            flux[test] += float(sum(np.asarray(c, np.float64).sum() for c in sums.caustic))
    ratios = np.array(times[True]) / np.array(times[False])
    removed = 1.0 - flux[True] / flux[False]
    print(f"\n{name}, caustic only, {n} photons a round: leak test off "
          f"{n / np.median(times[False]) / 1e6:.3f}, on {n / np.median(times[True]) / 1e6:.3f} "
          f"M photons/s (medians of 7, warm); on / off per round median "
          f"{np.median(ratios):.3f} (range {ratios.min():.3f}..{ratios.max():.3f}); "
          f"removed {removed:.2e} of the caustic flux")
    request.node.user_properties.append(("time_ratio_median", float(np.median(ratios))))
