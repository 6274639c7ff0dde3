"""The one comparison pipeline: every caller scores through the same function, a study
added from outside shows up in the data and on the page, and headlines come last so
that they can cite a failed check."""

from __future__ import annotations

import ast
import csv
import dataclasses
import json
from pathlib import Path

import pytest

from harness.cli import main
from harness.compare import pipeline
from harness.compare.headlines import with_headlines
from harness.compare.pipeline import CompareOptions, known_studies, run_comparison
from harness.compare.studies import register_study, unregister_study
from harness.sweep.rows import render_row, score_row
from renderers.methods import load_method
from reports.records import Check, StudySection, Table
from scenes import load_scene, parse_override, with_settings
from tests.conftest import REPO
from tests.harness.commands.test_compare import SMALL, _small_scene
from tests.reports.conftest import make_comparison

PACKAGES = ("harness", "renderers", "reports", "scenes")


def _small(tmp_path):
    """The small glass sphere of the compare tests, with SMALL's settings applied."""
    overrides = dict(parse_override(v) for v in SMALL[1::2])
    return with_settings(load_scene(_small_scene(tmp_path)), overrides)


class PeakStudy:
    """A study written in this test file alone: the method's and the reference's peak
    irradiance on receiver 0, their ratio, and a one-row table."""

    name, optional = "peak", True

    def applies(self, method):
        return True

    def run(self, context):
        method = float(context.render.result.receivers[0].irradiance.max())
        reference = float(context.references.reference.receivers[0].irradiance.max())
        table = Table(("side", "peak_w_m2"), (("method", method), ("reference", reference)))
        return StudySection(self.name, "Peak irradiance (a test plug-in)",
                            summary=f"peak ratio {method / reference:.6f}",
                            values={"peak_ratio": method / reference},
                            files={"peak.csv": table})


@pytest.fixture
def peak_study():
    register_study(PeakStudy())
    yield
    unregister_study("peak")


def test_compare_sweep_and_a_third_party_method_score_through_one_function(tmp_path,
                                                                         monkeypatch):
    """Regression lock of the structure: ``caustics compare`` (a preset), a sweep row
    (render task, then score task) and a third-party method object each reach the
    pipeline's one scoring function, and the sweep row's metrics equal those of the
    pipeline run on the same render and references (nothing scored another way)."""
    calls = []
    real = pipeline.score_render

    def spy(scene, geometry, render, references):
        calls.append(render.result.renderer)
        return real(scene, geometry, render, references)

    monkeypatch.setattr(pipeline, "score_render", spy)
    assert main(["compare", str(_small_scene(tmp_path)), "-o", str(tmp_path / "out"),
                 "--studies", "metrics", "--preset", "paper", "-q", *SMALL]) == 0
    assert len(calls) == 1

    paper = load_method("paper")
    scene = paper.configure(_small(tmp_path))
    options = CompareOptions(studies=("metrics",), quick=True, progress=False)
    references = pipeline.render_references(scene, options)
    row = score_row(scene, "paper", render_row(scene, "paper", repeats=1), *references)
    assert len(calls) == 2

    class Halved:
        """A third-party method given as an object, not an entry point."""

        name, description = "halved", "the paper preset's render, halved"

        def configure(self, scene):
            return paper.configure(scene)

        def render(self, scene):
            result = paper.render(scene)
            return dataclasses.replace(result, renderer="halved", receivers=tuple(
                dataclasses.replace(r, irradiance=r.irradiance / 2) for r in result.receivers))

    third = run_comparison(scene, Halved(), options=options, references=references)
    assert calls[2:] == ["halved"]
    flux = row.metric("receiver0", "full", "flux_ratio").value
    assert third.metric("receiver0", "full", "flux_ratio").value == pytest.approx(flux / 2,
                                                                                   rel=1e-5)


