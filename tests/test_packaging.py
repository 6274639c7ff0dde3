"""Packaging: every third-party module the packages import belongs to a declared
dependency (a clean install would otherwise fail where the test env, with its extra
packages, did not: tox -e demo once failed on an undeclared tqdm)."""

from __future__ import annotations

import ast
import re
import sys
import tomllib
from importlib.metadata import packages_distributions

from tests.conftest import REPO

FIRST_PARTY = {"harness", "renderers", "reports", "scenes"}
#: Imported only inside functions that need an optional extra, with the message
#: naming the extra (pymeshlab: the bunny); or only where that extra runs: pytest by
#: the pytest plugin (harness/pytest_plugin.py), which pytest itself loads through its
#: ``pytest11`` entry point; playwright by the drei-caustics method (renderers/drei).
OPTIONAL = {"pymeshlab": "bunny", "pyluxcore": "crosscheck", "pytest": "test",
            "playwright": "drei"}


def _name(requirement: str) -> str:
    return re.split(r"[<>=!~\[; ]", requirement, maxsplit=1)[0].strip().lower().replace("_", "-")


def _imports() -> set[str]:
    modules = set()
    for package in FIRST_PARTY:
        for path in (REPO / package).rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
                if isinstance(node, ast.Import):
                    modules.update(a.name.split(".")[0] for a in node.names)
                elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    modules.add(node.module.split(".")[0])
    return modules - FIRST_PARTY - set(sys.stdlib_module_names)


def test_every_third_party_import_is_declared():
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    declared = {_name(r) for r in project["dependencies"]}
    extras = {extra: {_name(r) for r in reqs}
              for extra, reqs in project["optional-dependencies"].items()}
    owners = packages_distributions()
    missing = []
    for module in sorted(_imports()):
        dists = {d.lower().replace("_", "-") for d in owners.get(module, [module])}
        if module in OPTIONAL:
            assert dists & extras[OPTIONAL[module]], f"{module} not in extra {OPTIONAL[module]}"
        elif not dists & declared:
            missing.append(f"{module} (from {sorted(dists)})")
    assert not missing, f"imported but not declared in pyproject.toml: {missing}"
