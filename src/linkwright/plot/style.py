"""The house style of every picture: one palette, numbers and angles written for captions
(true minus signs, no "−0.0"), figures with their own Agg canvas, and saving them.

Figures are :class:`matplotlib.figure.Figure` objects with an Agg canvas attached
(:func:`new_figure`), never pyplot's: no global state, so plotting works headless and from
several threads at once. :func:`save_figure` writes PNG, SVG or PDF by the file's extension.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import TypedDict

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.typing import CapStyleType, ColorType, LineStyleType
from numpy.typing import NDArray

from linkwright.mechanisms import Mechanism
from linkwright.mechanisms.registry import family_of

__all__ = [
    "COUPLER_FACE",
    "CURVE_COLOR",
    "GAMMA_COLOR",
    "GROUND_COLOR",
    "LIMIT_COLOR",
    "LINK_COLOR",
    "MINUS",
    "MIXED_NOTE_COLOR",
    "OTHER_COLOR",
    "LineKw",
    "TextKw",
    "deg_text",
    "family_name",
    "new_figure",
    "num_text",
    "save_figure",
    "sign_label",
]

Array = NDArray[np.float64]


MINUS = "\N{MINUS SIGN}"


# Colours and styles (one palette for every picture).
CURVE_COLOR = "tab:blue"


OTHER_COLOR = "tab:orange"


LIMIT_COLOR = "tab:red"


GAMMA_COLOR = "tab:purple"


LINK_COLOR = "0.15"


COUPLER_FACE = "#9ecae1"


GROUND_COLOR = "0.35"


MIXED_NOTE_COLOR = "0.2"


class LineKw(TypedDict, total=False):
    """Keyword arguments of :meth:`matplotlib.axes.Axes.plot` that a picture's styles set,
    kept as a TypedDict so that a style passed as ``**style`` is checked key by key."""

    color: ColorType
    lw: float
    ls: LineStyleType
    zorder: float
    marker: str
    ms: float
    mfc: ColorType
    mec: ColorType
    mew: float
    alpha: float
    solid_capstyle: CapStyleType


class TextKw(TypedDict, total=False):
    """Keyword arguments of :meth:`matplotlib.axes.Axes.text` that a picture's styles set."""

    fontsize: float
    color: ColorType
    clip_on: bool
    zorder: float


def new_figure(figsize: tuple[float, float]) -> Figure:
    """A figure with its own Agg canvas: no pyplot, no global backend switch."""
    fig = Figure(figsize=figsize, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def family_name(mechanism: Mechanism) -> str:
    return family_of(mechanism).display


def sign_label(sign: float) -> str:
    return f"assembly {'+1' if sign > 0 else MINUS + '1'}"


def num_text(x: float) -> str:
    """A number for a caption: up to 4 significant digits, no trailing zeros, true minus."""
    text = f"{x:.4g}"
    return text.replace("-", MINUS)


def deg_text(x: float) -> str:
    """An angle in degrees for a caption: one decimal, true minus (never "−0.0")."""
    return f"{round(float(x), 1) + 0.0:.1f}".replace("-", MINUS)


def save_figure(fig: Figure, path: str | os.PathLike[str], *, dpi: float | None = None) -> Path:
    """Write ``fig`` as PNG (150 dpi unless told), SVG or PDF, chosen by the file extension.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure to write.
    path : str or os.PathLike
        Destination ending in ``.png``, ``.svg`` or ``.pdf``; missing parent folders are
        created.
    dpi : float, optional
        Resolution of a PNG (default 150); ignored by the vector formats.

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    ValueError
        For any other extension, or a ``dpi`` that is not a positive number.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from linkwright.mechanisms import FourBar
    >>> from linkwright.plot import plot_curves
    >>> crank_rocker = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5)
    >>> fig = plot_curves(crank_rocker, samples=60)
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> save_figure(fig, folder / "deep" / "crank-rocker.svg").read_text()[:5]
    '<?xml'
    >>> save_figure(fig, folder / "crank-rocker.gif")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: ...
    """
    if dpi is not None and not (isinstance(dpi, int | float) and math.isfinite(dpi) and dpi > 0):
        raise ValueError(f"save_figure: dpi must be a positive number, got {dpi!r}")
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".png", ".svg", ".pdf"):
        raise ValueError(
            f"save_figure writes .png, .svg or .pdf, not {path.suffix or 'no extension'!r}"
        )
    path.parent.mkdir(parents=True, exist_ok=True)
    if suffix == ".png":
        fig.savefig(path, format="png", dpi=150 if dpi is None else dpi)
    else:
        fig.savefig(path, format=suffix[1:])
    return path
