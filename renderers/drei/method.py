"""``drei-caustics``: drei's ``Caustics`` in headless Chromium, as a harness method.

One render: the scene is exported to glTF (``scenes.export``, ``docs/export.md``); a
page loads it with three.js's ``GLTFLoader``, renders the component
(``@pmndrs/vanilla`` ``Caustics``) once per distinct IOR into its float render
targets, reads each caustic texture back, and renders the camera image into a float
target with tone mapping off (:mod:`renderers.drei.driver`); the textures are carried
onto the receiver's (u, v) map conserving their flux (:mod:`renderers.drei.mapping`).
The options come from the scene (:mod:`renderers.drei.params`), which also lists what
the component assumes and the scenes it refuses.

Timing: the page times its own work, one warm-up then ``repeats`` runs, the median of
each: the component's update (its normal, depth and caustic passes and mip chain) per
IOR, and the camera pass, with ``EXT_disjoint_timer_query_webgl2`` GPU timer queries
where the browser offers the extension and no query is void, else
``performance.now()`` around the work plus ``gl.finish()``; ``RenderResult.timer``
says which. Exporting, launching the browser and loading the page are not in them
(``metadata["wall_s"]`` holds the whole call's wall time).
"""

from __future__ import annotations

import dataclasses
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from renderers.drei import bundle as bundles
from renderers.drei import driver
from renderers.drei.mapping import LightCamera, light_affine, receiver_map
from renderers.drei.params import (
    ASSUMPTIONS,
    DEFAULT_WORLD_RADIUS,
    DreiParams,
    drei_params,
    refuse_unrepresentable,
)
from renderers.results import ReceiverMap, RenderResult
from scenes import Scene
from scenes.export import export_gltf
from scenes.geometry import build_geometry

__all__ = ["DREI", "DreiMethod", "DreiRender"]

#: The JavaScript packages the page is built from (renderers/web/package.json pins them).
COMPONENT = "@pmndrs/vanilla 1.25.0 Caustics, three 0.187.0"


@dataclass(frozen=True, eq=False)
class DreiRender:
    """One render with everything behind it (for tests and the docs' numbers).

    Attributes
    ----------
    result : RenderResult
    params : DreiParams
    textures : ndarray, (3, res, res)
        The caustic texture behind each RGB channel, W/m², row 0 at t = 0 (already
        scaled by the channel's share of the irradiance).
    affines : tuple
        Per pass, (A, c): light-space (s, t) from receiver (u, v) (:func:`light_affine`).
    light_cameras : tuple of LightCamera
        Per pass.
    page : dict
        The page's answer (timings, WebGL facts).
    """

    result: RenderResult
    params: DreiParams
    textures: np.ndarray
    affines: tuple[tuple[np.ndarray, np.ndarray], ...]
    light_cameras: tuple[LightCamera, ...]
    page: dict


