"""Scene commands: ``validate``, ``describe`` and ``schema``.

Imports nothing heavy: ``validate`` must run where Mitsuba, Dr.Jit and moderngl
cannot even be imported.
"""

from __future__ import annotations

import argparse
import json
import sys

from scenes import EFFECTS, SceneError, default_scene_path, effects_of, load_scene, resolve_scene
from scenes.geometry import build_geometry
from scenes.model import Scene
from scenes.schema import describe_schema

__all__ = ["describe", "load_scenes", "schema", "validate"]


def load_scenes(paths: list[str]) -> list[Scene]:
    """Load and fully validate scenes (meshes and height files too).

    Each entry is a file path or a bundled scene name (:func:`scenes.resolve_scene`);
    with none, the bundled default scene. Raises one :class:`SceneError` holding the
    problems of every file.
    """
    scenes, problems = [], []
    for path in paths or [str(default_scene_path())]:
        try:
            scene = load_scene(resolve_scene(path))
            build_geometry(scene)
            scenes.append(scene)
        except SceneError as error:
            problems += error.problems
    if problems:
        raise SceneError(problems)
    return scenes


def validate(args: argparse.Namespace) -> int:
    scenes, problems = [], []
    for path in args.scenes or [str(default_scene_path())]:
        try:
            scenes.extend(load_scenes([path]))
        except SceneError as error:
            problems += error.problems
    if args.json:
        report = {
            "scenes": [
                {"name": s.name, "path": s.source, "effects": list(effects_of(s))}
                for s in scenes
            ],
            "errors": [
                {"file": p.file, "path": p.path, "message": p.message} for p in problems
            ],
        }
        print(json.dumps(report, indent=2))
    else:
        for scene in scenes:
            print(f"ok  {scene.source}  [{scene.name}]  effects: {', '.join(effects_of(scene))}")
    for problem in problems:
        print(f"error: {problem}", file=sys.stderr)
    return 1 if problems else 0


def describe(args: argparse.Namespace) -> int:
    for scene in load_scenes(args.scenes):
        geometry = build_geometry(scene)
        print(f"scene {scene.name}  ({scene.source})")
        print(f"  {scene.info.description}")
        print(f"  light: {type(scene.light).kind}")
        for i, (rec, geo) in enumerate(zip(scene.receivers, geometry.receivers, strict=True)):
            umin, umax, vmin, vmax = geo.extent
            print(f"  receivers[{i}]: {rec.kind}, {len(geo.mesh.positions)} vertices, "
                  f"{len(geo.mesh.faces)} triangles, (u, v) in "
                  f"[{umin:g}, {umax:g}] x [{vmin:g}, {vmax:g}]")
        for i, (obj, geo) in enumerate(zip(scene.objects, geometry.objects, strict=True)):
            lo, hi = geo.mesh.bounds
            print(f"  objects[{i}]: {obj.kind} ({obj.material.kind}), "
                  f"{len(geo.mesh.positions)} vertices, {len(geo.mesh.faces)} triangles, "
                  f"bounds {lo.round(3).tolist()} .. {hi.round(3).tolist()} m")
        print("  effects:")
        for name in effects_of(scene):
            print(f"    {name}: {EFFECTS[name]}")
        s = scene.settings

        def chosen(value):
            return "(preset's)" if value is None else value

        print(f"  settings: preset {s.preset}, grid {s.grid}, caustic map {s.caustic_map}, "
              f"estimator {chosen(s.estimator)}, safeguarded {chosen(s.safeguarded)}, "
              f"iterations {chosen(s.iterations)}, splat {chosen(s.splat)}, "
              f"normalization {s.normalization}")
    return 0


def schema(args: argparse.Namespace) -> int:
    print("\n".join(describe_schema(Scene, title="Scene file")))
    return 0
