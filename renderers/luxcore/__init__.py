"""Second renderer: LuxCore (pyluxcore, LIGHTCPU light tracing) as an independent check
of the Mitsuba reference's receiver caustic irradiance maps (docs/reference.md, "The LuxCore
cross-check"). pyluxcore is imported only by a render worker process, never into the caller's.
"""

from renderers.luxcore._lux import LuxCoreUnavailable
from renderers.luxcore.caustic import render_receiver_caustic
from renderers.luxcore.errors import LuxCoreError
from renderers.luxcore.render import FilmRender, luxcore_version, render_film
from renderers.luxcore.translate import UnsupportedScene, check_supported, translate_scene
from renderers.luxcore.units import UnitsCheck, UnitsCheckFailed, check_units

__all__ = [
    "FilmRender",
    "LuxCoreError",
    "LuxCoreUnavailable",
    "UnitsCheck",
    "UnitsCheckFailed",
    "UnsupportedScene",
    "check_supported",
    "check_units",
    "luxcore_version",
    "render_film",
    "render_receiver_caustic",
    "translate_scene",
]
