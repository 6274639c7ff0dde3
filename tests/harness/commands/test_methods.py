"""Methods by name: the presets are registered entry points, and a third-party method
installed with pip is compared with ``--method NAME`` without any change to the
harness (the plug-in package is ``tests/plugins/toy_method``)."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from renderers.methods import MethodError, available_methods, load_method
from tests.conftest import REPO
from tests.harness.commands.test_compare import SMALL, _small_scene

PLUGIN = REPO / "tests" / "plugins" / "toy_method"


def test_presets_are_registered_methods():
    """Both presets are found through the entry-point group; an unknown name is one
    clear error that lists the registered methods."""
    assert {"paper", "strong"} <= set(available_methods())
    assert load_method("strong").name == "strong"
    with pytest.raises(MethodError, match=r"unknown method 'nope' .*paper, strong"):
        load_method("nope")


def test_third_party_method_is_compared_by_name(tmp_path):
    """pip installs the plug-in into a folder of its own; with that folder on the
    path, ``compare --method toy-double`` measures it beside the paper preset. The
    plug-in doubles the paper preset's render, so its flux ratio must be twice the
    paper's (to float32 rounding): the harness measured the named method's output."""
    site = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                    "--no-build-isolation", "--no-index", "--target", str(site), str(PLUGIN)],
                   check=True, cwd=tmp_path)
    out = tmp_path / "out"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(site), str(REPO), os.environ.get("PYTHONPATH", "")])}
    argv = [sys.executable, "-c", "from harness.cli import run; run()", "compare",
            str(_small_scene(tmp_path)), "-o", str(out), "--studies", "metrics", "-q",
            "--preset", "paper",
            "--method", "toy-double", *SMALL]
    done = subprocess.run(argv, check=False, env=env, cwd=tmp_path, capture_output=True,
                          text=True)
    assert done.returncode == 0, done.stderr
    assert "toy-double" in done.stdout

    def flux_ratio(page):
        data = json.loads((out / page / "metrics.json").read_text())
        (value,) = [m["value"] for m in data["metrics"] if (m["view"], m["region"], m["metric"])
                    == ("receiver0", "full", "flux_ratio")]
        return data, value

    paper, paper_ratio = flux_ratio("glass_sphere-paper")
    toy, toy_ratio = flux_ratio("glass_sphere-toy-double")
    assert toy["method"]["name"] == "toy-double" and paper["method"]["name"] == "paper"
    assert toy["provenance"]["method"]["renderer"] == "toy-double"
    assert toy_ratio == pytest.approx(2 * paper_ratio, rel=1e-5)
    assert "glass_sphere-toy-double/index.html" in (out / "index.html").read_text()
