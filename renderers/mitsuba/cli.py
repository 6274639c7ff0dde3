"""``caustics reference SCENE -o DIR``: render (or fetch from the cache) the Mitsuba
reference and write ``camera.exr``, ``receiver_irradiance*.exr`` and ``result.json``."""

from __future__ import annotations

import argparse
import sys

__all__ = ["register"]


def _reference(args: argparse.Namespace) -> int:
    from harness.scene import with_settings  # noqa: PLC0415
    from harness.scene_commands import load_scenes  # noqa: PLC0415
    from renderers.mitsuba.cache import write_result_dir  # noqa: PLC0415
    from renderers.mitsuba.reference import render_reference  # noqa: PLC0415

    (scene,) = load_scenes([args.scene] if args.scene else [])
    overrides = {name: getattr(args, name) for name in ("photons", "spp", "seed", "seeds")
                 if getattr(args, name) is not None}
    if args.target_noise is not None:
        overrides["target_noise"] = args.target_noise
    if overrides:
        scene = with_settings(scene, overrides)
    result = render_reference(scene, cache=args.cache_dir, use_cache=not args.no_cache,
                              progress=not args.quiet)
    document = write_result_dir(args.output, result)
    if not args.quiet:
        print(f"{scene.name}: {document['photons']} photons x {document['seeds']} seeds, "
              f"relative noise {document['relative_noise']:.4f} ({document['stopped_by']}), "
              f"cache {result.metadata.get('cache')}, wrote {args.output}", file=sys.stderr)
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "reference", help="render the Mitsuba ground truth (cached) into a directory"
    )
    p.add_argument("scene", nargs="?", metavar="SCENE", help="scene file (default: embedded)")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output directory")
    p.add_argument("--photons", type=int, help="photon budget per seed")
    p.add_argument("--spp", type=int, help="ptracer samples per pixel per seed")
    p.add_argument("--seed", type=int, help="first random seed")
    p.add_argument("--seeds", type=int, help="number of independent seeds K")
    p.add_argument("--target-noise", type=float, help="stop at this relative noise")
    p.add_argument("--cache-dir", help="cache root (default $CAUSTICS_CACHE_DIR or "
                   "~/.cache/caustics-harness/reference)")
    p.add_argument("--no-cache", action="store_true", help="render without the cache")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bars")
    p.set_defaults(func=_reference)
