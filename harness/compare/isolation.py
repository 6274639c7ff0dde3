"""One scene's comparison, data files and page, or its failure: a scene that fails
costs its own row, never the run. Every comparison's outputs are written here, one
way (:func:`write_outputs`), by ``compare``, the Python API and sweep rows alike.

Whatever goes wrong inside one scene and method (a renderer error, a NaN that a
later step cannot take, a bug) becomes a :class:`~reports.records.SceneFailure`:
a failure row in the index, a page with the one-line error, ``failure.json``
beside it; the run goes on with the next scene. An interrupt (Ctrl-C) is not a
failure of the scene and ends the run. A comparison that finished without an answer
(its status, e.g. ``no caustic``: :data:`reports.records.STATUS_REASONS`) keeps its
data files and gets a failure row and page that say why (:func:`status_failure`).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from harness.compare.outputs import write_comparison, write_json
from harness.terminal import error_line
from reports.build import write_page
from reports.plots import write_pdfs
from reports.records import STATUS_REASONS, SceneComparison, SceneFailure
from scenes import Scene, SceneError

__all__ = ["FAILURE_JSON", "load_failure", "run_scene", "scene_failure", "status_failure",
           "write_data", "write_failure", "write_outputs"]

#: Written into a failed scene's folder: the failure record as strict JSON.
FAILURE_JSON = "failure.json"


def scene_failure(scene: Scene, method: str, error: BaseException, *, stage: str,
                  comparison: SceneComparison | None = None) -> SceneFailure:
    """The failure record of ``scene`` and ``method``; ``comparison``, when the
    comparison itself finished, lends its flux budget."""
    return SceneFailure(name=scene.name, method=method, source=scene.source,
                        error=error_line(error), stage=stage,
                        description=scene.info.description,
                        flux_budget=comparison.flux_budget if comparison else None)


def status_failure(comparison: SceneComparison) -> SceneFailure | None:
    """The failure record of a comparison that finished without an answer (its
    ``status``: why, as one line; its flux budget kept), or None when it answered."""
    if comparison.answered:
        return None
    return SceneFailure(name=comparison.name, method=comparison.method,
                        source=comparison.source,
                        error=STATUS_REASONS.get(comparison.status, comparison.status),
                        stage="comparison", description=comparison.description,
                        flux_budget=comparison.flux_budget)


def load_failure(source: str, method: str, error: SceneError) -> SceneFailure:
    """The failure record of a scene file that did not load or validate: named by
    the file's stem, its first problem as the error (the others are counted)."""
    first, *rest = error.problems
    more = f" (and {len(rest)} more problems: caustics validate lists them)" if rest else ""
    return SceneFailure(name=Path(source).stem, method=method, source=str(source),
                        error=f"{first}{more}", stage="validation")


def _failure_json(failure: SceneFailure) -> dict[str, Any]:
    return {"scene": {"name": failure.name, "description": failure.description,
                      "source": failure.source},
            "method": {"name": failure.method},
            "failed": {"stage": failure.stage, "error": failure.error},
            "flux_budget": failure.flux_budget.records() if failure.flux_budget else None}


def write_data(folder: Path, comparison: SceneComparison) -> None:
    """A comparison's data files into ``folder``: ``metrics.json``, each table's CSV
    file, the EXR originals (:func:`harness.compare.outputs.write_comparison`) and the
    PDFs of its plots."""
    write_comparison(folder, comparison)
    write_pdfs(folder, comparison)


def write_outputs(out_dir: Path, folder: str, comparison: SceneComparison, *,
                  self_contained: bool = False) -> dict[str, Any]:
    """A comparison's data files (:func:`write_data`) and page into
    ``out_dir/folder``; returns the index row (:func:`reports.build.write_page`)."""
    write_data(out_dir / folder, comparison)
    return write_page(out_dir, comparison, folder=folder, self_contained=self_contained)


def run_scene(out_dir: Path, folder: str, scene: Scene, method: str,
              compare: Callable[[], SceneComparison], *, self_contained: bool = False,
              ) -> tuple[SceneComparison | SceneFailure, dict[str, Any]]:
    """Run ``compare`` and write its outputs into ``out_dir/folder`` (as
    :func:`write_outputs`); on any exception, or a comparison without an answer
    (:func:`status_failure`: its data files are written), the failure's page and
    ``failure.json``.

    Returns
    -------
    item : SceneComparison or SceneFailure
        What the summary reports.
    row : dict
        The index row (:func:`reports.build.write_page`).
    """
    stage, comparison = "comparison", None
    try:
        comparison = compare()
        stage = "data files"
        write_data(out_dir / folder, comparison)
        failure = status_failure(comparison)
        if failure is None:
            stage = "report page"
            return comparison, write_page(out_dir, comparison, folder=folder,
                                          self_contained=self_contained)
    except Exception as error:  # any failure is this scene's, not the run's
        failure = scene_failure(scene, method, error, stage=stage, comparison=comparison)
    return failure, write_failure(out_dir, folder, failure, self_contained=self_contained)


def write_failure(out_dir: Path, folder: str, failure: SceneFailure, *,
                  self_contained: bool = False) -> dict[str, Any]:
    """Write ``failure.json`` and the failure's page into ``out_dir/folder``; returns
    the index row."""
    write_json(out_dir / folder / FAILURE_JSON, _failure_json(failure))
    return write_page(out_dir, failure, folder=folder, self_contained=self_contained)
