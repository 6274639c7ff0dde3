"""The one-way house: import-linter's contracts hold on the tree, and they catch a
forbidden import injected into a copy of it (so the check can fail)."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import REPO

PACKAGES = ("scenes", "renderers", "reports", "harness")


def _lint(root: Path) -> subprocess.CompletedProcess:
    # lint-imports reads [tool.importlinter] from pyproject.toml in the working
    # directory and imports the packages from there.
    command = [sys.executable, "-c", "from importlinter.cli import lint_imports_command; "
               "lint_imports_command()", "--no-cache"]
    return subprocess.run(command, cwd=root, capture_output=True, text=True, check=False)


@pytest.fixture
def tree(tmp_path: Path) -> Path:
    """A copy of the four packages (Python files only) and pyproject.toml."""
    for package in PACKAGES:
        shutil.copytree(REPO / package, tmp_path / package,
                        ignore=shutil.ignore_patterns("__pycache__", "*.exr", "*.obj"))
    shutil.copy(REPO / "pyproject.toml", tmp_path)
    return tmp_path


def _inject(path: Path, line: str) -> None:
    path.write_text(path.read_text() + f"\n{line}\n")


def test_contracts_hold_on_the_tree(tree):
    result = _lint(tree)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "3 kept, 0 broken" in result.stdout


@pytest.mark.parametrize(("module", "line", "contract"), [
    ("scenes/files.py", "import harness.cli", "Layers"),
    ("reports/plots.py", "import renderers.results", "plain records"),
    ("renderers/results.py", "import reports.records", "Layers"),
    ("renderers/caustics_mapping/meshes.py", "import renderers.mitsuba.exporter",
     "independent"),
])
def test_a_forbidden_import_breaks_a_contract(tree, module, line, contract):
    """Each injected import goes against one contract, which then fails by name."""
    _inject(tree / module, line)
    result = _lint(tree)
    assert result.returncode != 0
    broken = [row for row in result.stdout.splitlines() if row.endswith("BROKEN")]
    assert len(broken) == 1 and contract in broken[0], result.stdout
