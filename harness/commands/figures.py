"""``caustics figures -o DIR``: regenerate the paper's figures with their data."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from harness.figures import FIGURES, FigureContext
from scenes import SCENES_DIR

__all__ = ["figures"]


def figures(args: argparse.Namespace) -> int:
    """``caustics figures``: each figure's PDF/PNG with the CSV/JSON it was drawn from."""
    names = args.only.split(",") if args.only else list(FIGURES)
    unknown = [n for n in names if n not in FIGURES]
    if unknown:
        print(f"error: unknown figure {', '.join(unknown)} (choose from "
              f"{', '.join(FIGURES)})", file=sys.stderr)
        return 2
    ctx = FigureContext(out_dir=Path(args.output),
                        scenes_dir=Path(args.scenes) if args.scenes else SCENES_DIR,
                        quick=args.quick, cache=args.cache_dir, progress=not args.quiet)
    if not ctx.scenes_dir.is_dir():
        print(f"error: scenes folder not found: {ctx.scenes_dir} (use --scenes)",
              file=sys.stderr)
        return 2
    try:
        for name in names:
            start = time.perf_counter()
            result = FIGURES[name](ctx)
            print(f"{name} ({time.perf_counter() - start:.1f} s): {result.caption}")
    finally:
        ctx.close()
    return 0
