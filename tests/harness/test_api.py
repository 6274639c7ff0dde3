"""The Python API (harness.api) without rendering: scenes by name, path or object
with overrides, option errors before anything runs, and compare's report writing,
isolation and results on a comparison that is built, not rendered (the end-to-end
renders are tests/harness/test_pytest_plugin.py's, through the example project)."""

from __future__ import annotations

import dataclasses
import json

import pytest

from harness import api
from harness.cli import main
from reports.records import NO_CAUSTIC, STATUS_REASONS, Check, MetricValue
from scenes import SceneError
from tests.conftest import SCENES
from tests.reports.conftest import make_comparison


def test_load_scene_by_name_path_or_object_with_overrides():
    by_name = api.load_scene("glass_sphere", settings={"photons": 1234},
                             resolution=(40, 30))
    assert by_name.source == str(SCENES / "glass_sphere.toml")
    assert by_name.settings.photons == 1234 and by_name.camera.resolution == (40, 30)
    by_path = api.load_scene(SCENES / "hard" / "tiny_scale.toml")
    assert by_path.name == api.load_scene("hard/tiny_scale").name
    again = api.load_scene(by_name, settings={"grid": 32})
    assert (again.settings.photons, again.settings.grid) == (1234, 32)
    assert "glass_sphere" in api.bundled_scenes(hard=False)
    assert "hard/tiny_scale" in api.bundled_scenes()
    assert not any(n.startswith("hard/") for n in api.bundled_scenes(hard=False))


def test_load_scene_errors_name_the_field():
    with pytest.raises(SceneError, match="photons"):
        api.load_scene("glass_sphere", settings={"photons": -1})
    with pytest.raises(SceneError, match="nosuch"):
        api.load_scene("nosuch")


def test_compare_refuses_bad_options_before_rendering(monkeypatch):
    monkeypatch.setattr(api, "run_comparison", pytest.fail)  # nothing may run
    with pytest.raises(api.OptionError, match="unknown study bogus"):
        api.compare("glass_sphere", ["paper"], studies=("metrics", "bogus"))
    with pytest.raises(api.OptionError, match="temporal"):
        api.compare("glass_sphere", ["paper"], studies=("metrics",), frames=3)


def _fake(metrics=()):
    """A run_comparison that returns a built comparison of the scene it is given,
    with ``metrics`` in place of those of the same view, region and metric; a scene
    named ``broken`` raises."""
    def run(scene, method, **kwargs):
        if scene.name == "broken":
            raise RuntimeError("injected failure")
        record = make_comparison(name=scene.name, checks=False, camera=(24, 32),
                                 receiver=(16, 16))
        replaced = {(m.view, m.region, m.metric) for m in metrics}
        kept = [m for m in record.metrics if (m.view, m.region, m.metric) not in replaced]
        return dataclasses.replace(record, method=method.name, metrics=(*kept, *metrics))
    return run


