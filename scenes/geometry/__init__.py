"""Geometry built once from a scene and handed to both renderers."""

from scenes.geometry.build import (
    ObjectGeometry,
    ReceiverGeometry,
    SceneGeometry,
    build_geometry,
    scene_warnings,
)
from scenes.geometry.mesh import TriangleMesh

__all__ = ["ObjectGeometry", "ReceiverGeometry", "SceneGeometry", "TriangleMesh", "build_geometry",
           "scene_warnings"]
