"""Energy: the radiometric normalisation gives physical flux.

Analytic scene (pbrt-v4 style, carrying its expected value): glass_sphere's sphere
(radius R = 1 m, IOR 1.5, no Fresnel, no absorption) under a vertical directional
light of irradiance E0 = 10 W/m^2, over an 8 m floor that catches the whole caustic.
Every ray through a sphere leaves it (no total internal reflection for a sphere),
so the caustic flux on the floor is the flux intercepted, E0 * pi * R^2.

Threshold 5 %: the issue's acceptance bound until the Mitsuba reference lands.
Measured at grid 64: -3.4 % (the image-space exit point of Wyman's approximation is
poor in the outermost ring of the silhouette, where its error turns some exit rays
into total internal reflection); grid 128: -1.7 %.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from renderers.caustics_mapping import render_frame
from scenes import parse_scene

from .conftest import ROOT

E0 = 10.0
RADIUS = 1.0


def _scene(extra_settings: str = ""):
    text = (ROOT / "scenes" / "glass_sphere.toml").read_text()
    light = text[text.index("[light]"):text.index("[[receivers]]")]
    text = text.replace(light, f'[light]\ntype = "directional"\ndirection = [0.0, 0.0, -1.0]\n'
                              f"irradiance = [{E0}, {E0}, {E0}]\n\n")
    text = text.replace("resolution = [512, 512]", "resolution = [32, 32]")
    text += ("\n[settings]\ngrid = 64\ncaustic_map = 256\npositions_map = 256\n"
             "receiver_map = [128, 128]\n" + extra_settings)
    return parse_scene(text, file="glass_sphere_directional", base_dir=Path(ROOT / "scenes"))


def test_total_caustic_flux_is_intercepted_flux(ctx):
    """Receiver-map flux within 5 % of E0 pi R^2; no splat lost off the floor."""
    frame = render_frame(_scene(), ctx=ctx)
    flux = frame.result.receivers[0].total_flux()
    expected = E0 * math.pi * RADIUS**2
    np.testing.assert_allclose(flux, expected, rtol=0.05)
    assert frame.result.metadata["lost_splats"] == 0


def test_caustic_map_holds_the_same_flux(ctx):
    """Flux is conserved between the caustic map and the receiver map: the caustic
    map's irradiance times each texel's area on the floor sums to the receiver map's
    flux. For a vertical sun over a horizontal floor a map texel's floor area is
    (2h / M)^2 with h the orthographic half-width. 1 % = the splats the caustic map
    drops where a kernel crosses its outer border (none here) plus float32 sums."""
    frame = render_frame(_scene(), ctx=ctx)
    lookup = frame.lookups[0]
    half = 1.0 / lookup.view_projs[0][0, 0]     # orthographic: m[0, 0] = 1 / h
    size = frame.caustic_map.shape[0]
    caustic_flux = frame.caustic_map.reshape(-1, 3).sum(axis=0) * (2 * half / size) ** 2
    np.testing.assert_allclose(caustic_flux, frame.result.receivers[0].total_flux(), rtol=0.01)
