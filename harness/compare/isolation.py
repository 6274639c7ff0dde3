"""One scene's comparison, data files and page, or its failure: a scene that fails
costs its own row, never the run.

Whatever goes wrong inside one scene and method (a renderer error, a NaN that a
later step cannot take, a bug) becomes a :class:`~reports.records.SceneFailure`:
a failure row in the index, a page with the one-line error, ``failure.json``
beside it; the run goes on with the next scene. An interrupt (Ctrl-C) is not a
failure of the scene and ends the run.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from harness.compare.budget import REFERENCE_ROW
from harness.compare.outputs import write_comparison, write_json
from harness.terminal import error_line
from reports.build import write_page
from reports.plots import write_pdfs
from reports.records import SceneComparison, SceneFailure
from scenes import Scene, SceneError
from scenes.errors import HarnessError

__all__ = ["FAILURE_JSON", "NoCausticError", "load_failure", "run_scene", "scene_failure",
           "write_failure"]

#: Written into a failed scene's folder: the failure record as strict JSON.
FAILURE_JSON = "failure.json"


class NoCausticError(HarnessError):
    """The reference puts no caustic light on any receiver: nothing to compare."""


def _reference_caustic_watts(comparison: SceneComparison) -> float | None:
    """The reference's caustic flux on the receivers (W), from the flux budget."""
    if comparison.flux_budget is None:
        return None
    for row in comparison.flux_budget.records():
        if row["item"] == REFERENCE_ROW:
            return row["flux_w"]
    return None


def scene_failure(scene: Scene, method: str, error: BaseException, *, stage: str,
                  comparison: SceneComparison | None = None) -> SceneFailure:
    """The failure record of ``scene`` and ``method``; ``comparison``, when the
    comparison itself finished, lends its flux budget."""
    return SceneFailure(name=scene.name, method=method, source=scene.source,
                        error=error_line(error), stage=stage,
                        description=scene.info.description,
                        flux_budget=comparison.flux_budget if comparison else None)


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


def run_scene(out_dir: Path, folder: str, scene: Scene, method: str,
              compare: Callable[[], SceneComparison], *, self_contained: bool = False,
              ) -> tuple[SceneComparison | SceneFailure, dict[str, Any]]:
    """Run ``compare`` and write its data files, PDFs and page into
    ``out_dir/folder``; on any exception, the failure's page and ``failure.json``.

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
        write_comparison(out_dir / folder, comparison)
        write_pdfs(out_dir / folder, comparison)
        stage = "comparison"
        if _reference_caustic_watts(comparison) == 0.0:
            # Every metric of the caustic would be NaN: the scene failed to pose
            # the question (its data files stay beside the failure page).
            raise NoCausticError("no caustic: the reference puts no caustic light on any "
                                 "receiver (check where the light, objects and receivers are)")
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
