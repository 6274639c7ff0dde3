"""Several standalone GL contexts in one process (studies, figures and tests each
make one): a render on a context must not land in whichever was made current last."""

from __future__ import annotations

import dataclasses

import numpy as np

from renderers.caustics_mapping import create_context, render
from scenes import load_scene, with_settings
from tests.conftest import SCENES


def test_render_after_another_context_came_and_went():
    scene = with_settings(load_scene(SCENES / "glass_sphere.toml"),
                          {"grid": 32, "caustic_map": 64, "positions_map": 64,
                           "shadow_map": 64, "receiver_map": [32, 32]})
    scene = dataclasses.replace(scene, camera=dataclasses.replace(scene.camera,
                                                                  resolution=(16, 16)))
    first = create_context()
    try:
        before = render(scene, ctx=first).receivers[0].irradiance
        other = create_context()
        render(scene, ctx=other)
        other.release()
        after = render(scene, ctx=first).receivers[0].irradiance
        assert first.error == "GL_NO_ERROR"
        np.testing.assert_array_equal(before, after)
    finally:
        first.release()