def _private_import(importer: str, module: str, name: str) -> bool:
    """Whether ``from module import name`` in module ``importer`` reaches a private
    name from outside its home: a ``_name`` function or class of another module, or a
    ``_module`` imported from outside the package that holds it."""
    parts = [*module.split("."), name]
    for i, part in enumerate(parts):
        if part.startswith("_") and not part.startswith("__"):
            home = ".".join(parts[:i])
            is_module = (REPO / Path(*parts[:i + 1])).with_suffix(".py").is_file() or (
                REPO / Path(*parts[:i + 1]) / "__init__.py").is_file()
            return not (is_module and (importer == home or importer.startswith(home + ".")))
    return False


def test_no_module_imports_another_modules_private_name():
    """Regression lock: no module of the four packages imports a ``_private`` name of
    another module, nor a private module from outside its package (what is used
    elsewhere is public)."""
    offenders = []
    for package in PACKAGES:
        for path in sorted((REPO / package).rglob("*.py")):
            importer = ".".join(path.relative_to(REPO).with_suffix("").parts)
            for node in ast.walk(ast.parse(path.read_text("utf-8"))):
                if isinstance(node, ast.ImportFrom) and node.module and (
                        node.module.split(".")[0] in PACKAGES):
                    offenders += [f"{importer}: {node.module}.{a.name}" for a in node.names
                                  if _private_import(importer, node.module, a.name)]
    assert offenders == []
    assert _private_import("harness.x", "renderers.mitsuba._mi", "load")
    assert _private_import("harness.x", "renderers.mitsuba.photons", "_lane_rng")
    assert not _private_import("renderers.mitsuba.photons", "renderers.mitsuba", "_mi")


def test_a_study_from_this_file_reaches_metrics_json_and_the_page(tmp_path, peak_study):
    """A study registered here, and nothing else changed, is a known study name;
    ``compare --studies metrics,peak`` runs it: its section is in metrics.json under
    ``studies.peak``, its table is written as peak.csv, and the page shows its title,
    summary and value. Its peak ratio is the one the metrics' own images give."""
    assert "peak" in known_studies()
    out = tmp_path / "out"
    assert main(["compare", str(_small_scene(tmp_path)), "-o", str(out), "--studies",
                 "metrics,peak", "--preset", "strong", "-q", *SMALL]) == 0
    folder = out / "glass_sphere-strong"
    data = json.loads((folder / "metrics.json").read_text())
    ratio = data["studies"]["peak"]["values"]["peak_ratio"]
    rows = list(csv.DictReader((folder / "peak.csv").open()))
    assert ratio == pytest.approx(float(rows[0]["peak_w_m2"]) / float(rows[1]["peak_w_m2"]))
    assert 0.2 < ratio < 5.0  # a caustic on both sides, not a blank map
    page = (folder / "index.html").read_text()
    assert 'id="study-peak"' in page and "Peak irradiance (a test plug-in)" in page
    assert f"peak ratio {ratio:.6f}" in page and "peak.csv" in page


def test_a_study_not_asked_for_does_not_run(tmp_path, peak_study):
    """An optional study runs only when named: a default compare has no section for it."""
    assert "peak" not in CompareOptions().selected
    assert "peak" in CompareOptions(studies=("metrics", "peak")).selected


def test_a_headline_cites_a_failed_check():
    """Headlines are made from the finished comparison, checks included: a failed
    physical requirement is the first banner, with its value and bound; a known gap
    is not cited as a failure, and a comparison whose checks pass has no such banner."""
    comparison = make_comparison(checks=False, camera=(24, 32), receiver=(16, 16))
    failed = Check("energy", "full", "all", 1.001, "max", 1.07, False, "energy is conserved",
                   kind="physical requirement")
    gap = Check("flux agreement", "full", "all", 0.02, "band", 1.09, False, "2 %",
                kind="physical requirement", gap="a known gap")
    cited = with_headlines(dataclasses.replace(comparison, checks=(failed, gap)))
    first = cited.headlines[0]
    assert (first.kind, first.level) == ("checks", "warning")
    assert "1 accuracy check failed" in first.text
    assert "physical requirement: energy (all, full) = 1.07, bound ≤ 1.001" in first.text
    assert "flux agreement" not in first.text
    passed = with_headlines(dataclasses.replace(comparison, checks=(
        dataclasses.replace(failed, value=1.0, passed=True),)))
    assert not [h for h in passed.headlines if h.kind == "checks"]

