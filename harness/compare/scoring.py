"""The one scoring function: a method's render against the reference, as ``compare``,
sweep rows and third-party methods are all scored.

:func:`score_render` takes a timed render and the two references (the reference, and
an independent one on disjoint seeds for the noise floor) and returns a
:class:`Scored`: every metric per view and region (``harness.compare.evaluate``),
the images and exposure the report shows, the names of the EXR files, the
numerical-stability summary (``harness.checks.stability``) and both sides' flux
budgets (``harness.compare.budget``).

Views: the camera (regions ``full``, ``object`` — the caustic object seen through,
its silhouette shrunk by a pixel — and ``object_masked``, the rest of the frame) and
each receiver's irradiance map (regions ``full`` and ``caustic``: the scene's caustic
region, thresholded on the independent reference alone and the same for every method,
:func:`harness.compare.regions.scene_caustic_region`; and ``outside``, its
complement, where the ``stray_flux`` record measures light the method puts there).
A ``ptracer`` reference camera cannot see through specular surfaces: its ``object``
region is not scored, and a camera it renders black where the method is lit is left
out with a note.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from harness.checks.stability import stability_summary
from harness.compare.budget import flux_budget, side_budgets
from harness.compare.evaluate import exposure_for, score_view
from harness.compare.regions import object_mask, object_region, scene_caustic_region
from harness.compare.timed import TimedRender
from renderers.mitsuba.noise import relative_noise_per_channel
from renderers.results import RenderResult
from reports.display import difference_range
from reports.records import FluxBudgets, MetricValue
from scenes import Scene, effects_of
from scenes.colour import luminance
from scenes.geometry import SceneGeometry

__all__ = ["References", "Scored", "camera_is_blind", "channel_correlation", "has_caustic",
           "relative_noise", "score_render", "views_of"]


class References(NamedTuple):
    """The reference a render is scored against, and an independent one on disjoint
    seeds (the noise floor)."""

    reference: RenderResult
    independent: RenderResult


class View(NamedTuple):
    """One scored image: the camera or a receiver map, with its regions and the
    variance of the reference's mean (None where it has none)."""

    name: str
    method: np.ndarray
    reference: np.ndarray
    independent: np.ndarray
    regions: dict[str, np.ndarray]
    masks: dict[str, np.ndarray]
    exposure_mask: np.ndarray | None
    variance: np.ndarray | None = None
    #: The reference's per-seed images (K, H, W, 3), where it keeps them.
    seed_maps: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class Scored:
    """What :func:`score_render` measured.

    Attributes
    ----------
    metrics : tuple of MetricValue
        Every metric per view and region, with its noise floor.
    images : dict of str to ndarray
        ``<view>/<kind>`` (``reports.records``): method, reference, signed, ssim, flip,
        masks, and where the reference has a variance, the variance itself, the
        reference's standard error (``stderr``) and the method's z map (``z``).
    exposure : dict
        Per view: ``white``, ``flip_start``, ``flip_stop``, ``diff_range``.
    files : dict of str to str
        EXR files to write: ``<view>/<kind>`` → file name.
    stability : dict
        The numerical-stability summary of the render.
    budgets : FluxBudgets
        Both sides' flux budgets.
    notes : tuple of str
        Views left out, and why.
    reference_noise : dict
        Per view, the reference's relative noise per channel over its scored caustic
        region (:func:`relative_noise`): what every excess interval is made of.
    """

    metrics: tuple[MetricValue, ...]
    images: dict[str, np.ndarray]
    exposure: dict
    files: dict[str, str]
    stability: dict
    budgets: FluxBudgets
    notes: tuple[str, ...] = field(default_factory=tuple)
    reference_noise: dict = field(default_factory=dict)


def channel_correlation(scene: Scene) -> float:
    """The correlation of a reference texel's channel noises: 1 when the same photons
    carry all three channels (white or absorbed light), 0 when the reference traces one
    pass per channel (dispersion)."""
    return 0.0 if "dispersion" in effects_of(scene) else 1.0


