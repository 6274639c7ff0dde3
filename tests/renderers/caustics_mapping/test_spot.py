"""The spot light on the caustics-mapping side, against its analytic falloff.

The method applies the spot's falloff in one GLSL function (``light_falloff`` in
``common.glsl``): to the flux of each grid texel and to the direct light of the
camera pass. The camera pass's direct light is compared here, pixel by pixel, with
the closed form that the reference's test (``tests/renderers/mitsuba/test_spot.py``)
holds the photon tracer to: L = albedo / pi * I f(theta) cos(theta_n) / r^2, with
f Mitsuba's spot profile (1 inside the beam width, linear in the angle to 0 at the
cutoff). Nothing here is noisy: the shader evaluates the formula at each pixel's
centre in float32, so the bounds are rounding (and the GL implementation's acos).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from renderers.caustics_mapping import render_frame
from scenes import load_scene, parse_scene, with_settings
from tests.renderers import spot_profile
from tests.renderers.caustics_mapping.conftest import ROOT

POSITION = np.array([0.3, -0.2, 2.5])
AXIS = np.array([-0.2, 0.1, -1.0])
INTENSITY = np.array([10.0, 20.0, 30.0])
CUTOFF, BEAM = 35.0, 15.0
ALBEDO = 0.5
EYE, TARGET, FOV, SIZE = np.array([0.0, -2.0, 7.0]), np.array([0.0, 0.0, 0.0]), 50.0, 64

SCENE = f"""
[scene]
name = "spot_bare"

[light]
type = "spot"
position = {POSITION.tolist()}
direction = {AXIS.tolist()}
intensity = {INTENSITY.tolist()}
cutoff_angle = {CUTOFF}
beam_width = {BEAM}

[[receivers]]
type = "plane"
center = [0.0, 0.0, 0.0]
size = [8.0, 8.0]
albedo = [{ALBEDO}, {ALBEDO}, {ALBEDO}]

[[objects]]                 # far outside the cone: the scene model needs one object
type = "sphere"
center = [50.0, 50.0, 50.0]
radius = 0.1
subdivisions = 1
material = {{ type = "dielectric", ior = 1.5 }}

[camera]
position = {EYE.tolist()}
look_at = {TARGET.tolist()}
fov = {FOV}
resolution = [{SIZE}, {SIZE}]

[settings]
grid = 32
caustic_map = 64
positions_map = 128
shadow_map = 256
receiver_map = [32, 32]
"""


#: The profile of this module's spot (tests/renderers/spot_profile.py).
falloff = functools.partial(spot_profile.falloff, cutoff=CUTOFF, beam=BEAM)
smoothstep_falloff = functools.partial(spot_profile.smoothstep_falloff, cutoff=CUTOFF,
                                       beam=BEAM)


def _pixel_floor_points() -> np.ndarray:
    """World point on z = 0 seen through each pixel's centre, (H, W, 3), row 0 at
    the top (the pinhole camera of the scene: fov along x, square image)."""
    forward = (TARGET - EYE) / np.linalg.norm(TARGET - EYE)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    t = math.tan(math.radians(FOV) / 2)
    ndc = (np.arange(SIZE) + 0.5) / SIZE * 2 - 1
    x, y = np.meshgrid(ndc * t, -ndc * t)
    d = forward + x[..., None] * right + y[..., None] * up
    return EYE - (EYE[2] / d[..., 2])[..., None] * d


def _geometry(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """theta (deg from the spot axis) and albedo/pi * I cos(theta_n) / r^2, (H, W, 3)."""
    rel = points - POSITION
    r = np.linalg.norm(rel, axis=-1)
    axis = AXIS / np.linalg.norm(AXIS)
    theta = np.degrees(np.arccos(np.clip(rel @ axis / r, -1.0, 1.0)))
    return theta, ALBEDO / np.pi * (POSITION[2] / r**3)[..., None] * INTENSITY


def test_direct_light_under_a_spot_is_albedo_over_pi_i_falloff_cos_over_r2(ctx):
    """Physical requirement: the method's camera image of a bare floor under a
    tilted spot (beam 15 deg, cutoff 35 deg) is L = albedo/pi * I f(theta)
    cos(theta_n) / r^2: inside the beam within 1e-5 relative (float32); in the
    falloff ring the profile read back, f = L / (albedo/pi * I cos / r^2), within
    1e-3 of f(theta) (the GL implementation's acos: llvmpipe's is off by ~1e-4 rad,
    2e-4 in f); exactly zero beyond the cutoff. The check can fail: a hard edge and
    pbrt's smoothstep profile differ from f by more than 0.05."""
    scene = parse_scene(SCENE, file="<spot_bare>")
    image = render_frame(scene, ctx=ctx).result.camera
    theta, scale = _geometry(_pixel_floor_points())
    expected = falloff(theta)
    measured = image / scale
    beam, beyond = theta < BEAM - 0.1, theta > CUTOFF + 0.1
    ring = ~beam & ~beyond
    beam_error = np.abs(measured[beam] - 1.0).max()
    profile_error = np.abs(measured - expected[..., None]).max()
    print(f"spot camera: beam rel. error {beam_error:.1e}, max |f - f(theta)| "
          f"{profile_error:.1e}; pixels: {beam.sum()} beam, {ring.sum()} ring, "
          f"{beyond.sum()} beyond")
    assert beam.sum() > 100 and ring.sum() > 300 and beyond.sum() > 300
    assert beam_error < 1e-5
    assert profile_error < 1e-3
    assert np.all(image[beyond] == 0.0)
    for wrong in (falloff(theta, cutoff=CUTOFF, beam=CUTOFF), smoothstep_falloff(theta)):
        assert np.abs(wrong - expected).max() > 0.05


