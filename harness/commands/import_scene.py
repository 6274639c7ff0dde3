"""``caustics import FILE -o SCENE.toml``: a glTF 2.0 (``.gltf``, ``.glb``) or Mitsuba 3
(``.xml``) scene as a scene file, its meshes as PLY files beside it
(``<stem>_meshes/``); ``docs/bring-your-scene.md``."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from harness.terminal import plain
from scenes.importers import ImportProblemError, read_gltf, write_draft

__all__ = ["import_scene"]


def import_scene(args: argparse.Namespace) -> int:
    """Read ``args.file``, write ``args.output``; one line per problem on refusal."""
    source = Path(args.file)
    output = Path(args.output)
    if output.suffix != ".toml":
        print(f"error: {plain(output)}: the scene file to write ends in .toml",
              file=sys.stderr)
        return 2
    if not source.is_file():
        print(f"error: {plain(source)}: no such file", file=sys.stderr)
        return 1
    try:
        if source.suffix.lower() in (".gltf", ".glb"):
            draft = read_gltf(source, approximate=args.approximate, camera=args.camera)
        elif source.suffix.lower() == ".xml":
            from renderers.mitsuba.importer import read_mitsuba  # noqa: PLC0415 (Mitsuba)

            draft = read_mitsuba(source, approximate=args.approximate, camera=args.camera)
        else:
            print(f"error: {plain(source)}: not .gltf, .glb or .xml", file=sys.stderr)
            return 2
        output.parent.mkdir(parents=True, exist_ok=True)
        scene = write_draft(draft, output)
    except ImportProblemError as error:
        for line in error.problems:
            print(f"error: {plain(line)}", file=sys.stderr)
        return 1
    print(f"{plain(scene.name)}: wrote {plain(output)} ({len(scene.receivers)} receiver(s), "
          f"{len(scene.objects)} object(s), {type(scene.light).kind} light)", file=sys.stderr)
    for line in draft.approximations:
        print(f"approximated: {plain(line)}", file=sys.stderr)
    return 0
