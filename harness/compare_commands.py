"""``caustics compare SCENE... -o DIR``: both renderers, every comparison, HTML report."""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from pathlib import Path

from harness.scene import parse_override, with_settings

__all__ = ["register", "summary_rows"]

DEFAULT_THRESHOLDS = Path("tests") / "thresholds.toml"
DEFAULT_GOLDEN = Path("tests") / "golden"


def summary_rows(comparisons) -> list[tuple[str, ...]]:
    """One row per scene: the key numbers of the one-screen summary."""
    rows = []
    for c in comparisons:
        def value(metric, view="receiver0", region="caustic", c=c):
            try:
                m = c.metric(view, region, metric)
            except KeyError:
                return "–"
            floor = "" if m.noise_floor is None else f" ({m.noise_floor:.3g})"
            return f"{m.value:.3g}{floor}"

        frame = c.provenance.get("caustics_mapping", {}).get("frame_time_ms")
        speedup = f"{c.speedup.speedup:.3g}x {c.speedup.kind}" if c.speedup else "–"
        passed = sum(t.passed for t in c.thresholds)
        bounds = f"{passed}/{len(c.thresholds)}" if c.thresholds else "–"
        rows.append((c.name, value("relmse"), value("ssim"), value("flip"),
                     value("flux_ratio", region="full"),
                     f"{frame:.1f}" if frame is not None and math.isfinite(frame) else "–",
                     speedup, bounds))
    return rows


def _print_summary(comparisons, out_dir: Path, seconds: float) -> None:
    from rich.console import Console  # noqa: PLC0415
    from rich.table import Table  # noqa: PLC0415

    table = Table(title=f"caustics mapping vs Mitsuba ({seconds:.0f} s) -> {out_dir}/index.html",
                  caption="receiver 0, caustic region; (noise floor: an independent "
                  "reference seed vs the reference)")
    for column in ("scene", "relMSE", "SSIM", "FLIP", "flux ratio (full)", "frame ms",
                   "equal-error speedup", "bounds"):
        table.add_column(column)
    for row in summary_rows(comparisons):
        table.add_row(*row)
    # A pipe or a log gets a wide table rather than rich's 80-column default.
    console = Console()
    if not console.is_terminal:
        console = Console(width=160)
    console.print(table)


def _compare(args: argparse.Namespace) -> int:
    from harness.accuracy import golden_checks  # noqa: PLC0415
    from harness.compare.outputs import write_comparison  # noqa: PLC0415
    from harness.compare.pipeline import STUDIES, CompareOptions, compare_scene  # noqa: PLC0415
    from harness.figures.common import default_scenes_dir  # noqa: PLC0415
    from harness.scene_commands import load_scenes  # noqa: PLC0415
    from harness.thresholds import load_thresholds  # noqa: PLC0415
    from reports import build_report, scene_folder  # noqa: PLC0415
    from reports.plots import write_pdfs  # noqa: PLC0415

    start = time.perf_counter()
    overrides = dict(parse_override(item) for item in args.set or [])
    for name in ("estimator", "iterations", "grid", "photons"):
        if getattr(args, name) is not None:
            overrides[name] = getattr(args, name)
    scenes = [with_settings(s, overrides) for s in load_scenes(args.scenes)]
    studies = tuple(s for s in (args.studies or ",".join(STUDIES)).split(",") if s)
    unknown = sorted(set(studies) - set(STUDIES))
    if unknown:
        print(f"error: unknown study {', '.join(unknown)} (choose from {', '.join(STUDIES)})",
              file=sys.stderr)
        return 2
    thresholds_path = Path(args.thresholds) if args.thresholds else DEFAULT_THRESHOLDS
    bounds = load_thresholds(thresholds_path) if thresholds_path.is_file() else ()
    options = CompareOptions(studies=studies, max_iterations=args.max_iterations,
                             quick=args.quick, cache=args.cache_dir,
                             use_cache=not args.no_cache, progress=not args.quiet)
    out_dir = Path(args.output)
    comparisons, taken = [], []
    for scene in scenes:
        comparison = compare_scene(scene, options=options)
        checks = None
        if bounds:
            checks = golden_checks(scene, scenes_dir=default_scenes_dir(),
                                   golden_dir=Path(args.golden), bounds=bounds)
        if checks:
            comparison = dataclasses.replace(comparison, thresholds=checks)
        folder = scene_folder(scene.name, taken=taken)
        taken.append(folder)
        write_comparison(out_dir / folder, comparison)
        write_pdfs(out_dir / folder, comparison)
        comparisons.append(comparison)
    build_report(out_dir, comparisons, self_contained=args.self_contained)
    _print_summary(comparisons, out_dir, time.perf_counter() - start)
    failed = [t for c in comparisons for t in c.thresholds if not t.passed]
    return 3 if failed and args.fail_on_thresholds else 0


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "compare", help="render both ways, compare, write data files and an HTML report")
    p.add_argument("scenes", nargs="*", metavar="SCENE", help="scene files (default: embedded)")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output directory")
    p.add_argument("--studies", metavar="LIST",
                   help="comma-separated: metrics,convergence,cost (default: all)")
    p.add_argument("--quick", action="store_true",
                   help="smaller sweeps, one timing repeat, at most 4 iterations")
    p.add_argument("--max-iterations", type=int, default=8, metavar="N",
                   help="iterations 0..N in the convergence table (default 8)")
    p.add_argument("--estimator", choices=("modified", "newton", "secant"))
    p.add_argument("--iterations", type=int)
    p.add_argument("--grid", type=int)
    p.add_argument("--photons", type=int, help="reference photon budget per seed")
    p.add_argument("--set", action="append", metavar="NAME=VALUE",
                   help="override any setting (repeatable)")
    p.add_argument("--thresholds", metavar="FILE",
                   help=f"accuracy bounds (default: {DEFAULT_THRESHOLDS} if present); checked "
                   "at the golden settings against the golden references, for committed "
                   "scenes only")
    p.add_argument("--golden", default=str(DEFAULT_GOLDEN), metavar="DIR",
                   help="golden references the bounds hold against (default: %(default)s)")
    p.add_argument("--fail-on-thresholds", action="store_true",
                   help="exit 3 when a bound fails")
    p.add_argument("--self-contained", action="store_true",
                   help="embed images, plots, scripts in one HTML file per page")
    p.add_argument("--cache-dir", help="reference cache root")
    p.add_argument("--no-cache", action="store_true", help="render references without the cache")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bars")
    p.set_defaults(func=_compare)
