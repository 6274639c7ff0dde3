"""Realistic :class:`SceneComparison` records built from synthetic images, without the
renderers: a Gaussian caustic blob on a dim receiver plus noise is the "reference",
the same blob shifted and scaled is the "method", and every value and map comes from
the real metric functions of ``harness.metrics`` and ``harness.studies.pareto``."""

from __future__ import annotations

import base64
import io
import re
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from harness.metrics import (
    flip_error,
    flux_ratio,
    relative_mse,
    signed_difference,
    structural_similarity,
    white_point,
)
from harness.studies.pareto import equal_error_speedup, pareto_front
from reports import images
from reports.display import difference_range
from reports.records import (
    Check,
    ConvergenceSection,
    CostSection,
    MethodProvenance,
    MetricValue,
    Provenance,
    SceneComparison,
    Table,
)

#: Markup that must render as text: a script, an event handler, a closing tag.
HOSTILE_NAME = '<script>window.__pwned = 1</script><b>bold</b>/../x'
HOSTILE_DESCRIPTION = ('<img src=x onerror="window.__pwned = 2"> & </p><script>'
                       'window.__pwned = 3</script> "quoted" \'single\'')


def caustic_blob(shape, *, centre, sigma, peak, rng, noise=0.0, background=0.05):
    """(H, W, 3) float32: a warm Gaussian caustic on a dim background, plus noise
    whose standard deviation is ``noise`` times the local value (Monte Carlo-like)."""
    h, w = shape
    y, x = np.mgrid[0:h, 0:w]
    cy, cx = centre
    blob = peak * np.exp(-((x - cx) ** 2 + (y - cy) ** 2) / (2 * sigma**2))
    image = background + blob[..., None] * np.array([1.0, 0.85, 0.6])
    if noise:
        image = image * (1 + noise * rng.standard_normal(image.shape))
    return np.maximum(image, 0).astype(np.float32)


def _view(prefix, shape, rng, *, shift, scale, object_mask=False, variance=False):
    """Images and metrics of one view: reference, an independent reference seed
    (for the noise floor) and the shifted, scaled method; with ``variance``, the
    reference's ``Var[mean]`` of its noise model, (0.05 × noiseless value)²."""
    h, w = shape
    centre = (h * 0.55, w * 0.45)
    sigma = min(h, w) / 9
    reference = caustic_blob(shape, centre=centre, sigma=sigma, peak=8.0, rng=rng, noise=0.05)
    seed2 = caustic_blob(shape, centre=centre, sigma=sigma, peak=8.0, rng=rng, noise=0.05)
    method = caustic_blob(shape, centre=(centre[0] + shift, centre[1] - shift),
                        sigma=sigma * scale, peak=8.0 / scale**2, rng=rng)
    caustic = reference.mean(axis=-1) > 1.0
    obj = None
    if object_mask:
        y, x = np.mgrid[0:h, 0:w]
        obj = (x - w * 0.5) ** 2 + (y - h * 0.3) ** 2 < (min(h, w) * 0.12) ** 2
    white = white_point(reference)
    start, stop = -4.0, 2.0
    _, ssim_map = structural_similarity(method, reference, white=white, return_map=True)
    flip, flip_map = flip_error(method, reference, start_exposure=start, stop_exposure=stop,
                                return_map=True)
    signed = signed_difference(method, reference).astype(np.float32)
    images = {f"{prefix}/method": method, f"{prefix}/reference": reference,
              f"{prefix}/signed": signed, f"{prefix}/ssim": ssim_map.astype(np.float32),
              f"{prefix}/flip": flip_map.astype(np.float32), f"{prefix}/mask_caustic": caustic}
    if obj is not None:
        images[f"{prefix}/mask_object"] = obj
    if variance:
        clean = caustic_blob(shape, centre=centre, sigma=sigma, peak=8.0, rng=rng)
        images[f"{prefix}/reference_variance"] = ((0.05 * clean) ** 2).astype(np.float32)
    regions = {"full": None, "caustic": caustic}
    if obj is not None:
        regions["object_masked"] = ~obj
    metrics = []
    for region, mask in regions.items():
        pairs = {
            "relmse": lambda a, b, m=mask: relative_mse(a, b, mask=m),
            "relmse_trimmed": lambda a, b, m=mask: relative_mse(a, b, mask=m, trim=0.001),
            "ssim": lambda a, b, m=mask: structural_similarity(a, b, white=white, mask=m),
            "flux_ratio": lambda a, b, m=mask: flux_ratio(a, b, mask=m),
        }
        for metric, function in pairs.items():
            metrics.append(MetricValue(prefix, region, metric, function(method, reference),
                                       function(seed2, reference)))
    metrics.append(MetricValue(prefix, "full", "flip", flip, flip_error(
        seed2, reference, start_exposure=start, stop_exposure=stop)))
    # The scene's difference scale, from the reference alone (harness.compare.scoring).
    return images, metrics, white, difference_range(reference)


