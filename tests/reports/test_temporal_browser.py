"""The temporal section in a real browser: headless Chromium (Debian's ``chromium``)
driven by Playwright, on file:// pages, linked and self-contained. The animation
plays, pauses, steps and seeks, shows the WebP's frames exactly, and the page logs no
console error and makes no request off the machine; without ``ImageDecoder`` the
WebP plays as a plain image. Screenshots go to ``test-artifacts/``.

Skipped with the reason when Chromium or playwright is missing (a failure under CI),
as ``tests/reports/test_browser.py``."""

from __future__ import annotations

import pytest

from reports import build_report, scene_folder
from tests.browser import new_context
from tests.conftest import REPO
from tests.reports.conftest import make_comparison
from tests.reports.temporal_helpers import (
    FPS,
    check_player,
    decode_webp,
    make_temporal,
    open_page,
    with_temporal,
)

ARTIFACTS = REPO / "test-artifacts"


@pytest.fixture(scope="module")
def browser(chromium):
    with new_context(chromium) as context:
        yield context


@pytest.fixture(scope="module")
def pages(tmp_path_factory):
    """One scene with a temporal record, as a linked and a self-contained report."""
    comparison = with_temporal(make_comparison(name="water_pool"), make_temporal())
    out = {}
    for mode, embed in (("linked", False), ("embedded", True)):
        root = tmp_path_factory.mktemp(f"temporal-{mode}")
        build_report(root, [comparison], self_contained=embed)
        out[mode] = root / scene_folder(comparison.page) / "index.html"
    # The file the linked page ships: what every mode must show, frame for frame.
    webp = (out["linked"].parent / "temporal_receiver0.webp").read_bytes()
    return out, decode_webp(webp)


@pytest.mark.parametrize("mode", ["linked", "embedded"])
def test_the_animation_plays_and_pauses_in_chromium(browser, pages, mode):
    """The player decodes every frame of the WebP, plays on load, pauses on a click
    (frame and pixels stay), steps and seeks to exactly the file's frames, plays
    again; every image decodes; no console error, no failed or external request."""
    paths, frames = pages
    page, log = open_page(browser, paths[mode])
    check_player(page, frames, fps=FPS)
    state = page.evaluate("""Array.from(document.querySelectorAll('#temporal img[src]')).map(
        (i) => [i.getAttribute('src').slice(0, 40), i.complete, i.naturalWidth])""")
    # 2 plots, 3 maps and their colour bars (and, linked, the hidden fallback animation)
    assert len(state) >= 8
    assert all(complete and width > 0 for _, complete, width in state), state
    ARTIFACTS.mkdir(exist_ok=True)
    page.locator("button.temporal-play").click()  # paused for a stable screenshot
    page.locator("#temporal").screenshot(path=str(ARTIFACTS / f"report-temporal-{mode}.png"))
    log.assert_clean()
    page.close()


@pytest.mark.parametrize("mode", ["linked", "embedded"])
def test_without_image_decoder_the_webp_plays_as_an_image(browser, pages, mode):
    """A browser without ``ImageDecoder`` gets the animated WebP itself (it decodes and
    is shown; a self-contained page sets it from the player's data: URI, its only
    copy), the player's controls hidden and a note saying why; no error."""
    paths, _ = pages
    page, log = open_page(browser, paths[mode], init_script="delete window.ImageDecoder;")
    assert page.locator(".temporal-player").get_attribute("data-mode") == "fallback"
    image = page.locator(".temporal-fallback img")
    assert image.is_visible()
    assert page.evaluate("document.querySelector('.temporal-fallback img').naturalWidth") > 0
    assert not page.locator("canvas.temporal-frame").is_visible()
    assert "no ImageDecoder" in page.locator(".temporal-why").text_content()
    log.assert_clean()
    page.close()
