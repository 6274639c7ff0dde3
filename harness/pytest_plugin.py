"""pytest plugin: hold a caustics method to accuracy bounds in its author's own tests.

Registered through the ``pytest11`` entry point, so every pytest run in an
environment with ``caustics-harness`` installed loads it; loading it imports nothing
but pytest and the standard library (the harness and its renderers are imported the
first time the ``caustics`` fixture is used).

Options (``pytest --help``, group "caustics-harness"; each also an ini key)
---------------------------------------------------------------------------
``--caustics-cache-dir DIR`` / ``caustics_cache_dir``
    The reference cache (default ``$CAUSTICS_CACHE_DIR``, else
    ``~/.cache/caustics-harness/reference``). References are content-addressed and
    locked per key, so tests, runs and ``pytest -n`` workers that need the same
    reference render it once.
``--caustics-failure-dir DIR`` / ``caustics_failure_dir``
    Where a failed assertion writes its report page (default
    ``<pytest basetemp>/caustics-failures``).

Fixture
-------
``caustics`` (session): a :class:`CausticsSession`: ``compare``, ``comparison``,
``score`` (images rendered elsewhere), ``load_scene``, ``render_reference`` (the
:mod:`harness.api` functions with the session's cache, each comparison computed once
per session) and the assertions.

Assertions
----------
:func:`assert_excess_below`, :func:`assert_flux_ratio_within`,
:func:`assert_no_physical_failures` (also methods of the fixture). A failure is one
message naming the scene, the method, the metric, the excess with its 95 % interval,
the bound and the report page written for it (method, reference, difference and
z-score maps).

Marker
------
``@pytest.mark.caustics_scenes(*names)`` parametrises the test's ``caustics_scene``
argument over scene names (none: every bundled scene but the hard cases).
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

if TYPE_CHECKING:
    from harness.api import Comparison, ComparisonSet

__all__ = ["CausticsSession", "assert_excess_below", "assert_flux_ratio_within",
           "assert_no_physical_failures", "bundled_scenes"]

_GROUP = "caustics-harness"
_REFERENCES = pytest.StashKey[list]()
_FAILURE_DIR = pytest.StashKey[Path]()
# The failure folder of the configured session, for the module-level assertions.
_configured: dict[str, Path] = {}


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup(_GROUP, "caustics-harness: accuracy checks of a caustics method")
    group.addoption("--caustics-cache-dir", dest="caustics_cache_dir", metavar="DIR",
                    default=None,
                    help="reference cache folder (default: ini caustics_cache_dir, else "
                         "$CAUSTICS_CACHE_DIR, else ~/.cache/caustics-harness/reference)")
    group.addoption("--caustics-failure-dir", dest="caustics_failure_dir", metavar="DIR",
                    default=None,
                    help="where a failed accuracy assertion writes its report page "
                         "(default: ini caustics_failure_dir, else "
                         "<basetemp>/caustics-failures)")
    parser.addini("caustics_cache_dir", "reference cache folder of the caustics fixture "
                  "(relative to the ini file's folder)", default=None)
    parser.addini("caustics_failure_dir", "where failed accuracy assertions write their "
                  "report pages (relative to the ini file's folder)", default=None)


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", "caustics_scenes(*names): parametrise the caustics_scene argument over "
        "scene names or files (none: the bundled scenes less the hard cases)")
    config.stash[_REFERENCES] = []


def _ini_path(config: pytest.Config, name: str) -> Path | None:
    value = config.getini(name)
    if not value:
        return None
    base = config.inipath.parent if config.inipath else config.rootpath
    return base / value


def _cache_dir(config: pytest.Config) -> Path | None:
    """Option, else ini key, else None (the harness default: ``$CAUSTICS_CACHE_DIR``,
    else ~/.cache/caustics-harness/reference)."""
    option = config.getoption("caustics_cache_dir")
    return Path(option) if option else _ini_path(config, "caustics_cache_dir")


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    marker = metafunc.definition.get_closest_marker("caustics_scenes")
    if marker is None or "caustics_scene" not in metafunc.fixturenames:
        return
    names = [os.fspath(n) for n in marker.args] or list(bundled_scenes(hard=False))
    metafunc.parametrize("caustics_scene", names, ids=names)


def bundled_scenes(*, hard: bool = True) -> tuple[str, ...]:
    """Names of the bundled scenes (:func:`harness.api.bundled_scenes`), e.g. for
    ``pytest.mark.parametrize``."""
    from harness.api import bundled_scenes as names  # noqa: PLC0415 - keeps moderngl out of pytest start-up

    return names(hard=hard)


class CausticsSession:
    """The ``caustics`` fixture: the Python API (:mod:`harness.api`) with the session's
    reference cache, and the assertions with its failure folder.

    Attributes
    ----------
    cache_dir : Path or None
        The reference cache (None: the harness default).
    failure_dir : Path
        Where failed assertions write their report pages.
    """

    def __init__(self, *, cache_dir: Path | None, failure_dir: Path,
                 record: Callable[[Comparison], None] = lambda _: None):
        self.cache_dir = cache_dir
        self.failure_dir = failure_dir
        self._record = record
        self._done: dict[tuple, Comparison] = {}

    def load_scene(self, scene, **overrides: Any):
        """:func:`harness.api.load_scene`."""
        from harness import api  # noqa: PLC0415 - keeps moderngl out of pytest start-up

        return api.load_scene(scene, **overrides)

    def render_reference(self, scene, **options: Any):
        """:func:`harness.api.render_reference` with the session's cache."""
        from harness import api  # noqa: PLC0415 - keeps moderngl out of pytest start-up

        return api.render_reference(scene, **{"cache_dir": self.cache_dir, **options})

    def compare(self, scene, methods=("paper", "strong"), *,
                settings: Mapping[str, Any] | None = None,
                resolution: tuple[int, int] | None = None,
                studies: Iterable[str] | None = ("metrics",), quick: bool = True,
                checks: bool = True, **options: Any) -> ComparisonSet:
        """:func:`harness.api.compare` with the session's cache, by default the quick
        metrics-and-checks comparison. Each scene, method and option set is compared
        once per session (per ``pytest -n`` worker); later calls return it again."""
        from harness import api  # noqa: PLC0415 - keeps moderngl out of pytest start-up

        loaded = api.load_scene(scene, settings=settings, resolution=resolution)
        studies = None if studies is None else tuple(studies)
        fixed = (repr(loaded), studies, quick, checks, repr(sorted(options.items())))
        items = []
        for method in [methods] if isinstance(methods, str) else methods:
            # A registered name, or an object by its name and class.
            key = (*fixed, *((method,) if isinstance(method, str)
                             else (method.name, type(method).__qualname__)))
            if key not in self._done:
                (done,) = api.compare(loaded, [method], studies=studies, quick=quick,
                                      checks=checks,
                                      **{"cache_dir": self.cache_dir, **options})
                self._record(done)
                self._done[key] = done
            items.append(self._done[key])
        return api.ComparisonSet(tuple(items))

    def comparison(self, scene, method, **options: Any) -> Comparison:
        """The one comparison of ``method`` on ``scene`` (:meth:`compare`)."""
        return self.compare(scene, [method], **options).get()

    def score(self, scene, *, camera=None, receivers=None, **options: Any) -> Comparison:
        """:func:`harness.api.score` with the session's cache: images rendered outside
        the harness (EXR files) scored against the reference, ready for the
        assertions. Not cached per session: the files may change between calls."""
        from harness import api  # noqa: PLC0415 - keeps moderngl out of pytest start-up

        done = api.score(scene, camera=camera, receivers=receivers,
                         **{"cache_dir": self.cache_dir, **options})
        self._record(done)
        return done

    def assert_excess_below(self, comparison: Comparison, metric: str, bound: float, *,
                            view: str = "receiver0", region: str = "caustic") -> None:
        """:func:`assert_excess_below`, pages into :attr:`failure_dir`."""
        __tracebackhide__ = True
        assert_excess_below(comparison, metric, bound, view=view, region=region,
                            failure_dir=self.failure_dir)

    def assert_flux_ratio_within(self, comparison: Comparison, tolerance: float, *,
                                 view: str = "receiver0", region: str = "full") -> None:
        """:func:`assert_flux_ratio_within`, pages into :attr:`failure_dir`."""
        __tracebackhide__ = True
        assert_flux_ratio_within(comparison, tolerance, view=view, region=region,
                                 failure_dir=self.failure_dir)

    def assert_no_physical_failures(self, comparison: Comparison) -> None:
        """:func:`assert_no_physical_failures`, pages into :attr:`failure_dir`."""
        __tracebackhide__ = True
        assert_no_physical_failures(comparison, failure_dir=self.failure_dir)


