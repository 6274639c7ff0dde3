"""Analogues of the paper's figures, each written with the data it was drawn from."""

from harness.figures.bunny import figure_10, figure_13a
from harness.figures.camera import figure_01, figure_09
from harness.figures.common import FigureContext, FigureResult
from harness.figures.decomposition import figure_decomposition
from harness.figures.ring import figure_12
from harness.figures.sphere import figure_06, figure_07, figure_11, figure_13b
from harness.figures.water import figure_05, figure_08

#: Figure name to the function that draws it, in the paper's order (then the
#: harness's own figures).
FIGURES = {
    "fig01": figure_01,
    "fig05": figure_05,
    "fig06": figure_06,
    "fig07": figure_07,
    "fig08": figure_08,
    "fig09": figure_09,
    "fig10": figure_10,
    "fig11": figure_11,
    "fig12": figure_12,
    "fig13a": figure_13a,
    "fig13b": figure_13b,
    # Not a paper figure: where each paper scene's error comes from (both presets).
    "decomposition": figure_decomposition,
}

__all__ = ["FIGURES", "FigureContext", "FigureResult"]
