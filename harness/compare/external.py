"""Images rendered anywhere, scored as a method: :class:`ExternalRender`.

An external renderer's output enters the comparison pipeline
(:func:`harness.compare.pipeline.run_comparison`) as a method whose
:meth:`~ExternalRender.render` reads EXR files instead of rendering
(``docs/scoring-external-renders.md``):

* the camera image: radiance in W m⁻² sr⁻¹, linear (no tone mapping), an ``RGB``
  layer of (H, W) = the scene camera's ``resolution`` (W, H), row 0 at the top;
* receiver ``i``'s map: caustic irradiance in W/m² over the receiver's (u, v)
  extent, an ``RGB`` layer of (H, W) = the scene's ``receiver_map`` (W, H), row 0 at
  vmin (``renderers.results``, ``docs/export.md``).

Either view alone is enough: a view not given is not scored. The files carry no unit
attribute (the harness's own EXRs carry none either): their values are taken in the
units above. A file that is missing, unreadable, of the wrong size or layout, or
holds NaN, Inf or negative values raises :class:`ExternalRenderError` naming the file
and what is wrong, before anything is scored or written.

Time: the harness cannot time a render it did not run. An optional JSON file of the
renderer's own report (``{"frame_ms": 12.3, "device": "..."}``) is carried into the
method's provenance as reported, labelled as not measured by the harness; no
equal-error speedup is computed from it (the cost study needs a GL runner).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from renderers.exr import ExrError, read_exr
from renderers.results import ReceiverMap, RenderResult
from scenes import Scene
from scenes.errors import HarnessError
from scenes.geometry import build_geometry

__all__ = ["NOT_MEASURED", "ExternalRender", "ExternalRenderError", "read_timing"]

#: How a reported time is labelled wherever it is shown.
NOT_MEASURED = "reported by the renderer, not measured by the harness"


class ExternalRenderError(HarnessError, ValueError):
    """An external render's file is missing or unusable (the message names the file
    and what is wrong), or no view was given."""


def read_timing(path: str | Path) -> dict:
    """The renderer's own timing report: a JSON object whose ``frame_ms`` (if present)
    is a non-negative finite number of milliseconds; other keys (``device``, ...) are
    kept as given.

    Raises
    ------
    ExternalRenderError
        The file is missing, not JSON, not an object, or ``frame_ms`` is not a
        non-negative number.
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ExternalRenderError(f"{path}: no such file") from None
    except (OSError, ValueError) as error:
        raise ExternalRenderError(f"{path}: not a JSON timing report ({error})") from None
    if not isinstance(data, dict):
        raise ExternalRenderError(f"{path}: a timing report is a JSON object, "
                                  f"got {type(data).__name__}")
    frame = data.get("frame_ms")
    if frame is not None and (isinstance(frame, bool) or not isinstance(frame, int | float)
                              or not math.isfinite(frame) or frame < 0):
        raise ExternalRenderError(f"{path}: frame_ms must be a non-negative number of "
                                  f"milliseconds, got {frame!r}")
    return data


def _rgb(path: Path, size: tuple[int, int], what: str) -> np.ndarray:
    """The RGB image of ``path``, checked: one ``RGB`` layer of ``size`` = (W, H),
    finite (``read_exr``) and non-negative. ``what`` names the setting ``size`` is."""
    try:
        layers = read_exr(path)
    except ExrError as error:
        raise ExternalRenderError(str(error)) from None
    if set(layers) != {"RGB"} or layers["RGB"].ndim != 3 or layers["RGB"].shape[2] != 3:
        found = ", ".join(f"{name} {'x'.join(map(str, a.shape[2:])) or 1} channel(s)"
                          for name, a in layers.items())
        raise ExternalRenderError(f"{path}: needs one RGB layer (channels R, G, B), "
                                  f"found {found or 'none'}")
    image = layers["RGB"]
    width, height = size
    if image.shape[:2] != (height, width):
        raise ExternalRenderError(f"{path}: {image.shape[1]}x{image.shape[0]} pixels, "
                                  f"but the scene's {what} is {width}x{height}")
    negative = int(np.count_nonzero(image < 0))
    if negative:
        raise ExternalRenderError(f"{path}: {negative} negative values (least "
                                  f"{float(image.min()):.4g}); radiance and irradiance "
                                  "are never negative")
    return image


@dataclass(frozen=True)
class ExternalRender:
    """A render made outside the harness, read from EXR files (module docstring).

    Attributes
    ----------
    camera : Path or None
        The camera image (W m⁻² sr⁻¹); None: the camera is not scored.
    receivers : dict of int to Path
        Receiver index to its irradiance map (W/m²); empty: no receiver is scored.
        When any is given, every receiver of the scene must be.
    timing : dict or None
        The renderer's own timing report (:func:`read_timing`), carried as reported.
    name : str
        The name on the pages.
    description : str
        One line for reports.
    """

    camera: Path | None = None
    receivers: dict[int, Path] = field(default_factory=dict)
    timing: dict | None = None
    name: str = "external"
    description: str = "images rendered outside the harness, read from EXR files"

    def configure(self, scene: Scene) -> Scene:
        """``scene`` unchanged: the images were rendered at its settings."""
        return scene

    def reported_timing(self) -> dict | None:
        """The renderer's report with its label (:data:`NOT_MEASURED`), or None."""
        return None if self.timing is None else {**self.timing, "label": NOT_MEASURED}

    def check_views(self, scene: Scene) -> None:
        """Raise :class:`ExternalRenderError` unless a view is given and the receivers
        given are exactly the scene's (reads no file)."""
        if self.camera is None and not self.receivers:
            raise ExternalRenderError("no image to score: give the camera image, the "
                                      "receiver maps, or both")
        count = len(scene.receivers)
        wrong = sorted(i for i in self.receivers if not 0 <= i < count)
        if wrong:
            raise ExternalRenderError(f"receiver {wrong[0]}: scene {scene.name!r} has "
                                      f"receivers 0..{count - 1}")
        missing = sorted(set(range(count)) - set(self.receivers))
        if self.receivers and missing:
            raise ExternalRenderError(f"receiver {missing[0]}: no map given; give every "
                                      f"receiver's map of scene {scene.name!r} "
                                      f"({count}) or none")

    def render(self, scene: Scene) -> RenderResult:
        """Read and check the files against ``scene``'s settings (module docstring).

        Raises
        ------
        ExternalRenderError
            No view given, a receiver index the scene lacks or one left out, or a
            file missing or unusable (the message names it).
        """
        self.check_views(scene)
        camera = (None if self.camera is None else
                  _rgb(Path(self.camera), tuple(scene.camera.resolution), "camera resolution"))
        maps = [_rgb(Path(self.receivers[i]), tuple(scene.settings.receiver_map),
                     "receiver_map") for i in sorted(self.receivers)]
        extents = ([tuple(float(e) for e in g.extent) for g in build_geometry(scene).receivers]
                   if maps else [])
        metadata = {"files": {"camera": None if self.camera is None else str(self.camera),
                              **{f"receiver{i}": str(p) for i, p in
                                 sorted(self.receivers.items())}}}
        if self.timing is not None:
            metadata["reported_timing"] = self.reported_timing()
        return RenderResult(
            renderer="external", camera=camera,
            receivers=tuple(ReceiverMap(m, e) for m, e in zip(maps, extents, strict=True)),
            effects=(), timer=NOT_MEASURED if self.timing else "", metadata=metadata)
