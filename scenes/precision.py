"""Single-precision limits of a scene: checks that need more than one field.

Both renderers hold scene numbers in float32 (GLSL; Mitsuba's single-precision
variants). The schema already refuses any one number that overflows float32; this
module refuses the values whose *products* in the renderers overflow:

* lengths (every field in metres) beyond :data:`LENGTH_LIMIT`: a scene point is at
  most a centre plus a half-extent (2L per coordinate), so the squared distance
  between two points is at most 3 (4L)² = 48 L², finite in float32 for
  L ≤ 1e18 m (48e36 < 3.4e38);
* the light's radiant power (4π I for point and spot lights, π I for an area light,
  irradiance × the scene's cross-section π R² for a directional light), and an
  area light's radiance I / area and area.

Works on any :class:`~scenes.model.Scene`-shaped object by field metadata and the
light's ``kind``, so :mod:`scenes.model` can call it without an import cycle.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator
from typing import Any

import numpy as np

from scenes.schema import FLOAT32_MAX, float32_overflows

__all__ = ["LENGTH_LIMIT", "length_fields", "precision_problems"]

#: Largest coordinate or extent (m) whose squared distances stay finite in float32.
LENGTH_LIMIT = 1e18


def length_fields(node: Any, path: str = "") -> Iterator[tuple[str, Any]]:
    """Every (field path, value) of a field declared in metres, recursively."""
    for field in dataclasses.fields(node):
        if field.metadata.get("internal"):
            continue
        value = getattr(node, field.name)
        key = field.metadata.get("key") or field.name
        sub = f"{path}.{key}" if path else key
        if dataclasses.is_dataclass(value):
            yield from length_fields(value, sub)
        elif isinstance(value, tuple) and value and dataclasses.is_dataclass(value[0]):
            for i, item in enumerate(value):
                yield from length_fields(item, f"{sub}[{i}]")
        elif field.metadata.get("unit") == "m" and value is not None:
            yield sub, value


def _largest(value: Any) -> float:
    values = value if isinstance(value, tuple) else (value,)
    return max(abs(float(v)) for v in values)


def _scene_radius(scene: Any) -> float:
    """Radius (m) of a sphere about the origin holding every receiver and object,
    from their centres and extents (meshes count by their translation)."""
    reach = 0.0
    for path, value in length_fields(scene):
        if path.startswith(("receivers", "objects")):
            reach = max(reach, _largest(value))
    return math.sqrt(3.0) * 2.0 * reach


def _emission_problems(scene: Any) -> list[tuple[str, str]]:
    light = scene.light
    kind = type(light).kind
    if kind == "directional":
        radius = _scene_radius(scene)
        power = max(light.irradiance) * math.pi * radius**2
        if float32_overflows(power):
            return [("light.irradiance", f"irradiance x the scene's cross-section "
                     f"pi R^2 (R = {radius:.3g} m) is {power:.3g} W, which overflows "
                     "float32 in the renderers")]
        return []
    peak = max(light.intensity)
    problems = []
    if kind == "area":
        area = light.size[0] * light.size[1]
        if float(np.float32(area)) == 0.0:
            return [("light.size", f"area {area:.3g} m^2 rounds to 0 in float32; "
                     "radiance = intensity / area would be infinite")]
        if float32_overflows(peak / area):
            problems.append(("light.intensity", f"radiance intensity / area = "
                             f"{peak / area:.3g} W/(m^2 sr) overflows float32"))
        power = math.pi * peak
    else:
        power = 4.0 * math.pi * peak
    if float32_overflows(power):
        factor = "pi" if kind == "area" else "4 pi"
        problems.append(("light.intensity", f"radiant power {factor} x intensity = "
                         f"{power:.3g} W overflows float32 (largest {FLOAT32_MAX:.3g})"))
    return problems


def precision_problems(scene: Any) -> list[tuple[str, str]]:
    """(field path, message) for every product of ``scene``'s values that the
    renderers form and that is not finite in float32 (see the module docstring)."""
    problems = []
    for path, value in length_fields(scene):
        if _largest(value) > LENGTH_LIMIT:
            problems.append((path, f"{_largest(value):.3g} m is beyond {LENGTH_LIMIT:g} m, "
                             "where squared distances overflow float32 in the renderers"))
    return problems + _emission_problems(scene)
