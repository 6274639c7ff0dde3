"""Method targets of the strong preset against the Mitsuba reference, at the scenes'
own settings (issue "Caustic maps without an implementation error floor").

Each bound is the issue's target, with the paper preset's value beside it; every
test also asserts that the paper preset does *not* reach the bound where the issue
says it does not, so the measure can fail. Measured on this machine (llvmpipe,
reference 4 seeds of 2M photons; caustic region = reference above 10 % of its
99.5th percentile):

============================  =================  ==================
measure                        strong             paper
============================  =================  ==================
glass_sphere relMSE            0.00084-0.00086    0.0427
focus peak / reference         0.998              0.47
share within 5 cm (ref 0.351)  0.351              0.166
flux ratio                     0.9985             1.0006
dispersion flux per channel    0.997 0.994 0.990  1.033 1.055 1.090
bunny relMSE                   0.12               0.48
============================  =================  ==================
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.ndimage import uniform_filter

from harness.compare.evaluate import score_value
from harness.compare.regions import caustic_region
from renderers.methods import load_method
from renderers.mitsuba.reference import render_reference
from reports.display import luminance
from scenes import load_scene
from tests.conftest import SCENES


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    """One reference cache for the module (both presets share each reference)."""
    return tmp_path_factory.mktemp("reference-cache")


def _maps(name: str, cache):
    scene = load_scene(SCENES / f"{name}.toml")
    reference = render_reference(scene, cache=cache, progress=False)
    methods = {p: load_method(p).render(scene) for p in ("paper", "strong")}
    return reference.receivers[0], {p: r.receivers[0] for p, r in methods.items()}


def caustic_errors(reference, maps) -> dict[str, float]:
    """Receiver relMSE of each preset over the reference's caustic region."""
    ref = reference.irradiance
    region = caustic_region(ref)
    return {p: score_value("relmse", m.irradiance, ref, mask=region, exposure=None)
            for p, m in maps.items()}


def focus_measures(reference: np.ndarray, method: np.ndarray, extent, *, radius: float):
    """(reference peak, method peak, reference share, method share): the peaks are
    the largest 3 x 3 box means of the luminance (W/m^2; the box tames the photon
    noise of single texels); the shares are the fractions of each map's luminance
    within ``radius`` metres of the reference's peak (the focus)."""
    ref, met = luminance(reference), luminance(method)
    ref_box, met_box = uniform_filter(ref, 3), uniform_filter(met, 3)
    iy, ix = np.unravel_index(np.argmax(ref_box), ref.shape)
    h, w = ref.shape
    u = extent[0] + (np.arange(w) + 0.5) / w * (extent[1] - extent[0])
    v = extent[2] + (np.arange(h) + 0.5) / h * (extent[3] - extent[2])
    near = np.hypot(*np.meshgrid(u - u[ix], v - v[iy])) <= radius
    return (float(ref_box.max()), float(met_box.max()), float(ref[near].sum() / ref.sum()),
            float(met[near].sum() / met.sum()))


def test_glass_sphere_focus_flux_and_error(cache):
    """Method targets: caustic relMSE <= 0.012 (the issue's emulation of filtered
    exits with flux/area triangles reached 0.0095; paper 0.043), focus peak within
    20 % of the reference's (paper 0.47x), share of the flux within 5 cm of the focus
    within 0.03 of the reference's (paper 0.17 vs 0.35), flux ratio within 1 %."""
    reference, maps = _maps("glass_sphere", cache)
    ref = reference.irradiance
    errors = caustic_errors(reference, maps)
    assert errors["strong"] <= 0.012 < errors["paper"]
    ref_peak, peak, ref_share, share = focus_measures(ref, maps["strong"].irradiance,
                                                      reference.extent, radius=0.05)
    assert abs(peak / ref_peak - 1) <= 0.20
    assert abs(share - ref_share) <= 0.03
    _, paper_peak, _, paper_share = focus_measures(ref, maps["paper"].irradiance,
                                                   reference.extent, radius=0.05)
    assert abs(paper_peak / ref_peak - 1) > 0.20 and abs(paper_share - ref_share) > 0.03
    ratio = maps["strong"].total_flux() / reference.total_flux()
    np.testing.assert_allclose(ratio, 1.0, atol=0.01)


def test_dispersion_sphere_flux_per_channel(cache):
    """Method target: flux ratio within 2 % in every channel (paper: +3.3 %, +5.5 %,
    +9.0 %, all of it from rays splatted although their exact path misses the
    floor)."""
    reference, maps = _maps("dispersion_sphere", cache)
    strong = maps["strong"].total_flux() / reference.total_flux()
    paper = maps["paper"].total_flux() / reference.total_flux()
    np.testing.assert_allclose(strong, 1.0, atol=0.02)
    assert np.max(np.abs(paper - 1)) > 0.02


def test_bunny_caustic_error(cache):
    """Method target: caustic relMSE <= 0.25 (paper 0.48)."""
    reference, maps = _maps("bunny", cache)
    errors = caustic_errors(reference, maps)
    assert errors["strong"] <= 0.25 < errors["paper"]
