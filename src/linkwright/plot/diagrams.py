"""Motion diagrams of any linkage: angles, velocities, accelerations and paper 003's kinematic
coefficients, against the input angle over the whole circuit the machine runs.

One function, :func:`plot_diagram`, draws one *kind* of diagram for every family the engine
builds, planar or spherical:

``angles``
    The output (a four-bar's φ3, a slider's position s, a six-bar's last link) and the
    transmission angle of every dyad, with 90° marked as ideal; a spherical four-bar adds paper
    003's two pressure-angle components at its balanced hinge-radius ratio μ.
``velocity``, ``acceleration``
    The first and second derivatives by the input angle θ of each traced point's position
    (planar: the x and y components and the magnitude; on the sphere the magnitude of the
    unit vector's derivative, radians of arc per radian of input) and of the output.
``coefficients``
    Paper 003's dimensionless coefficients Kω, Kε and Kp of the output over the cycle (four-bars
    and the slider-crank), or the kinematic analogues ψ′ = dψ/dθ and ψ″ = d²ψ/dθ² of the output
    link (six-bars) or of every moving link (families without one output).

Where the input only rocks, the circuit runs up its arc and back on the other branch of the
dyad at its limit: each leg is drawn as its own line (solid up, dashed back), the limit
positions are marked, and derivatives, which grow without bound there, are drawn on an axis
clipped as :func:`linkwright.plot.planar.plot_diagrams` clips its speed (the panel says so).

Everything is derived from the circuit's analytic derivatives (the engine differentiates the
constraint equations; nothing here differences numerically), and the figure is built without
pyplot, as in :mod:`linkwright.plot.planar`.

References
----------
Paper 003: R. P. Dzhavakhyan, A. G. Makhsudyan, V. A. Arakelyan, comparison of planar and
spherical four-hinge mechanisms, eqs. (3)–(4) (Kω, Kε, Kp) and the text after eq. (7) (the
double crank and δ); its pressure angle of the spherical four-bar and the balanced μ
(:mod:`linkwright.analysis.spherical`).

This module is the public face: what is plotted lives in
:mod:`~linkwright.plot.diagram_quantities`, the circuit's legs and the drawing of a panel in
:mod:`~linkwright.plot.diagram_panels`, and each kind's panels in
:mod:`~linkwright.plot.diagram_kinds`.
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from numpy.typing import NDArray

from linkwright.engine.circuits import NoPeriod
from linkwright.mechanisms import Mechanism
from linkwright.mechanisms.registry import family_of
from linkwright.mechanisms.sixbar import NoConstructionPlan
from linkwright.plot.axes import check_axes_list, figure_of
from linkwright.plot.diagram_kinds import PALETTE as PALETTE
from linkwright.plot.diagram_kinds import angle_panels, coefficient_panels, derivative_panels
from linkwright.plot.diagram_panels import (
    BACK_STYLE,
    NOTE_COLOR,
    UP_STYLE,
    Panel,
    Run,
    circuit_legs,
    clip_limit,
    draw_panel,
    mark_limits,
)
from linkwright.plot.diagram_panels import IDEAL_COLOR as IDEAL_COLOR
from linkwright.plot.diagram_quantities import Outputs, outputs_of
from linkwright.plot.planar import TracedCircuit, deg_text, new_figure, traced_circuits
from linkwright.plot.style import LIMIT_COLOR

__all__ = ["KINDS", "DiagramError", "diagram_series", "plot_diagram"]

Array = NDArray[np.float64]
KINDS: tuple[str, ...] = ("angles", "velocity", "acceleration", "coefficients")


class DiagramError(ValueError):
    """A motion diagram cannot be drawn: an unknown kind, a bad sample count, a batch, a linkage
    that assembles at no input, or one that has no construction plan to trace."""


# --------------------------------------------------------------------------------------------
# The public function
# --------------------------------------------------------------------------------------------


def _family_name(mechanism: Mechanism) -> str:
    if mechanism.family == "linkage":
        return "Spherical linkage" if mechanism.space == "sphere" else "Planar linkage"
    return family_of(mechanism).display


HEADLINES = {
    "angles": "output and transmission angles",
    "velocity": "velocities (first derivatives by the input angle)",
    "acceleration": "accelerations (second derivatives by the input angle)",
    "coefficients": "kinematic coefficients (paper 003)",
}


def _trace(mechanism: Mechanism, samples: int) -> list[TracedCircuit]:
    name = type(mechanism).__name__
    try:
        circuits = traced_circuits(mechanism, samples, order=2)
    except NoConstructionPlan as exc:
        raise DiagramError(
            f"{name} has no construction plan to trace, so its motion diagrams are not "
            f"supported: {exc}"
        ) from None
    except NoPeriod as exc:
        raise DiagramError(f"{name}: its circuit never closes, so it has no cycle: {exc}") from None
    if not circuits:
        why = (
            "its triad's ternary link cannot be held by its three links"
            if mechanism.plan.triads
            else "some dyad's links cannot reach each other"
        )
        raise DiagramError(
            f"{name} cannot be assembled at any input angle: {why}, so there is no motion to draw"
        )
    return circuits


def _panels(
    mechanism: Mechanism, kind: str, run: Run, outs: Outputs
) -> tuple[list[Panel], str, bool]:
    """The panels of one kind of diagram, the details line, and whether they are paper 003's."""
    paper = False
    if kind == "angles":
        panels, details = angle_panels(mechanism, run, outs)
    elif kind == "coefficients":
        panels, details, paper = coefficient_panels(mechanism, run, outs)
    else:
        panels, details = derivative_panels(mechanism, run, outs, 1 if kind == "velocity" else 2)
    if not panels:
        raise DiagramError(
            f"{type(mechanism).__name__} has nothing to draw as {kind}: no dyad and no link whose "
            "angle is defined (on the sphere, a link with no ground pivot has no single angle)"
        )
    return panels, details, paper


