"""``caustics figures -o DIR``: regenerate the paper's figures with their data."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

__all__ = ["register"]


def _figures(args: argparse.Namespace) -> int:
    from harness.figures import FIGURES, FigureContext  # noqa: PLC0415
    from harness.figures.common import default_scenes_dir  # noqa: PLC0415

    names = args.only.split(",") if args.only else list(FIGURES)
    unknown = [n for n in names if n not in FIGURES]
    if unknown:
        print(f"error: unknown figure {', '.join(unknown)} (choose from "
              f"{', '.join(FIGURES)})", file=sys.stderr)
        return 2
    ctx = FigureContext(out_dir=Path(args.output),
                        scenes_dir=Path(args.scenes) if args.scenes else default_scenes_dir(),
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


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("figures", help="regenerate the paper's figures with their data")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output directory")
    p.add_argument("--only", metavar="LIST", help="comma-separated figure names (fig06,...)")
    p.add_argument("--quick", action="store_true", help="small budgets and images")
    p.add_argument("--scenes", metavar="DIR", help="scenes folder (default: the repository's)")
    p.add_argument("--cache-dir", help="reference cache root")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bars")
    p.set_defaults(func=_figures)
