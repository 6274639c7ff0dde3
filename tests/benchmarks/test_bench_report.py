"""Benchmark: building the HTML report of one scene (budget: under 10 s).

The scene is synthetic but full-size (512×512 camera image, 256×256 receiver map,
convergence and cost studies) and already compared, like a compare run with a
cached reference: this measures only the report (encoding, plots, templates).
"""

from __future__ import annotations

import pytest

from reports import build_report
from tests.reports.conftest import make_comparison

pytestmark = pytest.mark.bench

#: Budget for one scene's report, seconds: a page that takes longer than a
#: reader waits for a local file is a defect.
BUDGET_S = 10.0


@pytest.fixture(scope="module")
def full_size():
    return make_comparison(camera=(512, 512), receiver=(256, 256))


@pytest.mark.parametrize("self_contained", [False, True], ids=["linked", "self-contained"])
def test_bench_report_one_scene(benchmark, tmp_path, full_size, self_contained):
    """Wall clock of build_report for one scene; the slowest round must fit the budget."""
    index = benchmark.pedantic(build_report, args=(tmp_path, [full_size]),
                               kwargs={"self_contained": self_contained}, rounds=3,
                               warmup_rounds=1)
    page = index.parent / "glass_sphere-paper" / "index.html"
    sizes = sum(p.stat().st_size for p in index.parent.rglob("*") if p.is_file())
    benchmark.extra_info.update(page_bytes=page.stat().st_size, total_bytes=sizes)
    print(f"\n{'self-contained' if self_contained else 'linked'}: page {page.stat().st_size} "
          f"bytes, all files {sizes} bytes")
    assert benchmark.stats.stats.max < BUDGET_S
