"""``[animation]``: bad fields name the file and the field path; the frames move
what the section says, by the amounts its velocities give (known answers worked out
from the definitions in ``scenes.animation``), and the geometry both renderers get
follows the frame's time."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from scenes import SceneError, load_scene
from scenes.animation import animation_frames, animation_of, scene_at
from scenes.geometry import build_geometry
from tests.conftest import MINIMAL_SCENE, SCENES

RING = """
[[objects]]
type = "ring"
center = [2.0, 0.0, 0.0]
radius = 0.5
height = 0.3
material = { type = "conductor", reflectance = [0.9, 0.9, 0.9] }
"""
CUBE = """
[[objects]]
type = "mesh"
file = "cube.obj"
material = { type = "conductor", reflectance = [0.9, 0.9, 0.9] }
transform = { translate = [-2.0, 0.0, 1.0] }
"""
WATER = """
[[objects]]
type = "water_surface"
center = [0.0, 0.0, 1.0]
size = [4.0, 4.0]
resolution = [161, 161]
material = { type = "dielectric", ior = 1.33 }
time = 0.5
[[objects.plops]]
position = [0.0, 0.0]
amplitude = 0.05
wavelength = 0.2
speed = 0.8
width = 0.05
damping = 0.0
start = 0.0
"""


def _scene(tmp_path, extra: str, *, objects: str = "", name: str = "anim.toml"):
    path = tmp_path / name
    text = MINIMAL_SCENE.replace("[camera]", objects + "\n[camera]") + extra
    path.write_text(text, encoding="utf-8")
    return path


def _errors(path) -> list[str]:
    with pytest.raises(SceneError) as info:
        load_scene(path)
    lines = str(info.value).splitlines()
    for line in lines:
        assert line.startswith(f"{path}: "), f"problem does not name the file: {line}"
    return [line.removeprefix(f"{path}: ") for line in lines]


@pytest.mark.parametrize(("section", "expected"), [
    ("[animation]\nframes = 1\n", "animation.frames: must be >= 2, got 1"),
    ("[animation]\nfps = 0.0\n", "animation.fps: must be > 0, got 0"),
    ("[animation]\nframes = 2.5\n", "animation.frames: expected an integer, got 2.5"),
    ("[animation]\nspeed = 2\n", "animation.speed: unknown key"),
    ("[animation.light]\nvelocity = [1.0, 0.0]\n",
     "animation.light.velocity: expected an array of 3 numbers, got 2"),
    ("[[animation.objects]]\nindex = 3\n",
     "animation.objects[0].index: must name an object: the scene has 1 (0 to 0)"),
    ("[[animation.objects]]\nindex = -1\n", "animation.objects[0].index: must be >= 0"),
    ("[[animation.objects]]\nvelocity = [0.0, 0.0, 1.0]\n",
     "animation.objects[0].index: missing required field"),
    ("[[animation.objects]]\nindex = 0\nangular_velocity = [0.0, 0.0, 10.0]\n",
     "animation.objects[0].angular_velocity: must be zero: a sphere has no orientation"),
    ("[[animation.objects]]\nindex = 0\n[[animation.objects]]\nindex = 0\n",
     "animation.objects[1].index: object 0 already moves in animation.objects[0]"),
    ("[animation.light]\nangular_velocity = [0.0, 0.0, 5.0]\n",
     "animation.light.angular_velocity: must be zero: a point light has no direction"),
])
def test_a_bad_animation_field_is_one_error_naming_file_and_field(tmp_path, section, expected):
    """Each bad ``[animation]`` value gives a SceneError whose one line names the
    scene file and the field path (the schema's and the section's own checks)."""
    lines = _errors(_scene(tmp_path, section))
    assert len(lines) == 1, lines
    assert lines[0].startswith(expected), lines


def test_a_directional_light_cannot_move_and_a_water_surface_cannot_turn(tmp_path):
    """A directional light has no position and a water surface no orientation: both
    motions are refused, each naming its field."""
    path = tmp_path / "pool.toml"
    text = (SCENES / "water_pool.toml").read_text("utf-8").split("[animation]")[0]
    text += ("[animation.light]\nvelocity = [0.1, 0.0, 0.0]\n"
             "[[animation.objects]]\nindex = 0\nangular_velocity = [1.0, 0.0, 0.0]\n")
    path.write_text(text, encoding="utf-8")
    lines = _errors(path)
    assert any(line.startswith("animation.light.velocity: must be zero: a directional")
               for line in lines), lines
    assert any(line.startswith("animation.objects[0].angular_velocity: must be zero: a water")
               for line in lines), lines


def test_a_frame_that_leaves_single_precision_is_an_error_naming_the_time(tmp_path):
    """A velocity that carries an object beyond the renderers' float32 range (1e18 m,
    ``scenes.precision``) fails at the first frame where it does, naming that time."""
    path = _scene(tmp_path, "[animation]\nframes = 3\nfps = 1.0\n"
                  "[[animation.objects]]\nindex = 0\nvelocity = [0.0, 0.0, 1e30]\n")
    scene = load_scene(path)  # frame 0 is the scene as written: legal
    with pytest.raises(SceneError) as info:
        animation_frames(scene)
    message = str(info.value)
    assert message.startswith(f"{path}: animation (at τ = 1 s): objects[0].center: ")
    assert "beyond 1e+18 m" in message


def test_frames_are_the_scene_at_start_plus_i_over_fps(tmp_path):
    """Known answers from the definitions: frame i is at τ = start + i / fps; a point
    light moves to p + v τ; a directional light's direction turns by ω τ (90°/s about
    z for 1 s takes (1, 0, -1) to (0, 1, -1)); frame 0 at start 0 is the scene as
    written, less its animation."""
    path = _scene(tmp_path, "[animation]\nframes = 4\nfps = 2.0\nstart = 0.5\n"
                  "[animation.light]\nvelocity = [1.0, -2.0, 0.5]\n")
    scene = load_scene(path)
    frames = animation_frames(scene)
    assert [f.index for f in frames] == [0, 1, 2, 3]
    assert [f.time for f in frames] == pytest.approx([0.5, 1.0, 1.5, 2.0])
    assert frames[3].scene.light.position == pytest.approx((2.0, -4.0, 7.0))
    assert all(f.scene.animation is None for f in frames)
    assert scene_at(scene, 0.0) == dataclasses.replace(scene, animation=None)

    sun = load_scene(SCENES / "water_pool.toml")
    sun = dataclasses.replace(sun, light=dataclasses.replace(sun.light,
                                                             direction=(1.0, 0.0, -1.0)))
    spin = dataclasses.replace(animation_of(sun), light=dataclasses.replace(
        animation_of(sun).light, angular_velocity=(0.0, 0.0, 90.0)))
    turned = scene_at(sun, 1.0, animation=spin).light.direction
    assert turned == pytest.approx((0.0, 1.0, -1.0), abs=1e-12)


def test_objects_move_and_turn_as_their_motions_say(tmp_path):
    """A ring's axis turned 90°/s about x for 1 s goes from +z to -y (R_x(90°) (0, 0, 1));
    a mesh spinning 180°/s about z for 1 s has every vertex at (-x, -y) about its
    origin, then moved by v τ; the sphere's centre moves by v τ."""
    path = _scene(tmp_path, "[animation]\n"
                  "[[animation.objects]]\nindex = 0\nvelocity = [0.0, 0.25, 0.0]\n"
                  "[[animation.objects]]\nindex = 1\nangular_velocity = [90.0, 0.0, 0.0]\n"
                  "[[animation.objects]]\nindex = 2\nvelocity = [0.0, 0.0, 0.5]\n"
                  "angular_velocity = [0.0, 0.0, 180.0]\n", objects=RING + CUBE)
    (tmp_path / "cube.obj").write_bytes((SCENES / "meshes" / "cube.obj").read_bytes())
    scene = load_scene(path)
    moved = scene_at(scene, 1.0)
    assert moved.objects[0].center == pytest.approx((0.0, 0.25, 2.0))
    assert moved.objects[1].axis == pytest.approx((0.0, -1.0, 0.0), abs=1e-12)
    assert moved.objects[1].center == scene.objects[1].center

    still = build_geometry(scene).objects[2].mesh.positions.astype(np.float64)
    spun = build_geometry(moved).objects[2].mesh.positions.astype(np.float64)
    origin = np.array([-2.0, 0.0, 1.0])
    expected = (still - origin) * np.array([-1.0, -1.0, 1.0]) + origin + [0.0, 0.0, 0.5]
    np.testing.assert_allclose(spun, expected, atol=1e-5)
    assert not np.allclose(spun, still, atol=1e-2)


