"""Scenes from other formats: glTF 2.0 here (:func:`read_gltf`); Mitsuba 3 XML needs
Mitsuba and lives in ``renderers.mitsuba.importer``. Both give a :class:`Draft`, which
:func:`write_draft` writes as a scene file with its meshes beside it."""

from scenes.importers.draft import Draft, ImportProblemError, MeshPart, Part, write_draft
from scenes.importers.gltf import read_gltf

__all__ = ["Draft", "ImportProblemError", "MeshPart", "Part", "read_gltf", "write_draft"]
