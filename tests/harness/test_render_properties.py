"""Property-based: valid but extreme scenes render without a traceback, NaN or hang.

Regression lock of "every failure is one clear line": Hypothesis mutates
the corpus base scene (a glass sphere over a floor) into legal extremes: lights
near and far, grazing and below the floor, tiny and huge intensities, near-unit and
high IORs, tiny and large spheres, either preset and estimator, few iterations, a
coarse grid. Each runs ``caustics render`` in-process. A scene ``validate`` refuses
must be refused with ``error:`` lines only; one it accepts must render, with every
image finite and strict JSON, within the per-example deadline (the no-hang bound:
the base renders in about 0.2 s on the 2-core CI machine, 100 x that is a hang).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from harness.cli import main
from renderers.exr import read_exr
from tests.harness.corpus_cases import edit

#: 20 s per render: 100 x the base scene's time (see the module docstring).
DEADLINE_MS = 20_000

finite = {"allow_nan": False, "allow_infinity": False}
extreme_scenes = st.fixed_dictionaries({
    "light": st.tuples(st.floats(-40, 40, **finite), st.floats(-40, 40, **finite),
                       st.floats(-3, 60, **finite)),
    "intensity": st.floats(1e-20, 1e20, **finite),
    "radius": st.floats(1e-3, 3.0, **finite),
    "centre_z": st.floats(-2.0, 5.0, **finite),
    "ior": st.floats(1.0001, 4.0, **finite),
    "grid": st.integers(2, 24),
    "iterations": st.integers(0, 8),
    "preset": st.sampled_from(["paper", "strong"]),
    "estimator": st.sampled_from(["modified", "newton", "secant"]),
})


def _scene_text(p: dict) -> str:
    x, y, z = p["light"]
    i = p["intensity"]
    return edit(
        ("position = [1.0, -0.5, 6.0]", f"position = [{x!r}, {y!r}, {z!r}]"),
        ("intensity = [30.0, 30.0, 30.0]", f"intensity = [{i!r}, {i!r}, {i!r}]"),
        ("radius = 1.0", f"radius = {p['radius']!r}"),
        ("center = [0.0, 0.0, 2.0]", f"center = [0.0, 0.0, {p['centre_z']!r}]"),
        ("ior = 1.5", f"ior = {p['ior']!r}"),
        ("grid = 16", f"grid = {p['grid']}\niterations = {p['iterations']}\n"
                      f"preset = \"{p['preset']}\"\nestimator = \"{p['estimator']}\""),
    )


@settings(max_examples=25, deadline=DEADLINE_MS, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow,
                                 HealthCheck.function_scoped_fixture])
@given(params=extreme_scenes)
def test_extreme_valid_scenes_render_finite(params, tmp_path_factory, capsys):
    """Regression lock: no traceback, no NaN or Inf, no hang, on legal extremes."""
    folder = tmp_path_factory.mktemp("extreme")
    scene = folder / "extreme.toml"
    scene.write_text(_scene_text(params), encoding="utf-8")
    out = folder / "out"
    status = main(["render", str(scene), "-o", str(out)])
    err = capsys.readouterr().err
    assert "Traceback" not in err, err
    if status != 0:
        # Refused (say, the light inside the sphere): one error line per problem.
        assert status == 1, err
        lines = [line for line in err.splitlines() if line.strip()]
        assert lines and all(line.startswith(("error:", "warning:")) for line in lines), err
        event("refused by validation")
        return
    event("rendered")
    json.loads((out / "result.json").read_text(encoding="utf-8"),
               parse_constant=lambda token: (_ for _ in ()).throw(AssertionError(token)))
    for image in sorted(Path(out).glob("*.exr")):
        for name, layer in read_exr(image).items():
            assert np.isfinite(layer).all(), f"{image.name}: {name} ({params})"