@dataclass(frozen=True, eq=False)
class DreiMethod:
    """drei's ``Caustics`` as a method (module docstring).

    Parameters
    ----------
    name : str
    world_radius : float
        The component's ``worldRadius`` (m); drei's default.
    repeats : int
        Timed runs in the page after one warm-up.
    timeout : float
        Seconds the page may take.
    browser : playwright Browser, optional
        A running Chromium to open the page on (a test session's); None launches one
        per render.
    """

    name: str = "drei-caustics"
    world_radius: float = DEFAULT_WORLD_RADIUS
    repeats: int = 5
    timeout: float = 300.0
    browser: Any = None
    description: str = ("drei's Caustics (@pmndrs/vanilla) in headless Chromium: one "
                        "refraction, the beam's area ratio drawn where the light meets "
                        "the ground")

    def configure(self, scene: Scene) -> Scene:
        """``scene`` unchanged: the component's texture side is the scene's
        ``caustic_map`` setting (it must be one it can represent).

        Raises
        ------
        renderers.drei.params.DreiSceneError
            A scene the component cannot represent (one line naming the file and field).
        """
        refuse_unrepresentable(scene)
        return scene

    def render(self, scene: Scene) -> RenderResult:
        """Render ``scene`` (module docstring)."""
        return self.render_all(scene).result

    def render_all(self, scene: Scene) -> DreiRender:
        """:meth:`render` with the textures, light camera and page answer behind it."""
        start = time.perf_counter()
        refuse_unrepresentable(scene)
        positions = np.concatenate([o.mesh.positions for o in build_geometry(scene).objects])
        lo, hi = positions.min(axis=0).astype(float), positions.max(axis=0).astype(float)
        params = drei_params(scene, objects_radius=float(np.linalg.norm(hi - lo) / 2),
                             resolution=scene.settings.caustic_map,
                             world_radius=self.world_radius)
        script = bundles.ensure_bundle()
        with tempfile.TemporaryDirectory(prefix="drei-") as folder:
            export = export_gltf(scene, Path(folder) / "scene.glb")
            glb = export.path.read_bytes()
        config = self._config(scene, params)
        if self.browser is not None:
            page = driver.render_page(self.browser, glb=glb, bundle=script, config=config,
                                      timeout=self.timeout)
        else:
            with driver.launch() as browser:
                page = driver.render_page(browser, glb=glb, bundle=script, config=config,
                                          timeout=self.timeout)
        frame = export.frames[0]
        cameras = tuple(LightCamera.from_page(c) for c in page.data["lightCameras"])
        affines = tuple(light_affine(c, frame, height=params.height) for c in cameras)
        # Each pass's texture carried onto the map; each channel takes its IOR's.
        passes = [receiver_map(np.stack([_caustic(page, p)] * 3), affines[p], frame)
                  for p in range(len(params.passes))]
        irradiance = np.stack([params.channel_scale[c] * passes[params.channel_pass[c]]
                               .irradiance[..., 0] for c in range(3)], axis=-1)
        textures = np.stack([params.channel_scale[c] * _caustic(page, params.channel_pass[c])
                             for c in range(3)])
        flux = np.array([params.channel_scale[c] * passes[params.channel_pass[c]]
                         .texture_flux[0] for c in range(3)])
        outside = np.array([params.channel_scale[c] * passes[params.channel_pass[c]]
                            .outside[0] for c in range(3)])
        timings, timer = _timings(page.data)
        metadata = {
            "component": COMPONENT, "options": params.component_options(),
            "iors": list(params.passes), "channel_pass": list(params.channel_pass),
            "channel_scale": list(params.channel_scale), "cos_theta": params.cos_theta,
            "assumptions": list(ASSUMPTIONS),
            "texture_flux_w": flux.tolist(), "flux_outside_receiver_w": outside.tolist(),
            "points_per_texel_side": passes[0].points, "texel_area_m2": passes[0].texel_area,
            "light_camera_far_m": [c["far"] for c in page.data["lightCameras"]],
            "far_after_repeated_updates_m": page.data["farAfterRepeats"],
            "caustics_type": page.data["causticsType"], "webgl": {
                "renderer": page.data["webgl"]["renderer"],
                "timer_query": page.data["webgl"]["timerQuery"]},
            "three": page.data["three"], "page_timings_ms": page.data["timings"],
            "chromium_args": list(driver.CHROMIUM_ARGS) if self.browser is None else None,
            "console_errors": page.data["console_errors"],
            "wall_s": time.perf_counter() - start,
        }
        result = RenderResult(
            renderer=self.name, camera=page.camera,
            receivers=(ReceiverMap(irradiance.astype(np.float32), frame.extent),),
            effects=("refraction.single", *(("dispersion",) if len(params.passes) > 1
                                            else ())),
            timings=timings, timer=timer, metadata=metadata)
        return DreiRender(result, params, textures, affines, cameras, page.data)

    def _config(self, scene: Scene, params: DreiParams) -> dict:
        width, height = scene.camera.resolution
        return {
            "offset": [0.0, -params.height, 0.0],
            "objects": [f"object_{i}" for i in range(len(scene.objects))],
            "receivers": ["receiver_0"],
            "albedo": [list(scene.receivers[0].albedo)],
            "passes": [{"ior": n} for n in params.passes],
            "caustics": params.component_options(),
            "camera": {"width": width, "height": height},
            "directLighting": scene.info.direct_lighting,
            "shadows": scene.info.shadows and scene.info.direct_lighting,
            "repeats": self.repeats,
        }

    def with_options(self, **changes) -> DreiMethod:
        """A copy with some fields changed (``browser``, ``world_radius``, ...)."""
        return dataclasses.replace(self, **changes)


def _caustic(page: driver.PageResult, index: int) -> np.ndarray:
    """Front plus back texture of one pass (the component's plane adds the two)."""
    back = page.back[index]
    return page.front[index] if back is None else page.front[index] + back


def _timings(data: dict) -> tuple[dict[str, float], str]:
    """Seconds per pass and the clock that measured them (module docstring)."""
    t = data["timings"]
    gpu = data["timer"] == "gpu"
    caustic = t["caustics_gpu_ms"] if gpu else t["caustics_wall_ms"]
    camera = t["camera_gpu_ms"] if gpu else t["camera_wall_ms"]
    renderer = data["webgl"]["renderer"]
    timer = (f"EXT_disjoint_timer_query_webgl2 (TIME_ELAPSED) in Chromium, {renderer}"
             if gpu else
             f"performance.now() around the work + gl.finish() in Chromium, {renderer} "
             "(no valid GPU timer query)")
    return ({"caustic_map": sum(caustic) / 1e3, "camera": camera / 1e3},
            f"{timer}; median of {data['repeats']} after a warm-up")


#: The registered method (pyproject's ``caustics_harness.methods`` entry point).
DREI = DreiMethod()
