"""Benchmark: what each side costs, warm, in one run, each measurement in a fresh
process so that its peak memory is its own (the timing policy of
docs/statistics.md, "Timing policy: warm and cold").

Printed in one table (glass_sphere, receiver maps 256 x 256, camera 512 x 512):

* the reference photon tracer's photons/s (caustic-only, as the reference) against
  Mitsuba's own ``ptracer`` light paths/s on the same scene, and their ratio;
* the reference's time to 1 % relative noise (K seeds, cold process: scene build
  and kernel compile included, as a user waits for it);
* the method's warm frame time and receiver-map passes time per preset;
* each run's peak memory: CPU RSS of its process (``os.wait4``'s ``ru_maxrss``)
  and, where ``nvidia-smi`` exists, the GPU memory it held at most (polled).

Warm means the median of ``REPEATS`` runs after an untimed warm-up
(``time.perf_counter``). Nothing is asserted about time; a run that fails fails.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import threading

import pytest

pytestmark = pytest.mark.bench

REPEATS = 5

_RUN = """
import json, statistics, sys, time
import numpy as np
from scenes import load_scene, resolve_scene, with_settings
REPEATS = int(sys.argv[2])
what = sys.argv[1]
scene = with_settings(load_scene(resolve_scene("glass_sphere")), {"receiver_map": [256, 256]})

def warm(run):
    run()
    times = []
    for _ in range(REPEATS):
        start = time.perf_counter(); run(); times.append(time.perf_counter() - start)
    return statistics.median(times)

if what == "photons":
    from renderers.mitsuba.photons import PhotonTracer
    tracer = PhotonTracer(scene, caustic_only=True)
    n = 1 << 22
    s = warm(lambda: tracer.trace(n, seed=0))
    print(json.dumps({"rate": n / s, "unit": "photons/s", "seconds": s}))
elif what == "ptracer":
    from renderers.mitsuba import load_mitsuba, mitsuba_versions
    from renderers.mitsuba.camera import camera_max_depth
    from renderers.mitsuba.exporter import export_scene, sensor_dict
    mi, _, _ = load_mitsuba()
    depth = camera_max_depth(scene)
    spp = 16
    exported = export_scene(scene, sensor=sensor_dict(scene.camera, spp=spp),
                            integrator={"type": "ptracer", "max_depth": depth,
                                        "rr_depth": depth + 1})
    w, h = scene.camera.resolution
    s = warm(lambda: np.asarray(mi.render(exported.scene, spp=spp, seed=0)))
    print(json.dumps({"rate": spp * w * h / s, "unit": "light paths/s", "seconds": s}))
elif what == "noise":
    from renderers.mitsuba.reference import estimate_receivers
    start = time.perf_counter()
    est = estimate_receivers(scene, photons=1 << 27, target_noise=0.01, caustic_only=True)
    print(json.dumps({"seconds": time.perf_counter() - start, "noise": est.relative_noise,
                      "photons": est.photons, "seeds": est.seeds}))
else:
    from harness.studies.runner import RealtimeRunner, caustic_seconds, frame_seconds
    from renderers.methods import load_method
    with RealtimeRunner(load_method(what).configure(scene), repeats=REPEATS) as runner:
        _, frame = runner.timed(clock=frame_seconds)
        maps = runner.median(clock=caustic_seconds)
        print(json.dumps({"seconds": frame, "maps_seconds": maps,
                          "gl": runner.ctx.info["GL_RENDERER"]}))
"""


def _gpu_mib(pid: int, stop: threading.Event, peak: list[float]) -> None:
    """Poll nvidia-smi for the memory ``pid`` holds; keep the maximum in ``peak``."""
    query = ["nvidia-smi", "--query-compute-apps=pid,used_memory",
             "--format=csv,noheader,nounits"]
    while not stop.wait(0.2):
        out = subprocess.run(query, capture_output=True, text=True, check=False).stdout
        for line in out.splitlines():
            fields = [f.strip() for f in line.split(",")]
            if len(fields) == 2 and fields[0] == str(pid) and fields[1].isdigit():
                peak[0] = max(peak[0], float(fields[1]))


def _measure(what: str) -> dict:
    proc = subprocess.Popen([sys.executable, "-c", _RUN, what, str(REPEATS)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    stop, peak, poller = threading.Event(), [0.0], None
    if shutil.which("nvidia-smi"):
        poller = threading.Thread(target=_gpu_mib, args=(proc.pid, stop, peak), daemon=True)
        poller.start()
    out, err = proc.stdout.read(), proc.stderr.read()
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    stop.set()
    assert proc.returncode == 0, err
    result = json.loads(out.strip().splitlines()[-1])
    result["peak_rss_mib"] = usage.ru_maxrss / 1024  # Linux: KiB
    result["peak_gpu_mib"] = peak[0] if poller else None
    return result


def test_cost_of_each_side(record_property):
    runs = {what: _measure(what) for what in ("photons", "ptracer", "noise", "paper", "strong")}
    ratio = runs["photons"]["rate"] / runs["ptracer"]["rate"]
    print(f"\nglass_sphere, warm: median of {REPEATS} after a warm-up (time.perf_counter):")
    for what, r in runs.items():
        rate = f"{r['rate'] / 1e6:.3f} M {r['unit']}" if "rate" in r else ""
        maps = f", maps {r['maps_seconds'] * 1e3:.1f} ms" if "maps_seconds" in r else ""
        gpu = f", GPU {r['peak_gpu_mib']:.0f} MiB" if r["peak_gpu_mib"] else ""
        print(f"  {what:8s} {r['seconds'] * 1e3:9.1f} ms{maps} {rate}  "
              f"peak RSS {r['peak_rss_mib']:.0f} MiB{gpu}")
        record_property(what, r)
    print(f"  photon tracer photons/s / ptracer light paths/s = {ratio:.3f}")
    print(f"  time to 1 % noise: {runs['noise']['seconds']:.1f} s "
          f"({runs['noise']['photons']} photons x {runs['noise']['seeds']} seeds, cold process)")
    record_property("photons_over_ptracer", ratio)
