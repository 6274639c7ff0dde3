"""Kernels drawn in boxes along their own axes (``TIGHT_BOXES``: long Gaussians as
rectangles, long quads' triangles in oriented boxes) give each pixel the share the
axis-aligned sprites and boxes give it: the receiver maps agree to float32 rounding
and the flux is the same. Kind: regression lock (the axis-aligned drawing is the
reference; both are the method's own splats)."""

from __future__ import annotations

import numpy as np
import pytest

from renderers.caustics_mapping import caustic_splat, render
from tests.renderers.caustics_mapping.conftest import ROOT, small_scene

pytestmark = pytest.mark.regression_lock


@pytest.mark.parametrize("name", ["bunny", "glass_sphere"])
def test_tight_boxes_give_every_pixel_its_share(name, monkeypatch):
    """Bunny (folds: long footprint Gaussians) and glass sphere (rim slivers: long
    quads), strong preset at the small settings: the maps differ (the boxes were
    drawn: blending order and llvmpipe's partial-block shading change the last bits)
    by at most 1e-5 of the map's peak (measured 2.6e-7 on the bunny, 1e-8 on the
    sphere), and the flux by at most 1e-6 (measured equal in float32). Boxes that
    missed pixels fail it: Gaussians' boxes at 0.8 of their half axes lose 0.8 % of
    the bunny's flux, quads' boxes grown by 0.3 px instead of half a pixel diagonal
    42 % of the sphere's."""
    scene = small_scene(ROOT / "scenes" / f"{name}.toml", preset="strong")
    tight = render(scene).receivers[0].irradiance
    monkeypatch.setattr(caustic_splat, "TIGHT_BOXES", False)
    aligned = render(scene).receivers[0].irradiance
    assert not np.array_equal(tight, aligned)
    peak = aligned.max()
    assert np.abs(tight - aligned).max() <= 1e-5 * peak
    assert abs(tight.sum() / aligned.sum() - 1.0) <= 1e-6
