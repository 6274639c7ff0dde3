"""The OpenGL context, GLSL program loading and per-pass timing.

Shaders live in ``.glsl`` files beside the pass that uses them, one file per
program with ``#if defined VERTEX_SHADER`` / ``#elif defined FRAGMENT_SHADER``
sections (the moderngl-window convention). A line ``#include "common.glsl"`` is
replaced by the shared include of this package.
"""

from __future__ import annotations

import os
import re
import time
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

import moderngl

from scenes.errors import HarnessError

__all__ = [
    "DEVICE_ENV", "GLError", "PassTimer", "ResourcePool", "create_context", "load_program",
    "pool",
    "release_framebuffer",
]

_HERE = Path(__file__).parent
#: Largest iteration count the shaders are compiled for (``Settings.iterations`` <= 64).
MAX_ITERATIONS = 64


class GLError(HarnessError, RuntimeError):
    """An OpenGL context could not be created, or a pass left a GL error."""


#: Names the EGL device to render on: an index (``0``, ``1``, ...), or ``default``
#: for the EGL default display; unset, a hardware device is preferred to llvmpipe.
DEVICE_ENV = "CAUSTICS_GL_DEVICE"

#: What a GL timer query returns where it is not supported (llvmpipe).
_INVALID_QUERY = 2**32 - 1

#: EGL device indices tried when looking for hardware.
_MAX_DEVICES = 8


def _egl(device: int | None) -> moderngl.Context:
    kwargs = {} if device is None else {"device_index": device}
    return moderngl.create_standalone_context(backend="egl", require=430, **kwargs)


def _is_software(ctx: moderngl.Context) -> bool:
    return any(name in ctx.info.get("GL_RENDERER", "").lower()
               for name in ("llvmpipe", "softpipe", "swrast"))


@cache
def _hardware_device() -> int | None:
    """The first EGL device that is not a software rasteriser (NVIDIA's, where a
    GPU is), or None. Looked up once per process."""
    for index in range(_MAX_DEVICES):
        try:
            ctx = _egl(index)
        except Exception:  # past the last device: glcontext raises plain Exception
            return None
        software = _is_software(ctx)
        ctx.release()
        if not software:
            return index
    return None


def _device_choice() -> int | None:
    value = os.environ.get(DEVICE_ENV, "").strip().lower()
    if value in ("", "auto"):
        return _hardware_device()
    if value == "default":
        return None
    try:
        return int(value)
    except ValueError:
        raise GLError(f"{DEVICE_ENV}={value}: expected an EGL device index, 'default' or "
                      "'auto'") from None


def create_context() -> moderngl.Context:
    """A headless OpenGL 4.5 context through EGL: on a hardware device (NVIDIA's
    EGL device on a GPU machine) where one exists, else the default display (Mesa
    llvmpipe on CPU). :data:`DEVICE_ENV` forces a device index or the default.

    Raises
    ------
    GLError
        When no EGL context of version 4.3 or newer can be created.
    """
    device = _device_choice()
    try:
        ctx = _egl(device)
    except Exception as error:  # moderngl raises plain Exception on EGL failures
        where = "" if device is None else f" on EGL device {device}"
        raise GLError(f"cannot create a headless OpenGL 4.3 context{where}: {error}") from error
    return ctx


_INCLUDE = re.compile(r'^#include "([A-Za-z0-9_]+\.glsl)"$', re.MULTILINE)


@cache
def _source(name: str) -> str:
    """The file's text with every ``#include "X.glsl"`` line replaced by that file
    (itself expanded), each file included once."""
    seen: set[str] = set()

    def expand(file: str) -> str:
        def include(match: re.Match) -> str:
            target = match.group(1)
            if target in seen:
                return ""
            seen.add(target)
            return expand(target)
        return _INCLUDE.sub(include, (_HERE / file).read_text())

    return expand(name)


def _context_cache(ctx: moderngl.Context) -> dict:
    """The dict kept in ``ctx.extra`` for what lives as long as the context (its
    programs, timer query, idle framebuffer and resource pool), made on first use."""
    if not isinstance(ctx.extra, dict):
        ctx.extra = {}
    return ctx.extra


