"""The bad-input corpus: malformed or awkward scene files and command lines, each with
its expected outcome: every failure is one clear line.

A case is a scene text (the base scene with edits), extra files beside it, a command
line and what must come of it: an exit status, and either a regular expression that
one ``error:`` line on stderr must match (each naming the file and the field), or a
finite result (for ``render``: every image finite, ``result.json`` strict JSON).
"""

from __future__ import annotations

import dataclasses

from tests.conftest import MINIMAL_SCENE

#: The shared minimal scene (glass sphere over a floor, point light), named, with the
#: light off-axis, a 48 x 48 camera and small maps so that ``render`` cases take well
#: under a second each.
BASE = MINIMAL_SCENE.lstrip().replace(
    'name = "minimal"', 'name = "corpus"\ndescription = "bad-input corpus base"').replace(
    "position = [0.0, 0.0, 6.0]", "position = [1.0, -0.5, 6.0]").replace(
    "resolution = [64, 64]", "resolution = [48, 48]") + """
[settings]
grid = 16
caustic_map = 64
positions_map = 64
shadow_map = 64
receiver_map = [32, 32]
"""
LIGHT = 'type = "point"\nposition = [1.0, -0.5, 6.0]\nintensity = [30.0, 30.0, 30.0]'
SPHERE = ('type = "sphere"\ncenter = [0.0, 0.0, 2.0]\nradius = 1.0\n'
          'material = { type = "dielectric", ior = 1.5 }')
#: A closed tetrahedron (OBJ), and an open one (one face missing).
TETRA = "v 0 0 1.5\nv 1 0 1.5\nv 0 1 1.5\nv 0 0 2.5\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
OPEN_TETRA = "v 0 0 1.5\nv 1 0 1.5\nv 0 1 1.5\nv 0 0 2.5\nf 1 3 2\nf 1 2 4\nf 1 4 3\n"
#: A cube, an open bowl shape (cube minus its top) for a mirror.
CUBE_V = ("v -.5 -.5 1\nv .5 -.5 1\nv .5 .5 1\nv -.5 .5 1\n"
          "v -.5 -.5 2\nv .5 -.5 2\nv .5 .5 2\nv -.5 .5 2\n")
BOWL = CUBE_V + ("f 1 3 2\nf 1 4 3\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\n"
                 "f 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n")


def mesh_object(file: str, material: str = '{ type = "dielectric", ior = 1.5 }') -> str:
    """An ``[[objects]]`` body for a mesh file."""
    return f'type = "mesh"\nfile = "{file}"\nmaterial = {material}'


@dataclasses.dataclass(frozen=True)
class Case:
    """One corpus entry.

    Attributes
    ----------
    id : str
        Test id.
    scene : str or None
        Scene file text, or None for a case about the command line only.
    argv : tuple of str
        Command line; ``{scene}``, ``{dir}`` and ``{out}`` are the scene file, its
        folder and a fresh output folder.
    exit : int
        Expected exit status.
    error : str or None
        Regular expression one ``error:`` line must match (searched).
    finite : bool
        The command writes a result whose images and JSON must be finite.
    files : tuple of (str, bytes)
        Files written beside the scene (name, content).
    scene_bytes : bytes or None
        Raw scene bytes (for encodings), instead of ``scene``.
    """

    id: str
    scene: str | None
    argv: tuple[str, ...] = ("validate", "{scene}")
    exit: int = 1
    error: str | None = None
    finite: bool = False
    files: tuple[tuple[str, bytes], ...] = ()
    scene_bytes: bytes | None = None


def edit(*pairs: tuple[str, str], base: str = BASE) -> str:
    """``base`` with each (old, new) replaced once; old must occur."""
    text = base
    for old, new in pairs:
        assert old in text, old
        text = text.replace(old, new, 1)
    return text


def rendered(case_id: str, scene: str, *options: str, **kw) -> Case:
    """A legal scene ``render`` must turn into a finite result (exit 0)."""
    return Case(case_id, scene, argv=("render", "{scene}", "-o", "{out}", *options), exit=0,
                finite=True, **kw)


def bad(case_id: str, pairs, error: str, **kw) -> Case:
    """A scene edit that ``validate`` must refuse with one line matching ``error``."""
    return Case(case_id, edit(*pairs), error=error, **kw)


INTENSITY = "intensity = [30.0, 30.0, 30.0]"
POSITION = "position = [1.0, -0.5, 6.0]"
RADIUS = "radius = 1.0"
CENTRE = "center = [0.0, 0.0, 2.0]"
IOR = "ior = 1.5"
SIZE = "size = [8.0, 8.0]"
ALBEDO = "albedo = [0.5, 0.5, 0.5]"
FOV = "fov = 40.0"
RES = "resolution = [48, 48]"
GRID = "grid = 16"