def convergence_table(rng) -> Table:
    """Errors halving per iteration for three estimators, one of them safeguarded."""
    columns = ("estimator", "safeguarded", "iteration", "mean_error_m", "p95_error_m",
               "max_error_m", "mean_error_texels", "p95_error_texels", "max_error_texels",
               "converged", "diverged", "lost", "lookups_per_vertex", "relmse", "time_ms")
    rows = []
    for estimator, guarded, rate in (("modified", False, 0.5), ("newton", True, 0.3),
                                     ("secant", False, 0.4)):
        for it in range(6):
            mean = 0.2 * rate**it
            rows.append((estimator, guarded, it, mean, 2 * mean, 5 * mean, mean * 64,
                         2 * mean * 64, 5 * mean * 64, min(1.0, 0.2 * it), 0.0, 0.01,
                         float(it + 1), 0.01 + mean, 0.4 + 0.1 * it + rng.uniform(0, 0.01)))
    return Table(columns, tuple(rows))


def cost_table(rng) -> tuple[Table, float, float]:
    """Caustics-mapping configurations and a reference whose relMSE falls as 1/t;
    returns the table and the best real-time (time, error)."""
    columns = ("series", "label", "estimator", "iterations", "grid", "caustic_map",
               "splat_sigma", "time_warm_s", "time_cold_s", "relmse", "pareto")
    times = rng.uniform(0.002, 0.05, 12)
    errors = 0.002 / times**0.5 * rng.uniform(0.8, 1.3, 12)
    on_front = set(pareto_front(times, errors).tolist())
    rows = [("caustics_mapping", f"cfg{i}", "modified", 1 + i % 4, 64 * (1 + i % 3), 512, 1.5,
             float(t), float(t) + 0.3, float(e), i in on_front)
            for i, (t, e) in enumerate(zip(times, errors, strict=True))]
    for t in (1.0, 4.0, 16.0, 64.0):
        rows.append(("reference", f"spp{int(t * 16)}", "", 0, 0, 0, 0.0, t, t + 0.8, 0.5 / t,
                     False))
    best = max(on_front, key=lambda i: times[i])
    return Table(columns, tuple(rows)), float(times[best]), float(errors[best])


