"""The Python API: load a scene, compare methods with the Mitsuba reference, read the
numbers, write the report, without the command line.

A thin public layer over the comparison pipeline (:mod:`harness.compare.pipeline`):
``caustics compare`` runs through :func:`compare`, and so does the pytest plugin
(:mod:`harness.pytest_plugin`). Everything public is in :data:`__all__`; the page
``docs/testing-your-method.md`` walks through it.

>>> from harness.api import compare
>>> result = compare("glass_sphere", ["strong"], studies=("metrics",), quick=True)
>>> m = result.get("strong").metric("relmse", view="receiver0", region="caustic")
>>> m.excess, m.excess_ci95          # the method's own error and its 95 % interval

References are cached (``$CAUSTICS_CACHE_DIR``, default
``~/.cache/caustics-harness/reference``; content-addressed, one lock per key, so two
processes that need the same reference render it once).
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from harness.checks import GOLDEN_DIR, LOCKS_FILE, PHYSICAL
from harness.checks.run import load_check_files
from harness.compare.external import ExternalRender, read_timing
from harness.compare.isolation import (
    load_failure,
    run_scene,
    scene_failure,
    status_failure,
    write_failure,
)
from harness.compare.pipeline import (
    CheckOptions,
    CompareOptions,
    CrossCheckOptions,
    default_studies,
    known_studies,
    run_comparison,
)
from harness.compare.staging import staged_output
from harness.loading import load_scenes as _load_files
from harness.writable import usable_cache
from renderers.methods import Method, load_method
from renderers.mitsuba.cache import cache_dir as default_cache_dir
from renderers.mitsuba.reference import render_reference as _render_reference
from renderers.results import RenderResult
from reports.build import scene_folder, write_index
from reports.records import Check, Headline, MetricValue, SceneComparison, SceneFailure
from scenes import Problem, Scene, SceneError, bundled_scene_names, with_settings
from scenes.errors import HarnessError

__all__ = ["DEFAULT_METHODS", "Comparison", "ComparisonError", "ComparisonSet", "Failure",
           "OptionError", "UnloadedScene", "bundled_scenes", "compare", "load_scene",
           "load_scenes", "render_reference", "score", "write_report"]

#: Methods compared when none is named: both caustics-mapping presets.
DEFAULT_METHODS = ("paper", "strong")

#: What names a scene: a file path, a bundled name (``glass_sphere``,
#: ``hard/tiny_scale``) or a loaded :class:`scenes.Scene`.
SceneLike = str | os.PathLike | Scene
#: What names a method: its registered name or an object with the
#: :class:`renderers.methods.Method` protocol.
MethodLike = str | Method


@dataclass(frozen=True)
class UnloadedScene:
    """A scene that did not load or validate (:func:`load_scenes`): :func:`compare`
    with ``isolate`` gives it a failure row and page per method, without loading it
    again.

    Attributes
    ----------
    source : str
        The file path or bundled name it was given as.
    error : scenes.SceneError
        Its problems, each naming the file and field.
    """

    source: str
    error: SceneError


class OptionError(HarnessError, ValueError):
    """An option of :func:`compare` is not usable (an unknown study, frames without
    the temporal study)."""


class ComparisonError(HarnessError):
    """A comparison failed and ``isolate`` was not asked for.

    Attributes
    ----------
    failure : Failure
        The failure record (scene, method, stage, one-line error) and, when the
        comparison wrote a report, its page.
    """

    def __init__(self, failure: Failure):
        where = f" (page: {failure.page})" if failure.page else ""
        super().__init__(f"{failure.name} / {failure.method} failed ({failure.stage}): "
                         f"{failure.error}{where}")
        self.failure = failure


class _Named:
    """The scene and method names of a result that wraps a record."""

    record: SceneComparison | SceneFailure

    @property
    def name(self) -> str:
        """The scene's name (a file that did not load: its stem)."""
        return self.record.name

    @property
    def method(self) -> str:
        """The method's name."""
        return self.record.method


