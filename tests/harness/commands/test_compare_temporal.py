"""``caustics compare water_pool --studies temporal --frames N`` end to end, on both
real renderers and both presets: ``temporal.csv``, the flicker metrics in
``metrics.json``, the EXR maps, an animated WebP linked from the page, the index's
comparison of the presets, the reference frames shared through the cache; the real
page's animation plays in Chromium. ``--frames`` is refused without the study.

The bundled water_pool (the paper's 100 × 100 water grid, waves and a plop), made
small: 48² camera, 48² vertex grid, 64² receiver map, 100 000 photons on 2 seeds,
6 frames (about 40 s on 2 CPU cores).

Kind: regression locks of the command's outputs (the accuracy of the numbers is
``tests/harness/studies/test_temporal.py``'s)."""

from __future__ import annotations

import csv
import json
import math

import pytest

from harness.cli import main
from harness.studies.temporal import COLUMNS
from tests.browser import new_context
from tests.conftest import SCENES
from tests.reports.temporal_helpers import check_player, decode_webp, open_page

FRAMES = 6
SMALL = ["--set", "photons=100000", "--set", "seeds=2", "--set", "spp=2",
         "--set", "grid=48", "--set", "caustic_map=128", "--set", "positions_map=128",
         "--set", "receiver_map=[64, 64]"]


def _strict(text: str):
    """JSON that refuses NaN and Infinity (the strict JSON the harness writes)."""
    def refuse(token):
        raise ValueError(f"non-strict JSON token {token}")
    return json.loads(text, parse_constant=refuse)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """One compare run of the small water_pool with the temporal study, both presets."""
    tmp = tmp_path_factory.mktemp("temporal-compare")
    text = (SCENES / "water_pool.toml").read_text("utf-8")
    scene = tmp / "water_pool.toml"
    scene.write_text(text.replace("resolution = [512, 512]", "resolution = [48, 48]"))
    out = tmp / "out"
    code = main(["compare", str(scene), "-o", str(out), "--studies", "temporal",
                 "--frames", str(FRAMES), "-q", *SMALL])
    return code, out


@pytest.mark.parametrize("preset", ["paper", "strong"])
def test_temporal_study_writes_its_table_metrics_maps_and_animation(run, preset):
    """Per preset: temporal.csv (one row per frame, every column, no flicker pair for
    frame 0), strict metrics.json with the flicker and energy ratio per region beside
    their noise floors, the run time, the reference's common random numbers (the
    second preset takes every reference frame from the cache), the EXR maps, and the
    animated WebP of every frame linked from the page."""
    code, out = run
    assert code == 0
    folder = out / f"water_pool-{preset}"
    with (folder / "temporal.csv").open(newline="") as handle:
        rows = list(csv.reader(handle))
    assert tuple(rows[0]) == COLUMNS and len(rows) == FRAMES + 1
    table = [dict(zip(COLUMNS, r, strict=True)) for r in rows[1:]]
    assert [int(r["frame"]) for r in table] == list(range(FRAMES))
    assert table[0]["flicker_caustic"] == "" and float(table[1]["flicker_caustic"]) > 0
    assert [float(r["time_s"]) for r in table] == pytest.approx([i / 30 for i in range(FRAMES)])

    data = _strict((folder / "metrics.json").read_text("utf-8"))
    temporal = data["studies"]["temporal"]
    assert temporal["frames"] == FRAMES and temporal["fps"] == 30.0
    for region in ("caustic", "full"):
        f = temporal["flicker"][region]
        assert all(math.isfinite(f[k]) for k in ("value", "noise_floor", "excess"))
        e = temporal["hf_energy_ratio"][region]
        assert all(math.isfinite(e[k]) for k in ("value", "noise_floor", "noise_corrected"))
    assert temporal["flicker"]["caustic"]["value"] == pytest.approx(
        sum(float(r["flicker_caustic"]) for r in table[1:]) / (FRAMES - 1), rel=1e-9)
    assert "flicker" in temporal["formulas"]
    assert temporal["run_time_s"]["total"] > 0
    reference = temporal["reference"]
    assert reference["common_random_numbers"] is True and reference["seeds"] == 2
    assert reference["cache"] == ({"hit": 0, "rendered": 2 * FRAMES} if preset == "paper"
                                  else {"hit": 2 * FRAMES, "rendered": 0})
    for name in temporal["files"].values():
        assert (folder / name).stat().st_size > 0, name

    webp = folder / "temporal_receiver0.webp"
    assert len(decode_webp(webp.read_bytes())) == FRAMES
    page = (folder / "index.html").read_text("utf-8")
    assert 'src="temporal_receiver0.webp"' in page and 'href="temporal.csv"' in page


def test_the_index_compares_the_presets_flicker(run):
    """The index's temporal section links both pages and says which preset flickers
    less, with the ratio of their flicker."""
    code, out = run
    assert code == 0
    index = (out / "index.html").read_text("utf-8")
    assert 'href="water_pool-paper/index.html#temporal"' in index
    assert 'href="water_pool-strong/index.html#temporal"' in index
    assert "flickers least over the caustic region" in index


def test_frames_needs_the_temporal_study(tmp_path, capsys):
    """``--frames`` without the temporal study is a usage error (exit 2, one line),
    before anything renders; so is a sequence of fewer than two frames."""
    assert main(["compare", "water_pool", "-o", str(tmp_path / "out"), "--frames", "6"]) == 2
    assert "(--frames) sets the temporal study's frames" in capsys.readouterr().err
    with pytest.raises(SystemExit) as info:
        main(["compare", "water_pool", "-o", str(tmp_path / "out"), "--studies", "temporal",
              "--frames", "1"])
    assert info.value.code == 2
    assert "must be at least 2" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_the_real_animation_plays_in_chromium(run, chromium):
    """The strong preset's page of the run above in headless Chromium: the player
    decodes the real animation's 6 frames, plays, pauses, steps through exactly the
    file's frames; no console error, no request off the machine."""
    code, out = run
    assert code == 0
    folder = out / "water_pool-strong"
    frames = decode_webp((folder / "temporal_receiver0.webp").read_bytes())
    with new_context(chromium) as browser:
        page, log = open_page(browser, folder / "index.html")
        check_player(page, frames, fps=30.0)
        log.assert_clean()
        page.close()