@pytest.fixture(scope="session")
def caustics(request: pytest.FixtureRequest,
             tmp_path_factory: pytest.TempPathFactory) -> CausticsSession:
    """The session's :class:`CausticsSession` (shared by every test of a run, one per
    ``pytest -n`` worker; references are shared through the cache)."""
    config = request.config
    option = config.getoption("caustics_failure_dir")
    failure_dir = (Path(option) if option else _ini_path(config, "caustics_failure_dir")
                   or tmp_path_factory.getbasetemp() / "caustics-failures")
    _configured["failure_dir"] = failure_dir
    references = config.stash[_REFERENCES]

    def record(comparison: Comparison) -> None:
        # One entry per reference fetched: its key and whether the cache had it.
        ref = comparison.record.provenance.reference
        key = str(ref.get("hash"))
        for name, status in comparison.reference_cache.items():
            references.append([f"{key}/{name}", status])

    return CausticsSession(cache_dir=_cache_dir(config), failure_dir=failure_dir,
                           record=record)


@pytest.fixture
def caustics_scene(request: pytest.FixtureRequest) -> str:
    """The scene a ``caustics_scenes`` marker parametrises (default: glass_sphere)."""
    return getattr(request, "param", "glass_sphere")


def pytest_sessionfinish(session: pytest.Session) -> None:
    # A pytest-xdist worker hands its references to the controller.
    workeroutput = getattr(session.config, "workeroutput", None)
    if workeroutput is not None:
        workeroutput["caustics_references"] = session.config.stash.get(_REFERENCES, [])


