"""``caustics score SCENE --camera FILE.exr [--receiver N=FILE.exr ...] -o DIR``: images
rendered anywhere, scored by the comparison pipeline (``docs/scoring-external-renders.md``).

Every file is checked before any reference is rendered or anything is written: a bad
one is one ``error:`` line naming it (exit 1). The timing report is ``--timing
FILE.json``, else a ``render.json`` beside the first image when there is one.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from harness.api import score as score_images
from harness.commands.compare import print_summary
from harness.commands.scene import print_warning
from harness.compare.consistency import disagreements as output_disagreements
from harness.compare.external import NOT_MEASURED, ExternalRenderError
from harness.terminal import markup, plain
from scenes import default_scene_path, parse_override

__all__ = ["TIMING_FILE", "score"]

#: The timing report looked for beside the images when ``--timing`` is not given.
TIMING_FILE = "render.json"


def _timing_file(args: argparse.Namespace) -> Path | None:
    """``--timing``, else ``render.json`` beside the first image given, if it exists."""
    if args.timing is not None:
        return Path(args.timing)
    first = args.camera or next((p for _, p in args.receiver or ()), None)
    beside = Path(first).parent / TIMING_FILE if first is not None else None
    return beside if beside is not None and beside.is_file() else None


def score(args: argparse.Namespace) -> int:
    """``caustics score``: check the files, run the pipeline, write, summarise.

    Returns 0; 1 for a bad file or a failed comparison (through :mod:`harness.cli`),
    or when two written copies of one number disagree
    (:mod:`harness.compare.consistency`).
    """
    start = time.perf_counter()
    receivers: dict[int, Path] = {}
    for index, path in args.receiver or ():
        if index in receivers:
            raise ExternalRenderError(f"receiver {index}: given twice ({receivers[index]}, "
                                      f"{path})")
        receivers[index] = Path(path)
    overrides = dict(parse_override(item) for item in args.set or [])
    timing = _timing_file(args)
    comparison = score_images(
        args.scene or str(default_scene_path()), camera=args.camera, receivers=receivers,
        timing=timing, settings=overrides, cache_dir=args.cache_dir,
        use_cache=not args.no_cache, output=args.output, progress=not args.quiet,
        on_warning=print_warning)
    print_summary([comparison.record], Path(args.output), time.perf_counter() - start)
    reported = comparison.record.provenance.method.metadata.get("reported_timing")
    if reported:
        print(markup(f"time ({NOT_MEASURED}, from {timing}): "
                     + ", ".join(f"{k} {v}" for k, v in reported.items() if k != "label")))
    disagreements = output_disagreements(Path(args.output))
    for line in disagreements:
        print(f"error: inconsistent output: {plain(line)}", file=sys.stderr)
    return 1 if disagreements else 0
