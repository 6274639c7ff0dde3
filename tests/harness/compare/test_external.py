"""ExternalRender and its timing report, without a reference: what is refused before
any file is scored."""

from __future__ import annotations

import numpy as np
import pytest

from harness.compare.external import ExternalRender, ExternalRenderError, read_timing
from renderers.exr import write_exr
from renderers.methods import has_gl_runner, renders_elsewhere
from scenes import load_scene, with_settings
from tests.conftest import SCENES


@pytest.fixture(scope="module")
def scene():
    return with_settings(load_scene(SCENES / "glass_sphere.toml"), {"receiver_map": [8, 6]})


def test_it_is_a_method_that_renders_elsewhere_without_a_gl_runner():
    method = ExternalRender(camera=None, receivers={0: "x.exr"})
    assert renders_elsewhere(method) and not has_gl_runner(method)


def test_a_map_of_the_settings_size_is_read_in_the_receivers_frame(scene, tmp_path):
    """The map comes back as written, (H, W) = receiver_map (W, H) reversed, with the
    receiver's extent; no camera means the camera is None, not an error."""
    image = np.random.default_rng(1).random((6, 8, 3)).astype(np.float32)
    write_exr(tmp_path / "r.exr", {"RGB": image})
    result = ExternalRender(receivers={0: tmp_path / "r.exr"}).render(scene)
    assert result.camera is None
    np.testing.assert_array_equal(result.receivers[0].irradiance, image)
    assert result.receivers[0].extent[1] > result.receivers[0].extent[0]


@pytest.mark.parametrize(("receivers", "said"), [
    ({}, "no image to score"),
    ({3: "r.exr"}, "receiver 3: scene 'glass_sphere' has receivers 0..0"),
])
def test_views_that_do_not_fit_the_scene_are_refused(scene, receivers, said):
    with pytest.raises(ExternalRenderError, match=said):
        ExternalRender(receivers=receivers).render(scene)


@pytest.mark.parametrize(("text", "said"), [
    ('{"frame_ms": -1}', "frame_ms must be a non-negative number"),
    ('{"frame_ms": true}', "frame_ms must be a non-negative number"),
    ("[12.3]", "a timing report is a JSON object"),
    ("{frame_ms: 1}", "not a JSON timing report"),
])
def test_a_bad_timing_report_names_its_file(tmp_path, text, said):
    path = tmp_path / "render.json"
    path.write_text(text)
    with pytest.raises(ExternalRenderError, match=said) as caught:
        read_timing(path)
    assert str(path) in str(caught.value)


def test_a_timing_report_is_kept_as_given_and_labelled(tmp_path):
    path = tmp_path / "render.json"
    path.write_text('{"frame_ms": 4, "device": "a GPU"}')
    method = ExternalRender(receivers={0: "r.exr"}, timing=read_timing(path))
    assert method.reported_timing() == {
        "frame_ms": 4, "device": "a GPU",
        "label": "reported by the renderer, not measured by the harness"}
