"""``caustics golden`` and ``caustics calibrate``: golden references and the bounds."""

from __future__ import annotations

import argparse
from pathlib import Path

from harness.checks import GOLDEN_DIR, THRESHOLDS_FILE
from harness.checks.accuracy import calibrate as calibrate_bounds
from harness.checks.accuracy import write_thresholds
from harness.checks.golden import GOLDEN_SCENES, load_golden, read_manifest, regenerate
from harness.terminal import plain
from scenes import SCENES_DIR

__all__ = ["calibrate", "golden"]


def golden(args: argparse.Namespace) -> int:
    """``caustics golden``: verify (or regenerate) the golden references."""
    golden_dir = Path(args.dir) if args.dir else GOLDEN_DIR
    if args.regenerate:
        regenerate(golden_dir, SCENES_DIR, names=GOLDEN_SCENES)
    manifest = read_manifest(golden_dir)
    for name in manifest["scenes"]:
        golden = load_golden(golden_dir, name)  # checks every SHA-256
        print(f"ok  {plain(name)}: {len(golden.receivers)} receiver map(s), "
              f"{golden.entry['photons']} photons x {golden.entry['seeds']} seeds, "
              f"relative noise {golden.entry['relative_noise']:.4f}")
    return 0


def calibrate(args: argparse.Namespace) -> int:
    """``caustics calibrate``: regression bounds from the measured spread."""
    golden_dir = Path(args.golden) if args.golden else GOLDEN_DIR
    output = Path(args.output) if args.output else THRESHOLDS_FILE
    names = list(read_manifest(golden_dir)["scenes"])
    bounds = calibrate_bounds(SCENES_DIR, golden_dir, names, extra=args.extra)
    write_thresholds(output, bounds)
    print(f"wrote {len(bounds)} bounds for {len(names)} scenes to {plain(output)}")
    return 0
