"""The uncertainty beside every difference map, one difference scale per scene, the
hardware beside every speedup, and the index's reasons for a missing value, in
headless Chromium on file:// pages (as ``test_probe_browser.py``).

Two methods of one synthetic scene share its reference (``tests.reports.conftest``,
with the reference's variance ``(0.05 × noiseless value)²``): ``paper`` as built, whose
record carries the scene's difference scale, and ``strong``, a method halfway to the
reference whose record carries none (an older record), so the page derives it by the
same rule from the reference alone. Their EXRs are written by the harness's own writer
beside the pages; every number the page shows is checked against the EXRs and the
record's variance, to the page data's promised rounding (half the 0.1 % bound,
``reports.page_data.RELATIVE_BOUND / 2``).
"""

from __future__ import annotations

import io
import json
import math
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from harness.compare.headlines import with_headlines
from harness.compare.outputs import write_comparison
from harness.metrics import signed_difference
from renderers.exr import read_exr
from reports import build_report
from reports.display import CLIP_ABOVE, CLIP_BELOW, difference_range, false_colour
from reports.page_data import RELATIVE_BOUND
from reports.panels import MAP_COLORMAPS, Z_LIMIT, Z_REPORTED
from reports.records import EqualErrorSpeedup, SpeedupWithheld
from scenes.colour import LUMA
from tests.browser import new_context
from tests.reports.test_browser import PageLog, open_ready_page

KINDS = ("method", "reference", "signed", "ssim", "flip")
VIEWS = ("camera", "receiver0")
#: What the page data promise: every value within half the report's 0.1 % bound.
PROMISED = RELATIVE_BOUND / 2
H100 = "NVIDIA H100 80GB HBM3/PCIe/SSE2"
LLVMPIPE = "llvmpipe (LLVM 19.1.1, 256 bits)"


def _named(c):
    """``c`` naming every EXR as ``caustics compare`` does."""
    return replace(c, files={f"{view}/{kind}": f"{view}_{kind}.exr"
                             for view in VIEWS for kind in KINDS})


def _hardware(c, *, gl, variant, cpus=16, processor="x86_64"):
    provenance = c.provenance
    return replace(c, provenance=replace(
        provenance, method=replace(provenance.method, gl_renderer=gl),
        reference={**provenance.reference, "variant": variant},
        machine={"cpus": cpus, "processor": processor}))


def _speedup(c, speedup):
    return c.with_section(replace(c.section("cost"), speedup=speedup))


def _strong(paper):
    """The same scene's ``strong`` method: halfway between the paper's method and the
    reference on both views, its record without a difference scale."""
    images = dict(paper.images)
    for view in VIEWS:
        reference = np.asarray(images[f"{view}/reference"], np.float64)
        method = 0.5 * (np.asarray(images[f"{view}/method"], np.float64) + reference)
        images[f"{view}/method"] = method.astype(np.float32)
        images[f"{view}/signed"] = signed_difference(
            images[f"{view}/method"], images[f"{view}/reference"]).astype(np.float32)
    exposure = {k: v for k, v in paper.exposure.items() if k != "diff_range"}
    return replace(paper, method="strong", method_description="best known implementation",
                   images=images, exposure=exposure)


@pytest.fixture(scope="module")
def scene(comparison_factory):
    """paper (an NVIDIA GPU renders it, a CUDA reference; speedup with its interval)
    and strong (llvmpipe, an LLVM reference; a lower bound) of one scene."""
    paper = _named(comparison_factory(variance=True, seed=4))
    paper = _speedup(_hardware(paper, gl=H100, variant="cuda_ad_rgb"), EqualErrorSpeedup(
        12.5, 3.0, "interpolated", low=8.25, high=19.5))
    strong = _speedup(_hardware(_strong(paper), gl=LLVMPIPE, variant="llvm_ad_rgb", cpus=2),
                      EqualErrorSpeedup(40.0, 10.0, "extrapolated", low=40.0, high=math.inf,
                                        bound_kind="lower bound"))
    return {"paper": paper, "strong": strong}


@pytest.fixture(scope="module")
def others(comparison_factory):
    """Index rows whose values are missing for a reason: a withheld speedup; and a
    comparison without the cost study, the reference's variance or a camera view."""
    withheld = replace(comparison_factory(name="withheld", seed=6, variance=True),
                       speedup_withheld=SpeedupWithheld(
                           reason="the method's relMSE is 3.6, worse than a black image",
                           short="relMSE ≥ 1"))
    bare = comparison_factory(name="bare", seed=7)
    bare = replace(
        bare, sections=tuple(s for s in bare.sections if s.name != "cost"),
        images={k: v for k, v in bare.images.items() if not k.startswith("camera/")},
        metrics=tuple(m for m in bare.metrics if m.view != "camera"),
        provenance=replace(bare.provenance, notes=(
            "camera not compared: the reference camera image is black",)))
    return {"withheld": withheld, "bare": bare}


