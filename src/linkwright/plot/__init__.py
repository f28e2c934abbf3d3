"""Pictures of linkages: the linkage, its coupler curves and its motion diagrams (matplotlib).

Figures are built on :class:`matplotlib.figure.Figure` with an Agg canvas, never through pyplot,
so plotting works headless and from several threads.
"""

from linkwright.plot.planar import (
    draw_linkage,
    new_figure,
    plot_curves,
    plot_diagrams,
    save_figure,
)

__all__ = ["draw_linkage", "new_figure", "plot_curves", "plot_diagrams", "save_figure"]
