"""The strong preset's adjoint shading-normal factor (``shading_factor`` in
``caustic_trace.glsl``): each grid vertex's flux is the exact path's of the same light
ray (``harness.studies.exact_paths``: Mitsuba's ray casts on the same triangles and
vertex normals, Veach's factor |d.n_s| |d'.n_g| / (|d.n_g| |d'.n_s|) at the event, as
the reference's photons carry it).

Kind: **physical requirement** (the method carries the reference's transport on meshes
with interpolated normals). Measured at grid 64, small maps, no rim patches (llvmpipe):
the relative flux difference over the vertices both call a hit has its 99th
percentile at 1.7e-5 on bowl_sun (493 vertices) and bowl_deep_sun75 (46); with the
factor off, 91 % and 96 % of them differ by more than 1 % (median 5 % and 15 %), so
the check can fail. A closed dielectric's exit (spot_torus) is left out: its
image-space exit point is not the exact one (p95 0.5 %, p99 6.7 %), which the
decomposition study measures as the image-space geometry error."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from harness.raycast import SurfaceTracer
from harness.studies.exact_paths import exact_paths
from renderers.caustics_mapping import caustic_trace, light_sample, render_frame
from renderers.caustics_mapping.caustic_trace import STATUS
from scenes.geometry import build_geometry

from .conftest import ROOT, small_scene

SCENES = ("bowl_sun", "hard/concave/bowl_deep_sun75")
#: Largest relative difference of the 99th percentile: float32 against float64 normals
#: at grazing incidence (measured 1.7e-5), with room for another GL's rounding.
TOLERANCE = 1e-3


def _flux_ratios(ctx, name: str, *, factor: bool) -> np.ndarray:
    scene = small_scene(ROOT / "scenes" / f"{name}.toml", preset="strong", grid=64,
                        rim_patches=1)
    geometry = build_geometry(scene)
    exact = exact_paths(scene, geometry, SurfaceTracer(scene, geometry))
    records = np.concatenate([r for light in exact.records for r in light])
    options = caustic_trace.trace_options
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(light_sample, "trace_options", lambda s, e: dataclasses.replace(
            options(s, e), shading_correction=factor))
        hits = render_frame(scene, ctx=ctx, geometry=geometry).hits
    both = (hits["status"] == STATUS["hit"]) & (records[:, 2, 3] == STATUS["hit"])
    assert both.sum() > 40, name
    return hits["flux"][both, 1] / records[both, 3, 1]


@pytest.mark.physical_requirement
@pytest.mark.parametrize("name", SCENES)
def test_each_vertex_carries_the_exact_paths_flux(context_factory, name):
    """Physical requirement: 99 % of the hit vertices' flux within 1e-3 of the exact
    path's; the same vertices without the factor mostly are not (more than half off
    by over 1 %)."""
    ctx = context_factory()
    on = np.abs(_flux_ratios(ctx, name, factor=True) - 1.0)
    off = np.abs(_flux_ratios(ctx, name, factor=False) - 1.0)
    assert np.percentile(on, 99) <= TOLERANCE, np.percentile(on, [50, 99, 100])
    assert (off > 0.01).mean() > 0.5, np.percentile(off, [50, 99])