def _check_request(mechanism: Mechanism, kinds: tuple[str, ...], samples: object) -> None:
    for kind in kinds:
        if not isinstance(kind, str) or kind not in KINDS:
            raise DiagramError(f"kind must be one of {', '.join(KINDS)}; got {kind!r}")
    if not isinstance(mechanism, Mechanism):
        raise DiagramError(f"diagrams are drawn of a Mechanism, got {type(mechanism).__name__}")
    if isinstance(samples, bool) or not isinstance(samples, int | np.integer) or samples < 8:
        raise DiagramError(f"samples must be an integer of at least 8, got {samples!r}")
    batch = mechanism.batch_shape
    if batch != ():
        raise DiagramError(f"draw one linkage at a time; this mechanism has batch shape {batch}")


def diagram_series(
    mechanism: Mechanism, kinds: tuple[str, ...] = KINDS, *, samples: int = 720
) -> dict[str, object]:
    """The numbers behind :func:`plot_diagram`, for a page that draws the diagrams itself.

    The circuit is traced once and every kind in ``kinds`` is read off it.

    Returns
    -------
    dict
        ``"x"``: the input angle in degrees per circuit, on the closed circuit's samples (the
        first sample again at the end); ``"limits"``: the input's limit positions (degrees);
        ``"full"``: whether the input turns fully; ``"describe"``: what the output is;
        ``"kinds"``: for each kind, ``{"details": str, "panels": [{"ylabel", "series":
        [{"label", "values" (per circuit, like x), "color"}], "ideal", "note", "clip"}]}``,
        where ``"clip"`` is the |value| beyond which the page should clip (derivatives grow
        without bound next to limit positions) or None.

    Raises
    ------
    DiagramError
        As :func:`plot_diagram`.

    Examples
    --------
    >>> from linkwright.mechanisms import FourBar
    >>> rocker = FourBar(A0=[0, 0], B0=[1, 0], crank=3.5, coupler=5, rocker=1)
    >>> d = diagram_series(rocker, ("angles",), samples=16)
    >>> d["full"], [round(v, 3) for v in d["limits"]]
    (False, [113.132, 246.868])
    >>> [p["series"][0]["label"] for p in d["kinds"]["angles"]["panels"]]
    ['φ3', 'γ']
    """
    _check_request(mechanism, tuple(kinds), samples)
    run = circuit_legs(mechanism, _trace(mechanism, int(samples)))
    outs = outputs_of(mechanism, run.circuits[0].motion)
    out: dict[str, object] = {}
    for kind in kinds:
        panels, details, _ = _panels(mechanism, kind, run, outs)
        out[kind] = {
            "details": details,
            "panels": [
                {
                    "ylabel": p.ylabel,
                    "series": [
                        {"label": s.label, "values": s.values, "color": s.color} for s in p.series
                    ],
                    "ideal": p.ideal,
                    "note": p.note,
                    "clip": clip_limit(p, run) if p.clip and not run.full else None,
                }
                for p in panels
            ],
        }
    return {
        "x": run.x,
        "limits": run.limits,
        "full": run.full,
        "describe": outs.describe,
        "kinds": out,
    }


