"""``caustics compare SCENE... -o DIR``: both renderers, every comparison, HTML report.

Every output goes to a staging folder beside ``DIR`` and is swapped in at the end
(:mod:`harness.compare.staging`); a scene that fails gets a failure row and page
and the others go on (:mod:`harness.compare.isolation`); the exit status is then 1.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

from rich.console import Console
from rich.table import Table

from harness.api import DEFAULT_METHODS, OptionError, UnloadedScene, load_scenes
from harness.api import compare as compare_scenes
from harness.checks import KINDS
from harness.checks.run import count_by_kind
from harness.commands.scene import print_warning
from harness.compare.consistency import disagreements as output_disagreements
from harness.terminal import markup, plain
from reports.records import SceneFailure, slower
from scenes import Scene, SceneError, default_scene_path, parse_override

__all__ = ["DEFAULT_METHODS", "check_count_lines", "compare", "excess_cell", "headline_lines",
           "print_summary", "summary_rows"]

def excess_cell(m) -> str:
    """One metric for the summary: the method's own (excess) error with its 95 %
    interval first, a mark when the interval excludes 0 (``OFF``: measurably off the
    noise-free image), then the raw value; the raw value alone where there is no
    excess."""
    if m.excess is None or m.excess_ci95 is None:
        return f"raw {m.value:.3g} (no interval)"
    low, high = m.excess_ci95
    mark = "OFF " if m.verdict == "measurably off" else ""
    return f"{mark}{m.excess:.3g} [{low:.3g}, {high:.3g}] (raw {m.value:.3g})"


def _speed(speedup: float) -> str:
    """``2.44x``, or ``1.73x slower`` for a speedup below 1."""
    return f"{1 / speedup:.3g}x slower" if slower(speedup) else f"{speedup:.3g}x"


def summary_rows(comparisons) -> list[tuple[str, ...]]:
    """One row per scene: the key numbers of the one-screen summary (plain text: the
    caller escapes it for Rich). A failed scene says ``FAILED`` and nothing else."""
    rows = []
    for c in comparisons:
        if isinstance(c, SceneFailure):
            rows.append((c.name, c.method, "FAILED", *("–",) * 5))
            continue

        def value(metric, view="receiver0", region="caustic", c=c):
            try:
                m = c.metric(view, region, metric)
            except KeyError:
                return "–"
            return excess_cell(m)

        timing = c.provenance.method
        # The speedup's own scope (receiver-map passes) where there is one.
        frame = (timing.maps_time_ms if timing.maps_time_ms is not None
                 else timing.frame_time_ms)
        speedup = (f"{_speed(c.speedup.speedup)} / {_speed(c.speedup_cold.speedup)}"
                   if c.speedup and c.speedup_cold else "–")
        if c.speedup_withheld is not None:  # not meaningful (harness.compare.headlines)
            speedup = f"withheld: {c.speedup_withheld.short}"
        passed = sum(t.outcome in ("pass", "gap closed") for t in c.checks)
        gaps = sum(t.outcome == "known gap" for t in c.checks)
        bounds = (f"{passed}/{len(c.checks)}"
                  + (f" ({gaps} known gap{'s' if gaps > 1 else ''})" if gaps else "")
                  if c.checks else "–")
        rows.append((c.name, c.method, value("relmse"), value("ssim"),
                     value("flux_ratio", region="full"),
                     f"{frame:.1f}" if frame is not None and math.isfinite(frame) else "–",
                     speedup, bounds))
    return rows


def headline_lines(comparisons) -> list[str]:
    """The pages' warnings (``harness.compare.headlines``: a reference that missed
    its noise target, an error within the noise floor, a withheld speedup, a claim
    undecided at this noise, a budget that does not close), one line each (plain
    text)."""
    return [f"warning: {c.page}: {h.text}" for c in comparisons
            if not isinstance(c, SceneFailure) for h in c.headlines if h.level == "warning"]


def check_count_lines(comparisons) -> list[str]:
    """One line per kind of accuracy check: how many were checked over every scene and
    method, and how they came out (plain text)."""
    checks = [t for c in comparisons if not isinstance(c, SceneFailure) for t in c.checks]
    counts = count_by_kind(checks)
    lines = []
    for kind in KINDS:
        n = counts[kind]
        parts = [f"{n['passed']} passed"]
        if n["failed"]:
            parts.append(f"{n['failed']} FAILED")
        if n["undecided"]:
            parts.append(f"{n['undecided']} undecided")
        if n["known gaps"]:
            gaps = n["known gaps"]
            parts.append(f"{gaps} known gap{'s' if gaps > 1 else ''}")
        lines.append(f"{kind}s checked: {n['checked']} ({', '.join(parts)})")
    return lines


def print_summary(comparisons, out_dir: Path, seconds: float) -> None:
    # Every cell may hold text from a scene file: escaped, or `[/]` is Rich markup.
    table = Table(title=markup(f"methods vs Mitsuba ({seconds:.0f} s) -> {out_dir}/index.html"),
                  caption="receiver 0, the scene's caustic region (the same texels for "
                  "every method): the method's own error against the noise-free image "
                  "[95 % interval], OFF when the interval excludes 0, then the raw value "
                  "against the reference; SSIM: the deficit below a perfect method's; "
                  "flux: ratio − 1 (FLIP and the camera: on the pages)")
    for column in ("scene", "method", "excess relMSE", "SSIM deficit",
                   "flux ratio − 1 (full)",
                   "maps ms (warm)", "equal-error speedup (warm / cold)", "checks passed"):
        table.add_column(column)
    for row in summary_rows(comparisons):
        table.add_row(*(markup(cell) for cell in row))
    # A pipe or a log gets a wide table rather than rich's 80-column default: each
    # metric cell holds its excess, interval and raw value on one line.
    console = Console()
    if not console.is_terminal:
        console = Console(width=250)
    console.print(table)
    for line in check_count_lines(comparisons):
        console.print(markup(line))
    for line in headline_lines(comparisons):
        console.print(markup(line))
    for c in comparisons:
        # A scene that did not validate had its problems printed before the run.
        if isinstance(c, SceneFailure) and c.stage != "validation":
            print(f"error: {plain(c.page)} failed ({c.stage}): {c.error}", file=sys.stderr)


def _load(paths: list[str], overrides: dict) -> list[Scene | UnloadedScene]:
    """Each scene loaded once with its overrides (:func:`harness.api.load_scenes`; its
    warnings printed), or the :class:`~harness.api.UnloadedScene` holding its error
    (its problems are printed now, one line each, before anything renders). Raises
    the SceneError when no scene at all is valid: there is then no run to save."""
    loaded = load_scenes(paths or [str(default_scene_path())], settings=overrides,
                         on_warning=print_warning)
    errors = [entry.error for entry in loaded if isinstance(entry, UnloadedScene)]
    if len(errors) == len(loaded):
        raise SceneError([p for error in errors for p in error.problems])
    for error in errors:
        for problem in error.problems:
            print(f"error: {plain(problem)}", file=sys.stderr)
    return loaded


def compare(args: argparse.Namespace) -> int:
    """``caustics compare``: load, isolate each scene and method, run the comparison
    pipeline (:func:`harness.compare.pipeline.run_comparison`), write.

    Returns 0; 1 when a scene failed (its row and page say why), a checks file is
    missing, or two written copies of one number disagree
    (:mod:`harness.compare.consistency`); 3 when an accuracy check failed (not a known gap) and
    ``--fail-on-checks`` asks for it; 2 for an unknown study, or ``--frames`` without
    the temporal study (:class:`harness.api.OptionError`, before anything renders).
    """
    start = time.perf_counter()
    overrides = dict(parse_override(item) for item in args.set or [])
    for name in ("estimator", "iterations", "grid", "photons"):
        if getattr(args, name) is not None:
            overrides[name] = getattr(args, name)
    scenes = _load(args.scenes, overrides)
    studies = tuple(s for s in args.studies.split(",") if s) if args.studies else None
    names = [*(args.preset or []), *(args.method or [])] or list(DEFAULT_METHODS)
    try:
        # The scenes carry their overrides already: the API does not load them again.
        result = compare_scenes(
            scenes, names, studies=studies, quick=args.quick,
            cache_dir=args.cache_dir, use_cache=not args.no_cache, locks=args.locks,
            golden_dir=args.golden, max_iterations=args.max_iterations,
            frames=getattr(args, "frames", None),
            crosscheck_photons=args.crosscheck_photons if args.crosscheck else None,
            output=args.output, self_contained=args.self_contained,
            progress=not args.quiet, isolate=True)
    except OptionError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    items = result.records
    print_summary(items, Path(args.output), time.perf_counter() - start)
    # One number per question: every copy written of a quantity agrees with its record.
    disagreements = output_disagreements(Path(args.output))
    for line in disagreements:
        print(f"error: inconsistent output: {plain(line)}", file=sys.stderr)
    if not disagreements:
        print("consistency: every number on the pages and in the tables agrees with "
              "metrics.json")
    if result.failures or disagreements:
        return 1
    failed = [c for item in items for c in item.failed_checks]
    return 3 if failed and args.fail_on_checks else 0
