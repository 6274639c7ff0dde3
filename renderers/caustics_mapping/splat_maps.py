"""Passes 3b and 3c of one light sample: the caustic maps splatted from its traces.

Each receiver's (u, v) map (pass 3c, :mod:`.receiver_splat`) is summed into the
frame's receiver maps, the ones the harness scores; the camera (pass 5) reads its
caustic irradiance from the light-space caustic map (pass 3b, :mod:`.caustic_splat`;
``caustic_lookup = "light"``, the paper's) or from the receivers' own maps
(``"receivers"``), optionally low-passed (:mod:`.lowpass`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import moderngl
import numpy as np

from renderers.caustics_mapping.caustic_splat import SplatOptions, splat_caustic_map
from renderers.caustics_mapping.caustic_trace import Trace
from renderers.caustics_mapping.context import ResourcePool, pool
from renderers.caustics_mapping.footprint import FALLBACK_TEXELS, mean_hit_spacing_texels
from renderers.caustics_mapping.lights import LightSetup
from renderers.caustics_mapping.lowpass import lowpass_filter
from renderers.caustics_mapping.receiver_splat import splat_receiver_map
from renderers.caustics_mapping.scored_maps import scored_maps

if TYPE_CHECKING:
    from renderers.caustics_mapping.light_sample import FrameState

__all__ = ["LOOKUP_OVERSAMPLE", "CausticMaps", "read_rgba", "splat_maps"]


def read_rgba(texture: moderngl.Texture) -> np.ndarray:
    """An RGBA32F texture read back, (H, W, 4) float32, row 0 at the bottom."""
    w, h = texture.size
    return np.frombuffer(texture.read(), np.float32).reshape(h, w, 4)


#: Texels per ``settings.receiver_map`` texel along each side of the triangles the
#: camera reads with ``caustic_lookup = "receivers"``: at 2 x the default 256^2
#: they are 1.6 cm texels on glass_sphere's floor, where its light-space map's are
#: 2.3 cm (the camera's brightest pixels there, an ad-hoc relMSE: 0.0105 reading the
#: light-space map bilinearly, 0.0094 reading these; with the triangles at 1 x and
#: nearest reads, 0.054).
LOOKUP_OVERSAMPLE = 2


@dataclass(frozen=True, eq=False)
class CausticMaps:
    """A light sample's caustic maps (textures of the context's pool).

    Attributes
    ----------
    light : moderngl.Texture or None
        The light-space caustic-map atlas (:func:`.caustic_splat.splat_caustic_map`;
        rgb W/m^2), low-passed with ``settings.lowpass`` where the camera reads it;
        None where it was not drawn.
    receivers : moderngl.Texture or None
        With ``caustic_lookup = "receivers"``: the atlas of the receivers' (u, v)
        maps the camera reads (:func:`.receiver_splat.splat_receiver_map`; rgb
        W/m^2, slots of ``settings.receiver_map``), low-passed with
        ``settings.lowpass``; else None.
    triangles : moderngl.Texture or None
        With triangle splats, the part of ``receivers`` the triangles drew, in an
        atlas of :data:`LOOKUP_OVERSAMPLE` x finer slots (``receivers`` holds the
        Gaussians); the camera reads the sum.
    """

    light: moderngl.Texture | None
    receivers: moderngl.Texture | None = None
    triangles: moderngl.Texture | None = None

    def give_back(self, resources: ResourcePool) -> None:
        """Return the textures to the context's pool."""
        for texture in (self.light, self.receivers, self.triangles):
            if texture is not None:
                resources.give_back(texture)


def splat_maps(state: FrameState, light: LightSetup, *, faces: tuple[int, ...],
               traces: list[Trace], positions, light_map: bool = False) -> CausticMaps:
    """Splat the traces into each receiver's (u, v) map (summed into
    ``state.acc.maps``) and into the caustic map the camera reads: the light-space
    one (``caustic_lookup = "light"``) or the receivers' own maps, whose triangles are
    drawn at :data:`LOOKUP_OVERSAMPLE` x ``receiver_map`` (their means over the finer
    texels are the maps summed). ``light_map``: draw the light-space map also where
    the camera does not read it (for the frame's outputs)."""
    ctx, acc, timer = state.ctx, state.acc, state.timer
    s = state.scene.settings
    reads_light = s.caustic_lookup != "receivers"
    options = None
    caustic = None
    if reads_light or light_map:
        caustic, options = _splat_light_map(state, light, faces=faces, traces=traces)
    options = options or _splat_options(state, light, traces)
    oversample = LOOKUP_OVERSAMPLE if not reads_light and s.splat == "triangles" else 1
    with timer.measure("receiver_map"):
        atlas, fine = _splat_receiver_maps(state, light, traces=traces, positions=positions,
                                           options=options, oversample=oversample)
    acc.ran("receiver_map")
    resources = pool(ctx)
    w, h = s.receiver_map
    if reads_light:
        resources.give_back(atlas)
        return CausticMaps(_lowpass(state, caustic, size=(s.caustic_map, s.caustic_map)))
    return CausticMaps(caustic, _lowpass(state, atlas, size=(w, h)),
                       _lowpass(state, fine, size=(oversample * w, oversample * h)))