def plot_diagram(
    mechanism: Mechanism,
    kind: str,
    *,
    samples: int = 720,
    title: str | None = None,
    ax: Axes | Sequence[Axes] | None = None,
) -> Figure:
    """One kind of motion diagram of a linkage, against the input angle over its whole circuit.

    Kinds (:data:`KINDS`) and their panels, top to bottom, all against the input angle θ in
    degrees (a full turn spans 360°; where the input only rocks, each leg of the circuit is a
    line of its own, solid up and dashed back, its ends at the input's limit positions, which
    are marked and labelled):

    ``"angles"``
        The output: a four-bar's φ3 (angle of B − B0 from the frame line A0→B0, paper 003's
        convention), a spherical four-bar's φ3 (about +OB0 from the frame circle beyond B0), a
        slider-crank's slider position s, a six-bar's last link (planar: its angle from +x;
        spherical: its angle about its ground pivot); for families without one output (geared
        five-bar, composed linkages) every moving link's angle (links of one rigid body once),
        for the double slider its sliders' travels. Then the transmission angle of every dyad
        (90° ideal) and, for a spherical four-bar, paper 003's normal and tangential pressure
        angles at its balanced hinge-radius ratio μ (:func:`~linkwright.analysis.balanced_mu`;
        0° ideal). Sampled extremes are written on each panel.
    ``"velocity"``
        |dP/dθ| of each traced point (plane: length per radian of input; sphere: radians of
        arc per radian), in the plane also dx/dθ and dy/dθ, then the output's velocity ratio
        ω_out/ω_in = dφ/dθ (or each link's).
    ``"acceleration"``
        The same for d²P/dθ² (on the sphere the magnitude of the unit vector's second
        derivative, sphere radii per rad²) and ε_out/ω_in² = d²φ/dθ² (constant input speed).
    ``"coefficients"``
        Four-bar, slider-crank and spherical four-bar whose input turns fully: paper 003's
        Kω, Kε and Kp = Kω·Kε over the cycle (eq. 3: Kω = φ3′·φΨ/Ψ, Kε = φ3″·φΨ²/Ψ for a
        rocking output; Kω = φ3′, Kε = 2π·φ3″ for a double crank; the stroke for Ψ of a
        slider), each with its exact maximum (:func:`~linkwright.analysis.coefficients`) and a
        right axis reading the plain analogue φ3′, φ3″. Otherwise the analogues ψ′ = dψ/dθ and
        ψ″ = d²ψ/dθ² of the output link, or of each moving link where there is no single
        output (the panel says which).

    Where derivatives grow without bound next to limit positions, their axis is clipped as
    :func:`linkwright.plot.planar.plot_diagrams` clips its speed, and the panel says so.

    Parameters
    ----------
    mechanism : Mechanism
        One (unbatched) linkage of any family, planar or spherical.
    kind : str
        One of :data:`KINDS`.
    samples : int, optional
        Samples per circuit (at least 8).
    title : str, optional
        The mechanism's name, put after the family name in the figure title.
    ax : matplotlib.axes.Axes or sequence of them, optional
        Draw into these flat axes, one per panel (a wrong count is refused in one line, giving
        the count); the titles and legend then go on the axes, not the figure.

    Returns
    -------
    matplotlib.figure.Figure
        Its panels, ``fig.axes``, share the input axis (the given axes' figure when ``ax`` is
        given). Each plotted quantity's first line is
        labelled with its name (the traced joint, ``"φ3"``, ``"s"``, ``"γ"``, ``"γ at D"``,
        ``"Kω"``, ``"Kε"``, ``"Kp"``, a link such as ``"D0–D"``); further legs of a rocking
        circuit are labelled ``"_<name> | <leg>"`` (kept out of the legend).

    Raises
    ------
    DiagramError
        For an unknown ``kind``, fewer than 8 samples, a batch of mechanisms, a linkage that
        cannot be assembled at any input, one with nothing of that kind to plot (a composed
        linkage of cranks alone), or one driven where it has no construction plan
        (``Stephenson3(input="output")``, ``SphericalStephenson3(input="FG")``: their
        configurations come from the all-configurations solver, whose branches are not traced
        into a circuit).

    Examples
    --------
    >>> from linkwright.mechanisms import FourBar
    >>> crank_rocker = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5, u=2, v=1)
    >>> fig = plot_diagram(crank_rocker, "coefficients", samples=90, title="crank-rocker")
    >>> fig.get_suptitle().splitlines()[0]
    'Four-bar — crank-rocker'
    >>> [ax.get_lines()[0].get_label() for ax in fig.axes]
    ['Kω', 'Kε', 'Kp']

    A linkage that cannot be assembled has no diagram:

    >>> never = FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3)
    >>> plot_diagram(never, "angles")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    linkwright.plot.diagrams.DiagramError: FourBar cannot be assembled at any input angle: ...
    """
    _check_request(mechanism, (kind,), samples)
    run = circuit_legs(mechanism, _trace(mechanism, int(samples)))
    outs = outputs_of(mechanism, run.circuits[0].motion)
    panels, details, paper = _panels(mechanism, kind, run, outs)
    given = check_axes_list(ax, len(panels))
    axes: list[Axes]
    if given is None:
        fig = new_figure((8.5, 1.6 + 2.55 * len(panels)))
        axes = list(np.atleast_1d(fig.subplots(len(panels), 1, sharex=True)))
    else:
        # The top-level figure, also for axes in a subfigure (which cannot be saved alone).
        fig, axes = figure_of(given[0]), given
    for panel_ax, panel in zip(axes, panels, strict=True):
        draw_panel(panel_ax, panel, run, unbounded=not run.full)
    mark_limits(axes, run)

    axes[-1].set_xlabel("input angle θ (°)")
    lines = [outs.describe, details]
    if run.full:
        start = float(run.x[0][0])
        axes[-1].set_xlim(start, start + run.period_deg)
        step = 45.0 if run.period_deg <= 360.0 else 90.0
        axes[-1].set_xticks(start + np.arange(0.0, run.period_deg + 1e-9, step))
    else:
        arcs = ", ".join(
            f"[{deg_text(float(np.nanmin(x)))}°, {deg_text(float(np.nanmax(x)))}°]" for x in run.x
        )
        # A triad has no branch sign: at its limits two of its configurations meet.
        turn = "two configurations meet" if mechanism.plan.triads else "a dyad changes branch"
        lines.append(f"input rocks over {arcs}: at each limit {turn}")
        handles = [
            Line2D([], [], color="0.2", ls=UP_STYLE, lw=1.6, label="up (θ increasing)"),
            Line2D([], [], color="0.2", ls=BACK_STYLE, lw=1.6, label="back (θ decreasing)"),
            Line2D([], [], color=LIMIT_COLOR, ls=":", lw=0.8, label="input limit position"),
        ]
        if given is None:
            fig.legend(
                handles=handles, loc="outside lower center", ncols=3, fontsize=8.5, frameon=False
            )
        else:
            axes[-1].legend(handles=handles, loc="best", fontsize=7)
    if outs.skipped:
        lines.append(
            f"links with no ground pivot ({', '.join(outs.skipped)}) have no single angle on "
            "the sphere: not shown"
        )
    subtitle = "\n".join(textwrap.fill(line, 110) for line in lines if line)
    axes[0].set_title(subtitle, fontsize=8.5, color=NOTE_COLOR, pad=14 if run.limits else 6)
    family = _family_name(mechanism)
    same = title is not None and title.strip().casefold() == family.casefold()
    head = family + (f" — {title}" if title and not same else "")
    what = HEADLINES[kind]
    if kind == "coefficients" and not paper:
        what = "kinematic analogues (derivatives of the output by the input angle)"
        if not outs.single:
            what = "kinematic analogues of the moving links (derivatives by the input angle)"
    if kind == "angles" and not outs.single:
        what = "link positions and transmission angles"
    if given is None:
        fig.suptitle(f"{head}\n{what} against the input angle", fontsize=12)
    else:
        axes[0].set_title(f"{head}: {what}\n{subtitle}", fontsize=8.5, color=NOTE_COLOR)
    return fig
