"""``caustics crosscheck SCENE --with luxcore -o DIR``: the reference's receiver caustic
against an independent renderer, with full transport on both sides."""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

from harness.commands.scene import load_scenes
from harness.compare.outputs import write_json
from harness.crosscheck import TOLERANCES, CrossCheck, compare_maps, full_transport
from harness.terminal import plain
from renderers.luxcore import check_supported, luxcore_version, render_receiver_caustic
from renderers.mitsuba._mi import versions
from renderers.mitsuba.reference import estimate_receivers
from reports import scene_folder

__all__ = ["crosscheck", "run_crosscheck"]


def run_crosscheck(scene, *, photons: int, seeds: int, other_photons: int) -> CrossCheck:
    """Render ``scene`` (full transport) with Mitsuba's photon tracer and LuxCore, and
    compare receiver 0. LuxCore's units are checked on the bare receiver first.

    Parameters
    ----------
    photons
        Mitsuba photons per seed (aimed at the caustic objects).
    seeds
        Independent seeds K on each side (variance of the mean).
    other_photons
        LuxCore light paths per film (two films, glass and black, per seed).
    """
    full = full_transport(scene)
    check_supported(full)  # one line per field LuxCore cannot render faithfully
    start = time.perf_counter()
    estimate = estimate_receivers(full, photons=photons, seeds=seeds, caustic_only=True,
                                  target_noise=1e-12)
    reference_seconds = time.perf_counter() - start
    start = time.perf_counter()
    other = render_receiver_caustic(full, photons=other_photons, seeds=seeds)
    other_seconds = time.perf_counter() - start
    ratios = compare_maps(estimate.caustic[0], other[0])
    provenance = {
        "transport": "full: all L S+ D paths, exact Fresnel on every dielectric",
        "reference": {"renderer": "mitsuba photon tracer", **versions(),
                      "photons_per_seed": estimate.photons, "seeds": seeds,
                      "cut_flux_fraction": estimate.cut_fraction,
                      "seconds": reference_seconds},
        "other": {"renderer": "luxcore LIGHTCPU (one thread)",
                  "pyluxcore": luxcore_version(), "photons_per_film": other_photons,
                  "seeds": seeds, "seconds": other_seconds},
        "tolerances": TOLERANCES,
    }
    return CrossCheck(scene.name, "luxcore", ratios, provenance)


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
