"""Energy: the radiometric normalisation gives physical flux.

Analytic scene (pbrt-v4 style, carrying its expected value): glass_sphere's sphere
(radius R = 1 m, IOR 1.5, no Fresnel, no absorption) under a vertical directional
light of irradiance E0 = 10 W/m^2, over an 8 m floor. Every ray through a sphere
leaves it (no total internal reflection for a sphere), but the rays through the
sphere's rim leave so steeply that they pass the floor's edge: the caustic flux on
the floor is E0 pi R^2 F, with F the share of parallel rays through an exact sphere
that land on the floor, traced here in closed form (:func:`floor_fraction`,
F = 0.9678).

Paper preset, threshold 5 % (the bound set before the Mitsuba reference
existed); measured at grid 64: -0.15 % against E0 pi R^2 F, two errors cancelling
(spurious TIR from nearest-texel exit normals loses flux, rays that pass the
floor's edge are splatted anyway). Strong preset, threshold 0.5 %: the exact
silhouette coverage of the grid and verified hits leave only the grid's sampling;
measured at grid 128: +0.07 %.
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
IOR = 1.5
CENTRE_Z = 2.0
FLOOR_HALF = 4.0


def floor_fraction(samples: int = 2000) -> float:
    """Share of vertical parallel rays through the exact sphere (refracted in and
    out, Snell's law) that land on the floor |x|, |y| <= 4 m at z = 0."""
    u = (np.arange(samples) + 0.5) / samples * 2 - 1
    x, y = np.meshgrid(u * RADIUS, u * RADIUS)
    inside = x**2 + y**2 < RADIUS**2
    x, y = x[inside], y[inside]
    centre = np.array([0.0, 0.0, CENTRE_Z])
    entry = np.stack([x, y, CENTRE_Z + np.sqrt(RADIUS**2 - x**2 - y**2)], axis=1)

    def refract(d, n, eta):
        c = -(d * n).sum(axis=1, keepdims=True)
        k = 1 - eta**2 * (1 - c**2)
        return eta * d + (eta * c - np.sqrt(np.maximum(k, 0))) * n, k[:, 0] < 0

    down = np.broadcast_to([0.0, 0.0, -1.0], entry.shape)
    inner, _ = refract(down, (entry - centre) / RADIUS, 1 / IOR)
    chord = -2 * ((entry - centre) * inner).sum(axis=1, keepdims=True)
    exit_point = entry + chord * inner
    out, tir = refract(inner, -(exit_point - centre) / RADIUS, IOR)
    assert not tir.any()                       # a sphere cannot trap light
    landing = exit_point - (exit_point[:, 2] / out[:, 2])[:, None] * out
    on_floor = (out[:, 2] < 0) & np.all(np.abs(landing[:, :2]) <= FLOOR_HALF, axis=1)
    return float(on_floor.mean())


def _scene(extra_settings: str = ""):
    text = (ROOT / "scenes" / "glass_sphere.toml").read_text()
    light = text[text.index("[light]"):text.index("[[receivers]]")]
    text = text.replace(light, f'[light]\ntype = "directional"\ndirection = [0.0, 0.0, -1.0]\n'
                              f"irradiance = [{E0}, {E0}, {E0}]\n\n")
    text = text.replace("resolution = [512, 512]", "resolution = [32, 32]")
    settings = {"grid": "64", "caustic_map": "256", "positions_map": "256",
                "receiver_map": "[128, 128]"}
    for line in extra_settings.splitlines():
        if "=" in line:
            key, value = (part.strip() for part in line.split("=", 1))
            settings[key] = value
    text += "\n[settings]\n" + "".join(f"{k} = {v}\n" for k, v in settings.items())
    return parse_scene(text, file="glass_sphere_directional", base_dir=Path(ROOT / "scenes"))


def test_total_caustic_flux_is_intercepted_flux(ctx):
    """Paper preset: receiver-map flux within 5 % of E0 pi R^2 F; no splat lost (the
    paper's final check accepts any estimate with a receiver behind it)."""
    frame = render_frame(_scene(), ctx=ctx)
    flux = frame.result.receivers[0].total_flux()
    expected = E0 * math.pi * RADIUS**2 * floor_fraction()
    np.testing.assert_allclose(flux, expected, rtol=0.05)
    assert frame.result.metadata["lost_splats"] == 0


def test_strong_preset_lands_exactly_the_floor_share(ctx):
    """Strong preset: receiver-map flux within 0.5 % of E0 pi R^2 F (physical
    requirement, tolerance from the grid's silhouette sampling at grid 128); the rays
    that pass the floor's edge end unconverged (not splatted), carrying the rest."""
    frame = render_frame(_scene('preset = "strong"\ngrid = 128\n'), ctx=ctx)
    flux = frame.result.receivers[0].total_flux()
    share = floor_fraction()
    np.testing.assert_allclose(flux, E0 * math.pi * RADIUS**2 * share, rtol=0.005)
    unconverged = frame.result.metadata["status_flux_fraction"]["unconverged"]
    np.testing.assert_allclose(unconverged, 1 - share, atol=0.005)


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
