"""One timing policy for both sides of a cost comparison.

Every time the cost study reports comes in two kinds, taken the same way for the
real-time method and for the reference's photon tracer, over the same scope (the
work that produces the compared receiver maps, their read-back to host memory
included on both sides; Python imports and driver start-up, the EGL display and
Dr.Jit's backend, excluded on both sides):

* **warm**: steady state, the median of ``repeats`` runs (at least
  :data:`MIN_REPEATS` unless the comparison is a quick look) after one untimed
  warm-up run of the same configuration;
* **cold**: a first frame or launch in a fresh process,

      t_cold = t_build + t_compile + t_warm,

  with each term measured in the same run: ``t_build`` the one-off set-up
  (method: the GL context and the scene's meshes; reference: the scene's meshes,
  the Mitsuba scene and its acceleration structure), ``t_compile`` the first
  run's excess over the warm time of the same configuration (method: shader
  compilation and first-use allocations; reference: Dr.Jit kernel compilation,
  from its on-disk cache when one is warm, as a user's second session sees it).

The reference's photon kernel is compiled once for every photon budget (its
launch size enters as opaque values), so ``t_compile`` is one number per side.
"""

from __future__ import annotations

import dataclasses
import statistics
import time
from collections.abc import Callable
from typing import Any

__all__ = ["MIN_REPEATS", "TIMING_POLICY", "OneOffCosts", "median_seconds"]

#: Fewest repeats whose median is reported as a warm time (docs/statistics.md,
#: "Timing policy: warm and cold").
MIN_REPEATS = 5

#: One line for reports and CSV readers.
TIMING_POLICY = ("warm: median of the repeats after an untimed warm-up of the same "
                 "configuration; cold = build + compile + warm, each measured in this run "
                 "(build: GL context and meshes / Mitsuba scene and BVH; compile: first "
                 "run minus warm); scope: the passes producing the receiver maps, "
                 "read-back included, on both sides; timer: time.perf_counter")


@dataclasses.dataclass(frozen=True)
class OneOffCosts:
    """What a fresh process pays once, before its first result.

    Attributes
    ----------
    build_s : float
        One-off set-up (s).
    compile_s : float
        First run's excess over the warm time of the same configuration (s),
        never negative.
    """

    build_s: float
    compile_s: float

    def cold(self, warm_s: float) -> float:
        """Cold time (s) of a configuration whose warm time is ``warm_s``."""
        return self.build_s + self.compile_s + warm_s

    def as_dict(self) -> dict[str, float]:
        return dataclasses.asdict(self)


def median_seconds(run: Callable[[], Any], *, repeats: int) -> tuple[Any, float, float]:
    """``(last result, first run's seconds, median seconds of the repeats)``: one
    warm-up run, then ``repeats`` timed runs, each timed with ``time.perf_counter``."""
    start = time.perf_counter()
    result = run()
    first = time.perf_counter() - start
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        result = run()
        times.append(time.perf_counter() - start)
    return result, first, statistics.median(times)
