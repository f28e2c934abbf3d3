"""The slot through which values of the lower layers show themselves in Jupyter.

A mechanism (:mod:`linkwright.mechanisms`) or a motion (:mod:`linkwright.engine`) may not import
the plots, which sit above them; they call :func:`repr_svg`, and the package's root, which sits
above every layer, fills :data:`renderer` with a function that imports the plots on first use.
This module imports nothing of linkwright.
"""

from __future__ import annotations

from collections.abc import Callable

__all__ = ["renderer", "repr_svg"]

renderer: Callable[[object], str | None] | None = None
"""Draws a value as an SVG document (set by ``linkwright/__init__.py``)."""


def repr_svg(value: object) -> str | None:
    """The SVG picture of ``value``, or ``None`` (no picture: Jupyter then shows its repr).

    >>> repr_svg(object()) is None or isinstance(repr_svg(object()), str)
    True
    """
    return None if renderer is None else renderer(value)