@dataclass(frozen=True)
class Comparison(_Named):
    """One scene and method compared with the reference.

    Attributes
    ----------
    record : reports.records.SceneComparison
        Everything the comparison produced (metrics, images, checks, headlines,
        studies, provenance).
    scene : scenes.Scene
        The scene as compared (before the method configured it).
    page : Path or None
        The report page, ``<output>/<scene>-<method>/index.html``, when one was written
        (:func:`compare` with ``output``, :func:`write_report`).
    """

    record: SceneComparison
    scene: Scene
    page: Path | None = None

    @property
    def metrics(self) -> tuple[MetricValue, ...]:
        """Every metric, per view and region, with its baseline and excess interval."""
        return self.record.metrics

    def metric(self, metric: str = "relmse", *, view: str = "receiver0",
               region: str = "caustic") -> MetricValue:
        """One metric (``relmse``, ``ssim``, ``flip``, ``flux_ratio``, ...) of ``view``
        (``camera``, ``receiver0``, ...) over ``region`` (``full``, ``caustic``,
        ``object``, ``object_masked``).

        Raises
        ------
        KeyError
            Not computed (the message lists what was).
        """
        try:
            return self.record.metric(view, region, metric)
        except KeyError:
            known = sorted({(m.metric, m.view, m.region) for m in self.metrics})
            raise KeyError(f"no metric {metric!r} of view {view!r} over region {region!r} "
                           f"in {self.record.page}; computed: {known}") from None

    @property
    def checks(self) -> tuple[Check, ...]:
        """The accuracy checks of every kind that applied."""
        return self.record.checks

    @property
    def failed_checks(self) -> tuple[Check, ...]:
        """The checks that failed (known gaps excluded)."""
        return self.record.failed_checks

    @property
    def physical_failures(self) -> tuple[Check, ...]:
        """The physical requirements that failed (known gaps excluded)."""
        return tuple(c for c in self.failed_checks if c.kind == PHYSICAL)

    @property
    def headlines(self) -> tuple[Headline, ...]:
        """The page's banners (verdict, warnings), in order."""
        return self.record.headlines

    @property
    def reference_cache(self) -> dict[str, str]:
        """How each reference was obtained: ``{"reference": "hit" | "miss (why)",
        "independent_reference": ...}``."""
        provenance = self.record.provenance
        return {"reference": str(provenance.reference.get("cache", "")),
                "independent_reference": str(provenance.independent_reference.get("cache", ""))}


@dataclass(frozen=True)
class Failure(_Named):
    """A scene and method whose comparison failed (with ``isolate``, the others go on).

    Attributes
    ----------
    record : reports.records.SceneFailure
        Scene, method, stage and one-line error.
    page : Path or None
        Its page, when a report was written.
    """

    record: SceneFailure
    page: Path | None = None

    @property
    def stage(self) -> str:
        """What was running: ``validation``, ``comparison``, ``data files``, ``report
        page``."""
        return self.record.stage

    @property
    def error(self) -> str:
        """The one-line error."""
        return self.record.error


@dataclass(frozen=True)
class ComparisonSet:
    """What :func:`compare` produced, in scene-then-method order.

    Iterating gives the :class:`Comparison` objects (failures are in
    :attr:`failures`).

    Attributes
    ----------
    items : tuple of Comparison or Failure
        Every scene and method, in order.
    index : Path or None
        The report's ``index.html``, when one was written.
    """

    items: tuple[Comparison | Failure, ...]
    index: Path | None = None

    @property
    def comparisons(self) -> tuple[Comparison, ...]:
        """The comparisons that finished."""
        return tuple(i for i in self.items if isinstance(i, Comparison))

    @property
    def failures(self) -> tuple[Failure, ...]:
        """The comparisons that failed."""
        return tuple(i for i in self.items if isinstance(i, Failure))

    @property
    def records(self) -> tuple[SceneComparison | SceneFailure, ...]:
        """The plain records, in order (what the report and the summary take)."""
        return tuple(i.record for i in self.items)

    def __iter__(self) -> Iterator[Comparison]:
        return iter(self.comparisons)

    def __len__(self) -> int:
        return len(self.comparisons)

    def get(self, method: str | None = None, *, scene: str | None = None) -> Comparison:
        """The one comparison of ``method`` (and ``scene``, by name); either may be
        left out when it leaves one match.

        Raises
        ------
        LookupError
            None or several match.
        """
        found = [c for c in self.comparisons if (method is None or c.method == method)
                 and (scene is None or c.name == scene)]
        if len(found) != 1:
            have = [f"{c.name}/{c.method}" for c in self.comparisons]
            raise LookupError(f"{len(found)} comparisons match method={method!r} "
                              f"scene={scene!r} (have: {have})")
        return found[0]


