"""Method targets (harness/checks/data/method_targets.toml) against the Mitsuba
reference, at the scenes' own settings. Kind: **method target** — what a preset
should reach, each number with its reason in the file (docs/method.md, "Presets").
A target missed today carries its gap and is a strict ``xfail`` naming it; a target
with a ``contrast`` method is also shown missed by that method, so the measure can
fail.

Measured on this machine (llvmpipe; relMSE: the excess over the scene's caustic region
with its 95 % interval, as ``caustics compare`` reports it). Two references: the
scenes' own budget (4 seeds x 2 M photons and on toward 1 % noise, the bunny's at its
120 s time cap), and this test's (REFERENCE_BUDGET: 4 seeds x 1 M photons, no launch
past them; SCENE_PHOTONS: 256 k for dispersion_sphere and the bunny). The smaller
budget widens the intervals and still decides every target (the decisions are
asserted):

===============================  ==================  ==================
measure                          strong              paper
===============================  ==================  ==================
glass_sphere excess relMSE       5.64e-5             0.0422
  (95 % interval)                [4.77e-5, 6.51e-5]  [0.0422, 0.0423]
  here (1 M photons a seed)      5.08e-5             0.0423
  (95 % interval)                [6.6e-6, 9.49e-5]   [0.0422, 0.0425]
focus peak / reference           0.998 (here 0.999)  0.47
share within 5 cm (ref 0.351)    0.351               0.166
flux ratio                       0.9985 (here 0.999) 1.0006
TIR / off-receiver flux          0 / 0               1.15 % / 0.95 %
dispersion flux per channel      0.997 0.994 0.990   1.033 1.055 1.090
  (here 256 k, worst channel)    0.988               1.090
bunny excess relMSE              0.0695              0.473
  (95 % interval)                [0.0693, 0.0697]    [0.472, 0.474]
  here (256 k photons a seed)    0.0715              0.478
  (95 % interval)                [0.0681, 0.0748]    [0.451, 0.504]
bunny vertices on the object     9,813               4,753
camera black fraction, |Δ| vs    0.0031              0.027
  exact (glass_sphere, 512²)
camera mean radiance / exact     0.9999              1.061
dispersion camera black |Δ|      0.0030              0.27 (known gap)
===============================  ==================  ==================

Time (pytest's clock, this file alone on the 2-core machine): 21 s here, against 197 s
in a full run with the old budget (on to 2 % noise or a 15 s cap per reference, the
camera tracer's image: the bunny's reference alone traced 140 s).
"""

from __future__ import annotations

import pytest

from harness.checks import TARGETS_FILE
from harness.checks.bounds import judge, load_targets
from harness.checks.camera import camera_measures, exact_camera
from harness.checks.stability import stability_summary
from harness.checks.targets import caustic_relmse, check_targets, target_measures
from harness.compare.regions import scene_caustic_region
from harness.compare.scoring import channel_correlation
from renderers.caustics_mapping import render_frame
from renderers.methods import load_method
from renderers.mitsuba import render_reference
from scenes import load_scene, with_settings
from scenes.geometry import build_geometry
from tests.conftest import SCENES

pytestmark = pytest.mark.method_target

TARGETS = load_targets(TARGETS_FILE)

#: The references' budget here, smaller than the scenes' own (2 M photons per seed
#: and on to 1 % noise or a 120 s cap; the bunny's took its whole cap): the starting
#: budget of 1 M photons per seed only (a target noise of 100 %, met there, so no launch
#: past it; on toward 2 % the bunny's traced 12 M photons a seed, 140 s), and one camera
#: sample per pixel by Mitsuba's ptracer (no target reads the reference's camera image;
#: the camera tracer's lookup maps scale with the receiver maps' photons and cost as much
#: again). The method renders at the scene's own settings, which is what a target is
#: about; the excess relMSE has no bias from the reference's noise, only a wider
#: interval, and every target's decision is still asserted ("holds", and "fails" for the
#: contrast method, never "undecided"), so a budget too small to decide a target fails
#: here rather than passing.
REFERENCE_BUDGET = {"photons": 1 << 20, "target_noise": 1.0, "spp": 1}
#: Photons per seed where a quarter of them still decides every target of the scene:
#: dispersion_sphere's is a flux ratio (its standard error from the seeds' totals is
#: far below the 2 % band; measured 0.988 at 1 M); the bunny's excess relMSE interval
#: at 1 M, [0.0674, 0.0700], lies far below its bound of 0.2 (paper: 0.465, far above).
SCENE_PHOTONS = {"dispersion_sphere": 1 << 18, "bunny": 1 << 18}
REFERENCE_CAMERA = "ptracer"


