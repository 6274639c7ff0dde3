"""Where the light went: the flux budget of one method render.

The caustics-mapping renderer traces the light through its vertex grid and records,
per vertex status, the share of the traced flux (``status_flux_fraction``) and the
watts of the splatted and lost vertices (``splatted_flux``, ``lost_flux``); the
stability check adds the share splatted by vertices whose exact ray meets no
receiver (``off_receiver_flux_fraction``). With the flux on the receiver maps, of
the method and of the reference, this says why a flux ratio is far from 1: light
lost to total internal reflection, held back unconverged, splatted where no
receiver is, or never emitted (a dark light).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from renderers.results import ReceiverMap
from reports.records import Table

__all__ = ["BUDGET_COLUMNS", "METHOD_ROW", "REFERENCE_ROW", "flux_budget"]

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
    method_w, reference_w = _received(method_maps), _received(reference_maps)
    for label, value in ((METHOD_ROW, method_w), (REFERENCE_ROW, reference_w)):
        fraction = value / traced if traced else None
        rows.append((label, value, fraction))
    return Table(BUDGET_COLUMNS, tuple(rows))