@pytest.hookimpl(optionalhook=True)
def pytest_testnodedown(node, error) -> None:
    """pytest-xdist: collect a finished worker's references."""
    found = getattr(node, "workeroutput", {}).get("caustics_references", [])
    node.config.stash[_REFERENCES].extend(found)


def pytest_terminal_summary(terminalreporter, exitstatus, config: pytest.Config) -> None:
    """One line: how many references the comparisons needed, how many were rendered
    and how many read from the cache (over every ``pytest -n`` worker)."""
    found = config.stash.get(_REFERENCES, [])
    if not found:
        return
    rendered = sum(1 for _, status in found if status != "hit")
    distinct = len({key for key, _ in found})
    where = _cache_dir(config) or os.environ.get("CAUSTICS_CACHE_DIR") or "the default cache"
    terminalreporter.write_line(
        f"caustics-harness: {distinct} distinct references, {rendered} rendered, "
        f"{len(found) - rendered} read from the cache ({where})")


def _failure_page(comparison: Comparison, failure_dir: Path | None) -> Path | None:
    """The comparison's report page: the one it has, else one written now into
    ``failure_dir/<test>/`` (None when none can be written)."""
    if comparison.page is not None and comparison.page.is_file():
        return comparison.page
    from harness import api  # noqa: PLC0415 - keeps moderngl out of pytest start-up

    root = failure_dir or _configured.get("failure_dir") or Path("caustics-failures")
    test = os.environ.get("PYTEST_CURRENT_TEST", "").rsplit(" ", 1)[0]
    name = re.sub(r"[^A-Za-z0-9._-]+", "_", test.split("/")[-1]).strip("._")[:120]
    try:
        written = api.write_report(comparison, root / (name or comparison.record.page))
    except OSError:
        return None
    return (written.items[0].page) if written.items else None


