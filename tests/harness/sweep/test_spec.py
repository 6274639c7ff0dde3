"""The sweep file: validated like a scene file (every problem names the file and the
field), expanded into rows and references with content keys."""

from __future__ import annotations

import dataclasses
import time

import pytest

from harness.cli import main
from harness.sweep.plan import plan_sweep
from harness.sweep.spec import (
    SWEEPS_DIR,
    SweepFileError,
    bundled_sweep_names,
    load_sweep,
    parse_sweep,
)
from renderers.methods import available_methods
from scenes import SCENES_DIR

from .conftest import small_scene, write_sweep

VERSIONS = {"mitsuba": "3.9.0", "drjit": "1.5.0", "variant": "llvm_ad_rgb"}

BAD = """
other = 1

[sweep]
name = "bad"
scenes = ["glass_sphere", "nosuch_scene"]
presets = ["paper", "fastest"]
methods = ["no-such-method"]
repeats = 0
colour = "red"

[sweep.settings]
receiver_map = [1, 64]
photons = 10

[sweep.grid]
iterations = [1, 3, 3, 65]
estimator = ["secant", "bisection"]
preset = ["paper"]
nosuch = [1]
grid = 64

[sweep.reference]
seeds = 65
noise_floor = true
"""

EXPECTED = {
    ("other", "unknown key (allowed: sweep)"),
    ("sweep.settings.receiver_map", "must be >= 2, got [1, 64]"),
    ("sweep.settings.photons", "sizes the reference: set it in [sweep.reference], not in "
                               "[sweep.settings]"),
    ("sweep.grid.iterations[2]", "3 is listed twice"),
    ("sweep.grid.iterations[3]", "must be <= 64, got 65"),
    ("sweep.grid.estimator[1]", "must be one of 'modified', 'newton', 'secant', got "
                                "'bisection'"),
    ("sweep.grid.preset", "the preset is chosen by the method: list it in `presets` (or "
                          "`methods`)"),
    ("sweep.grid.grid", "expected a non-empty array of values (e.g. grid = [a, b])"),
    ("sweep.presets[1]", "must be one of 'paper', 'strong', got 'fastest'"),
    ("sweep.repeats", "must be >= 1, got 0"),
    ("sweep.colour", None),
    ("sweep.reference.seeds", "must be <= 64, got 65"),
    ("sweep.reference.noise_floor", None),
    ("sweep.grid.nosuch", None),
}


def test_every_problem_names_the_file_and_the_field(tmp_path):
    """Regression lock (input validation): a sweep file with fourteen mistakes gets
    all fourteen, each with the file and the dotted field path (indices into
    arrays, as a scene file's problems have), not just the first; the messages are
    the scene schema's own for the same values."""
    path = tmp_path / "bad.toml"
    path.write_text(BAD)
    with pytest.raises(SweepFileError) as caught:
        load_sweep(path)
    problems = caught.value.problems
    assert {p.file for p in problems} == {str(path)}
    got = {(p.path, p.message) for p in problems}
    for field, message in EXPECTED:
        if message is None:
            assert any(p.path == field and p.message.startswith("unknown")
                       for p in problems), field
        else:
            assert (field, message) in got, (field, sorted(got))
    assert len(problems) == len(EXPECTED)


def test_scene_and_method_names_are_checked_after_the_tables(tmp_path):
    """Regression lock (input validation): a sweep whose tables are right but names a
    scene that does not exist and an unregistered method gets both problems, at
    ``sweep.scenes[1]`` (listing the bundled scenes) and ``sweep.methods[0]``
    (listing the registered methods); a scene file with its own mistake reports it
    under the scene file's name and field."""
    small_scene(tmp_path, "glass_sphere", **{"ior = 1.5": "ior = 0.5"})
    text = ('[sweep]\nname = "x"\nscenes = ["glass_sphere.toml", "nosuch"]\n'
            'methods = ["no-such-method"]\n')
    with pytest.raises(SweepFileError) as caught:
        parse_sweep(text, file="s.toml", base_dir=tmp_path)
    problems = {(p.file, p.path): p.message for p in caught.value.problems}
    assert problems[("s.toml", "sweep.scenes[1]")].startswith(
        "no such file, and no bundled scene of that name (bundled: ")
    # Every registered method is listed (this project's presets, and any plug-in the
    # environment installs, as the example project in the test env).
    assert problems[("s.toml", "sweep.methods[0]")] == (
        f"unknown method 'no-such-method' (registered: {', '.join(available_methods())})")
    scene_file = str(tmp_path / "glass_sphere.toml")
    assert problems[(scene_file, "objects[0].material.ior")] == "must be >= 1, got 0.5"