@pytest.fixture(scope="module")
def reports(tmp_path_factory, scene, others) -> dict[str, Path]:
    """The report, linked and self-contained, with the EXRs beside the scene's pages."""
    out = {}
    for mode, embed in (("linked", False), ("embedded", True)):
        root = tmp_path_factory.mktemp(f"uncertainty-{mode}")
        for c in scene.values():
            write_comparison(root / c.page, c)
        build_report(root, [*scene.values(), *others.values()], self_contained=embed)
        out[mode] = root
    return out


@pytest.fixture(scope="module")
def exr(reports, scene):
    """The EXRs as written, by method and ``<view>/<kind>`` (SSIM, FLIP as (H, W, 1))."""
    def layer(path):
        layers = read_exr(path)
        return layers["RGB"] if "RGB" in layers else layers["Y"][..., None]

    return {name: {f"{view}/{kind}": layer(reports["linked"] / c.page / f"{view}_{kind}.exr")
                   for view in VIEWS for kind in KINDS}
            for name, c in scene.items()}


@pytest.fixture(scope="module")
def browser(chromium):
    with new_context(chromium) as context:
        yield context


def _point(page, view: str, panel: str, x: int, y: int) -> tuple[float, float]:
    """Page coordinates of display pixel (x, y)'s centre on a panel, scrolled clear of
    the sticky controls."""
    selector = f'#view-{view} .viewport[data-panel="{panel}"] .zoom'
    page.locator(selector).evaluate("(e) => e.parentElement.scrollIntoView({block: 'center'})")
    box = page.locator(selector).bounding_box()
    meta = page.evaluate(f"window.causticsData[{json.dumps(view)}]")
    return (box["x"] + (x + 0.5) * box["width"] / meta["width"],
            box["y"] + (y + 0.5) * box["height"] / meta["height"])


def _probe_rows(page) -> dict:
    return page.evaluate("""() => {
        const rows = {};
        document.querySelectorAll('#probe tr[data-layer]').forEach((r) => {
            rows[r.dataset.layer] = r.dataset.values ? JSON.parse(r.dataset.values) : null;
        });
        return rows;
    }""")


def _png(folder: Path, name: str) -> np.ndarray:
    return np.asarray(Image.open(io.BytesIO((folder / name).read_bytes())).convert("RGB"))


def _shown(array, view):
    """An image as the page shows it: receiver maps flipped so +v points up."""
    return np.asarray(array)[::-1] if view != "camera" else np.asarray(array)