def bundled_scenes(*, hard: bool = True) -> tuple[str, ...]:
    """Names of the bundled scenes (``glass_sphere``, ..., with ``hard``: the hard
    cases ``hard/grazing_light``, ...), each accepted by :func:`load_scene`."""
    return tuple(n for n in bundled_scene_names() if hard or not n.startswith("hard/"))


def load_scene(scene: SceneLike, *, settings: Mapping[str, Any] | None = None,
               resolution: tuple[int, int] | None = None,
               on_warning: Callable[[Problem], None] | None = None) -> Scene:
    """A scene, fully validated (meshes read, geometry built), as every command loads it.

    Parameters
    ----------
    scene
        A file path, a bundled scene name (``glass_sphere``, ``hard/tiny_scale``) or a
        :class:`scenes.Scene` (returned with the overrides applied).
    settings
        Renderer settings to override, as ``--set`` takes them (``{"photons":
        100000, "receiver_map": [48, 48]}``); validated like the scene file.
    resolution
        The camera image's width and height in pixels (a smaller image makes a quick
        test; the reference cache key changes with it).
    on_warning
        Called with each warning of a file (a legal but suspect scene).

    Raises
    ------
    scenes.SceneError
        The file is missing or invalid, or an override is (each problem names the
        file and field).
    """
    if isinstance(scene, Scene):
        loaded = scene
    else:
        (loaded,) = _load_files([os.fspath(scene)], on_warning=on_warning)
    loaded = with_settings(loaded, dict(settings or {}))
    if resolution is not None:
        width, height = (int(v) for v in resolution)
        if width < 1 or height < 1:
            raise SceneError([f"{loaded.source}: camera.resolution: must be >= 1 "
                              f"(got {resolution!r})"])
        loaded = dataclasses.replace(
            loaded, camera=dataclasses.replace(loaded.camera, resolution=(width, height)))
    return loaded


def load_scenes(scenes: SceneLike | Sequence[SceneLike], *,
                settings: Mapping[str, Any] | None = None,
                resolution: tuple[int, int] | None = None,
                on_warning: Callable[[Problem], None] | None = None
                ) -> list[Scene | UnloadedScene]:
    """Each scene loaded once (:func:`load_scene`), in order; one that does not load
    is an :class:`UnloadedScene` holding its error, and the others still load. The
    list is what :func:`compare` takes (``caustics compare`` loads its scenes here
    and prints the problems before anything renders); an :class:`UnloadedScene`
    given is kept as it is."""
    loaded: list[Scene | UnloadedScene] = []
    for entry in _entries(scenes):
        if isinstance(entry, UnloadedScene):
            loaded.append(entry)
            continue
        try:
            loaded.append(load_scene(entry, settings=settings, resolution=resolution,
                                     on_warning=on_warning))
        except SceneError as error:
            source = entry.source if isinstance(entry, Scene) else os.fspath(entry)
            loaded.append(UnloadedScene(source, error))
    return loaded


def render_reference(scene: SceneLike, *, settings: Mapping[str, Any] | None = None,
                     resolution: tuple[int, int] | None = None,
                     cache_dir: str | os.PathLike | None = None, use_cache: bool = True,
                     camera: str = "trace", progress: bool = False) -> RenderResult:
    """The Mitsuba reference of a scene alone (cached; ``caustics reference``).

    Parameters
    ----------
    scene, settings, resolution
        As for :func:`load_scene`.
    cache_dir
        Reference cache root (default ``$CAUSTICS_CACHE_DIR`` or
        ``~/.cache/caustics-harness/reference``).
    use_cache
        False renders without reading or writing the cache.
    camera
        ``trace`` (the camera tracer) or ``ptracer``.
    progress
        Progress bars on stderr.

    Returns
    -------
    renderers.results.RenderResult
        ``camera`` radiance (W m^-2 sr^-1, RGB, (H, W, 3) float32), one receiver
        irradiance map (W/m^2, RGB) per receiver with its variance, and ``metadata``
        (``cache``: ``"hit"`` or why it missed, photons, seeds, noise, versions).
    """
    loaded = load_scene(scene, settings=settings, resolution=resolution)
    return _render_reference(loaded, cache=None if cache_dir is None else os.fspath(cache_dir),
                             use_cache=use_cache, progress=progress, camera=camera)