@pytest.mark.parametrize(("text", "path", "message"), [
    ("[sweep\n", "", "TOML syntax error"),
    ("title = 1\n", "sweep", "missing required table [sweep]"),
    ('sweep = "x"\n', "sweep", "expected a table"),
    ('[sweep]\nscenes = []\n', "sweep.name", "missing required field"),
    ('[sweep]\nname = "x"\nscenes = []\n', "sweep.scenes", "needs at least one scene"),
    ('[sweep]\nname = "x"\nscenes = ["glass_sphere", "glass_sphere"]\n', "sweep.scenes[1]",
     "'glass_sphere' is listed twice"),
])
def test_malformed_files_fail_with_one_named_problem(text, path, message):
    """Regression lock (input validation): broken TOML, a missing or mistyped
    ``[sweep]`` table, an empty or repeated scene list: a problem naming the field,
    never a traceback."""
    with pytest.raises(SweepFileError) as caught:
        parse_sweep(text, file="s.toml")
    assert any(p.file == "s.toml" and p.path == path and p.message.startswith(message)
               for p in caught.value.problems), caught.value.problems


def test_bundled_example_expands_to_the_grid_and_shares_references():
    """Regression lock: the bundled example (``caustics sweep estimators``) validates
    and expands to 2 scenes x 2 presets x (3 iterations x 2 grids) = 24 rows in
    scene, method, setting order; every row of a scene shares one reference and one
    independent reference (4 in all: 16 seed tasks of 4M photons), keyed as the
    reference cache keys them (photons, seeds), and no two rows share a key."""
    assert "estimators" in bundled_sweep_names()
    sweep = load_sweep("estimators")
    assert sweep.file == str(SWEEPS_DIR / "estimators.toml")
    assert SWEEPS_DIR.parent == SCENES_DIR
    plan = plan_sweep(sweep, versions=VERSIONS)
    assert len(plan.rows) == 24
    assert [(r.scene.name, r.method, r.setting.label) for r in plan.rows[:7]] == [
        ("glass_sphere", "paper", f"iterations={i}, grid={g}")
        for i in (1, 3, 5) for g in (64, 128)] + [("glass_sphere", "strong",
                                                   "iterations=1, grid=64")]
    assert len({r.key for r in plan.rows}) == 24
    assert len({r.folder for r in plan.rows}) == 24
    assert len(plan.references) == 4
    assert {(j.scene.name, j.role, j.seeds) for j in plan.references.values()} == {
        (name, role, seeds) for name in ("glass_sphere", "water_pool")
        for role, seeds in (("reference", (0, 1, 2, 3)), ("independent", (4, 5, 6, 7)))}
    for job in plan.rows:
        s = job.scene.settings
        assert (s.photons, s.seeds, s.preset) == (4_000_000, 4, job.method)
        assert (s.iterations, s.grid) == tuple(v for _, v in job.setting.items)


def test_reference_time_cap_sizes_the_reference():
    """Regression lock: ``reference_time_cap`` sizes the shared reference, so it is
    set in ``[sweep.reference]`` and reaches the planned references and rows; in
    ``[sweep.settings]`` it is refused by name (before, it was accepted there and the
    shared reference went on with the scene's own cap)."""
    head = '[sweep]\nname = "x"\nscenes = ["glass_sphere"]\npresets = ["paper"]\n'
    sweep = parse_sweep(head + "[sweep.reference]\nreference_time_cap = 7.5\n",
                        file="s.toml")
    plan = plan_sweep(sweep, versions=VERSIONS)
    assert {j.scene.settings.reference_time_cap for j in plan.references.values()} == {7.5}
    assert {r.scene.settings.reference_time_cap for r in plan.rows} == {7.5}
    with pytest.raises(SweepFileError) as caught:
        parse_sweep(head + "[sweep.settings]\nreference_time_cap = 7.5\n", file="s.toml")
    assert [(p.path, p.message) for p in caught.value.problems] == [
        ("sweep.settings.reference_time_cap",
         "sizes the reference: set it in [sweep.reference], not in [sweep.settings]")]


