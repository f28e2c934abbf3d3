"""Plot verbs drawing into axes of a subfigure return the top-level figure, which can be saved.

A :class:`~matplotlib.figure.SubFigure` has no ``savefig``: the verbs used to return
``ax.figure`` (the subfigure) although they promise a :class:`~matplotlib.figure.Figure`, so
``save_figure(plot_mechanism(m, ax=sub_ax), path)`` failed with an AttributeError. The saved
PNG's size is checked against the figure's size in inches times the dpi.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import matplotlib.image as mpimg
import numpy as np
import pytest
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from linkwright.mechanisms import FourBar, SphericalFourBar, circuit
from linkwright.plot import new_figure, plot_curves, plot_mechanism, save_figure
from linkwright.plot.generic import plot_linkage, plot_speed
from linkwright.plot.sphere import (
    plot_spherical_curves,
    plot_spherical_linkage,
    plot_spherical_mechanism,
)

PLANAR = FourBar(A0=[0, 0], B0=[3.5, 0], crank=1, coupler=5, rocker=6.02, u=2.5, v=1.5)
SPHERICAL = SphericalFourBar(*np.radians([40, 20, 45, 35, 50, 130]))
N = 24


def _sphere_path(ax: Axes) -> Figure:
    points = circuit(SPHERICAL, N, order=0).positions["P"]
    return plot_spherical_curves([("P", points)], ax=ax)


VERBS: dict[str, Callable[[Axes], Figure]] = {
    "plot_mechanism planar": lambda ax: plot_mechanism(PLANAR, samples=N, ax=ax),
    "plot_mechanism spherical": lambda ax: plot_mechanism(SPHERICAL, samples=N, ax=ax),
    "plot_curves": lambda ax: plot_curves(PLANAR, samples=N, ax=ax),
    "plot_linkage": lambda ax: plot_linkage(PLANAR, samples=N, ax=ax),
    "plot_speed": lambda ax: plot_speed(PLANAR, samples=N, ax=ax),
    "plot_spherical_linkage": lambda ax: plot_spherical_linkage(SPHERICAL, samples=N, ax=ax),
    "plot_spherical_mechanism": lambda ax: plot_spherical_mechanism(SPHERICAL, samples=N, ax=ax),
    "plot_spherical_curves": _sphere_path,
}


@pytest.mark.parametrize("verb", VERBS, ids=list(VERBS))
def test_a_verb_drawing_in_a_subfigure_returns_the_figure_to_save(
    verb: str, tmp_path: Path
) -> None:
    fig = new_figure((6.0, 3.0))
    _, right = fig.subfigures(1, 2)
    out = VERBS[verb](right.add_subplot())
    assert out is fig
    png = save_figure(out, tmp_path / "both.png", dpi=50)
    height, width = mpimg.imread(png).shape[:2]
    assert (width, height) == (300, 150)
