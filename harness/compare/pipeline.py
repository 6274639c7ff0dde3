"""One comparison pipeline: scene and method in, a
:class:`~reports.records.SceneComparison` out, shared by ``caustics compare``, sweep
rows, the Python API and third-party methods.

The stages, in order (``docs/architecture.md``):

1. **configure** — the method fills the scene's unset settings (a caustics-mapping
   preset its choices);
2. **references** — the Mitsuba reference (cached, shared by every method) and an
   independent one on disjoint seeds (the noise floor);
3. **render** — the method's render through its protocol's ``render``, timed by the
   one timing function (:func:`harness.compare.timed.timed_render`; a method with a
   GL runner in the runner's context, which its studies share);
4. **score** — every metric per view and region, stability, flux budgets
   (:func:`harness.compare.scoring.score_render`); a reference with no caustic ends
   the comparison here with the status ``no caustic``
   (:data:`reports.records.NO_CAUSTIC`);
5. **studies** — each registered study the options name that applies to the method
   adds a typed section (:mod:`harness.compare.studies`);
6. **checks** — the accuracy checks of every kind (:mod:`harness.checks.run`);
7. **cross-check** — the reference against an independent renderer (LuxCore);
8. **headlines** — last, so that they can cite the checks
   (:mod:`harness.compare.headlines`).

Writing the data files and the page is the caller's (``harness.compare.isolation``).
A sweep row passes its references and its render in (they are Dask tasks of their
own) and runs the rest.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path

from harness.checks import GOLDEN_DIR, LOCKS_FILE
from harness.checks.run import CheckFiles, comparison_checks, load_check_files
from harness.checks.stability import convergence_outcomes
from harness.compare.headlines import with_headlines
from harness.compare.provenance import provenance
from harness.compare.scoring import References, Scored, has_caustic, score_render
from harness.compare.studies import Study, StudyContext, registered_studies
from harness.compare.timed import TimedRender, gl_runner, timed_render
from harness.crosscheck import run_crosscheck
from harness.studies.timing import MIN_REPEATS
from renderers.methods import Method
from renderers.mitsuba.reference import render_reference
from reports.records import COMPARED, NO_CAUSTIC, SceneComparison, Section
from scenes import SCENES_DIR, Scene, effects_of, with_settings
from scenes.geometry import build_geometry

__all__ = ["CheckOptions", "CompareOptions", "CrossCheckOptions", "default_studies",
           "known_studies", "render_references", "run_comparison"]


def known_studies() -> tuple[str, ...]:
    """Every name ``--studies`` accepts: ``metrics`` (the scoring stage, always run)
    and each registered study."""
    return ("metrics", *(s.name for s in registered_studies()))


def default_studies() -> tuple[str, ...]:
    """The studies run when none are named: ``metrics`` and every study that is not
    optional."""
    return ("metrics", *(s.name for s in registered_studies() if not s.optional))


@dataclass(frozen=True)
class CompareOptions:
    """How much to compute.

    Attributes
    ----------
    studies : tuple of str or None
        Names from :func:`known_studies` (``metrics`` is always computed); None: the
        :func:`default_studies`.
    frames : int or None
        Frames of the temporal study (None: the scene's ``[animation] frames``).
    max_iterations : int
        Iterations 0..N of the convergence table.
    quick : bool
        Smaller sweeps and one timing repeat (a quick look, not for reporting);
        otherwise :data:`~harness.studies.timing.MIN_REPEATS`.
    cache, use_cache
        Reference cache root (None: the default) and whether to use it.
    progress : bool
        Progress bars on stderr.
    dense_grid : int or None
        Lattice side of the decomposition's step 0 (dense exact paths); None, or
        ``quick``, leaves the step out.
    """

    studies: tuple[str, ...] | None = None
    max_iterations: int = 8
    quick: bool = False
    cache: str | None = None
    use_cache: bool = True
    progress: bool = True
    frames: int | None = None
    dense_grid: int | None = 1024

    @property
    def repeats(self) -> int:
        """Timed renders per configuration (the median is kept)."""
        return 1 if self.quick else MIN_REPEATS

    @property
    def selected(self) -> tuple[str, ...]:
        """The studies to run: :attr:`studies`, or the defaults."""
        return self.studies if self.studies is not None else default_studies()


@dataclass(frozen=True)
class CheckOptions:
    """The accuracy checks' files and folders (``harness.checks``).

    Attributes
    ----------
    files : CheckFiles
        Regression locks, method targets and known gaps, loaded.
    scenes_dir, golden_dir : Path
        The committed scenes (targets and locks apply to them unchanged) and the
        golden references.
    """

    files: CheckFiles = field(default_factory=lambda: load_check_files(LOCKS_FILE))
    scenes_dir: Path = SCENES_DIR
    golden_dir: Path = GOLDEN_DIR


@dataclass(frozen=True)
class CrossCheckOptions:
    """The cross-check's photon counts (``caustics crosscheck``).

    Attributes
    ----------
    photons : int
        Mitsuba photons per seed, and LuxCore light paths per film.
    """

    photons: int


def render_references(scene: Scene, options: CompareOptions = CompareOptions()) -> References:
    """The reference of ``scene`` and an independent one on the disjoint seeds
    ``seed + K .. seed + 2K − 1`` (cached per ``options``)."""
    s = scene.settings
    kwargs = {"cache": options.cache, "use_cache": options.use_cache,
              "progress": options.progress}
    return References(render_reference(scene, **kwargs),
                      render_reference(with_settings(scene, {"seed": s.seed + s.seeds}),
                                       **kwargs))


def _studies(context: StudyContext, studies: list[Study]) -> dict[str, Section]:
    """Run ``studies`` in order; each sees the sections of those before it."""
    for study in studies:
        section = study.run(context)
        if section is not None:
            context.sections[section.name] = section
    return context.sections


def run_comparison(scene: Scene, method: Method, *,
                   options: CompareOptions = CompareOptions(),
                   checks: CheckOptions | None = None,
                   crosscheck: CrossCheckOptions | None = None,
                   references: References | None = None,
                   render: TimedRender | None = None,
                   sweep: dict | None = None) -> SceneComparison:
    """Compare ``method`` on ``scene`` with the reference, stage by stage (module
    docstring).

    Parameters
    ----------
    scene : Scene
        The scene as loaded (the method configures it).
    method : Method
        The method (``renderers.methods.load_method(name)``).
    options : CompareOptions
        Studies, repeats, cache.
    checks : CheckOptions, optional
        Run the accuracy checks (None: none are run).
    crosscheck : CrossCheckOptions, optional
        Cross-check the reference with LuxCore (None: not run).
    references : References, optional
        Already rendered references of the configured scene (a sweep's); else rendered
        (or read from the cache).
    render : TimedRender, optional
        The method's render, already timed (a sweep's); else rendered here.
    sweep : dict, optional
        A sweep row's settings, recorded in the provenance.

    Returns
    -------
    SceneComparison
        Its ``status``: :data:`~reports.records.COMPARED`, or
        :data:`~reports.records.NO_CAUSTIC` when the reference puts no caustic light on
        any receiver (scored, without studies, checks or cross-check).
    """
    scene = method.configure(scene)
    references = references or render_references(scene, options)
    wanted = [s for s in registered_studies()
              if s.name in options.selected and s.applies(method)]
    with gl_runner(method, scene, repeats=options.repeats,
                   needed=render is None or bool(wanted)) as runner:
        geometry = runner.geometry if runner is not None else build_geometry(scene)
        render = render or timed_render(method, scene, repeats=options.repeats, runner=runner)
        scored = score_render(scene, geometry, render, references)
        if not has_caustic(references.reference):
            # A scene with no caustic poses no question: its scores and files say where
            # the light went; no study, check or cross-check runs on it.
            return _assemble(scene, method, scored, render, references, sweep=sweep,
                             status=NO_CAUSTIC)
        sections = _studies(StudyContext(scene, method, geometry, render, references, scored,
                                         runner, options, {}), wanted)
    stability = dict(scored.stability)
    if "convergence" in sections:
        stability |= convergence_outcomes(sections["convergence"].table)
    found, not_applied = (), {}
    if checks is not None:
        checked = comparison_checks(scene, method, geometry=geometry, images=scored.images,
                                    stability=stability,
                                    status_counts=render.result.metadata.get("status_counts"),
                                    files=checks.files, scenes_dir=checks.scenes_dir,
                                    golden_dir=checks.golden_dir, metrics=scored.metrics,
                                    seed_maps=[m.seed_maps for m in
                                               references.reference.receivers])
        found, not_applied = checked.checks, checked.not_applied
    table = cross = None
    if crosscheck is not None:
        result = run_crosscheck(scene, photons=crosscheck.photons, seeds=scene.settings.seeds,
                                other_photons=crosscheck.photons)
        table, cross = result.table(), result.provenance
    return _assemble(scene, method, scored, render, references, sweep=sweep,
                     stability=stability, sections=tuple(sections.values()), checks=found,
                     checks_not_applied=not_applied, crosscheck=table,
                     crosscheck_provenance=cross)


def _assemble(scene: Scene, method: Method, scored: Scored, render: TimedRender,
              references: References, *, sweep: dict | None, status: str = COMPARED,
              stability: dict | None = None,
              sections: tuple[Section, ...] = (), checks: tuple = (),
              checks_not_applied: dict | None = None, crosscheck=None,
              crosscheck_provenance: dict | None = None) -> SceneComparison:
    """The comparison from its stages' results, headlines made last."""
    return with_headlines(SceneComparison(
        name=scene.name, description=scene.info.description, source=scene.source,
        effects=effects_of(scene), settings=asdict(scene.settings), method=method.name,
        method_description=method.description, metrics=scored.metrics, images=scored.images,
        exposure=scored.exposure, files=scored.files,
        provenance=provenance(scene.source, method, render, references, notes=scored.notes,
                              reference_noise=scored.reference_noise,
                              checks_not_applied=checks_not_applied,
                              crosscheck=crosscheck_provenance, sweep=sweep),
        stability=scored.stability if stability is None else stability,
        budgets=scored.budgets, sections=sections, checks=checks, crosscheck=crosscheck,
        status=status))
