"""One headless Chromium per test process (Debian's ``chromium``, driven by
Playwright; the default run's two xdist workers start at most two):
``tests/conftest.py`` launches it once per process as the session fixture
``chromium``, and each browser test module opens its own fresh browser context on
it (:func:`new_context`: no cookies, storage or cache shared between modules),
instead of a browser of its own.

A missing browser or ``playwright`` skips the browser tests with the reason, except
under CI (``CI`` set), where it is a failure: ``python -m harness.system`` installs
chromium there and the ``test`` extra installs playwright.
"""

from __future__ import annotations

import contextlib
import importlib.util
import os
from collections.abc import Iterator
from pathlib import Path

import pytest

CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
]
#: The viewport every report test lays the page out in (the index must fit 1400 px).
VIEWPORT = {"width": 1400, "height": 1000}


def missing() -> str | None:
    """Why the browser tests cannot run here, or None."""
    if not CHROMIUM.is_file():
        return (f"{CHROMIUM} not found: install Debian's chromium (as root: "
                "python -m harness.system, or apt-get install -y chromium)")
    if importlib.util.find_spec("playwright") is None:
        return "the playwright package is missing: pip install -e .[test]"
    return None


def require_browser() -> None:
    """Skip (locally) or fail (under CI) when the browser cannot run."""
    reason = missing()
    if reason:
        if os.environ.get("CI"):
            pytest.fail(f"browser test cannot run on CI: {reason}")
        pytest.skip(reason)


@contextlib.contextmanager
def launch() -> Iterator[object]:
    """A headless Chromium (a Playwright ``Browser``), closed on exit."""
    from playwright.sync_api import sync_playwright  # noqa: PLC0415 - only with a browser

    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=str(CHROMIUM),
                                             args=CHROMIUM_ARGS, headless=True)
        try:
            yield browser
        finally:
            browser.close()


@contextlib.contextmanager
def new_context(chromium) -> Iterator[object]:
    """A fresh, offline browser context on the run's ``chromium``, closed on exit."""
    context = chromium.new_context(viewport=VIEWPORT, offline=True)
    try:
        yield context
    finally:
        context.close()