def _broken_scene(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text((SCENES / "glass_sphere.toml").read_text().replace(
        'name = "glass_sphere"', 'name = "broken"'))
    return path


def test_compare_writes_pages_and_the_result_knows_them(tmp_path, monkeypatch):
    monkeypatch.setattr(api, "run_comparison", _fake())
    out = tmp_path / "out"
    result = api.compare("glass_sphere", ["paper", "strong"], output=out, cache_dir=tmp_path)
    assert [c.method for c in result] == ["paper", "strong"]
    assert result.index == out.resolve() / "index.html" and result.index.is_file()
    strong = result.get("strong", scene="glass_sphere")
    assert strong.page == out.resolve() / "glass_sphere-strong" / "index.html"
    assert strong.page.is_file()
    data = json.loads((strong.page.parent / "metrics.json").read_text())
    assert data["method"]["name"] == "strong"
    with pytest.raises(LookupError, match="2 comparisons"):
        result.get()


def test_isolate_records_a_failure_and_goes_on(tmp_path, monkeypatch):
    monkeypatch.setattr(api, "run_comparison", _fake())
    out = tmp_path / "out"
    result = api.compare([_broken_scene(tmp_path), "glass_sphere"], ["paper"], output=out,
                         cache_dir=tmp_path, isolate=True)
    (failure,) = result.failures
    assert (failure.name, failure.method, failure.stage) == ("broken", "paper", "comparison")
    assert "injected failure" in failure.error and failure.page.is_file()
    assert [c.name for c in result] == ["glass_sphere"]


def test_without_isolate_the_first_failure_raises_after_its_page(tmp_path, monkeypatch):
    monkeypatch.setattr(api, "run_comparison", _fake())
    out = tmp_path / "out"
    with pytest.raises(api.ComparisonError, match="broken / paper failed") as caught:
        api.compare([_broken_scene(tmp_path), "glass_sphere"], ["paper"], output=out,
                    cache_dir=tmp_path)
    assert isinstance(caught.value.__cause__, RuntimeError)
    assert caught.value.failure.page.is_file()
    assert not (out / "glass_sphere-paper").exists()     # the run stopped there


def test_comparison_reads_metrics_checks_and_writes_its_report(tmp_path, monkeypatch):
    excess = MetricValue("receiver0", "caustic", "flux_ratio", 1.05, baseline=1.0,
                         excess=0.05, excess_stderr=0.001, excess_ci95=(0.048, 0.052),
                         distinguishable=True)
    monkeypatch.setattr(api, "run_comparison", _fake([excess]))
    (c,) = api.compare("glass_sphere", ["paper"], cache_dir=tmp_path)
    assert c.page is None
    assert c.metric("flux_ratio", region="caustic").excess_ci95 == (0.048, 0.052)
    with pytest.raises(KeyError, match="no metric 'nope'"):
        c.metric("nope")
    failing = Check("energy", "full", "all", 1.001, "max", 1.04, False, "test",
                    kind="physical requirement")
    gap = dataclasses.replace(failing, gap="known")
    c = dataclasses.replace(c, record=dataclasses.replace(c.record, checks=(failing, gap)))
    assert c.physical_failures == (failing,)
    written = api.write_report(c, tmp_path / "report")
    assert written.get().page.is_file() and written.index.is_file()


def _no_caustic(scene, method, **kwargs):
    """A run_comparison whose reference held no caustic: it returns (never raises)
    a comparison with that status."""
    record = make_comparison(name=scene.name, checks=False, camera=(24, 32), receiver=(16, 16))
    return dataclasses.replace(record, method=method.name, status=NO_CAUSTIC)


def test_no_caustic_is_a_status_that_becomes_a_failure(tmp_path, monkeypatch):
    """Regression lock: a comparison with the status ``no caustic`` is a Failure
    (stage ``comparison``, the status's reason) with isolate, written or not, its
    data files kept; without isolate it raises ComparisonError, after its page."""
    monkeypatch.setattr(api, "run_comparison", _no_caustic)
    (failure,) = api.compare("glass_sphere", ["paper"], isolate=True).failures
    assert (failure.stage, failure.error) == ("comparison", STATUS_REASONS[NO_CAUSTIC])
    out = tmp_path / "out"
    written = api.compare("glass_sphere", ["paper"], output=out, isolate=True)
    assert written.failures[0].page.is_file()
    assert (out / "glass_sphere-paper" / "metrics.json").is_file()
    with pytest.raises(api.ComparisonError, match="no caustic"):
        api.compare("glass_sphere", ["paper"])
    with pytest.raises(api.ComparisonError, match="no caustic") as caught:
        api.compare("glass_sphere", ["paper"], output=tmp_path / "again")
    assert caught.value.failure.page.is_file()


def test_the_command_line_loads_each_scene_once(tmp_path, monkeypatch):
    """Regression lock: ``caustics compare`` loads each scene file once and applies
    its overrides once, however many methods compare it; a scene that does not load
    is a failure row of each method without a second load."""
    loads, applied = [], []
    real_load, real_settings = api._load_files, api.with_settings

    def load(paths, **kwargs):
        loads.append(list(paths))
        return real_load(paths, **kwargs)

    def settings(scene, overrides, **kwargs):
        if overrides:
            applied.append(scene.name)
        return real_settings(scene, overrides, **kwargs)

    monkeypatch.setattr(api, "_load_files", load)
    monkeypatch.setattr(api, "with_settings", settings)
    monkeypatch.setattr(api, "run_comparison", _fake())
    bad = tmp_path / "bad.toml"
    bad.write_text("[scene]\nname = 'bad'\n")
    out = tmp_path / "out"
    assert main(["compare", "glass_sphere", str(bad), "-o", str(out), "-q", "--set",
                 "grid=32", "--studies", "metrics", "--cache-dir", str(tmp_path)]) == 1
    assert loads == [["glass_sphere"], [str(bad)]] and applied == ["glass_sphere"]
    assert sorted(p.parent.name for p in out.glob("*/index.html")) == [
        "bad-paper", "bad-strong", "glass_sphere-paper", "glass_sphere-strong"]
