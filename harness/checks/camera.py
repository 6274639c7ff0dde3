"""Accuracy checks of the camera view over the object: the lens image of a sphere.

Where the ideal-sphere answer describes the scene (one dielectric sphere, planar
receivers, a point or directional light, chain mode:
:func:`harness.checks.analytic.not_applicable`) and there is one receiver, the exact
camera image is known: :func:`harness.checks.sphere_camera.analytic_sphere_camera`
traces the ideal sphere's two refractions to the plane and shades it with the
analytic direct light and the *reference's own* caustic map. Over the pixels inside
the sphere's silhouette (``SphereCamera.interior``):

``reference lens image`` (physical requirement, on the reference)
    |black fraction of the reference camera − the exact one| ≤ 0.05. The sphere is an
    inverted lens image whose pixels see the sky past the floor (black) or the floor;
    the black fraction measures whether the camera follows both refractions. 0.05 is
    the bound: the icosphere's facets move the sky's edge by a pixel or so
    (measured 0.002 at 512² on glass_sphere).

Method target measures (``data/method_targets.toml``):

``camera_black_fraction_difference``
    The same |difference| for the method's camera image.
``camera_object_radiance_ratio``
    Mean radiance (luminance) of the method over the sphere's interior / the exact
    image's.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from harness.checks.analytic import not_applicable
from harness.checks.bounds import holds
from harness.checks.physical import PHYSICAL
from harness.checks.sphere_camera import SphereCamera, analytic_sphere_camera, black_fraction
from reports.records import Check
from scenes import Scene
from scenes.colour import luminance

__all__ = ["LENS_BOUND", "camera_measures", "camera_requirements", "exact_camera"]

#: Bound on the reference's black fraction over the sphere (module docstring).
LENS_BOUND = 0.05


def exact_camera(scene: Scene, reference_maps, *,
                 resolution: tuple[int, int] | None = None) -> SphereCamera | None:
    """The exact camera image, shaded with the reference's caustic map of receiver 0,
    at ``resolution`` (W, H; default the scene camera's: give the compared images'
    own size); None where it does not describe ``scene``."""
    if not_applicable(scene) is not None or len(scene.receivers) != 1:
        return None
    if resolution is not None and tuple(resolution) != tuple(scene.camera.resolution):
        scene = dataclasses.replace(scene, camera=dataclasses.replace(
            scene.camera, resolution=tuple(int(x) for x in resolution)))
    return analytic_sphere_camera(scene, reference_maps[0], supersample=2)


def camera_requirements(exact: SphereCamera, reference_camera: np.ndarray
                        ) -> list[Check]:
    """``reference lens image`` (module docstring)."""
    value = abs(black_fraction(reference_camera, exact.interior) - exact.black_fraction)
    return [Check(
        metric="reference lens image", region="object", view="camera", bound=LENS_BOUND,
        relation="max", value=float(value), passed=holds("max", LENS_BOUND, value),
        origin=(f"|black fraction over the sphere − the exact lens image's "
                    f"({exact.black_fraction:.3f})|; the exact: the ideal sphere's two "
                    "refractions to the plane, shaded with the analytic direct light "
                    "and the reference's caustic map; 0.05: the icosphere's facets move "
                    "the sky's edge by about a pixel"),
        kind=PHYSICAL, subject="reference")]


def camera_measures(exact: SphereCamera, method_camera: np.ndarray) -> dict[str, float]:
    """The method target measures of the camera (module docstring)."""
    mask = exact.interior
    exact_mean = float(luminance(exact.image)[mask].mean())
    method_mean = float(luminance(np.asarray(method_camera, np.float64))[mask].mean())
    return {"camera_black_fraction_difference":
            abs(black_fraction(method_camera, mask) - exact.black_fraction),
            "camera_object_radiance_ratio":
            method_mean / exact_mean if exact_mean > 0 else float("nan")}
