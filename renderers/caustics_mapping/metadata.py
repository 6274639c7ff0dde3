"""What one caustics-mapping render records about itself (``RenderResult.metadata``).

The typed record is built once per render; ``as_dict()`` is the JSON form that goes
into ``result.json`` and the report, with the keys in the order below.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

__all__ = ["MethodMetadata"]


@dataclass(frozen=True)
class MethodMetadata:
    """Provenance and counts of one render.

    Attributes
    ----------
    passes : list of str
        Passes that ran, in first-run order (``caustic_trace.<paths>[.<channel>]``).
    lost_splats : int
        Grid vertices whose estimate found no receiver (status ``lost``).
    status_counts : dict of str to int
        Grid vertices per status (:data:`.caustic_trace.STATUS`).
    lost_flux, splatted_flux : list of float
        Flux (W, RGB) of the lost vertices and of the splatted (``hit``) ones.
    status_flux_fraction : dict of str to float
        Share of the flux of every traced vertex (all but ``empty``; summed over
        channels) per status: e.g. ``tir`` is the flux lost to total internal
        reflection at the exit surface, ``unconverged`` the flux verified hits held
        back. These flux parts count the grid's and the rim patches' vertices, each
        at the share of its flux the splats draw (``Frame.traced_records``).
    light_views : str
        ``"cube"`` for a point light, else the single view's name.
    map_faces : list of str
        Caustic-map views that see a receiver (cube faces or the single view).
    object_views : list of str
        Views the object grid is rendered from.
    light_samples : int
        Point samples of the light (1, or N for an area light).
    covered_texels : int or None
        Grid texels covered by caustic objects (the paper's V, Eq. 6); None unless
        ``normalization == "paper"``.
    preset : str
        ``paper`` or ``strong``.
    estimator, safeguarded, iterations, grid, caustic_map, positions_map, normalization
        The settings used (after the preset filled the unset ones).
    lookup, back_resolution, frustum, verify_hits, start, splat, rim_patches
        The preset-dependent choices used.
    rim_patches_traced : int
        Rim patches traced, summed over light samples (0 without).
    splat_sigma : list of float
        Width of the Gaussians per light sample (caustic-map texels): ``points``'
        width, or the fallback of Gaussians without neighbours.
    newton_eps : float
        Newton's finite-difference step (m).
    channels : list of str
        ``["rgb"]``, or ``["r", "g", "b"]`` with dispersion.
    receiver_extent : list of list of float
        (umin, umax, vmin, vmax) per receiver.
    gl_renderer : str
        ``GL_RENDERER`` of the context (llvmpipe or a GPU).
    timer : str
        The clock behind the pass timings.
    """

    passes: list[str]
    lost_splats: int
    status_counts: dict[str, int]
    lost_flux: list[float]
    splatted_flux: list[float]
    status_flux_fraction: dict[str, float]
    light_views: str
    map_faces: list[str]
    object_views: list[str]
    light_samples: int
    covered_texels: int | None
    preset: str
    estimator: str
    safeguarded: bool
    iterations: int
    grid: int
    caustic_map: int
    positions_map: int
    normalization: str
    lookup: str
    back_resolution: int
    rim_patches: int
    rim_patches_traced: int
    frustum: str
    verify_hits: bool
    start: str
    splat: str
    splat_sigma: list[float]
    newton_eps: float
    channels: list[str]
    receiver_extent: list[list[float]]
    gl_renderer: str
    timer: str

    def as_dict(self) -> dict:
        """The JSON-serialisable form (``RenderResult.metadata``)."""
        return asdict(self)