def _expected_z(signed: np.ndarray, variance: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """z per channel, and of the luminance over Σ w_c σ_c, of (H, W, 3) arrays."""
    se = np.sqrt(np.asarray(variance, np.float64))
    signed = np.asarray(signed, np.float64)
    return signed / se, (signed @ LUMA) / (se @ LUMA)


@pytest.mark.parametrize("mode", ["linked", "embedded"])
def test_standard_error_and_z_maps_beside_each_difference(browser, reports, scene, exr, mode):
    """Every view with the reference's variance shows, right after its difference map,
    the standard-error map and the z-score map (colour bar ±Z_LIMIT); hovering them
    shows sqrt(Var) and z = (method − reference) / σ from the EXRs and the record: per
    channel, and of the luminance over σ_lum = Σ w_c σ_c, within the data's rounding
    (difference within PROMISED Σ w |d_c|, σ within PROMISED relative: |Δz| ≤ PROMISED
    (Σ w |d_c| / σ_lum + |z|) / (1 − PROMISED)). The z map's pixel there is the
    colour of that z, and the stated share of |z| > 3 is the EXRs' at full resolution."""
    c = scene["paper"]
    folder = reports["linked"] / c.page
    page, log = open_ready_page(browser, reports[mode] / c.page / "index.html")
    for view in VIEWS:
        kinds = page.evaluate(f"""Array.from(document.querySelectorAll(
            '#view-{view} figure.map-panel')).map((f) => f.dataset.kind)""")
        assert kinds[:3] == ["signed", "se", "z"], kinds
        z_figure = page.locator(f'#view-{view} figure.map-panel[data-kind="z"]')
        assert (z_figure.get_attribute("data-vmin"), z_figure.get_attribute("data-vmax")) \
            == (f"{-Z_LIMIT:g}", f"{Z_LIMIT:g}")
        signed, variance = exr["paper"][f"{view}/signed"], c.images[f"{view}/reference_variance"]
        z_rgb, z_lum = _expected_z(signed, variance)
        share = float(np.mean(np.abs(z_lum) > Z_REPORTED))
        assert float(z_figure.get_attribute("data-z-share")) == pytest.approx(share, rel=1e-6)
        assert f"|z| > 3 at {100 * share:.3g} %" in z_figure.inner_text()
        height, width = signed.shape[:2]
        lum = exr["paper"][f"{view}/reference"] @ LUMA
        peak_y, peak_x = np.unravel_index(np.argmax(lum), lum.shape)
        z_png = _png(folder, f"{view}_z.png")
        for panel, (ex, ey) in (("z", (int(peak_x), int(peak_y))), ("se", (7, 3)),
                                ("z", (width - 5, height // 3))):
            x, y = ex, (height - 1 - ey if view != "camera" else ey)
            page.mouse.move(*_point(page, view, panel, x, y))
            rows = _probe_rows(page)
            se = np.sqrt(np.float64(variance[ey, ex]))
            assert np.all(np.abs(np.asarray(rows["reference_se"][:3]) - se) <= PROMISED * se)
            d = np.asarray(signed[ey, ex], np.float64)
            bound = PROMISED * (np.abs(d) @ LUMA / (se @ LUMA) + abs(z_lum[ey, ex])) \
                / (1 - PROMISED)
            assert abs(rows["z"][3] - z_lum[ey, ex]) <= bound, (view, panel, rows["z"])
            assert np.all(np.abs(np.asarray(rows["z"][:3]) - z_rgb[ey, ex])
                          <= 2 * PROMISED * np.abs(z_rgb[ey, ex]) + 1e-12)
            colour = false_colour(np.array([[z_lum[ey, ex]]]), vmin=-Z_LIMIT, vmax=Z_LIMIT,
                                  colormap=MAP_COLORMAPS["z"], mark_clipped=True)[0, 0]
            assert np.array_equal(z_png[y, x], colour), (view, x, y)
    log.assert_clean()
    page.close()


def test_a_view_without_variance_says_so(browser, tmp_path, scene):
    """A view whose reference records no variance gets a note in place of the two maps
    (and no such panels); the other view keeps them."""
    c = scene["paper"]
    c = replace(c, images={k: v for k, v in c.images.items()
                           if k != "receiver0/reference_variance"})
    build_report(tmp_path, [c])
    page, log = open_ready_page(browser, tmp_path / c.page / "index.html")
    note = page.locator("#view-receiver0 figure.no-variance")
    assert note.is_visible() and "no per-pixel variance" in note.inner_text()
    assert page.locator('#view-receiver0 .viewport[data-panel="z"]').count() == 0
    assert page.locator('#view-receiver0 .viewport[data-panel="se"]').count() == 0
    assert page.locator('#view-camera .viewport[data-panel="z"]').count() == 1
    assert page.locator("#view-camera figure.no-variance").count() == 0
    log.assert_clean()
    page.close()


def test_one_difference_scale_per_scene(browser, reports, scene, exr):
    """The paper and strong pages of one scene draw their difference maps on the same
    scale, ±difference_range(reference) (the colour bars' limits read the same), the
    strong page deriving it from the reference although its record carries none; each
    page states the share of pixels beyond it, which is the EXRs' and differs between
    the two methods, and draws exactly those pixels in the marker colours."""
    limits = {}
    for name, c in scene.items():
        page, log = open_ready_page(browser, reports["linked"] / c.page / "index.html")
        for view in VIEWS:
            figure = page.locator(f'#view-{view} figure.map-panel[data-kind="signed"]')
            limits[name, view] = (figure.locator(".bar-min").inner_text(),
                                  figure.locator(".bar-max").inner_text(),
                                  float(figure.get_attribute("data-vmax")))
            limit = difference_range(exr[name][f"{view}/reference"])
            assert limits[name, view][2] == pytest.approx(limit, rel=1e-6)
            lum = exr[name][f"{view}/signed"] @ LUMA
            share = float(np.mean(np.abs(lum) > limit))
            assert float(figure.get_attribute("data-clipped-share")) == pytest.approx(
                share, rel=1e-6)
            shown = figure.locator(".clipped-share")
            assert shown.is_visible() and f"{100 * share:.3g} %" in shown.inner_text()
            png = _png(reports["linked"] / c.page, f"{view}_signed.png")
            lum = _shown(lum, view)
            assert np.array_equal(np.all(png == CLIP_ABOVE, axis=-1), lum > limit)
            assert np.array_equal(np.all(png == CLIP_BELOW, axis=-1), lum < -limit)
        log.assert_clean()
        page.close()
    for view in VIEWS:
        assert limits["paper", view] == limits["strong", view]
        paper = np.abs(exr["paper"][f"{view}/signed"] @ LUMA)
        strong = np.abs(exr["strong"][f"{view}/signed"] @ LUMA)
        limit = limits["paper", view][2]
        assert np.mean(paper > limit) > np.mean(strong > limit)


def _text(locator) -> str:
    return re.sub(r"\s+", " ", locator.inner_text())


def test_hardware_beside_every_speedup(browser, tmp_path, reports, scene):
    """Where a speedup is shown (the cost section, the headline, the index) the
    hardware is beside it: the GL renderer, the GPU it names (or none for llvmpipe),
    the CPU count, the processor and the reference's variant; the speedup carries its
    interval, or "at least" for a lower bound."""
    expected = {"paper": (H100, "GPU: NVIDIA H100 80GB HBM3", "16 CPUs", "x86_64",
                          "cuda_ad_rgb on a GPU (CUDA)"),
                "strong": (LLVMPIPE, "no GPU", "2 CPUs", "x86_64", "llvm_ad_rgb on the CPU")}
    shown = {"paper": "12.5× (95 % interval 8.25×–19.5×)", "strong": "at least 40×"}
    for name, c in scene.items():
        page, log = open_ready_page(browser, reports["linked"] / c.page / "index.html")
        speedup = page.locator("#cost p.speedup")
        assert shown[name] in _text(speedup)
        beside = page.locator("#cost p.speedup + p.hardware")
        assert all(part in _text(beside) for part in expected[name]), _text(beside)
        log.assert_clean()
        page.close()
    index, log = _open_index(browser, reports["linked"])
    for name, c in scene.items():
        cell = index.locator(f'tr:has(a[href="{c.page}/index.html"]) td.speedup-cell')
        assert shown[name] in _text(cell)
        assert all(part in _text(cell.locator(".hardware")) for part in expected[name])
    log.assert_clean()
    index.close()
    headlined = with_headlines(scene["paper"])
    assert headlined.speedup is not None, headlined.speedup_withheld
    build_report(tmp_path, [headlined])
    page, log = open_ready_page(browser, tmp_path / headlined.page / "index.html")
    headline = page.locator('#headlines p.headline[data-kind="speedup"]')
    assert shown["paper"] in _text(headline)
    assert all(part in _text(headline.locator(".hardware")) for part in expected["paper"])
    log.assert_clean()
    page.close()


def _open_index(browser, root: Path):
    page = browser.new_page()
    log = PageLog(page)
    page.goto((root / "index.html").as_uri(), wait_until="load")
    return page, log


@pytest.mark.parametrize("mode", ["linked", "embedded"])
def test_the_index_dashes_say_why(browser, reports, scene, others, mode):
    """Every "—" in the index's table carries its reason as a tooltip and a visible
    note: a withheld speedup (with its reason), a cost study not run, a camera view not
    compared (the note the comparison recorded), the method's own error without the
    reference's variance."""
    page, log = _open_index(browser, reports[mode])
    dashes = page.evaluate("""() => {
        const walker = document.createTreeWalker(document.querySelector('table.summary'),
                                                 NodeFilter.SHOW_TEXT);
        const out = [];
        while (walker.nextNode()) {
            const node = walker.currentNode;
            if (node.textContent.includes('—') && !node.parentElement.closest('.hardware')) {
                const why = node.parentElement.closest('.why');
                const note = why && why.nextElementSibling;
                out.push({row: node.parentElement.closest('tr').querySelector('a').textContent,
                          title: why ? why.title : null,
                          note: note && note.classList.contains('why-note')
                              ? note.textContent : null});
            }
        }
        return out;
    }""")
    assert dashes, "the index shows no dash"
    assert all(d["title"] and d["note"] for d in dashes), [d for d in dashes
                                                          if not (d["title"] and d["note"])]
    found = {(d["row"], d["note"]) for d in dashes}
    assert ("withheld", "withheld: relMSE ≥ 1") in found
    assert ("bare", "cost study not run") in found
    assert ("bare", "no camera") in found
    assert ("bare", "no variance") in found
    assert ("glass_sphere", "no variance") not in found
    camera = next(d for d in dashes if d["note"] == "no camera")
    assert camera["title"] == "camera not compared: the reference camera image is black"
    withheld = next(d for d in dashes if d["note"].startswith("withheld"))
    assert "worse than a black image" in withheld["title"]
    for note in page.locator(".why-note").all()[:5]:
        assert note.is_visible()
    log.assert_clean()
    page.close()