def test_the_falloff_is_never_negative_just_inside_the_cutoff(ctx):
    """``light_falloff`` over the 262,144 float32 cosines just above cos(cutoff) (a
    band of 0.016 rad) for cutoffs of 26..40 degrees, where llvmpipe's acos rounds past
    the cutoff angle by up to 6e-5 rad (measured) and the unclamped linear ramp gave
    down to -1.8e-4: every value is in [0, 1] and within 1e-3 of the float64 ramp
    (4e-4 = 6e-5 rad over the 0.14 rad ramp, rounded up)."""
    source = (
        "#version 430\n#define COMPUTE_SHADER\n" + _common_glsl() + """
layout(local_size_x = 64) in;
layout(std430, binding = 0) buffer Values { float values[]; };
void main() {
    uint i = gl_GlobalInvocationID.x;
    float c = values[i];
    values[i] = light_falloff(c * u_light_dir + sqrt(max(1.0 - c * c, 0.0)) * vec3(1, 0, 0));
}""")
    program = ctx.compute_shader(source)
    for cutoff in (26.0, 30.0, 35.0, 40.0):
        cut, beam = math.radians(cutoff), math.radians(0.4 * cutoff)
        cosines = (np.float32(math.cos(cut))
                   + np.arange(1, 64 * 4096 + 1, dtype=np.float32) * np.float32(6e-8))
        buffer = ctx.buffer(cosines.astype(np.float32).tobytes())
        buffer.bind_to_storage_buffer(0)
        program["u_light_type"] = 1
        program["u_light_dir"] = (0.0, 0.0, -1.0)
        program["u_spot"] = (math.cos(cut), math.cos(beam), cut, beam)
        program.run(len(cosines) // 64)
        values = np.frombuffer(buffer.read(), np.float32)
        buffer.release()
        exact = (cut - np.arccos(cosines.astype(np.float64))) / (cut - beam)
        assert values.min() >= 0.0 and values.max() <= 1.0, cutoff
        assert np.abs(values - exact).max() < 1e-3, cutoff


def _common_glsl() -> str:
    """``common.glsl``, which includes no other file."""
    return (ROOT / "renderers" / "caustics_mapping" / "common.glsl").read_text()


def test_no_negative_pixel_on_the_spot_torus(ctx):
    """The bundled spot_torus scene (its spot's cutoff ring on the floor in the
    camera's view) renders with no negative value in the camera image or the
    receiver map under either preset; before the falloff was clamped, 14 (paper) and
    11 (strong) camera pixels were negative at its own settings."""
    for preset in ("paper", "strong"):
        scene = with_settings(load_scene(ROOT / "scenes" / "spot_torus.toml"),
                              {"preset": preset})
        result = render_frame(scene, ctx=ctx, lookups=False).result
        assert result.camera.min() >= 0.0, preset
        # The lit disc (radius about 3 m, the cutoff) fills 28 % of the image.
        assert (result.camera > 0).mean() > 0.2, preset
        for receiver in result.receivers:
            assert receiver.irradiance.min() >= 0.0, preset
