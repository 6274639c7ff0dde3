"""Benchmark: reading and building scenes (the fixed cost before any render).

Reported by pytest-benchmark (wall clock, time.perf_counter); compare the rows of one
run as ratios, e.g. bunny geometry vs glass_sphere geometry.
"""

from __future__ import annotations

import pytest

from scenes import load_scene
from scenes.geometry.build import _object, _receiver
from tests.conftest import SCENES

pytestmark = pytest.mark.bench


@pytest.mark.parametrize("name", ["glass_sphere", "bunny", "seabed"])
def test_bench_load_scene(benchmark, name):
    scene = benchmark(load_scene, SCENES / f"{name}.toml")
    assert scene.name == name


@pytest.mark.parametrize("name", ["glass_sphere", "bunny", "seabed", "water_pool"])
def test_bench_build_geometry(benchmark, name):
    """Uncached geometry build (build_geometry itself caches per scene)."""
    scene = load_scene(SCENES / f"{name}.toml")

    def build():
        return [_receiver(r) for r in scene.receivers] + [_object(o) for o in scene.objects]

    meshes = benchmark(build)
    assert len(meshes) == len(scene.receivers) + len(scene.objects)
