"""Benchmark: reading and building scenes (the fixed cost before any render).

Reported by pytest-benchmark (wall clock, time.perf_counter); compare the rows of one
run as ratios, e.g. bunny geometry vs glass_sphere geometry.
"""

from __future__ import annotations

import dataclasses
import itertools

import pytest

from scenes import load_scene
from scenes.geometry import build_geometry
from tests.conftest import SCENES

pytestmark = pytest.mark.bench


@pytest.mark.parametrize("name", ["glass_sphere", "bunny", "seabed"])
def test_bench_load_scene(benchmark, name):
    scene = benchmark(load_scene, SCENES / f"{name}.toml")
    assert scene.name == name


@pytest.mark.parametrize("name", ["glass_sphere", "bunny", "seabed", "water_pool"])
def test_bench_build_geometry(benchmark, name):
    """Uncached geometry build: build_geometry caches per scene, so each round builds
    a copy of the scene under a source path of its own (a scene the cache has not
    seen), with the geometry checks a renderer's first build runs."""
    scene = load_scene(SCENES / f"{name}.toml")
    rounds = itertools.count()

    def fresh_scene():
        return (dataclasses.replace(scene, source=f"{scene.source}#{next(rounds)}"),), {}

    geometry = benchmark.pedantic(build_geometry, setup=fresh_scene, rounds=5)
    assert len(geometry.receivers) == len(scene.receivers)
    assert len(geometry.objects) == len(scene.objects)
