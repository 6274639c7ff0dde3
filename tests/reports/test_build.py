"""The report's files without a browser: layout, escaping, tables, links, embedding."""

from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET
from dataclasses import replace
from html import unescape
from pathlib import Path

import numpy as np
import pytest

from reports import build_report, scene_folder
from reports.build import hardware, speedup_text
from reports.page_data import RELATIVE_BOUND
from reports.records import METRIC_FORMULAS, EqualErrorSpeedup, Table
from scenes.colour import LUMA
from tests.reports.conftest import HOSTILE_NAME, hdr_uris
from tests.reports.data_helpers import page_layers


@pytest.fixture(scope="module")
def linked(tmp_path_factory, comparison, hostile_comparison) -> Path:
    """A linked (multi-file) report of two scenes."""
    out = tmp_path_factory.mktemp("linked")
    build_report(out, [comparison, hostile_comparison])
    return out


@pytest.fixture(scope="module")
def embedded(tmp_path_factory, comparison, hostile_comparison) -> Path:
    """A self-contained report of the same two scenes."""
    out = tmp_path_factory.mktemp("embedded")
    build_report(out, [comparison, hostile_comparison], self_contained=True)
    return out


@pytest.mark.parametrize(("name", "expected"), [
    ("glass_sphere", "glass_sphere"),
    ("a/b", "a_b"),
    ("../../etc/passwd", "etc_passwd"),
    ("<script>alert(1)</script>", "script_alert_1_script"),
    ("", "scene"),
    ("...", "scene"),
    ("_static", "static"),
    ("Wasser über Glas", "Wasser_uber_Glas"),
])
def test_scene_folder_is_a_safe_single_path_component(name, expected):
    assert scene_folder(name) == expected


def test_scene_folder_never_repeats_and_stays_short():
    taken = []
    for _ in range(3):
        taken.append(scene_folder("a/b", taken=taken))
    assert taken == ["a_b", "a_b-2", "a_b-3"]
    assert len(scene_folder("x" * 500)) == 64


def test_layout_of_a_linked_report(linked, comparison):
    """index.html, the vendored static files, and one folder per scene with its
    previews, plots and HDR data; nothing written outside ``out_dir``."""
    assert (linked / "index.html").is_file()
    assert {p.name for p in (linked / "_static").iterdir()} == {"report.css", "report.js"}
    scene = linked / "glass_sphere-paper"
    for name in ("index.html", "hdr.js", "convergence.svg", "cost_accuracy.svg",
                 "camera_signed.png", "receiver0_flip.png", "thumbnail_method.png"):
        assert (scene / name).is_file(), name
    folders = sorted(p.name for p in linked.iterdir() if p.is_dir())
    hostile = scene_folder(f"{HOSTILE_NAME}-paper")
    assert folders == sorted(["_data", "_static", "glass_sphere-paper", hostile])


def test_the_pages_luminance_weights_are_the_metrics(linked, embedded):
    """Regression lock: the page's script has no weights of its own: both page forms
    carry ``window.causticsLuma`` with exactly :data:`scenes.colour.LUMA` (the probe
    and canvases weigh RGB with it), and the script reads them from there."""
    expected = f"window.causticsLuma = {json.dumps(LUMA.tolist())};"
    assert expected == "window.causticsLuma = [0.2126, 0.7152, 0.0722];"
    assert expected in (linked / "glass_sphere-paper" / "hdr.js").read_text("utf-8")
    assert expected in (embedded / "glass_sphere-paper" / "index.html").read_text("utf-8")
    script = (linked / "_static" / "report.js").read_text("utf-8")
    assert "report.LUMA = window.causticsLuma;" in script
    assert "0.7152" not in script


def test_self_contained_report_is_one_file_per_page(embedded):
    """Only HTML files are written, and they reference no other local file except
    the scene pages, the index and the EXR originals."""
    files = sorted(p.relative_to(embedded).as_posix() for p in embedded.rglob("*")
                   if p.is_file())
    assert files == sorted(["index.html", "glass_sphere-paper/index.html",
                            f"{scene_folder(f'{HOSTILE_NAME}-paper')}/index.html"])
    for page in files:
        html = (embedded / page).read_text("utf-8")
        refs = re.findall(r'(?:src|href)="([^"]*)"', html)
        assert refs, page
        for ref in refs:
            assert (ref.startswith("data:") or ref.endswith((".exr", "index.html"))
                    or ref.startswith("#")), (page, ref[:60])
        assert "<script src" not in html and "<link" not in html


