"""Exact light paths through the method's vertex grid, as the method's own records.

For every grid vertex of the caustics-mapping object views (the light ray through the
texel's centre, as the front-surface pass rasterises it), the light path is traced
with Mitsuba's ray tracing on the reference's own scene (``harness.raycast``) and
written as the record the GPU trace writes for that vertex
(``renderers.caustics_mapping.record_splat``), so the splat passes can splat it.

Flux of a vertex (the GPU trace's own formula, ``caustic_trace.glsl``):
Φ = I · f(l) · Δω for point and spot lights, with Δω = s_x s_y / (1 + |p|²)^{3/2} the
solid angle of a texel of sides s = (rect width, height) / grid centred at p on the
view plane at unit distance, and f the spot cone's falloff (times max(cos, 0) for a
sample of an area light); Φ = E₀ · s_x s_y for a directional light. In the paper's
normalisation (``normalization = "paper"``), Φ = P · max(n · −l, 0) / V with V the
vertices whose ray meets a caustic object.

The path follows the reference photon tracer's event chains exactly
(``renderers.mitsuba.photons``), in expectation rather than by sampling:

* the light ray's first hit must be a caustic object (else the vertex is ``empty``);
* refraction at the shading normal n (the meshes' vertex normals) oriented against
  the incoming direction d: t = η d + (η cos_i − √k) n, k = 1 − η² (1 − cos_i²), with
  η = n₁/n₂ and the side (entering or leaving) decided by the geometric normal;
  k < 0 is total internal reflection, which breaks the chain (status ``tir``);
  a conductor reflects, r = d + 2 cos_i n, with weight its reflectance;
* with the ``fresnel`` effect each transmission weighs 1 − F (the unpolarised
  dielectric Fresnel reflectance): the reference samples the branch with
  probability 1 − F at weight one, so the expectation is the same;
* every event multiplies by Veach's adjoint shading-normal factor
  |d·n_s| |d'·n_g| / (|d·n_g| |d'·n_s|) (1997, §5.3), as the reference does;
* Beer-Lambert exp(−σ t) over every segment inside a dielectric;
* a closed dielectric: the refracted ray's next hit must be the same object (the
  exit; else ``no_exit``); an open one (water) and a conductor: one event;
* the last segment must reach a receiver's front side (d · n_s < 0) before any
  object; otherwise the chain is broken and the vertex is ``lost`` (its fate says
  why: ``missed`` every surface, ``blocked`` by an object, a receiver's ``back_side``).

Rays leaving a surface start as Mitsuba's ``spawn_ray`` starts them (offset along the
geometric normal), so the casts are the reference tracer's own.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from harness.raycast import SurfaceHits, SurfaceTracer
from renderers.caustics_mapping.caustic_trace import STATUS, material_table
from renderers.caustics_mapping.lights import LightSetup, LightView, light_setups
from renderers.caustics_mapping.presets import resolve_settings
from renderers.caustics_mapping.record_splat import pack_records
from scenes import Scene, effects_of
from scenes.geometry import SceneGeometry

__all__ = ["FATES", "ExactPaths", "exact_paths", "fresnel_transmittance", "lattice_rays",
           "refract", "shading_factor", "texel_measure"]

#: What became of each traced vertex's flux (keys of :attr:`ExactPaths.fates`).
FATES = ("hit", "tir", "no_exit", "missed", "blocked", "back_side")
#: Material codes of ``caustic_trace.MaterialTable``.
_CLOSED, _OPEN, _CONDUCTOR = 1, 2, 3


@dataclass(frozen=True, eq=False)
class ExactPaths:
    """Exact light paths of one grid, as GPU trace records.

    Attributes
    ----------
    records : list of list of ndarray
        Per light sample, per traced channel: (views · grid², 5, 4) float32 records
        (``renderers.caustics_mapping.record_splat``).
    grid : int
    fates : dict of str to float
        Share of the traced flux (W summed over channels, as recorded: after the
        events' weights) per fate of :data:`FATES`; ``hit`` is what gets splatted.
    shading_factor_change : float
        Splatted flux with the adjoint shading-normal factors over the same flux
        without them, minus one (how much the reference's correction moves the total).
    casts : int
        Ray casts made.
    """

    records: list[list[np.ndarray]]
    grid: int
    fates: dict[str, float]
    shading_factor_change: float
    casts: int


def refract(d: np.ndarray, n: np.ndarray, rel: np.ndarray):
    """Refraction of unit directions ``d`` (N, 3) at unit normals ``n`` facing them
    (d · n ≤ 0) with relative index ``rel`` = n₁/n₂ (N,).

    Returns
    -------
    t : ndarray (N, 3)
        Unit refracted directions (zeros under total internal reflection).
    tir : ndarray (N,) bool
    cos_i : ndarray (N,)
        Cosine of the incidence angle.
    """
    cos_i = np.clip(-np.einsum("ij,ij->i", d, n), 0.0, 1.0)
    k = 1.0 - rel**2 * (1.0 - cos_i**2)
    tir = k < 0
    t = rel[:, None] * d + (rel * cos_i - np.sqrt(np.maximum(k, 0.0)))[:, None] * n
    norm = np.linalg.norm(t, axis=1, keepdims=True)
    t = np.where(tir[:, None], 0.0, t / np.where(norm > 0, norm, 1.0))
    return t, tir, cos_i


def fresnel_transmittance(cos_i: np.ndarray, eta_i: np.ndarray, eta_t: np.ndarray) -> np.ndarray:
    """Unpolarised dielectric Fresnel transmittance 1 − (R_s + R_p)/2 for incidence
    cosines ``cos_i`` from index ``eta_i`` into ``eta_t``; 0 beyond the critical angle
    (``common.glsl``'s formula, which equals Mitsuba's ``fresnel``)."""
    eta = eta_i / eta_t
    sin_t2 = eta**2 * np.maximum(1.0 - cos_i**2, 0.0)
    cos_t = np.sqrt(np.maximum(1.0 - sin_t2, 0.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        rs = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t)
        rp = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t)
    out = 1.0 - 0.5 * (np.nan_to_num(rs) ** 2 + np.nan_to_num(rp) ** 2)
    return np.where(sin_t2 >= 1.0, 0.0, out)


def shading_factor(d: np.ndarray, d_new: np.ndarray, shading: np.ndarray,
                   geometric: np.ndarray) -> np.ndarray:
    """Veach's adjoint factor |d·n_s| |d'·n_g| / (|d·n_g| |d'·n_s|) for light arriving
    along ``d`` and leaving along ``d_new``; 0 where the denominator is (a direction in
    a tangent plane), as the reference has it."""
    num = np.abs(np.einsum("ij,ij->i", d, shading)) * np.abs(np.einsum("ij,ij->i", d_new,
                                                                          geometric))
    den = np.abs(np.einsum("ij,ij->i", d, geometric)) * np.abs(np.einsum("ij,ij->i", d_new,
                                                                         shading))
    return np.where(den > 0, num / np.maximum(den, 1e-30), 0.0)


def lattice_rays(light: LightSetup, view: LightView, *, grid: int,
                 offset: tuple[float, float] = (0.0, 0.0)):
    """The light rays through the centres of a ``grid`` × ``grid`` lattice of the
    object view ``view``, moved by ``offset`` texels (a jittered lattice).

    Returns
    -------
    origins, directions : ndarray (grid², 3)
        Metres and unit vectors; row ``ty * grid + tx`` (the record order).
    ndc : ndarray (grid², 2)
        The rays' normalised device coordinates in the view.
    """
    t = (np.arange(grid) + 0.5) / grid
    tx = t + offset[0] / grid
    ty = t + offset[1] / grid
    x, y = np.meshgrid(tx * 2 - 1, ty * 2 - 1)           # row ty, column tx
    ndc = np.stack([x.ravel(), y.ravel()], axis=1)
    inverse = np.linalg.inv(view.view_proj)

    def unproject(z: float) -> np.ndarray:
        # inverse @ (x, y, z, 1), column by column (a (N, 4) @ (4, 4) product is slow).
        world = (np.outer(ndc[:, 0], inverse[:, 0]) + np.outer(ndc[:, 1], inverse[:, 1])
                 + (z * inverse[:, 2] + inverse[:, 3]))
        return world[:, :3] / world[:, 3:]

    near, far = unproject(-1.0), unproject(1.0)
    directions = far - near
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    origins = np.broadcast_to(light.position, near.shape).copy() if view.perspective else near
    return origins, directions, ndc


def texel_measure(view: LightView, grid: int, ndc: np.ndarray) -> np.ndarray:
    """``texel_measure`` of ``common.glsl``: solid angle (sr, perspective) or area
    across the beam (m², orthographic) of a lattice cell centred at ``ndc``."""
    x0, x1, y0, y1 = view.bounds
    sx, sy = (x1 - x0) / grid, (y1 - y0) / grid
    if not view.perspective:
        return np.full(len(ndc), sx * sy)
    t = ndc * 0.5 + 0.5
    px, py = x0 + t[:, 0] * (x1 - x0), y0 + t[:, 1] * (y1 - y0)
    q = 1.0 + px**2 + py**2
    return sx * sy / (q * np.sqrt(q))


def _falloff(light: LightSetup, incident: np.ndarray) -> np.ndarray:
    """``light_falloff`` of ``common.glsl``: the spot cone (linear in angle between
    the beam width and the cutoff) and an area-light sample's cosine."""
    f = np.ones(len(incident))
    if light.kind == "spot":
        c = incident @ light.direction
        ramp = (light.cutoff - np.arccos(np.clip(c, -1.0, 1.0))) / (light.cutoff - light.beam) \
            if light.cutoff > light.beam else np.ones(len(incident))
        f = np.where(c <= light.cos_cutoff, 0.0, np.where(c < light.cos_beam, ramp, 1.0))
    if light.lambertian:
        f = f * np.maximum(incident @ light.direction, 0.0)
    return f


def _facing(n: np.ndarray, d: np.ndarray) -> np.ndarray:
    """``n`` flipped where needed so that d · n ≤ 0."""
    return np.where((np.einsum("ij,ij->i", d, n) > 0)[:, None], -n, n)


def exact_paths(scene: Scene, geometry: SceneGeometry, tracer: SurfaceTracer, *,
                grid: int | None = None, offset: tuple[float, float] = (0.0, 0.0)
                ) -> ExactPaths:
    """The exact light path of every vertex of the method's grid (module docstring).

    Parameters
    ----------
    scene : Scene
        Its settings (preset filled in) give the object frustum (``frustum``), the
        grid, the normalisation; its effects the channels, Fresnel and absorption.
    geometry : SceneGeometry
    tracer : SurfaceTracer
        Built on ``scene`` with its objects.
    grid : int, optional
        Vertices per side of each object view (default ``settings.grid``).
    offset : (float, float)
        Lattice offset in texels (a jittered lattice; (0, 0) is the method's own).
    """
    settings = resolve_settings(scene.settings)
    grid = grid or settings.grid
    effects = effects_of(scene)
    table = material_table([g.material for g in geometry.objects],
                           [g.mesh.closed for g in geometry.objects], effects)
    channels = (0, 1, 2) if "dispersion" in effects else (-1,)
    paper = settings.normalization == "paper"
    fates = dict.fromkeys(FATES, 0.0)
    with_factor = without_factor = 0.0
    casts = 0
    records: list[list[np.ndarray]] = []
    for light in light_setups(scene, geometry, frustum_fit=settings.frustum):
        views = light.object_views
        rays = [lattice_rays(light, view, grid=grid, offset=offset) for view in views]
        origins = np.concatenate([r[0] for r in rays])
        directions = np.concatenate([r[1] for r in rays])
        measure = np.concatenate([texel_measure(views[0], grid, r[2]) for r in rays])
        view_index = np.repeat(np.arange(len(views)), grid * grid)
        first = tracer(origins, directions)
        casts += len(origins)
        obj = np.where(first.kind == SurfaceTracer.OBJECT, first.index, -1)
        code = np.array((*table.code, 0))[obj]                # obj = -1 reads the 0
        caustic = code != 0
        per_channel = []
        for channel in channels:
            path = _Path.start(light, table, channel, rays=(origins, directions), first=first,
                               obj=obj, code=code, measure=measure, paper=paper,
                               covered=int(caustic.sum()))
            casts += path.run(tracer)
            per_channel.append(path.records(view_index))
            for fate in FATES:
                fates[fate] += path.fate_flux(fate)
            with_factor += path.fate_flux("hit")
            without_factor += path.fate_flux("hit", factor=False)
        records.append(per_channel)
    traced = sum(fates.values())
    return ExactPaths(
        records=records, grid=grid,
        fates={k: (v / traced if traced > 0 else 0.0) for k, v in fates.items()},
        shading_factor_change=(with_factor / without_factor - 1.0) if without_factor > 0
        else 0.0,
        casts=casts)


@dataclass
class _Path:
    """The paths of one light sample and channel, advanced event by event in place
    (mutable on purpose: the working state of :func:`exact_paths`); arrays over the
    grid's vertices (float64)."""

    v: np.ndarray             # current origin (m)
    d: np.ndarray             # current direction
    flux: np.ndarray          # (K, 3) W, before the adjoint factors
    factor: np.ndarray        # product of the adjoint shading-normal factors
    status: np.ndarray        # STATUS codes
    fate: np.ndarray          # index into FATES, -1 while going on or empty
    alive: np.ndarray         # still travelling
    obj: np.ndarray
    code: np.ndarray
    eta: np.ndarray
    sigma: np.ndarray         # (K, 3) 1/m of each object's medium
    fresnel: np.ndarray
    reflectance: np.ndarray   # (K, 3)
    first: SurfaceHits
    hit: np.ndarray | None = None         # set by run(): P (m), d (m), receiver, normal
    distance: np.ndarray | None = None
    receiver: np.ndarray | None = None
    normal: np.ndarray | None = None

    @classmethod
    def start(cls, light, table, channel, *, rays, first, obj, code, measure, paper: bool,
              covered: int) -> _Path:
        origins, directions = rays
        count = len(origins)
        mask = np.ones(3) if channel < 0 else np.eye(3)[channel]
        caustic = code != 0
        n_face = _facing(first.shading_normal, directions)
        if paper:
            cosine = np.maximum(np.einsum("ij,ij->i", n_face, -directions), 0.0)
            scale = cosine / max(covered, 1)
        else:
            scale = _falloff(light, directions) * measure
        flux = np.where(caustic[:, None], light.power[None, :] * scale[:, None] * mask, 0.0)
        pick = np.where(caustic, obj, 0)

        def rows(values, default: float) -> np.ndarray:
            table_rows = np.asarray(values, float).reshape(-1, 3) if values else np.zeros((1, 3))
            return np.where(caustic[:, None], table_rows[pick], default)

        ior = np.array([c[max(channel, 0)] for c in table.ior] or [1.0])
        return cls(
            v=origins.astype(float), d=directions.astype(float), flux=flux,
            factor=np.ones(count), status=np.where(caustic, STATUS["hit"], STATUS["empty"]),
            fate=np.full(count, -1), alive=caustic.copy(), obj=obj, code=code,
            eta=np.where(caustic, ior[pick], 1.0),
            sigma=rows(table.absorption, 0.0),
            fresnel=np.where(caustic, np.array(table.fresnel or [0])[pick], 0).astype(bool),
            reflectance=rows(table.reflectance, 1.0), first=first)

    # ------------------------------------------------------------------ events
    def _event(self, at: np.ndarray, hits: SurfaceHits) -> np.ndarray:
        """The specular event at ``hits`` for the vertices ``at``; returns the medium
        (σ, 1/m) each is in afterwards."""
        d = self.d[at]
        ns, ng = hits.shading_normal[at], hits.geometric_normal[at]
        nf = _facing(ns, d)
        conductor = self.code[at] == _CONDUCTOR
        entering = np.einsum("ij,ij->i", d, ng) < 0
        eta = self.eta[at]
        rel = np.where(entering, 1.0 / eta, eta)
        t, tir, cos_i = refract(d, nf, rel)
        reflected = d + 2.0 * cos_i[:, None] * nf
        reflected /= np.linalg.norm(reflected, axis=1, keepdims=True)
        new = np.where(conductor[:, None], reflected, t)
        weight = np.where(conductor[:, None], self.reflectance[at], 1.0)
        fresnel = self.fresnel[at] & ~conductor
        eta_i, eta_t = np.where(entering, 1.0, eta), np.where(entering, eta, 1.0)
        weight = weight * np.where(fresnel, fresnel_transmittance(cos_i, eta_i, eta_t),
                                   1.0)[:, None]
        self.flux[at] *= weight
        broken = ~conductor & tir
        self.factor[at] *= np.where(broken, 1.0, shading_factor(d, new, ns, ng))
        self.v[at], self.d[at] = hits.position[at], np.where(broken[:, None], d, new)
        idx = np.flatnonzero(at)
        self.status[idx[broken]] = STATUS["tir"]
        self.fate[idx[broken]] = FATES.index("tir")
        self.alive[idx[broken]] = False
        # Transmission into a dielectric enters its medium; anything else is in air.
        return np.where((~conductor & entering)[:, None], self.sigma[at], 0.0)

    def run(self, tracer: SurfaceTracer) -> int:
        """Follow the paths to their receivers; returns the ray casts made."""
        count = len(self.v)
        casts = 0
        medium = np.zeros((count, 3))
        leaving = self.first.geometric_normal.copy()
        at = self.alive.copy()
        medium[at] = self._event(at, self.first)
        # Closed dielectrics: the inside segment must end on the same object.
        inside = self.alive & (self.code == _CLOSED)
        if inside.any():
            hits = _cast(tracer, self.v, self.d, leaving, inside)
            casts += int(inside.sum())
            same = (hits.kind == SurfaceTracer.OBJECT) & (hits.index == self.obj)
            lost = inside & ~same
            self.status[lost], self.fate[lost] = STATUS["no_exit"], FATES.index("no_exit")
            self.alive[lost] = False
            exit_ = inside & same
            self.flux[exit_] *= np.exp(-medium[exit_] * hits.distance[exit_, None])
            medium[exit_] = self._event(exit_, hits)
            leaving[exit_] = hits.geometric_normal[exit_]
        go = self.alive
        self.hit = self.v.copy()
        self.distance = np.zeros(count)
        self.receiver = np.full(count, -1)
        self.normal = np.zeros((count, 3))
        if go.any():
            hits = _cast(tracer, self.v, self.d, leaving, go)
            casts += int(go.sum())
            on_receiver = hits.kind == SurfaceTracer.RECEIVER
            front = np.einsum("ij,ij->i", self.d, hits.shading_normal) < 0
            ok = go & on_receiver & front
            self.hit[ok], self.distance[ok] = hits.position[ok], hits.distance[ok]
            self.receiver[ok], self.normal[ok] = hits.index[ok], hits.shading_normal[ok]
            # Beer-Lambert below a water surface, down to the receiver.
            self.flux[ok] *= np.exp(-medium[ok] * hits.distance[ok, None])
            self.fate[ok] = FATES.index("hit")
            for name, where in (("missed", hits.kind == SurfaceTracer.NONE),
                                ("blocked", hits.kind == SurfaceTracer.OBJECT),
                                ("back_side", on_receiver & ~front)):
                self.status[go & where] = STATUS["lost"]
                self.fate[go & where] = FATES.index(name)
        return casts

    def records(self, view_index: np.ndarray) -> np.ndarray:
        return pack_records(origin=self.v, view=view_index, direction=self.d,
                            distance=self.distance, hit=self.hit, status=self.status,
                            flux=self.flux * self.factor[:, None], receiver=self.receiver,
                            normal=self.normal)

    def fate_flux(self, fate: str, *, factor: bool = True) -> float:
        """Flux (W, summed over channels) of the vertices of ``fate``, with or without
        the adjoint factors."""
        mine = self.fate == FATES.index(fate)
        flux = self.flux[mine] * (self.factor[mine, None] if factor else 1.0)
        return float(flux.sum())


def _cast(tracer: SurfaceTracer, origins, directions, leaving, where) -> SurfaceHits:
    """Cast the rays of ``where`` only; the result spans every vertex (misses elsewhere)."""
    count = len(origins)
    hits = tracer(origins[where], directions[where], leaving=leaving[where])
    full = SurfaceHits(np.full(count, np.inf), np.zeros(count, int), np.full(count, -1),
                       np.zeros((count, 3)), shading_normal=np.zeros((count, 3)),
                       geometric_normal=np.zeros((count, 3)))
    for name in ("distance", "kind", "index", "position", "shading_normal",
                 "geometric_normal"):
        getattr(full, name)[where] = getattr(hits, name)
    return full

