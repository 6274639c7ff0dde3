"""Probing, zoom, display modes and profiles of the report's images, in headless
Chromium (Debian's ``chromium``, driven by Playwright) on file:// pages, linked and
self-contained, plus the float data the pages get (no browser needed).

The comparison is synthetic with known data (``tests.reports.conftest``, with the
reference's variance); its EXRs are written by the harness's own writer
(``harness.compare.outputs.write_comparison``) beside the linked page, and every value
the page shows is checked against what those EXRs hold, to the data's promised
rounding: half the 0.1 % bound (``reports.page_data.RELATIVE_BOUND / 2``; the data
keep 10 mantissa bits, an error of at most 2^-11 = 4.9e-4). Skipped with the reason
when Chromium or playwright is missing (a failure under CI), as ``test_browser.py``.
"""

from __future__ import annotations

import csv
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from harness.compare.outputs import write_comparison
from renderers.exr import read_exr
from reports import build_report, images, page_data
from reports.page_data import BLOB_FOLDER, RELATIVE_BOUND
from reports.profiles import line_pixels
from scenes.colour import LUMA
from tests.browser import new_context
from tests.conftest import REPO
from tests.reports.data_helpers import blob_payload, page_layers
from tests.reports.test_browser import open_ready_page

ARTIFACTS = REPO / "test-artifacts"
SCENE = "glass_sphere-paper"


KINDS = ("method", "reference", "signed", "ssim", "flip")


@pytest.fixture(scope="module")
def known(comparison_factory):
    """A comparison with the reference's variance on both views (96×128 camera,
    64×64 receiver map), naming every EXR as ``caustics compare`` does."""
    c = comparison_factory(variance=True, seed=4)
    return replace(c, files={f"{view}/{kind}": f"{view}_{kind}.exr"
                             for view in ("camera", "receiver0") for kind in KINDS})


@pytest.fixture(scope="module")
def pages(tmp_path_factory, known) -> dict[str, Path]:
    """The scene page, linked and self-contained, with the EXRs beside both."""
    out = {}
    for mode, embed in (("linked", False), ("embedded", True)):
        root = tmp_path_factory.mktemp(f"probe-{mode}")
        write_comparison(root / SCENE, known)
        build_report(root, [known], self_contained=embed)
        out[mode] = root / SCENE / "index.html"
    return out


@pytest.fixture(scope="module")
def exr(pages):
    """The EXR originals as written, by ``<view>/<kind>`` (a one-channel map, SSIM or
    FLIP, as (H, W, 1))."""
    folder = pages["linked"].parent

    def layer(path):
        layers = read_exr(path)
        return layers["RGB"] if "RGB" in layers else layers["Y"][..., None]

    return {f"{view}/{kind}": layer(folder / f"{view}_{kind}.exr")
            for view in ("camera", "receiver0") for kind in KINDS}


@pytest.fixture(scope="module")
def browser(chromium):
    with new_context(chromium) as context:
        yield context


# ---- the data the page gets -------------------------------------------------------

#: What the data promise: every value within half the report's 0.1 % bound.
PROMISED = RELATIVE_BOUND / 2


def _close(shown, expected, *, scale=None) -> bool:
    """``shown`` is ``expected`` to :data:`PROMISED`, relative to ``scale`` (by default
    |expected|, per value): zero must stay exactly zero."""
    expected = np.asarray(expected, np.float64)
    scale = np.abs(expected) if scale is None else np.asarray(scale, np.float64)
    return bool(np.all(np.abs(np.asarray(shown, np.float64) - expected) <= PROMISED * scale))


