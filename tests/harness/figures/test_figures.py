"""`caustics figures --quick`: every figure is written with its data and caption, no
two of its texts overlap, and the data say what the paper's figures show (the data
are checked, not the pixels); and the overlap check itself, on figures made to
overlap and not to.

The default run makes the figures of :data:`SUBSET` (about 10 s of the command's
45 s on llvmpipe: fig07 0.6 s, fig11 1.0 s, fig12 1.5 s, fig13a 3.0 s, decomposition
3.4 s); every figure, and the tests of the others' data, run with ``slow``."""

from __future__ import annotations

import csv
import json
import math

import matplotlib.pyplot as plt
import pytest

from harness.cli import main
from harness.figures import FIGURES, FigureContext, common
from harness.figures.common import FigureTextOverlapError, text_overlaps

#: The figures the default run makes (the cheapest at quick settings, each with a
#: test of its data below); the rest are made for the ``slow`` tests.
SUBSET = ("fig07", "fig11", "fig12", "fig13a", "decomposition")


def _made(tmp_path_factory, names):
    """The figures ``names`` at quick settings, through the command: the output folder
    and what the overlap check that ``save`` runs found for each, by figure name (None:
    saved without the check; a failing check also fails the command, whose assertion
    then shows the pairs)."""
    out = tmp_path_factory.mktemp("figures")
    found: dict[int, list] = {}
    checked: dict[str, list | None] = {}
    real_overlaps, real_save = common.text_overlaps, FigureContext.save

    def recording_overlaps(figure, **kwargs):
        found[id(figure)] = real_overlaps(figure, **kwargs)
        return found[id(figure)]

    def recording_save(self, name, figure, **kwargs):
        try:
            return real_save(self, name, figure, **kwargs)
        finally:
            checked[name] = found.pop(id(figure), None)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(common, "text_overlaps", recording_overlaps)
        patch.setattr(FigureContext, "save", recording_save)
        code = main(["figures", "-o", str(out), "--quick", "-q", "--only", ",".join(names)])
    assert code == 0, checked
    return out, checked


@pytest.fixture(scope="module")
def subset(tmp_path_factory):
    """:data:`SUBSET`'s figures (:func:`_made`)."""
    return _made(tmp_path_factory, SUBSET)


@pytest.fixture(scope="module")
def every(tmp_path_factory):
    """Every figure (:func:`_made`)."""
    return _made(tmp_path_factory, tuple(FIGURES))


@pytest.fixture
def figures(subset):
    """The folder of :data:`SUBSET`'s figures."""
    return subset[0]


@pytest.fixture
def all_figures(every):
    """The folder of every figure."""
    return every[0]


#: The two runs: the subset by default, every figure with ``slow``.
RUNS = [pytest.param("subset", SUBSET, id="subset"),
        pytest.param("every", tuple(FIGURES), id="every", marks=pytest.mark.slow)]


def _csv(path):
    with path.open() as f:
        return list(csv.DictReader(f))


@pytest.mark.parametrize(("run", "names"), RUNS)
def test_every_figure_has_png_pdf_data_and_caption(run, names, request):
    out, _ = request.getfixturevalue(run)
    for name in names:
        assert (out / f"{name}.png").stat().st_size > 1000
        assert (out / f"{name}.pdf").read_bytes().startswith(b"%PDF")
        assert (out / f"{name}.csv").is_file() or (out / f"{name}.json").is_file()
        caption = (out / f"{name}.txt").read_text()
        assert caption.startswith("Fig.") and any(ch.isdigit() for ch in caption)


@pytest.mark.parametrize(("run", "names"), RUNS)
def test_no_figure_has_overlapping_text(run, names, request):
    """Each figure the run made was checked when saved, and none has two texts over
    each other (the bottom row of Figs. 6 and 10 once had its panel titles run into
    each other)."""
    _, checked = request.getfixturevalue(run)
    assert set(checked) == set(names)
    assert {name: found for name, found in checked.items() if found != []} == {}


def _two_titles(*, gap: float):
    """Two 2.4-inch panels side by side, ``gap`` inches apart, each under a 10-pt
    title about 2.8 inches wide (measured): 0.4 inch wider than its panel."""
    figure = plt.figure(figsize=(8.0, 3.0))
    for i, name in enumerate(("left", "right")):
        ax = figure.add_axes(((0.4 + i * (2.4 + gap)) / 8.0, 0.1, 2.4 / 8.0, 0.7))
        ax.set_title(f"{name}: a title far wider than its own panel", fontsize=10)
        ax.set_axis_off()
    return figure


