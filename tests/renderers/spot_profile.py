"""The spot light's angular profile, for the tests of both renderers' spot lights."""

from __future__ import annotations

import math

import numpy as np


def falloff(theta_deg, *, cutoff: float, beam: float):
    """Mitsuba's spot profile f(theta): 1 inside ``beam``, linear in the angle to 0
    at ``cutoff`` (degrees in, dimensionless out); a hard edge when they are equal."""
    theta = np.asarray(theta_deg, float)
    if cutoff == beam:
        return np.where(theta < cutoff, 1.0, 0.0)
    return np.clip((cutoff - theta) / (cutoff - beam), 0.0, 1.0)


def smoothstep_falloff(theta_deg, *, cutoff: float, beam: float):
    """pbrt-v4's spot profile (smoothstep in cos theta): a plausible wrong answer."""
    c0, c1 = math.cos(math.radians(cutoff)), math.cos(math.radians(beam))
    t = np.clip((np.cos(np.radians(theta_deg)) - c0) / (c1 - c0), 0.0, 1.0)
    return t * t * (3 - 2 * t)
