"""Studies: small plug-ins that add a typed section to a comparison.

A study has a ``name``, says whether it ``applies`` to a method, and ``run`` returns a
:class:`~reports.records.Section` (or None when it has nothing to add). The
pipeline (:mod:`harness.compare.pipeline`) runs every registered study that the
options name, in registration order, after the render has been scored; the section
then reaches ``metrics.json`` (``studies[name]``), its tables the CSV files beside
it, and the page, without any change to the pipeline, the records, the outputs or
the report. A study registers with :func:`register_study`, or from another package
through the entry-point group :data:`GROUP`.

Built in:

========================  ==========================================================
``convergence``           estimator × iteration table and the paper's claims
                          (:mod:`harness.studies.convergence_study`, ``claims``)
``cost``                  cost-versus-accuracy sweep, equal-error speedup
                          (:mod:`harness.studies.cost_study`)
``temporal`` (optional)   the animation frame by frame (:mod:`harness.studies.temporal`)
``decomposition`` (opt.)  where the error comes from (:mod:`harness.studies.decomposition`)
========================  ==========================================================
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from importlib.metadata import entry_points
from typing import Any, Protocol, runtime_checkable

from tqdm import tqdm

from harness.compare.evaluate import exposure_for
from harness.compare.scoring import References, Scored, channel_correlation
from harness.compare.temporal_outputs import temporal_json
from harness.compare.timed import TimedRender
from harness.studies.claims import paper_claims
from harness.studies.convergence_study import convergence_study
from harness.studies.cost_study import cost_study, sweep_size
from harness.studies.decomposition import DecompositionOptions, decomposition_study
from harness.studies.runner import RealtimeRunner
from harness.studies.temporal import TemporalOptions, temporal_study
from harness.terminal import plain
from renderers.methods import Method, has_gl_runner
from reports.records import ConvergenceSection, CostSection, RecordSection, Section
from scenes import Scene
from scenes.animation import animation_of
from scenes.errors import HarnessError
from scenes.geometry import SceneGeometry

__all__ = ["GROUP", "Study", "StudyContext", "StudyError", "register_study",
           "registered_studies", "unregister_study"]

#: Entry-point group through which other packages add studies.
GROUP = "caustics_harness.studies"


class StudyError(HarnessError, ValueError):
    """A study is not a study, or its name is taken."""


@dataclass(frozen=True, eq=False)
class StudyContext:
    """What a study may read.

    Attributes
    ----------
    scene : Scene
        The scene as the method configured it.
    method : Method
    geometry : SceneGeometry
        The meshes both renderers see.
    render : TimedRender
        The method's timed render.
    references : References
        The reference and the independent one.
    scored : Scored
        The metrics, images and stability of the render.
    runner : RealtimeRunner or None
        The method's GL runner (its GL context and settings), for methods with one
        (:func:`renderers.methods.has_gl_runner`).
    options : object
        The comparison's options (:class:`harness.compare.pipeline.CompareOptions`).
    sections : dict of str to Section
        The sections of the studies that ran before this one.
    """

    scene: Scene
    method: Method
    geometry: SceneGeometry
    render: TimedRender
    references: References
    scored: Scored
    runner: RealtimeRunner | None
    options: Any
    sections: dict[str, Section]

    @property
    def caustic(self):
        """Receiver 0's caustic region, (H, W) bool: the scene's
        (:func:`harness.compare.regions.scene_caustic_region`), the texels every record,
        study and check of the scene scores."""
        return self.scored.images["receiver0/mask_caustic"]

    @contextlib.contextmanager
    def progress(self, total: int, label: str) -> Iterator[Callable[[], None]]:
        """A tick function for a progress bar of ``total`` steps on stderr (a no-op
        when the options turn progress off)."""
        if not getattr(self.options, "progress", False):
            yield lambda: None
            return
        bar = tqdm(total=total, desc=plain(f"{self.scene.name}: {label}"), unit="render",
                   leave=False)
        try:
            yield lambda: bar.update(1)
        finally:
            bar.close()


@runtime_checkable
class Study(Protocol):
    """The protocol of a study.

    Attributes
    ----------
    name : str
        The name ``--studies`` uses and the section's key.
    optional : bool
        Run only when named (otherwise also by default).
    """

    name: str
    optional: bool

    def applies(self, method: Method) -> bool:
        """Whether the study can run for ``method``."""
        ...

    def run(self, context: StudyContext) -> Section | None:
        """The study's section (None: nothing to add)."""
        ...


class ConvergenceStudy:
    """Estimator × iteration table against the exact ray-cast distances, and the
    paper's claims judged on it (caustics-mapping methods)."""

    name, optional = "convergence", False

    def applies(self, method: Method) -> bool:
        """Methods with a GL runner only (their estimators are swept in it)."""
        return has_gl_runner(method)

    def run(self, context: StudyContext) -> Section:
        """Convergence table and claims, over receiver 0's scene caustic region."""
        reference = context.references.reference.receivers[0]
        caustic = context.caustic
        options = context.options
        seeds = context.references.reference.metadata.get("seeds")
        top = min(options.max_iterations, 4) if options.quick else options.max_iterations
        with context.progress(6 * (top + 1), "convergence") as tick:
            table = convergence_study(context.runner, reference.irradiance, caustic,
                                      max_iterations=top,
                                      exposure=exposure_for(reference.irradiance),
                                      variance=reference.variance,
                                      seed_maps=reference.seed_maps,
                                      seeds=int(seeds) if seeds else None,
                                      channel_correlation=channel_correlation(context.scene),
                                      progress=tick)
        claims, verdicts = paper_claims(
            table, runner=context.runner, reference=reference, caustic=caustic,
            seeds=seeds)
        return ConvergenceSection(table, claims, verdicts)


