"""results.csv and the sweep's index page: the columns docs/architecture.md lists, the Pareto
front per scene (known answers), every text from a file rendered inert."""

from __future__ import annotations

import math
import re

from harness.sweep.plan import RowJob
from harness.sweep.results import pareto_keys, results_columns, write_results_csv
from harness.sweep.run import RowResult
from harness.sweep.spec import Setting
from reports.sweep import SweepIndex, SweepRow, write_sweep_index
from scenes import load_scene

from .conftest import read_rows, small_scene

HOSTILE = '<script>window.__pwned = 1</script>"&'


def _row(scene, key, time_ms, relmse, *, error="", iterations=1):
    job = RowJob(scene=scene, method="paper", setting=Setting((("iterations", iterations),)),
                 key=key, folder=f"{scene.name}-{key}", reference="r", independent="i")
    # The front is read on the excess relMSE; the raw value is a baseline of 1e-3 above.
    values = {} if error else {"excess_relmse": relmse, "relmse": relmse + 1e-3, "ssim": 0.9,
                               "flip": 0.1, "flux_ratio": 1.0, "relmse_noise_floor": 0.01}
    return RowResult(job=job, values=values, time_warm_ms=None if error else time_ms,
                     worker="" if error else "tcp://127.0.0.1:1", error=error,
                     stage="render" if error else "", page=None if error else job.folder)


def test_pareto_front_per_scene_known_answers(tmp_path):
    """Regression lock (known answers, worked by hand): on scene a the points
    (time ms, excess relMSE) (1, 0.5), (2, 0.3), (3, 0.4), (4, 0.1), (5, NaN) and a failed
    row: the front is (1, 0.5), (2, 0.3), (4, 0.1) ((3, 0.4) is dominated by (2,
    0.3)); scene b's one point (9, 0.9) is its own front although scene a has better
    ones: fronts are per scene. results.csv has its documented columns in order and
    flags exactly those rows."""
    a = load_scene(small_scene(tmp_path, "glass_sphere"))
    b = load_scene(small_scene(tmp_path, "water_pool"))
    rows = [_row(a, "a1", 1, 0.5), _row(a, "a2", 2, 0.3, iterations=2),
            _row(a, "a3", 3, 0.4, iterations=3), _row(a, "a4", 4, 0.1, iterations=4),
            _row(a, "a5", 5, math.nan, iterations=5),
            _row(a, "a6", 0.1, 0.01, error="RuntimeError: x", iterations=6),
            _row(b, "b1", 9, 0.9)]
    assert pareto_keys(rows) == {"a1", "a2", "a4", "b1"}
    path = tmp_path / "results.csv"
    write_results_csv(path, rows, grid=("iterations",))
    header = path.read_text().splitlines()[0].split(",")
    assert header[:7] == ["scene", "method", "iterations", "excess_relmse",
                          "excess_relmse_low", "excess_relmse_high", "relmse"]
    assert header[19:23] == ["time_warm_ms", "worker", "cached", "error"]
    assert tuple(header) == results_columns(("iterations",))
    table = read_rows(path)
    assert [r["pareto"] for r in table] == ["true", "true", "false", "true", "false", "false",
                                            "true"]
    assert table[4]["excess_relmse"] == "" and table[5]["error"] == "RuntimeError: x"
    assert float(table[0]["relmse"]) == 0.5 + 1e-3
    assert table[5]["page"] == "" and table[0]["page"] == "glass_sphere-a1"


def test_index_page_draws_each_scene_and_renders_names_inert(tmp_path):
    """Regression lock (report safety and content): a scene and a method named with
    markup, a failed row and a scene without a finite point: the page escapes every
    text (no live script), marks the Pareto rows, links each row's page, shows the
    failure with its stage, and writes one SVG plot per scene (the empty one says
    why it is empty)."""
    rows = (
        SweepRow(scene=HOSTILE, method="paper", setting=(("iterations", "1"),),
                 values={"excess_relmse": 0.5, "excess_relmse_low": 0.4,
                         "excess_relmse_high": 0.6, "relmse": 0.51}, time_warm_ms=2.0,
                 worker="tcp://w0", pareto=True, folder="x-paper-iterations1"),
        SweepRow(scene=HOSTILE, method=HOSTILE, setting=(("iterations", "3"),),
                 values={"excess_relmse": 0.6, "relmse": 0.61}, time_warm_ms=3.0,
                 worker="tcp://w1", cached=True,
                 folder="x-m-iterations3"),
        SweepRow(scene=HOSTILE, method="strong", setting=(("iterations", "5"),),
                 error=f"RuntimeError: {HOSTILE}", stage="render"),
        SweepRow(scene="empty", method="paper", setting=(("iterations", "1"),),
                 values={"excess_relmse": math.nan, "relmse": math.nan}, time_warm_ms=1.0,
                 folder="empty-paper"),
    )
    index = SweepIndex(name=HOSTILE, description=HOSTILE, file="s.toml",
                       columns=("iterations",), rows=rows,
                       scenes=((HOSTILE, HOSTILE), ("empty", "")),
                       run={"workers": ["tcp://w0", "tcp://w1"], "wall time (s)": 1.5})
    page = write_sweep_index(tmp_path, index).read_text()
    assert "<script>window" not in page and "&lt;script&gt;window.__pwned" in page
    assert page.count("<td>★</td>") == 1
    assert 'href="x-paper-iterations1/index.html"' in page
    assert 'href="x-m-iterations3/index.html"' in page
    assert "1 of 4 rows failed" in page and "(render)" in page
    plots = sorted(p.name for p in (tmp_path / "plots").iterdir())
    assert len(plots) == 2
    svgs = [(tmp_path / "plots" / name).read_text() for name in plots]
    assert any("Pareto front" in s for s in svgs)
    assert any("no row has a finite, positive time and excess relMSE" in s for s in svgs)
    assert all("<script" not in s for s in svgs)
    assert (tmp_path / "_static" / "report.css").is_file()
    srcs = re.findall(r'<img src="([^"]+)"', page)
    assert all((tmp_path / s).is_file() for s in srcs if s.startswith("plots/"))
