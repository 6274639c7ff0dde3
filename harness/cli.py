"""The ``caustics`` command line: every subcommand's arguments, and the dispatch.

Library code raises typed errors; only this module turns them into exit codes and
one-line messages. It imports nothing heavy: each subcommand names its handler as
``"module:function"`` and the module is imported only when that subcommand runs, so
``caustics --help``, ``setup``, ``schema``, ``describe`` and ``validate --no-trace``
never load Mitsuba, Dr.Jit, moderngl, matplotlib or playwright (plain ``validate``
loads Mitsuba for its caustic probe, a small photon trace). Only ``setup`` installs
system packages.

Exit codes (:data:`EXIT_CODES`): 0 done; 1 bad input or a failure the harness
detected (a scene error, an unwritable ``-o``, a refused file, a scene whose
comparison failed); 2 usage (argparse, an unknown study or figure); 3 a bound or
cross-check missed with ``--fail-on-checks`` / ``--fail-on-disagreement``;
70 internal error (a bug: any other exception; ``--debug`` or ``CAUSTICS_DEBUG=1``
prints its traceback); 130 interrupted. Every error is one ``error: ...`` line on
stderr, never a traceback unless asked for.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
import traceback
import warnings

from harness.terminal import error_line, plain, warn
from harness.writable import check_output_dir
from scenes import SceneError
from scenes.errors import HarnessError

__all__ = ["EXIT_CODES", "build_parser", "main"]

#: Exit status of each outcome (the README's table).
EXIT_CODES = {"ok": 0, "failure": 1, "usage": 2, "threshold": 3, "internal": 70,
              "interrupted": 130}
_DEBUG_HINT = "rerun with --debug (or CAUSTICS_DEBUG=1) for the traceback"

_SCENES_HELP = "scene files or bundled scene names (default: glass_sphere)"
_ESTIMATOR_HELP = ("intersection estimator (default: the preset's: paper modified, "
                   "strong secant)")
_ITERATIONS_HELP = "estimator iterations (default: the preset's: paper 3, strong 5)"
_GRID_HELP = "refractive vertex grid resolution, G x G (default: the scene's, 128)"


def _common() -> argparse.ArgumentParser:
    """Options every subcommand takes (also accepted before the subcommand)."""
    parser = argparse.ArgumentParser(add_help=False)
    # SUPPRESS: a subcommand's default must not overwrite `caustics --debug CMD`.
    parser.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                        help="print the traceback of an internal error")
    return parser


def _command(subparsers, name: str, handler: str, help_text: str, *,
             output_dir: bool = False) -> argparse.ArgumentParser:
    """A subcommand; ``output_dir``: its ``-o`` is a folder checked before the handler."""
    parser = subparsers.add_parser(name, help=help_text, parents=[_common()])
    parser.set_defaults(handler=handler, output_dir=output_dir)
    return parser


def _setup_command(subparsers) -> None:
    p = _command(subparsers, "setup", "harness.commands.setup:setup",
                 "find, and as root install, the system packages the harness needs "
                 "(Debian's libllvm19 for Mitsuba's CPU variant, chromium for the "
                 "report's browser test); nothing else ever installs them")
    p.add_argument("--check", action="store_true",
                   help="only look for them and say what is missing; install nothing")


def _scene_commands(subparsers) -> None:
    p = _command(subparsers, "validate", "harness.commands.scene:validate",
                 "check scene files and print the effects each calls for")
    p.add_argument("scenes", nargs="*", metavar="SCENE", help=_SCENES_HELP)
    p.add_argument("--json", action="store_true", help="print a JSON report")
    p.add_argument("--no-trace", dest="trace", action="store_false",
                   help="skip the caustic probe (a small photon trace with the reference "
                        "tracer that finds scenes whose caustic misses every receiver); "
                        "validate then loads no renderer")
    p = _command(subparsers, "describe", "harness.commands.scene:describe",
                 "summarise scenes: geometry, effects, settings")
    p.add_argument("scenes", nargs="*", metavar="SCENE", help=_SCENES_HELP)
    _command(subparsers, "schema", "harness.commands.scene:schema",
             "print the scene-file field reference (Markdown)")


def _render_commands(subparsers) -> None:
    p = _command(subparsers, "render", "harness.commands.render:render",
                 "render a scene with caustics mapping (OpenGL): the method", output_dir=True)
    p.add_argument("scene", nargs="?", metavar="SCENE", help=_SCENES_HELP)
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output directory")
    p.add_argument("--estimator", choices=("modified", "newton", "secant"), help=_ESTIMATOR_HELP)
    p.add_argument("--safeguarded", action="store_true", help="safeguarded estimator")
    p.add_argument("--iterations", type=int, metavar="N", help=_ITERATIONS_HELP)
    p.add_argument("--grid", type=int, metavar="G", help=_GRID_HELP)
    p.add_argument("--caustic-map", type=int, metavar="M", dest="caustic_map",
                   help="caustic-map resolution per face, in texels (default: the scene's, 512)")
    p.add_argument("--normalization", choices=("radiometric", "paper"),
                   help="flux per grid texel: physical (radiometric, the default) or the "
                   "paper's Eq. 6")
    p.add_argument("--preset", choices=("paper", "strong"),
                   help="caustics-mapping preset (default: the scene's, else paper)")
    p.add_argument("--set", action="append", metavar="NAME=VALUE",
                   help="override any setting (repeatable)")

    p = _command(subparsers, "reference", "harness.commands.reference:reference",
                 "render the Mitsuba ground truth (cached) into a directory", output_dir=True)
    p.add_argument("scene", nargs="?", metavar="SCENE", help=_SCENES_HELP)
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output directory")
    p.add_argument("--photons", type=int, help="photon budget per seed")
    p.add_argument("--spp", type=int, help="camera samples per pixel per seed")
    p.add_argument("--seed", type=int, help="first random seed")
    p.add_argument("--seeds", type=int, help="number of independent seeds K")
    p.add_argument("--target-noise", type=float, help="stop at this relative noise")
    p.add_argument("--camera", choices=("trace", "ptracer"), default="trace",
                   help="camera image: the camera tracer, which sees through glass and "
                   "water (default), or Mitsuba's ptracer, which renders specular surfaces "
                   "and all seen through them black")
    _cache_options(p)


_CACHE_ROOT = "$CAUSTICS_CACHE_DIR or ~/.cache/caustics-harness/reference"


def _cache_options(p: argparse.ArgumentParser, *,
                   cache: str = f"reference cache root (default {_CACHE_ROOT})",
                   no_cache: str = "render references without the cache") -> None:
    """The cache and progress options of the commands that render references."""
    p.add_argument("--cache-dir", metavar="DIR", help=cache)
    p.add_argument("--no-cache", action="store_true", help=no_cache)
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bars")


def _frame_count(text: str) -> int:
    """``--frames``: an integer of at least 2 (a sequence needs one frame pair)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    if value < 2:
        raise argparse.ArgumentTypeError(f"must be at least 2, got {value}")
    return value