SCENE_CASES = [
    # --- the file itself
    Case("empty-file", "", error=r"corpus\.toml"),
    Case("not-toml", "this is = = not toml", error=r"corpus\.toml"),
    Case("duplicate-key", edit((FOV, FOV + "\nfov = 30.0")), error=r"corpus\.toml"),
    Case("utf16-scene", None, scene_bytes=BASE.encode("utf-16"), error=r"corpus\.toml"),
    Case("latin1-scene", None, scene_bytes=BASE.replace("bad-input", "caf\u00e9").encode(
        "latin-1"), error=r"corpus\.toml"),
    Case("bom-scene", None, scene_bytes=b"\xef\xbb\xbf" + BASE.encode(), exit=0),
    Case("missing-file", None, argv=("validate", "{dir}/nosuch.toml"), error=r"nosuch"),
    Case("directory", None, argv=("validate", "{dir}"), error=r"."),
    Case("unknown-bundled", None, argv=("validate", "glass_spere"), error=r"glass_spere"),
    # --- tables and fields
    bad("no-light", [("[light]\n" + LIGHT + "\n", "")], r"light"),
    bad("no-camera", [("[camera]", "[cameraX]")], r"camera"),
    bad("unknown-table", [("[settings]", "[nonsense]\nx = 1\n\n[settings]")], r"nonsense"),
    bad("unknown-light-field", [(INTENSITY, INTENSITY + "\ncolour = 3")], r"light\.colour"),
    bad("unknown-light-type", [('type = "point"', 'type = "laser"')], r"light\.type"),
    bad("unknown-object-type", [('type = "sphere"', 'type = "cone"')], r"objects\[0\]\.type"),
    bad("unknown-receiver-type", [('type = "plane"', 'type = "disk"')],
        r"receivers\[0\]\.type"),
    bad("unknown-material", [('type = "dielectric"', 'type = "glassy"')],
        r"objects\[0\]\.material"),
    bad("missing-material", [('material = { type = "dielectric", ior = 1.5 }', "")],
        r"objects\[0\]\.material"),
    bad("no-receivers", [('[[receivers]]\ntype = "plane"\ncenter = [0.0, 0.0, 0.0]\n'
                          + SIZE + "\n" + ALBEDO + "\n", "")], r"receivers"),
    bad("unknown-setting", [(GRID, GRID + "\nturbo = true")], r"settings\.turbo"),
    # --- values: types and ranges
    bad("intensity-string", [(INTENSITY, 'intensity = "bright"')], r"light\.intensity"),
    bad("intensity-bool", [(INTENSITY, "intensity = true")], r"light\.intensity"),
    bad("intensity-length", [(INTENSITY, "intensity = [30.0, 30.0]")], r"light\.intensity"),
    bad("intensity-negative", [(INTENSITY, "intensity = [-1.0, 30.0, 30.0]")],
        r"light\.intensity"),
    bad("intensity-nan", [(INTENSITY, "intensity = [nan, 30.0, 30.0]")], r"light\.intensity"),
    bad("intensity-inf", [(INTENSITY, "intensity = [inf, 30.0, 30.0]")], r"light\.intensity"),
    bad("intensity-overflow", [(INTENSITY, "intensity = [1e38, 1e38, 1e38]")],
        r"light\.intensity"),
    bad("intensity-zero", [(INTENSITY, "intensity = [0.0, 0.0, 0.0]")], r"light\.intensity"),
    bad("position-length", [(POSITION, "position = [1.0, 2.0]")], r"light\.position"),
    bad("position-nested", [(POSITION, "position = [[1.0], 2.0, 3.0]")], r"light\.position"),
    bad("position-nan", [(POSITION, "position = [nan, 0.0, 6.0]")], r"light\.position"),
    bad("position-huge", [(POSITION, "position = [1e300, 0.0, 6.0]")], r"light\.position"),
    bad("radius-zero", [(RADIUS, "radius = 0.0")], r"objects\[0\]\.radius"),
    bad("radius-negative", [(RADIUS, "radius = -1.0")], r"objects\[0\]\.radius"),
    bad("radius-huge", [(RADIUS, "radius = 1e300")], r"objects\[0\]\.radius"),
    bad("radius-1e20", [(RADIUS, "radius = 1e20")], r"objects\[0\]\.radius"),
    bad("radius-underflow", [(RADIUS, "radius = 1e-50")], r"objects\[0\]\.radius"),
    bad("centre-huge", [(CENTRE, "center = [1e300, 0.0, 2.0]")], r"objects\[0\]\.center"),
    bad("ior-zero", [(IOR, "ior = 0.0")], r"objects\[0\]\.material\.ior"),
    bad("ior-negative", [(IOR, "ior = -1.5")], r"objects\[0\]\.material\.ior"),
    bad("ior-nan", [(IOR, "ior = nan")], r"objects\[0\]\.material\.ior"),
    bad("receiver-size-zero", [(SIZE, "size = [0.0, 8.0]")], r"receivers\[0\]\.size"),
    bad("receiver-size-negative", [(SIZE, "size = [-8.0, 8.0]")], r"receivers\[0\]\.size"),
    bad("albedo-above-one", [(ALBEDO, "albedo = [1.5, 0.5, 0.5]")], r"receivers\[0\]\.albedo"),
    bad("albedo-negative", [(ALBEDO, "albedo = [-0.5, 0.5, 0.5]")], r"receivers\[0\]\.albedo"),
    bad("fov-zero", [(FOV, "fov = 0.0")], r"camera\.fov"),
    bad("fov-180", [(FOV, "fov = 180.0")], r"camera\.fov"),
    bad("resolution-zero", [(RES, "resolution = [0, 48]")], r"camera\.resolution"),
    bad("resolution-huge", [(RES, "resolution = [100000, 48]")], r"camera\.resolution"),
    bad("resolution-float", [(RES, "resolution = [48.5, 48]")], r"camera\.resolution"),
    bad("resolution-bigint", [(RES, "resolution = [99999999999999999999, 48]")],
        r"camera\.resolution"),
    bad("camera-at-target", [("look_at = [0.0, 0.0, 0.5]", "look_at = [0.0, -9.0, 7.0]")],
        r"camera"),
    bad("grid-zero", [(GRID, "grid = 0")], r"settings\.grid"),
    bad("grid-huge", [(GRID, "grid = 100000")], r"settings\.grid"),
    bad("iterations-negative", [(GRID, GRID + "\niterations = -1")], r"settings\.iterations"),
    bad("estimator-unknown", [(GRID, GRID + '\nestimator = "magic"')],
        r"settings\.estimator"),
    bad("preset-unknown", [(GRID, GRID + '\npreset = "fast"')], r"settings\.preset"),
    bad("spot-zero-direction", [(LIGHT, 'type = "spot"\nposition = [0.0, 0.0, 6.0]\n'
                                 'direction = [0.0, 0.0, 0.0]\n' + INTENSITY
                                 + "\ncutoff_angle = 30.0")], r"light\.direction"),
    bad("spot-cutoff-90", [(LIGHT, 'type = "spot"\nposition = [0.0, 0.0, 6.0]\n'
                            'direction = [0.0, 0.0, -1.0]\n' + INTENSITY
                            + "\ncutoff_angle = 95.0")], r"light\.cutoff_angle"),
    bad("spot-beam-wider-than-cutoff", [(LIGHT, 'type = "spot"\nposition = [0.0, 0.0, 6.0]\n'
                                         'direction = [0.0, 0.0, -1.0]\n' + INTENSITY
                                         + "\ncutoff_angle = 20.0\nbeam_width = 40.0")],
        r"light\.beam_width"),
    bad("directional-zero-direction", [(LIGHT, 'type = "directional"\n'
                                        'direction = [0.0, 0.0, 0.0]\n'
                                        'irradiance = [1.0, 1.0, 1.0]')],
        r"light\.direction"),
    bad("area-zero-size", [(LIGHT, 'type = "area"\ncenter = [0.0, 0.0, 6.0]\n'
                            'normal = [0.0, 0.0, -1.0]\nsize = [0.0, 1.0]\n' + INTENSITY)],
        r"light\.size"),
    # --- geometry the renderers would fail on
    bad("light-inside-sphere", [(POSITION, "position = [0.0, 0.0, 2.0]")], r"light\.position"),
    # --- no caustic reaches a receiver: validate's probe predicts compare's failure
    bad("caustic-misses-receiver", [("center = [0.0, 0.0, 0.0]", "center = [6.0, 6.0, 0.0]"),
                                    (SIZE, "size = [1.0, 1.0]")], r"receivers: no caustic"),
    bad("no-specular-object", [('material = { type = "dielectric", ior = 1.5 }',
                                'material = { type = "diffuse", albedo = [0.5, 0.5, 0.5] }')],
        r"receivers: no caustic"),
    bad("spot-aimed-away", [(LIGHT, 'type = "spot"\nposition = [0.0, 0.0, 6.0]\n'
                             'direction = [0.0, 0.0, 1.0]\n' + INTENSITY
                             + "\ncutoff_angle = 30.0")], r"receivers: no caustic"),
    bad("light-below-receiver", [(POSITION, "position = [1.0, -0.5, -6.0]")],
        r"receivers: no caustic"),
    # --- meshes
    bad("mesh-missing", [(SPHERE, mesh_object("nosuch.obj"))], r"objects\[0\]\.file"),
    bad("mesh-garbage", [(SPHERE, mesh_object("garbage.obj"))], r"objects\[0\]\.file",
        files=(("garbage.obj", b"\x00\x01\x02 not a mesh \xff\xfe"),)),
    bad("mesh-text-garbage", [(SPHERE, mesh_object("text.obj"))], r"objects\[0\]\.file",
        files=(("text.obj", b"hello world\nthis is not an obj\n"),)),
    bad("mesh-empty", [(SPHERE, mesh_object("empty.obj"))], r"objects\[0\]\.file",
        files=(("empty.obj", b""),)),
    bad("mesh-utf16", [(SPHERE, mesh_object("wide.obj"))], r"objects\[0\]\.file",
        files=(("wide.obj", TETRA.encode("utf-16")),)),
    bad("mesh-escape", [(SPHERE, mesh_object("../../../etc/passwd"))],
        r"objects\[0\]\.file"),
    bad("mesh-absolute", [(SPHERE, mesh_object("/etc/passwd"))], r"objects\[0\]\.file"),
    bad("mesh-wrong-extension", [(SPHERE, mesh_object("tetra.stl"))], r"objects\[0\]\.file",
        files=(("tetra.stl", TETRA.encode()),)),
    bad("mesh-open-dielectric", [(SPHERE, mesh_object("open.obj"))],
        r"objects\[0\]\.file.*open", files=(("open.obj", OPEN_TETRA.encode()),)),
    bad("mesh-nan-vertex", [(SPHERE, mesh_object("nan.obj"))], r"objects\[0\]\.file",
        files=(("nan.obj", TETRA.replace("v 1 0 1.5", "v nan 0 1.5").encode()),)),
    bad("mesh-flat", [(SPHERE, mesh_object("flat.obj"))], r"objects\[0\]\.file",
        files=(("flat.obj", b"v 0 0 1\nv 1 0 1\nv 2 0 1\nv 3 0 1\nf 1 2 3\nf 2 3 4\n"),)),
    bad("mesh-too-few", [(SPHERE, mesh_object("tri.obj"))], r"objects\[0\]\.file",
        files=(("tri.obj", b"v 0 0 1\nv 1 0 1\nv 0 1 1\nf 1 2 3\n"),)),
    bad("mesh-bad-index", [(SPHERE, mesh_object("idx.obj"))], r"objects\[0\]\.file",
        files=(("idx.obj", (TETRA + "f 1 2 99\n").encode()),)),
    bad("mesh-builtin-unknown", [(SPHERE, mesh_object("builtin:dragon"))],
        r"objects\[0\]\.file"),
    # --- legal but awkward: these validate
    Case("latin1-comment-mesh", edit((SPHERE, mesh_object("tetra.obj"))), exit=0,
         files=(("tetra.obj", b"# caf\xe9\n" + TETRA.encode()),)),
    Case("open-mirror-bowl", edit((SPHERE, mesh_object(
        "bowl.obj", '{ type = "conductor", reflectance = [0.9, 0.9, 0.9] }'))), exit=0,
        files=(("bowl.obj", BOWL.encode()),)),
    Case("markup-name", edit(('name = "corpus"', 'name = "a[/]b[bold]c"')), exit=0),
    Case("ansi-name", edit(('name = "corpus"', 'name = "a\\u001b[31mred\\u0007"')), exit=0),
    Case("unicode-name", edit(('name = "corpus"', 'name = "\u30ac\u30e9\u30b9\u7403"')),
         exit=0),
    Case("long-name", edit(('name = "corpus"', f'name = "{"n" * 5000}"')), exit=0),
    Case("int-for-float", edit((RADIUS, "radius = 1")), exit=0),
    Case("camera-inside-sphere", edit(("position = [0.0, -9.0, 7.0]",
                                       "position = [0.3, 0.0, 2.0]")), exit=0),
]

