"""``caustics render``: render a scene with the method (caustics mapping) and write its
outputs.

Writes into DIR: ``camera.exr`` (linear radiance), ``receiver_irradiance.exr`` (one
receiver) or ``receiver_irradiance_1.exr``, ``_2`` ... (several; W per (u, v) area,
row 0 of the EXR at vmin, as in :class:`renderers.results.ReceiverMap`),
``caustic_map.exr`` (the caustic-map atlas, W/m^2, top row = last texel row),
``hits.npz`` (per grid vertex: origin v, direction r, estimated d per iteration,
status, ...), ``patches.npz`` (the same per rim-patch vertex, with its patch's grid
``quad``; only with rim patches) and ``result.json`` (receiver_extent, passes, lost_splats, timings,
timer, metadata; strict JSON, a non-finite number as null with its reason under
``null_reasons``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from harness.commands.scene import load_scenes
from harness.terminal import plain
from renderers.caustics_mapping.caustic_trace import STATUS
from renderers.caustics_mapping.renderer import Frame, render_frame
from renderers.exr import write_exr
from scenes import parse_override, with_settings
from scenes.files import atomic_write_bytes, dumps_strict

__all__ = ["render", "write_outputs"]


def write_outputs(frame: Frame, directory: str | Path) -> list[Path]:
    """Write a frame's files into ``directory``; returns the paths written."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    result = frame.result
    paths = [out / "camera.exr"]
    write_exr(paths[-1], {"RGB": result.camera})
    many = len(result.receivers) > 1
    for i, receiver in enumerate(result.receivers, start=1):
        paths.append(out / (f"receiver_irradiance_{i}.exr" if many else "receiver_irradiance.exr"))
        write_exr(paths[-1], {"RGB": receiver.irradiance})
    paths.append(out / "caustic_map.exr")
    write_exr(paths[-1], {"RGB": frame.caustic_map[::-1]})
    paths.append(out / "hits.npz")
    with open(paths[-1], "wb") as f:
        np.savez_compressed(f, **frame.hits, status_codes=np.array(list(STATUS)))
    if frame.patches:
        paths.append(out / "patches.npz")
        with open(paths[-1], "wb") as f:
            np.savez_compressed(f, **frame.patches, status_codes=np.array(list(STATUS)))
    else:
        # An earlier render's patches must not pass for this one's.
        (out / "patches.npz").unlink(missing_ok=True)
    summary = {
        "renderer": result.renderer,
        "receiver_extent": [list(r.extent) for r in result.receivers],
        "passes": result.metadata["passes"],
        "lost_splats": result.metadata["lost_splats"],
        "timings": result.timings,
        "timer": result.timer,
        "effects": list(result.effects),
        "total_flux": [r.total_flux().tolist() for r in result.receivers],
        "metadata": result.metadata,
    }
    paths.append(out / "result.json")
    atomic_write_bytes(paths[-1], (dumps_strict(summary) + "\n").encode("utf-8"))
    return paths


def render(args: argparse.Namespace) -> int:
    """``caustics render``: one frame of the method, written to ``args.output``."""
    (scene,) = load_scenes([args.scene] if args.scene else [])
    overrides = dict(parse_override(item) for item in args.set or [])
    overrides |= {k: v for k, v in (
        ("estimator", args.estimator), ("iterations", args.iterations), ("grid", args.grid),
        ("caustic_map", args.caustic_map), ("normalization", args.normalization),
        ("preset", args.preset),
    ) if v is not None}
    if args.safeguarded:
        overrides["safeguarded"] = True
    if overrides:
        scene = with_settings(scene, overrides)
    frame = render_frame(scene)  # a GLError is a HarnessError: the CLI makes it one line
    paths = write_outputs(frame, args.output)
    meta = frame.result.metadata
    print(f"{plain(scene.name)}: passes {', '.join(meta['passes'])}; lost splats "
          f"{meta['lost_splats']}; total {sum(frame.result.timings.values()) * 1e3:.1f} ms "
          f"({frame.result.timer})")
    for path in paths:
        print(f"  wrote {plain(path)}")
    return 0
