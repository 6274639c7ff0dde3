"""The temporal study's data files beside a comparison's: ``temporal.csv`` (one row
per frame; written by :func:`harness.compare.outputs.write_comparison` as its other
tables), the per-pixel maps as EXR (``temporal_flicker.exr``,
``temporal_flicker_floor.exr``, ``temporal_hf_ratio.exr``, receiver (u, v) layout,
row 0 at vmin, the value in every channel), and the ``temporal`` object of
``metrics.json``."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from renderers.exr import write_exr
from reports.temporal_records import TemporalComparison

__all__ = ["temporal_json", "write_temporal_maps"]


def temporal_json(temporal: TemporalComparison | None) -> dict[str, Any] | None:
    """``metrics.json``'s ``temporal``: the study's summary (flicker per region with
    noise floor and excess, energy ratios, per-frame means, frame and run times, the
    reference's seeds, formulas) and the names of its files; None when it did not run."""
    if temporal is None:
        return None
    return {**temporal.summary, "files": dict(temporal.files)}


def write_temporal_maps(scene_dir: str | Path, temporal: TemporalComparison | None) -> None:
    """Write the per-pixel maps named in ``temporal.files`` (nothing when None)."""
    if temporal is None:
        return
    for key, array in temporal.maps.items():
        name = temporal.files.get(key)
        if name is None:
            continue
        values = np.asarray(array, np.float32)
        write_exr(Path(scene_dir) / name, {"RGB": np.repeat(values[..., None], 3, axis=2)})
