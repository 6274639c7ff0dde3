"""Read mesh files (OBJ, PLY) into :class:`TriangleMesh`; every failure is a
:class:`MeshFileError` saying why, never a library's own exception.

Encoding policy
---------------
The file's bytes are read here and trimesh receives text (OBJ) or bytes (PLY), so
trimesh never guesses an encoding (its guess needs ``charset_normalizer``, which is
not a dependency, and a wrong guess would parse a different mesh).

* OBJ is ASCII by specification; UTF-8 (with or without a byte-order mark) is read
  as is.
* Bytes that are not UTF-8 (Latin-1, Windows-1252...) are accepted inside comments
  only (after ``#`` on a line), where they cannot change the geometry: the comment's
  text is dropped. Anywhere else they are an error naming the line.
* UTF-16 and UTF-32 text (a byte-order mark, or NUL bytes) is refused with a message
  saying to re-save the file as UTF-8.
* PLY is read as bytes (its header is ASCII, its body may be binary).

Material libraries (``mtllib``) are not read: the harness needs only triangles,
normals and (u, v), and reading them would open files the scene did not name.
"""

from __future__ import annotations

import io
import re
from pathlib import Path

import numpy as np
import trimesh

from scenes.geometry.mesh import TriangleMesh, make_mesh

__all__ = ["MESH_FORMATS", "MeshFileError", "builtin_mesh_path", "decode_obj",
           "load_mesh_file", "watertight"]

#: File extensions read, each with trimesh's format name.
MESH_FORMATS = {".obj": "obj", ".ply": "ply"}

_WIDE_BOMS = {b"\xff\xfe\x00\x00": "UTF-32", b"\x00\x00\xfe\xff": "UTF-32",
              b"\xff\xfe": "UTF-16", b"\xfe\xff": "UTF-16"}


class MeshFileError(ValueError):
    """A mesh file cannot be read or holds no usable mesh; the message says why
    (the caller adds the scene file and field path)."""


def decode_obj(raw: bytes) -> str:
    """OBJ bytes as text, by the module's encoding policy.

    Raises
    ------
    MeshFileError
        UTF-16/32 or binary data, or non-UTF-8 bytes outside a comment.
    """
    for bom, name in _WIDE_BOMS.items():
        if raw.startswith(bom):
            raise MeshFileError(f"{name} text is not supported; save the OBJ as UTF-8")
    if b"\x00" in raw:
        raise MeshFileError("holds NUL bytes (UTF-16/32 text or binary data), not OBJ "
                            "text; save the OBJ as UTF-8")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        pass
    lines = []
    for number, line in enumerate(raw.removeprefix(b"\xef\xbb\xbf").split(b"\n"), 1):
        try:
            lines.append(line.decode("utf-8"))
            continue
        except UnicodeDecodeError as error:
            bad = error.start
        hash_at = line.find(b"#")
        if hash_at < 0 or hash_at > bad:
            raise MeshFileError(
                f"line {number}: byte 0x{line[bad]:02x} is not UTF-8 and is not inside "
                "a comment; save the OBJ as UTF-8") from None
        # The comment is dropped: it holds no geometry.
        lines.append(line[:hash_at].decode("utf-8"))
    return "\n".join(lines)


_VERTEX_LINE = re.compile(r"^[ \t]*v[ \t]+([^\n]*)", re.MULTILINE)


def _count_non_finite(coordinates: np.ndarray) -> int:
    """Rows with a coordinate that is not finite in float32 (NaN, Inf, > 3.4e38)."""
    with np.errstate(over="ignore", invalid="ignore"):
        return int((~np.isfinite(coordinates.astype(np.float32)).all(axis=1)).sum())


def _refuse_non_finite(count: int) -> None:
    if count:
        which = "1 vertex has" if count == 1 else f"{count} vertices have"
        raise MeshFileError(f"{which} coordinates that are not finite in float32 (NaN, "
                            "Inf or beyond 3.4e38)")