def test_a_plop_ring_spreads_at_its_speed_in_the_built_geometry(tmp_path):
    """Physical requirement of the animated water (paper Fig. 8): the geometry both
    renderers get at frame i is the surface at ``time`` + τ_i, so the crest of a
    plop's ring (speed 0.8 m/s, undamped, 5 cm wide) is 0.8 m/s × 0.5 s = 0.4 m
    further out five frames (0.5 s at 10 fps) later; the grid spacing (2.5 cm) bounds
    the error."""
    path = _scene(tmp_path, "[animation]\nframes = 6\nfps = 10.0\n",
                  objects=WATER)
    scene = load_scene(path)
    frames = animation_frames(scene)
    radii = []
    for frame in (frames[0], frames[5]):
        mesh = build_geometry(frame.scene).objects[1].mesh
        p = mesh.positions.astype(np.float64)
        radius = np.hypot(p[:, 0], p[:, 1])
        radii.append(float(radius[np.argmax(p[:, 2])]))
    assert radii[0] == pytest.approx(0.8 * 0.5, abs=0.05)
    assert radii[1] - radii[0] == pytest.approx(0.8 * 0.5, abs=0.025 * 2)


def test_a_scene_without_animation_animates_only_its_water_time():
    """No ``[animation]``: 24 frames at 30 fps (the defaults); the glass sphere's frames
    are all the scene itself (a still scene), ``--frames`` replaces the count, and a
    sequence of fewer than two frames is refused."""
    scene = load_scene(SCENES / "glass_sphere.toml")
    frames = animation_frames(scene)
    assert len(frames) == 24 and frames[-1].time == pytest.approx(23 / 30)
    assert all(f.scene == frames[0].scene for f in frames)
    assert len(animation_frames(scene, frames=3)) == 3
    with pytest.raises(SceneError, match=r"animation\.frames: must be an integer >= 2"):
        animation_of(scene, frames=1)


def test_the_bundled_water_pool_is_animated():
    """water_pool carries its ``[animation]`` (24 frames, 30 fps): its frames advance
    the water's time by 1/30 s each."""
    scene = load_scene(SCENES / "water_pool.toml")
    frames = animation_frames(scene)
    assert len(frames) == 24
    times = [f.scene.objects[0].time for f in frames]
    assert np.diff(times) == pytest.approx(np.full(23, 1 / 30))
    assert times[0] == scene.objects[0].time
