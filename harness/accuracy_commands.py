"""``caustics golden`` and ``caustics calibrate``: golden references and the bounds."""

from __future__ import annotations

import argparse
from pathlib import Path

__all__ = ["register"]

DEFAULT_GOLDEN = Path("tests") / "golden"
DEFAULT_THRESHOLDS = Path("tests") / "thresholds.toml"


def _golden(args: argparse.Namespace) -> int:
    from harness.figures.common import default_scenes_dir  # noqa: PLC0415
    from harness.golden import GOLDEN_SCENES, load_golden, read_manifest, regenerate  # noqa: PLC0415

    golden_dir = Path(args.dir)
    if args.regenerate:
        regenerate(golden_dir, default_scenes_dir(), names=GOLDEN_SCENES)
    manifest = read_manifest(golden_dir)
    for name in manifest["scenes"]:
        golden = load_golden(golden_dir, name)  # checks every SHA-256
        print(f"ok  {name}: {len(golden.receivers)} receiver map(s), "
              f"{golden.entry['photons']} photons x {golden.entry['seeds']} seeds, "
              f"relative noise {golden.entry['relative_noise']:.4f}")
    return 0


def _calibrate(args: argparse.Namespace) -> int:
    from harness.accuracy import calibrate, write_thresholds  # noqa: PLC0415
    from harness.figures.common import default_scenes_dir  # noqa: PLC0415
    from harness.golden import read_manifest  # noqa: PLC0415

    names = list(read_manifest(Path(args.golden))["scenes"])
    bounds = calibrate(default_scenes_dir(), Path(args.golden), names, extra=args.extra)
    write_thresholds(Path(args.output), bounds)
    print(f"wrote {len(bounds)} bounds for {len(names)} scenes to {args.output}")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("golden", help="check (or --regenerate) the golden references")
    p.add_argument("--dir", default=str(DEFAULT_GOLDEN), help="golden folder")
    p.add_argument("--regenerate", action="store_true",
                   help="re-render into a staging folder and swap it in atomically")
    p.set_defaults(func=_golden)

    p = subparsers.add_parser("calibrate", help="set accuracy bounds from measured spread")
    p.add_argument("--golden", default=str(DEFAULT_GOLDEN), help="golden folder")
    p.add_argument("--extra", type=int, default=3,
                   help="independent references beyond the golden one (default 3)")
    p.add_argument("-o", "--output", default=str(DEFAULT_THRESHOLDS), help="thresholds file")
    p.set_defaults(func=_calibrate)
