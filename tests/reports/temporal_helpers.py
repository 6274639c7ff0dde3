"""Shared by the temporal report tests: a realistic temporal record built from
synthetic sequences by the real scoring code (``harness.studies.temporal``), a
the checks that the page's animation decodes, plays and
pauses.

Synthetic sequences: a caustic (a Gaussian on a dim floor) moving 1.5 px per frame;
the reference and an independent reference carry Monte Carlo-like noise of 3 % of
the level; the method is the noise-free caustic, 10 % too dim, with a patch that
alternates by ±``shimmer`` of the level every frame (flicker).
"""

from __future__ import annotations

import dataclasses
import io
import time
from pathlib import Path

import numpy as np
from PIL import Image

from harness.studies.temporal import compare_sequences
from reports.records import RecordSection, SceneComparison
from reports.temporal_records import TemporalComparison
from tests.reports.test_browser import open_ready_page

__all__ = [
    "FPS",
    "FRAMES",
    "check_player",
    "decode_webp",
    "make_temporal",
    "with_temporal",
]

FRAMES, SIZE, FPS = 6, 48, 10.0


def _truth(frames: int, size: int) -> np.ndarray:
    y, x = np.mgrid[0:size, 0:size].astype(np.float64)
    out = []
    for t in range(frames):
        blob = 400.0 * np.exp(-((x - 12 - 1.5 * t) ** 2 + (y - size / 2) ** 2) / (2 * 4.0**2))
        out.append(np.repeat((20.0 + blob)[..., None], 3, axis=2) * [1.0, 0.9, 0.7])
    return np.stack(out)


def make_temporal(*, shimmer: float = 0.05, seed: int = 0, frames: int = FRAMES,
                  size: int = SIZE) -> TemporalComparison:
    """A temporal record scored by :func:`compare_sequences` (see the module docstring)."""
    rng = np.random.default_rng(seed)
    truth = _truth(frames, size)

    def noisy() -> np.ndarray:
        return truth * (1 + 0.03 * rng.standard_normal(truth.shape))

    method = truth * 0.9
    sign = (-1.0) ** np.arange(frames)
    method[:, 20:30, 10:30] *= 1 + shimmer * sign[:, None, None, None]
    times = [t / FPS for t in range(frames)]
    return compare_sequences(noisy(), method, noisy(), times=times, fps=FPS,
                             columns={"method_ms": [2.0] * frames})


def with_temporal(comparison: SceneComparison, temporal: TemporalComparison, *,
                  method: str | None = None) -> SceneComparison:
    """``comparison`` with the temporal record (and another method name)."""
    section = RecordSection("temporal", "Temporal stability", temporal, temporal.files["table"])
    return dataclasses.replace(comparison.with_section(section),
                               method=method or comparison.method)


def decode_webp(data: bytes) -> list[np.ndarray]:
    """Every frame of an animated WebP as uint8 RGB (Pillow)."""
    picture = Image.open(io.BytesIO(data))
    frames = []
    for index in range(picture.n_frames):
        picture.seek(index)
        frames.append(np.asarray(picture.convert("RGB")))
    return frames


def open_page(browser, path: Path, *, init_script: str | None = None):
    """A page at ``path`` with its ``PageLog``, the temporal player set up."""
    return open_ready_page(browser, path, ready="temporalReady", init_script=init_script)


def _canvas(page) -> np.ndarray:
    w, h, values = page.evaluate("""() => {
        const c = document.querySelector('canvas.temporal-frame');
        const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
        return [c.width, c.height, Array.from(d)];
    }""")
    return np.asarray(values, np.uint8).reshape(h, w, 4)


def _frame(page) -> int:
    return int(page.locator("canvas.temporal-frame").get_attribute("data-frame"))


def _playing(page) -> bool:
    return page.locator(".temporal-player").get_attribute("data-playing") == "true"


def check_player(page, frames: list[np.ndarray], *, fps: float) -> None:
    """The player decoded every frame of the file; it plays (the frame advances), a
    click pauses it (frame and pixels stay), single steps show exactly the file's
    frames (lossless: the canvas's RGB equals Pillow's decoding, alpha opaque), the
    slider seeks, and a click plays again."""
    player = page.locator(".temporal-player")
    assert player.get_attribute("data-mode") == "player"
    assert int(player.get_attribute("data-decoded-frames")) == len(frames)
    assert _playing(page)
    seen = {_frame(page)}
    deadline = time.monotonic() + 10 * len(frames) / fps + 5
    while len(seen) < 3 and time.monotonic() < deadline:
        page.wait_for_timeout(1000 / fps)
        seen.add(_frame(page))
    assert len(seen) >= 3, f"the animation does not advance: frames {sorted(seen)}"

    page.locator("button.temporal-play").click()
    assert not _playing(page)
    assert page.locator("button.temporal-play").text_content() == "Play"
    paused, pixels = _frame(page), _canvas(page)
    page.wait_for_timeout(3 * 1000 / fps + 100)
    assert _frame(page) == paused
    assert np.array_equal(_canvas(page), pixels)

    for _ in range(2):
        page.locator("button.temporal-forward").click()
        index = _frame(page)
        assert index == (paused + 1) % len(frames)
        shown = _canvas(page)
        assert np.all(shown[..., 3] == 255)
        assert np.array_equal(shown[..., :3], frames[index]), f"frame {index} differs"
        paused = index
    page.locator("button.temporal-back").click()
    assert _frame(page) == (paused - 1) % len(frames)
    page.locator("input.temporal-seek").fill(str(len(frames) - 1))
    assert _frame(page) == len(frames) - 1
    assert np.array_equal(_canvas(page)[..., :3], frames[-1])
    assert page.locator("output.temporal-label").text_content().startswith(
        f"frame {len(frames)} / {len(frames)}")

    page.locator("button.temporal-play").click()
    assert _playing(page)
    start, deadline = _frame(page), time.monotonic() + 10 / fps + 5
    while _frame(page) == start:
        assert time.monotonic() < deadline, "the animation does not play again"
        page.wait_for_timeout(500 / fps)