CLI_CASES = [
    Case("render-set-unknown", BASE, argv=("render", "{scene}", "-o", "{out}", "--set",
                                           "turbo=1"), error=r"turbo"),
    Case("render-set-bad-value", BASE, argv=("render", "{scene}", "-o", "{out}", "--set",
                                             "grid=abc"), error=r"grid"),
    Case("render-set-out-of-range", BASE, argv=("render", "{scene}", "-o", "{out}", "--set",
                                                "grid=-1"), error=r"grid"),
    Case("render-set-no-equals", BASE, argv=("render", "{scene}", "-o", "{out}", "--set",
                                             "grid"), error=r"grid: expected NAME=VALUE"),
    Case("render-bad-estimator", BASE, argv=("render", "{scene}", "-o", "{out}",
                                             "--estimator", "magic"), exit=2),
    Case("render-negative-iterations", BASE, argv=("render", "{scene}", "-o", "{out}",
                                                   "--iterations", "-1"), error=r"iterations"),
    Case("render-bad-preset", BASE, argv=("render", "{scene}", "-o", "{out}", "--preset",
                                          "fast"), exit=2),
    Case("render-out-is-file", BASE, argv=("render", "{scene}", "-o", "{scene}"),
         error=r"corpus\.toml"),
    Case("compare-unknown-method", BASE, argv=("compare", "{scene}", "-o", "{out}",
                                               "--method", "nosuch"), error=r"nosuch"),
    Case("compare-bad-studies", BASE, argv=("compare", "{scene}", "-o", "{out}", "--studies",
                                            "bogus"), exit=2),
    Case("compare-missing-thresholds", BASE, argv=("compare", "{scene}", "-o", "{out}",
                                                   "--thresholds", "{dir}/nosuch.toml"),
         error=r"nosuch\.toml"),
    Case("compare-out-is-file", BASE, argv=("compare", "{scene}", "-o", "{scene}"),
         error=r"corpus\.toml"),
    Case("reference-zero-photons", BASE, argv=("reference", "{scene}", "-o", "{out}",
                                               "--photons", "0"), error=r"photons"),
    Case("reference-zero-seeds", BASE, argv=("reference", "{scene}", "-o", "{out}",
                                             "--seeds", "0"), error=r"seeds"),
    Case("crosscheck-unknown-renderer", BASE, argv=("crosscheck", "{scene}", "--with",
                                                    "povray", "-o", "{out}"), exit=2),
    Case("unknown-command", None, argv=("frobnicate",), exit=2),
    Case("figures-unknown", None, argv=("figures", "-o", "{out}", "--only", "fig99"),
         exit=2, error=r"fig99"),
    # --- finite results from legal extremes
    rendered("render-base", BASE),
    rendered("render-markup-name", edit(('name = "corpus"', 'name = "a[/]b"'))),
    rendered("render-ior-near-one", edit((IOR, "ior = 1.0001"))),
    rendered("render-huge-ior", edit((IOR, "ior = 4.0"))),
    rendered("render-tiny-intensity", edit((INTENSITY, "intensity = [1e-30, 1e-30, 1e-30]"))),
    rendered("render-large-intensity", edit((INTENSITY, "intensity = [1e20, 1e20, 1e20]"))),
    rendered("render-grazing-light", edit((POSITION, "position = [30.0, 0.0, 2.5]"))),
    rendered("render-light-below-floor", edit((POSITION, "position = [1.0, -0.5, -6.0]"))),
    rendered("render-sphere-touching-floor", edit((CENTRE, "center = [0.0, 0.0, 1.0]"))),
    rendered("render-tiny-sphere", edit((RADIUS, "radius = 1e-4"))),
    rendered("render-grid-2", edit((GRID, "grid = 2"))),
    rendered("render-zero-iterations", BASE, "--iterations", "0"),
    rendered("render-strong", BASE, "--preset", "strong"),
    rendered("render-open-mirror-bowl", edit((SPHERE, mesh_object(
        "bowl.obj", '{ type = "conductor", reflectance = [0.9, 0.9, 0.9] }'))),
        files=(("bowl.obj", BOWL.encode()),)),
    rendered("render-spot", edit((LIGHT, 'type = "spot"\nposition = [0.0, 0.0, 6.0]\n'
                                  'direction = [0.0, 0.0, -1.0]\n' + INTENSITY
                                  + "\ncutoff_angle = 30.0\nbeam_width = 20.0"))),
    rendered("render-directional", edit((LIGHT, 'type = "directional"\n'
                                         'direction = [0.1, 0.0, -1.0]\n'
                                         'irradiance = [1.0, 1.0, 1.0]'))),
]

CASES = SCENE_CASES + CLI_CASES
