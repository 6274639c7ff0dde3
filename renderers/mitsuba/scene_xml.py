"""Scene -> Mitsuba 3 XML: the reference's own scene description, written to files.

The XML is :func:`~.exporter.scene_dict` (the dict the reference loads) serialised by
Mitsuba's own writer (``mi.parser.parse_dict`` + ``mi.parser.write_file``), with each
receiver and object as a PLY file beside it (``meshes/receiver_<i>.ply``: the same
float32 positions, vertex normals, faces and, for receivers, (u, v) texture coordinates
that both renderers receive). So the XML and the reference cannot drift apart: there is
no second mapping.

* Objects keep the dict's keys as ids (``id`` and ``name``): shapes ``receiver_<i>`` and
  ``object_<i>``, indexed like the scene's lists, ``light``, ``sensor``, ``integrator``.
* Dielectrics, with ``bsdf="stock"`` (the default), are Mitsuba's own ``dielectric``
  (``int_ior`` = the scene's IOR, ``ext_ior`` = 1): the file loads in any Mitsuba 3
  process. It is the reference's BSDF exactly where the scene weights by Fresnel and
  absorbs nothing; otherwise :func:`stock_differences` names each difference (it always
  weights by Fresnel; it has no Beer-Lambert absorption). With ``bsdf="harness"`` they
  are the reference's own ``chain_dielectric`` (:mod:`.bsdf`: Fresnel only when the
  scene asks, Beer-Lambert absorption on exit), a Python plugin: a process loads that
  XML after registering it (:func:`load_scene_xml` does; any other Mitsuba 3 process
  does so with ``renderers.mitsuba.bsdf.register(mi, dr)``).
* Dispersion (an IOR per channel) is one file per channel pass, ``scene_r.xml``,
  ``scene_g.xml``, ``scene_b.xml``, as the reference renders it: each with that
  channel's IOR and the light's power in that channel only; their sum is the scene.
  Otherwise one file, ``scene.xml``.
* The sensor is the scene camera, the integrator a plain ``ptracer``; units are the
  reference's (W/sr, W/m^2, radiance W m^-2 sr^-1).
* The scene's exact tables (its ``[scene]``, ``[settings]``, light, camera, receivers
  and objects, without this machine's file paths) are a comment at the top of each file
  (:data:`TABLES_MARK`, then JSON), as the glTF export keeps them in its extras: Mitsuba
  ignores it; ``caustics import`` takes them where the file's shapes, BSDFs, emitter and
  sensor still agree with them, so that an export imports back as the same scene (a
  water surface's waves, the IORs of every dispersion channel, the renderer settings).

Mitsuba's parser does not know a Python plugin's object type, so for ``bsdf="harness"``
the writer is handed a stock ``dielectric`` in its place and the plugin's name is put
back on those nodes before writing (each is recognised by its ``tir_reflects``
property, which only ``chain_dielectric`` has).
"""

from __future__ import annotations

import json
from pathlib import Path
from xml.etree import ElementTree

from renderers.mitsuba import _mi
from renderers.mitsuba.bsdf import BSDF_NAME
from renderers.mitsuba.exporter import ExportedScene, exported, mitsuba_mesh, scene_dict
from scenes import effects_of
from scenes.geometry import build_geometry
from scenes.model import DielectricMaterial, Scene
from scenes.tables import portable_table, to_table

__all__ = ["BSDFS", "CHANNEL_FILES", "TABLES_MARK", "load_scene_xml", "stock_differences",
           "write_scene_xml"]

#: The files of a dispersion scene's channel passes (0, 1, 2 = red, green, blue).
CHANNEL_FILES = {None: "scene.xml", 0: "scene_r.xml", 1: "scene_g.xml", 2: "scene_b.xml"}
_STAND_IN = "dielectric"
#: How the XML writes a dielectric: Mitsuba's own BSDF, or the reference's plugin.
BSDFS = ("stock", "harness")
#: Top-level XML elements that are scene objects (``<default>`` is a parameter).
_OBJECTS = {"shape", "emitter", "sensor", "integrator"}
#: The first line of the comment that holds the scene's exact tables (JSON follows).
TABLES_MARK = "caustics-harness scene tables, version 1"


def _stand_in(value, *, stock: bool):
    """``value`` with every ``chain_dielectric`` dict typed as a stock dielectric: with
    ``stock``, Mitsuba's own (relative IOR ``eta`` = ``int_ior`` / ``ext_ior``, the
    outside being vacuum as in the reference); otherwise the plugin's properties kept,
    for :func:`_write` to name the plugin again."""
    if isinstance(value, dict):
        out = {k: _stand_in(v, stock=stock) for k, v in value.items()}
        if out.get("type") == BSDF_NAME:
            if stock:
                return {"type": _STAND_IN, "int_ior": out["eta"], "ext_ior": 1.0}
            out["type"] = _STAND_IN
        return out
    return value