def test_no_page_points_at_the_network(linked, embedded):
    """No src or href to http(s) or protocol-relative URLs, in either mode."""
    for root in (linked, embedded):
        for page in root.rglob("*.html"):
            refs = re.findall(r'(?:src|href)="([^"]*)"', page.read_text("utf-8"))
            assert not [r for r in refs if re.match(r"^(https?:)?//", r)], page


def test_hostile_text_is_escaped_and_folder_is_sanitised(linked, embedded):
    """Name and description appear only HTML-escaped; no raw tag survives."""
    folder = scene_folder(f"{HOSTILE_NAME}-paper")
    assert "/" not in folder and "<" not in folder
    for root in (linked, embedded):
        for page in (root / "index.html", root / folder / "index.html"):
            html = page.read_text("utf-8")
            assert "<script>window.__pwned" not in html
            assert '<img src=x' not in html
            assert "&lt;script&gt;window.__pwned = 1&lt;/script&gt;" in html


def test_metric_table_shows_excess_first_then_raw_and_formula(linked, comparison):
    """Regression lock on the page's Metrics table: the excess (the method's own error)
    comes before the raw value, and the seed-against-seed floor is last, labelled a
    diagnostic, never beside the raw value as a yardstick."""
    html = (linked / "glass_sphere-paper" / "index.html").read_text("utf-8")
    m = comparison.metric("receiver0", "caustic", "ssim")
    table = html[html.index("<caption>receiver0</caption>"):]
    header = table[:table.index("</thead>")]
    assert header.index("excess") < header.index("raw value") < header.index("diagnostic")
    row = re.search(r"<td>caustic</td><td>ssim</td>(.*?)</tr>", table, re.S).group(1)
    cells = re.findall(r"<td[^>]*>(.*?)</td>", row, re.S)
    assert f"{m.value:.4g}" in row and "Wang et al. 2004" in row
    assert cells[-1] == f"{m.noise_floor:.4g}"
    assert cells.index(f"{m.value:.4g}") < len(cells) - 1
    shown = {m.metric for m in comparison.metrics}
    for metric in shown:
        assert METRIC_FORMULAS[metric] in unescape(html), metric


def test_checks_pass_fail_gaps_and_none_by_kind(linked, embedded):
    """The summary counts passes, failures and known gaps, and per kind; a scene
    without checks says so. The page lists each kind under its own heading with what
    the kind means (a regression lock guards against change, not accuracy), a known
    gap apart from a failure."""
    index = (linked / "index.html").read_text("utf-8")
    assert "1/3 passed" in index and "(1 failed)" in index and "(1 known gap)" in index
    assert "0/1 · 0/0 · 1/2" in index
    assert "no accuracy checks applied" in index
    scene = unescape((linked / "glass_sphere-paper" / "index.html").read_text("utf-8"))
    assert scene.count('<tr class="fail">') == 1 and "FAIL" in scene
    assert scene.count('<tr class="gap">') == 1 and "a known gap, for the test" in scene
    for heading in ("Physical requirements: 0/1 passed, 1 known gap",
                    "Method targets: 0/0 passed", "Regression locks: 1/2 passed, 1 failed"):
        assert heading in re.sub(r"<[^>]+>", "", scene), heading
    assert "guards against change, not accuracy" in scene
    assert "|v − 1| ≤ 0.02" in scene


def test_provenance_settings_and_claims_are_shown(linked, comparison):
    html = (linked / "glass_sphere-paper" / "index.html").read_text("utf-8")
    for text in ("caustic_map", "L T T D", "3.9.0", "frame_time_ms",
                 "scenes/glass_sphere.toml", "refraction.double",
                 "one iteration is enough for rendering", "lost_splats"):
        assert text in html, text
    assert f"{comparison.speedup.speedup:.4g}×" in html


