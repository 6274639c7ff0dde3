"""Where the light went: the flux budget of one method render.

The caustics-mapping renderer traces the light through its vertex grid and records,
per vertex status, the share of the traced flux (``status_flux_fraction``) and the
watts of the splatted and lost vertices (``splatted_flux``, ``lost_flux``); the
stability check adds the share splatted by vertices whose exact ray meets no
receiver (``off_receiver_flux_fraction``) and sorts the vertices left without a
verified hit (lost, unconverged, diverged) by their exact rays
(:func:`harness.checks.stability.search_outcomes`): the light leaves the scene, meets
an object again (a chain the method does not model), or the estimator failed (a
receiver is on the ray: the one share a physical requirement bounds); and, of the
vertices the method's tests ended as re-entering an object, those whose exact ray
meets a receiver first (light the tests dropped). With the flux
on the receiver maps, of the method and of the reference, this says why a flux ratio
is far from 1: light lost to total internal reflection, held back unconverged,
splatted where no receiver is, or never emitted (a dark light).

Budgets of both sides (:func:`method_budget`, :func:`reference_budget_table`), in
watts per RGB channel, each as a :class:`Table` of :data:`SIDE_COLUMNS` whose rows
have a ``role``:

* ``emitted``: the flux each side sends toward the object. The method: the flux of
  every grid vertex it traced (the light through the object grid, i.e. the
  object's silhouette seen from the light). The reference: the flux its
  caustic-only photons carry toward the objects' bounding spheres.
* ``part``: where that flux went; the parts of one side add up to its emitted flux.
  The method: per vertex status (lost, total internal reflection, unconverged,
  diverged, no exit surface, re-entered) from the per-vertex records, and the flux on its
  receiver maps (Σ E · texel area) for the splatted vertices. The reference: the
  items of :data:`renderers.mitsuba.photons.BUDGET_ITEMS`, from a separate
  caustic-only trace (:func:`harness.compare.probe.reference_budget`).
* ``detail``: a share of one part, not added (the splatted vertices' own flux; the
  splats off every receiver; the exact fates of the vertices without a verified hit,
  :data:`SEARCH_ROWS`; the reference trace's maps).
* ``unaccounted``: emitted minus the parts. Not a part: a closing budget has it at
  float round-off (both sides measured ~1e-5 of the emitted flux), so anything
  larger is flux a side created or lost without saying where (the method: splats
  whose kernel does not integrate to their flux on the maps).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from harness.compare.probe import BUDGET_PHOTONS, reference_budget
from renderers.caustics_mapping.caustic_trace import STATUS
from renderers.results import ReceiverMap
from reports.records import Table
from scenes import Scene

__all__ = ["BUDGET_COLUMNS", "METHOD_ROW", "REFERENCE_ROW", "SEARCH_ROWS", "SIDE_COLUMNS",
           "budget_closure",
           "flux_budget", "method_budget", "reference_budget_table", "side_budgets"]

BUDGET_COLUMNS = ("item", "flux_w", "fraction")
#: The budget rows of the caustic flux on the receivers (W), method and reference.
METHOD_ROW, REFERENCE_ROW = "on the receivers: method maps", "on the receivers: reference"

#: Status of the grid's vertices (``status_flux_fraction`` keys) and their labels.
_STATUS_ROWS = (
    ("hit", "splatted on a receiver (hit)"),
    ("lost", "lost: no receiver found"),
    ("tir", "total internal reflection at the exit"),
    ("unconverged", "unconverged: held back by verified hits"),
    ("diverged", "diverged"),
    ("no_exit", "no exit surface found"),
    ("reentered", "re-entered the object: the two-transmission chain ends"),
)


#: The exact fates of the vertices whose search ended without a verified hit, and the
#: re-entered ones' light that reaches a receiver (keys of
#: :func:`harness.checks.stability.search_outcomes`), their ``key`` and label.
SEARCH_ROWS = (
    ("leaves_scene_flux_fraction", "leaves_scene",
     "  of the lost, unconverged, diverged: leaves the scene (exact ray meets nothing)"),
    ("meets_object_flux_fraction", "meets_object",
     "  of the lost, unconverged, diverged: meets an object again (a chain not modelled)"),
    ("estimator_failed_flux_fraction", "estimator_failed",
     "  of the lost, unconverged, diverged: estimator failed (exact ray meets a receiver)"),
    ("reentered_reaches_receiver_flux_fraction", "reentered_reaches_receiver",
     "  of the re-entered: a test ended it, but the exact ray meets a receiver first"),
)


def _traced_watts(metadata: Mapping, shares: Mapping[str, float]) -> float | None:
    """The flux the grid traced (W, summed over channels), from a status whose
    watts and share are both known; 0 when nothing was traced; None if unknown."""
    for status, key in (("hit", "splatted_flux"), ("lost", "lost_flux")):
        share = float(shares.get(status, 0.0))
        watts = metadata.get(key)
        if share > 0 and watts is not None:
            return float(np.sum(watts)) / share
    if shares and all(float(v) == 0.0 for v in shares.values()):
        return 0.0
    return None


def _received(maps: Sequence[ReceiverMap]) -> float:
    return float(sum(np.sum(m.total_flux()) for m in maps))


def flux_budget(metadata: Mapping, stability: Mapping | None,
                method_maps: Sequence[ReceiverMap],
                reference_maps: Sequence[ReceiverMap]) -> Table:
    """The budget as a :class:`Table` (columns :data:`BUDGET_COLUMNS`): the traced
    flux, its share per vertex status and off the receivers, and the caustic flux on
    the receivers, the method's and the reference's. ``fraction`` is of the traced
    flux; a watt value that cannot be known is None. A method that records no
    statuses gets the receiver rows only.
    """
    shares = metadata.get("status_flux_fraction") or {}
    traced = _traced_watts(metadata, shares) if shares else None

    def watts(fraction):
        return None if traced is None or fraction is None else traced * fraction

    rows = []
    if shares:
        rows.append(("traced: light through the object grid", traced, 1.0))
        for status, label in _STATUS_ROWS:
            if status in shares:
                share = float(shares[status])
                rows.append((label, watts(share), share))
        off = (stability or {}).get("off_receiver_flux_fraction")
        if off is not None:
            rows.append(("  of the hits: off every receiver (exact ray)", watts(off), off))
        for key, _, label in SEARCH_ROWS:
            share = (stability or {}).get(key)
            if share is not None:
                rows.append((label, watts(share), share))
    # A method that gave no receiver maps (a camera-only external render) has no
    # received flux to state.
    method_w = _received(method_maps) if method_maps else None
    reference_w = _received(reference_maps)
    for label, value in ((METHOD_ROW, method_w), (REFERENCE_ROW, reference_w)):
        fraction = value / traced if traced and value is not None else None
        rows.append((label, value, fraction))
    return Table(BUDGET_COLUMNS, tuple(rows))


#: Columns of :func:`method_budget` and :func:`reference_budget_table`: the row's
#: label and a short ``key`` (the same key on both sides for the same fate:
#: ``emitted``, ``received`` for the flux on the receivers, ``tir``, ...), watts
#: summed over RGB and per channel (None where a side does not know them),
#: ``fraction`` of the side's emitted flux (RGB summed) and its standard error
#: (reference only).
SIDE_COLUMNS = ("item", "key", "role", "flux_w", "flux_r_w", "flux_g_w", "flux_b_w",
                "fraction", "fraction_se")

#: Labels of the reference budget's items (``BUDGET_ITEMS``), in the tracer's order.
REFERENCE_LABELS = {
    "missed": "missed the objects: met nothing, or a receiver straight from the light",
    "tir": "total internal reflection: dropped by the chain rule",
    "cap": "cut: still going after the last event (a chain longer than any counted one)",
    "left": "left the scene off every receiver",
    "uncounted": "reached a receiver along a chain that is not counted",
    "fresnel": "a Fresnel reflection broke the chain",
    "back_or_outside": "reached a receiver's back side or outside its map",
    "absorbed_medium": "absorbed in the medium (Beer-Lambert)",
    "absorbed_surface": "absorbed at a surface (conductor 1 - R, diffuse object)",
    "shading": "shading-normal adjoint factor (negative: a gain)",
    "roulette": "Russian roulette past 64 events (zero in expectation: its sign varies)",
    "deposited": "deposited on a counted chain: the caustic maps",
}
_CAP_ALL_PATHS = "cut by the safety cap of specular events (all-paths mode)"
_UNACCOUNTED = "unaccounted: emitted minus the parts"


def _row(item: str, key: str, role: str, rgb, fraction, *, se=None, total=None) -> tuple:
    if rgb is None:
        return (item, key, role, total, None, None, None, fraction, se)
    rgb = [float(x) for x in np.asarray(rgb, float)]
    return (item, key, role, float(sum(rgb)), *rgb, fraction, se)


def method_budget(metadata: Mapping, stability: Mapping | None,
                  method_maps: Sequence[ReceiverMap],
                  hits: Mapping[str, np.ndarray] | None = None) -> Table | None:
    """The method's budget (:data:`SIDE_COLUMNS`; roles in the module docstring).

    With ``hits`` (the per-vertex records of the render: ``status``, ``flux`` (K, 3)
    W) every part is in watts per channel; without, the parts come from
    ``status_flux_fraction`` times the traced flux, summed over channels. None for a
    method that records no vertex statuses (nothing to budget).
    """
    shares = metadata.get("status_flux_fraction") or {}
    if hits is None and not shares:
        return None
    on_maps = sum((np.asarray(m.total_flux(), float) for m in method_maps), np.zeros(3))
    if hits is not None:
        status = np.asarray(hits["status"])
        flux = np.asarray(hits["flux"], np.float64)
        emitted = flux[status != STATUS["empty"]].sum(axis=0)
        watts = {name: flux[status == code].sum(axis=0) for name, code in STATUS.items()}
        total = float(emitted.sum())
    else:
        total = _traced_watts(metadata, shares)
        if total is None:
            return None
        emitted = None
        watts = {name: None for name in shares}

    def fraction(value) -> float | None:
        return float(np.sum(value)) / total if total > 0 else None

    rows = [_row("emitted toward the object: traced through the object grid", "emitted",
                 "emitted", emitted, 1.0 if total > 0 else None, total=total)]
    parts = []
    for status, label in _STATUS_ROWS:
        if status == "hit" or (hits is None and status not in shares):
            continue
        value = watts.get(status)
        share = fraction(value) if value is not None else float(shares.get(status, 0.0))
        parts.append(value if value is not None else np.full(3, share * total / 3))
        rows.append(_row(label, status, "part", value, share, total=share * total))
    rows.append(_row("splatted: on the receiver maps (sum of E x texel area)", "received", "part",
                     on_maps, fraction(on_maps)))
    parts.append(on_maps)
    if hits is not None:
        rows.append(_row("  of the emitted: the splatted (hit) vertices' own flux", "hit",
                         "detail", watts["hit"], fraction(watts["hit"])))
    off = (stability or {}).get("off_receiver_flux_fraction")
    if off is not None:
        rows.append(_row("  of the splatted: off every receiver (exact ray)", "off_receiver",
                         "detail", None, float(off), total=float(off) * total))
    for key, short, label in SEARCH_ROWS:
        share = (stability or {}).get(key)
        if share is not None:
            rows.append(_row(label, short, "detail", None, float(share),
                             total=float(share) * total))
    rest = (emitted - sum(parts)) if emitted is not None else None
    rest_total = total - float(sum(np.sum(p) for p in parts))
    rows.append(_row(_UNACCOUNTED, "unaccounted", "unaccounted", rest, fraction(rest_total),
                     total=rest_total))
    return Table(SIDE_COLUMNS, tuple(rows))


def reference_budget_table(budget) -> Table:
    """The reference's budget (:data:`SIDE_COLUMNS`) from a
    :class:`harness.compare.probe.ReferenceBudget`: every item with its share's
    standard error, and the trace's own maps as a check of ``deposited``."""
    emitted = np.asarray(budget.emitted_w, float)
    total = float(emitted.sum())
    label = ("emitted toward the objects' bounding spheres" if budget.aimed
             else "emitted by the area light (its photons are not aimed)")
    rows = [_row(label, "emitted", "emitted", emitted, 1.0 if total > 0 else None)]
    for item, value in budget.items_w.items():
        label = REFERENCE_LABELS.get(item, item)
        if item == "cap" and budget.all_paths:
            label = _CAP_ALL_PATHS
        key = "received" if item == "deposited" else item
        rows.append(_row(label, key, "part", value, budget.share.get(item),
                         se=budget.share_se.get(item)))
    if budget.maps_flux_w is not None:
        maps = np.asarray(budget.maps_flux_w, float)
        rows.append(_row("  check of the deposited: flux on the trace's caustic maps", "maps",
                         "detail", maps, float(maps.sum()) / total if total > 0 else None))
    rest = np.asarray(budget.unaccounted_w, float)
    rows.append(_row(_UNACCOUNTED, "unaccounted", "unaccounted", rest,
                     float(rest.sum()) / total if total > 0 else None))
    return Table(SIDE_COLUMNS, tuple(rows))


