"""drei's Caustics rendered in headless Chromium on the glass sphere under the sun,
small: the page, the maps the method hands the harness, and the camera image's units.

The render is the ``drei`` fixture's (``conftest.py``): the test session's Chromium
with the JavaScript workspace installed; without either it is skipped locally and
fails on CI (``CI`` set).

Kind: physical requirements (flux kept, placement, units). The flux the component
computes is its texture times a texel's area on the floor, taken here from the light
camera's extent the page reports and the light's angle, not from the mapping.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.renderers.drei.scenes import AXIS_ON_FLOOR
from tests.renderers.drei.test_mapping import assert_caustic_at

pytestmark = pytest.mark.physical_requirement

#: cos(theta) of the sun scene's light on the floor, and its unrefracted irradiance.
COS = 1.0 / math.sqrt(1.13)
E0 = 5.0


def test_the_map_keeps_the_flux_the_component_computes(drei):
    camera = drei.light_cameras[0]
    texel = ((camera.right - camera.left) / drei.textures.shape[1]) ** 2 / COS
    computed = drei.textures.reshape(3, -1).sum(axis=1, dtype=np.float64) * texel
    held = drei.result.receivers[0].total_flux()
    assert computed[0] > 0
    np.testing.assert_allclose(held, computed, rtol=1e-5)
    np.testing.assert_allclose(drei.result.metadata["texture_flux_w"], computed, rtol=1e-9)
    assert drei.result.metadata["flux_outside_receiver_w"] == [0.0, 0.0, 0.0]


def test_the_caustic_lands_on_the_axis_and_a_flipped_map_is_caught(drei):
    receiver = drei.result.receivers[0]
    texel = (receiver.extent[1] - receiver.extent[0]) / receiver.irradiance.shape[1]
    assert_caustic_at(receiver.irradiance, receiver.extent, AXIS_ON_FLOOR, tolerance=texel / 2)
    with pytest.raises(AssertionError, match="caustic centroid"):
        assert_caustic_at(receiver.irradiance[::-1], receiver.extent, AXIS_ON_FLOOR,
                          tolerance=texel / 2)


def test_the_page_renders_floats_in_radiometric_units(drei):
    """The float caustic target, and the lit floor's radiance in the camera image:
    albedo / pi x E0 cos(theta) (three.js reads the light's W/m² as lux)."""
    assert drei.page["causticsType"] == "float32"
    assert drei.page["console_errors"] == []
    image = drei.result.camera
    assert np.isfinite(image).all() and (image >= 0).all()
    floor = 0.5 / math.pi * E0 * COS
    lit = image[..., 0][image[..., 0] > 0.05]
    assert np.median(lit) == pytest.approx(floor, rel=1e-3)
    assert drei.result.timings["caustic_map"] > 0 and drei.result.timer
