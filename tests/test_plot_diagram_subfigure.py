"""A motion diagram drawn into axes of a subfigure returns the top-level figure, which saves.

``plot_diagram(..., ax=...)`` returned ``axes[0].figure``: for axes in a subfigure that is the
:class:`~matplotlib.figure.SubFigure`, which has no ``savefig``, although the verb promises a
:class:`~matplotlib.figure.Figure` (mypy found it when the module was typed). The saved PNG's
size is checked against the figure's size in inches times the dpi, and the panels against the
diagram's own labels.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.image as mpimg

from linkwright.mechanisms import FourBar
from linkwright.plot import new_figure, plot_diagram, save_figure

ROCKER = FourBar(A0=[0, 0], B0=[1, 0], crank=3.5, coupler=5, rocker=1)


def test_a_diagram_drawn_in_a_subfigure_returns_the_figure_to_save(tmp_path: Path) -> None:
    fig = new_figure((6.0, 4.0))
    _, right = fig.subfigures(1, 2)
    axes = list(right.subplots(2, 1))  # the "angles" diagram of a four-bar: φ3, then γ
    out = plot_diagram(ROCKER, "angles", samples=16, ax=axes)
    assert out is fig
    assert [ax.get_lines()[0].get_label() for ax in axes] == ["φ3", "γ"]
    png = save_figure(out, tmp_path / "diagram.png", dpi=50)
    height, width = mpimg.imread(png).shape[:2]
    assert (width, height) == (300, 200)
