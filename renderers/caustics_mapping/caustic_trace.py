"""Pass 3a: refract or reflect at every grid vertex and estimate the receiver hit.

Runs ``caustic_trace.glsl`` as a compute shader over the ``grid`` x ``grid`` vertices
of every object view (one invocation each), writing one record per vertex into a
shader storage buffer (layout in the shader's header) and the estimate after every
iteration into a second. The splat passes draw the record buffer as point sprites;
the renderer reads both back for ``hits.npz`` and for the NumPy mirror in
:mod:`.estimators`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import moderngl
import numpy as np

from renderers.caustics_mapping.context import ResourcePool, load_program, pool
from renderers.caustics_mapping.lights import LightSetup
from renderers.caustics_mapping.object_positions import ObjectSurfaces
from renderers.caustics_mapping.receiver_positions import ReceiverPositions
from renderers.caustics_mapping.uniforms import (
    set_light_uniforms,
    set_object_view_uniforms,
    set_uniform,
)
from scenes.model import ConductorMaterial, DielectricMaterial

if TYPE_CHECKING:
    from renderers.caustics_mapping.rim_patches import RimPatches

__all__ = ["CONVERGED", "ESTIMATORS", "STATUS", "MaterialTable", "Trace", "TraceOptions",
           "material_table", "run_caustic_trace", "trace_options"]

#: Estimator names and their shader codes.
ESTIMATORS = {"modified": 0, "newton": 1, "secant": 2}
#: Record status codes (``common.glsl`` and ``caustic_trace.glsl``).
STATUS = {"empty": 0, "hit": 1, "lost": 2, "tir": 3, "diverged": 4, "no_exit": 5,
          "unconverged": 6, "reentered": 7}


@dataclass(frozen=True)
class TraceOptions:
    """How the trace pass estimates hits (from the resolved settings).

    Attributes
    ----------
    estimator, iterations, safeguarded
        The intersection estimator, its updates, and the bracketing safeguard.
    eps : float
        Newton's finite-difference step (m).
    filtered : bool
        Bilinear reads of receiver positions and exit surfaces within one surface.
    start : {"receiver", "fixed"}
    start_distance : float
        d1 of the fixed start (m).
    verify : bool
        Verified hits (see ``caustic_trace.glsl``); tolerance ``hit_tolerance`` (m,
        None: one positions-map texel over the cosine).
    exit_iterations : int
        Refinements of the image-space exit point (double refraction).
    converged : float
        The estimators stop at a residual |h| of at most this many positions-map
        texels at the estimate (0: only at h = 0); :data:`CONVERGED` with the
        safeguard, 0 without (the paper's iterations run in full).
    reflected_search : bool
        A reflected ray whose estimate is not verified is searched again on the
        signed depth along the light from the tangent plane of the receiver seen
        through its origin (``reflected_search`` in ``caustic_trace.glsl``); on with
        verified hits.
    contact_test : bool
        A reflected hit where the object rests on the receiver (``under_contact`` in
        ``caustic_trace.glsl``) ends as ``reentered``; on with verified hits.
    facet_side_test : bool
        A conductor's reflected ray that leaves below the plane of its own triangle
        (the shading normal tilted past the geometric one near grazing) meets its
        object again, as the reference's photon does, and ends as ``reentered``
        (``below_own_triangle`` in ``caustic_trace.glsl``); on with verified hits.
    depth_spread : bool
        The crossing test (``reflection_blocked``) takes a sample behind a sheet by
        no more than the sheet's depth spread across half a texel
        (``depth_spread`` in ``caustic_trace.glsl``) as on neither side, but for the
        hit itself; the contact test (``under_contact``) takes that spread as its
        tolerance; on with verified hits.
    open_escape : bool
        The reflected search's stricter test (``stays_in_front``) lets a ray pass
        behind a sheet the light does not see edge-on when it then leaves the
        objects' silhouette or bounding box (a half-pipe's open end); on with
        verified hits.
    box_samples : bool
        The crossing test's samples run over the ray's part inside the object's
        bounding box (grown by a texel), not to its hit: past the box no surface of
        the object is seen; on with verified hits.
    shading_correction : bool
        Veach's adjoint shading-normal factor at every specular event (entry, exit),
        |d . n_s| |d' . n_g| / (|d . n_g| |d' . n_s|), as the reference's photons
        carry it; on in the ``strong`` preset.
    """

    estimator: str
    iterations: int
    safeguarded: bool
    eps: float
    filtered: bool = False
    start: str = "receiver"
    start_distance: float = 0.1
    verify: bool = False
    hit_tolerance: float | None = None
    exit_iterations: int = 8
    converged: float = 0.0
    reflected_search: bool = False
    contact_test: bool = False
    facet_side_test: bool = False
    depth_spread: bool = False
    open_escape: bool = False
    box_samples: bool = False
    shading_correction: bool = False


#: Residual |h| (positions-map texels at the estimate) at which the safeguarded
#: estimators stop: 100x the bilinear reads' and float32 rounding's error on a plane
#: (measured up to 4e-4 texel on metal_ring), 1 % of the verified hit's tolerance.
#: Below it h's sign is noise, and the safeguard's bisection on that sign threw
#: converged estimates away (estimators.glsl).
CONVERGED = 0.01


def trace_options(settings, eps: float) -> TraceOptions:
    """:class:`TraceOptions` from resolved :class:`scenes.model.Settings`."""
    return TraceOptions(
        estimator=settings.estimator, iterations=settings.iterations,
        safeguarded=bool(settings.safeguarded), eps=eps,
        filtered=settings.lookup == "filtered", start=settings.start,
        start_distance=settings.start_distance, verify=bool(settings.verify_hits),
        hit_tolerance=settings.hit_tolerance,
        converged=CONVERGED if settings.safeguarded else 0.0,
        reflected_search=bool(settings.verify_hits), contact_test=bool(settings.verify_hits),
        facet_side_test=bool(settings.verify_hits),
        depth_spread=bool(settings.verify_hits), open_escape=bool(settings.verify_hits),
        box_samples=bool(settings.verify_hits),
        shading_correction=settings.preset == "strong")
#: Largest number of caustic objects one render handles.
MAX_OBJECTS = 8
RECORD_FLOATS = 20


@dataclass(frozen=True)
class MaterialTable:
    """Per-object material uniforms (index = object index).

    ``code``: 0 no caustic (diffuse), 1 closed dielectric (double refraction),
    2 open dielectric (single refraction), 3 conductor (reflection). ``extent``: the
    diagonal of each object's bounding box (m), the length over which a verified
    exit ray is tested for re-entering its object (empty: no test). ``convex``: 1 for
    an object that bounds a convex body (:func:`.meshes.convex`), which no ray leaving
    it meets again, so verified hits skip the re-entry and blocked-reflection tests
    there (exact; empty: none is). ``bounds``: each object's axis-aligned bounding
    box (min and max corners, m), past which the re-entry test takes no samples
    (exact; empty: unknown, every sample taken).
    """

    code: tuple[int, ...]
    ior: tuple[tuple[float, float, float], ...]
    absorption: tuple[tuple[float, float, float], ...]
    reflectance: tuple[tuple[float, float, float], ...]
    fresnel: tuple[int, ...]
    extent: tuple[float, ...] = ()
    convex: tuple[int, ...] = ()
    bounds: tuple[tuple[tuple[float, float, float], tuple[float, float, float]], ...] = ()


def material_table(materials, closed: list[bool], effects: tuple[str, ...], *,
                   extent: tuple[float, ...] = (),
                   convex: tuple[bool, ...] = (),
                   bounds: tuple = ()) -> MaterialTable:
    """Build the table from the objects' materials; Fresnel only with the effect;
    ``extent`` the objects' bounding-box diagonals (m), ``convex`` whether each bounds
    a convex body, ``bounds`` their bounding boxes ((min xyz, max xyz), m), if known."""
    if len(materials) > MAX_OBJECTS:
        raise ValueError(f"at most {MAX_OBJECTS} caustic objects are supported")
    code, ior, absorption, reflectance, fresnel = [], [], [], [], []
    for material, is_closed in zip(materials, closed, strict=False):
        if isinstance(material, DielectricMaterial):
            code.append(1 if is_closed else 2)
            ior.append(material.iors)
            absorption.append(material.absorption if "absorption" in effects else (0.0,) * 3)
            reflectance.append((0.0,) * 3)
            fresnel.append(int(material.fresnel and "fresnel" in effects))
        elif isinstance(material, ConductorMaterial):
            code.append(3)
            ior.append((1.0,) * 3)
            absorption.append((0.0,) * 3)
            reflectance.append(material.reflectance)
            fresnel.append(0)
        else:
            code.append(0)
            ior.append((1.0,) * 3)
            absorption.append((0.0,) * 3)
            reflectance.append((0.0,) * 3)
            fresnel.append(0)
    return MaterialTable(tuple(code), tuple(ior), tuple(absorption), tuple(reflectance),
                         tuple(fresnel), tuple(float(e) for e in extent),
                         tuple(int(c) for c in convex),
                         tuple((tuple(map(float, lo)), tuple(map(float, hi)))
                               for lo, hi in bounds))


@dataclass(eq=False)
class Trace:
    """GPU buffers of one trace pass.

    Attributes
    ----------
    records : moderngl.Buffer
        ``count`` x 5 vec4 (see ``caustic_trace.glsl``).
    history : moderngl.Buffer
        ``count`` x (iterations + 1) float32 estimates (m).
    count, iterations : int
    grid : int
        Vertices per side of each view's lattice (0: the settings' grid); a rim patch
        counts as a view of ``rim_patches + 1``.
    patches : bool
        The records are rim patches (``caustic_trace.glsl``).
    handoff : moderngl.Buffer, optional
        Per grid quad, 1 where a rim patch is drawn instead
        (:class:`.rim_patches.RimPatches`).
    """

    records: moderngl.Buffer
    history: moderngl.Buffer
    count: int
    iterations: int
    grid: int = 0
    patches: bool = False
    handoff: moderngl.Buffer | None = None

    def read(self) -> dict[str, np.ndarray]:
        """The records as arrays: origin (K, 3), direction (K, 3), distance (K,),
        hit (K, 3), status (K,) int, flux (K, 3), receiver (K,) int, normal (K, 3),
        view (K,) int, history (K, iterations + 1)."""
        rec = np.frombuffer(self.records.read(), np.float32).reshape(self.count, 5, 4)
        hist = np.frombuffer(self.history.read(), np.float32).reshape(
            self.count, self.iterations + 1)
        return {
            "origin": rec[:, 0, :3].copy(), "view": rec[:, 0, 3].astype(np.int32),
            "direction": rec[:, 1, :3].copy(), "distance": rec[:, 1, 3].copy(),
            "hit": rec[:, 2, :3].copy(), "status": rec[:, 2, 3].astype(np.int32),
            "flux": rec[:, 3, :3].copy(), "receiver": np.rint(rec[:, 3, 3]).astype(np.int32),
            "normal": rec[:, 4, :3].copy(), "history": hist.copy(),
        }

    def give_back(self, resources: ResourcePool) -> None:
        """Return the buffers to the context's pool."""
        resources.give_back(self.records)
        resources.give_back(self.history)


