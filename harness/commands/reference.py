"""``caustics reference SCENE -o DIR``: render (or fetch from the cache) the Mitsuba
reference and write ``camera.exr``, ``receiver_irradiance*.exr`` and ``result.json``.

``--camera`` picks the camera image's integrator: ``trace`` (default, the camera
tracer: glass and water are seen through) or ``ptracer``."""

from __future__ import annotations

import argparse
import dataclasses
import sys

import numpy as np

from harness.commands.scene import load_scenes
from harness.terminal import plain
from harness.writable import usable_cache
from renderers.mitsuba.cache import cache_dir, write_result_dir
from renderers.mitsuba.reference import render_reference
from renderers.results import RenderResult
from scenes import with_settings
from scenes.files import NULL_REASONS, strict_json

__all__ = ["reference", "strict_result"]


def strict_result(result: RenderResult) -> RenderResult:
    """``result`` with every non-finite float of its metadata and timings as None and
    the reasons under ``metadata["null_reasons"]`` (pointers into ``result.json``, whose
    top level holds the metadata and ``timings``), so the file is strict JSON.
    Arrays stay in the metadata: they go to the EXRs, not the JSON."""
    arrays = {k: v for k, v in result.metadata.items() if isinstance(v, np.ndarray)}
    rest = {k: v for k, v in result.metadata.items() if k not in arrays}
    clean, reasons = strict_json({**rest, "timings": result.timings})
    timings = clean.pop("timings")
    if reasons:
        clean[NULL_REASONS] = reasons
    return dataclasses.replace(result, metadata={**clean, **arrays}, timings=timings)


def _number(value, spec: str) -> str:
    return "n/a" if value is None else format(value, spec)


def reference(args: argparse.Namespace) -> int:
    """``caustics reference``: the cached Mitsuba reference, written to ``args.output``."""
    (scene,) = load_scenes([args.scene] if args.scene else [])
    overrides = {name: getattr(args, name) for name in ("photons", "spp", "seed", "seeds")
                 if getattr(args, name) is not None}
    if args.target_noise is not None:
        overrides["target_noise"] = args.target_noise
    if overrides:
        scene = with_settings(scene, overrides)
    # An unwritable cache must not cost the render: render without it (one warning).
    use_cache = not args.no_cache and usable_cache(cache_dir(args.cache_dir))
    result = render_reference(scene, cache=args.cache_dir, use_cache=use_cache,
                              progress=not args.quiet, camera=args.camera)
    # The cache module writes result.json with json.dumps; hand it only finite numbers.
    document = write_result_dir(args.output, strict_result(result))
    if not args.quiet:
        print(f"{plain(scene.name)}: {document['photons']} photons x {document['seeds']} "
              f"seeds, relative noise {_number(document['relative_noise'], '.4f')} "
              f"({document['stopped_by']}), camera {document.get('camera_integrator')}, "
              f"cache {result.metadata.get('cache')}, "
              f"wrote {plain(args.output)}", file=sys.stderr)
    return 0
