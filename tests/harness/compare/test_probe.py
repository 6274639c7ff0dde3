"""The caustic probe (harness/compare/probe.py) that lets ``validate`` predict
``compare``: its flux is the reference's, and a caustic that misses every receiver
is an error naming the file and field."""

from __future__ import annotations

import json

import numpy as np

from harness.cli import main
from harness.compare.probe import PROBE_PHOTONS, probe_caustic
from tests.renderers.mitsuba.scenes import (
    glass_sphere,
    ideal_sphere_paths,
    inradius_deficit,
    make_scene,
)

#: Probe runs with distinct seeds, for the probe's own standard error.
SEEDS = 4


def test_probe_flux_is_the_analytic_sphere_flux():
    """Physical requirement: sun straight down (E0 = 10 W/m² per channel) on a glass
    sphere (IOR 1.5, R = 1 m, no Fresnel, no absorption) over a 3 x 3 m receiver: the
    probe's caustic flux is the L T T D flux that lands, 3 E0 π R² times the fraction
    of ideal-sphere rays that land (the same known answer as the reference tracer's
    test in tests/renderers/mitsuba/test_analytic.py). Tolerance: 4 standard errors
    of the mean over SEEDS probe runs, plus the icosphere's flux deficit bound. A
    wrong texel area or photon count in the probe's sum is off by a factor of 256
    or more and fails."""
    e0 = 10.0
    scene = make_scene(light=f'type = "directional"\ndirection = [0.0, 0.0, -1.0]\n'
                             f'irradiance = [{e0}, {e0}, {e0}]', objects=glass_sphere(),
                       receiver_size=3.0, direct=False)
    fluxes = np.array([probe_caustic(scene, seed=s).caustic_flux_w for s in range(SEEDS)])
    mean, se = fluxes.mean(), fluxes.std(ddof=1) / np.sqrt(SEEDS)
    lands, _ = ideal_sphere_paths(1.0, 2.0, 1.5, 1.5)
    expected = 3 * e0 * np.pi * lands.mean()
    deficit = inradius_deficit(scene)
    print(f"probe flux {mean:.4f} ± {se:.4f} W vs expected {expected:.4f} W "
          f"({PROBE_PHOTONS} photons x {SEEDS} seeds)")
    assert abs(mean - expected) < 4 * se + deficit * expected


def test_validate_refuses_a_caustic_that_misses_every_receiver(tmp_path, minimal_scene_text,
                                                                capsys):
    """Regression lock of "every failure is one clear line" ("validate predicts
    compare"): a 1 x 1 m receiver moved 6 m aside of the sphere's caustic
    passes every geometric check, yet its reference holds no caustic, on which
    ``compare`` fails. validate says so in one error line naming the file and the
    receivers, and exits 1; --no-trace skips the probe (exit 0); the good scene's
    JSON entry carries the probe's positive flux."""
    miss = tmp_path / "miss.toml"
    miss.write_text(minimal_scene_text.replace("center = [0.0, 0.0, 0.0]",
                                               "center = [6.0, 6.0, 0.0]")
                    .replace("size = [8.0, 8.0]", "size = [1.0, 1.0]"))
    assert miss.read_text() != minimal_scene_text
    assert main(["validate", str(miss)]) == 1
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert line.startswith(f"error: {miss}: receivers: no caustic: none of {PROBE_PHOTONS}")
    assert main(["validate", "--no-trace", str(miss)]) == 0
    capsys.readouterr()
    good = tmp_path / "good.toml"
    good.write_text(minimal_scene_text)
    assert main(["validate", "--json", str(good)]) == 0
    (entry,) = json.loads(capsys.readouterr().out)["scenes"]
    assert entry["probe_caustic_flux_w"] > 0
