"""The Khronos glTF validator on every bundled scene's export: no errors, no warnings.

The validator runs under Node from the project's JavaScript workspace
(``npm ci --prefix renderers/web``, which tox's set-up runs). Without it the test is
skipped on a developer's machine, and fails on CI (``CI`` set): there it must run.

Kind: physical requirement of the export (a file every glTF 2.0 reader accepts)."""

from __future__ import annotations

import json
import os

import pytest

from renderers.web.validator import ValidatorError, unavailable_reason, validate_gltf
from scenes import load_scene
from scenes.export import export_gltf
from tests.conftest import BUNDLED_FILES as BUNDLED
from tests.conftest import bundled_id
from tests.scenes.export.scenes import area_light_scene


@pytest.fixture(scope="module")
def validator():
    reason = unavailable_reason()
    if reason:
        if os.environ.get("CI"):
            pytest.fail(f"the glTF validator must run on CI: {reason}")
        pytest.skip(reason)


@pytest.mark.usefixtures("validator")
@pytest.mark.parametrize("path", BUNDLED, ids=bundled_id)
def test_every_bundled_scene_exports_valid_gltf(tmp_path, path):
    done = export_gltf(load_scene(path), tmp_path / "scene.glb")
    report = validate_gltf(done.path)
    assert (report.errors, report.warnings) == (0, 0), report.describe()
    assert report.report["info"]["totalTriangleCount"] > 0


@pytest.mark.usefixtures("validator")
def test_validator_reports_a_broken_file(tmp_path):
    """Not vacuous: the same export, one accessor claiming more vertices than its buffer
    view holds, gives errors, and a file that is not glTF at all is refused."""
    export_gltf(load_scene(BUNDLED[0]), tmp_path / "scene.gltf")
    document = json.loads((tmp_path / "scene.gltf").read_text())
    document["accessors"][0]["count"] *= 1000
    (tmp_path / "scene.gltf").write_text(json.dumps(document))
    assert validate_gltf(tmp_path / "scene.gltf").errors > 0
    (tmp_path / "junk.glb").write_bytes(b"not a glTF file")
    with pytest.raises(ValidatorError, match="could not detect glTF format"):
        validate_gltf(tmp_path / "junk.glb")


@pytest.mark.usefixtures("validator")
def test_an_area_light_scene_is_valid(tmp_path):
    """No bundled scene has an area light: the emissive rectangle it becomes validates."""
    report = validate_gltf(export_gltf(area_light_scene(), tmp_path / "area.glb").path)
    assert (report.errors, report.warnings) == (0, 0), report.describe()