def test_row_keys_follow_what_the_row_depends_on(tmp_path):
    """Regression lock: a row's key changes with the method's settings, the reference
    (its photons), the timing repeats and the versions; it does not change with the
    sweep's name, or a scene file's folder."""
    path = write_sweep(tmp_path / "a", ("glass_sphere",))
    base = plan_sweep(load_sweep(path), versions=VERSIONS)
    sweep = load_sweep(path)
    keys = [r.key for r in base.rows]
    assert keys == [r.key for r in plan_sweep(dataclasses.replace(sweep, name="renamed"),
                                              versions=VERSIONS).rows]
    moved = write_sweep(tmp_path / "b", ("glass_sphere",))
    assert keys == [r.key for r in plan_sweep(load_sweep(moved), versions=VERSIONS).rows]
    changed = [
        dataclasses.replace(sweep, repeats=2),
        dataclasses.replace(sweep, reference=dataclasses.replace(sweep.reference,
                                                                 photons=30_000)),
        dataclasses.replace(sweep, settings=(*sweep.settings, ("splat_radius", 2.0))),
    ]
    for other in changed:
        assert not set(keys) & {r.key for r in plan_sweep(other, versions=VERSIONS).rows}
    newer = {**VERSIONS, "mitsuba": "3.9.1"}
    assert not set(keys) & {r.key for r in plan_sweep(sweep, versions=newer).rows}


def test_command_prints_each_problem_and_writes_nothing(tmp_path, capsys):
    """Regression lock (command line): ``caustics sweep`` on a bad file exits 1 with
    one ``error:`` line per problem and no traceback, before any cluster starts or
    any output is written; ``--workers`` with ``--scheduler`` is a usage error (2);
    an unknown sweep name lists the bundled sweeps."""
    path = tmp_path / "bad.toml"
    path.write_text(BAD)
    out = tmp_path / "out"
    assert main(["sweep", str(path), "-o", str(out)]) == 1
    err = capsys.readouterr().err.splitlines()
    assert len(err) == len(EXPECTED)
    assert all(line.startswith(f"error: {path}: ") for line in err)
    assert not out.exists()
    assert main(["sweep", str(path), "-o", str(out), "--workers", "2", "--scheduler",
                 "tcp://127.0.0.1:9"]) == 2
    assert "--workers sizes a local cluster" in capsys.readouterr().err
    assert main(["sweep", "nosuch", "-o", str(out)]) == 1
    assert "(bundled: estimators)" in capsys.readouterr().err


def test_dry_run_lists_rows_without_rendering(tmp_path, capsys):
    """Regression lock (command line): ``--dry-run`` validates, prints the rows with
    their keys and the seed tasks, and starts no cluster and writes nothing."""
    path = write_sweep(tmp_path)
    assert main(["sweep", str(path), "-o", str(tmp_path / "out"), "--dry-run"]) == 0
    out = capsys.readouterr().out
    assert "small: 2 scenes x 1 methods x 2 settings = 4 rows; 4 references (8 seed tasks" \
        in out
    assert "glass_sphere-paper-iterations1" in out
    assert not (tmp_path / "out").exists()


def test_unreachable_scheduler_is_one_line_and_exit_1(tmp_path, capsys):
    """Regression lock (command line): a sweep with rows to compute and a scheduler
    that does not answer (a closed port) fails in ``--connect-timeout`` seconds with
    one ``error:`` line naming the address, exit 1, nothing written."""
    path = write_sweep(tmp_path)
    out = tmp_path / "out"
    start = time.perf_counter()
    assert main(["sweep", str(path), "-o", str(out), "--scheduler", "tcp://127.0.0.1:9",
                 "--connect-timeout", "2", "--cache-dir", str(tmp_path / "cache"), "-q"]) == 1
    assert time.perf_counter() - start < 30
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert err[0].startswith("error: cannot reach the Dask scheduler at tcp://127.0.0.1:9: ")
    assert not out.exists()