def _compare_command(subparsers) -> None:
    p = _command(subparsers, "compare", "harness.commands.compare:compare",
                 "render both ways, compare, write data files and an HTML report",
                 output_dir=True)
    p.add_argument("scenes", nargs="*", metavar="SCENE", help=_SCENES_HELP)
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output directory")
    p.add_argument("--studies", metavar="LIST",
                   help="comma-separated: metrics,convergence,cost,temporal,decomposition, "
                   "or a study another package registers (default: metrics,convergence,cost; "
                   "temporal renders the scene's "
                   "[animation] frame by frame on both sides and writes temporal.csv, the "
                   "flicker metrics and an animation; decomposition traces exact light paths "
                   "and swaps in the method's approximations one at a time, writing "
                   "decomposition.csv and a waterfall)")
    p.add_argument("--frames", type=_frame_count, metavar="N",
                   help="frames of the temporal study, at least 2 (default: the scene's "
                   "[animation] frames, else 24)")
    p.add_argument("--quick", action="store_true",
                   help="smaller sweeps, one timing repeat, at most 4 iterations")
    p.add_argument("--max-iterations", type=int, default=8, metavar="N",
                   help="iterations 0..N in the convergence table (default 8)")
    p.add_argument("--preset", action="append", choices=("paper", "strong"),
                   help="a caustics-mapping preset to compare (repeatable; default: both)")
    p.add_argument("--method", action="append", metavar="NAME",
                   help="a registered method (entry-point group caustics_harness.methods) "
                   "to compare (repeatable)")
    p.add_argument("--estimator", choices=("modified", "newton", "secant"), help=_ESTIMATOR_HELP)
    p.add_argument("--iterations", type=int, metavar="N", help=_ITERATIONS_HELP)
    p.add_argument("--grid", type=int, metavar="G", help=_GRID_HELP)
    p.add_argument("--photons", type=int, help="reference photon budget per seed")
    p.add_argument("--set", action="append", metavar="NAME=VALUE",
                   help="override any setting (repeatable)")
    p.add_argument("--locks", "--thresholds", dest="locks", metavar="FILE",
                   help="regression locks (default: the bundled ones); checked at the "
                   "golden settings against the golden references, for bundled scenes only; "
                   "physical requirements and method targets are checked as well "
                   "(--thresholds: the older name)")
    p.add_argument("--golden", metavar="DIR",
                   help="golden references the bounds hold against (default: the bundled ones)")
    p.add_argument("--fail-on-checks", "--fail-on-thresholds", dest="fail_on_checks",
                   action="store_true",
                   help="exit 3 when an accuracy check of any kind fails (a known gap does "
                   "not; --fail-on-thresholds: the older name)")
    p.add_argument("--self-contained", action="store_true",
                   help="embed images, plots, scripts in one HTML file per page")
    p.add_argument("--crosscheck", choices=("luxcore",),
                   help="also check the reference against an independent renderer "
                   "(full transport; needs the `crosscheck` extra)")
    p.add_argument("--crosscheck-photons", type=int, default=4_000_000, metavar="N",
                   help="photons per seed on each side of the cross-check (default %(default)s)")
    _cache_options(p)


