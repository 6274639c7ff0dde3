"""A scene read from another format, before it is a scene file: its TOML tables, the
meshes to write beside it, where each part came from, and what was approximated.

:func:`write_draft` writes the meshes (OBJ with normals, beside the scene file, named by
relative path), the scene file (``tomli_w``; each ``[light]``, ``[camera]``,
``[[receivers]]`` and ``[[objects]]`` preceded by a comment naming its source), and
then reads the file back with :func:`scenes.loader.load_scene`, so that what it
returns is a scene ``caustics validate`` accepts.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import tomli_w
import trimesh

from scenes.errors import HarnessError
from scenes.files import atomic_path, atomic_write_bytes
from scenes.geometry import build_geometry
from scenes.loader import load_scene
from scenes.model import Scene

__all__ = ["Draft", "ImportProblemError", "MeshPart", "Part", "usable", "write_draft"]


class ImportProblemError(HarnessError, ValueError):
    """A file cannot be imported; ``problems`` holds one line per reason, each naming the
    file and the node, shape or element."""

    def __init__(self, problems: list[str]):
        self.problems = list(problems)
        super().__init__("\n".join(self.problems))


@dataclass(frozen=True)
class MeshPart:
    """Triangles to write as a mesh file: positions (n, 3) in scene metres (+z up),
    faces (m, 3) indices with counter-clockwise fronts."""

    name: str
    positions: np.ndarray
    faces: np.ndarray
    #: Vertex normals (n, 3), where the file has them: a vertex repeated with different
    #: normals keeps its crease (a flat-shaded cube stays flat).
    normals: np.ndarray | None = None


@dataclass(frozen=True)
class Part:
    """One table of the scene file; ``origin`` says where it came from (a comment in the
    file). A part with a ``mesh`` gets its ``file`` key when the mesh is written."""

    table: dict[str, Any]
    origin: str
    mesh: MeshPart | None = None
    #: What to write instead when an exact table from the file's extras turns out not to
    #: describe the file's triangles (the node was edited): (section, part).
    fallback: tuple[str, Part] | None = None
    #: The file's triangles' bounding box (2, 3), m, that the exact table must reproduce.
    bounds: np.ndarray | None = None
    #: Why the triangles alone could not be imported (an open water surface is only its
    #: exact table): the problems raised if the table turns out stale.
    refused: tuple[str, ...] = ()


@dataclass
class Draft:
    """The scene being imported (mutable while the reader collects it)."""

    source: str
    name: str
    #: Every light found; the scene model holds one (:meth:`check` keeps the first, with
    #: ``approximate``, or refuses).
    lights: list[Part] = field(default_factory=list)
    #: Point lights standing in for area lights (``approximate``): after the file's own.
    stand_in_lights: list[Part] = field(default_factory=list)
    light: Part | None = None
    camera: Part | None = None
    receivers: list[Part] = field(default_factory=list)
    objects: list[Part] = field(default_factory=list)
    info: dict[str, Any] = field(default_factory=dict)
    settings: dict[str, Any] = field(default_factory=dict)
    #: One line per approximation made (``--approximate``), naming the part.
    approximations: list[str] = field(default_factory=list)
    #: One line per thing the scene model cannot hold, naming the part.
    problems: list[str] = field(default_factory=list)
    #: Parts ("shape", "light", "camera") a refusal already accounts for.
    explained: set[str] = field(default_factory=set)

    def refuse(self, where: str, why: str, *, part: str | None = None) -> None:
        """Record a problem: ``<source>: <where>: <why>``. ``part`` ("shape", "light",
        "camera"): what the refused element would have been, so that :meth:`check` does
        not report that part missing as a second line for the same problem."""
        self.problems.append(f"{self.source}: {where}: {why}")
        if part:
            self.explained.add(part)

    def approximate(self, approximate: bool, where: str, why: str, instead: str, *,
                    part: str | None = None) -> bool:
        """A part the model cannot hold: with ``approximate``, record ``instead`` and return
        True (the caller substitutes it); else record a problem and return False."""
        if approximate:
            self.approximations.append(f"{where}: {why}; {instead}")
            return True
        self.refuse(where, f"{why} (--approximate: {instead})", part=part)
        return False

    def area_light(self, approximate: bool, where: str, centre, radiance, area: float
                   ) -> None:
        """An emitting surface (radiance W m^-2 sr^-1 per channel, one-sided area m²):
        refused, or approximated by a point light of the same power at its centre:
        Φ = π L A, I = Φ / 4π = L A / 4."""
        intensity = [float(v) * area / 4 for v in radiance]
        if self.approximate(approximate, where, "an area light: the scene model holds "
                            "point, spot and directional lights", "a point light of the same "
                            f"power at its centre, intensity {_short(intensity)} W/sr",
                            part="light"):
            table = {"type": "point", "position": [float(c) for c in centre],
                     "intensity": intensity}
            self.stand_in_lights.append(Part(table, f"{where} (area light, approximated by "
                                             "a point light)"))

    def choose_light(self, approximate: bool) -> None:
        """Keep the one light the scene model holds."""
        lights = self.lights + self.stand_in_lights
        if len(lights) > 1:
            names = "; ".join(p.origin for p in lights)
            if not self.approximate(approximate, "lights", f"{len(lights)} lights "
                                    f"({names}): the scene model holds one",
                                    "only the first listed is kept", part="light"):
                return
        if lights:
            self.light = lights[0]

    def check(self) -> None:
        """Raise :class:`ImportProblemError` with every problem, including missing parts."""
        if self.light is None and "light" not in self.explained:
            self.refuse("light", "the file has no light the scene model holds (a point, spot "
                        "or directional light)")
        if self.camera is None and "camera" not in self.explained:
            self.refuse("camera", "the file has no perspective camera")
        if not self.receivers and "shape" not in self.explained:
            self.refuse("receivers", "no diffuse surface can serve as a receiver (a plane, "
                        "or a mesh that is a height field over x, y)")
        if not self.objects and "shape" not in self.explained:
            self.refuse("objects", "no caustic object (a dielectric or conductor shape)")
        if self.problems:
            raise ImportProblemError(self.problems)


def usable(table: dict) -> bool:
    """An exported shape's exact table names every file it needs (an export drops this
    machine's paths: such a shape is rebuilt from the file's triangles)."""
    if table.get("type") == "mesh" and "file" not in table:
        return False
    height = table.get("height")
    return not (isinstance(height, dict) and height.get("type") == "file"
                and "file" not in height)


def _short(values) -> str:
    return "(" + ", ".join(f"{v:.4g}" for v in values) + ")"


def _write_obj(path: Path, mesh: MeshPart) -> None:
    """OBJ with ``vn`` lines (the mesh loader keeps vertices apart whose normals differ;
    a PLY's would be merged), 12 decimals: float32 positions to well below an ulp."""
    data = trimesh.Trimesh(np.asarray(mesh.positions, np.float64),
                           np.asarray(mesh.faces, np.int64), process=False)
    if mesh.normals is not None:
        data.vertex_normals = np.asarray(mesh.normals, np.float64)
    text = data.export(file_type="obj", include_normals=mesh.normals is not None, digits=12)
    atomic_write_bytes(path, text.encode("utf-8"))


def write_draft(draft: Draft, path: str | Path) -> Scene:
    """Write the scene file ``path`` and its meshes (``<stem>_meshes/*.obj`` beside it),
    and read it back.

    Raises
    ------
    ImportProblemError
        The draft has problems (nothing is written).
    SceneError
        The written file does not validate (the importer's fault: it names the field).
    """
    draft.check()
    path = Path(path)
    folder = path.parent / f"{path.stem}_meshes"
    parts = [("receivers", p) for p in draft.receivers] + [("objects", p) for p in draft.objects]
    tables: dict[str, list] = {"receivers": [], "objects": []}
    for section, part in parts:
        table = dict(part.table)
        if part.mesh is not None:
            folder.mkdir(parents=True, exist_ok=True)
            _write_obj(folder / f"{part.mesh.name}.obj", part.mesh)
            table["file"] = f"{folder.name}/{part.mesh.name}.obj"
        tables[section].append(table)
    description = draft.info.get("description") or f"Imported from {Path(draft.source).name}"
    if draft.approximations:
        description += ". Approximated: " + "; ".join(draft.approximations)
    document = {
        "scene": {**draft.info, "name": draft.info.get("name", draft.name),
                  "description": description},
        "light": draft.light.table, "receivers": tables["receivers"],
        "objects": tables["objects"], "camera": draft.camera.table,
    }
    if draft.settings:
        document["settings"] = draft.settings
    text = _with_origins(tomli_w.dumps(document), draft)
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    scene = load_scene(path)
    stale = _stale(draft, scene)
    if not stale:
        return scene
    # An exact table that no longer describes the file's triangles (the node was edited
    # after the export): write those parts from their triangles instead.
    lost = [line for part in stale if part.fallback is None for line in part.refused]
    if lost:
        raise ImportProblemError(lost)
    for part in stale:
        section, replacement = part.fallback
        for name in ("receivers", "objects"):
            if part in getattr(draft, name):
                getattr(draft, name).remove(part)
        getattr(draft, section).append(replacement)
    return write_draft(draft, path)


def _stale(draft: Draft, scene: Scene) -> list[Part]:
    """Parts from exact tables whose built triangles' bounding box differs from the
    file's by more than 1e-3 of its diagonal (those with a fallback to write instead, or
    whose triangles alone were refused)."""
    geometry = build_geometry(scene)
    built = [g.mesh for g in geometry.receivers] + [g.mesh for g in geometry.objects]
    stale = []
    for part, mesh in zip(draft.receivers + draft.objects, built, strict=True):
        if part.bounds is None or (part.fallback is None and not part.refused):
            continue
        positions = np.asarray(mesh.positions, np.float64)
        box = np.stack([positions.min(axis=0), positions.max(axis=0)])
        scale = np.linalg.norm(part.bounds[1] - part.bounds[0])
        if np.abs(box - part.bounds).max() > 1e-3 * scale + 1e-9:
            stale.append(part)
    return stale


def _with_origins(text: str, draft: Draft) -> str:
    """The TOML text with a comment before each part's header naming its source."""
    origins = {"[light]": [draft.light.origin], "[camera]": [draft.camera.origin],
               "[[receivers]]": [p.origin for p in draft.receivers],
               "[[objects]]": [p.origin for p in draft.objects]}
    lines = [f"# Imported from {Path(draft.source).name} by `caustics import`."]
    lines += [f"# Approximated: {line}" for line in draft.approximations]
    for line in text.splitlines():
        queue = origins.get(line.strip())
        if queue:
            lines.append(f"# from {queue.pop(0)}")
        lines.append(line)
    return "\n".join(lines) + "\n"