def has_caustic(reference: RenderResult) -> bool:
    """Whether the reference's receivers hold any caustic flux. Without any, every
    caustic metric is NaN and the scene poses no question: the comparison's status
    is :data:`reports.records.NO_CAUSTIC`."""
    return sum(float(np.sum(r.total_flux())) for r in reference.receivers) != 0.0


def camera_is_blind(reference: np.ndarray, method: np.ndarray) -> bool:
    """Whether a ``ptracer`` reference camera image is black where the real-time one
    is lit: ptracer cannot connect receivers seen only through a specular surface
    (everything under a water surface). Blind when, over the pixels the real-time
    image lights (above 1 % of its 99th-percentile luminance), the reference holds
    under 10 % of the real-time image's energy. ptracer is unbiased, so this holds at
    any sample count (at 2 spp most pixels are still black), while a few stray
    particles (seabed: about 1 % of the energy) do not make a usable reference. The
    default camera tracer sees through specular surfaces and is never blind."""
    rt = luminance(method)
    top = float(np.percentile(rt, 99))
    if top <= 0:
        return False
    lit = rt > 0.01 * top
    return float(luminance(reference)[lit].sum()) < 0.1 * float(rt[lit].sum())


def views_of(scene: Scene, geometry: SceneGeometry, method: RenderResult,
             references: References) -> tuple[list[View], tuple[str, ...]]:
    """The views to score (module docstring), and notes on any left out."""
    reference, independent = references
    views, notes = [], ()
    ptracer = reference.metadata.get("camera_integrator") == "ptracer"
    if method.camera is None:
        notes += ("camera not scored: the method gave no camera image",)
    elif ptracer and camera_is_blind(reference.camera, method.camera):
        notes += ("camera not compared: the reference camera image is black "
                 "(ptracer cannot see receivers through a specular surface)",)
    else:
        obj = object_mask(scene.camera, geometry)
        regions = {"full": np.ones(obj.shape, bool), "object_masked": ~obj}
        if not ptracer:
            regions["object"] = object_region(scene.camera, geometry)
        views.append(View("camera", method.camera, reference.camera, independent.camera,
                          regions, {"mask_object": obj}, ~obj if ptracer else None,
                          reference.metadata.get("camera_variance")))
    if not method.receivers:
        notes += ("receiver maps not scored: the method gave none",)
        return views, notes
    for i, (method_map, ref_map, ind_map) in enumerate(zip(
            method.receivers, reference.receivers, independent.receivers, strict=True)):
        caustic = scene_caustic_region(ind_map.irradiance)
        views.append(View(f"receiver{i}", method_map.irradiance, ref_map.irradiance,
                          ind_map.irradiance,
                          {"full": np.ones(caustic.shape, bool), "caustic": caustic},
                          {"mask_caustic": caustic}, None, ref_map.variance,
                          ref_map.seed_maps))
    return views, notes


def relative_noise(reference: np.ndarray, variance: np.ndarray, mask: np.ndarray
                   ) -> list[float]:
    """The reference's relative noise per channel over ``mask``: the root mean square of
    each texel's standard error over its value (``v`` the variance of the mean), the
    measure the reference's noise target uses
    (:func:`renderers.mitsuba.noise.relative_noise_per_channel`), here over the region
    the comparison scores."""
    return [float(x) for x in relative_noise_per_channel(reference, variance, mask)]


def _noise_maps(view: View) -> dict[str, np.ndarray]:
    """``<view>/stderr``, the reference mean's standard error per texel and channel
    (the square root of its variance of the mean; the view's units), and ``<view>/z``,
    (method − reference) / stderr per texel and channel (0 where the standard error is
    0: no photon reached the texel in any seed); (H, W, 3) float32 each."""
    stderr = np.sqrt(np.maximum(np.asarray(view.variance, np.float64), 0.0))
    difference = np.asarray(view.method, np.float64) - np.asarray(view.reference, np.float64)
    z = np.divide(difference, stderr, out=np.zeros_like(difference), where=stderr > 0)
    return {f"{view.name}/stderr": stderr.astype(np.float32),
            f"{view.name}/z": z.astype(np.float32)}