def _receiver_file(text: str) -> tuple[int, str]:
    """``--receiver N=FILE.exr``: receiver index N and its file."""
    index, sep, path = text.partition("=")
    if not sep or not index.strip().isdigit() or not path:
        raise argparse.ArgumentTypeError(f"expected N=FILE.exr (N a receiver index), "
                                         f"got {text!r}")
    return int(index), path


def _score_command(subparsers) -> None:
    p = _command(subparsers, "score", "harness.commands.score:score",
                 "score images rendered by any renderer (EXR) against the reference: "
                 "metrics with intervals, checks, report (docs/scoring-external-renders.md)",
                 output_dir=True)
    p.add_argument("scene", nargs="?", metavar="SCENE", help=_SCENES_HELP)
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output directory")
    p.add_argument("--camera", metavar="FILE.exr",
                   help="camera image: linear radiance in W m^-2 sr^-1, RGB, the scene "
                   "camera's resolution (default: the camera is not scored)")
    p.add_argument("--receiver", action="append", type=_receiver_file, metavar="N=FILE.exr",
                   help="receiver N's caustic irradiance map in W/m^2 over its (u, v), RGB, "
                   "receiver_map texels, row 0 at vmin (repeatable; every receiver or none)")
    p.add_argument("--timing", metavar="FILE.json",
                   help="the renderer's own timing report, e.g. {\"frame_ms\": 12.3, "
                   "\"device\": \"...\"}: shown as reported, not measured by the harness "
                   "(default: render.json beside the first image, when there is one)")
    p.add_argument("--set", action="append", metavar="NAME=VALUE",
                   help="override any setting, as the images were rendered (repeatable)")
    _cache_options(p)


