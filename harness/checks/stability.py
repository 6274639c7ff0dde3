"""Numerical stability of a render: finite outputs, counted losses, energy bounds.

The energy bound: caustic flux on the receivers can never exceed the flux the light
sends through the caustic objects. We bound that from above with each object's
bounding sphere (centre c, radius R):

* point/spot/area light of intensity I at distance D: I Ω with the sphere's solid
  angle Ω = 2π (1 − √(1 − (R/D)²)) (the light inside the sphere: no bound, inf);
* directional light of irradiance E0: E0 π R²;
* an open water surface: E0 times its area projected on the light's direction
  (its bounding sphere would be loose but still a bound; this one is tight).
"""

from __future__ import annotations

import numpy as np

from harness.raycast import ReceiverTracer, SurfaceTracer
from harness.studies.convergence import OUTCOMES, classify, texel_footprint
from renderers.caustics_mapping.caustic_trace import STATUS
from renderers.caustics_mapping.lights import light_setups
from renderers.caustics_mapping.presets import resolve_settings
from renderers.results import RenderResult
from scenes.geometry import SceneGeometry
from scenes.model import DirectionalLight, Scene, WaterSurface

__all__ = ["UNFOUND", "convergence_outcomes", "estimate_outcomes", "incident_flux_bound",
           "off_receiver_flux", "search_outcomes", "stability_summary"]


def incident_flux_bound(scene: Scene, geometry: SceneGeometry) -> np.ndarray:
    """Upper bound (W, RGB) of the flux the light sends through the caustic objects."""
    light = scene.light
    total = np.zeros(3)
    for obj, geo in zip(scene.objects, geometry.objects, strict=True):
        points = geo.mesh.positions.astype(np.float64)
        lo, hi = points.min(axis=0), points.max(axis=0)
        centre = (lo + hi) / 2
        radius = float(np.linalg.norm(points - centre, axis=1).max())
        if isinstance(light, DirectionalLight):
            power = np.asarray(light.irradiance, float)
            if isinstance(obj, WaterSurface):
                d = np.asarray(light.direction, float)
                cos = abs(d[2]) / np.linalg.norm(d)
                total += power * obj.size[0] * obj.size[1] * cos
            else:
                total += power * np.pi * radius**2
            continue
        position = np.asarray(getattr(light, "position", getattr(light, "center", centre)), float)
        distance = float(np.linalg.norm(centre - position))
        if distance <= radius:
            return np.full(3, np.inf)
        solid_angle = 2 * np.pi * (1 - np.sqrt(1 - (radius / distance) ** 2))
        total += np.asarray(light.intensity, float) * solid_angle
    return total


def off_receiver_flux(geometry: SceneGeometry, hits: dict[str, np.ndarray]) -> float:
    """Share of the traced flux (summed over channels) splatted by vertices whose
    exact ray (Mitsuba's ray tracing from the record's v along its r) meets no
    receiver: splats that should not exist."""
    status = hits["status"]
    per_vertex = hits["flux"].sum(axis=1)
    traced = float(per_vertex[status != STATUS["empty"]].sum())
    splatted = status == STATUS["hit"]
    if traced <= 0 or not splatted.any():
        return 0.0
    exact = ReceiverTracer(geometry)(hits["origin"][splatted], hits["direction"][splatted])
    return float(per_vertex[splatted][~np.isfinite(exact.distance)].sum()) / traced


#: Statuses of a traced vertex whose search ended without a verified hit.
UNFOUND = ("lost", "unconverged", "diverged")
#: The exact ray starts this far (m, per metre of the scene's receivers' extent) along
#: its direction from the record's origin, which lies on the surface it leaves (in
#: float32): without it a ray may meet its own surface at distance ~0.
_SPAWN = 1e-5
#: An object met closer than this (m, per metre of the receivers' extent) to the origin
#: is the origin's own surface, and the ray is cast again from past it (twice at most):
#: the method's origins are image-space points that can lie just inside the mesh
#: (glass_sphere's exit points at radius 0.9998 met the icosphere's facets within
#: 0.8 mm: 0.83 % of its traced flux read "meets an object" without this).
_OWN_SURFACE = 1e-3