def _methods(methods: MethodLike | Iterable[MethodLike]) -> list[Method]:
    """Each method once, by name or as given (an unknown name raises MethodError)."""
    if isinstance(methods, str | Method):
        methods = [methods]
    found: dict[str, Method] = {}
    for m in methods:
        method = load_method(m) if isinstance(m, str) else m
        found.setdefault(method.name, method)
    return list(found.values())


def _entries(scene) -> list:
    if isinstance(scene, str | os.PathLike | Scene | UnloadedScene):
        return [scene]
    return list(scene)


def _page(output: Path, folder: str) -> Path:
    return output / folder / "index.html"


def compare(scene: SceneLike | UnloadedScene | Sequence[SceneLike | UnloadedScene],
            methods: MethodLike | Iterable[MethodLike] = DEFAULT_METHODS, *,
            studies: Sequence[str] | None = None, quick: bool = False,
            settings: Mapping[str, Any] | None = None,
            resolution: tuple[int, int] | None = None,
            cache_dir: str | os.PathLike | None = None, use_cache: bool = True,
            checks: bool = True, locks: str | os.PathLike | None = None,
            golden_dir: str | os.PathLike | None = None,
            crosscheck_photons: int | None = None, max_iterations: int = 8,
            frames: int | None = None, output: str | os.PathLike | None = None,
            self_contained: bool = False, progress: bool = False,
            isolate: bool = False) -> ComparisonSet:
    """Compare each method with the Mitsuba reference on each scene (the pipeline of
    :func:`harness.compare.pipeline.run_comparison`; ``caustics compare``).

    Parameters
    ----------
    scene
        One scene or several: file paths, bundled names or :class:`scenes.Scene`
        objects (:func:`load_scene`), or what :func:`load_scenes` returned. Each is
        loaded once, before anything renders.
    methods
        Registered names (``paper``, ``strong``, a third-party method) or
        :class:`renderers.methods.Method` objects; each name once.
    studies
        Studies to run (``metrics`` is always computed; ``convergence``, ``cost``,
        ``temporal``, ``decomposition`` or a registered one); None: the defaults.
        ``("metrics",)`` is the quickest: metrics and checks only.
    quick
        Smaller sweeps and one timing repeat (a quick look, not for reporting).
    settings, resolution
        Overrides of every scene (:func:`load_scene`).
    cache_dir, use_cache
        The reference cache (:func:`render_reference`); an unwritable cache folder is
        left out with one warning.
    checks
        Run the accuracy checks of every kind (physical requirements, method targets,
        regression locks); ``locks`` and ``golden_dir`` replace the bundled locks file
        and golden references (read before anything renders).
    crosscheck_photons
        Cross-check the reference with LuxCore at this many photons (None: not run).
    max_iterations, frames
        The convergence table's iterations 0..N; the temporal study's frames.
    output
        Write the report there (a page per scene and method, ``index.html``, the
        data files), staged and swapped in at the end as ``caustics compare -o``
        does; each :class:`Comparison` then knows its :attr:`~Comparison.page`.
    self_contained
        Pages with their images and styles inlined.
    progress
        Progress bars on stderr.
    isolate
        A comparison that fails becomes a :class:`Failure` (with a page, when
        ``output`` is given) and the others go on, as on the command line. Without
        it the first failure stops the run: its page and the index are written
        (with ``output``) and :class:`ComparisonError` is raised (from the error,
        when one was raised). A comparison whose reference puts no caustic light on
        any receiver (status ``no caustic``) is such a failure; with ``output`` its
        data files are written beside its page.

    Raises
    ------
    OptionError
        An unknown study, or ``frames`` without the temporal study.
    scenes.SceneError
        A scene does not load (without ``isolate``).
    renderers.methods.MethodError
        An unknown method name.
    ComparisonError
        A comparison failed (without ``isolate``).
    """
    selected = tuple(studies) if studies is not None else default_studies()
    unknown = sorted(set(selected) - set(known_studies()))
    if unknown:
        raise OptionError(f"unknown study {', '.join(unknown)} "
                          f"(choose from {', '.join(known_studies())})")
    if frames is not None and "temporal" not in selected:
        raise OptionError("frames (--frames) sets the temporal study's frames: add temporal "
                          "to the studies (--studies temporal)")
    chosen = _methods(methods)
    # Every checks file is read before anything renders: a missing one is an error.
    check_options = CheckOptions(
        files=load_check_files(Path(locks) if locks is not None else LOCKS_FILE),
        golden_dir=Path(golden_dir) if golden_dir is not None else GOLDEN_DIR,
    ) if checks else None
    cache = None if cache_dir is None else os.fspath(cache_dir)
    options = CompareOptions(
        studies=selected, max_iterations=max_iterations, quick=quick, cache=cache,
        use_cache=use_cache and usable_cache(default_cache_dir(cache)), progress=progress,
        frames=frames)
    crosscheck = (CrossCheckOptions(photons=crosscheck_photons)
                  if crosscheck_photons is not None else None)

    def run(scene: Scene, method: Method) -> SceneComparison:
        return run_comparison(scene, method, options=options, checks=check_options,
                              crosscheck=crosscheck)

    # Every scene is loaded once, before anything renders.
    entries = _loaded(scene, settings, resolution, isolate=isolate)
    if output is None:
        return ComparisonSet(tuple(_unwritten(entries, chosen, run, isolate=isolate)))
    final = Path(output).resolve()
    items: list[Comparison | Failure] = []
    stopped, cause = None, None
    with staged_output(final) as out_dir:
        rows = []
        for item, row, folder, error in _written(out_dir, entries, chosen, run,
                                                 self_contained=self_contained):
            rows.append(row)
            items.append(dataclasses.replace(item, page=_page(final, folder)))
            if isinstance(item, Failure) and not isolate:
                stopped, cause = ComparisonError(items[-1]), error
                break
        write_index(out_dir, rows, self_contained=self_contained)
    if stopped is not None:
        raise stopped from cause
    return ComparisonSet(tuple(items), final / "index.html")