def _positive_metres(text: str) -> float:
    """``--tolerance``: a positive, finite number of metres."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of metres, got {text!r}") from None
    if not (value > 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"must be a positive number of metres, got {text}")
    return value


def _export_command(subparsers) -> None:
    p = _command(subparsers, "export", "harness.commands.export:export",
                 "write a scene for a renderer outside the harness: glTF 2.0 or Mitsuba 3 "
                 "XML (docs/export.md)", output_dir=True)
    p.add_argument("scene", nargs="?", metavar="SCENE", help=_SCENES_HELP)
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output directory")
    p.add_argument("--format", choices=("gltf", "mitsuba"), default="gltf",
                   help="gltf: DIR/<scene>.glb (KHR lights and materials, a camera per "
                   "receiver); mitsuba: DIR/scene.xml and DIR/meshes/*.ply, the reference's "
                   "own Mitsuba scene (default %(default)s)")
    p.add_argument("--mitsuba-bsdf", choices=("stock", "harness"), default="stock",
                   help="dielectrics in the XML: stock, Mitsuba's own dielectric (loads "
                   "in any Mitsuba 3; each way it differs from the reference's BSDF is "
                   "printed as a note); harness, the reference's chain_dielectric plugin "
                   "(exact; load it after renderers.mitsuba.bsdf.register) "
                   "(default %(default)s)")
    p.add_argument("--gltf-container", choices=("glb", "gltf"), default="glb",
                   help="one binary .glb, or a .gltf with its .bin beside it "
                   "(default %(default)s)")
    p.add_argument("--tolerance", type=_positive_metres, metavar="METRES",
                   help="largest chord error of analytic shapes (spheres, rings) in the "
                   "glTF, in metres (default: 1e-4 of the diagonal of the scene's bounding "
                   "box; never coarser than the scene's own tessellation)")


def _import_command(subparsers) -> None:
    p = _command(subparsers, "import", "harness.commands.import_scene:import_scene",
                 "read a glTF 2.0 or Mitsuba 3 XML scene into a scene file "
                 "(docs/bring-your-scene.md)")
    p.add_argument("file", metavar="FILE", help=".gltf, .glb or Mitsuba .xml")
    p.add_argument("-o", "--output", required=True, metavar="SCENE.toml",
                   help="scene file to write; meshes go to <stem>_meshes/ beside it")
    p.add_argument("--approximate", action="store_true",
                   help="replace what the scene model cannot hold (area lights, rough or "
                   "textured materials, extra lights) by a stated approximation instead "
                   "of refusing the file")
    p.add_argument("--camera", metavar="NAME",
                   help="the camera node (glTF) or sensor id (Mitsuba) to use (default: the "
                   "first perspective one)")


def _figures_command(subparsers) -> None:
    p = _command(subparsers, "figures", "harness.commands.figures:figures",
                 "regenerate the paper's figures with their data", output_dir=True)
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output directory")
    p.add_argument("--only", metavar="LIST", help="comma-separated figure names (fig06,...)")
    p.add_argument("--quick", action="store_true", help="small budgets and images")
    p.add_argument("--scenes", metavar="DIR", help="scenes folder (default: the bundled scenes)")
    p.add_argument("--cache-dir", help="reference cache root (default $CAUSTICS_CACHE_DIR or "
                   "~/.cache/caustics-harness/reference)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bars")


def _crosscheck_command(subparsers) -> None:
    p = _command(subparsers, "crosscheck", "harness.commands.crosscheck:crosscheck",
                 "check the reference against an independent renderer (full transport)",
                 output_dir=True)
    p.add_argument("scenes", nargs="*", metavar="SCENE", help=_SCENES_HELP)
    p.add_argument("--with", dest="other", choices=("luxcore",), required=True,
                   help="the independent renderer (needs the `crosscheck` extra)")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output directory")
    p.add_argument("--photons", type=int, default=4_000_000,
                   help="Mitsuba photons per seed (default %(default)s)")
    p.add_argument("--other-photons", type=int, default=4_000_000,
                   help="LuxCore light paths per film, two films per seed (default %(default)s)")
    p.add_argument("--seeds", type=int, default=4, help="seeds per side (default %(default)s)")
    p.add_argument("--fail-on-disagreement", action="store_true",
                   help="exit 3 when a comparison misses its tolerance")


def _sweep_command(subparsers) -> None:
    p = _command(subparsers, "sweep", "harness.commands.sweep:sweep",
                 "run a sweep (scenes x methods x settings x reference seeds) on Dask: "
                 "results.csv, an index of error against cost, a page per row",
                 output_dir=True)
    p.add_argument("sweep", metavar="SWEEP",
                   help="a sweep file (TOML, one [sweep] table) or a bundled sweep's name "
                   "(estimators)")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output directory")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--scheduler", metavar="ADDRESS",
                       help="an existing Dask scheduler, e.g. tcp://host:8786 (default: "
                       "$DASK_SCHEDULER_ADDRESS, else a local cluster)")
    where.add_argument("--scheduler-file", metavar="PATH",
                       help="the file `dask scheduler --scheduler-file PATH` wrote")
    where.add_argument("--in-process", action="store_true",
                       help="a Dask cluster of one worker thread inside this process, no "
                       "other process (debugging)")
    p.add_argument("--workers", type=int, metavar="N",
                   help="process workers of the local cluster (default: one per core)")
    p.add_argument("--connect-timeout", type=float, default=60.0, metavar="S",
                   help="seconds to wait for an existing scheduler to answer, and again "
                   "for its first worker (default %(default)s)")
    p.add_argument("--dry-run", action="store_true",
                   help="validate the sweep file, print the rows and their keys, run nothing")
    _cache_options(p, cache="cache root: the references, and the sweep's rows under "
                   f"sweep-results/ (default {_CACHE_ROOT})",
                   no_cache="compute every reference and row; read and write neither cache")


def _check_commands(subparsers) -> None:
    p = _command(subparsers, "golden", "harness.commands.checks:golden",
                 "check (or --regenerate) the golden references")
    p.add_argument("--dir", help="golden folder (default: the bundled one)")
    p.add_argument("--regenerate", action="store_true",
                   help="re-render into a staging folder and swap it in atomically")
    p = _command(subparsers, "calibrate", "harness.commands.checks:calibrate",
                 "set the regression locks from measured spread (they guard against "
                 "change, not accuracy)")
    p.add_argument("--golden", help="golden folder (default: the bundled one)")
    p.add_argument("--extra", type=int, default=3,
                   help="independent references beyond the golden one (default 3)")
    p.add_argument("-o", "--output", help="locks file (default: the bundled one)")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand (imports no handler module)."""
    parser = argparse.ArgumentParser(
        prog="caustics",
        description="Ground-truth validation harness for real-time caustics "
        "(caustics mapping vs Mitsuba 3).",
        epilog="exit status: 0 done, 1 bad input or failure, 2 usage, 3 a bound missed "
        "(--fail-on-...), 70 internal error, 130 interrupted",
    )
    parser.add_argument("--debug", action="store_true",
                        help="print the traceback of an internal error (also CAUSTICS_DEBUG=1)")
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for group in (_setup_command, _scene_commands, _render_commands, _compare_command,
                  _figures_command, _crosscheck_command, _check_commands, _sweep_command,
                  _export_command, _import_command, _score_command):
        group(subparsers)
    return parser