def run_caustic_trace(
    ctx: moderngl.Context, light: LightSetup, *, positions: ReceiverPositions,
    front: ObjectSurfaces, back: ObjectSurfaces | None, materials: MaterialTable,
    grid: int, options: TraceOptions, back_size: int | None = None, channel: int = -1,
    paper: bool = False, covered: int = 0, far: ObjectSurfaces | None = None,
    front_stride: int = 1, patches: RimPatches | None = None,
) -> Trace:
    """Run the vertex grid once; returns the record and history buffers.

    Parameters
    ----------
    back_size : int, optional
        Texels per object view of the exit-surface textures (default ``grid``).
    channel : int
        -1 for all channels, else the one channel (and its IOR) this dispersion
        pass carries.
    paper, covered : bool, int
        The paper's Eq. 6 flux with V = ``covered`` grid texels.
    far : ObjectSurfaces, optional
        The conductors' farthest surfaces at ``grid`` texels per view: with verified
        hits a reflected ray is also tested against this layer for meeting its object
        again.
    front_stride : int
        Texels of ``front`` per grid step (odd; ``grid * front_stride`` per view).
    patches : RimPatches, optional
        Trace these rim patches' vertices (``front_stride + 1`` per side each, record
        layout in ``caustic_trace.glsl``) instead of the grid's.
    """
    iterations = options.iterations
    count = len(light.object_views) * grid * grid
    if patches is not None:
        count = patches.vertices
    resources = pool(ctx)
    records = resources.buffer(count * RECORD_FLOATS * 4)        # every record is written
    history = resources.buffer(count * (iterations + 1) * 4)     # every entry is written
    program = load_program(ctx, "caustic_trace.glsl", compute=True)
    set_light_uniforms(program, light)
    set_object_view_uniforms(program, light)
    units = {"u_receiver_positions": positions.positions, "u_receiver_normals": positions.normals,
             "u_front_positions": front.positions, "u_front_normals": front.normals,
             "u_front_geometric": front.geometric}
    if back is not None:
        units |= {"u_back_positions": back.positions, "u_back_normals": back.normals,
                  "u_back_geometric": back.geometric}
    if far is not None:
        units |= {"u_far_positions": far.positions, "u_far_normals": far.normals}
    for unit, (name, tex) in enumerate(units.items()):
        tex.use(location=unit)
        set_uniform(program, name, unit)
    pad = MAX_OBJECTS - len(materials.code)
    set_uniform(program, "u_material", np.array(materials.code + (0,) * pad, np.int32))
    for name, values in (("u_ior", materials.ior), ("u_absorption", materials.absorption),
                         ("u_reflectance", materials.reflectance)):
        set_uniform(program, name, np.array(values + ((0.0,) * 3,) * pad, np.float32))
    set_uniform(program, "u_fresnel", np.array(materials.fresnel + (0,) * pad, np.int32))
    extent = materials.extent or (0.0,) * len(materials.code)
    set_uniform(program, "u_extent", np.array(extent + (0.0,) * pad, np.float32))
    convex = materials.convex or (0,) * len(materials.code)
    set_uniform(program, "u_convex", np.array(convex + (0,) * pad, np.int32))
    # Unknown bounds: a box no exit ray leaves within its object's extent.
    unbounded = ((-1e30,) * 3, (1e30,) * 3)
    bounds = materials.bounds or (unbounded,) * len(materials.code)
    for k, name in enumerate(("u_bound_lo", "u_bound_hi")):
        set_uniform(program, name, np.array([b[k] for b in bounds] + [unbounded[k]] * pad,
                                            np.float32))
    for name, value in (
        ("u_positions_size", positions.size), ("u_grid", grid),
        ("u_back_size", back_size or grid), ("u_channel", channel),
        ("u_paper", int(paper)), ("u_covered", float(covered)),
        ("u_estimator", ESTIMATORS[options.estimator]),
        ("u_safeguarded", int(options.safeguarded)), ("u_iterations", iterations),
        ("u_eps", float(options.eps)), ("u_exit_iterations", options.exit_iterations),
        ("u_filtered", int(options.filtered)), ("u_start", int(options.start == "fixed")),
        ("u_start_distance", float(options.start_distance)), ("u_verify", int(options.verify)),
        ("u_hit_tolerance", float(options.hit_tolerance or 0.0)), ("u_count", count),
        ("u_converged", float(options.converged)), ("u_has_far", int(far is not None)),
        ("u_front_stride", front_stride), ("u_patches", int(patches is not None)),
        ("u_reflected_search", int(options.reflected_search)),
        ("u_contact_test", int(options.contact_test)),
        ("u_facet_side", int(options.facet_side_test)),
        ("u_depth_spread", int(options.depth_spread)),
        ("u_open_escape", int(options.open_escape)),
        ("u_box_samples", int(options.box_samples)),
        ("u_shading_correction", int(options.shading_correction)),
    ):
        set_uniform(program, name, value)
    records.bind_to_storage_buffer(0)
    history.bind_to_storage_buffer(1)
    if patches is None:
        program.run((count + 63) // 64)
        ctx.memory_barrier()
        return Trace(records, history, count, iterations)
    # The patches' vertices that their owners trace (rim_patches.glsl), then the
    # copies of them the neighbouring patches hold.
    for binding, buffer in ((2, patches.quads), (3, patches.unique), (4, patches.dispatch)):
        buffer.bind_to_storage_buffer(binding)
    program.run_indirect(patches.dispatch)
    ctx.memory_barrier()
    trace = Trace(records, history, count, iterations, grid=front_stride + 1, patches=True)
    patches.copy_shared(ctx, trace)
    return trace
