"""The report in a real browser: headless Chromium (Debian's ``chromium``) driven by
Playwright, on file:// pages, linked and self-contained.

The run's one Chromium (``tests/browser.py``): skipped with the reason when
``/usr/bin/chromium`` or ``playwright`` is missing, except under CI, where that fails.
Screenshots are written to ``test-artifacts/`` at the repository root.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest

from harness.metrics import tonemap
from reports import build_report, scene_folder
from tests.browser import new_context
from tests.conftest import REPO
from tests.reports.conftest import HOSTILE_DESCRIPTION, HOSTILE_NAME
from tests.reports.data_helpers import page_layers

ARTIFACTS = REPO / "test-artifacts"


@pytest.fixture(scope="module")
def browser(chromium):
    """A fresh browser context on the run's one Chromium, closed after the module."""
    with new_context(chromium) as context:
        yield context


@pytest.fixture(scope="module")
def reports(tmp_path_factory, comparison, hostile_comparison) -> dict[str, Path]:
    """The same two scenes as a linked and as a self-contained report."""
    out = {}
    for mode, embed in (("linked", False), ("embedded", True)):
        root = tmp_path_factory.mktemp(mode)
        build_report(root, [comparison, hostile_comparison], self_contained=embed)
        out[mode] = root
    return out


class PageLog:
    """Console errors, page errors, failed and non-local requests of one page."""

    def __init__(self, page):
        self.errors: list[str] = []
        self.failed: list[str] = []
        self.external: list[str] = []
        self.requests: list[str] = []
        page.on("console", lambda m: m.type == "error" and self.errors.append(m.text))
        page.on("pageerror", lambda e: self.errors.append(f"pageerror: {e}"))
        page.on("requestfailed", lambda r: self.failed.append(f"{r.url[:100]} {r.failure}"))
        page.on("request", self._request)
        page.route("**/*", self._route)

    def _local(self, url: str) -> bool:
        return url.startswith(("file:", "data:"))

    def _request(self, request) -> None:
        # A file's URL whole (a test matches it by its name, and a temporary folder
        # under xdist is long); a data: URI cut, it can be megabytes.
        url = request.url
        self.requests.append(url[:100] if url.startswith("data:") else url)
        if not self._local(request.url):
            self.external.append(request.url)

    def _route(self, route) -> None:
        if self._local(route.request.url):
            route.continue_()
        else:
            route.abort()

    def assert_clean(self) -> None:
        assert not self.errors, self.errors
        assert not self.failed, self.failed
        assert not self.external, self.external


def open_ready_page(browser, path: Path, *, ready: str = "hdrReady",
                    init_script: str | None = None):
    """(page, its PageLog) of ``path`` opened in ``browser`` (after ``init_script``,
    if any), once the page's ``document.body.dataset[ready]`` says it is ready:
    ``hdrReady`` for its images, ``temporalReady`` for the temporal player. Polled
    from here: ``wait_for_function`` evaluates with eval(), which the page's CSP
    refuses."""
    page = browser.new_page()
    if init_script:
        page.add_init_script(init_script)
    log = PageLog(page)
    page.goto(path.as_uri(), wait_until="load")
    deadline = time.monotonic() + 30
    while page.evaluate(f"document.body.dataset.{ready}") is None:
        assert time.monotonic() < deadline, f"the page never set {ready}"
        page.wait_for_timeout(50)
    assert page.evaluate(f"document.body.dataset.{ready}") == "true"
    return page, log


def _open(browser, path: Path):
    page = browser.new_page()
    log = PageLog(page)
    page.goto(path.as_uri(), wait_until="load")
    return page, log


def _wait_ready(page) -> None:
    page.wait_for_function("document.body.dataset.hdrReady !== undefined", timeout=20_000)
    assert page.evaluate("document.body.dataset.hdrReady") == "true"


def _assert_images_decode(page) -> int:
    state = page.evaluate("""Array.from(document.images).map(
        (i) => [i.getAttribute('src').slice(0, 60), i.complete, i.naturalWidth])""")
    assert state, "no images on the page"
    broken = [s for s in state if not (s[1] and s[2] > 0)]
    assert not broken, broken
    return len(state)


def _canvas(page, selector: str) -> np.ndarray:
    """RGBA pixels of the first canvas matching ``selector`` as (H, W, 4) uint8."""
    data = page.evaluate("""(selector) => {
        const c = document.querySelector(selector);
        const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
        return [c.width, c.height, Array.from(d)];
    }""", selector)
    w, h, values = data
    return np.asarray(values, np.uint8).reshape(h, w, 4)


def _set_range(page, selector: str, value: float) -> None:
    page.locator(selector).first.fill(str(value))


