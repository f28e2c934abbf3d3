"""The main picture of any linkage (``linkwright plot FILE``): the linkage at one input, its
coupler curves in every assembly mode, and the positions a designer looks for.

:func:`plot_mechanism` dispatches by family to the picture that draws it:
:func:`~linkwright.plot.planar.plot_curves` for the four-bar and slider-crank,
:func:`~linkwright.plot.generic.plot_linkage` for every other planar family, and
:func:`~linkwright.plot.sphere.plot_spherical_mechanism` (a 3-D view of the sphere beside a
Lambert azimuthal equal-area map of the curves) for spherical linkages. Each draws:

* the linkage at the chosen input, on the document's own assembly (the pose
  :func:`~linkwright.mechanisms.solve` gives);
* the traced curve for both assembly modes; for a six-bar every combination
  ``assembly`` × ``assembly2``, each named in the legend, the document's own drawn bold;
* **limit positions**, where the *input* cannot go on: a dyad's links fall in line, the dyad
  changes branch and the input turns back (only where the input rocks);
* **dead centres**, where the *output* is stationary: a four-bar's crank and coupler in line,
  a slider at either end of its stroke; driven from its output, the mechanism locks there.
  Only families with an output link have them: four-bar, slider-crank and spherical four-bar
  (:func:`linkwright.analysis.output_extremes`) and the six-bars (the stationary points of
  their last grounded link's angle along the circuit). The geared five-bar, the double slider
  and composed linkages have no output link, and none are marked;
* **transmission-angle extremes**: :func:`linkwright.analysis.transmission_extremes` for the
  four-bar, slider-crank and spherical four-bar; for the other families the least and
  greatest of :func:`linkwright.analysis.dyad_transmission_angles` along the circuit. Each is
  marked on the traced curve where it occurs.

The details (which link is a six-bar's output, how the extremes are refined) are in
:mod:`linkwright.plot.generic`.
"""

from __future__ import annotations

import itertools
import math
import numbers

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from linkwright.engine import InputArcs, input_arcs
from linkwright.mechanisms import FourBar, Mechanism, SliderCrank, input_range, solve
from linkwright.mechanisms.sixbar import NoConstructionPlan
from linkwright.plot.axes import check_axes
from linkwright.plot.generic import plot_linkage
from linkwright.plot.planar import deg_text, plot_curves
from linkwright.plot.sphere import plot_spherical_mechanism

__all__ = ["PlotError", "plot_mechanism"]

MINUS = "\N{MINUS SIGN}"
MIN_SAMPLES = 8


class PlotError(ValueError):
    """A linkage that cannot be drawn as asked (names the problem and, for an input where it
    does not assemble, the inputs where it does)."""


def range_text(arcs: InputArcs) -> str:
    """Where the linkage assembles on its own assembly (its :func:`input_range`), in degrees.

    >>> from linkwright.mechanisms import FourBar
    >>> range_text(input_range(FourBar(A0=[0, 0], B0=[4, 0], crank=3.5, coupler=5, rocker=1)))
    'θ in [−106.1°, −64.1°] and [64.1°, 106.1°]'
    """
    if bool(arcs.full):
        return "every input"
    spans = [
        f"[{deg_text(math.degrees(lo))}°, {deg_text(math.degrees(hi))}°]"
        for lo, hi in zip(arcs.lo, arcs.hi, strict=True)
        if math.isfinite(lo)
    ]
    return "θ in " + " and ".join(spans)


def _elsewhere(mechanism: Mechanism) -> str:
    """Which other assembly modes do assemble, if any (plans of at most two dyads)."""
    plan = mechanism.plan
    names = [d.branch for d in plan.dyads]
    if not names or len(names) > 2:
        return ""
    params = mechanism.params()
    own = tuple(1.0 if float(np.asarray(params[n])) > 0 else -1.0 for n in names)
    found = []
    for signs in itertools.product((1.0, -1.0), repeat=len(names)):
        if signs == own:
            continue
        trial = {**params, **{n: np.asarray(s) for n, s in zip(names, signs, strict=True)}}
        if not bool(input_arcs(plan, trial, points=mechanism.points).never):
            found.append(
                ", ".join(
                    f"{n} {'+1' if s > 0 else MINUS + '1'}"
                    for n, s in zip(names, signs, strict=True)
                )
            )
    mine = ", ".join(
        f"{n} {'+1' if s > 0 else MINUS + '1'}" for n, s in zip(names, own, strict=True)
    )
    if not found:
        return " in any assembly mode"
    return f" on its own assembly ({mine}); it does on " + "; ".join(found)