def search_outcomes(scene: Scene, geometry: SceneGeometry,
                    hits: dict[str, np.ndarray]) -> dict[str, float]:
    """What became of the traced flux whose search ended without a verified hit
    (statuses :data:`UNFOUND`), by the exact ray from each such record's origin
    along its direction (Mitsuba's ray tracing on the scene's own triangles, the
    objects included):

    * ``leaves_scene_flux_fraction``: the ray meets nothing: the light leaves the
      scene off every receiver (physics: the reference does not count it either);
    * ``meets_object_flux_fraction``: it meets a caustic object first, a chain
      longer than the method models (the reference does not count it); an object
      met within ``_OWN_SURFACE`` of the scene's extent is taken for the origin's own
      surface, and the ray goes on past it;
    * ``estimator_failed_flux_fraction``: it meets a receiver first: a hit the
      method should have found and did not (the share a physical requirement bounds).

    and, by the same exact rays, what the method's own tests ended as re-entering an
    object (status ``reentered``: the exit ray's slab test, the reflected ray's
    crossing, contact and facet-side tests) while the ray meets a receiver first:

    * ``reentered_reaches_receiver_flux_fraction``: light the method's tests dropped
      that the reference counts (on ``scenes/hard/concave``'s shallow bowl under a
      45 deg sun, 2.9 % of the floor's flux at grid 128 before the crossing test's
      depth spread: grazing reflections off the outer wall's lit sliver, judged
      crossing the sheet they leave; 0.0015 % of the traced flux after).

    Each is a share of the traced flux (the non-empty vertices', summed over
    channels; ``hits`` holds every traced vertex at its ``flux`` share, as
    :meth:`renderers.caustics_mapping.Frame.traced_records` gives them). The first
    three add up to the :data:`UNFOUND` statuses' share.
    """
    status = np.asarray(hits["status"]).astype(int)
    per_vertex = np.asarray(hits["flux"], np.float64).sum(axis=1)
    traced = float(per_vertex[status != STATUS["empty"]].sum())
    unfound = np.isin(status, [STATUS[name] for name in UNFOUND])
    reentered = status == STATUS["reentered"]
    out = {"leaves_scene_flux_fraction": 0.0, "meets_object_flux_fraction": 0.0,
           "estimator_failed_flux_fraction": 0.0,
           "reentered_reaches_receiver_flux_fraction": 0.0}
    judged = unfound | reentered
    if traced <= 0 or not judged.any():
        return out
    origin = np.asarray(hits["origin"], np.float64)[judged]
    direction = np.asarray(hits["direction"], np.float64)[judged]
    direction = direction / np.linalg.norm(direction, axis=1, keepdims=True)
    extent = max((float(np.max(np.abs(g.mesh.positions))) for g in geometry.receivers),
                 default=1.0)
    tracer = SurfaceTracer(scene, geometry)
    start = origin + _SPAWN * extent * direction
    exact = tracer(start, direction)
    travelled = np.zeros(len(start))
    for _ in range(2):
        own = (exact.kind == SurfaceTracer.OBJECT) & (
            travelled + exact.distance < _OWN_SURFACE * extent)
        if not own.any():
            break
        step = np.where(own, exact.distance + _SPAWN * extent, 0.0)
        travelled += step
        start = start + step[:, None] * direction
        again = tracer(start[own], direction[own])
        for field in ("kind", "distance"):
            getattr(exact, field)[own] = getattr(again, field)
    flux = per_vertex[judged]
    was_unfound = unfound[judged]
    for key, kind in (("leaves_scene_flux_fraction", SurfaceTracer.NONE),
                      ("meets_object_flux_fraction", SurfaceTracer.OBJECT),
                      ("estimator_failed_flux_fraction", SurfaceTracer.RECEIVER)):
        out[key] = float(flux[was_unfound & (exact.kind == kind)].sum()) / traced
    out["reentered_reaches_receiver_flux_fraction"] = float(
        flux[~was_unfound & (exact.kind == SurfaceTracer.RECEIVER)].sum()) / traced
    return out


