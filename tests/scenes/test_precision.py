"""Values finite in float64 but not in the renderers' float32 (alone, or in the
products the renderers form) are errors naming the field, and so is a dark light."""

from __future__ import annotations

import numpy as np
import pytest

from scenes import SceneError, load_scene
from scenes.precision import LENGTH_LIMIT
from tests.conftest import all_scene_files

POINT = 'type = "point"\nposition = [0.0, 0.0, 6.0]\nintensity = [30.0, 30.0, 30.0]'


def _only_problem(tmp_path, text: str) -> tuple[str, str]:
    path = tmp_path / "scene.toml"
    path.write_text(text)
    with pytest.raises(SceneError) as info:
        load_scene(path)
    (problem,) = info.value.problems
    assert str(problem).startswith(f"{path}: {problem.path}: ")
    return problem.path, problem.message


def _replace(text: str, old: str, new: str) -> str:
    assert old in text, f"fixture text lacks {old!r}"
    return text.replace(old, new, 1)


@pytest.mark.parametrize("case", [
    ("radius = 1.0", "radius = 1e300", "objects[0].radius", "overflows float32"),
    ("center = [0.0, 0.0, 2.0]", "center = [1e300, 0.0, 2.0]", "objects[0].center[0]",
     "overflows float32"),
    ("intensity = [30.0, 30.0, 30.0]", "intensity = [1e39, 30.0, 30.0]",
     "light.intensity[0]", "overflows float32"),
], ids=["radius", "centre", "intensity"])
def test_single_value_overflowing_float32(tmp_path, minimal_scene_text, case):
    """Physical requirement: a value finite in float64 whose float32 cast is infinite
    cannot reach either renderer; the error names the component."""
    old, new, field, words = case
    path, message = _only_problem(tmp_path, _replace(minimal_scene_text, old, new))
    assert path == field and words in message


@pytest.mark.parametrize("case", [
    ("intensity = [30.0, 30.0, 30.0]", "intensity = [1e38, 1e38, 1e38]", "light.intensity",
     "radiant power 4 pi x intensity = 1.26e+39 W overflows float32"),
    ("radius = 1.0", "radius = 1e20", "objects[0].radius", "squared distances overflow"),
    ("center = [0.0, 0.0, 2.0]", "center = [0.0, 2e18, 2.0]", "objects[0].center",
     "squared distances overflow"),
    ("position = [0.0, 0.0, 6.0]", "position = [0.0, 0.0, 6e19]", "light.position",
     "squared distances overflow"),
], ids=["power", "radius-squared", "centre-squared", "light-distance"])
def test_products_overflowing_float32(tmp_path, minimal_scene_text, case):
    """Physical requirement: each value fits float32 but a product the renderers form
    (power 4 pi I; squared distances of points up to 1e18 m out) does not."""
    old, new, field, words = case
    path, message = _only_problem(tmp_path, _replace(minimal_scene_text, old, new))
    assert path == field and words in message


def test_area_light_radiance_and_tiny_area(tmp_path, minimal_scene_text):
    """Physical requirement: an area light's radiance I / area must be finite, and
    its area must not round to 0 in float32."""
    area = ('type = "area"\ncenter = [0.0, 0.0, 6.0]\nnormal = [0.0, 0.0, -1.0]\n'
            "size = [SIZE, SIZE]\nintensity = [INTENSITY, 30.0, 30.0]")
    text = _replace(minimal_scene_text, POINT, area)
    small = text.replace("SIZE", "1e-25").replace("INTENSITY", "30.0")
    assert _only_problem(tmp_path, small)[0] == "light.size"
    bright = text.replace("SIZE", "1e-10").replace("INTENSITY", "1e30")
    path, message = _only_problem(tmp_path, bright)
    assert path == "light.intensity" and "radiance intensity / area" in message


def test_directional_power_over_scene_cross_section(tmp_path, minimal_scene_text):
    """Physical requirement: irradiance x the scene's cross-section is the power a
    directional light delivers; 1e37 W/m^2 over an 8 m floor overflows float32."""
    sun = 'type = "directional"\ndirection = [0.0, 0.0, -1.0]\nirradiance = [1e37, 1.0, 1.0]'
    path, message = _only_problem(tmp_path, _replace(minimal_scene_text, POINT, sun))
    assert path == "light.irradiance" and "cross-section" in message


def test_positive_value_rounding_to_zero(tmp_path, minimal_scene_text):
    """Physical requirement: a radius > 0 in float64 that is 0 in float32 is refused."""
    path, message = _only_problem(tmp_path, _replace(minimal_scene_text, "radius = 1.0",
                                                     "radius = 1e-50"))
    assert path == "objects[0].radius" and "in float32 too" in message


def test_integer_beyond_64_bits(tmp_path, minimal_scene_text):
    """Regression lock: a huge TOML integer is an error, not an OverflowError."""
    text = minimal_scene_text + "\n[settings]\nphotons = 1" + "0" * 30 + "\n"
    assert _only_problem(tmp_path, text) == ("settings.photons",
                                             "must fit in 64 bits (TOML's integer range)")


@pytest.mark.parametrize(("light", "field"), [
    (POINT.replace("[30.0, 30.0, 30.0]", "[0.0, 0.0, 0.0]"), "light.intensity"),
    ('type = "directional"\ndirection = [0.0, 0.0, -1.0]\nirradiance = [0.0, 0.0, 0.0]',
     "light.irradiance"),
], ids=["point", "directional"])
def test_zero_intensity_is_an_error(tmp_path, minimal_scene_text, light, field):
    """Physical requirement: a light dark in every channel forms no caustic, and the
    comparison's metrics are undefined on a black reference."""
    path, message = _only_problem(tmp_path, _replace(minimal_scene_text, POINT, light))
    assert path == field and "emits nothing" in message


def test_one_dark_channel_is_legal(minimal_scene_text, tmp_path):
    """Regression lock: a red light (two dark channels) is a legal scene."""
    path = tmp_path / "red.toml"
    path.write_text(minimal_scene_text.replace("[30.0, 30.0, 30.0]", "[30.0, 0.0, 0.0]"))
    assert load_scene(path).light.intensity == (30.0, 0.0, 0.0)


def test_bundled_scenes_are_within_limits():
    """Regression lock: the huge-scale hard case (x 1e3) is far inside the limit, so
    the limit refuses no bundled scene."""
    for path in all_scene_files():
        load_scene(path)


def test_length_limit_keeps_squared_distances_finite_in_float32():
    """The limit's reason (scenes.precision): two points ``LENGTH_LIMIT`` out on
    opposite corners are 2 sqrt(3) LENGTH_LIMIT apart, and that distance squared
    (1.2e37 at 1e18 m) is still finite in float32; ten times the limit out it
    overflows (1.2e39 > 3.4e38, float32's largest)."""
    for reach, finite in ((LENGTH_LIMIT, True), (10 * LENGTH_LIMIT, False)):
        corner = np.full(3, reach, np.float32)
        gap = corner - (-corner)
        with np.errstate(over="ignore"):
            assert bool(np.isfinite(np.dot(gap, gap))) is finite
