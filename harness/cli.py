"""The ``caustics`` command line. Library code raises typed errors; only this module
turns them into exit codes and one-line messages."""

from __future__ import annotations

import argparse
import importlib
import sys
from importlib import resources
from pathlib import Path

from harness.errors import HarnessError
from harness.scene import SceneError

__all__ = ["COMMAND_MODULES", "default_scene_path", "main"]

#: Modules that each provide ``register(subparsers)``; one line per command group.
COMMAND_MODULES = (
    "harness.scene_commands",
    "renderers.mitsuba.cli",
    "renderers.caustics_mapping.cli",
    "harness.compare_commands",
    "harness.figures_commands",
    "harness.accuracy_commands",
)


def default_scene_path() -> Path:
    """The embedded default scene (a copy of ``scenes/glass_sphere.toml``)."""
    return Path(str(resources.files("harness") / "default_scene.toml"))


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="caustics",
        description="Ground-truth validation harness for real-time caustics "
        "(caustics mapping vs Mitsuba 3).",
    )
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; return the exit status (0 ok, 1 bad input or failure, 130 interrupted)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except SceneError as error:
        for problem in error.problems:
            print(f"error: {problem}", file=sys.stderr)
        return 1
    except HarnessError as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


def run() -> None:
    """Console-script entry point."""
    sys.exit(main())
