"""``caustics compare SCENE... -o DIR``: both renderers, every comparison, HTML report."""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from pathlib import Path

from rich.console import Console
from rich.table import Table

from harness.checks import GOLDEN_DIR, THRESHOLDS_FILE
from harness.checks.accuracy import golden_checks
from harness.checks.thresholds import load_thresholds
from harness.commands.crosscheck import run_crosscheck
from harness.commands.scene import load_scenes
from harness.compare.outputs import write_comparison
from harness.compare.pipeline import STUDIES, CompareOptions, compare_scene
from renderers.methods import load_method
from reports import build_report, scene_folder
from reports.plots import write_pdfs
from scenes import SCENES_DIR, parse_override, with_settings

__all__ = ["DEFAULT_METHODS", "compare", "summary_rows"]

#: Methods compared when none is named: both caustics-mapping presets.
DEFAULT_METHODS = ("paper", "strong")


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

        frame = (c.provenance.get("caustics_mapping") or c.provenance.get("method")
                 or {}).get("frame_time_ms")
        speedup = f"{c.speedup.speedup:.3g}x {c.speedup.kind}" if c.speedup else "–"
        passed = sum(t.passed for t in c.thresholds)
        bounds = f"{passed}/{len(c.thresholds)}" if c.thresholds else "–"
        rows.append((c.name, c.method, value("relmse"), value("ssim"), value("flip"),
                     value("flux_ratio", region="full"),
                     f"{frame:.1f}" if frame is not None and math.isfinite(frame) else "–",
                     speedup, bounds))
    return rows


def _print_summary(comparisons, out_dir: Path, seconds: float) -> None:
    table = Table(title=f"methods vs Mitsuba ({seconds:.0f} s) -> {out_dir}/index.html",
                  caption="receiver 0, caustic region; (noise floor: an independent "
                  "reference seed vs the reference)")
    for column in ("scene", "method", "relMSE", "SSIM", "FLIP", "flux ratio (full)", "frame ms",
                   "equal-error speedup", "bounds"):
        table.add_column(column)
    for row in summary_rows(comparisons):
        table.add_row(*row)
    # A pipe or a log gets a wide table rather than rich's 80-column default.
    console = Console()
    if not console.is_terminal:
        console = Console(width=160)
    console.print(table)


def compare(args: argparse.Namespace) -> int:
    """``caustics compare``: both renderers, every study, data files and the report."""
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
    names = [*(args.preset or []), *(args.method or [])] or list(DEFAULT_METHODS)
    methods = [load_method(name) for name in dict.fromkeys(names)]
    thresholds_path = Path(args.thresholds) if args.thresholds else THRESHOLDS_FILE
    bounds = load_thresholds(thresholds_path)  # a missing file is an error, never "no bounds"
    golden_dir = Path(args.golden) if args.golden else GOLDEN_DIR
    options = CompareOptions(studies=studies, max_iterations=args.max_iterations,
                             quick=args.quick, cache=args.cache_dir,
                             use_cache=not args.no_cache, progress=not args.quiet)
    out_dir = Path(args.output)
    comparisons, taken = [], []
    for scene, method in ((scene, method) for scene in scenes for method in methods):
        comparison = compare_scene(scene, method=method, options=options)
        checks = None
        # The bounds are regression locks of the paper preset (calibrated from its
        # output); no other method has any yet.
        if bounds and method.name == "paper":
            checks = golden_checks(scene, scenes_dir=SCENES_DIR, golden_dir=golden_dir,
                                   bounds=bounds)
        if checks:
            comparison = dataclasses.replace(comparison, thresholds=checks)
        if args.crosscheck:
            cross = run_crosscheck(scene, photons=args.crosscheck_photons,
                                   seeds=scene.settings.seeds,
                                   other_photons=args.crosscheck_photons)
            comparison = dataclasses.replace(
                comparison, crosscheck=cross.table(),
                provenance={**comparison.provenance, "crosscheck": cross.provenance})
        folder = scene_folder(comparison.page, taken=taken)
        taken.append(folder)
        write_comparison(out_dir / folder, comparison)
        write_pdfs(out_dir / folder, comparison)
        comparisons.append(comparison)
    build_report(out_dir, comparisons, self_contained=args.self_contained)
    _print_summary(comparisons, out_dir, time.perf_counter() - start)
    failed = [t for c in comparisons for t in c.thresholds if not t.passed]
    return 3 if failed and args.fail_on_thresholds else 0
