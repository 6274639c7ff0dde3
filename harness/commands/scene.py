"""Scene commands: ``validate``, ``describe`` and ``schema``.

Imports nothing heavy: ``validate --no-trace``, ``describe`` and ``schema`` run where
Mitsuba, Dr.Jit and moderngl cannot even be imported. Plain ``validate`` also traces
a small photon probe with the reference tracer (:mod:`harness.compare.probe`,
Mitsuba imported only then) so that it finds the scenes whose caustic misses every
receiver, which ``compare`` fails on.
"""

from __future__ import annotations

import argparse
import json
import sys

from harness import loading
from harness.loading import check_scenes
from harness.terminal import plain
from scenes import (
    EFFECTS,
    Problem,
    effects_of,
)
from scenes.geometry import build_geometry
from scenes.model import Scene
from scenes.schema import describe_schema

__all__ = ["describe", "load_scenes", "print_warning", "schema", "validate"]


def print_warning(warning: Problem) -> None:
    """Print a scene warning as one ``warning: ...`` line on stderr."""
    print(plain(f"warning: {warning}"), file=sys.stderr)


def load_scenes(paths: list[str]) -> list[Scene]:
    """:func:`harness.loading.load_scenes`, each warning printed on stderr (every
    command loads its scenes here)."""
    return loading.load_scenes(paths, on_warning=print_warning)


def _problem_dicts(problems: list[Problem]) -> list[dict[str, str]]:
    return [{"file": p.file, "path": p.path, "message": p.message} for p in problems]


def _probe(scenes: list[Scene]) -> tuple[list[Scene], list[Problem], dict[str, float]]:
    """Run the caustic probe on each scene: ``(scenes with a caustic, errors,
    caustic flux (W) by scene source)``."""
    from harness.compare.probe import no_caustic_problem, probe_caustic  # noqa: PLC0415 (Mitsuba)

    kept, problems, flux = [], [], {}
    for scene in scenes:
        probe = probe_caustic(scene)
        flux[scene.source] = probe.caustic_flux_w
        problem = no_caustic_problem(scene, probe)
        if problem:
            problems.append(problem)
        else:
            kept.append(scene)
    return kept, problems, flux


def validate(args: argparse.Namespace) -> int:
    scenes, problems, warnings = check_scenes(args.scenes)
    flux: dict[str, float] = {}
    if args.trace and scenes:
        scenes, probe_problems, flux = _probe(scenes)
        problems += probe_problems
    if args.json:
        report = {
            "scenes": [
                {"name": s.name, "path": s.source, "effects": list(effects_of(s)),
                 "probe_caustic_flux_w": flux.get(s.source)}
                for s in scenes
            ],
            "errors": _problem_dicts(problems),
            "warnings": _problem_dicts(warnings),
        }
        print(json.dumps(report, indent=2))
    else:
        for scene in scenes:
            probed = (f"  caustic {flux[scene.source]:.3g} W (probe)"
                      if scene.source in flux else "")
            print(plain(f"ok  {scene.source}  [{scene.name}]  effects: "
                        f"{', '.join(effects_of(scene))}{probed}"))
    for warning in warnings:
        print(plain(f"warning: {warning}"), file=sys.stderr)
    for problem in problems:
        print(plain(f"error: {problem}"), file=sys.stderr)
    return 1 if problems else 0


def describe(args: argparse.Namespace) -> int:
    for scene in load_scenes(args.scenes):
        geometry = build_geometry(scene)
        print(plain(f"scene {scene.name}  ({scene.source})"))
        print(plain(f"  {scene.info.description}"))
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
        if scene.animation is not None:
            a = scene.animation
            moving = (["light"] if any(a.light.velocity) or any(a.light.angular_velocity)
                      else []) + [f"objects[{m.index}]" for m in a.objects]
            moves = ", ".join(moving) or "nothing but the water surfaces' time"
            print(f"  animation: {a.frames} frames at {a.fps:g} fps from τ = {a.start:g} s; "
                  f"moves: {moves}")
    return 0


def schema(args: argparse.Namespace) -> int:
    print("\n".join(describe_schema(Scene, title="Scene file")))
    return 0
