"""``caustics golden`` and ``caustics calibrate``: golden references and the regression
locks calibrated against them."""

from __future__ import annotations

import argparse
from pathlib import Path

from harness.checks import GOLDEN_DIR, LOCKS_FILE
from harness.checks.golden import GOLDEN_SCENES, load_golden, read_manifest, regenerate
from harness.checks.locks import calibrate as calibrate_locks
from harness.checks.locks import write_locks
from harness.terminal import plain
from scenes import SCENES_DIR

__all__ = ["calibrate", "golden"]


def golden(args: argparse.Namespace) -> int:
    """``caustics golden``: verify (or regenerate) the golden references."""
    golden_dir = Path(args.dir) if args.dir else GOLDEN_DIR
    if args.regenerate:
        regenerate(golden_dir, SCENES_DIR, names=GOLDEN_SCENES)
    manifest = read_manifest(golden_dir)  # missing or unreadable: GoldenError naming it
    for name in manifest["scenes"]:
        golden = load_golden(golden_dir, name)  # checks every SHA-256
        print(f"ok  {plain(name)}: {len(golden.receivers)} receiver map(s) "
              f"{golden.entry['resolution'][0]}x{golden.entry['resolution'][1]}, "
              f"{golden.entry['photons']} photons x {golden.entry['seeds']} seeds, "
              f"relative noise {golden.entry['relative_noise']:.4f}")
    return 0


def calibrate(args: argparse.Namespace) -> int:
    """``caustics calibrate``: regression locks from the measured spread (reference
    seeds and light jitter); they guard against change, not accuracy."""
    golden_dir = Path(args.golden) if args.golden else GOLDEN_DIR
    output = Path(args.output) if args.output else LOCKS_FILE
    names = list(read_manifest(golden_dir)["scenes"])
    locks = calibrate_locks(SCENES_DIR, golden_dir, names, extra=args.extra)
    write_locks(output, locks)
    print(f"wrote {len(locks)} regression locks for {len(names)} scenes to {plain(output)}")
    return 0