def _handler(spec: str):
    module, _, function = spec.partition(":")
    return getattr(importlib.import_module(module), function)


def _debugging(args: argparse.Namespace) -> bool:
    return bool(getattr(args, "debug", False)) or os.environ.get(
        "CAUSTICS_DEBUG", "").strip() not in ("", "0")


def _one_line_warning(message, *_where) -> None:
    """warnings.showwarning for the CLI: ``warning: <message>`` on one line (the
    library warnings, such as a cut-flux or an invalid cache entry, name their scene
    or entry themselves; the source line Python would add means nothing to a user)."""
    warn(message)


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; return the exit status (:data:`EXIT_CODES`, the module docstring)."""
    args = build_parser().parse_args(argv)
    debug = _debugging(args)
    shown = warnings.showwarning
    if not debug:
        warnings.showwarning = _one_line_warning
    try:
        return _run(args, debug=debug)
    finally:
        warnings.showwarning = shown


def _run(args: argparse.Namespace, *, debug: bool) -> int:
    try:
        if args.output_dir:
            check_output_dir(args.output)  # before any import or render: fail in seconds
        return int(_handler(args.handler)(args) or 0)
    except SceneError as error:
        for problem in error.problems:
            print(f"error: {plain(problem)}", file=sys.stderr)
        return EXIT_CODES["failure"]
    except HarnessError as error:
        # One line; a long report (a worker's output) follows only with --debug.
        first, *rest = str(error).splitlines() or [""]
        print(f"error: {plain(first)}" + (f" ({len(rest)} more lines: --debug shows them)"
                                          if rest and not debug else ""), file=sys.stderr)
        for line in rest if debug else ():
            print(f"  {plain(line)}", file=sys.stderr)
        return EXIT_CODES["failure"]
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return EXIT_CODES["interrupted"]
    except Exception as error:
        # The system refused (a full disk, a permission): the user's to fix, so 1;
        # anything else is a bug in the harness: 70, traceback on request.
        if debug:
            traceback.print_exc()
        code = EXIT_CODES["failure" if isinstance(error, OSError) else "internal"]
        hint = "" if debug else f" ({_DEBUG_HINT})"
        print(f"error: {error_line(error)}{hint}", file=sys.stderr)
        return code


def run() -> None:
    """Console-script entry point."""
    sys.exit(main())