def load_program(
    ctx: moderngl.Context, name: str, *, defines: dict[str, object] | None = None,
    fragment: bool = True, compute: bool = False, geometry: bool = False,
) -> moderngl.Program | moderngl.ComputeShader:
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
    compute : bool
        Compile the file's ``COMPUTE_SHADER`` section alone into a compute shader.
    geometry : bool
        Whether the file has a ``GEOMETRY_SHADER`` section.
    """
    cache = _context_cache(ctx)
    key = ("program", name, tuple(sorted((defines or {}).items())), fragment, compute, geometry)
    if key in cache:
        return cache[key]
    body = _source(name)
    head = "#version 450 core\n" + f"#define MAX_ITERATIONS {MAX_ITERATIONS}\n"
    head += "".join(f"#define {k} {v}\n" for k, v in (defines or {}).items())
    if compute:
        program = ctx.compute_shader(head + "#define COMPUTE_SHADER 1\n" + body)
        cache[key] = program
        return program
    vertex = head + "#define VERTEX_SHADER 1\n" + body
    frag = head + "#define FRAGMENT_SHADER 1\n" + body if fragment else None
    geom = head + "#define GEOMETRY_SHADER 1\n" + body if geometry else None
    program = ctx.program(vertex_shader=vertex, fragment_shader=frag, geometry_shader=geom)
    cache[key] = program
    return program


@dataclass
class PassTimer:
    """Seconds per pass, summed over repeated runs of the same pass.

    Each measured pass is also checked for GL errors (:class:`GLError` names it).

    Each pass is timed on the CPU: ``ctx.finish()`` before and after,
    ``time.perf_counter()`` between, so a pass's time includes the read-backs it
    makes (the receiver maps), as the photon tracer's time includes its own. The
    ``timer`` attribute names that clock. On a hardware device a GL timer query
    (``GL_TIME_ELAPSED``) also times the GPU work of each pass alone, into
    ``gpu_timings``; on llvmpipe those queries return 2^32 - 1 (invalid) and
    ``gpu_timings`` stays empty.
    """

    ctx: moderngl.Context
    timings: dict[str, float] = field(default_factory=dict)
    timer: str = "ctx.finish + time.perf_counter"
    gpu_timings: dict[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.queries = not _is_software(self.ctx)

    def measure(self, name: str):
        """Context manager timing one pass under ``name``."""
        return _Measure(self, name)


def _time_query(ctx: moderngl.Context) -> moderngl.Query:
    """The context's one ``GL_TIME_ELAPSED`` query, made on first use and reused by
    every pass (passes are timed one after another, never nested; moderngl's Query
    has no ``release``, so a query per pass would leak one GL object each)."""
    cache = _context_cache(ctx)
    if "time_query" not in cache:
        cache["time_query"] = ctx.query(time=True)
    return cache["time_query"]


class _Measure:
    def __init__(self, timer: PassTimer, name: str) -> None:
        self.timer, self.name = timer, name

    def __enter__(self) -> None:
        self.timer.ctx.finish()
        self.query = _time_query(self.timer.ctx) if self.timer.queries else None
        if self.query is not None:
            self.query.__enter__()
        self.start = time.perf_counter()

    def __exit__(self, *exc) -> None:
        if self.query is not None:
            self.query.__exit__(*exc)
        self.timer.ctx.finish()
        elapsed = time.perf_counter() - self.start
        self.timer.timings[self.name] = self.timer.timings.get(self.name, 0.0) + elapsed
        if self.query is not None:
            nanoseconds = self.query.elapsed
            if 0 < nanoseconds < _INVALID_QUERY:
                gpu = self.timer.gpu_timings
                gpu[self.name] = gpu.get(self.name, 0.0) + nanoseconds * 1e-9
        error = self.timer.ctx.error
        if error != "GL_NO_ERROR" and exc[0] is None:
            raise GLError(f"pass {self.name} left {error}")


def release_framebuffer(ctx: moderngl.Context, fbo: moderngl.Framebuffer) -> None:
    """Bind a small persistent framebuffer, then release ``fbo``.

    moderngl re-binds the current framebuffer after creating a new one; if that is a
    released one, GL reports GL_INVALID_OPERATION, so a pass never leaves a released
    framebuffer bound.
    """
    cache = _context_cache(ctx)
    if "idle_fbo" not in cache:
        cache["idle_fbo"] = ctx.framebuffer([ctx.renderbuffer((1, 1), 4)])
    cache["idle_fbo"].use()
    fbo.release()


class ResourcePool:
    """Render targets and storage buffers reused from frame to frame on one context.

    A fresh allocation is expensive on Mesa llvmpipe (the memory is zero-filled and
    page-faulted on first use: creating and clearing a 1024 x 1024 RGBA32F target
    with its depth texture takes about 18 ms, clearing a reused one about 1.3 ms),
    so the passes take their textures, depth textures, framebuffers and buffers
    from here instead of creating and releasing them every frame.

    Whoever takes a resource clears or overwrites all of it before reading it, as
    with a fresh one, so reuse changes no result. Resources live for one frame:
    :meth:`give_back` returns one early (for reuse within the frame, e.g. by the
    next light sample), :meth:`end_frame` takes back all the rest and releases the
    free ones the frame did not use, so at most one frame's worth stays alive.
    Framebuffers are cached per set of attachments and released with them. Callers
    must not release pooled resources themselves.
    """

    def __init__(self, ctx: moderngl.Context) -> None:
        self.ctx = ctx
        self._free: dict[tuple, list[Any]] = {}
        self._key: dict[int, tuple] = {}        # id(resource) -> its pool key
        self._taken: dict[int, Any] = {}        # taken and not yet given back
        self._used: set[int] = set()            # ids taken during the current frame
        self._fbos: dict[tuple, tuple[tuple, moderngl.Framebuffer]] = {}

    def _take(self, key: tuple, make) -> Any:
        free = self._free.get(key)
        resource = free.pop() if free else make()
        self._key[id(resource)] = key
        self._taken[id(resource)] = resource
        self._used.add(id(resource))
        return resource

    def texture(self, size: tuple[int, int], components: int = 4,
                dtype: str = "f4") -> moderngl.Texture:
        """A colour texture (contents undefined, filter NEAREST)."""
        tex = self._take(("texture", tuple(size), components, dtype),
                         lambda: self.ctx.texture(tuple(size), components, dtype=dtype))
        tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
        return tex

    def depth_texture(self, size: tuple[int, int]) -> moderngl.Texture:
        """A depth texture (contents undefined)."""
        return self._take(("depth", tuple(size)), lambda: self.ctx.depth_texture(tuple(size)))

    def buffer(self, nbytes: int) -> moderngl.Buffer:
        """A buffer of exactly ``nbytes`` bytes (contents undefined)."""
        return self._take(("buffer", int(nbytes)), lambda: self.ctx.buffer(reserve=int(nbytes)))

    def framebuffer(self, colors: list[moderngl.Texture],
                    depth: moderngl.Texture | None = None) -> moderngl.Framebuffer:
        """The (cached) framebuffer of these pooled attachments."""
        attachments = (*colors, depth)
        key = tuple(id(a) for a in attachments)
        entry = self._fbos.get(key)
        if entry is None or any(a is not b for a, b in zip(entry[0], attachments, strict=True)):
            entry = (attachments, self.ctx.framebuffer(list(colors), depth))
            self._fbos[key] = entry
        return entry[1]

    def give_back(self, resource: Any) -> None:
        """Return a resource taken from this pool (anything else is released)."""
        if self._taken.pop(id(resource), None) is None:
            resource.release()
            return
        self._free.setdefault(self._key[id(resource)], []).append(resource)

    def end_frame(self) -> None:
        """Take everything back; release the free resources this frame did not use."""
        for resource in list(self._taken.values()):
            self.give_back(resource)
        stale = []
        for key, free in self._free.items():
            stale += [r for r in free if id(r) not in self._used]
            self._free[key] = [r for r in free if id(r) in self._used]
        gone = {id(r) for r in stale}
        for key, (attachments, fbo) in list(self._fbos.items()):
            if any(id(a) in gone for a in attachments if a is not None):
                release_framebuffer(self.ctx, fbo)
                del self._fbos[key]
        for resource in stale:
            del self._key[id(resource)]
            resource.release()
        self._free = {k: v for k, v in self._free.items() if v}
        self._used = set()


def pool(ctx: moderngl.Context) -> ResourcePool:
    """The context's :class:`ResourcePool` (kept in ``ctx.extra``)."""
    cache = _context_cache(ctx)
    if "pool" not in cache:
        cache["pool"] = ResourcePool(ctx)
    return cache["pool"]
