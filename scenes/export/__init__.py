"""Scenes written for renderers outside the process: glTF 2.0 (:mod:`.gltf`), with the
axis conversion and receiver frames of :mod:`.frames` and the chord tolerance of
:mod:`.tessellation`. The mapping both ways is ``docs/export.md``."""

from scenes.export.frames import GLTF_FROM_SCENE, ReceiverFrame, receiver_frame, to_gltf
from scenes.export.gltf import UNITS, GltfExport, export_gltf
from scenes.export.tessellation import (
    DEFAULT_RELATIVE_TOLERANCE,
    Tessellation,
    default_tolerance,
    tessellate,
)

__all__ = ["DEFAULT_RELATIVE_TOLERANCE", "GLTF_FROM_SCENE", "UNITS", "GltfExport",
           "ReceiverFrame", "Tessellation", "default_tolerance", "export_gltf",
           "receiver_frame", "tessellate", "to_gltf"]