@pytest.mark.parametrize("mode", ["linked", "embedded"])
def test_scene_page_in_chromium(browser, reports, comparison, mode):
    """Loads with no console error and no failed or external request; every image
    decodes; the exposure slider brightens the HDR canvases; the A/B slider and the
    pointer swap method and reference; a screenshot is saved."""
    start = time.perf_counter()
    page, log = _open(browser, reports[mode] / "glass_sphere-paper" / "index.html")
    _wait_ready(page)
    count = _assert_images_decode(page)
    assert count >= 8  # 3 maps + 3 colour bars per view, regions, 2 plots

    test_canvas = '#view-camera canvas.hdr[data-layer="method"]'
    before = _canvas(page, test_canvas)
    shot_before = page.locator(test_canvas).screenshot()
    _set_range(page, "#exposure", 2)
    after = _canvas(page, test_canvas)
    assert page.locator("#exposure-value").text_content() == "2.00"
    assert after[..., :3].mean() > before[..., :3].mean() + 5
    assert page.locator(test_canvas).screenshot() != shot_before
    _set_range(page, "#exposure", -3)
    assert _canvas(page, test_canvas)[..., :3].mean() < before[..., :3].mean() - 5

    ab = "#view-camera canvas.ab"
    _set_range(page, "#view-camera input.ab-split", 100)
    all_test = _canvas(page, ab)
    _set_range(page, "#view-camera input.ab-split", 0)
    all_reference = _canvas(page, ab)
    assert np.array_equal(all_test, _canvas(page, test_canvas))
    assert np.array_equal(all_reference,
                          _canvas(page, '#view-camera canvas.hdr[data-layer="reference"]'))
    assert not np.array_equal(all_test, all_reference)
    box = page.locator(ab).bounding_box()
    page.mouse.move(box["x"] + box["width"] * 0.75, box["y"] + box["height"] / 2)
    hovered = _canvas(page, ab)
    width = hovered.shape[1]
    assert int(page.locator(ab).get_attribute("data-split")) == pytest.approx(0.75 * width, abs=2)
    assert np.array_equal(hovered[:, : width // 2], all_test[:, : width // 2])
    assert np.array_equal(hovered[:, -width // 8:], all_reference[:, -width // 8:])

    ARTIFACTS.mkdir(exist_ok=True)
    shot = ARTIFACTS / f"report-scene-{mode}.png"
    _set_range(page, "#exposure", 0)
    page.screenshot(path=str(shot), full_page=True)
    print(f"screenshot: {shot}  ({time.perf_counter() - start:.2f} s, {count} images, "
          f"{len(log.requests)} requests)")
    assert shot.stat().st_size > 10_000
    log.assert_clean()
    page.close()


def test_canvas_tone_map_matches_the_metrics_tone_map(browser, reports, comparison):
    """At exposure 0 the page's JavaScript tone curve gives the same 8-bit pixels as
    ``scenes.colour.tonemap`` on the shipped data (within one level), for the
    camera image and the (flipped) receiver map: no colour management, no alpha
    premultiplication, no drift between the two implementations."""
    root = reports["linked"] / "glass_sphere-paper"
    page, log = _open(browser, root / "index.html")
    _wait_ready(page)
    for view in ("camera", "receiver0"):
        white = float(page.locator(f"#view-{view}").get_attribute("data-white"))
        _, layers = page_layers(root, view)
        for layer in ("method", "reference"):
            expected = np.round(tonemap(layers[layer], white=white) * 255)
            shown = _canvas(page, f'#view-{view} canvas.hdr[data-layer="{layer}"]')
            assert np.all(shown[..., 3] == 255)
            assert np.abs(shown[..., :3].astype(int) - expected).max() <= 1, (view, layer)
    log.assert_clean()
    page.close()


@pytest.mark.parametrize("mode", ["linked", "embedded"])
def test_summary_page_in_chromium(browser, reports, mode):
    """The index decodes its thumbnails, fits the 1400 px window without scrolling
    sideways (the page and its summary table's own scroller), and links to a scene
    page that opens."""
    page, log = _open(browser, reports[mode] / "index.html")
    _assert_images_decode(page)
    assert page.locator("table.summary tbody tr").count() == 2
    widths = page.evaluate("""() => { const t = document.querySelector('table.summary');
        return [document.documentElement.scrollWidth, t.scrollWidth,
                t.closest('.table-wrap').clientWidth]; }""")
    assert widths[0] <= 1400 and widths[1] <= widths[2], widths
    ARTIFACTS.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS / f"report-index-{mode}.png"), full_page=True)
    page.locator("a.scene-link").first.click()
    page.wait_for_load_state("load")
    assert page.url.endswith("/glass_sphere-paper/index.html")
    _wait_ready(page)
    log.assert_clean()
    page.close()


@pytest.mark.parametrize("mode", ["linked", "embedded"])
def test_hostile_scene_text_is_inert(browser, reports, mode):
    """A name and description full of tags and scripts show as text: no script runs
    (``window.__pwned`` stays undefined), no element is injected, and the visible
    text is the original string."""
    folder = reports[mode] / scene_folder(f"{HOSTILE_NAME}-paper")
    for path in (folder / "index.html", reports[mode] / "index.html"):
        page, log = _open(browser, path)
        if path.parent == folder:
            _wait_ready(page)
            assert page.locator("#scene-name").text_content() == HOSTILE_NAME
            assert page.locator("#scene-description").text_content() == HOSTILE_DESCRIPTION
            assert page.title().startswith(HOSTILE_NAME)
        else:
            names = page.locator("a.scene-link").all_text_contents()
            assert HOSTILE_NAME in names
        assert page.evaluate("typeof window.__pwned") == "undefined"
        assert page.locator("b").count() == 0
        assert page.locator('img[src="x"]').count() == 0
        log.assert_clean()
        page.close()
