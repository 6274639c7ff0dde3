"""Headless Chromium through Playwright: one page that loads the exported scene with
three.js's ``GLTFLoader``, renders drei's ``Caustics`` and the camera image, and hands
back float32 pixels and browser-side timings.

The browser is Debian's ``chromium`` (never a browser Playwright downloads). WebGL2
comes from ANGLE on SwiftShader (a CPU Vulkan) on a machine without a GPU: the flags
:data:`CHROMIUM_ARGS` are what gives it ``EXT_color_buffer_float`` (float render
targets), ``OES_texture_float_linear`` (the component's float caustic texture) and
``EXT_disjoint_timer_query_webgl2`` (GPU timer queries); with ``--disable-gpu``
instead, WebGL2 and the float extensions remain but the timer query goes, and the
page falls back to ``performance.now()`` around the work plus ``gl.finish()``, and
says so.

Nothing is fetched: the page, the bundle and the ``.glb`` are answered by a route
handler on a host that does not exist (``caustics.invalid``), and every other request
is aborted and reported as an error.
"""

from __future__ import annotations

import base64
import contextlib
import importlib.util
import json
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from renderers.drei.bundle import DreiSetupError

__all__ = ["CHROMIUM", "CHROMIUM_ARGS", "HOST", "PageResult", "launch", "render_page",
           "unavailable_reason"]

#: Debian's Chromium.
CHROMIUM = Path("/usr/bin/chromium")
#: Headless, no sandbox (containers), WebGL2 on SwiftShader with its timer query.
CHROMIUM_ARGS = (
    "--headless", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
    "--ignore-gpu-blocklist", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
)
#: The page's origin: answered by the route handler, resolvable nowhere.
HOST = "http://caustics.invalid"
_PAGE = """<!doctype html><html><head><meta charset="utf-8"><title>drei-caustics</title>
</head><body style="margin:0"><script src="drei.js"></script></body></html>"""


def unavailable_reason() -> str | None:
    """Why the page cannot run here (no Chromium, no Playwright), or None."""
    if not CHROMIUM.is_file():
        return (f"{CHROMIUM} not found: install Debian's chromium (as root: "
                "python -m harness.system, or apt-get install -y chromium)")
    if importlib.util.find_spec("playwright") is None:
        return "the playwright package is missing: pip install -e '.[drei]'"
    return None


@contextlib.contextmanager
def launch() -> Iterator[object]:
    """A headless Chromium (a Playwright ``Browser``) with :data:`CHROMIUM_ARGS`,
    closed on exit.

    Raises
    ------
    DreiSetupError
        No Chromium or no Playwright here.
    """
    reason = unavailable_reason()
    if reason:
        raise DreiSetupError(f"drei-caustics needs a browser: {reason}")
    from playwright.sync_api import sync_playwright  # noqa: PLC0415 - heavy, only here

    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=str(CHROMIUM),
                                             args=list(CHROMIUM_ARGS), headless=True)
        try:
            yield browser
        finally:
            browser.close()


@dataclass(frozen=True, eq=False)
class PageResult:
    """What the page returned, decoded.

    Attributes
    ----------
    front, back : tuple of ndarray
        Per pass (one per distinct IOR), the component's front (and back: None without
        ``backside``) caustic texture, (res, res) float32, row 0 at t = 0, W/m².
    camera : ndarray, (H, W, 3), float32
        Linear radiance, row 0 at the image's top.
    data : dict
        The rest of the page's answer (light camera, timings, timer, WebGL facts).
    """

    front: tuple[np.ndarray, ...]
    back: tuple[np.ndarray | None, ...]
    camera: np.ndarray
    data: dict


def _floats(text: str, shape: tuple[int, ...]) -> np.ndarray:
    return np.frombuffer(base64.b64decode(text), dtype="<f4").reshape(shape).copy()


def _decode(answer: dict) -> PageResult:
    res, width, height = answer["resolution"], answer["width"], answer["height"]
    front = tuple(_floats(t, (res, res)) for t in answer.pop("front"))
    back = tuple(None if t is None else _floats(t, (res, res)) for t in answer.pop("back"))
    # readPixels gives rows bottom to top; images are stored top row first.
    image = _floats(answer.pop("camera"), (height, width, 4))[::-1, :, :3]
    return PageResult(front, back, np.ascontiguousarray(image), answer)


def render_page(browser, *, glb: bytes, bundle: Path, config: dict,
                timeout: float = 300.0) -> PageResult:
    """Run ``window.dreiCaustics.run(config)`` on a fresh page of ``browser``.

    Parameters
    ----------
    browser : playwright.sync_api.Browser
        A Chromium (:func:`launch`, or a test session's).
    glb : bytes
        The exported scene, served as ``scene.glb``.
    bundle : Path
        The page's script (:func:`renderers.drei.bundle.ensure_bundle`).
    config : dict
        The page's configuration (``js/main.mjs`` lists it); its ``glb`` is set here.
    timeout : float
        Seconds the page may take.

    Raises
    ------
    DreiSetupError
        The page threw (its message and the console's errors), or asked for anything
        that is not the page, the bundle or the scene.
    """
    served = {"/index.html": ("text/html", _PAGE.encode()),
              "/drei.js": ("text/javascript", bundle.read_bytes()),
              "/scene.glb": ("model/gltf-binary", glb)}
    refused: list[str] = []
    errors: list[str] = []

    def answer(route):
        url = route.request.url
        path = url[len(HOST):] if url.startswith(HOST + "/") else None
        if path not in served:
            refused.append(url)
            route.abort()
            return
        kind, body = served[path]
        route.fulfill(status=200, content_type=kind, body=body)

    context = browser.new_context(viewport={"width": 64, "height": 64})
    try:
        context.route("**/*", answer)
        page = context.new_page()
        page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.set_default_timeout(timeout * 1e3)
        page.goto(f"{HOST}/index.html")
        try:
            raw = page.evaluate("config => window.dreiCaustics.run(config)",
                                {**config, "glb": f"{HOST}/scene.glb"})
        except Exception as error:  # Playwright's Error: the page threw
            raise DreiSetupError(f"the drei page failed: {error}; console: "
                                 f"{json.dumps(errors)}") from None
    finally:
        context.close()
    if refused:
        raise DreiSetupError(f"the drei page asked for {refused}: nothing but its page, "
                             "bundle and scene may be loaded")
    result = _decode(raw)
    result.data["console_errors"] = errors
    return result
