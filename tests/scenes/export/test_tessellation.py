"""Chord tolerance of the export (``scenes/export/tessellation.py``): the default follows
the scene's size, a tolerance no allowed level meets is an error naming the field, and a
bad tolerance is refused.

Kind: physical requirements (the chord-error formulas against a direct measurement are
in test_gltf.py)."""

from __future__ import annotations

import math

import pytest

from scenes import SceneError, load_scene, resolve_scene
from scenes.export.tessellation import (
    DEFAULT_RELATIVE_TOLERANCE,
    default_tolerance,
    ring_chord_error,
    sphere_chord_error,
    tessellate,
)


def test_default_tolerance_scales_with_the_scene():
    """huge_scale is glass_sphere x 1e3: its default tolerance is 1e3 times as large, and
    glass_sphere's is 1e-4 of its 11.7 m bounding-box diagonal (sqrt(8^2 + 8^2 + 3^2))."""
    small = default_tolerance(load_scene(resolve_scene("glass_sphere")))
    huge = default_tolerance(load_scene(resolve_scene("huge_scale")))
    assert small == pytest.approx(DEFAULT_RELATIVE_TOLERANCE * math.sqrt(137), rel=1e-6)
    assert huge == pytest.approx(1e3 * small, rel=1e-5)


def test_chord_errors_shrink_fourfold_per_level_and_with_the_square_of_segments():
    """Halving the edge quarters the sagitta: icosphere levels by about 4 each, a band's
    r (1 - cos(pi / n)) ~ r pi^2 / (2 n^2)."""
    ratios = [sphere_chord_error(1.0, k) / sphere_chord_error(1.0, k + 1) for k in (3, 4, 5)]
    assert all(3.9 < r < 4.1 for r in ratios)
    assert ring_chord_error(2.0, 1000) == pytest.approx(2.0 * math.pi**2 / 2e6, rel=1e-5)


def test_a_tolerance_no_level_meets_names_the_field():
    scene = load_scene(resolve_scene("glass_sphere"))
    with pytest.raises(SceneError) as caught:
        tessellate(scene, tolerance=1e-9)
    (problem,) = caught.value.problems
    assert problem.path == "objects[0].subdivisions" and "1e-09 m" in problem.message
    ring = load_scene(resolve_scene("metal_ring"))
    with pytest.raises(SceneError) as caught:
        tessellate(ring, tolerance=1e-9)
    assert caught.value.problems[0].path == "objects[0].segments"


@pytest.mark.parametrize("tolerance", [0.0, -1.0, float("nan"), float("inf")])
def test_a_tolerance_must_be_a_positive_number(tolerance):
    with pytest.raises(SceneError, match="positive number of metres"):
        tessellate(load_scene(resolve_scene("glass_sphere")), tolerance=tolerance)