def _loaded(scene, settings, resolution, *, isolate: bool) -> list[Scene | UnloadedScene]:
    """Each entry loaded once: a :class:`~scenes.Scene` (with the overrides applied,
    when there are any), or, with ``isolate``, an :class:`UnloadedScene`; without it
    the first scene that does not load raises."""
    if isolate:
        return load_scenes(scene, settings=settings, resolution=resolution)
    loaded: list[Scene | UnloadedScene] = []
    for entry in _entries(scene):
        if isinstance(entry, UnloadedScene):
            raise entry.error
        loaded.append(load_scene(entry, settings=settings, resolution=resolution))
    return loaded


def _answer(comparison: SceneComparison, scene: Scene, *, isolate: bool
                ) -> Comparison | Failure:
    """The comparison, or the failure of one that finished without an answer (its
    status: no caustic); without ``isolate`` that failure raises
    :class:`ComparisonError`."""
    failure = status_failure(comparison)
    if failure is None:
        return Comparison(comparison, scene)
    if not isolate:
        raise ComparisonError(Failure(failure))
    return Failure(failure)


def _unwritten(entries, methods, run, *, isolate: bool) -> Iterator[Comparison | Failure]:
    """Each scene and method compared, nothing written."""
    for entry in entries:
        for method in methods:
            if isinstance(entry, UnloadedScene):
                yield Failure(load_failure(entry.source, method.name, entry.error))
                continue
            try:
                comparison = run(entry, method)
            except Exception as error:  # with isolate, a failure is this scene's alone
                if not isolate:
                    raise
                yield Failure(scene_failure(entry, method.name, error, stage="comparison"))
                continue
            yield _answer(comparison, entry, isolate=isolate)