def _obj_non_finite(text: str) -> int:
    """Vertex lines with a non-finite coordinate. Counted on the text because
    trimesh's processing silently deletes such vertices and their faces."""
    count = 0
    for rest in _VERTEX_LINE.findall(text):
        try:
            xyz = [float(t) for t in rest.split()[:3]]
        except ValueError:
            continue  # not numbers: trimesh reports the malformed line
        count += _count_non_finite(np.array([xyz]))
    return count


def _parse(path: Path) -> trimesh.Trimesh:
    kind = MESH_FORMATS.get(path.suffix.lower())
    if kind is None:
        known = ", ".join(MESH_FORMATS)
        raise MeshFileError(f"unsupported mesh format {path.suffix or '(none)'!r} "
                            f"(known: {known})")
    try:
        raw = path.read_bytes()
    except OSError as error:
        raise MeshFileError(f"cannot read {path}: {error.strerror}") from None
    if kind == "obj":
        text = decode_obj(raw)
        _refuse_non_finite(_obj_non_finite(text))
        source, options = io.StringIO(text), {"skip_materials": True, "process": True}
    else:
        source, options = io.BytesIO(raw), {"process": False}
    try:
        loaded = trimesh.load(source, file_type=kind, force="mesh", **options)
        if kind == "ply" and isinstance(loaded, trimesh.Trimesh):
            vertices = np.asarray(loaded.vertices, np.float64).reshape(-1, 3)
            _refuse_non_finite(_count_non_finite(vertices))
            loaded.process()  # after counting: processing deletes non-finite vertices
    except MeshFileError:
        raise
    except Exception as error:  # trimesh raises many types on malformed input
        raise MeshFileError(f"not a readable {kind.upper()} mesh "
                            f"({type(error).__name__}: {error})") from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise MeshFileError("holds no triangles")
    if np.asarray(loaded.vertices).ndim != 2 or np.asarray(loaded.vertices).shape[1] != 3:
        raise MeshFileError("vertices must have three coordinates (x, y, z)")
    return loaded


def watertight(positions: np.ndarray, faces: np.ndarray) -> bool:
    """Whether the triangles close a volume: with vertices merged by position (a
    flat-shaded file repeats each corner once per face), every edge is shared by
    exactly two faces (trimesh's ``is_watertight``)."""
    mesh = trimesh.Trimesh(np.asarray(positions, np.float64), faces, process=False)
    mesh.merge_vertices(merge_tex=True, merge_norm=True)
    return bool(mesh.is_watertight)


def load_mesh_file(path: str | Path) -> TriangleMesh:
    """Load OBJ/PLY, merge duplicate vertices, area-weighted smooth normals.

    The result's ``closed`` is whether the mesh is :func:`watertight`.

    Raises
    ------
    MeshFileError
        Unreadable, undecodable or malformed file, no triangles, or vertex
        coordinates that are not finite in float32.
    """
    loaded = _parse(Path(path))
    vertices = np.asarray(loaded.vertices, np.float64)
    uvs = None
    visual = getattr(loaded, "visual", None)
    if visual is not None and getattr(visual, "uv", None) is not None:
        if len(visual.uv) == len(loaded.vertices):
            uvs = np.asarray(visual.uv)
    closed = watertight(vertices, loaded.faces)
    with np.errstate(invalid="ignore", divide="ignore"):
        normals = np.asarray(loaded.vertex_normals)
    return make_mesh(vertices, normals, loaded.faces, uvs, closed=closed)


def builtin_mesh_path(name: str) -> Path:
    """Path of a built-in mesh (``bunny``: the Stanford bunny inside pymeshlab's wheel).

    Raises
    ------
    FileNotFoundError
        With the install command, when the package that ships the mesh is missing.
    """
    if name != "bunny":
        raise FileNotFoundError(f"unknown built-in mesh {name!r} (known: bunny)")
    try:
        import pymeshlab  # noqa: PLC0415 - optional extra `bunny`, only for the bunny
    except ImportError:
        raise FileNotFoundError(
            "builtin:bunny needs the optional extra: pip install 'caustics-harness[bunny]'"
        ) from None
    path = Path(pymeshlab.__file__).parent / "tests" / "sample_meshes" / "bunny.obj"
    if not path.is_file():
        raise FileNotFoundError(f"pymeshlab no longer ships {path}")
    return path
