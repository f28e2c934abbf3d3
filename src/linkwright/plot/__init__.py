"""Pictures of linkages: the linkage, its coupler curves, its motion diagrams and animations
(matplotlib).

Figures are built on :class:`matplotlib.figure.Figure` with an Agg canvas, never through pyplot,
so plotting works headless and from several threads.
"""

from linkwright.plot.animation import AnimationError, animate
from linkwright.plot.axes import AxesError
from linkwright.plot.diagrams import KINDS, DiagramError, plot_diagram
from linkwright.plot.planar import (
    draw_linkage,
    new_figure,
    plot_curves,
    plot_diagrams,
    save_figure,
)
from linkwright.plot.view import PlotError, plot_mechanism

__all__ = [
    "KINDS",
    "AnimationError",
    "AxesError",
    "DiagramError",
    "PlotError",
    "animate",
    "draw_linkage",
    "new_figure",
    "plot_curves",
    "plot_diagram",
    "plot_diagrams",
    "plot_mechanism",
    "save_figure",
]
