"""Effects derived from scenes: the committed scenes and each rule in isolation."""

from __future__ import annotations

import dataclasses

import pytest

from scenes import effects_of, event_chain, load_scene, parse_scene
from scenes.model import ConductorMaterial, DielectricMaterial, DiffuseMaterial
from tests.conftest import SCENES

EXPECTED = {
    "glass_sphere": ("refraction.double", "shadows"),
    "bunny": ("refraction.double", "shadows"),
    "colored_bunny": ("refraction.double", "absorption", "shadows"),
    "dispersion_sphere": ("refraction.double", "dispersion", "shadows"),
    "water_pool": ("refraction.single",),
    "seabed": ("refraction.single",),
    "metal_ring": ("reflection", "shadows"),
}


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_paper_scene_effects(name):
    """Each paper scene calls for exactly the effects its figure shows."""
    assert effects_of(load_scene(SCENES / f"{name}.toml")) == EXPECTED[name]


def _with_material(text, material):
    scene = parse_scene(text)
    obj = dataclasses.replace(scene.objects[0], material=material)
    return dataclasses.replace(scene, objects=(obj,))


def test_rules(minimal_scene_text):
    base = parse_scene(minimal_scene_text)
    assert effects_of(base) == ("refraction.double", "shadows")
    glass = DielectricMaterial(ior=1.5)
    assert "absorption" in effects_of(
        _with_material(minimal_scene_text, dataclasses.replace(glass, absorption=(0, 0, 0.1))))
    assert "dispersion" in effects_of(
        _with_material(minimal_scene_text, dataclasses.replace(glass, ior=(1.5, 1.5, 1.51))))
    assert "dispersion" not in effects_of(
        _with_material(minimal_scene_text, dataclasses.replace(glass, ior=(1.5, 1.5, 1.5))))
    assert "fresnel" in effects_of(
        _with_material(minimal_scene_text, dataclasses.replace(glass, fresnel=True)))
    metal = _with_material(minimal_scene_text, ConductorMaterial(reflectance=(1, 1, 1)))
    assert effects_of(metal) == ("reflection", "shadows")
    diffuse = _with_material(minimal_scene_text, DiffuseMaterial(albedo=(1, 1, 1)))
    assert effects_of(diffuse) == ("shadows",)
    unlit = dataclasses.replace(base, info=dataclasses.replace(base.info, direct_lighting=False))
    assert "shadows" not in effects_of(unlit)


def test_event_chains():
    """Chains the reference counts: two transmissions for closed, one for open."""
    sphere = load_scene(SCENES / "glass_sphere.toml").objects[0]
    water = load_scene(SCENES / "water_pool.toml").objects[0]
    ring = load_scene(SCENES / "metal_ring.toml").objects[0]
    assert (event_chain(sphere), event_chain(water), event_chain(ring)) == (
        "L T T D", "L T D", "L R D")