class CostStudy:
    """What accuracy costs in time: the sweep of settings against the reference's own
    cost curve, and the equal-error speedup (caustics-mapping methods)."""

    name, optional = "cost", False

    def applies(self, method: Method) -> bool:
        """Methods with a GL runner only (their settings are swept in it)."""
        return has_gl_runner(method)

    def run(self, context: StudyContext) -> Section:
        """The sweep, the speedups warm and cold, and the timing policy."""
        reference = context.references.reference
        ref0 = reference.receivers[0]
        quick = context.options.quick
        seeds = reference.metadata.get("seeds")
        with context.progress(sweep_size(context.runner.settings, quick=quick),
                              "cost sweep") as tick:
            # Scored over the scene's caustic region, as every record of the scene.
            outcome = cost_study(
                context.runner, ref0.irradiance, context.caustic,
                reference_photons=int(reference.metadata["photons"]), quick=quick,
                progress=tick, reference_variance=ref0.variance if seeds else None,
                reference_seeds=int(seeds) if seeds else None,
                channel_correlation=channel_correlation(context.scene),
                reference_seed_maps=ref0.seed_maps)
        return CostSection(outcome.table, outcome.warm, outcome.cold, outcome.point,
                           outcome.timing())


class TemporalSection(RecordSection):
    """The temporal study's section: its JSON form adds the names of its files
    (:func:`harness.compare.temporal_outputs.temporal_json`)."""

    def as_dict(self) -> dict[str, Any]:
        """``metrics.json``'s ``studies.temporal``."""
        return temporal_json(self.record)


class TemporalStudy:
    """The scene's animation rendered frame by frame on both sides (any method)."""

    name, optional = "temporal", True

    def applies(self, method: Method) -> bool:
        """Every method."""
        return True

    def run(self, context: StudyContext) -> Section:
        """Per-frame metrics and the flicker metrics."""
        options = context.options
        count = animation_of(context.scene, frames=options.frames).frames
        ctx = context.runner.ctx if context.runner is not None else None
        with context.progress(3 * count, "temporal") as tick:
            record = temporal_study(context.scene, context.method, ctx=ctx,
                                    options=TemporalOptions(
                                        frames=options.frames, cache=options.cache,
                                        use_cache=options.use_cache, progress=tick))
        return TemporalSection("temporal", "Temporal stability", record,
                               record.files["table"])


class DecompositionStudy:
    """Where the error comes from: exact light paths, then the method's
    approximations one at a time (caustics-mapping methods)."""

    name, optional = "decomposition", True

    def applies(self, method: Method) -> bool:
        """Methods with a GL runner only (their passes are swapped step by step)."""
        return has_gl_runner(method)

    def run(self, context: StudyContext) -> Section:
        """The waterfall; its noise floor is the measured one of receiver 0."""
        floor = next((m.noise_floor for m in context.scored.metrics
                      if (m.view, m.region, m.metric) == ("receiver0", "caustic", "relmse")),
                     None)
        options = context.options
        dense = None if options.quick else options.dense_grid
        with context.progress(4 + (dense is not None), "decomposition") as tick:
            record = decomposition_study(
                context.runner, context.references.reference.receivers[0],
                caustic=context.caustic, noise_floor=floor,
                options=DecompositionOptions(dense_grid=dense, repeats=options.repeats),
                progress=tick)
        return RecordSection("decomposition", "Where the error comes from", record,
                             "decomposition.csv")


_REGISTRY: dict[str, Study] = {}


def register_study(study: Study) -> None:
    """Add ``study`` after those registered before it.

    Raises
    ------
    StudyError
        ``study`` lacks the :class:`Study` protocol, or its name is taken (or is
        ``metrics``, the scoring stage's name).
    """
    if not isinstance(study, Study):
        raise StudyError(f"{study!r} is not a study (needs name, optional, applies, run)")
    if study.name in _REGISTRY or study.name == "metrics":
        raise StudyError(f"a study named {study.name!r} is already registered")
    _REGISTRY[study.name] = study


def unregister_study(name: str) -> None:
    """Remove the study registered as ``name`` (KeyError if there is none)."""
    del _REGISTRY[name]


def _load_entry_points() -> None:
    for entry in entry_points(group=GROUP):
        if entry.name not in _REGISTRY:
            target = entry.load()
            register_study(target() if isinstance(target, type) else target)


def registered_studies() -> tuple[Study, ...]:
    """Every study, built-in first, then those of other packages, in order."""
    _load_entry_points()
    return tuple(_REGISTRY.values())


for _study in (ConvergenceStudy(), CostStudy(), TemporalStudy(), DecompositionStudy()):
    register_study(_study)
