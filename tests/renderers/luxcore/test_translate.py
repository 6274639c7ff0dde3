"""LuxCore refuses what it cannot render faithfully, naming the file and field path."""

from __future__ import annotations

import dataclasses

import pytest

from renderers.luxcore import UnsupportedScene, check_supported, render_receiver_caustic
from renderers.luxcore.translate import receiver_view, translate_scene
from scenes import load_scene
from scenes.errors import HarnessError
from tests.conftest import SCENES
from tests.renderers.luxcore.conftest import GLASS_SPHERE, make_scene

SPOT = ('type = "spot"\nposition = [0.0, 0.0, 4.0]\ndirection = [0.0, 0.0, -1.0]\n'
        "intensity = [10.0, 10.0, 10.0]\ncutoff_angle = 30.0")
POINT = 'type = "point"\nposition = [0.0, 0.0, 4.0]\nintensity = [10.0, 10.0, 10.0]'


def test_metal_ring_is_refused_with_file_and_field_path():
    scene = load_scene(SCENES / "metal_ring.toml")
    with pytest.raises(UnsupportedScene) as caught:
        render_receiver_caustic(scene, photons=1000, seeds=1)
    assert isinstance(caught.value, HarnessError)
    first = str(caught.value).splitlines()[0]
    assert first == (f"{scene.source}: objects[0].material: conductor has no faithful "
                     "LuxCore equivalent")


def test_spot_light_is_refused():
    with pytest.raises(UnsupportedScene, match=r"luxcore_test\.toml: light\.type: spot light"):
        check_supported(make_scene(light=SPOT))


def test_every_problem_is_listed():
    """Dispersion, absorption, Fresnel off, event-filtered chains: one line each."""
    scene = make_scene(light=POINT, settings="all_specular_paths = false")
    sphere = scene.objects[0]
    material = dataclasses.replace(sphere.material, ior=(1.5, 1.52, 1.54),
                                   absorption=(0.1, 0.0, 0.0), fresnel=False)
    scene = dataclasses.replace(scene, objects=(dataclasses.replace(sphere, material=material),))
    with pytest.raises(UnsupportedScene) as caught:
        check_supported(scene)
    fields = [line.split(": ")[1] for line in str(caught.value).splitlines()]
    assert fields == ["objects[0].material.ior", "objects[0].material.absorption",
                      "objects[0].material.fresnel", "settings.all_specular_paths"]


def test_glass_sphere_translates_with_the_same_triangles():
    scene = make_scene(light=POINT, objects=GLASS_SPHERE)
    check_supported(scene)
    lux = translate_scene(scene, variant="glass", receiver_albedo=1e-3,
                          view=receiver_view(scene, 0, resolution=(8, 8)))
    names = [name for name, _ in lux.meshes]
    assert names == ["receiver0", "object0"]
    assert "scene.materials.object0.interiorior = 1.5" in lux.properties
    # gain = 4 pi I: LuxCore's point light emits `gain` watts per unit colour.
    assert "scene.lights.light.gain = 125.66370614359172" in lux.properties
    black = translate_scene(scene, variant="black", receiver_albedo=1e-3,
                            view=receiver_view(scene, 0, resolution=(8, 8)))
    assert black.meshes[1][1] is lux.meshes[1][1]
    assert "scene.materials.object0.kd = 0 0 0" in black.properties