def test_exr_links_are_relative_and_flag_missing_files(tmp_path, comparison):
    """Links resolve from the scene page; a missing original is marked; a path that
    leaves the scene folder is not linked."""
    c = replace(comparison, files={"camera/method": "camera_method.exr",
                                   "camera/reference": "../../escape.exr"})
    (tmp_path / "glass_sphere-paper").mkdir()
    (tmp_path / "glass_sphere-paper" / "camera_method.exr").write_bytes(b"x")
    build_report(tmp_path, [c])
    html = (tmp_path / "glass_sphere-paper" / "index.html").read_text("utf-8")
    assert '<a href="camera_method.exr">camera_method.exr</a></li>' in html
    assert 'href="../../escape.exr"' not in html and "not linked" in html
    build_report(tmp_path, [replace(c, files={"camera/method": "gone.exr"})])
    page = tmp_path / "glass_sphere-paper" / "index.html"
    assert "not found beside this page" in page.read_text()


def test_views_with_float_data_ship_them_instead_of_hdr_previews(linked, comparison):
    """A view with float data is drawn from them: its shipped method and reference are
    the comparison's images (receiver maps upside down so +v points up) within the
    data's promise, half the 0.1 % bound (``reports.page_data``), and ``hdr.js`` carries
    no RGBE preview for it."""
    assert hdr_uris(linked / "glass_sphere-paper") == {}
    for view, flip in (("camera", False), ("receiver0", True)):
        _, layers = page_layers(linked / "glass_sphere-paper", view)
        for layer in ("method", "reference"):
            expected = np.asarray(comparison.images[f"{view}/{layer}"], np.float64)
            expected = expected[::-1] if flip else expected
            error = np.abs(layers[layer] - expected)
            assert np.all(error <= RELATIVE_BOUND / 2 * np.abs(expected)), (view, layer)


def test_large_images_are_downsampled_and_the_page_says_so(tmp_path, comparison_factory):
    c = comparison_factory(camera=(300, 400), receiver=(32, 32))
    build_report(tmp_path, [c], preview_size=128)
    html = (tmp_path / "glass_sphere-paper" / "index.html").read_text("utf-8")
    assert "box-filtered down 4×" in html
    _, camera = page_layers(tmp_path / "glass_sphere-paper", "camera")
    assert camera["method"].shape == (75, 100, 3)


def test_plots_are_valid_svg_with_the_pareto_front(linked):
    cost = ET.parse(linked / "glass_sphere-paper" / "cost_accuracy.svg").getroot()
    assert cost.tag.endswith("svg")
    text = (linked / "glass_sphere-paper" / "cost_accuracy.svg").read_text("utf-8")
    assert "Pareto front" in text and "equal-error speedup" in text
    conv = (linked / "glass_sphere-paper" / "convergence.svg").read_text("utf-8")
    for label in ("modified", "newton (safeguarded)", "secant"):
        assert label in conv


def test_optional_parts_may_be_missing(tmp_path, comparison):
    """No studies, no checks, no receiver: the page still builds
    and says what was not run."""
    c = replace(comparison, sections=(), files={}, checks=(), stability=None,
                images={k: v for k, v in comparison.images.items() if k.startswith("camera/")})
    build_report(tmp_path, [c])
    html = (tmp_path / "glass_sphere-paper" / "index.html").read_text("utf-8")
    assert html.count("<p>Not run.</p>") == 3 and "No accuracy checks applied." in html
    assert "No originals written." in html and "receiver0_signed" not in html


def test_bad_image_key_is_refused(tmp_path, comparison):
    c = replace(comparison, images={"../evil/method": np.zeros((2, 2, 3))})
    with pytest.raises(ValueError, match="image keys"):
        build_report(tmp_path, [c])


def test_rebuild_overwrites_in_place(tmp_path, comparison):
    """Building twice gives the same page (deterministic output, atomic rewrites)."""
    build_report(tmp_path, [comparison])
    first = (tmp_path / "glass_sphere-paper" / "index.html").read_bytes()
    svg = (tmp_path / "glass_sphere-paper" / "cost_accuracy.svg").read_bytes()
    build_report(tmp_path, [comparison])
    assert (tmp_path / "glass_sphere-paper" / "index.html").read_bytes() == first
    assert (tmp_path / "glass_sphere-paper" / "cost_accuracy.svg").read_bytes() == svg
    assert not list(tmp_path.rglob("*.tmp"))


