"""How mechanisms and motions show themselves in Jupyter: an SVG picture, bounded in cost.

A mechanism is drawn as :func:`~linkwright.plot.plot_mechanism` draws it (the linkage at its
first pose, its coupler curves in every assembly mode, the marks), at :data:`SAMPLES` samples a
circuit on a small figure; a motion as the paths of its joints. What cannot be drawn (a linkage
that assembles nowhere, a batch) is a short line of text in the picture's place, never an
exception: a notebook cell that shows a value must not fail.
"""

from __future__ import annotations

import html
import io
from typing import Any

import numpy as np
from matplotlib import rc_context

from linkwright.engine import Motion
from linkwright.mechanisms import Mechanism
from linkwright.plot.planar import new_figure
from linkwright.plot.view import plot_mechanism

__all__ = ["MAX_PATH_SAMPLES", "SAMPLES", "svg"]

SAMPLES = 180
"""Samples a circuit in a mechanism's picture: its cost stays a fraction of a second."""

MAX_PATH_SAMPLES = 2000
"""A motion's paths are thinned to at most this many samples each (the SVG's size)."""


def svg(value: object) -> str | None:
    """The SVG document that shows ``value`` in a notebook, or ``None`` for other values.

    Parameters
    ----------
    value : object
        A :class:`~linkwright.mechanisms.Mechanism` or a :class:`~linkwright.engine.Motion`.

    Returns
    -------
    str or None
        An SVG document; a mechanism that cannot be drawn gives one with a line of text saying
        why.

    Examples
    --------
    >>> from linkwright.mechanisms import FourBar, circuit
    >>> crank_rocker = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5, u=2, v=1)
    >>> svg(crank_rocker).lstrip().startswith("<?xml")
    True
    >>> "<path" in svg(circuit(crank_rocker, 90))
    True

    A linkage that cannot assemble shows a short text:

    >>> print(svg(FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3)))
    <svg xmlns="http://www.w3.org/2000/svg" width="640" height="28"><text x="6" y="19" \
font-family="sans-serif" font-size="13">FourBar: the linkage cannot be assembled at any input \
in any assembly mode</text></svg>
    >>> svg("not a linkage") is None
    True
    """
    if isinstance(value, Mechanism):
        return _mechanism_svg(value)
    if isinstance(value, Motion):
        return _motion_svg(value)
    return None


def _text_svg(text: str) -> str:
    line = " ".join(text.split())
    line = line if len(line) <= 160 else line[:157] + "..."
    return (
        '<svg xmlns="http://www.w3.org/2000/svg" width="640" height="28">'
        f'<text x="6" y="19" font-family="sans-serif" font-size="13">{html.escape(line)}</text>'
        "</svg>"
    )


def _figure_svg(fig: Any) -> str:
    out = io.StringIO()
    # Text as text (not glyph outlines) and no date: a smaller picture, the same every time.
    with rc_context({"svg.fonttype": "none", "svg.hashsalt": "linkwright"}):
        fig.savefig(out, format="svg", metadata={"Date": None})
    return out.getvalue()


def _mechanism_svg(mechanism: Mechanism) -> str:
    name = type(mechanism).__name__
    if mechanism.batch_shape != ():
        return _text_svg(
            f"{name}: a batch of shape {mechanism.batch_shape}; index one linkage to draw it"
        )
    fig = new_figure((6.0, 5.0))
    try:
        plot_mechanism(mechanism, samples=SAMPLES, ax=fig.add_subplot())
    except (ValueError, LookupError) as exc:  # PlotError and the like: what cannot be drawn
        return _text_svg(f"{name}: {str(exc).splitlines()[0]}")
    return _figure_svg(fig)


def _motion_svg(motion: Motion) -> str:
    if motion.input.ndim != 1:
        return _text_svg(
            f"Motion of a batch: input shape {motion.input.shape}; index one to draw it"
        )
    valid = np.asarray(motion.valid, bool)
    if not valid.any():
        return _text_svg("Motion: the linkage is assembled at none of its samples")
    step = max(1, -(-motion.input.size // MAX_PATH_SAMPLES))
    fig = new_figure((5.0, 4.2))
    ax = fig.add_subplot()
    first = int(np.argmax(valid))
    sphere = False
    for name, p in motion.positions.items():
        p = np.asarray(p, float)
        sphere = p.shape[-1] == 3
        ax.plot(p[::step, 0], p[::step, 1], lw=1.2, label=name)
        ax.plot(*p[first, :2], "o", color="black", ms=3)
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, lw=0.4, alpha=0.5)
    ax.legend(loc="best", fontsize=7, ncols=2)
    count = f"{motion.input.size} samples, {int(valid.sum())} assembled"
    view = "; unit sphere seen from +z" if sphere else ""
    ax.set_title(f"joint paths ({count}{view}); dots: first assembled sample", fontsize=8)
    return _figure_svg(fig)