def _splat_options(state: FrameState, light: LightSetup, traces: list[Trace]) -> SplatOptions:
    """The settings' splat kernel, its ``points`` width found from the hits where the
    settings leave it unset (recorded in ``state.acc.splat_sigma``)."""
    s = state.scene.settings
    sigma = s.splat_sigma
    if sigma is None and s.splat == "points":
        grid_traces = [t for t in traces if not t.patches]
        sigma = mean_hit_spacing_texels(grid_traces, light, grid=s.grid,
                                        caustic_size=s.caustic_map)
    elif sigma is None:
        sigma = FALLBACK_TEXELS     # only Gaussians without neighbours use it
    state.acc.splat_sigma.append(float(sigma))
    return SplatOptions(mode=s.splat, sigma=float(sigma), cut=s.splat_radius,
                        footprint_scale=s.footprint_scale,
                        unconverged=s.splat_unconverged, grid=s.grid)


def _splat_light_map(state: FrameState, light: LightSetup, *, faces: tuple[int, ...],
                     traces: list[Trace]) -> tuple[moderngl.Texture, SplatOptions]:
    """Pass 3b, the light-space caustic-map atlas, and the splat options used."""
    ctx, s = state.ctx, state.scene.settings
    csize = s.caustic_map
    caustic = pool(ctx).texture((len(faces) * csize, csize))
    with state.timer.measure("caustic_map"):
        options = _splat_options(state, light, traces)
        splat_caustic_map(ctx, light, traces, caustic, size=csize, faces=faces,
                          options=options)
    state.acc.ran("caustic_map")
    return caustic, options


def _splat_receiver_maps(state: FrameState, light: LightSetup, *, traces: list[Trace],
                         positions, options: SplatOptions, oversample: int,
                         ) -> tuple[moderngl.Texture, moderngl.Texture | None]:
    """Pass 3c into an atlas of ``receiver_map`` slots and, with ``oversample`` > 1,
    the triangles into a second one of ``oversample`` x finer slots; adds each
    receiver's map to ``state.acc.maps``: its slot plus the means of the finer
    slot's texels (for the exact triangle integrals, the integral over the coarser
    texel). Returns the two atlases (the second None without ``oversample``)."""
    ctx, setup, s = state.ctx, state.setup, state.scene.settings
    resources = pool(ctx)
    receivers = state.geometry.receivers
    w, h = s.receiver_map
    atlases = [resources.texture((len(receivers) * w, h))]
    if oversample > 1:
        atlases.append(resources.texture((len(receivers) * oversample * w, oversample * h)))
    for atlas in atlases:
        fbo = resources.framebuffer([atlas])
        fbo.use()
        fbo.clear(0.0, 0.0, 0.0, 0.0)
    fine = atlases[1] if oversample > 1 else None
    for index, rec in enumerate(receivers):
        splat_receiver_map(ctx, light, traces, atlases[0], index=index, size=(w, h),
                           receiver=rec, mapping=setup.mappings[index], positions=positions,
                           caustic_size=s.caustic_map, options=options, fine=fine,
                           oversample=oversample)
    if fine is None:
        maps = read_rgba(atlases[0])[:, :, :3]
    else:
        scored = scored_maps(ctx, atlases[0], fine, factor=oversample)
        maps = read_rgba(scored)[:, :, :3]
        resources.give_back(scored)
    for index in range(len(receivers)):
        state.acc.maps[index] += maps[:, index * w:(index + 1) * w]
    return atlases[0], fine


def _lowpass(state: FrameState, texture: moderngl.Texture | None, *,
             size: tuple[int, int]) -> moderngl.Texture | None:
    """``texture`` low-passed per slot of ``size`` with ``settings.lowpass`` (the
    original goes back to the pool), else itself."""
    if texture is None or not state.scene.settings.lowpass:
        return texture
    with state.timer.measure("lowpass"):
        filtered = lowpass_filter(state.ctx, texture, size=size)
    pool(state.ctx).give_back(texture)
    state.acc.ran("lowpass")
    return filtered
