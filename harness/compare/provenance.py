"""Where a comparison's numbers come from: the method's render and its timing, both
references, and the machine (:class:`~reports.records.Provenance`)."""

from __future__ import annotations

import os
import platform

from harness.compare.scoring import References
from harness.compare.timed import TimedRender
from renderers.methods import Method
from reports.records import MethodProvenance, Provenance

__all__ = ["REFERENCE_KEYS", "machine", "method_provenance", "provenance"]

#: The reference's metadata recorded in the provenance.
REFERENCE_KEYS = ("photons", "photon_budget", "spp", "seed", "seeds", "relative_noise",
                  "target_noise", "stopped_by", "event_chains", "variant", "versions",
                  "camera_integrator", "camera_max_depth", "camera_limits", "cache", "hash")
#: The independent reference's metadata recorded in the provenance.
INDEPENDENT_KEYS = ("seed", "seeds", "relative_noise", "cache")


def machine() -> dict:
    """Platform, processor, CPU count and Python version of this process."""
    return {"platform": platform.platform(), "processor": platform.processor(),
            "cpus": os.cpu_count(), "python": platform.python_version()}


def method_provenance(method: Method, render: TimedRender) -> MethodProvenance:
    """The method's side: its render's passes, status counts and timing."""
    result = render.result
    data = result.metadata
    caustics_mapping = render.hits is not None
    passes = data.get("passes")
    return MethodProvenance(
        name=method.name, renderer=result.renderer, timer=render.timer,
        frame_time_ms=render.warm_seconds * 1e3,
        timings_ms={k: v * 1e3 for k, v in result.timings.items()},
        maps_time_ms=render.maps_seconds * 1e3 if render.maps_seconds is not None else None,
        preset=data.get("preset"), passes=tuple(passes) if passes is not None else None,
        gl_renderer=render.gl_renderer, lost_splats=data.get("lost_splats"),
        status_counts=data.get("status_counts"),
        status_flux_fraction=data.get("status_flux_fraction"),
        metadata={} if caustics_mapping else dict(data))


def provenance(scene_file: str, method: Method, render: TimedRender, references: References,
               *, notes: tuple[str, ...] = (), reference_noise: dict | None = None,
               checks_not_applied: dict | None = None,
               crosscheck: dict | None = None, sweep: dict | None = None) -> Provenance:
    """The provenance of one comparison; ``reference_noise`` is the reference's
    relative noise per channel over each view's scored caustic region."""
    reference, independent = references
    return Provenance(
        scene_file=scene_file, method=method_provenance(method, render),
        reference={**{k: reference.metadata.get(k) for k in REFERENCE_KEYS},
                   "relative_noise_scored": reference_noise or {},
                   "timings_s": reference.timings, "timer": reference.timer},
        independent_reference={k: independent.metadata.get(k) for k in INDEPENDENT_KEYS},
        machine=machine(), notes=notes, checks_not_applied=checks_not_applied or {},
        crosscheck=crosscheck, sweep=sweep)