def stability_summary(scene: Scene, geometry: SceneGeometry, result: RenderResult,
                      convergence=None, *, hits: dict[str, np.ndarray] | None = None) -> dict:
    """What the report shows under "Numerical stability" for one render.

    Keys: ``finite`` (every output finite), ``negative_values`` (the number of
    negative values over the camera image and receiver maps, and ``min_value`` the
    least value: radiance and irradiance are never negative), ``lost_splats`` and
    ``lost_fraction``,
    ``flux_over_bound`` (receiver caustic flux / incident bound, must be <= 1),
    the flux shares ``tir_flux_fraction`` (lost to total internal reflection at the
    exit surface), ``unconverged_flux_fraction`` (held back by verified hits) and,
    given the per-vertex records ``hits``, ``off_receiver_flux_fraction``
    (:func:`off_receiver_flux`) and the fates of the vertices left without a verified
    hit (:func:`search_outcomes`); and, when a convergence table is given, the
    safeguarded estimators' outcomes at the most iterations measured (``diverged``
    and ``oscillating`` must be 0).
    """
    # A view the method did not give (RenderResult.camera None, no receivers) is not
    # checked.
    arrays = ([result.camera] if result.camera is not None else []) + [
        m.irradiance for m in result.receivers]
    finite = bool(all(np.isfinite(a).all() for a in arrays))
    negative = int(sum(np.count_nonzero(np.asarray(a) < 0) for a in arrays))
    least = float(min(np.nanmin(a) if np.size(a) else 0.0 for a in arrays))
    counts = result.metadata.get("status_counts") or {}
    traced = sum(v for k, v in counts.items() if k != "empty") or 1
    lost = int(result.metadata.get("lost_splats", 0))
    bound = incident_flux_bound(scene, geometry)
    flux = sum(m.total_flux() for m in result.receivers)
    ratio = float(np.max(np.where(bound > 0, flux / np.maximum(bound, 1e-300), 0.0)))
    summary = {"finite": finite, "negative_values": negative, "min_value": least,
               "lost_splats": lost, "lost_fraction": lost / traced,
               "flux_over_bound": ratio, "energy_ok": ratio <= 1.0 + 1e-3}
    shares = result.metadata.get("status_flux_fraction") or {}
    for status in ("tir", "unconverged"):
        if status in shares:
            summary[f"{status}_flux_fraction"] = float(shares[status])
    if hits is not None:
        summary["off_receiver_flux_fraction"] = off_receiver_flux(geometry, hits)
        summary |= search_outcomes(scene, geometry, hits)
    if convergence is not None:
        summary |= convergence_outcomes(convergence)
    return summary


def estimate_outcomes(scene: Scene, geometry: SceneGeometry, hits: dict[str, np.ndarray],
                      *, tolerance_texels: float = 1.0) -> dict[str, float]:
    """Outcome shares of the estimator's runs, judged from the history of its
    estimates against exact ray casts, never from the status the renderer assigned
    (:func:`harness.studies.convergence.classify`: ``diverged`` = the last estimate
    is not finite, negative or over 10x the exact distance; ``oscillating`` = the
    last two steps change sign, the last at least 3/4 of the one before and over a
    texel). Vertices whose exact ray meets no receiver are left out; so are those
    the trace never estimated (empty, total internal reflection, no exit, re-entered).

    Returns the share of each outcome (:data:`OUTCOMES`) and ``count`` (vertices
    judged)."""
    status = hits["status"].astype(int)
    traced = ~np.isin(status, [STATUS["empty"], STATUS["tir"], STATUS["no_exit"],
                               STATUS["reentered"]])
    exact = ReceiverTracer(geometry)(hits["origin"][traced], hits["direction"][traced])
    history = hits["history"][traced].astype(np.float64)
    lost = status[traced] == STATUS["lost"]
    points = np.where(np.isfinite(exact.position), exact.position, hits["origin"][traced])
    # One caustic-map texel at the exact hit, seen from the light that traced it.
    settings = resolve_settings(scene.settings)
    setups = light_setups(scene, geometry, frustum_fit=settings.frustum)
    which = hits.get("light", np.zeros(len(status)))[traced].astype(int)
    texel = texel_footprint(setups, which, points, size=settings.caustic_map)
    outcome = classify(history, lost, exact.distance, texel,
                       tolerance_texels=tolerance_texels)
    judged = outcome != ""
    count = int(judged.sum())
    shares = {name: float((outcome == name).sum()) / max(count, 1) for name in OUTCOMES}
    return {**shares, "count": count}


def convergence_outcomes(convergence) -> dict:
    """The stability summary's entries from a convergence table
    (``harness.studies.convergence_study``): the safeguarded estimators' outcomes at
    the most iterations measured (``diverged`` and ``oscillating`` must be 0), and
    plain Newton's oscillating share there."""
    rows = convergence.records()
    last = max(r["iteration"] for r in rows)
    out = {}
    for r in rows:
        if r["safeguarded"] and r["iteration"] == last:
            out[f"{r['estimator']} (safeguarded), {last} iterations"] = {
                k: round(float(r[k]), 4) for k in ("converged", "stalled", "lost",
                                                   "diverged", "oscillating")}
        if r["estimator"] == "newton" and not r["safeguarded"] and r["iteration"] == last:
            out["plain newton oscillating"] = round(float(r["oscillating"]), 4)
    return out
