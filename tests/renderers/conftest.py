"""GL fixtures for every renderer test, in the style of moderngl's own
tests/conftest.py: ONE context factory for the session, and a ``ctx`` fixture that
asserts the context holds no GL error before and after every test."""

from __future__ import annotations

import pytest

from renderers.caustics_mapping import create_context


@pytest.fixture(scope="session")
def context_factory():
    """The one place a GL context is created; shared by the whole session."""
    ctx = create_context()
    yield lambda: ctx
    ctx.release()


@pytest.fixture
def ctx(context_factory):
    """The session's context, asserting GL_NO_ERROR before and after the test."""
    context = context_factory()
    assert context.error == "GL_NO_ERROR"
    yield context
    assert context.error == "GL_NO_ERROR"
