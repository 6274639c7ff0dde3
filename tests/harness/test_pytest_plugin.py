"""The pytest plugin (harness.pytest_plugin) and the example third-party project
(examples/caustics-example-method) that uses it: loading the plugin imports no
renderer; its options are listed and read from the ini file, and the command line
wins over the ini file; the example's tests pass under ``pytest -n 2`` with each
reference rendered once; its broken variant fails with one message naming scene,
method, metric, excess and interval, bound and a report page that exists."""

from __future__ import annotations

import importlib.metadata
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from harness.pytest_plugin import bundled_scenes
from tests.conftest import REPO

EXAMPLE = REPO / "examples" / "caustics-example-method"


def test_loading_the_plugin_imports_no_renderer(pytestconfig):
    """pytest loads the plugin in every run of every project that installs the
    harness: it must not import the API (moderngl, Mitsuba) on load."""
    code = ("import sys, harness.pytest_plugin; "
            "print(sorted(m for m in ('harness.api', 'moderngl', 'mitsuba', 'drjit', "
            "'matplotlib') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    assert done.stdout.strip() == "[]"
    # Registered through the pytest11 entry point, so this very run loaded it.
    plugin = pytestconfig.pluginmanager.get_plugin("caustics-harness")
    assert plugin is not None and plugin.__name__ == "harness.pytest_plugin"


def test_options_are_listed_and_read_from_the_ini_file(pytester):
    help_text = pytester.runpytest("--help").stdout.str()
    assert "caustics-harness" in help_text
    assert "--caustics-cache-dir" in help_text and "--caustics-failure-dir" in help_text
    pytester.makeini("[pytest]\ncaustics_cache_dir = refs\ncaustics_failure_dir = fails\n")
    pytester.makepyfile(test_paths="""
        from pathlib import Path

        def test_paths(caustics, pytestconfig):
            root = Path(pytestconfig.inipath).parent
            assert caustics.cache_dir == root / "refs"
            assert caustics.failure_dir == root / "fails"
    """)
    pytester.runpytest("-p", "no:cacheprovider").assert_outcomes(passed=1)


#: A test of the pytester project that records the folders the plugin settled on.
_RECORD_FOLDERS = """
import json
from pathlib import Path

def test_record(caustics, pytestconfig):
    seen = {"cache": str(caustics.cache_dir), "failures": str(caustics.failure_dir)}
    (Path(pytestconfig.inipath).parent / "seen.json").write_text(json.dumps(seen))
"""


def test_the_command_line_wins_over_the_ini_file(pytester):
    """With both folders set in the ini file, ``--caustics-cache-dir`` replaces the
    ini's cache folder and leaves its failure folder as it is; with both options
    given, both come from the command line (read back from what the ``caustics``
    fixture holds inside the run)."""
    pytester.makeini("[pytest]\ncaustics_cache_dir = refs\ncaustics_failure_dir = fails\n")
    pytester.makepyfile(test_record=_RECORD_FOLDERS)
    root, seen = pytester.path, pytester.path / "seen.json"
    other_cache, other_fails = root / "cli-refs", root / "cli-fails"

    pytester.runpytest("-p", "no:cacheprovider", "--caustics-cache-dir",
                       str(other_cache)).assert_outcomes(passed=1)
    assert json.loads(seen.read_text()) == {"cache": str(other_cache),
                                            "failures": str(root / "fails")}
    seen.unlink()
    pytester.runpytest("-p", "no:cacheprovider", "--caustics-cache-dir", str(other_cache),
                       "--caustics-failure-dir", str(other_fails)).assert_outcomes(passed=1)
    assert json.loads(seen.read_text()) == {"cache": str(other_cache),
                                            "failures": str(other_fails)}


def test_caustics_scenes_marker_parametrises_the_scene(pytester):
    pytester.makepyfile(test_marker="""
        import pytest

        @pytest.mark.caustics_scenes("glass_sphere", "hard/tiny_scale")
        def test_named(caustics_scene):
            assert caustics_scene in ("glass_sphere", "hard/tiny_scale")

        @pytest.mark.caustics_scenes()
        def test_bundled(caustics_scene):
            assert not caustics_scene.startswith("hard/")
    """)
    result = pytester.runpytest("-p", "no:cacheprovider", "-q")
    outcomes = result.parseoutcomes()
    # 2 named, and one per bundled scene less the hard cases.
    bundled = bundled_scenes(hard=False)
    assert "glass_sphere" in bundled and not any(n.startswith("hard/") for n in bundled)
    assert outcomes["passed"] == 2 + len(bundled), result.stdout.str()


def _example_env(tmp_path: Path) -> dict[str, str]:
    """The environment to run the example's tests in: the example installed (as CI
    does, ``pip install -e``), else installed here into a folder of its own."""
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    try:
        importlib.metadata.distribution("caustics-example-method")
    except importlib.metadata.PackageNotFoundError:
        site = tmp_path / "site"
        subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                        "--no-build-isolation", "--no-index", "--target", str(site),
                        str(EXAMPLE)], check=True, cwd=tmp_path)
        env["PYTHONPATH"] = os.pathsep.join([str(site), env.get("PYTHONPATH", "")])
    return env


