"""``caustics reference SCENE -o DIR``: render (or fetch from the cache) the Mitsuba
reference and write ``camera.exr``, ``receiver_irradiance*.exr`` and ``result.json``."""

from __future__ import annotations

import argparse
import sys

from harness.commands.scene import load_scenes
from renderers.mitsuba.cache import write_result_dir
from renderers.mitsuba.reference import render_reference
from scenes import with_settings

__all__ = ["reference"]


def reference(args: argparse.Namespace) -> int:
    """``caustics reference``: the cached Mitsuba reference, written to ``args.output``."""
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