def _references(scene):
    """The reference and the independent one (seeds K..2K-1) at REFERENCE_BUDGET, their
    receiver maps as ``caustics compare`` traces them, in the run's reference cache."""
    scene = with_settings(scene, {**REFERENCE_BUDGET,
                                  "photons": SCENE_PHOTONS.get(scene.name, 1 << 20)})
    other = with_settings(scene, {"seed": scene.settings.seed + scene.settings.seeds})
    return tuple(render_reference(s, progress=False, camera=REFERENCE_CAMERA)
                 for s in (scene, other))


def _param(t):
    marks = [pytest.mark.xfail(strict=True, reason=f"known gap: {t.gap}")] if t.gap else []
    return pytest.param(t, marks=marks, id=f"{t.scene}-{t.method}-{t.metric}")


@pytest.fixture(scope="module")
def measures(tmp_path_factory, context_factory):
    """Every measure of (scene, method) and the intervals of those that have one, each
    reference and render made once: the reference and the independent one (the
    scene's caustic region) by :func:`_references`, shared by both presets; relMSE is
    the comparison's ``caustic / relmse`` record
    (:func:`harness.checks.targets.caustic_relmse`)."""
    ctx = context_factory()
    references, out = {}, {}

    def get(name, method):
        if (name, method) not in out:
            scene = load_scene(SCENES / f"{name}.toml")
            if name not in references:
                references[name] = _references(scene)
            reference, independent = references[name]
            configured = load_method(method).configure(scene)
            with ctx:
                frame = render_frame(configured, ctx=ctx)
            stability = stability_summary(configured, build_geometry(configured),
                                          frame.result, hits=frame.hits)
            relmse = caustic_relmse(
                reference.receivers[0], frame.result.receivers[0],
                scene_caustic_region(independent.receivers[0].irradiance),
                seeds=int(reference.metadata["seeds"]),
                channel_correlation=channel_correlation(scene))
            out[(name, method)] = target_measures(
                reference.receivers[0], frame.result.receivers[0], relmse=relmse,
                stability=stability, status_counts=frame.result.metadata["status_counts"])
            exact = exact_camera(scene, reference.receivers)
            if exact is not None:
                out[(name, method)][0].update(camera_measures(exact, frame.result.camera))
        return out[(name, method)]

    return get


@pytest.mark.parametrize("target", [_param(t) for t in TARGETS])
def test_method_target(measures, record_property, target):
    """The method reaches the target (the file gives the reason for each number);
    the contrast method, where one is named, misses it."""
    record_property("checks", 1)
    values, intervals = measures(target.scene, target.method)
    (check,) = check_targets([target], scene=target.scene, method=target.method,
                             measures=values, intervals=intervals)
    print(f"{target.scene} ({target.method}) {target.metric} = {check.value:.5g} "
          f"{check.interval_text} {check.bound_text}: {check.decision}")
    assert check.decision == "holds", \
        f"{target.metric} = {check.value:.5g} {check.interval_text} is {check.decision} " \
        f"against {check.bound_text} ({target.reason})"
    if target.contrast:
        other, other_intervals = measures(target.scene, target.contrast)
        verdict = judge(target.kind, target.bound, other[target.metric],
                        other_intervals.get(target.metric))
        print(f"  {target.contrast}: {other[target.metric]:.5g} "
              f"{other_intervals.get(target.metric, '')}: {verdict}")
        assert verdict == "fails", \
            f"the {target.contrast} preset does not miss it ({other[target.metric]:.5g}: " \
            f"{verdict}): it separates nothing"