# slow (``tox -e slow``): a second pytest session with two xdist workers that render two
# references, 32 s of the default run's 10 minutes on the 2-core machine (clean-clone CI:
# 605 s with it). The plugin's options, fixtures and marker are tested above in this
# process; the per-key lock that lets two processes share a reference is tested in
# tests/renderers/mitsuba/test_cache.py.
@pytest.mark.slow
def test_example_passes_under_xdist_and_its_broken_variant_fails_readably(tmp_path):
    """End to end (about 90 s with 2 workers on 2 cores, then about 25 s): the
    example's own tests pass with ``pytest -n 2``; both workers need the same two
    references (the reference and the independent one) and each is rendered exactly
    once (the cache's per-key lock: the other worker waits and reads it). Run again
    with ``--runxfail``, the broken variant (caustic maps x 1.05) fails with the
    one-message format and the page it names exists and shows the difference."""
    env, cache, fails = _example_env(tmp_path), tmp_path / "cache", tmp_path / "fails"
    common = [sys.executable, "-m", "pytest", "-p", "no:cacheprovider",
              "--caustics-cache-dir", str(cache), "--caustics-failure-dir", str(fails)]
    done = subprocess.run([*common, "-n", "2"], cwd=EXAMPLE, env=env, capture_output=True,
                          text=True, check=False)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "3 passed, 1 xfailed" in done.stdout
    counts = re.search(r"caustics-harness: (\d+) distinct references, (\d+) rendered, "
                       r"(\d+) read from the cache", done.stdout)
    assert counts, done.stdout
    distinct, rendered, read = map(int, counts.groups())
    assert distinct == 2 and rendered == 2 and read >= 2, counts.group(0)
    assert len([p for p in cache.iterdir() if p.is_dir()]) == 2     # two cache entries

    done = subprocess.run([*common, "--runxfail", "tests/test_broken.py"], cwd=EXAMPLE,
                          env=env, capture_output=True, text=True, check=False)
    assert done.returncode == 1, done.stdout + done.stderr
    message = re.search(
        r"caustics accuracy: scene glass_sphere, method example-x1\.05: relmse "
        r"\(receiver0, caustic\) excess (\S+) ± \S+ \(95 % \[(\S+), (\S+)\]\) is above "
        r"the bound 0\.003 \(rule: [^)]*\); report page: (\S+index\.html)", done.stdout)
    assert message, done.stdout
    excess, low, high = (float(v) for v in message.groups()[:3])
    assert low <= excess <= high and high > 0.003
    page = Path(message.group(4))
    assert page.is_file() and page.is_relative_to(fails)
    html = page.read_text()
    assert "example-x1.05" in html and "ifference" in html
    assert "rendered, 0" not in done.stdout and "0 rendered" in done.stdout  # from the cache


def test_the_docs_show_the_example_test_file_verbatim():
    """docs/testing-your-method.md includes the example's test file, which the test
    above runs: each block marked ``<!-- example: PATH -->`` must be that file."""
    doc = (REPO / "docs" / "testing-your-method.md").read_text()
    blocks = re.findall(r"<!-- example: (\S+) -->\n```python\n(.*?)```", doc, re.S)
    assert blocks, "no example block in the doc"
    for path, code in blocks:
        assert code == (REPO / path).read_text(), path