def test_overlap_found_between_titles_of_neighbours():
    """Over touching panels the two titles share 0.4 inch (40 px at the default 100
    dpi), far over the 1-px tolerance; the pair names both titles, in drawing order."""
    figure = _two_titles(gap=0.0)
    try:
        overlaps = text_overlaps(figure)
    finally:
        plt.close(figure)
    assert len(overlaps) == 1
    pair = overlaps[0]
    assert pair.first == "title of axes 0 'left: a title far wider than its own panel'"
    assert pair.second == "title of axes 1 'right: a title far wider than its own panel'"
    assert 30 < pair.width_px < 50 and pair.height_px > 5


def test_no_overlap_when_apart_and_hidden_ticks_ignored():
    """The same titles over panels 0.8 inch apart (twice the 0.4 inch they would
    share) do not overlap. The tick labels that an axes switched off still holds
    (visible, but neither drawn nor placed: counted, two of them sit on each other)
    are not counted."""
    figure = _two_titles(gap=0.8)
    try:
        assert text_overlaps(figure) == []
    finally:
        plt.close(figure)


def test_tick_labels_of_one_axis_overlap_each_other():
    """Tick labels are checked against each other: twenty 10-pt labels of nine
    characters (each over half an inch wide) on the 1.5-inch x axis of a 2-inch
    figure (under 0.1 inch apart) collide, and only with each other."""
    figure, ax = plt.subplots(figsize=(2.0, 2.0))
    ax.set_xticks(range(20), [f"label {i:03d}" for i in range(20)])
    try:
        overlaps = text_overlaps(figure)
    finally:
        plt.close(figure)
    assert overlaps and all("x tick label" in o.first and "x tick label" in o.second
                            for o in overlaps)


def test_save_refuses_a_figure_with_overlapping_text(tmp_path):
    """``FigureContext.save`` raises the typed error naming the figure and both
    titles, and writes nothing."""
    context = FigureContext(out_dir=tmp_path)
    with pytest.raises(FigureTextOverlapError) as raised:
        context.save("figX", _two_titles(gap=0.0), caption="Fig. X")
    message = str(raised.value)
    assert message.startswith("figure figX: two texts overlap: title of axes 0")
    assert "'left: a title" in message and "'right: a title" in message
    assert raised.value.name == "figX" and len(raised.value.overlaps) == 1
    assert list(tmp_path.iterdir()) == []