def stock_differences(scene: Scene) -> tuple[str, ...]:
    """Where a stock ``dielectric`` is not the reference's BSDF, one line per object
    (empty where the stock file is the reference's scene exactly).

    Mitsuba's ``dielectric`` reflects with probability F and transmits otherwise, which
    is the reference's rule for ``fresnel = true``; with ``fresnel = false`` the
    reference transmits every photon with weight one (and drops one whose chain meets
    total internal reflection). It has no interior absorption: the reference weights a
    particle leaving the medium by exp(-sigma t).
    """
    lines = []
    for index, obj in enumerate(scene.objects):
        material = obj.material
        if not isinstance(material, DielectricMaterial):
            continue
        where = f"objects[{index}].material"
        if not material.fresnel:
            lines.append(f"{where}: the scene transmits every photon (fresnel = false); "
                         "Mitsuba's dielectric weights by Fresnel")
        if any(s > 0 for s in material.absorption):
            lines.append(f"{where}: absorption {list(material.absorption)} 1/m is not in "
                         "Mitsuba's dielectric (it has no Beer-Lambert term)")
    return tuple(lines)


def _tables(scene: Scene, *, channel: int | None, bsdf: str) -> dict:
    """What the comment holds: the scene's tables (scene coordinates, SI units), which
    channel pass this file is, and how its dielectrics are written."""
    return {
        "name": scene.name, "scene": to_table(scene.info),
        "settings": to_table(scene.settings), "light": to_table(scene.light),
        "camera": to_table(scene.camera),
        "receivers": [portable_table(to_table(r)) for r in scene.receivers],
        "objects": [portable_table(to_table(o)) for o in scene.objects],
        "channel": channel, "bsdf": bsdf,
        "stock_differences": list(stock_differences(scene)) if bsdf == "stock" else [],
    }


def _comment(tables: dict) -> ElementTree.Element:
    # An XML comment may not hold "--"; JSON has it only inside strings, where the
    # escape \u002d reads back as the same "-".
    lines = ",\n".join(f"{json.dumps(k)}: {json.dumps(v)}" for k, v in tables.items())
    text = ("{\n" + lines + "\n}").replace("--", "-\\u002d")
    return ElementTree.Comment(f" {TABLES_MARK}\n{text}\n")


def _write(mi, variant: str, desc: dict, path: Path, *, stock: bool, tables: dict) -> None:
    config = mi.parser.ParserConfig(variant)
    state = mi.parser.parse_dict(config, _stand_in(desc, stock=stock))
    for node in state.nodes:
        props = node.props
        if props.plugin_name() == _STAND_IN and "tir_reflects" in props:
            props.set_plugin_name(BSDF_NAME)
            node.props = props
    mi.parser.write_file(state, str(path))
    # Mitsuba's writer names top-level objects (``name=``) but gives them no ``id``, which
    # is what a loaded object's id() returns (and mi.traverse's keys): add it, as the
    # dict's key.
    tree = ElementTree.parse(path)
    for element in tree.getroot():
        if element.tag in _OBJECTS and element.get("name") is not None:
            element.set("id", element.get("name"))
    comment = _comment(tables)
    comment.tail = "\n\n    "
    tree.getroot().insert(0, comment)
    tree.write(path, encoding="unicode")


def write_scene_xml(scene: Scene, folder: str | Path, *, bsdf: str = "stock"
                    ) -> tuple[Path, ...]:
    """Write ``scene`` as Mitsuba 3 XML into ``folder`` (created if missing).

    Parameters
    ----------
    bsdf : {"stock", "harness"}
        Dielectrics as Mitsuba's own ``dielectric`` (loads anywhere; see
        :func:`stock_differences`) or as the reference's ``chain_dielectric`` plugin.

    Returns
    -------
    tuple of Path
        ``scene.xml``, or the three channel passes of a dispersion scene
        (:data:`CHANNEL_FILES`); the meshes are under ``meshes/`` beside them.
    """
    if bsdf not in BSDFS:
        raise ValueError(f"bsdf must be one of {BSDFS}, not {bsdf!r}")
    mi, _, variant = _mi.load()
    folder = Path(folder)
    (folder / "meshes").mkdir(parents=True, exist_ok=True)
    geometry = build_geometry(scene)

    def ply(name, mesh, bsdf, texcoords):
        relative = f"meshes/{name}.ply"
        mitsuba_mesh(mi, name, mesh, bsdf, texcoords=texcoords).write_ply(str(folder / relative))
        return {"type": "ply", "filename": relative, "bsdf": bsdf}

    channels = [0, 1, 2] if "dispersion" in effects_of(scene) else [None]
    written = []
    for channel in channels:
        desc = scene_dict(scene, geometry=geometry, channel=channel, shape=ply)
        path = folder / CHANNEL_FILES[channel]
        _write(mi, variant, desc, path, stock=bsdf == "stock",
               tables=_tables(scene, channel=channel, bsdf=bsdf))
        written.append(path)
    return tuple(written)


def load_scene_xml(path: str | Path, *, receivers: int, objects: int) -> ExportedScene:
    """Load an XML file :func:`write_scene_xml` wrote, either ``bsdf`` (the
    ``chain_dielectric`` plugin registered first), with its shapes' registry ids.

    Raises
    ------
    KeyError
        A receiver or object the counts name is missing from the file.
    """
    mi, _, _ = _mi.load()
    return exported(mi.load_file(str(path)), receivers=receivers, objects=objects)
