"""The ``ax=`` of the plot verbs: drawing into a caller's matplotlib axes, checked up front.

Every picture of linkwright is drawn on flat (2-D) axes: a spherical linkage too, as an
orthographic view of the sphere, so a 3-D axes is refused with a one-line error rather than
drawn wrongly.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from matplotlib.axes import Axes
from matplotlib.figure import Figure

__all__ = ["AxesError", "check_axes", "check_axes_list", "figure_of"]


class AxesError(ValueError):
    """An ``ax=`` that a picture cannot be drawn into (names what was given and what is
    needed)."""


def check_axes(ax: Any, name: str = "ax") -> Axes | None:
    """``ax`` if it is a flat matplotlib :class:`~matplotlib.axes.Axes` (or ``None``).

    Parameters
    ----------
    ax : matplotlib.axes.Axes or None
        The axes to draw into; ``None`` asks for a new figure.
    name : str
        The argument's name, for the message.

    Returns
    -------
    matplotlib.axes.Axes or None
        ``ax`` itself.

    Examples
    --------
    >>> from linkwright.plot import new_figure
    >>> fig = new_figure((4, 3))
    >>> check_axes(fig.add_subplot()) is fig.axes[0]
    True
    >>> check_axes(fig.add_subplot(projection="3d"))
    Traceback (most recent call last):
    ...
    linkwright.plot.axes.AxesError: ax: linkwright draws on flat axes (a sphere as an \
orthographic view), got a 3-D Axes; make it with fig.add_subplot() without projection='3d'
    >>> check_axes("left")
    Traceback (most recent call last):
    ...
    linkwright.plot.axes.AxesError: ax: expected a matplotlib Axes, got 'left'
    """
    if ax is None:
        return None
    if not isinstance(ax, Axes):
        raise AxesError(f"{name}: expected a matplotlib Axes, got {_short(ax)}")
    if getattr(ax, "name", "rectilinear") == "3d":
        raise AxesError(
            f"{name}: linkwright draws on flat axes (a sphere as an orthographic view), got a "
            "3-D Axes; make it with fig.add_subplot() without projection='3d'"
        )
    return ax


def check_axes_list(axes: Any, count: int, name: str = "ax") -> list[Axes] | None:
    """``axes`` as a list of ``count`` flat axes (one per panel), or ``None``.

    Examples
    --------
    >>> from linkwright.plot import new_figure
    >>> fig = new_figure((4, 6))
    >>> len(check_axes_list(fig.subplots(3, 1), 3))
    3
    >>> check_axes_list(fig.axes[:2], 3)
    Traceback (most recent call last):
    ...
    linkwright.plot.axes.AxesError: ax: this diagram has 3 panels, so it needs 3 axes, got 2
    """
    if axes is None:
        return None
    if isinstance(axes, Axes):
        axes = [axes]
    if not isinstance(axes, Sequence) and not hasattr(axes, "ravel"):
        raise AxesError(f"{name}: expected a matplotlib Axes or a list of them, got {_short(axes)}")
    found = list(axes.ravel()) if hasattr(axes, "ravel") else list(axes)
    if len(found) != count:
        raise AxesError(
            f"{name}: this diagram has {count} panel{'s' * (count != 1)}, so it needs {count} "
            f"axes, got {len(found)}"
        )
    return [check_axes(a, name) for a in found]  # type: ignore[misc]


def figure_of(ax: Axes) -> Figure:
    """The figure a plot verb drawing into ``ax`` returns: the top-level one, also where ``ax``
    is in a subfigure (a :class:`~matplotlib.figure.SubFigure` cannot be saved on its own).

    Examples
    --------
    >>> from linkwright.plot import new_figure
    >>> fig = new_figure((4, 3))
    >>> figure_of(fig.subfigures(1, 2)[1].add_subplot()) is fig
    True
    """
    fig = ax.get_figure(root=True)
    # The stubs allow None, but an Axes is made in a figure and matplotlib refuses to move it.
    assert fig is not None
    return fig


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."