def make_comparison(*, name: str = "glass_sphere",
                    description: str = "Glass sphere over a diffuse floor, point light",
                    camera: tuple[int, int] = (96, 128), receiver: tuple[int, int] = (64, 64),
                    seed: int = 0, checks: bool = True,
                    variance: bool = False) -> SceneComparison:
    """A complete comparison of one synthetic scene (camera image + one receiver map);
    ``variance`` adds ``<view>/reference_variance`` to both views."""
    rng = np.random.default_rng(seed)
    cam_images, cam_metrics, cam_white, cam_range = _view(
        "camera", camera, rng, shift=3, scale=1.1, object_mask=True, variance=variance)
    rec_images, rec_metrics, rec_white, rec_range = _view(
        "receiver0", receiver, rng, shift=2, scale=0.9, variance=variance)
    metrics = tuple(cam_metrics + rec_metrics)
    cost, method_time, method_error = cost_table(rng)
    reference = [row for row in cost.records() if row["series"] == "reference"]
    speedup = equal_error_speedup(method_time, method_error, [r["time_warm_s"] for r in reference],
                                  [r["relmse"] for r in reference])
    found = ()
    if checks:
        ssim = next(m for m in metrics if (m.view, m.region, m.metric)
                    == ("receiver0", "caustic", "ssim")).value
        relmse = next(m for m in metrics if (m.view, m.region, m.metric)
                      == ("receiver0", "caustic", "relmse")).value
        found = (
            Check("ssim", "caustic", "receiver0", 0.5, "min", ssim, ssim >= 0.5,
                  "spread 0.01 over 4 seeds, margin 3σ"),
            Check("relmse", "caustic", "receiver0", relmse / 2, "max", relmse, False,
                  "deliberately tight for the test"),
            Check("flux agreement", "full", "all", 0.02, "band", 1.09, False,
                  "2 % (Weber fraction)", kind="physical requirement",
                  gap="a known gap, for the test"),
        )
    return SceneComparison(
        name=name, description=description, source=f"scenes/{name}.toml",
        effects=("refraction.double", "shadows", "fresnel"),
        settings={"estimator": "modified", "iterations": 3, "grid": 128, "caustic_map": 512,
                  "splat": {"kernel": "gaussian", "sigma": 1.5}, "photons": 10_000_000,
                  "spp": 1024, "seed": seed},
        metrics=metrics,
        images={**cam_images, **rec_images},
        exposure={"white": {"camera": cam_white, "receiver0": rec_white},
                  "flip_start": -4.0, "flip_stop": 2.0,
                  "diff_range": {"camera": cam_range, "receiver0": rec_range}},
        sections=(
            ConvergenceSection(convergence_table(rng), claims={
                "one iteration is enough for rendering": "holds: relMSE 0.012 at iteration 1",
                "error negligible after five iterations": "holds: mean error 0.02 texels"}),
            CostSection(cost, speedup=speedup, point=(method_time, method_error))),
        method="paper", method_description="the paper's choices",
        provenance=Provenance(
            scene_file=f"scenes/{name}.toml",
            method=MethodProvenance(
                name="paper", renderer="caustics mapping", timer="ctx.finish + perf_counter",
                frame_time_ms=12.0, preset="paper",
                passes=("receiver_positions", "object_front", "object_back", "caustic_map",
                        "shadow_map", "final")),
            reference={"event_chains": ["L T T D"], "photons": 10_000_000, "spp": 1024,
                       "seeds": [1, 2, 3, 4], "versions": {"mitsuba": "3.9.0", "drjit": "1.5.0"},
                       "timings_s": {"reference": 42.0}, "cache": "hit"},
            machine={"platform": "method fixture"}),
        files={"camera/method": "camera_method.exr", "camera/reference": "camera_ref.exr",
               "receiver0/method": "receiver0_method.exr"},
        checks=found,
        stability={"hard_cases": 3, "nan_or_inf": 0, "lost_splats": 12, "outcome": "pass"},
    )


def hdr_uris(scene_dir: Path) -> dict[str, dict[str, str]]:
    """The HDR preview data: URIs a linked scene folder ships in ``hdr.js``."""
    text = (scene_dir / "hdr.js").read_text("utf-8")
    found = re.findall(r'window\.causticsHdr\["(\w+)"\] = \{"method": "([^"]+)", '
                       r'"reference": "([^"]+)"\};', text)
    return {view: {"method": t, "reference": r} for view, t, r in found}


def decode_uri(uri: str) -> np.ndarray:
    """Linear HDR values of an RGBE-stack PNG data: URI (as the page's JS decodes them)."""
    data = base64.b64decode(uri.split(",", 1)[1])
    return images.decode_rgbe_stack(np.asarray(Image.open(io.BytesIO(data))))


@pytest.fixture(scope="session")
def comparison() -> SceneComparison:
    """One realistic comparison (96×128 camera image, 64×64 receiver map)."""
    return make_comparison()


@pytest.fixture(scope="session")
def hostile_comparison() -> SceneComparison:
    """A scene whose name and description carry HTML and script tags."""
    return make_comparison(name=HOSTILE_NAME, description=HOSTILE_DESCRIPTION, seed=1,
                           checks=False)


@pytest.fixture(scope="session")
def comparison_factory() -> Callable[..., SceneComparison]:
    """:func:`make_comparison` itself, for tests that need other sizes or names."""
    return make_comparison
