"""Frames of an animated scene: the scene at each time of its ``[animation]``.

Frame i of ``frames`` is the scene at τ_i = start + i / fps seconds after the scene
as written (``scenes.model.Animation``):

* every water surface is evaluated at its own ``time`` + τ_i (its waves travel, its
  plops spread: ``scenes.geometry.surfaces.water_height``);
* the light's position (point, spot) or centre (area) is p + v τ_i, and its
  direction (spot, directional) or normal (area) is turned by the angles ω τ_i about
  x, then y, then z (the rotation convention of ``transform.rotate``);
* each object of ``animation.objects`` moves by v τ_i: the centre of a sphere, water
  surface or ring, or the ``translate`` of a mesh's transform; a mesh's rotation
  angles grow by ω τ_i, and a ring's axis is turned by the angles ω τ_i.

A scene without ``[animation]`` is animated with the defaults (24 frames at 30 fps,
nothing moving but the water surfaces' time): a scene without water is then a still
scene rendered as a sequence, whose frames are all the same scene.

Each frame is a plain :class:`~scenes.model.Scene` without ``animation``, so both
renderers render it as they render any scene, and it is checked as a scene file is
(a frame that moves a value out of single precision is an error naming the frame).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from scenes.geometry.mesh import transform_matrix
from scenes.model import Animation, MeshObject, Scene, Transform, WaterSurface
from scenes.schema import Problem, SceneError

__all__ = ["AnimationFrame", "animation_frames", "animation_of", "scene_at"]


@dataclass(frozen=True)
class AnimationFrame:
    """One frame of an animation.

    Attributes
    ----------
    index : int
        Frame number, 0 first.
    time : float
        τ, seconds after the scene as written.
    scene : Scene
        The scene at τ (no ``animation``).
    """

    index: int
    time: float
    scene: Scene


def animation_of(scene: Scene, *, frames: int | None = None) -> Animation:
    """The scene's ``[animation]`` (the defaults when it has none), with ``frames``
    replaced when given (``--frames``).

    Raises
    ------
    SceneError
        ``frames`` below 2 (a sequence needs two frames for one difference).
    """
    animation = scene.animation or Animation()
    if frames is None:
        return animation
    if isinstance(frames, bool) or not isinstance(frames, int) or frames < 2:
        raise SceneError([Problem(scene.source or scene.name, "animation.frames",
                                  f"must be an integer >= 2, got {frames!r}")])
    return dataclasses.replace(animation, frames=frames)


def _turn(vector, angles_deg) -> tuple[float, float, float]:
    """``vector`` rotated by ``angles_deg`` about x, then y, then z."""
    if not any(angles_deg):
        return tuple(float(v) for v in vector)
    rotation = transform_matrix(Transform(rotate=tuple(float(a) for a in angles_deg)))[:3, :3]
    return tuple(float(v) for v in rotation @ np.asarray(vector, np.float64))


def _moved(point, velocity, tau: float) -> tuple[float, float, float]:
    return tuple(float(p + v * tau) for p, v in zip(point, velocity, strict=True))


#: Per light kind: the field a velocity moves and the field an angular velocity
#: turns (None where the light has no position or no direction).
_LIGHT_MOTION = {"point": ("position", None), "spot": ("position", "direction"),
                 "directional": (None, "direction"), "area": ("center", "normal")}
#: The same per object kind; a mesh moves and turns its transform instead.
_OBJECT_MOTION = {"sphere": ("center", None), "water_surface": ("center", None),
                  "ring": ("center", "axis")}


def _moved_node(node, fields: tuple[str | None, str | None], velocity, angles, tau: float):
    """``node`` with its ``fields`` (moved, turned) at τ = ``tau``."""
    moves, turns = fields
    changes = {}
    if moves is not None:
        changes[moves] = _moved(getattr(node, moves), velocity, tau)
    if turns is not None:
        changes[turns] = _turn(getattr(node, turns), angles)
    return dataclasses.replace(node, **changes)


def _light_at(light, animation: Animation, tau: float):
    motion = animation.light
    angles = tuple(w * tau for w in motion.angular_velocity)
    return _moved_node(light, _LIGHT_MOTION[type(light).kind], motion.velocity, angles, tau)


def _object_at(obj, motion, tau: float):
    if isinstance(obj, WaterSurface):
        obj = dataclasses.replace(obj, time=obj.time + tau)
    if motion is None:
        return obj
    velocity = motion.velocity
    angles = tuple(w * tau for w in motion.angular_velocity)
    if isinstance(obj, MeshObject):
        t = obj.transform
        transform = dataclasses.replace(
            t, translate=_moved(t.translate, velocity, tau),
            rotate=tuple(float(r + a) for r, a in zip(t.rotate, angles, strict=True)))
        return dataclasses.replace(obj, transform=transform)
    return _moved_node(obj, _OBJECT_MOTION[type(obj).kind], velocity, angles, tau)


def scene_at(scene: Scene, tau: float, *, animation: Animation | None = None) -> Scene:
    """The scene ``tau`` seconds after the scene as written (see the module
    docstring), without ``animation``; ``animation`` defaults to the scene's own.

    Raises
    ------
    SceneError
        The moved scene fails a check a scene file must pass (a length beyond
        single precision, ...); each problem names the time.
    """
    animation = animation or animation_of(scene)
    motions = {m.index: m for m in animation.objects}
    objects = tuple(_object_at(obj, motions.get(i), tau) for i, obj in enumerate(scene.objects))
    moved = dataclasses.replace(scene, light=_light_at(scene.light, animation, tau),
                                objects=objects, animation=None)
    problems = list(moved.validate())
    for path, node in (("light", moved.light), *((f"objects[{i}]", o)
                                                  for i, o in enumerate(moved.objects))):
        check = getattr(node, "validate", None)
        problems += [(f"{path}.{sub}", message) for sub, message in (check() if check else [])]
    if problems:
        where = scene.source or scene.name
        raise SceneError([Problem(where, f"animation (at τ = {tau:g} s): {path}", message)
                          for path, message in problems])
    return moved


def animation_frames(scene: Scene, *, frames: int | None = None) -> tuple[AnimationFrame, ...]:
    """Every frame of the scene's animation (:func:`animation_of`), frame 0 first."""
    animation = animation_of(scene, frames=frames)
    times = animation.start + np.arange(animation.frames) / animation.fps
    return tuple(AnimationFrame(i, float(tau), scene_at(scene, float(tau), animation=animation))
                 for i, tau in enumerate(times))