def test_the_page_data_are_the_images_as_shown(pages, known):
    """The data hold method, reference, difference (the float32 ``signed``), SSIM and
    FLIP, and the reference's standard error sqrt(Var), each within :data:`PROMISED`
    of the comparison's (receiver maps flipped as shown), with the method's zeros
    exact; the self-contained page carries the same scripts inline."""
    folder = pages["linked"].parent
    embedded = pages["embedded"].read_text("utf-8")
    for view, flip in (("camera", False), ("receiver0", True)):
        meta, layers = page_layers(folder, view)
        script = (folder / f"data_{view}.js").read_text("utf-8")
        assert script in embedded
        for layer in meta["layers"].values():
            blob = (folder.parent / BLOB_FOLDER / f"{layer['blob']}.js").read_text("ascii")
            assert blob in embedded
        assert meta["factor"] == 1
        for name, kind in (("method", "method"), ("reference", "reference"),
                           ("difference", "signed"), ("ssim", "ssim"), ("flip", "flip")):
            expected = np.asarray(known.images[f"{view}/{kind}"], np.float32)
            expected = expected[::-1] if flip else expected
            assert layers[name].shape == expected.shape
            assert _close(layers[name], expected), (view, name)
        method = np.asarray(known.images[f"{view}/method"])
        assert np.array_equal(layers["method"] == 0, (method[::-1] if flip else method) == 0)
        variance = np.asarray(known.images[f"{view}/reference_variance"], np.float64)
        se = np.sqrt(variance[::-1] if flip else variance).astype(np.float32)
        assert _close(layers["reference_se"], se)


def test_previews_box_filtered_down_ship_box_means(tmp_path, comparison_factory):
    """A view shown f× smaller ships the f×f means, and the standard error of a mean
    of f² independent pixels, sqrt(mean(Var) / f²)."""
    c = comparison_factory(camera=(40, 60), receiver=(32, 32), variance=True)
    build_report(tmp_path, [c], preview_size=20)
    meta, layers = page_layers(tmp_path / SCENE, "camera")
    assert (meta["factor"], meta["height"], meta["width"]) == (3, 13, 20)
    method = np.asarray(c.images["camera/method"], np.float64)[:39, :60]
    means = method.reshape(13, 3, 20, 3, 3).mean(axis=(1, 3))
    # The means are rounded to float32 (6e-8) before the data's own rounding.
    assert _close(layers["method"], means, scale=np.abs(means) * (1 + 1e-6))
    variance = np.asarray(c.images["camera/reference_variance"], np.float64)[:39, :60]
    se = np.sqrt(variance.reshape(13, 3, 20, 3, 3).sum(axis=(1, 3)) / 9**2)
    assert _close(layers["reference_se"], se, scale=se * (1 + 1e-6))


# ---- in the browser ---------------------------------------------------------------

def _layer(view: str, panel: str) -> str:
    return f'#view-{view} .viewport[data-panel="{panel}"] .zoom'


def _point(page, view: str, panel: str, x: float, y: float) -> tuple[float, float]:
    """Page coordinates of display pixel (x, y)'s centre on a panel, scrolled into the
    middle of the window (clear of the sticky controls)."""
    selector = _layer(view, panel)
    page.locator(selector).evaluate(
        "(e) => e.parentElement.scrollIntoView({block: 'center'})")
    box = page.locator(selector).bounding_box()
    w, h = page.evaluate(f"window.causticsData[{json.dumps(view)}].width"), page.evaluate(
        f"window.causticsData[{json.dumps(view)}].height")
    return box["x"] + (x + 0.5) * box["width"] / w, box["y"] + (y + 0.5) * box["height"] / h


def _probe(page) -> dict:
    state = page.evaluate("""() => {
        const box = document.getElementById('probe');
        const rows = {};
        box.querySelectorAll('tr[data-layer]').forEach((r) => {
            rows[r.dataset.layer] = r.dataset.values ? JSON.parse(r.dataset.values) : null;
        });
        return {hidden: box.hidden, text: box.textContent, rows: rows,
                dataset: Object.assign({}, box.dataset)};
    }""")
    assert not state["hidden"]
    return state


def _canvas(page, selector: str) -> np.ndarray:
    w, h, values = page.evaluate("""(selector) => {
        const c = document.querySelector(selector);
        return [c.width, c.height,
                Array.from(c.getContext('2d').getImageData(0, 0, c.width, c.height).data)];
    }""", selector)
    return np.asarray(values, np.uint8).reshape(h, w, 4)


