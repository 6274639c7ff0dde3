"""`caustics score`: the harness's own `strong` render, written to EXR by `compare`,
scored as an external render, and every kind of bad file refused in one line."""

from __future__ import annotations

import json

import numpy as np
import pytest

from harness.cli import main
from renderers.exr import read_exr, write_exr
from scenes import parse_override
from tests.harness.commands.test_compare import SMALL, _small_scene


@pytest.fixture(scope="module")
def strong(tmp_path_factory):
    """A small glass_sphere compared with ``strong`` (metrics only): the scene file and
    the comparison's folder, whose ``<view>_method.exr`` are the render (the run's
    shared reference cache)."""
    root = tmp_path_factory.mktemp("score")
    scene = _small_scene(root)
    out = root / "compare"
    assert main(["compare", str(scene), "--preset", "strong", "--studies", "metrics", "-q",
                 "-o", str(out), *SMALL]) == 0
    return scene, out / "glass_sphere-strong"


def _metrics(folder) -> dict:
    data = json.loads((folder / "metrics.json").read_text())
    return {(m["view"], m["region"], m["metric"]): m for m in data["metrics"]}


def _score(scene, out, *args) -> int:
    return main(["score", str(scene), "-o", str(out), "-q", *args, *SMALL])


def test_score_of_strongs_own_exrs_reproduces_compare(strong, tmp_path, capsys):
    """Regression lock: scoring strong's own EXRs gives compare's excess relMSE, its
    interval and every other metric, to float rounding; the reported time is shown as
    reported, never as a harness measurement, and no speedup is computed from it."""
    scene, folder = strong
    (folder.parent / "render.json").write_text('{"frame_ms": 12.5, "device": "a GPU"}')
    capsys.readouterr()
    assert _score(scene, tmp_path / "out", "--camera", str(folder / "camera_method.exr"),
                  "--receiver", f"0={folder / 'receiver0_method.exr'}",
                  "--timing", str(folder.parent / "render.json")) == 0
    printed = capsys.readouterr().out
    assert "reported by the renderer, not measured by the harness" in printed
    scored_folder = tmp_path / "out" / "glass_sphere-external"
    compared, scored = _metrics(folder), _metrics(scored_folder)
    assert set(scored) == set(compared)
    for key, m in compared.items():
        s = scored[key]
        assert s["value"] == pytest.approx(m["value"], rel=1e-6, abs=1e-12, nan_ok=True), key
        if m["excess"] is not None:
            assert s["excess"] == pytest.approx(m["excess"], rel=1e-6, abs=1e-12), key
            assert s["excess_ci95"] == pytest.approx(m["excess_ci95"], rel=1e-6, abs=1e-12)
    relmse = scored[("receiver0", "caustic", "relmse")]
    assert relmse["excess"] is not None and relmse["excess_ci95"] is not None
    data = json.loads((scored_folder / "metrics.json").read_text())
    method = data["provenance"]["method"]
    assert method["frame_time_ms"] is None            # the harness measured nothing
    assert method["metadata"]["reported_timing"]["frame_ms"] == 12.5
    assert data["equal_error_speedup"] is None
    assert any(h["kind"] == "timing" and "12.5 ms" in h["text"] for h in data["headlines"])
    assert set(data["files"].values()) >= {"camera_method.exr", "receiver0_method.exr"}


@pytest.mark.parametrize("view", ["camera", "receiver"])
def test_either_view_alone_is_scored(strong, tmp_path, view):
    """A render of one view only scores that view; the other is said not scored."""
    scene, folder = strong
    arg = (["--camera", str(folder / "camera_method.exr")] if view == "camera"
           else ["--receiver", f"0={folder / 'receiver0_method.exr'}"])
    assert _score(scene, tmp_path / "out", *arg) == 0
    out = tmp_path / "out" / "glass_sphere-external"
    views = {v for v, _, _ in _metrics(out)}
    assert views == ({"camera"} if view == "camera" else {"receiver0"})
    data = json.loads((out / "metrics.json").read_text())
    missing = "receiver maps" if view == "camera" else "camera"
    assert any(h["kind"] == "views" and missing in h["text"].lower()
               for h in data["headlines"])


