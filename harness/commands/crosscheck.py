"""``caustics crosscheck SCENE --with luxcore -o DIR``: the reference's receiver caustic
against an independent renderer, with full transport on both sides."""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from harness.commands.scene import load_scenes
from harness.compare.outputs import write_json
from harness.crosscheck import TOLERANCES, CrossCheck, run_crosscheck
from harness.terminal import plain
from reports import scene_folder

__all__ = ["crosscheck"]


def _print(check: CrossCheck) -> None:
    total = check.of_kind("total")[0]
    print(f"{plain(check.scene)}: caustic flux reference / luxcore = {total.ratio:.4f} "
          f"± {total.sigma:.4f} ({'agrees' if total.agrees else 'DISAGREES'}, "
          f"tolerance {TOLERANCES['total']:.1%})")
    for kind in ("encircled", "region"):
        rows = check.of_kind(kind)
        worst = max(rows, key=lambda r: abs(r.ratio - 1.0), default=None)
        if worst is not None:
            misses = sum(not r.agrees for r in rows)
            print(f"  {kind}: {len(rows)} compared, {misses} outside ±{TOLERANCES[kind]:.0%}; "
                  f"worst {plain(worst.label)} ({worst.share:.1%} of the flux): "
                  f"{worst.ratio:.4f} ± {worst.sigma:.4f} (z = {worst.z:+.1f})")


def crosscheck(args: argparse.Namespace) -> int:
    """``caustics crosscheck``: writes ``DIR/<scene>/crosscheck.json``; exit 3 with
    ``--fail-on-disagreement`` when a comparison misses its tolerance."""
    failed = False
    for scene in load_scenes(args.scenes):
        check = run_crosscheck(scene, photons=args.photons, seeds=args.seeds,
                               other_photons=args.other_photons)
        document = {"scene": check.scene, "with": check.renderer, "agrees": check.agrees,
                    "ratios": [{**dataclasses.asdict(r), "z": r.z} for r in check.ratios],
                    "provenance": check.provenance}
        # scene_folder: a scene name is untrusted text, never a path (no "/", no "..").
        write_json(Path(args.output) / scene_folder(scene.name) / "crosscheck.json", document)
        _print(check)
        failed |= not check.agrees
    return 3 if failed and args.fail_on_disagreement else 0
