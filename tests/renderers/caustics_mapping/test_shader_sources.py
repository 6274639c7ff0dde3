"""The GLSL include mechanism (``#include "X.glsl"``, expanded by the program loader)
and the shared shader files the passes include instead of keeping copies."""

from __future__ import annotations

import re
from pathlib import Path

from renderers.caustics_mapping import context

PACKAGE = Path(context.__file__).parent
INCLUDE = re.compile(r'^#include "([A-Za-z0-9_]+\.glsl)"$', re.MULTILINE)


def _expand(name: str) -> str:
    """The loader's expansion of ``name``, bypassing its per-process cache."""
    return context._source.__wrapped__(name)


def _programs() -> list[str]:
    """The .glsl files no other file includes: the programs the passes load."""
    files = sorted(p.name for p in PACKAGE.glob("*.glsl"))
    included = {m for f in files for m in INCLUDE.findall((PACKAGE / f).read_text())}
    return [f for f in files if f not in included]


def test_a_file_reached_twice_is_included_once(tmp_path, monkeypatch):
    """A diamond (top includes left and right, both include base) expands base once,
    before its first user: GLSL rejects a function defined twice."""
    files = {
        "base.glsl": "float base_value() { return 1.0; }\n",
        "left.glsl": '#include "base.glsl"\nfloat left() { return base_value(); }\n',
        "right.glsl": '#include "base.glsl"\nfloat right() { return 2.0; }\n',
        "top.glsl": '#include "left.glsl"\n#include "right.glsl"\n',
    }
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    monkeypatch.setattr(context, "_HERE", tmp_path)
    text = _expand("top.glsl")
    assert text.count("float base_value()") == 1
    order = [text.index(f) for f in ("float base_value()", "float left()", "float right()")]
    assert order == sorted(order)
    assert not INCLUDE.search(text)


def test_every_program_expands_without_include_lines():
    """Each program's source, once expanded, has no ``#include`` left and no shared
    file twice (every include file's first line at most once)."""
    programs = _programs()
    assert "caustic_trace.glsl" in programs and "estimators.glsl" not in programs
    for name in programs:
        text = _expand(name)
        assert not INCLUDE.search(text), name
        for include in PACKAGE.glob("*.glsl"):
            first = include.read_text().splitlines()[0]
            assert text.count(first) <= 1, (name, include.name)


def test_shared_shader_maths_has_one_copy():
    """The estimators run by the caustic trace and the camera pass, and the Gaussian
    splat program of both splat passes, are the same included text, defined in one
    file only; so is the stream compaction of the Gaussians' rectangles and the rim
    patches."""
    estimators = (PACKAGE / "estimators.glsl").read_text()
    for program in ("caustic_trace.glsl", "camera.glsl"):
        assert estimators in _expand(program), program
    gaussians = _expand("splat_gaussians.glsl")
    for program in ("caustic_splat.glsl", "receiver_splat.glsl"):
        assert gaussians in _expand(program), program
    compact = (PACKAGE / "compact.glsl").read_text()
    for program in ("caustic_splat.glsl", "rim_patches.glsl"):
        assert compact in _expand(program), program
    definitions = {
        "void compact(int n)": "compact.glsl",
        "int estimate_along(": "estimators.glsl",
        "float light_distance(": "common.glsl",
        "bool receiver_lookup(": "common.glsl",
        "void write_surface(": "surface_positions.glsl",
    }
    for signature, home in definitions.items():
        owners = [p.name for p in PACKAGE.glob("*.glsl") if signature in p.read_text()]
        assert owners == [home], signature