def _bad_files(folder, tmp_path):
    """(file, arguments, what the error line says) for each kind of bad file."""
    receiver = read_exr(folder / "receiver0_method.exr")["RGB"]
    cases = []

    def case(name, layers, said):
        path = tmp_path / name
        write_exr(path, layers)
        cases.append((path, ["--receiver", f"0={path}"], said))

    case("small.exr", {"RGB": receiver[:40]}, "48x40 pixels, but the scene's receiver_map")
    case("grey.exr", {"Y": receiver[..., 0]}, "needs one RGB layer")
    negative = receiver.copy()
    negative[3, 4, 1] = -1.0
    case("negative.exr", {"RGB": negative}, "1 negative values")
    nan = receiver.copy()
    nan[0, 0, 0] = np.nan
    case("nan.exr", {"RGB": nan}, "NaN or Inf")
    torn = tmp_path / "torn.exr"
    torn.write_bytes((folder / "receiver0_method.exr").read_bytes()[:200])
    cases.append((torn, ["--receiver", f"0={torn}"], "unreadable EXR"))
    camera = tmp_path / "camera_small.exr"
    write_exr(camera, {"RGB": read_exr(folder / "camera_method.exr")["RGB"][:, :47]})
    cases.append((camera, ["--camera", str(camera)], "but the scene's camera resolution"))
    timing = tmp_path / "timing.json"
    timing.write_text('{"frame_ms": "fast"}')
    cases.append((timing, ["--camera", str(folder / "camera_method.exr"),
                           "--timing", str(timing)], "frame_ms must be"))
    return cases


def test_each_bad_file_is_one_line_naming_it_and_nothing_is_written(strong, tmp_path,
                                                                      capsys):
    """A file of the wrong size, channels or layout, with NaN or a negative value,
    truncated, or a bad timing report: exit 1, one ``error:`` line naming the file
    and what is wrong, and no output folder."""
    scene, folder = strong
    for path, args, said in _bad_files(folder, tmp_path):
        out = tmp_path / f"out-{path.stem}"
        capsys.readouterr()
        assert _score(scene, out, *args) == 1, path.name
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("error: ") and str(path) in err[0], err
        assert said in err[0], err
        assert not out.exists() or not any(out.iterdir()), path.name


def test_no_view_and_a_missing_file_are_refused(strong, tmp_path, capsys):
    """No image at all, and a file that is not there: one line each, nothing written."""
    scene, _ = strong
    assert _score(scene, tmp_path / "none") == 1
    assert "no image to score" in capsys.readouterr().err
    missing = tmp_path / "nowhere.exr"
    assert _score(scene, tmp_path / "gone", "--camera", str(missing)) == 1
    err = capsys.readouterr().err
    assert f"{missing}: no such file" in err
    assert not (tmp_path / "none").exists() and not (tmp_path / "gone").exists()


def test_the_api_and_the_pytest_fixture_score_the_same_files(strong, caustics):
    """Regression lock: ``caustics.score`` (the pytest fixture, through
    ``harness.api.score``) on strong's receiver map gives compare's excess relMSE,
    and the fixture's assertions take its comparison."""
    scene, folder = strong
    settings = dict(parse_override(SMALL[i + 1]) for i in range(0, len(SMALL), 2))
    comparison = caustics.score(scene, receivers={0: folder / "receiver0_method.exr"},
                                settings=settings)
    m = comparison.metric("relmse", view="receiver0", region="caustic")
    compared = _metrics(folder)[("receiver0", "caustic", "relmse")]
    assert m.excess == pytest.approx(compared["excess"], rel=1e-6)
    assert comparison.method == "external"
    caustics.assert_excess_below(comparison, "relmse", 1.0)
