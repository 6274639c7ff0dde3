"""``caustics export SCENE --format gltf|mitsuba -o DIR``: the scene for a renderer
outside the process.

* ``gltf``: ``DIR/<scene name>.glb`` (or, with ``--gltf-container gltf``,
  ``<scene name>.gltf`` and its ``.bin``), :func:`scenes.export.export_gltf`; analytic
  shapes within ``--tolerance`` metres of their surface.
* ``mitsuba``: ``DIR/scene.xml`` (a dispersion scene: ``scene_r.xml``, ``scene_g.xml``,
  ``scene_b.xml``) and ``DIR/meshes/*.ply``, :func:`renderers.mitsuba.scene_xml.write_scene_xml`:
  the reference's own Mitsuba scene, the same triangles; dielectrics as Mitsuba's stock
  ``dielectric`` (``--mitsuba-bsdf stock``, each difference from the reference printed
  as a ``note:`` line) or the reference's ``chain_dielectric`` plugin (``harness``).

The mapping, units, axes and receiver frames are ``docs/export.md``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from harness.commands.scene import load_scenes
from harness.terminal import plain

__all__ = ["export"]


def _millimetres(metres: float | None) -> str:
    return "n/a" if metres is None else f"{metres * 1e3:.3g} mm"


def export(args: argparse.Namespace) -> int:
    """``caustics export``: write the scene in ``args.format`` into ``args.output``."""
    (scene,) = load_scenes([args.scene] if args.scene else [])
    folder = Path(args.output)
    folder.mkdir(parents=True, exist_ok=True)
    if args.format == "mitsuba":
        if args.tolerance is not None:
            print("error: --tolerance applies to --format gltf: the Mitsuba XML holds the "
                  "triangles the reference renders", file=sys.stderr)
            return 2
        from renderers.mitsuba.scene_xml import (  # noqa: PLC0415 (Mitsuba)
            stock_differences,
            write_scene_xml,
        )

        written = write_scene_xml(scene, folder, bsdf=args.mitsuba_bsdf)
        if args.mitsuba_bsdf == "stock":
            for line in stock_differences(scene):
                print(f"note: {plain(scene.name)}: {plain(line)}", file=sys.stderr)
        print(f"{plain(scene.name)}: wrote {', '.join(plain(p) for p in written)} and "
              f"{plain(folder / 'meshes')}/", file=sys.stderr)
        return 0
    if args.mitsuba_bsdf != "stock":
        print("error: --mitsuba-bsdf applies to --format mitsuba", file=sys.stderr)
        return 2
    from scenes.export import export_gltf  # noqa: PLC0415 - pygltflib, only here

    done = export_gltf(scene, folder / f"{scene.name}.{args.gltf_container}",
                       tolerance=args.tolerance)
    shapes = "; ".join(
        f"{t.field} {t.kind}, " + ", ".join(f"{k} {v}" for k, v in t.level.items())
        + f", {_millimetres(t.chord_error)}"
        for t in (*done.receivers, *done.objects) if t.chord_error)
    print(f"{plain(scene.name)}: wrote {plain(done.path)} (chord tolerance "
          f"{_millimetres(done.tolerance)}{'; ' + shapes if shapes else ''})", file=sys.stderr)
    return 0
