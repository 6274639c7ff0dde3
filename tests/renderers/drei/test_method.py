"""drei-caustics as a plug-in: registered in pyproject's entry-point group like any
third-party method, and refusing in ``configure`` (before any reference is rendered)
a scene it cannot represent."""

from __future__ import annotations

import importlib
import tomllib

import pytest

from renderers.drei.method import DREI
from renderers.drei.params import DreiSceneError
from renderers.methods import GROUP, Method, has_gl_runner
from tests.conftest import REPO
from tests.renderers.drei.scenes import sun_scene


def test_the_entry_point_names_a_method():
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    target = project["entry-points"][GROUP]["drei-caustics"]
    module, _, attribute = target.partition(":")
    method = getattr(importlib.import_module(module), attribute)
    assert isinstance(method, Method) and not has_gl_runner(method)
    assert method.name == "drei-caustics"


def test_configure_refuses_a_point_light_in_one_line(tmp_path):
    scene = sun_scene(tmp_path, replace=((
        'type = "directional"\ndirection = [0.3, 0.2, -1.0]\nirradiance = [5.0, 5.0, 5.0]',
        'type = "point"\nposition = [1.0, 0.0, 6.0]\nintensity = [30.0, 30.0, 30.0]'),))
    with pytest.raises(DreiSceneError, match=r"variant\.toml: light\.type: drei-caustics "
                       r"cannot represent this: point light"):
        DREI.configure(scene)