def _written(out_dir: Path, entries, methods, run, *, self_contained: bool
             ) -> Iterator[tuple[Comparison | Failure, dict, str, BaseException | None]]:
    """Each scene and method compared and written into ``out_dir`` (its data files,
    PDFs and page: :func:`harness.compare.isolation.run_scene`), as ``(item, index
    row, folder, the exception of a failed comparison)``."""
    taken: list[str] = []
    for entry in entries:
        for method in methods:
            if isinstance(entry, UnloadedScene):
                failure = Failure(load_failure(entry.source, method.name, entry.error))
                folder = scene_folder(failure.record.page, taken=taken)
                row = write_failure(out_dir, folder, failure.record,
                                    self_contained=self_contained)
                taken.append(folder)
                yield failure, row, folder, None
                continue
            caught: list[BaseException] = []

            def compared(scene=entry, method=method, caught=caught) -> SceneComparison:
                try:
                    return run(scene, method)
                except Exception as error:
                    caught.append(error)
                    raise

            folder = scene_folder(f"{entry.name}-{method.name}", taken=taken)
            record, row = run_scene(out_dir, folder, entry, method.name, compared,
                                    self_contained=self_contained)
            taken.append(folder)
            item = (Failure(record) if isinstance(record, SceneFailure)
                    else Comparison(record, entry))
            yield item, row, folder, caught[0] if caught else None


def score(scene: SceneLike, *, camera: str | os.PathLike | None = None,
          receivers: Mapping[int, str | os.PathLike] | None = None,
          timing: str | os.PathLike | Mapping[str, Any] | None = None,
          settings: Mapping[str, Any] | None = None,
          resolution: tuple[int, int] | None = None,
          cache_dir: str | os.PathLike | None = None, use_cache: bool = True,
          checks: bool = True, output: str | os.PathLike | None = None,
          self_contained: bool = False, progress: bool = False,
          on_warning: Callable[[Problem], None] | None = None) -> Comparison:
    """Score images rendered outside the harness against the reference, with the
    pipeline of :func:`compare` (``caustics score``;
    ``docs/scoring-external-renders.md``).

    Parameters
    ----------
    scene
        The scene the images show, with the ``settings`` and ``resolution`` they were
        rendered at (:func:`load_scene`): its camera resolution and ``receiver_map``
        are the sizes the files must have.
    camera
        EXR of the camera image, radiance in W m^-2 sr^-1 (None: not scored).
    receivers
        Receiver index to EXR of its irradiance map in W/m² over (u, v); every
        receiver of the scene, or none (not scored).
    timing
        The renderer's own timing report (a JSON file or its dict, ``frame_ms`` in
        ms): shown as reported, not measured by the harness.
    cache_dir, use_cache, checks, output, self_contained, progress
        As for :func:`compare`; the studies are ``metrics`` alone.
    on_warning
        Called with each warning of the scene (:func:`load_scene`).

    Raises
    ------
    harness.compare.external.ExternalRenderError
        No view given, or a file missing or unusable (the message names it), before
        any reference is rendered or anything written.
    ComparisonError
        The comparison failed.
    """
    if timing is not None and not isinstance(timing, Mapping):
        timing = read_timing(timing)
    method = ExternalRender(
        camera=None if camera is None else Path(camera),
        receivers={int(i): Path(p) for i, p in (receivers or {}).items()},
        timing=None if timing is None else dict(timing))
    loaded = load_scene(scene, settings=settings, resolution=resolution,
                        on_warning=on_warning)
    method.render(loaded)           # every file checked before anything renders or is written
    return compare(loaded, method, studies=("metrics",), cache_dir=cache_dir,
                   use_cache=use_cache, checks=checks, output=output,
                   self_contained=self_contained, progress=progress).get(method.name)


def write_report(comparisons: Comparison | Iterable[Comparison], output: str | os.PathLike,
                 *, self_contained: bool = False) -> ComparisonSet:
    """Write the report of finished comparisons into ``output``: each one's data files,
    PDFs and page (method, reference, difference and z-score maps, metrics with their
    intervals, checks) and ``index.html``, staged and swapped in as :func:`compare`
    does. Returns them with their pages; one whose files cannot be written becomes a
    :class:`Failure` with a page saying why."""
    if isinstance(comparisons, Comparison):
        comparisons = [comparisons]
    final = Path(output).resolve()
    items: list[Comparison | Failure] = []
    with staged_output(final) as out_dir:
        rows, taken = [], []
        for c in comparisons:
            folder = scene_folder(c.record.page, taken=taken)
            record, row = run_scene(out_dir, folder, c.scene, c.method, lambda c=c: c.record,
                                    self_contained=self_contained)
            taken.append(folder)
            rows.append(row)
            page = _page(final, folder)
            items.append(dataclasses.replace(c, page=page) if record is c.record
                         else Failure(record, page))
        write_index(out_dir, rows, self_contained=self_contained)
    return ComparisonSet(tuple(items), final / "index.html")
