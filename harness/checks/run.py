"""Every accuracy check that applies to one comparison, as ``caustics compare`` runs
them, with the same functions the test suite uses.

* **Physical requirements** on this run: the method's outputs against this run's
  reference (finite, energy, flux agreement, no TIR in a sphere) and, where the
  ideal-sphere answer describes the scene, the reference against it (its receiver
  maps, and its camera's lens image: :mod:`harness.checks.camera`). Any scene.
* **Method targets**: this run's measures, for a committed scene run without setting
  overrides (the targets hold at the scene's own settings).
* **Regression locks**: the method re-rendered at the golden settings against the
  golden reference, for a committed scene (:mod:`harness.checks.locks`).

Where a kind does not apply, the reason is returned beside the checks; a missing or
unreadable file is an error naming it, never "no checks".
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from harness.checks import GAPS_FILE, TARGETS_FILE
from harness.checks.bounds import Bound, Gap, Target, load_gaps, load_locks, load_targets
from harness.checks.camera import camera_measures, camera_requirements, exact_camera
from harness.checks.golden import GOLDEN_SETTINGS, load_golden
from harness.checks.locks import (
    LOCKED_METHODS,
    golden_applies,
    lock_checks,
    not_committed,
    realtime_maps,
)
from harness.checks.physical import (
    apply_gaps,
    method_requirements,
    reference_requirements,
)
from harness.checks.targets import check_targets, target_measures
from renderers.methods import Method
from renderers.results import ReceiverMap
from reports.records import CHECK_KINDS, Check
from scenes import Scene, load_scene, with_settings
from scenes.geometry import SceneGeometry

__all__ = ["CheckFiles", "Checked", "comparison_checks", "count_by_kind", "load_check_files"]


@dataclass(frozen=True)
class CheckFiles:
    """The three reviewed files, loaded."""

    locks: tuple[Bound, ...]
    targets: tuple[Target, ...]
    gaps: tuple[Gap, ...]


def load_check_files(locks: Path, targets: Path = TARGETS_FILE,
                     gaps: Path = GAPS_FILE) -> CheckFiles:
    """Load all three; each missing or unreadable file raises, naming it."""
    return CheckFiles(load_locks(locks), load_targets(targets), load_gaps(gaps))


@dataclass(frozen=True)
class Checked:
    """The checks that applied, and why each kind that did not, did not."""

    checks: tuple[Check, ...]
    not_applied: dict[str, str] = field(default_factory=dict)


def count_by_kind(checks) -> dict[str, dict[str, int]]:
    """Per kind (:data:`reports.records.CHECK_KINDS`): checked, passed, failed,
    undecided (the interval straddles the bound) and known gaps (a known gap is
    neither passed nor failed)."""
    out = {}
    for kind in CHECK_KINDS:
        mine = [c for c in checks if c.kind == kind]
        out[kind] = {"checked": len(mine),
                     "passed": sum(1 for c in mine if c.outcome in ("pass", "gap closed")),
                     "failed": sum(1 for c in mine if c.outcome == "FAIL"),
                     "undecided": sum(1 for c in mine if c.outcome == "undecided"),
                     "known gaps": sum(1 for c in mine if c.outcome == "known gap")}
    return out


def _maps(images: dict[str, np.ndarray], geometry, layer: str,
          seed_maps=None) -> list[ReceiverMap]:
    maps = []
    for i, receiver in enumerate(geometry.receivers):
        variance = seeds = None
        if layer == "reference":
            variance = images.get(f"receiver{i}/reference_variance")
            seeds = seed_maps[i] if seed_maps is not None else None
        maps.append(ReceiverMap(np.asarray(images[f"receiver{i}/{layer}"]),
                                receiver.extent, variance, seed_maps=seeds))
    return maps


def _unchanged(scene: Scene, method: Method, scenes_dir: Path) -> bool:
    """The scene's settings are the committed file's, after the method configured both
    (no ``--set`` or other override)."""
    try:
        committed = method.configure(load_scene(Path(scenes_dir) / f"{scene.name}.toml"))
    except Exception:  # any failure means "not the committed scene"
        return False
    return committed.settings == scene.settings


def comparison_checks(scene: Scene, method: Method, *, geometry: SceneGeometry,
                      images: dict[str, np.ndarray], stability: dict | None,
                      status_counts: dict | None, files: CheckFiles, scenes_dir: Path,
                      golden_dir: Path, metrics=(), seed_maps=None, ctx=None) -> Checked:
    """All checks of one comparison (module docstring).

    Parameters
    ----------
    scene : Scene
        The scene as the method configured it (``method.configure``).
    method : Method
        The method compared.
    geometry : SceneGeometry
        The scene's meshes.
    images : dict of str to ndarray
        The comparison's images (``reports.records``): ``receiver<i>/method``,
        ``receiver<i>/reference``, ``receiver<i>/reference_variance``, and the
        camera's ``camera/method`` and ``camera/reference`` when it was compared.
    stability : dict or None
        The render's numerical-stability summary.
    status_counts : dict or None
        The caustics-mapping per-status vertex counts (method targets on them).
    files : CheckFiles
        Locks, targets and gaps.
    seed_maps : sequence of ndarray (K, H, W, 3) or None, optional
        The reference's per-seed maps per receiver: *flux agreement*'s interval comes
        from their totals' spread (:func:`harness.checks.physical.seed_flux_interval`).
    metrics : sequence of MetricValue
        The comparison's records: the method targets on relMSE quote (and are judged
        from the interval of) its ``receiver0 / caustic / relmse`` record.
    scenes_dir, golden_dir : Path
        The committed scenes and the golden references.
    """
    if not all(f"receiver{i}/method" in images for i in range(len(geometry.receivers))):
        # A method that gave no receiver maps (a camera-only external render): every
        # kind of check is made on the maps, the camera's on the reference's maps too.
        why = "the method gave no receiver maps; the checks are made on them"
        return Checked((), {"physical requirement": why, "method target": why,
                            "regression lock": why})
    method_maps = _maps(images, geometry, "method")
    reference_maps = _maps(images, geometry, "reference", seed_maps)
    not_applied = {}
    checks = []
    stability = stability or {}
    if "flux_over_bound" in stability:
        checks += method_requirements(scene, geometry, method_maps=method_maps,
                                      reference_maps=reference_maps, stability=stability)
    else:
        not_applied["physical requirement (method)"] = "no stability summary"
    if all(m.variance is not None for m in reference_maps):
        checks += reference_requirements(scene, geometry, reference_maps)
    # As for the maps: the reference's checks run on a real reference (with variance).
    has_camera = ("camera/method" in images and "camera/reference" in images
                  and all(m.variance is not None for m in reference_maps))
    exact = None
    if has_camera:
        height, width = np.shape(images["camera/reference"])[:2]
        exact = exact_camera(scene, reference_maps, resolution=(width, height))
    if exact is not None:
        checks += camera_requirements(exact, images["camera/reference"])
    checks = apply_gaps(checks, files.gaps, scene=scene.name, method=method.name)

    why = not_committed(scene, scenes_dir)
    if why is None and not _unchanged(scene, method, scenes_dir):
        why = "settings differ from the committed scene's"
    if why is None:
        relmse = next((m for m in metrics
                       if (m.view, m.region, m.metric) == ("receiver0", "caustic", "relmse")),
                      None)
        measures, intervals = target_measures(reference_maps[0], method_maps[0],
                                              relmse=relmse, stability=stability,
                                              status_counts=status_counts)
        if exact is not None:
            measures.update(camera_measures(exact, images["camera/method"]))
        checks += check_targets(files.targets, scene=scene.name, method=method.name,
                                measures=measures, intervals=intervals)
    else:
        not_applied["method target"] = why
    why = golden_applies(scene, scenes_dir, golden_dir)
    if why is None and method.name not in LOCKED_METHODS:
        why = f"no locks for method {method.name}"
    if why is None:
        golden = load_golden(golden_dir, scene.name)
        at_golden = with_settings(scene, {"receiver_map": GOLDEN_SETTINGS["receiver_map"]})
        maps = realtime_maps(at_golden, ctx=ctx)
        checks += lock_checks(scene, method.name, maps, golden, files.locks)
    else:
        not_applied["regression lock"] = why
    return Checked(tuple(checks), not_applied)
