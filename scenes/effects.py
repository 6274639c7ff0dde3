"""The one place that decides which physical effects a scene calls for.

Both renderers ask :func:`effects_of`: the caustics-mapping renderer runs only the
passes these effects need, and the Mitsuba reference counts only the light paths
they describe. Names are stable strings, shown in results and reports.
"""

from __future__ import annotations

from scenes.model import (
    ConductorMaterial,
    DielectricMaterial,
    MeshObject,
    RingObject,
    Scene,
    WaterSurface,
)

__all__ = ["EFFECTS", "effects_of", "event_chain"]

#: Every effect name, in the order results list them, with its meaning.
EFFECTS: dict[str, str] = {
    "refraction.single": "one refraction at an open surface (water), then the receiver",
    "refraction.double": "refraction into and out of a closed dielectric (Wyman 2005)",
    "reflection": "one specular reflection off a conductor",
    "absorption": "Beer-Lambert attenuation exp(-K_a d) inside the medium (paper Eq. 7)",
    "dispersion": "a different IOR per RGB channel (paper Fig. 13b)",
    "shadows": "caustic objects occlude the light's direct illumination of receivers",
    "fresnel": "specular events are weighted by the Fresnel factor",
    "open_mesh": "a mesh object is not watertight: rendered as an open surface, with no "
    "back-face culling (the shadow map included); a conductor reflects on both sides",
}


def _is_open(obj: object) -> bool:
    return isinstance(obj, (WaterSurface, RingObject))


def effects_of(scene: Scene) -> tuple[str, ...]:
    """Effects the scene calls for, as a tuple ordered like :data:`EFFECTS`.

    Rules
    -----
    * a dielectric on an open surface (water surface, ring) -> ``refraction.single``;
      on a closed one (sphere, mesh) -> ``refraction.double``;
    * a conductor -> ``reflection``;
    * a dielectric with any non-zero absorption coefficient -> ``absorption``;
    * a dielectric whose three channel IORs differ -> ``dispersion``;
    * ``scene.shadows`` and ``scene.direct_lighting`` both on -> ``shadows``;
    * any specular material with ``fresnel = true`` -> ``fresnel``;
    * a mesh object whose mesh is not watertight (legal for conductors and diffuse
      objects; refused for dielectrics) -> ``open_mesh``. Only this rule reads the
      mesh files (through :func:`scenes.geometry.build_geometry`, cached).
    """
    found: set[str] = set()
    for obj in scene.objects:
        material = obj.material
        if isinstance(material, DielectricMaterial):
            found.add("refraction.single" if _is_open(obj) else "refraction.double")
            if any(k > 0 for k in material.absorption):
                found.add("absorption")
            if len(set(material.iors)) > 1:
                found.add("dispersion")
        elif isinstance(material, ConductorMaterial):
            found.add("reflection")
        if getattr(material, "fresnel", False):
            found.add("fresnel")
    if scene.info.shadows and scene.info.direct_lighting:
        found.add("shadows")
    if _has_open_mesh(scene):
        found.add("open_mesh")
    return tuple(name for name in EFFECTS if name in found)


def _has_open_mesh(scene: Scene) -> bool:
    meshes = [i for i, obj in enumerate(scene.objects) if isinstance(obj, MeshObject)]
    if not meshes:
        return False
    # scenes.geometry brings trimesh and scipy (about 1 s); only mesh scenes get here.
    from scenes.geometry import build_geometry  # noqa: PLC0415 - keeps `import scenes` light

    objects = build_geometry(scene).objects
    return any(not objects[i].mesh.closed for i in meshes)


def event_chain(obj: object) -> str:
    """The specular event chain light takes through one caustic object.

    ``T`` is a transmission, ``R`` a specular reflection, ``D`` the diffuse receiver:
    a closed dielectric is ``L T T D``, a water surface ``L T D``, a conductor
    ``L R D``; a diffuse object forms no caustic (``""``).
    """
    material = obj.material
    if isinstance(material, DielectricMaterial):
        return "L T D" if _is_open(obj) else "L T T D"
    if isinstance(material, ConductorMaterial):
        return "L R D"
    return ""
