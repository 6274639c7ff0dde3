"""The scene tables an exported Mitsuba XML file carries in its comment
(:data:`~renderers.mitsuba.scene_xml.TABLES_MARK`), and whether the file's own shapes,
BSDFs, emitter and sensor still agree with them.

The import takes a table only where the part Mitsuba loaded agrees with it: the same
role and material (type; a dielectric's IOR in the file's channel, and for the
harness's own BSDF its Fresnel switch and absorption; a conductor's reflectance; a
diffuse albedo), a light of the same type at the same place and direction, a camera at
the same eye looking the same way. A part edited after the export is read from the
file as if the comment were not there.
"""

from __future__ import annotations

import json
from pathlib import Path
from xml.etree import ElementTree

import numpy as np

from renderers.mitsuba.scene_xml import TABLES_MARK
from scenes.importers.draft import ImportProblemError

__all__ = ["camera_agrees", "light_agrees", "material_agrees", "read_tables", "shape_table"]

#: Relative tolerance of a position or value read back through Mitsuba's float32.
_RTOL = 1e-5


def read_tables(path: Path) -> dict:
    """The comment's tables, or ``{}`` where the file has none (a file the harness did
    not write).

    Raises
    ------
    ImportProblemError
        The comment is there but its JSON does not parse (it was edited).
    """
    parser = ElementTree.XMLParser(target=ElementTree.TreeBuilder(insert_comments=True))
    root = ElementTree.parse(path, parser).getroot()
    for node in root:
        text = (node.text or "").strip() if node.tag is ElementTree.Comment else ""
        if not text.startswith(TABLES_MARK):
            continue
        try:
            tables = json.loads(text[len(TABLES_MARK):])
        except json.JSONDecodeError as error:
            raise ImportProblemError([f"{path}: the comment '{TABLES_MARK}' is not valid "
                                      f"JSON ({error}); delete the comment to import the "
                                      "file's own shapes"]) from None
        return tables if isinstance(tables, dict) else {}
    return {}


def shape_table(tables: dict, shape_id: str) -> tuple[str, dict] | None:
    """(role, table) of an exported shape (ids ``receiver_<i>``, ``object_<i>``)."""
    role, _, index = shape_id.rpartition("_")
    listed = tables.get(f"{role}s") if role in {"receiver", "object"} else None
    if not index.isdigit() or not isinstance(listed, list) or int(index) >= len(listed):
        return None
    table = listed[int(index)]
    return (role, table) if isinstance(table, dict) else None


def _close(a, b) -> bool:
    a, b = np.asarray(a, float).ravel(), np.asarray(b, float).ravel()
    return a.shape == b.shape and bool(np.allclose(a, b, rtol=_RTOL, atol=_RTOL))


def _unit(vector) -> np.ndarray:
    v = np.asarray(vector, float)
    return v / np.linalg.norm(v)


def material_agrees(role: str, table: dict, read: dict | None, *, channel: int | None,
                    bsdf: str) -> bool:
    """Whether the material Mitsuba loaded (``read``, the importer's table of it) is the
    exact table's: a receiver's albedo, an object's material in the file's channel.
    A ``stock`` file's dielectric always weights by Fresnel and absorbs nothing, so only
    its IOR is compared (the comment lists those differences)."""
    if read is None:
        return False
    if role == "receiver":
        return read["type"] == "diffuse" and _close(read["albedo"], table.get("albedo"))
    exact = table.get("material") or {}
    if read["type"] != exact.get("type"):
        return False
    if read["type"] == "diffuse":
        return _close(read["albedo"], exact.get("albedo", [0.5] * 3))
    if read["type"] == "conductor":
        return _close(read["reflectance"], exact.get("reflectance", [1.0] * 3))
    iors = np.resize(np.asarray(exact.get("ior", 1.5), float), 3)
    if not _close(read["ior"], iors[0 if channel is None else channel]):
        return False
    return bsdf == "stock" or (
        read["fresnel"] == exact.get("fresnel", True)
        and _close(read["absorption"], exact.get("absorption", [0.0] * 3)))


def light_agrees(table: dict, read: dict) -> bool:
    """The same type of light at the same position and pointing the same way (its power
    may be one channel's: a dispersion pass)."""
    if table.get("type") != read.get("type"):
        return False
    if "position" in read and not _close(table.get("position"), read["position"]):
        return False
    return "direction" not in read or _close(_unit(table.get("direction")),
                                             _unit(read["direction"]))


def camera_agrees(table: dict, read: dict) -> bool:
    """The same eye looking the same way (the loaded look-at point is a choice)."""
    def forward(camera):
        return _unit(np.subtract(camera["look_at"], camera["position"]))

    try:
        return _close(table["position"], read["position"]) and _close(forward(table),
                                                                        forward(read))
    except (KeyError, TypeError, ValueError):
        return False
