"""The error decomposition of one scene and method as a plain record for the report
(built by ``harness.studies.decomposition``)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from reports.records import Table

__all__ = ["DECOMPOSITION_COLUMNS", "DecompositionRecord"]

#: Columns of ``decomposition.csv``: eight per step (step, description, relMSE, SSIM,
#: FLIP, flux ratio, peak ratio, time), then the step before's relMSE,
#: the step's change of it, and the step's time split into where its records came
#: from (``trace_ms``) and the splat passes (``splat_ms``).
DECOMPOSITION_COLUMNS = ("step", "description", "relmse", "ssim", "flip", "flux_ratio",
                         "peak_ratio", "time_ms", "relmse_previous", "relmse_added",
                         "trace_ms", "splat_ms")


@dataclass(frozen=True)
class DecompositionRecord:
    """Where the error of one method on one scene comes from.

    Attributes
    ----------
    table : Table
        One row per step, in order (:data:`DECOMPOSITION_COLUMNS`): ``relmse``,
        ``ssim``, ``flip`` over receiver 0's caustic region; ``flux_ratio`` over the
        whole map; ``peak_ratio`` the largest 3 × 3 box mean of the luminance, step
        over reference; times in ms (warm medians).
    summary : str
        The sentence naming the largest error source, with numbers, and where a later
        step is lower than the one before.
    largest : str
        The step that adds the most relMSE.
    lower : tuple of str
        Steps whose relMSE is below the previous step's (approximations cancelling).
    noise_floor : float or None
        The reference's caustic-region relMSE noise floor (what reference noise alone
        gives; the truth itself scores about half of it).
    noise_floor_kind : str
        ``measured`` (an independent reference) or ``expected`` (from the reference's
        per-texel variance).
    run_time_s : float
        Wall time of the whole study (``time.perf_counter``).
    claims : dict of str to str
        The paper's attributions this decomposition tests, and their verdicts.
    fates : dict of str to float
        Shares of the exact paths' traced flux by fate (``hit``, ``tir``,
        ``no_exit``, ``missed``, ``blocked``, ``back_side``).
    notes : dict of str to Any
        Further numbers (the adjoint shading factor's effect, the lattice, timer).
    """

    table: Table
    summary: str
    largest: str
    lower: tuple[str, ...]
    noise_floor: float | None
    noise_floor_kind: str
    run_time_s: float
    claims: dict[str, str] = field(default_factory=dict)
    fates: dict[str, float] = field(default_factory=dict)
    notes: dict[str, Any] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        """JSON form (``metrics.json`` and the figure's data)."""
        return {"steps": self.table.records(), "summary": self.summary,
                "largest": self.largest, "lower": list(self.lower),
                "noise_floor": self.noise_floor, "noise_floor_kind": self.noise_floor_kind,
                "run_time_s": self.run_time_s, "claims": self.claims, "fates": self.fates,
                "notes": self.notes}
