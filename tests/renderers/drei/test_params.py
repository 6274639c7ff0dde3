"""drei's options from a scene (hand-derived values) and the scenes it refuses, each
with one line naming the file and field."""

from __future__ import annotations

import math

import numpy as np
import pytest

from renderers.drei.params import DreiSceneError, drei_params, refuse_unrepresentable
from scenes import load_scene
from tests.renderers.drei.scenes import SUN_SCENE, sun_scene

#: |(0.3, 0.2, -1)|.
LENGTH = math.sqrt(0.3**2 + 0.2**2 + 1.0)


def test_options_follow_the_scene():
    params = drei_params(load_scene(SUN_SCENE), objects_radius=math.sqrt(3), resolution=256)
    # Towards the light, in glTF axes (x, z, -y): -(0.3, 0.2, -1) -> (-0.3, 1, 0.2).
    np.testing.assert_allclose(params.light_source, np.array([-0.3, 1.0, 0.2]) / LENGTH)
    # An area ratio of 1 is the unrefracted irradiance on the floor: E0 cos(theta).
    assert params.cos_theta == pytest.approx(1.0 / LENGTH)
    assert params.intensity == pytest.approx(5.0 / LENGTH)
    # The plane adds caustic x albedo / pi: radiance off the Lambertian floor.
    np.testing.assert_allclose(params.color, [0.5 / math.pi] * 3)
    assert params.passes == (1.5,) and params.channel_pass == (0, 0, 0)
    assert params.height == 0.0 and params.near == pytest.approx(-0.01 * math.sqrt(3))


def test_a_coloured_light_and_dispersion(tmp_path):
    scene = sun_scene(tmp_path, replace=(
        ("irradiance = [5.0, 5.0, 5.0]", "irradiance = [2.0, 4.0, 1.0]"),
        ("ior = 1.5 }", "ior = [1.52, 1.5, 1.52] }"),
        ("center = [0.0, 0.0, 0.0]", "center = [0.0, 0.0, 0.25]")))
    params = drei_params(scene, objects_radius=1.0, resolution=64)
    assert params.intensity == pytest.approx(4.0 / LENGTH)
    np.testing.assert_allclose(params.channel_scale, [0.5, 1.0, 0.25])
    # One render per distinct IOR; each channel reads its own.
    assert params.passes == (1.5, 1.52) and params.channel_pass == (1, 0, 1)
    assert params.height == 0.25


@pytest.mark.parametrize(("replace", "append", "field"), [
    ((('type = "directional"\ndirection = [0.3, 0.2, -1.0]\nirradiance = [5.0, 5.0, 5.0]',
       'type = "point"\nposition = [1.0, 0.0, 6.0]\nintensity = [30.0, 30.0, 30.0]'),),
     "", "light.type"),
    ((("direction = [0.3, 0.2, -1.0]", "direction = [0.3, 0.2, 1.0]"),), "",
     "light.direction"),
    ((('ior = 1.5 }', 'ior = 1.5, absorption = [0.1, 0.0, 0.0] }'),), "",
     "objects[0].material.absorption"),
    ((('{ type = "dielectric", ior = 1.5 }', '{ type = "conductor", reflectance = '
       '[0.9, 0.9, 0.9] }'),), "", "objects[0].material.type"),
    ((), '\n[[objects]]\ntype = "sphere"\ncenter = [2.5, 0.0, 2.0]\nradius = 0.5\n'
     'material = { type = "dielectric", ior = 1.33 }\n', "objects[1].material.ior"),
    ((("albedo = [0.5, 0.5, 0.5]", "albedo = [0.5, 0.5, 0.5]\nnormal = [0.0, 0.6, 0.8]"),),
     "", "receivers[0].normal"),
    ((('type = "plane"\ncenter', 'type = "heightfield"\nheight = { type = "sines", '
       'amplitude = 0.05, wavelength = 1.0 }\ncenter'),), "", "receivers[0].type"),
])
def test_a_scene_it_cannot_represent_is_refused_naming_file_and_field(tmp_path, replace,
                                                                       append, field):
    scene = sun_scene(tmp_path, replace=replace, append=append)
    with pytest.raises(DreiSceneError) as raised:
        refuse_unrepresentable(scene)
    message = str(raised.value)
    assert "\n" not in message
    assert message.startswith(f"{tmp_path / 'variant.toml'}: {field}: ")
    assert raised.value.field == field


def test_every_bundled_sun_scene_is_rendered_or_refused_by_name():
    """The bundled scenes with a directional light: glass under the sun is rendered;
    metal, heightfields and extra receivers are refused with their field."""
    expected = {"glass_sphere_sun": None, "dispersion_sphere": None, "water_pool": None,
                "hard/grazing_light": None, "bowl_sun": "objects[0].material.type",
                "cup_sun": "objects[0].material.type", "seabed": "receivers[1]",
                "hard/newton_oscillation": "receivers[0].type"}
    for name, field in expected.items():
        scene = load_scene(SUN_SCENE.parent / f"{name}.toml")
        if field is None:
            refuse_unrepresentable(scene)
            continue
        with pytest.raises(DreiSceneError) as raised:
            refuse_unrepresentable(scene)
        assert raised.value.field == field, name