def test_crosscheck_section_shows_the_result_when_one_was_run(tmp_path, comparison):
    """With a cross-check the scene page tables its ratios, noise and verdicts, and
    names the other renderer; without one it says it was not run and how to run it."""
    table = Table(("kind", "label", "share", "reference_w", "other_w", "ratio", "deviation_pct",
                   "sigma_pct", "z", "tolerance_pct", "agrees"),
                  (("total", "all", 1.0, 4.8402, 4.8368, 1.0007, 0.0703, 0.17, 0.41, 0.5, True),
                   ("region", "block (3, 4)", 0.011, 0.05, 0.048, 1.0473, 4.73, 5.06, 0.93, 2.0,
                    False)))
    provenance = replace(comparison.provenance, crosscheck={
        "transport": "full: all L S+ D paths", "other": {"renderer": "luxcore LIGHTCPU"}})
    checked = replace(comparison, name="checked", crosscheck=table, provenance=provenance)
    build_report(tmp_path, [checked, comparison])
    page = unescape((tmp_path / "checked-paper" / "index.html").read_text("utf-8"))
    section = page[page.index('<section id="crosscheck">'):]
    section = section[:section.index("</section>")]
    assert "luxcore LIGHTCPU" in section and "block (3, 4)" in section
    assert "0.0703" in section and "4.73" in section and "4.84" in section
    plain = unescape((tmp_path / "glass_sphere-paper" / "index.html").read_text("utf-8"))
    assert "Not run (caustics compare --crosscheck luxcore" in re.sub(r"<[^>]+>", "", plain)


def test_an_open_mesh_is_said_on_the_page(tmp_path, comparison):
    """Regression lock ("every failure is one clear line"): a scene with a
    non-watertight mesh says on its page that it was rendered as an open surface;
    a scene without one says nothing of the kind."""
    build_report(tmp_path / "open", [replace(comparison, effects=(*comparison.effects,
                                                                  "open_mesh"))])
    build_report(tmp_path / "closed", [comparison])
    open_page = next((tmp_path / "open").glob("*/index.html")).read_text()
    closed_page = next((tmp_path / "closed").glob("*/index.html")).read_text()
    assert 'id="open-mesh"' in open_page and "open surface" in open_page
    assert 'id="open-mesh"' not in closed_page


@pytest.mark.parametrize(("speedup", "text"), [
    (EqualErrorSpeedup(12.5, 3.0, "interpolated", low=8.25, high=19.5),
     "12.5× (95 % interval 8.25×–19.5×)"),
    # An exact fit propagates no uncertainty: ends equal to 4 digits say nothing.
    (EqualErrorSpeedup(1201.8, 3.0, "interpolated", low=1201.81912, high=1201.81913), "1202×"),
    (EqualErrorSpeedup(40.0, 3.0, "extrapolated", low=40.0, high=float("inf"),
                       bound_kind="lower bound"), "at least 40× (95 % confidence)"),
    (EqualErrorSpeedup(2.0, 3.0, "bound", high=2.0, bound_kind="upper bound"), "at most 2×"),
    (EqualErrorSpeedup(3.0, 3.0, "interpolated"), "3×"),
])
def test_a_speedup_shows_its_interval_or_bound(speedup, text):
    """An estimate shows its 95 % interval where one was computed; a lower bound reads
    "at least", an upper bound "at most"."""
    assert speedup_text(speedup) == text


def test_hardware_names_the_gpu_only_when_one_renders(comparison):
    """An NVIDIA GL renderer names its GPU and a CUDA reference runs on a GPU; llvmpipe
    and an LLVM reference run on the CPU; nothing recorded is said to be so."""
    def with_(gl, variant, machine):
        prov = comparison.provenance
        return replace(comparison, provenance=replace(
            prov, method=replace(prov.method, gl_renderer=gl), machine=machine,
            reference={"variant": variant} if variant else {}))

    gpu = hardware(with_("NVIDIA H100 80GB HBM3/PCIe/SSE2", "cuda_ad_rgb",
                         {"cpus": 16, "processor": "x86_64"}))
    assert gpu["gpu"] == "NVIDIA H100 80GB HBM3" and gpu["reference_device"] == "a GPU (CUDA)"
    assert "16 CPUs, processor x86_64" in gpu["text"]
    cpu = hardware(with_("llvmpipe (LLVM 19.1.1, 256 bits)", "llvm_ad_rgb", {"cpus": 2}))
    assert cpu["gpu"] is None and "no GPU" in cpu["text"] and "on the CPU" in cpu["text"]
    assert "processor not recorded" in cpu["text"]
    unknown = hardware(with_(None, None, {}))
    assert unknown["gpu"] is None
    assert all(part in unknown["text"] for part in (
        "GL renderer not recorded", "CPU count not recorded", "variant not recorded"))
