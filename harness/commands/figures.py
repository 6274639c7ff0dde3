"""``caustics figures -o DIR``: regenerate the paper's figures with their data."""

from __future__ import annotations

import argparse
import contextlib
import sys
import tempfile
import time
from pathlib import Path

from harness.figures import FIGURES, FigureContext
from harness.terminal import plain
from harness.writable import usable_cache
from renderers.mitsuba.cache import cache_dir
from scenes import SCENES_DIR

__all__ = ["figures"]


def figures(args: argparse.Namespace) -> int:
    """``caustics figures``: each figure's PDF/PNG with the CSV/JSON it was drawn from."""
    names = args.only.split(",") if args.only else list(FIGURES)
    unknown = [n for n in names if n not in FIGURES]
    if unknown:
        print(f"error: unknown figure {plain(', '.join(unknown))} (choose from "
              f"{', '.join(FIGURES)})", file=sys.stderr)
        return 2
    scenes_dir = Path(args.scenes) if args.scenes else SCENES_DIR
    if not scenes_dir.is_dir():
        print(f"error: scenes folder not found: {plain(scenes_dir)} (use --scenes)",
              file=sys.stderr)
        return 2
    with contextlib.ExitStack() as stack:
        cache = args.cache_dir
        if not usable_cache(cache_dir(cache)):
            # FigureContext always caches; a throw-away cache keeps the run going (and
            # still shares a reference between the figures that use it).
            cache = stack.enter_context(tempfile.TemporaryDirectory(prefix="caustics-cache-"))
        ctx = FigureContext(out_dir=Path(args.output), scenes_dir=scenes_dir,
                            quick=args.quick, cache=cache, progress=not args.quiet)
        stack.callback(ctx.close)
        for name in names:
            start = time.perf_counter()
            result = FIGURES[name](ctx)
            print(f"{name} ({time.perf_counter() - start:.1f} s): {plain(result.caption)}")
    return 0