def budget_closure(table: Table | None) -> float | None:
    """|emitted − Σ parts| / emitted of a side's budget (RGB summed), None when the
    table has no emitted flux."""
    if table is None:
        return None
    records = table.records()
    emitted = next((r["flux_w"] for r in records if r["role"] == "emitted"), None)
    if not emitted:
        return None
    parts = sum(r["flux_w"] for r in records if r["role"] == "part")
    return abs(emitted - parts) / emitted


#: Reference budget traces of this process by reference hash: the presets of one
#: scene share their reference, so they share its budget trace too.
_TRACES: dict = {}
_TRACES_KEPT = 16


def side_budgets(scene: Scene, result, stability: Mapping | None, reference, *,
                 hits: Mapping[str, np.ndarray] | None = None, geometry=None) -> dict:
    """``SceneComparison`` fields ``method_budget``, ``reference_budget`` and
    ``budget_trace`` for one method render (``result``, its per-vertex ``hits`` when
    known) and its reference (a ``RenderResult``: its hash keys the budget trace,
    traced once per process with :func:`harness.compare.probe.reference_budget`)."""
    key = (reference.metadata.get("hash"), BUDGET_PHOTONS)
    trace = _TRACES.get(key) if key[0] else None
    reused = trace is not None
    if trace is None:
        trace = reference_budget(scene, geometry=geometry)
        if key[0]:
            if len(_TRACES) >= _TRACES_KEPT:
                _TRACES.clear()
            _TRACES[key] = trace
    return {"method_budget": method_budget(result.metadata, stability, result.receivers, hits),
            "reference_budget": reference_budget_table(trace),
            "budget_trace": {**trace.provenance(), "reused_from_an_earlier_method": reused}}
