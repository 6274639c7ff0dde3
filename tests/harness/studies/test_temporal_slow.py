"""water_pool's animation at the scene's own settings (docs/architecture.md, "Temporal stability"):
``caustics compare water_pool --studies temporal --frames 24`` writes its table,
flicker metrics and animation for both presets, and the strong preset flickers less
than the paper preset. Slow: 2 × 24 reference frames of 2 M photons × 4 seeds (about
1 s each on 2 CPU cores, cached afterwards) and per-frame FLIP (about 2 s a frame)."""

from __future__ import annotations

import csv
import json

import pytest

from harness.cli import main
from tests.reports.temporal_helpers import decode_webp

pytestmark = [pytest.mark.slow, pytest.mark.method_target]

FRAMES = 24


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("water-pool-temporal") / "out"
    assert main(["compare", "water_pool", "--studies", "temporal", "--frames", str(FRAMES),
                 "-o", str(out), "-q"]) == 0
    return out


def _temporal(out, preset: str) -> dict:
    data = json.loads((out / f"water_pool-{preset}" / "metrics.json").read_text())
    return data["studies"]["temporal"]


@pytest.mark.parametrize("preset", ["paper", "strong"])
def test_water_pool_24_frames_writes_table_metrics_and_animation(run, preset):
    """temporal.csv has 24 frames, metrics.json the flicker beside its noise floor, the
    page links the 24-frame animated WebP."""
    folder = run / f"water_pool-{preset}"
    with (folder / "temporal.csv").open(newline="") as handle:
        assert len(list(csv.DictReader(handle))) == FRAMES
    temporal = _temporal(run, preset)
    assert temporal["frames"] == FRAMES
    assert temporal["flicker"]["caustic"]["value"] > 0
    assert temporal["flicker"]["caustic"]["noise_floor"] > 0
    assert len(decode_webp((folder / "temporal_receiver0.webp").read_bytes())) == FRAMES
    assert 'src="temporal_receiver0.webp"' in (folder / "index.html").read_text("utf-8")


def test_strong_flickers_less_than_paper_on_water_pool(run):
    """Method target: the strong preset's flicker above the reference's noise (the
    excess F − floor / 2) is at most half the paper preset's. Reason: its triangle
    splats follow the moving ripples (it keeps about half of the reference's temporal
    high-frequency energy, the paper preset's Gaussian points under 2 %), so its error
    changes less from frame to frame. Measured 0.0032 against 0.0101 (3.1×), and the
    raw flicker 0.0141 against 0.0210; the target asks for 2× on the excess."""
    paper = _temporal(run, "paper")["flicker"]["caustic"]
    strong = _temporal(run, "strong")["flicker"]["caustic"]
    assert strong["value"] < paper["value"]
    assert strong["excess"] <= 0.5 * paper["excess"], (strong, paper)
