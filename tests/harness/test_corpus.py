"""Every failure is one clear line: the bad-input corpus (``corpus_cases.py``).

Regression lock of "every failure is one clear line": each malformed or
awkward scene file and command line gives its expected exit status and either an
``error:`` line naming what is wrong, or a finite result; none ends in a traceback.
The command runs in-process through ``harness.cli.main``, exactly as the console
script does.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from harness.cli import main
from renderers.exr import read_exr
from tests.harness.corpus_cases import CASES, Case

#: At least 80 cases (the corpus's size when it was locked: a case dropped is seen).
MINIMUM_CASES = 80


def test_the_corpus_is_large_enough():
    """Regression lock: the corpus keeps at least 80 cases (MINIMUM_CASES)."""
    print(f"\nbad-input corpus: {len(CASES)} cases")
    assert len(CASES) >= MINIMUM_CASES
    assert len({c.id for c in CASES}) == len(CASES), "case ids must be unique"


def _strict_json(path) -> dict:
    def refuse(token):
        raise AssertionError(f"{path}: non-finite JSON constant {token}")
    return json.loads(path.read_text(encoding="utf-8"), parse_constant=refuse)


def _run(case: Case, tmp_path, capsys) -> tuple[int, str, str, dict]:
    folder = tmp_path / "scenes"
    folder.mkdir()
    scene = folder / "corpus.toml"
    if case.scene_bytes is not None:
        scene.write_bytes(case.scene_bytes)
    elif case.scene is not None:
        scene.write_text(case.scene, encoding="utf-8")
    for name, content in case.files:
        (folder / name).write_bytes(content)
    places = {"scene": str(scene), "dir": str(folder), "out": str(tmp_path / "out")}
    argv = [a.format(**places) for a in case.argv]
    try:
        status = main(argv)
    except SystemExit as stop:  # argparse's usage errors
        status = stop.code if isinstance(stop.code, int) else 1
    captured = capsys.readouterr()
    return status, captured.out, captured.err, places


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.id)
def test_case(case: Case, tmp_path, capsys, monkeypatch):
    """Regression lock: the case's exit status, its one-line error (or its finite
    result), and no traceback."""
    # Its own cache: a case that fails must leave nothing behind, cache included, and
    # no case may read a reference another test traced.
    monkeypatch.setenv("CAUSTICS_CACHE_DIR", str(tmp_path / "cache"))
    status, out, err, places = _run(case, tmp_path, capsys)
    assert "Traceback" not in out + err, err
    assert "\x1b" not in out + err, "an escape sequence reached the terminal"
    assert status == case.exit, f"exit {status}, expected {case.exit}\n{err}"
    lines = [line for line in err.splitlines() if line.strip()]
    if case.error is not None:
        errors = [line for line in lines if line.startswith("error:")]
        assert errors, f"no error line:\n{err}"
        assert any(re.search(case.error, line) for line in errors), \
            f"no error line matches {case.error!r}:\n{err}"
    if case.exit == 1:
        # One line per problem: everything on stderr is an error or warning line.
        strays = [line for line in lines if not line.startswith(("error:", "warning:"))]
        assert not strays, f"stray stderr lines:\n{err}"
    if case.finite:
        out_dir = places["out"]
        result = Path(out_dir) / "result.json"
        _strict_json(result)
        images = sorted(Path(out_dir).glob("*.exr"))
        assert images, f"no EXR written in {out_dir}"
        for image in images:
            for name, layer in read_exr(image).items():
                assert np.isfinite(layer).all(), f"{image.name}: {name}"