@pytest.mark.parametrize("mode", ["linked", "embedded"])
def test_hovering_shows_the_exr_values(browser, pages, known, exr, mode):
    """On every panel of both views, hovering a pixel shows the method, reference and
    difference values of the EXRs (per channel within :data:`PROMISED`, and their
    luminance within PROMISED of Σ w_c |v_c|, the most the channels' rounding can
    move it), the reference's standard error sqrt(Var), the SSIM and FLIP there, the EXR pixel
    (receiver rows flipped back) and the units; no console error, nothing requested
    off the machine."""
    page, log = open_ready_page(browser, pages[mode])
    units = {"camera": "W m⁻² sr⁻¹", "receiver0": "W/m²"}
    for view in ("camera", "receiver0"):
        height, width = known.images[f"{view}/reference"].shape[:2]
        lum = known.images[f"{view}/reference"] @ LUMA
        peak_y, peak_x = np.unravel_index(np.argmax(lum), lum.shape)
        shown_peak = (int(peak_x), int(height - 1 - peak_y if view != "camera" else peak_y))
        panels = page.evaluate(f"""Array.from(document.querySelectorAll(
            '#view-{view} .viewport')).map((v) => v.dataset.panel)""")
        # The difference map's standard-error ("se") and z-score ("z") maps stand
        # beside it where the reference has a variance, as here.
        assert set(panels) == {"method", "reference", "signed", "se", "z", "ssim", "flip",
                               "regions", "ab"}
        for panel, (x, y) in zip(panels, [shown_peak, (0, 0), (width - 1, height - 1),
                                          (2, height - 2), (width - 3, 1), (7, 3), shown_peak,
                                          (width // 2, 5), (11, 13)],
                                     strict=True):
            page.mouse.move(*_point(page, view, panel, x, y))
            state = _probe(page)
            ey = height - 1 - y if view != "camera" else y
            assert (state["dataset"]["view"], state["dataset"]["x"], state["dataset"]["y"]) \
                == (view, str(x), str(y)), panel
            assert state["dataset"]["exr"] == f"{x} {x} {ey} {ey}"
            rows = state["rows"]
            for name, kind in (("method", "method"), ("reference", "reference"),
                               ("difference", "signed")):
                expected = exr[f"{view}/{kind}"][ey, x]
                assert _close(rows[name][:3], expected), (panel, name)
                assert _close(rows[name][3], expected @ LUMA, scale=np.abs(expected) @ LUMA)
            se = np.sqrt(np.float64(known.images[f"{view}/reference_variance"][ey, x]))
            assert _close(rows["reference_se"][:3], se)
            assert _close(rows["reference_se"][3], se @ LUMA)
            for name in ("ssim", "flip"):
                assert _close(float(state["dataset"][name]), exr[f"{view}/{name}"][ey, x, 0])
            shown = page.evaluate("(v) => window.causticsReport.format(v)", rows["method"][0])
            assert shown in state["text"] and units[view] in state["text"]
            squares = page.evaluate(f"""Array.from(document.querySelectorAll(
                '#view-{view} rect.probe-mark')).map((r) => [r.getAttribute('x'),
                r.getAttribute('y')])""")
            assert squares == [[str(x), str(y)]] * len(panels)
    if mode == "linked":
        assert any(r.endswith("/data_camera.js") for r in log.requests), log.requests
        assert any(f"/{BLOB_FOLDER}/" in r for r in log.requests), log.requests
    assert all(r.startswith(("file:", "data:")) for r in log.requests), log.requests
    log.assert_clean()
    page.close()


def _drag(page, start, end, *, shift: bool) -> None:
    if shift:
        page.keyboard.down("Shift")
    page.mouse.move(*start)
    page.mouse.down()
    page.mouse.move(*end, steps=6)
    page.mouse.up()
    if shift:
        page.keyboard.up("Shift")


def _samples(page, view: str) -> dict:
    return page.evaluate(f"""JSON.parse(document.querySelector(
        '#view-{view} .profile svg.profile-svg').dataset.samples)""")


def _check_samples(samples, exr, known, view, *, start, end):
    """The plotted samples are the data along the line, pixel for pixel (to
    :data:`PROMISED`)."""
    height = known.images[f"{view}/reference"].shape[0]
    xs, ys = line_pixels(start, end)
    assert samples["displayX"] == xs.tolist() and samples["displayY"] == ys.tolist()
    ey = height - 1 - ys if view != "camera" else ys
    assert samples["x"] == xs.tolist() and samples["y"] == ey.tolist()
    for name in ("method", "reference"):
        expected = exr[f"{view}/{name}"][ey, xs]
        assert _close(samples[name], expected), name
        assert _close(samples[f"{name}Lum"], expected @ LUMA, scale=np.abs(expected) @ LUMA)
    se = np.sqrt(np.float64(known.images[f"{view}/reference_variance"][ey, xs]))
    assert _close(samples["stderr"], se)
    assert _close(samples["stderrLum"], se @ LUMA)


@pytest.mark.parametrize("mode", ["linked", "embedded"])
def test_a_dragged_profile_plots_the_data(browser, pages, known, exr, mode):
    """Shift+drag on a panel plots method and reference along the line, with the
    reference's ±2σ band, and the plotted samples are the EXRs' values there; with
    "drag draws a profile" ticked a plain drag does it too and nothing pans; the
    receiver map's default profile is the CSV written beside the page."""
    page, log = open_ready_page(browser, pages[mode])
    default = _samples(page, "receiver0")
    with open(pages["linked"].parent / "profile_receiver0.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [int(r["x"]) for r in rows] == default["x"]
    assert [int(r["y"]) for r in rows] == default["y"]
    # The CSV holds the comparison's values, the page the data's (within PROMISED).
    for channel, c in (("r", 0), ("g", 1), ("b", 2)):
        assert _close([s[c] for s in default["reference"]],
                      [float(r[f"reference_{channel}"]) for r in rows])
    assert _close(default["stderrLum"], [float(r["reference_se_lum"]) for r in rows])

    start, end = (5, 80), (120, 10)
    _drag(page, _point(page, "camera", "reference", *start),
          _point(page, "camera", "reference", *end), shift=True)
    samples = _samples(page, "camera")
    _check_samples(samples, exr, known, "camera", start=start, end=end)
    n = len(samples["x"])
    counts = page.evaluate("""Array.from(document.querySelectorAll(
        '#view-camera .profile-svg [data-series]')).map((e) =>
        [e.dataset.series, e.getAttribute('points').trim().split(/ +/).length])""")
    assert dict(counts) == {"reference ± 2σ": 2 * n, "reference": n, "method": n}
    lines = page.evaluate("""Array.from(document.querySelectorAll(
        '#view-camera line.profile-line')).map((l) => ['x1', 'y1', 'x2', 'y2'].map(
        (a) => parseFloat(l.getAttribute(a))))""")
    # One line on every panel of the view (nine: see test_hovering_shows_the_exr_values).
    assert lines == [[5.5, 80.5, 120.5, 10.5]] * 9
    assert page.locator("#view-camera").get_attribute("data-zoom") == "1 0 0"
    link = page.locator("#view-camera a.profile-download")
    assert link.get_attribute("href").startswith("data:text/csv")

    page.locator("#profile-mode").check()
    start, end = (3, 60), (60, 3)
    _drag(page, _point(page, "receiver0", "signed", *start),
          _point(page, "receiver0", "signed", *end), shift=False)
    _check_samples(_samples(page, "receiver0"), exr, known, "receiver0", start=start, end=end)
    assert page.locator("#view-receiver0").get_attribute("data-zoom") == "1 0 0"
    ARTIFACTS.mkdir(exist_ok=True)
    page.locator("#view-camera").screenshot(path=str(ARTIFACTS / f"report-profile-{mode}.png"))
    log.assert_clean()
    page.close()


def test_log_and_false_colour_views(browser, pages, known):
    """The display toggle redraws every view from the float data: log shows
    g = clamp((log10 L − lo) / 4, 0, 1) as grey with lo = log10(peak / 2^stops) − 4,
    peak the reference's largest luminance, false colour the same g through the
    colormap table; the exposure shifts it; the colour bar and the profile's axis
    follow; the A/B image shows the same pixels."""
    page, log = open_ready_page(browser, pages["linked"])
    selector = '#view-camera canvas.hdr[data-layer="method"]'
    linear = _canvas(page, selector)
    reference = np.asarray(known.images["camera/reference"], np.float32).astype(np.float64)
    peak = float((reference @ LUMA).max())
    assert float(page.locator("#view-camera").get_attribute("data-peak")) == pytest.approx(peak)
    lum = np.asarray(known.images["camera/method"], np.float32).astype(np.float64) @ LUMA

    def level(stops):
        with np.errstate(divide="ignore"):
            g = (np.log10(lum) - (np.log10(peak / 2**stops) - 4)) / 4
        return np.round(255 * np.clip(np.nan_to_num(g, neginf=0.0), 0, 1)).astype(int)

    page.locator('input[name="display-mode"][value="log"]').check()
    shown = _canvas(page, selector)
    assert not np.array_equal(shown, linear)
    assert np.abs(shown[..., 0].astype(int) - level(0)).max() <= 1
    assert np.array_equal(shown[..., 0], shown[..., 2])
    assert page.locator("#view-camera .bar-low").text_content() == page.evaluate(
        "(v) => window.causticsReport.format(v)", peak * 1e-4)
    assert page.locator("#view-receiver0 .profile-svg").get_attribute("data-scale") == "log"
    page.locator("#exposure").fill("2")
    brighter = _canvas(page, selector)
    assert np.abs(brighter[..., 0].astype(int) - level(2)).max() <= 1
    assert brighter[..., 0].mean() > shown[..., 0].mean() + 10
    page.locator("#exposure").fill("0")

    page.locator('input[name="display-mode"][value="false-colour"]').check()
    coloured = _canvas(page, selector)[..., :3].astype(int)
    table = np.frombuffer(images.lookup_table(), np.uint8).reshape(256, 3).astype(int)
    g = level(0)
    near = [np.abs(coloured - table[np.clip(g + k, 0, 255)]).max(axis=-1) == 0
            for k in (-1, 0, 1)]
    assert np.all(np.any(near, axis=0))
    assert np.mean(near[1]) > 0.99
    page.locator("#view-camera input.ab-split").fill("100")
    assert np.array_equal(_canvas(page, "#view-camera canvas.ab")[..., :3], coloured)
    page.locator('input[name="display-mode"][value="linear"]').check()
    assert np.array_equal(_canvas(page, selector), linear)
    assert page.locator("#view-receiver0 .profile-svg").get_attribute("data-scale") == "linear"
    log.assert_clean()
    page.close()


def _visible(page, view: str) -> list[list[float]]:
    """Per viewport of a view: the zoom layer's box in units of the viewport's inner
    size (inside its border)."""
    return page.evaluate(f"""Array.from(document.querySelectorAll('#view-{view} .viewport'))
        .map((v) => {{
            const a = v.getBoundingClientRect(), edge = v.clientLeft;
            const w = a.width - 2 * edge, h = a.height - 2 * edge;
            const b = v.querySelector('.zoom').getBoundingClientRect();
            return [(b.left - a.left - edge) / w, (b.top - a.top - edge) / h,
                    b.width / w, b.height / h];
        }})""")


def test_zoom_and_pan_stay_in_sync(browser, pages, known):
    """The wheel over one panel zooms every panel of its view alike (the A/B image,
    twice as wide, included) about the pointer's pixel, and no other view; a drag pans
    them together; the A/B split still follows the pointer in image units; a
    double-click resets."""
    page, log = open_ready_page(browser, pages["linked"])
    where = _point(page, "camera", "method", 40, 30)
    page.mouse.move(*where)
    page.mouse.wheel(0, -600)
    page.wait_for_timeout(100)
    zooms = page.evaluate("""Array.from(document.querySelectorAll('#view-camera .zoom'))
        .map((z) => z.dataset.zoom)""")
    # Nine panels: the seven image panels, and the standard-error and z-score maps.
    assert len(zooms) == 9 and len(set(zooms)) == 1
    scale = float(zooms[0].split()[0])
    assert scale == pytest.approx(np.exp(1.2), rel=1e-6)
    boxes = np.array(_visible(page, "camera"))
    assert np.allclose(boxes, boxes[0], atol=2e-3) and boxes[0, 2] == pytest.approx(scale, rel=1e-3)
    page.mouse.move(where[0] + 1, where[1])
    page.mouse.move(*where)
    assert (_probe(page)["dataset"]["x"], _probe(page)["dataset"]["y"]) == ("40", "30")
    # Scrolling a zoomed layer into view must not scroll its viewport out of step.
    page.locator(_layer("camera", "reference")).evaluate(
        "(e) => e.scrollIntoView({block: 'center'})")
    assert np.allclose(_visible(page, "camera"), boxes, atol=2e-3)
    assert set(page.evaluate("""Array.from(document.querySelectorAll('#view-receiver0 .zoom'))
        .map((z) => z.dataset.zoom)""")) == {"1 0 0"}

    start = _point(page, "camera", "reference", 45, 35)
    _drag(page, start, (start[0] - 40, start[1] + 25), shift=False)
    panned = np.array(_visible(page, "camera"))
    assert np.allclose(panned, panned[0], atol=2e-3)
    assert not np.allclose(panned[0], boxes[0], atol=1e-3)

    ab = page.locator("#view-camera canvas.ab")
    ab.evaluate("(e) => e.scrollIntoView({block: 'center'})")
    layer = page.locator(_layer("camera", "ab")).bounding_box()
    frame = page.locator('#view-camera .viewport[data-panel="ab"]').bounding_box()
    x = frame["x"] + frame["width"] * 0.6
    page.mouse.move(x, frame["y"] + frame["height"] / 2)
    width = known.images["camera/method"].shape[1]
    expected = width * (x - layer["x"]) / layer["width"]
    assert int(ab.get_attribute("data-split")) == pytest.approx(expected, abs=1)
    cut = int(ab.get_attribute("data-split"))
    method = _canvas(page, '#view-camera canvas.hdr[data-layer="method"]')
    reference = _canvas(page, '#view-camera canvas.hdr[data-layer="reference"]')
    mixed = _canvas(page, "#view-camera canvas.ab")
    assert np.array_equal(mixed[:, :cut], method[:, :cut])
    assert np.array_equal(mixed[:, cut:], reference[:, cut:])

    flip = page.locator('#view-camera .viewport[data-panel="flip"]')
    flip.evaluate("(e) => e.scrollIntoView({block: 'center'})")
    box = flip.bounding_box()
    page.mouse.dblclick(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    assert set(page.evaluate("""Array.from(document.querySelectorAll('#view-camera .zoom'))
        .map((z) => z.dataset.zoom)""")) == {"1 0 0"}
    log.assert_clean()
    page.close()


# ---- two methods of one scene --------------------------------------------------------

def _second_method(known):
    """The same scene and reference with another method: the method 20 % brighter."""
    images = dict(known.images)
    for view in ("camera", "receiver0"):
        method = np.asarray(images[f"{view}/method"], np.float64) * 1.2
        images[f"{view}/method"] = method.astype(np.float32)
        images[f"{view}/signed"] = (method.astype(np.float32).astype(np.float64)
                                    - images[f"{view}/reference"]).astype(np.float32)
    return replace(known, method="strong", images=images)


@pytest.fixture(scope="module")
def two_methods(tmp_path_factory, known) -> Path:
    """A linked report of two methods of one scene, with their EXRs."""
    root = tmp_path_factory.mktemp("probe-two-methods")
    second = _second_method(known)
    for c in (known, second):
        write_comparison(root / c.page, c)
    build_report(root, [known, second])
    return root


def test_two_method_pages_share_the_reference_data_written_once(tmp_path, known,
                                                               monkeypatch):
    """Both pages of a scene name the same reference and standard-error blobs, each
    one file under ``_data``, written once: by the first page, not again by the
    second, nor by building the report again; the methods' own blobs differ."""
    writes: list[Path] = []
    real_write = page_data.atomic_write_bytes

    def counting(path, data):
        writes.append(Path(path))
        real_write(path, data)

    monkeypatch.setattr(page_data, "atomic_write_bytes", counting)
    second = _second_method(known)
    build_report(tmp_path, [known, second])
    blob_writes = [p for p in writes if p.parent.name == BLOB_FOLDER]
    assert len(blob_writes) == len(set(blob_writes))
    for view in ("camera", "receiver0"):
        first, _ = page_layers(tmp_path / known.page, view)
        other, _ = page_layers(tmp_path / second.page, view)
        for name in ("reference", "reference_se"):
            key = first["layers"][name]["blob"]
            assert other["layers"][name]["blob"] == key
            assert blob_writes.count(tmp_path / BLOB_FOLDER / f"{key}.js") == 1
        for name in ("difference", "method_exceptions"):
            assert first["layers"][name]["blob"] != other["layers"][name]["blob"]
    stored = sorted((tmp_path / BLOB_FOLDER).iterdir())
    assert len(stored) == len(blob_writes)
    for path in stored:
        assert blob_payload(path.read_text("ascii"))[0] == path.stem
    writes.clear()
    build_report(tmp_path, [known, second])
    assert [p for p in writes if p.parent.name == BLOB_FOLDER] == []


def test_a_two_method_report_stays_compact(tmp_path, comparison_factory):
    """A two-method report of a small scene (96×128 camera, 64×64 receiver map) ships
    its float data in fewer bytes than the raw float32 of what it must hold, each
    once: per view the reference and its standard error (3 + 3 channels) and per
    method the method, SSIM and FLIP (3 + 1 + 1; the difference follows from method
    and reference). Pages that each carried all their layers as base64 float32, as
    the report once did, take 2 × 11 channels × 4/3 = 29.3 channel-images, against
    this bound's 6 + 2 × 5 = 16."""
    first = comparison_factory(variance=True, seed=4)
    second = _second_method(first)
    build_report(tmp_path, [first, second])
    pixels = sum(np.asarray(first.images[f"{view}/reference"]).shape[0]
                 * np.asarray(first.images[f"{view}/reference"]).shape[1]
                 for view in ("camera", "receiver0"))
    bound = 4 * pixels * (6 + 2 * 5)
    shipped = sum(p.stat().st_size for p in (tmp_path / BLOB_FOLDER).iterdir())
    shipped += sum(p.stat().st_size for page in (first.page, second.page)
                   for p in (tmp_path / page).glob("data_*.js"))
    assert shipped <= bound, (shipped, bound)


def test_both_method_pages_probe_the_shared_reference(browser, two_methods, known):
    """Each of the two pages loads the one reference blob and shows, at the same pixel,
    its own method and difference and the common reference, all within
    :data:`PROMISED` of its EXRs."""
    second = _second_method(known)
    requested = {}
    for c in (known, second):
        folder = two_methods / c.page
        page, log = open_ready_page(browser, folder / "index.html")
        exr = {kind: read_exr(folder / f"camera_{kind}.exr")["RGB"]
               for kind in ("method", "reference", "signed")}
        page.mouse.move(*_point(page, "camera", "method", 40, 30))
        rows = _probe(page)["rows"]
        for name, kind in (("method", "method"), ("reference", "reference"),
                           ("difference", "signed")):
            assert _close(rows[name][:3], exr[kind][30, 40]), (c.method, name)
        meta, _ = page_layers(folder, "camera")
        key = meta["layers"]["reference"]["blob"]
        requested[c.method] = [r for r in log.requests if r.endswith(f"/{key}.js")]
        log.assert_clean()
        page.close()
    assert len(requested["paper"]) == 1
    assert requested["paper"] == requested["strong"]
