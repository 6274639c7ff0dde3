"""The report's temporal section, without a browser: what is written beside a page
(or into it), the animation file frame for frame, and the index's comparison of the
presets. Records are scored by the real code from synthetic sequences
(``tests/reports/temporal_helpers.py``).

Kind: regression locks of the report's contract (no accuracy is measured here)."""

from __future__ import annotations

import base64
import hashlib
import re

import numpy as np
import pytest

from reports import build_report, scene_folder
from reports.images import downsample
from reports.temporal import GAP, PROGRESS_HEIGHT, animation_frames, compare_flicker
from scenes.colour import tonemap
from tests.reports.conftest import make_comparison
from tests.reports.temporal_helpers import FRAMES, decode_webp, make_temporal, with_temporal


@pytest.fixture(scope="module")
def records():
    """Two methods of one scene: ``paper`` shimmers by ±8 %, ``strong`` by ±2 %."""
    base = make_comparison(name="water_pool")
    return [with_temporal(base, make_temporal(shimmer=0.08), method="paper"),
            with_temporal(base, make_temporal(shimmer=0.02, seed=1), method="strong")]


@pytest.fixture(scope="module")
def linked(records, tmp_path_factory):
    root = tmp_path_factory.mktemp("temporal-linked")
    build_report(root, records)
    return root


def test_the_animation_file_holds_every_frame_losslessly(linked, records):
    """The WebP beside the page is an animation of T frames, each exactly the frame
    the report composed (lossless): method | reference | difference, a progress bar
    under them; the method panel is the tone-mapped method frame with +v up."""
    temporal = records[0].temporal
    page = linked / scene_folder(records[0].page)
    decoded = decode_webp((page / "temporal_receiver0.webp").read_bytes())
    composed = animation_frames(temporal)
    assert len(decoded) == len(composed) == FRAMES
    for got, want in zip(decoded, composed, strict=True):
        np.testing.assert_array_equal(got, want)
    h = temporal.method.shape[1]
    assert composed[0].shape == (h + GAP + PROGRESS_HEIGHT, 3 * h + 2 * GAP, 3)
    expected = np.round(tonemap(downsample(temporal.method[0][::-1], max_size=256)[0],
                                white=temporal.white) * 255)
    np.testing.assert_array_equal(composed[0][:h, :h], expected)
    bars = [int((f[-1, :, 0] > 200).sum()) for f in composed]
    assert bars == sorted(bars) and len(set(bars)) == FRAMES  # no two frames alike


def test_a_linked_page_links_the_animation_and_its_data(linked, records):
    """The page has the temporal section (and its table of contents entry), the
    animation as an image and a download link, the player's script beside it with the
    same WebP as a data: URI, the maps, plots and temporal data files linked."""
    page = linked / scene_folder(records[0].page)
    html = (page / "index.html").read_text("utf-8")
    assert 'href="#temporal"' in html and '<section id="temporal">' in html
    assert 'src="temporal_receiver0.webp"' in html
    assert 'href="temporal_receiver0.webp" download' in html
    assert '<script src="temporal.js"></script>' in html
    script = (page / "temporal.js").read_text("utf-8")
    uri = re.search(r'causticsTemporal\["receiver0"\] = "([^"]+)"', script).group(1)
    assert base64.b64decode(uri.split(",", 1)[1]) == (page / "temporal_receiver0.webp").read_bytes()
    for name in ("temporal_series.svg", "temporal_strip.png", "temporal_flicker.png",
                 "temporal_flicker_floor.png", "temporal_hf_ratio.png"):
        assert (page / name).stat().st_size > 500, name
        assert f'src="{name}"' in html
    assert 'href="temporal.csv"' in html
    assert "Fig. 8 analogue" in html


def test_a_self_contained_page_embeds_the_player_under_its_csp(records, tmp_path):
    """Self-contained: nothing beside the page but the page; the player's script is
    inline and allowed by its SHA-256 in the page's Content-Security-Policy."""
    build_report(tmp_path, records[:1], self_contained=True)
    folder = tmp_path / scene_folder(records[0].page)
    assert sorted(p.name for p in folder.iterdir()) == ["index.html"]
    html = (folder / "index.html").read_text("utf-8")
    scripts = re.findall(r"<script>(.*?)</script>", html, flags=re.S)
    player = [s for s in scripts if "causticsTemporal" in s]
    assert len(player) == 1
    digest = base64.b64encode(hashlib.sha256(player[0].encode()).digest()).decode()
    assert f"'sha256-{digest}'" in html
    assert html.count("data:image/webp;base64,") == 1  # the animation is embedded once


def test_the_index_says_which_preset_flickers_less_and_by_how_much(linked, records):
    """The index's temporal table lists both methods with their flicker and noise
    floors, and its sentence names the one with the lower flicker and the ratio of the
    two (paper's ±8 % shimmer against strong's ±2 %)."""
    html = (linked / "index.html").read_text("utf-8")
    assert '<section id="temporal-summary">' in html
    paper, strong = (r.temporal.summary["flicker"]["caustic"]["value"] for r in records)
    assert paper > strong
    sentence = compare_flicker("water_pool", [
        {"method": r.method, "region": "caustic", **r.temporal.summary["flicker"]["caustic"]}
        for r in records])
    assert sentence.startswith("water_pool: strong flickers least over the caustic region;")
    assert f"paper's flicker is {paper / strong:.2f}× strong's" in sentence
    assert sentence in html.replace("&#39;", "'")


def test_pages_without_the_study_are_unchanged(tmp_path):
    """No temporal record: no section, no script, no link in the table of contents,
    and no temporal summary on the index."""
    comparison = make_comparison()
    build_report(tmp_path, [comparison])
    folder = tmp_path / scene_folder(comparison.page)
    html = (folder / "index.html").read_text("utf-8")
    assert 'id="temporal"' not in html and "temporal.js" not in html
    assert not (folder / "temporal.js").exists()
    assert "temporal-summary" not in (tmp_path / "index.html").read_text("utf-8")