def test_command_fails_on_a_figure_with_overlapping_text(tmp_path, monkeypatch, capsys):
    """``caustics figures`` exits 1 with one ``error:`` line naming the figure and the
    first pair when a figure's texts overlap (the figure here is made to)."""
    monkeypatch.setitem(FIGURES, "figX", lambda ctx: ctx.save(
        "figX", _two_titles(gap=0.0), caption="Fig. X"))
    code = main(["figures", "--only", "figX", "-o", str(tmp_path / "out"), "-q"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1
    assert len(err) == 1 and err[0].startswith("error: figure figX: two texts overlap: title")
    assert "'left: a title" in err[0] and "'right: a title" in err[0]


@pytest.mark.slow
def test_fig06_both_methods_scored(all_figures):
    """Both of the paper's estimators (paper preset) and the strong preset beside
    them are scored; the strong preset's receiver error is below the paper's
    (method target, also at the figures' quick settings)."""
    rows = {(r["preset"], r["estimator"]): r for r in _csv(all_figures / "fig06.csv")}
    assert set(rows) == {("paper", "secant"), ("paper", "modified"), ("strong", "secant")}
    for row in rows.values():
        assert 0 < float(row["receiver_relmse"]) < 1 and float(row["frame_ms"]) > 0
        assert 0.9 < float(row["flux_ratio"]) < 1.1
    assert float(rows["strong", "secant"]["receiver_relmse"]) < float(
        rows["paper", "modified"]["receiver_relmse"])


def test_fig11_finer_grid_is_more_accurate(figures):
    """The paper's point: 128² resolves what 64² leaves as gaps (measured relMSE
    0.057 vs 0.018 in quick mode)."""
    rows = {int(r["grid"]): r for r in _csv(figures / "fig11.csv")}
    assert float(rows[128]["receiver_relmse"]) < float(rows[64]["receiver_relmse"])
    assert float(rows[128]["gap_fraction"]) <= float(rows[64]["gap_fraction"])


def test_fig13a_absorption_colours_agree(figures):
    """Beer-Lambert per channel (K_a 0.1, 0.6, 1.5 1/m): red passes most, blue least,
    and the two renderers' transmitted fractions agree within 3 % (measured 0.3 %)."""
    rows = {r["renderer"]: [float(r[f"transmitted_{c}"]) for c in "rgb"]
            for r in _csv(figures / "fig13a.csv")}
    for values in rows.values():
        assert values[0] > values[1] > values[2]
    for a, b in zip(rows["reference"], rows["caustics mapping"], strict=True):
        assert a == pytest.approx(b, rel=0.03)


@pytest.mark.slow
def test_fig13b_channels_separate(all_figures):
    """Higher IOR focuses closer (ball lens: f = nR / 2(n − 1) from the centre, 1.61 m
    for red, 1.31 m for blue), so on the floor 2 m below the centre blue has passed
    its focus furthest and spreads widest: radius R < G < B in both renderers."""
    rows = _csv(all_figures / "fig13b.csv")
    for renderer in ("caustics mapping", "reference"):
        radius = {r["channel"]: float(r["radius_m"]) for r in rows if r["renderer"] == renderer}
        assert radius["R"] < radius["G"] < radius["B"], (renderer, radius)


def test_fig12_uses_cube_faces(figures):
    data = json.loads((figures / "fig12.json").read_text())
    assert len(data["map_faces"]) > 1
    assert any(p.startswith("caustic_trace.reflection") for p in data["passes"])


def test_decomposition_figure_names_the_bunnys_largest_source(figures):
    """The decomposition figure (quick: the bunny, both presets) has the four steps
    per preset in order (the strong preset's rim patches a fifth), relMSE in (0, 1);
    its caption names
    the bunny's largest error source with numbers and gives the paper's Fig. 10
    attribution a verdict (regression lock on the outputs' content, not on numbers)."""
    rows = _csv(figures / "decomposition.csv")
    steps = {}
    for r in rows:
        steps.setdefault((r["scene"], r["preset"]), []).append(r["step"])
        assert 0 < float(r["relmse"]) < 1 and float(r["time_ms"]) > 0
    assert set(steps) == {("bunny", "paper"), ("bunny", "strong")}
    four = ["exact", "exact+kernel", "image-space surfaces", "estimated hits"]
    assert steps[("bunny", "paper")] == four
    assert steps[("bunny", "strong")] == [*four, "rim patches"]
    caption = (figures / "decomposition.txt").read_text()
    assert "bunny, paper preset: the largest error source is" in caption
    assert "Fig. 10: the differences come mainly" in caption
    assert "holds (paper preset)" in caption or "does not hold (paper preset)" in caption


@pytest.mark.slow
def test_fig08_is_the_water_animation_with_its_flicker(all_figures):
    """The Fig. 8 analogue is a sequence (``harness.studies.temporal``): both presets,
    6 frames each at 30 fps, per-frame relMSE and, for every frame pair, the flicker
    and its noise floor; the caption and the JSON name the steadier preset
    (regression lock on the outputs' content, not on numbers)."""
    rows = _csv(all_figures / "fig08.csv")
    for preset in ("paper", "strong"):
        mine = [r for r in rows if r["preset"] == preset]
        assert [int(r["frame"]) for r in mine] == list(range(6))
        assert mine[0]["flicker_caustic"] == ""
        assert all(float(r["flicker_caustic"]) > 0 and float(r["flicker_caustic_floor"]) > 0
                   for r in mine[1:])
        assert all(0 < float(r["relmse_caustic"]) < 1 for r in mine)
    data = json.loads((all_figures / "fig08.json").read_text())
    assert data["frames"] == 6 and data["fps"] == 30.0
    steadier = data["steadier"]
    flicker = {p: data["presets"][p]["flicker"]["caustic"]["value"] for p in ("paper", "strong")}
    assert flicker[steadier] == min(flicker.values())
    assert f"{steadier} flickers least" in (all_figures / "fig08.txt").read_text()


@pytest.mark.slow
def test_camera_figures_score_the_object_seen_through(all_figures):
    """Figs. 1, 6, 9 and 10 (the camera view the paper shows): both renderers draw the
    refractive object, so each camera figure scores the object region (the pixels inside
    its silhouette), per method. At the quick figures' 128² camera the glass sphere's
    silhouette holds about 930 pixels and the bunny's more (harness.compare.regions), so
    each region has over 300; every object metric is a finite number."""
    rows = _csv(all_figures / "fig09.csv") + _csv(all_figures / "fig01.csv")
    assert {r["scene"] for r in rows} == {"glass_sphere", "bunny", "colored_bunny"}
    methods = {r["method"] for r in _csv(all_figures / "fig01.csv")}
    assert methods == {"paper preset", "strong preset"}
    for row in rows:
        assert int(row["object_pixels"]) > 300, row
        assert all(math.isfinite(float(row[k])) for k in ("object_relmse", "object_ssim",
                                                          "object_flip")), row
    fig06 = _csv(all_figures / "fig06.csv")
    assert len(fig06) == 3 and all(math.isfinite(float(r["object_relmse"])) for r in fig06)
    fig10 = json.loads((all_figures / "fig10.json").read_text())
    assert [o["method"] for o in fig10["object"]] == ["paper preset", "strong preset"]
