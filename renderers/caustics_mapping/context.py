"""The OpenGL context, GLSL program loading and per-pass timing.

Shaders live in ``.glsl`` files beside the pass that uses them, one file per
program with ``#if defined VERTEX_SHADER`` / ``#elif defined FRAGMENT_SHADER``
sections (the moderngl-window convention). A line ``#include "common.glsl"`` is
replaced by the shared include of this package.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path

import moderngl

from harness.errors import HarnessError

__all__ = ["GLError", "PassTimer", "create_context", "load_program", "release_framebuffer"]

_HERE = Path(__file__).parent
#: Largest iteration count the shaders are compiled for (``Settings.iterations`` <= 64).
MAX_ITERATIONS = 64


class GLError(HarnessError, RuntimeError):
    """An OpenGL context could not be created, or a pass left a GL error."""


def create_context() -> moderngl.Context:
    """A headless OpenGL 4.5 context through EGL (Mesa llvmpipe on CPU, NVIDIA on GPU).

    Raises
    ------
    GLError
        When no EGL context of version 4.3 or newer can be created.
    """
    try:
        ctx = moderngl.create_standalone_context(backend="egl", require=430)
    except Exception as error:  # moderngl raises plain Exception on EGL failures
        raise GLError(f"cannot create a headless OpenGL 4.3 context: {error}") from error
    return ctx


@cache
def _source(name: str) -> str:
    text = (_HERE / name).read_text()
    common = (_HERE / "common.glsl").read_text()
    return text.replace('#include "common.glsl"', common)


def load_program(
    ctx: moderngl.Context, name: str, *, defines: dict[str, object] | None = None,
    fragment: bool = True,
) -> moderngl.Program:
    """Compile ``name`` (a ``.glsl`` file beside this module) into a program.

    Programs are cached on the context (``ctx.extra``), so repeated frames do not
    recompile; callers must not release them.

    Parameters
    ----------
    name : str
        File name, e.g. ``"caustic_trace.glsl"``.
    defines : dict, optional
        Extra ``#define NAME VALUE`` lines, inserted after ``#version``.
    fragment : bool
        Whether the file has a ``FRAGMENT_SHADER`` section.
    """
    cache = ctx.extra if isinstance(ctx.extra, dict) else {}
    ctx.extra = cache
    key = ("program", name, tuple(sorted((defines or {}).items())), fragment)
    if key in cache:
        return cache[key]
    body = _source(name)
    head = "#version 450 core\n" + f"#define MAX_ITERATIONS {MAX_ITERATIONS}\n"
    head += "".join(f"#define {k} {v}\n" for k, v in (defines or {}).items())
    vertex = head + "#define VERTEX_SHADER 1\n" + body
    frag = head + "#define FRAGMENT_SHADER 1\n" + body if fragment else None
    program = ctx.program(vertex_shader=vertex, fragment_shader=frag)
    cache[key] = program
    return program


@dataclass
class PassTimer:
    """Seconds per pass, summed over repeated runs of the same pass.

    Each measured pass is also checked for GL errors (:class:`GLError` names it).

    GL timer queries return 2^32 - 1 (invalid) on llvmpipe, so each pass is timed
    on the CPU: ``ctx.finish()`` before and after, ``time.perf_counter()`` between.
    The ``timer`` attribute names the clock for the result.
    """

    ctx: moderngl.Context
    timings: dict[str, float] = field(default_factory=dict)
    timer: str = "ctx.finish + time.perf_counter"

    def measure(self, name: str):
        """Context manager timing one pass under ``name``."""
        return _Measure(self, name)


class _Measure:
    def __init__(self, timer: PassTimer, name: str) -> None:
        self.timer, self.name = timer, name

    def __enter__(self) -> None:
        self.timer.ctx.finish()
        self.start = time.perf_counter()

    def __exit__(self, *exc) -> None:
        self.timer.ctx.finish()
        elapsed = time.perf_counter() - self.start
        self.timer.timings[self.name] = self.timer.timings.get(self.name, 0.0) + elapsed
        error = self.timer.ctx.error
        if error != "GL_NO_ERROR" and exc[0] is None:
            raise GLError(f"pass {self.name} left {error}")


def release_framebuffer(ctx: moderngl.Context, fbo: moderngl.Framebuffer) -> None:
    """Bind a small persistent framebuffer, then release ``fbo``.

    moderngl re-binds the current framebuffer after creating a new one; if that is a
    released one, GL reports GL_INVALID_OPERATION, so a pass never leaves a released
    framebuffer bound.
    """
    cache = ctx.extra if isinstance(ctx.extra, dict) else {}
    ctx.extra = cache
    if "idle_fbo" not in cache:
        cache["idle_fbo"] = ctx.framebuffer([ctx.renderbuffer((1, 1), 4)])
    cache["idle_fbo"].use()
    fbo.release()