def _score_views(views: list[View], *, seeds: int | None, channel_correlation: float):
    """Metrics, images, per-view exposure and EXR file names of every view."""
    metrics, images, files = [], {}, {}
    exposure = {"white": {}, "flip_start": {}, "flip_stop": {}, "diff_range": {}}
    for view in views:
        expo = exposure_for(view.reference, mask=view.exposure_mask)
        values, maps = score_view(view.name, view.method, view.reference, view.independent,
                                  regions=view.regions, exposure=expo, variance=view.variance,
                                  seeds=seeds, channel_correlation=channel_correlation,
                                  seed_estimates=view.seed_maps,
                                  # The camera's pixels share lookup texels' noise.
                                  independent_texels=view.name != "camera")
        metrics += values
        images.update(maps)
        images[f"{view.name}/method"] = np.asarray(view.method, np.float32)
        images[f"{view.name}/reference"] = np.asarray(view.reference, np.float32)
        for name, mask in view.masks.items():
            images[f"{view.name}/{name}"] = mask
        exposure["white"][view.name] = expo.white
        exposure["flip_start"][view.name] = expo.flip_start
        exposure["flip_stop"][view.name] = expo.flip_stop
        # One difference scale per scene, from the reference alone (so known before
        # the first method's page is written): ±25 % of its 99.5th-percentile luminance.
        exposure["diff_range"][view.name] = difference_range(view.reference,
                                                             mask=view.exposure_mask)
        for kind in ("method", "reference", "signed", "ssim", "flip"):
            files[f"{view.name}/{kind}"] = f"{view.name}_{kind}.exr"
        if view.variance is not None:
            images.update(_noise_maps(view))
            for kind in ("stderr", "z"):
                files[f"{view.name}/{kind}"] = f"{view.name}_{kind}.exr"
    return tuple(metrics), images, exposure, files


def _reference_variance(reference: RenderResult, views: list[View]) -> dict[str, np.ndarray]:
    """``<view>/reference_variance``: the variance of the reference's mean per texel
    (receivers) or pixel (the camera, when it is compared), which the physical
    requirements (``harness.checks``) and the report's probes need; not written."""
    out = {f"receiver{i}/reference_variance": np.asarray(m.variance, np.float32)
           for i, m in enumerate(reference.receivers) if m.variance is not None}
    camera = reference.metadata.get("camera_variance")
    if camera is not None and any(v.name == "camera" for v in views):
        out["camera/reference_variance"] = np.asarray(camera, np.float32)
    return out


def score_render(scene: Scene, geometry: SceneGeometry, render: TimedRender,
                 references: References) -> Scored:
    """Score ``render`` of ``scene`` against ``references`` (module docstring)."""
    result = render.result
    views, notes = views_of(scene, geometry, result, references)
    seeds = references.reference.metadata.get("seeds")
    metrics, images, exposure, files = _score_views(
        views, seeds=int(seeds) if seeds else None,
        channel_correlation=channel_correlation(scene))
    images.update(_reference_variance(references.reference, views))
    stability = stability_summary(scene, geometry, result, hits=render.hits)
    sides = side_budgets(scene, result, stability, references.reference, hits=render.hits,
                         geometry=geometry)
    budgets = FluxBudgets(
        summary=flux_budget(result.metadata, stability, result.receivers,
                            references.reference.receivers),
        method=sides["method_budget"], reference=sides["reference_budget"],
        trace=sides["budget_trace"])
    noise = {v.name: relative_noise(v.reference, v.variance, v.regions["caustic"])
             for v in views if v.variance is not None and "caustic" in v.regions
             and v.regions["caustic"].any()}
    return Scored(metrics, images, exposure, files, stability, budgets, notes, noise)