def plot_mechanism(
    mechanism: Mechanism,
    *,
    at: float | None = None,
    samples: int = 720,
    title: str | None = None,
    ax: Axes | None = None,
) -> Figure:
    """The main picture of a linkage of any family: the linkage at ``at`` and its curves.

    See the module docstring for what is drawn and what each mark means. The figure is built
    on an Agg canvas without pyplot; write it with :func:`linkwright.plot.save_figure`.

    Parameters
    ----------
    mechanism : Mechanism
        One linkage (batch shape ``()``) of any family, planar or spherical.
    at : float, optional
        Input angle (radians) of the pose drawn, on the document's own assembly. Default: the
        first sample of the first circuit (θ = 0 where the input turns fully, the lower limit
        where it rocks).
    samples : int
        Samples per circuit (at least 8).
    title : str, optional
        The figure's title (a document's ``title``).
    ax : matplotlib.axes.Axes, optional
        Draw into this flat axes (in a notebook's grid of subplots, say), the legend inside
        it; a spherical linkage then gets its sphere's orthographic view alone, without the
        map. A 3-D axes, or anything not an axes, is refused in one line.

    Returns
    -------
    matplotlib.figure.Figure
        One axes for a planar linkage; two for a spherical one (the sphere, then the map);
        ``ax``'s figure when ``ax`` is given (the top-level one, where ``ax`` is in a
        subfigure).

    Raises
    ------
    PlotError
        For a batch of mechanisms, a linkage with no construction plan (driven at a triad), a
        linkage that cannot be assembled at any input, an ``at`` that is not finite or where
        the linkage does not assemble (the message gives the inputs where it does), or too
        few samples.

    Examples
    --------
    >>> from linkwright.mechanisms import FourBar
    >>> crank_rocker = FourBar(A0=[0, 0], B0=[3.5, 0], crank=1, coupler=5, rocker=6.02,
    ...                        u=2.5, v=1.5)
    >>> fig = plot_mechanism(crank_rocker, samples=90, title="crank-rocker")
    >>> fig.get_suptitle()
    'Four-bar — crank-rocker'

    A rocker-input four-bar assembles only over two arcs of its input:

    >>> rocking = FourBar(A0=[0, 0], B0=[4, 0], crank=3.5, coupler=5, rocker=1, u=2, v=1)
    >>> try:
    ...     plot_mechanism(rocking, at=0.0)
    ... except PlotError as exc:
    ...     print(exc)
    at θ = 0.0° the linkage does not assemble on its own assembly: the coupler and rocker
    cannot fold that short (dyad B: |A B0| = 0.5 < |coupler - rocker| = 4); it does for
    θ in [−106.1°, −64.1°] and [64.1°, 106.1°]

    Into axes of one's own, side by side:

    >>> from linkwright.plot import new_figure
    >>> fig = new_figure((10, 4))
    >>> left, right = fig.subplots(1, 2)
    >>> plot_mechanism(crank_rocker, samples=90, ax=left) is fig
    True
    >>> plot_mechanism(rocking, samples=90, ax=right).axes[1].get_title().splitlines()[0]
    'Four-bar'

    A linkage that closes nowhere cannot be drawn:

    >>> plot_mechanism(FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3))
    Traceback (most recent call last):
    ...
    linkwright.plot.view.PlotError: the linkage cannot be assembled at any input in any assembly
    mode
    """
    if not isinstance(mechanism, Mechanism):
        raise PlotError(f"mechanism: expected a linkwright Mechanism, got {mechanism!r}")
    check_axes(ax)
    if (
        isinstance(samples, bool)
        or not isinstance(samples, numbers.Integral)
        or samples < MIN_SAMPLES
    ):
        raise PlotError(f"samples: must be an integer ≥ {MIN_SAMPLES}, got {samples!r}")
    if mechanism.batch_shape != ():
        raise PlotError(
            f"draw one linkage at a time; this mechanism has batch shape {mechanism.batch_shape}"
        )
    try:
        never = bool(input_range(mechanism).never)
    except NoConstructionPlan as exc:
        raise PlotError(str(exc)) from None
    if never:
        raise PlotError("the linkage cannot be assembled at any input" + _elsewhere(mechanism))
    if at is not None:
        if isinstance(at, bool) or not isinstance(at, numbers.Real) or not math.isfinite(at):
            raise PlotError(f"at: must be a finite input angle in radians, got {at!r}")
        at = float(at)
        if not bool(solve(mechanism, [at], order=0).valid[0]):
            why = mechanism.plan.unassembled(mechanism.params(), at, points=mechanism.points)
            raise PlotError(
                f"at θ = {deg_text(math.degrees(at))}° the linkage does not assemble on its own "
                + ("assembly" if why is None else f"assembly: {why}")
                + f"; it does for {range_text(input_range(mechanism))}"
            )
    samples = int(samples)
    if mechanism.space == "sphere":
        return plot_spherical_mechanism(mechanism, samples=samples, at=at, title=title, ax=ax)
    if isinstance(mechanism, FourBar | SliderCrank):
        return plot_curves(mechanism, samples=samples, theta=at, title=title, ax=ax)
    return plot_linkage(mechanism, samples=samples, at=at, title=title, ax=ax)