def _fail(comparison: Comparison, what: str, failure_dir: Path | None) -> None:
    __tracebackhide__ = True
    page = _failure_page(comparison, failure_dir)
    pytest.fail(f"caustics accuracy: scene {comparison.name}, method {comparison.method}: "
                f"{what}; report page: {page or 'not written'}", pytrace=False)


def assert_excess_below(comparison: Comparison, metric: str, bound: float, *,
                        view: str = "receiver0", region: str = "caustic",
                        failure_dir: str | os.PathLike | None = None) -> None:
    """Fail unless the method's excess error on ``metric`` is below ``bound`` with 95 %
    confidence.

    The rule: the upper end of the excess's 95 % interval (``MetricValue.excess_ci95``)
    must be at most ``bound``. So the test passes only when the data show the
    method's own error (the reference's noise taken out, ``docs/statistics.md``) is at
    most the bound, at 97.5 % one-sided confidence; a reference too noisy to tell
    fails too (render more photons, or loosen the bound). The excess is relMSE − its
    noise baseline, SSIM baseline − SSIM, FLIP − its baseline, or flux ratio − 1
    (signed: use :func:`assert_flux_ratio_within` for the flux).

    A failure is one message: scene, method, metric, view and region, the excess
    ± its standard error and its 95 % interval, the bound, and the path of the report
    page written for it (into ``failure_dir``: the fixture's
    ``--caustics-failure-dir``).
    """
    __tracebackhide__ = True
    m = comparison.metric(metric, view=view, region=region)
    where = f"{metric} ({view}, {region})"
    if m.excess is None or m.excess_ci95 is None:
        _fail(comparison, f"{where} has no excess estimate (a metric without one, or a "
              f"reference without variance), so it cannot be held to the bound {bound:.4g}",
              _folder(failure_dir))
    elif not m.excess_ci95[1] <= bound:
        _fail(comparison, f"{where} excess {m.interval_text} is above the bound "
              f"{bound:.4g} (rule: the 95 % interval's upper end must be <= the bound)",
              _folder(failure_dir))


def assert_flux_ratio_within(comparison: Comparison, tolerance: float, *,
                             view: str = "receiver0", region: str = "full",
                             failure_dir: str | os.PathLike | None = None) -> None:
    """Fail unless the flux ratio (method over reference, luminance summed over the
    region) is within ``1 ± tolerance`` with 95 % confidence: the whole 95 % interval
    of its excess, ratio − 1, must lie in ``[−tolerance, tolerance]``. The failure
    message is as for :func:`assert_excess_below`."""
    __tracebackhide__ = True
    m = comparison.metric("flux_ratio", view=view, region=region)
    where = f"flux_ratio ({view}, {region}) = {m.value:.4g}"
    if m.excess_ci95 is None:
        _fail(comparison, f"{where} has no interval (a reference without variance), so "
              f"it cannot be held to 1 ± {tolerance:.4g}", _folder(failure_dir))
    elif not (-tolerance <= m.excess_ci95[0] and m.excess_ci95[1] <= tolerance):
        _fail(comparison, f"{where}: excess (ratio − 1) {m.interval_text} is not within "
              f"the bound ±{tolerance:.4g} (rule: the whole 95 % interval must lie within "
              "it)", _folder(failure_dir))


def assert_no_physical_failures(comparison: Comparison, *,
                                failure_dir: str | os.PathLike | None = None) -> None:
    """Fail when a physical requirement failed (energy, flux agreement, finite and
    non-negative values, ...; known gaps do not count): one message listing each with
    its value, bound and origin, and the report page."""
    __tracebackhide__ = True
    failed = comparison.physical_failures
    if failed:
        listed = "; ".join(f"{c.metric} ({c.view}, {c.region}) = {c.value:.4g}, bound "
                           f"{c.bound_text} [{c.origin}]" for c in failed)
        _fail(comparison, f"{len(failed)} physical requirement"
              f"{'s' if len(failed) > 1 else ''} failed: {listed}", _folder(failure_dir))


def _folder(failure_dir: str | os.PathLike | None) -> Path | None:
    return None if failure_dir is None else Path(failure_dir)
