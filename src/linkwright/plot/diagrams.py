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
"""

from __future__ import annotations

import itertools
import math
import textwrap
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from numpy.typing import NDArray

from linkwright.analysis import (
    balanced_mu,
    coefficients,
    dyad_transmission_angles,
    output_angle,
    output_rates,
    pressure_angles,
    transmission_angle,
)
from linkwright.engine import DyadRRP, DyadRRR, Fixed, Motion, SphereDyad
from linkwright.engine.circuits import NoPeriod
from linkwright.geometry import plane, sphere
from linkwright.mechanisms import (
    DoubleSlider,
    FourBar,
    Mechanism,
    SliderCrank,
    SphericalFourBar,
    SphericalSixBar,
    SphericalStephenson3,
    input_range,
)
from linkwright.mechanisms.registry import family_of
from linkwright.mechanisms.sixbar import NoConstructionPlan, SixBar
from linkwright.plot.axes import check_axes_list
from linkwright.plot.planar import (
    CURVE_COLOR,
    GAMMA_COLOR,
    LIMIT_COLOR,
    MINUS,
    OTHER_COLOR,
    TracedCircuit,
    deg_text,
    new_figure,
    num_text,
    speed_limit,
    traced_circuits,
    unwrap_finite,
)

__all__ = ["KINDS", "DiagramError", "diagram_series", "plot_diagram"]

Array = NDArray[np.float64]

KINDS: tuple[str, ...] = ("angles", "velocity", "acceleration", "coefficients")


# One colour per plotted quantity (a traced point, an output, a link); the line style tells
# the legs of a rocking circuit apart.
PALETTE = (
    CURVE_COLOR,
    OTHER_COLOR,
    "tab:green",
    GAMMA_COLOR,
    "tab:brown",
    "tab:pink",
    "tab:olive",
    "tab:cyan",
    "tab:gray",
    "tab:red",
)
UP_STYLE = "-"
BACK_STYLE = (0, (5, 2.5))
IDEAL_COLOR = "0.45"
NOTE_COLOR = "0.3"


class DiagramError(ValueError):
    """A motion diagram cannot be drawn: an unknown kind, a bad sample count, a batch, a linkage
    that assembles at no input, or one that has no construction plan to trace."""


# --------------------------------------------------------------------------------------------
# What is plotted: outputs and links as functions of a motion
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Quantity:
    """A scalar of the linkage along a motion, with its first two derivatives by θ.

    ``unit`` is ``"angle"`` (radians, drawn in degrees) or ``"length"``.
    """

    label: str
    unit: str
    value: Callable[[Motion], Array]
    rates: Callable[[Motion], tuple[Array, Array]]


def _link_angle(origin: str, joint: str, label: str) -> _Quantity:
    """Angle of joint − origin from +x; ψ′ = (r × r′)/|r|², ψ″ from differentiating that."""

    def value(m: Motion) -> Array:
        r = m.positions[joint] - m.positions[origin]
        return np.arctan2(r[..., 1], r[..., 0])

    def rates(m: Motion) -> tuple[Array, Array]:
        assert m.velocities is not None and m.accelerations is not None
        r = m.positions[joint] - m.positions[origin]
        r1 = m.velocities[joint] - m.velocities[origin]
        r2 = m.accelerations[joint] - m.accelerations[origin]
        q = plane.dot(r, r)
        w = plane.cross(r, r1) / q
        return w, plane.cross(r, r2) / q - 2.0 * plane.dot(r, r1) * w / q

    return _Quantity(label, "angle", value, rates)


def _pivot_angle(pivot: str, ref: str, joint: str, label: str) -> _Quantity:
    """On the sphere: the angle of ``joint`` about the fixed axis ``pivot``, right-handed, from
    the great circle pivot→ref. The joint turns on a circle about the pivot, so
    dJ/dψ = pivot × J and, dotting J′ and J″ with it, ψ′ = (p × J)·J′/|p × J|² and
    ψ″ = (p × J)·J″/|p × J|² (as the spherical four-bar's output rates)."""

    def value(m: Motion) -> Array:
        j = m.positions[joint]
        return sphere.angle_at(
            np.broadcast_to(m.positions[pivot], j.shape),
            np.broadcast_to(m.positions[ref], j.shape),
            j,
        )

    def rates(m: Motion) -> tuple[Array, Array]:
        assert m.velocities is not None and m.accelerations is not None
        j = m.positions[joint]
        w = sphere.cross(np.broadcast_to(m.positions[pivot], j.shape), j)
        s2 = sphere.dot(w, w)
        return sphere.dot(w, m.velocities[joint]) / s2, sphere.dot(w, m.accelerations[joint]) / s2

    return _Quantity(label, "angle", value, rates)


def _travel(line_point: str, direction: Array, joint: str, label: str) -> _Quantity:
    """Position of a slider pin along its guide, measured from the guide's point."""

    def along(d: dict[str, Array]) -> Array:
        return plane.dot(d[joint] - d[line_point], direction)

    def rates(m: Motion) -> tuple[Array, Array]:
        assert m.velocities is not None and m.accelerations is not None
        return along(m.velocities), along(m.accelerations)

    return _Quantity(label, "length", lambda m: along(m.positions), rates)


@dataclass
class _Outputs:
    """The quantities a family's diagrams show, and how to name them."""

    quantities: list[_Quantity]
    single: bool
    """One output link (four-bars, slider-crank, six-bars) or several moving links."""
    describe: str
    """A line for the subtitle: what the quantities are, measured from what."""
    symbol: str = "ψ"
    skipped: list[str] = field(default_factory=list)


def _fixed(mechanism: Mechanism, name: str) -> bool:
    return isinstance(mechanism.plan.step(name), Fixed)


def _guide_direction(mechanism: Mechanism, dyad: DyadRRP) -> Array:
    angle = dyad.line_angle
    value = mechanism.params()[angle] if isinstance(angle, str) else angle
    return plane.unit_direction(np.asarray(value, dtype=float))


def _dyad_links(mechanism: Mechanism) -> tuple[list[tuple[_Quantity, tuple[str, ...]]], list[str]]:
    """Every link a dyad hangs on, as (quantity, the link's joints); and the links left out.

    Planar links by their angle from +x, slider pins by their travel; on the sphere only links
    on a ground pivot have one angle (a floating spherical body's attitude is three angles).
    """
    out: list[tuple[_Quantity, tuple[str, ...]]] = []
    skipped: list[str] = []
    fixed = list(mechanism.plan.ground)
    for dyad in mechanism.plan.dyads:
        j = dyad.name
        if isinstance(dyad, DyadRRR):
            for p in (dyad.p1, dyad.p2):
                out.append((_link_angle(p, j, f"{p}–{j}"), (p, j)))
        elif isinstance(dyad, DyadRRP):
            out.append((_link_angle(dyad.p1, j, f"{dyad.p1}–{j}"), (dyad.p1, j)))
            direction = _guide_direction(mechanism, dyad)
            out.append((_travel(dyad.line_point, direction, j, f"slider {j}"), (j,)))
        elif isinstance(dyad, SphereDyad):
            for p in (dyad.p1, dyad.p2):
                ref = next((f for f in fixed if f != p), None)
                if _fixed(mechanism, p) and ref is not None:
                    out.append((_pivot_angle(p, ref, j, f"{j} about {p}"), (p, j)))
                else:
                    skipped.append(f"{p}–{j}")
    # A triad hangs on its three binary links, each from an anchor to one of its joints.
    for triad in mechanism.plan.triads:
        for p, j in triad.links()[:3]:
            ref = next((f for f in fixed if f != p), None)
            if mechanism.space == "plane":
                out.append((_link_angle(p, j, f"{p}–{j}"), (p, j)))
            elif _fixed(mechanism, p) and ref is not None:
                out.append((_pivot_angle(p, ref, j, f"{j} about {p}"), (p, j)))
            else:
                skipped.append(f"{p}–{j}")
    return out, skipped


def _outputs(mechanism: Mechanism, reference: Motion) -> _Outputs:
    """The output of a family that has one, else every moving link; ``reference`` (a circuit
    with derivatives) groups links that turn as one body."""
    if isinstance(mechanism, FourBar):
        q = _Quantity(
            "φ3",
            "angle",
            lambda m: output_angle(mechanism, m),
            lambda m: output_rates(mechanism, m),
        )
        return _Outputs([q], True, "φ3: angle of B − B0 from the frame line A0→B0", "φ3")
    if isinstance(mechanism, SliderCrank):
        q = _Quantity(
            "s", "length", mechanism.slider_position, lambda m: output_rates(mechanism, m)
        )
        return _Outputs([q], True, "s: slider position along its line from the foot of A0", "s")
    if isinstance(mechanism, SphericalFourBar):
        q = _Quantity(
            "φ3",
            "angle",
            mechanism.output_angle,
            lambda m: output_rates(mechanism, m),
        )
        return _Outputs(
            [q], True, "φ3: angle of B about +OB0 from the frame circle beyond B0", "φ3"
        )
    if isinstance(mechanism, DoubleSlider):
        r_dir = plane.unit_direction(np.asarray(mechanism.alpha + mechanism.beta, dtype=float))
        q_dir = plane.unit_direction(np.asarray(mechanism.beta, dtype=float))
        return _Outputs(
            [_travel("M", r_dir, "R", "slider R"), _travel("M", q_dir, "Q", "slider Q")],
            False,
            "the coupler turns with the input (its angle is θ + 180°) and the sliders only "
            "translate: their travels along the guides from M are shown",
            "t",
        )
    if isinstance(mechanism, SixBar | SphericalSixBar | SphericalStephenson3) and (
        mechanism.plan.dyads
    ):
        # The last link: the one from the second dyad's second pivot (E or D0 in the plane,
        # the ground pivot E0 or G on the sphere) to its joint.
        dyad = mechanism.plan.dyads[-1]
        j, p = dyad.name, dyad.p2
        if mechanism.space == "sphere":
            ref = next(s.name for s in mechanism.plan.steps if isinstance(s, Fixed) and s.name != p)
            q = _pivot_angle(p, ref, j, f"{j} about {p}")
            what = f"ψ: angle of {j} about +O{p} from the great circle {p}→{ref} (last link {p}{j})"
        else:
            q = _link_angle(p, j, f"{p}–{j}")
            what = f"ψ: angle of the last link, {j} − {p}, from +x"
        return _Outputs([q], True, what, "ψ")
    links, skipped = _dyad_links(mechanism)
    grouped = _group_bodies(links, reference)
    if mechanism.space == "sphere":
        what = "each link on a ground pivot: its angle about that pivot (right-handed)"
    else:
        what = "each dyad's links: angle from +x (links of one rigid body shown once)"
    return _Outputs(grouped, False, what, "ψ", skipped)


def _group_bodies(
    links: list[tuple[_Quantity, tuple[str, ...]]], reference: Motion
) -> list[_Quantity]:
    """Links that turn as one rigid body (pinned together, equal ψ′ at every sample) shown
    once, named by the body's joints; sliders are kept as they are."""
    groups: list[tuple[_Quantity, list[str], Array]] = []
    for q, joints in links:
        if q.unit != "angle":
            groups.append((q, list(joints), np.array([])))
            continue
        w = q.rates(reference)[0]
        scale = 1.0 + float(np.nanmax(np.abs(w))) if np.isfinite(w).any() else 1.0
        for g in groups:
            other = g[2]
            # Two links pinned at a common joint that always turn alike are one rigid body
            # (a triangle); parallel links elsewhere (a parallelogram) stay apart.
            shared = any(x in g[1] for x in joints)
            if (
                shared
                and other.shape == w.shape
                and np.allclose(w, other, rtol=0.0, atol=1e-9 * scale, equal_nan=True)
            ):
                g[1].extend(x for x in joints if x not in g[1])
                break
        else:
            groups.append((q, list(joints), w))
    out = []
    for q, joints, _ in groups:
        if q.unit == "angle" and len(joints) > 2:
            q = _Quantity(f"{q.label} (body {'–'.join(joints)})", q.unit, q.value, q.rates)
        out.append(q)
    return out


# --------------------------------------------------------------------------------------------
# The circuit: legs against the input angle
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Leg:
    circuit: int
    index: NDArray[np.int64]  # into the closed circuit's samples
    name: str
    style: object


@dataclass(frozen=True)
class _Run:
    """The traced circuits, their input axis (degrees) and how they split into legs."""

    circuits: list[TracedCircuit]
    x: list[Array]
    legs: list[_Leg]
    limits: list[float]
    full: bool
    period_deg: float

    def closed(self, values: list[Array]) -> list[Array]:
        return [v[c.closed()] for v, c in zip(values, self.circuits, strict=True)]


def _legs(mechanism: Mechanism, circuits: list[TracedCircuit]) -> _Run:
    arcs = input_range(mechanism)
    period = math.degrees(float(np.max(np.asarray(arcs.period))))
    xs: list[Array] = []
    legs: list[_Leg] = []
    limits: list[float] = []
    for k, c in enumerate(circuits):
        m = c.motion
        closed = c.closed()
        x = np.degrees(unwrap_finite(m.input[closed].astype(float)))
        suffix = "" if k == 0 else f", circuit {k + 1}"
        if c.full:
            x[-1] = x[0] + period
            xs.append(x)
            legs.append(_Leg(k, np.arange(c.n + 1), "full turn" + suffix, UP_STYLE))
            continue
        xs.append(x)
        # Legs end where the input turns back: at limit positions (exact samples of the circuit).
        step = np.sign(np.diff(x))
        turns = [i for i in range(1, len(step)) if step[i] != step[i - 1] and step[i] != 0]
        bounds = [0, *turns, c.n]
        changing = [name for name, b in m.labels.items() if np.unique(np.asarray(b)).size > 1]
        count = {"up": 0, "back": 0}
        for a, b in itertools.pairwise(bounds):
            word = "up" if x[b] > x[a] else "back"
            count[word] += 1
            label = word if count[word] == 1 else f"{word} {count[word]}"
            mid = closed[(a + b) // 2]
            signs = ", ".join(
                f"{name} {'+1' if float(m.labels[name][mid]) > 0 else MINUS + '1'}"
                for name in changing
            )
            if signs:
                label += f" (branch {signs})"
            legs.append(
                _Leg(
                    k, np.arange(a, b + 1), label + suffix, UP_STYLE if word == "up" else BACK_STYLE
                )
            )
        for i in bounds[:-1]:
            if not any(abs(x[i] - v) < 1e-9 for v in limits):
                limits.append(float(x[i]))
    full = all(c.full for c in circuits)
    return _Run(circuits, xs, legs, sorted(limits), full, period)


# --------------------------------------------------------------------------------------------
# Panels
# --------------------------------------------------------------------------------------------


@dataclass
class _Series:
    label: str
    values: list[Array]  # per circuit, on the closed circuit's samples
    color: str


@dataclass
class _Panel:
    ylabel: str
    series: list[_Series]
    note: str = ""
    ideal: float | None = None
    ideal_label: str = ""
    clip: str | None = None  # "magnitude" or "signed": derivatives that blow up at limits
    secondary: tuple[float, str] | None = None  # (scale, label): right axis = left / scale
    extra: list[str] = field(default_factory=list)


def _minmax(values: list[Array]) -> tuple[float, float] | None:
    v = np.concatenate([np.ravel(a) for a in values])
    v = v[np.isfinite(v)]
    if v.size == 0:
        return None
    return float(v.min()), float(v.max())


def _clip_limit(panel: _Panel, run: _Run) -> float | None:
    """An upper limit for |values| that clips their growth next to the input's limits.

    The rule of :func:`linkwright.plot.planar.speed_limit`, applied to the samples away from
    the limits (the middle 80 % of each leg) plus the overall peak: the circuit's samples
    crowd towards the limits, where second derivatives grow like the distance to the limit to
    the power −3/2, so a percentile of all samples would measure the blow-up, not the curve.
    """
    inner: list[Array] = []
    peak = 0.0
    for s in panel.series:
        for leg in run.legs:
            x = run.x[leg.circuit][leg.index]
            y = np.abs(s.values[leg.circuit][leg.index])
            if not np.isfinite(x).any():  # a leg with no assembled sample has no extent
                continue
            lo, hi = float(np.nanmin(x)), float(np.nanmax(x))
            margin = 0.1 * (hi - lo)
            inner.append(y[(x - lo >= margin) & (hi - x >= margin)])
            if np.isfinite(y).any():
                peak = max(peak, float(np.nanmax(y)))
    return speed_limit([*inner, np.array([peak])])


def _draw_panel(ax: Axes, panel: _Panel, run: _Run, *, unbounded: bool) -> None:
    for s in panel.series:
        first = True
        for leg in run.legs:
            x = run.x[leg.circuit][leg.index]
            y = s.values[leg.circuit][leg.index]
            label = s.label if first else f"_{s.label} | {leg.name}"
            ax.plot(x, y, color=s.color, ls=leg.style, lw=1.6, label=label)
            first = False
    span = _minmax([v for s in panel.series for v in s.values])
    # A zero line only where the quantity changes sign: else it would squash the curves.
    crosses = span is not None and span[0] < 0.0 < span[1]
    if panel.ideal is not None and (panel.ideal_label != "_zero" or crosses):
        ax.axhline(panel.ideal, color=IDEAL_COLOR, lw=0.9, ls=":", label=panel.ideal_label)
    notes = [panel.note] if panel.note else []
    if panel.clip and unbounded:
        top = _clip_limit(panel, run)
        if top is not None and span is not None:
            lo, hi = span
            if panel.clip == "magnitude":
                ax.set_ylim(0.0, top)
            else:
                pad = 0.05 * top
                ax.set_ylim(max(lo, -top) - pad, min(hi, top) + pad)
            notes.append("axis clipped: grows without bound at the input limits")
        elif panel.clip == "magnitude":
            ax.set_ylim(bottom=0.0)
    elif panel.clip == "magnitude":
        ax.set_ylim(bottom=0.0)
    notes += panel.extra
    if panel.secondary is not None:
        scale, label = panel.secondary
        right = ax.secondary_yaxis("right", functions=(lambda y: y / scale, lambda y: y * scale))
        right.set_ylabel(label, color=NOTE_COLOR)
        right.tick_params(colors=NOTE_COLOR)
    ax.set_ylabel(panel.ylabel)
    ax.grid(True, lw=0.4, alpha=0.5)
    entries = len(panel.series) + (panel.ideal_label[:1] not in ("", "_"))
    # A few entries fit inside the panel; more would hide curves, so they go beside it.
    note_lines = "\n".join(notes).count("\n") + 1 if notes else 0
    inside = entries + note_lines <= 5 or panel.secondary is not None
    ax.legend(
        loc="best" if inside else "upper left",
        bbox_to_anchor=None if inside else (1.01, 1.0),
        fontsize=8,
        title="\n".join(notes) if notes else None,
        title_fontsize=8,
        framealpha=0.85,
        alignment="left",
    )


def _mark_limits(axes: list[Axes], run: _Run) -> None:
    for at in run.limits:
        for ax in axes:
            ax.axvline(at, color=LIMIT_COLOR, lw=0.8, ls=":", alpha=0.8, label="_limit")
        axes[0].annotate(
            f"limit {deg_text(at)}°",
            xy=(at, 1.0),
            xycoords=("data", "axes fraction"),
            xytext=(0, 3),
            textcoords="offset points",
            fontsize=8,
            ha="center",
            va="bottom",
            color=LIMIT_COLOR,
        )


def _continuous_degrees(angle: Array) -> Array:
    """An angle along a closed circuit, in degrees, without jumps: unwrapped (a turning link
    ends 360° on), then shifted by whole turns so that its range is centred in (−180°, 180°]."""
    out = np.degrees(unwrap_finite(angle))
    span = _minmax([out])
    if span is not None:
        mid = 0.5 * (span[0] + span[1])
        out = out - 360.0 * np.round(mid / 360.0)
    return out


def _colors(n: int) -> list[str]:
    return [PALETTE[i % len(PALETTE)] for i in range(n)]


def _deg_range(values: list[Array], name: str) -> str:
    span = _minmax(values)
    if span is None:
        return f"{name}: not assembled"
    if span[1] - span[0] < 0.05:
        return f"{name} constant, {deg_text(span[0])}°"
    return f"{name} from {deg_text(span[0])}° to {deg_text(span[1])}°"


# --------------------------------------------------------------------------------------------
# The kinds
# --------------------------------------------------------------------------------------------


def _angle_panels(mechanism: Mechanism, run: _Run, outs: _Outputs) -> tuple[list[_Panel], str]:
    motions = [c.motion for c in run.circuits]
    panels: list[_Panel] = []
    details = ""
    by_unit: dict[str, list[_Quantity]] = {}
    for q in outs.quantities:
        by_unit.setdefault(q.unit, []).append(q)
    colors = iter(_colors(len(outs.quantities)))
    for unit, quantities in by_unit.items():
        series = []
        for q in quantities:
            values = run.closed([q.value(m) for m in motions])
            if unit == "angle":
                values = [_continuous_degrees(v) for v in values]
            series.append(_Series(q.label, values, next(colors)))
        note = ""
        if len(series) == 1:
            span = _minmax(series[0].values)
            sym = outs.symbol
            if span is not None and unit == "angle":
                turned = abs(span[1] - span[0]) >= 359.0
                note = (
                    f"{sym} turns fully"
                    if turned
                    else f"{sym} from {deg_text(span[0])}° to {deg_text(span[1])}° "
                    f"(swing {deg_text(span[1] - span[0])}°)"
                )
            elif span is not None:
                note = (
                    f"{sym} from {num_text(span[0])} to {num_text(span[1])} "
                    f"(stroke {num_text(span[1] - span[0])})"
                )
        if unit == "angle":
            ylabel = f"output angle {outs.symbol} (°)" if outs.single else "link angle ψ (°)"
        else:
            ylabel = "slider position s (length)" if outs.single else "slider travel t (length)"
        panels.append(_Panel(ylabel, series, note=note))

    if isinstance(mechanism, FourBar | SliderCrank | SphericalFourBar):
        gammas = {"γ": [np.degrees(transmission_angle(mechanism, m)) for m in motions]}
    else:
        per = [dyad_transmission_angles(mechanism, m) for m in motions]
        gammas = {f"γ at {name}": [np.degrees(p[name]) for p in per] for name in per[0]}
    if gammas:
        colors_g = iter([GAMMA_COLOR] if len(gammas) == 1 else _colors(len(gammas)))
        series = [_Series(name, run.closed(v), next(colors_g)) for name, v in gammas.items()]
        note = "sampled " + "\n".join(_deg_range(s.values, s.label) for s in series)
        panels.append(
            _Panel(
                "transmission angle γ (°)",
                series,
                note=note,
                ideal=90.0,
                ideal_label="90° (ideal)",
            )
        )
        if isinstance(mechanism, FourBar | SliderCrank | SphericalFourBar):
            at = (
                "at B" if not isinstance(mechanism, SliderCrank) else "between rod and guide normal"
            )
            details = f"γ: transmission angle {at}"
        else:
            details = "γ: transmission angle of each dyad, at its joint"
    else:
        details = "no dyad, so no transmission angle"

    if isinstance(mechanism, SphericalFourBar):
        mu = float(balanced_mu(mechanism))
        if math.isfinite(mu):
            nu = [pressure_angles(mechanism, m, mu) for m in motions]
            series = [
                _Series(
                    "ν_n (normal)", run.closed([np.degrees(n["normal"]) for n in nu]), "tab:brown"
                ),
                _Series(
                    "ν_τ (tangential)",
                    run.closed([np.degrees(n["tangential"]) for n in nu]),
                    "tab:cyan",
                ),
            ]
            note = "sampled " + "\n".join(_deg_range(s.values, s.label) for s in series)
            panels.append(
                _Panel(
                    "pressure angle ν (°)", series, note=note, ideal=0.0, ideal_label="0° (ideal)"
                )
            )
            details += (
                f"; ν_n, ν_τ: paper 003's pressure-angle components at μ = OB/OA = {num_text(mu)} "
                "(balanced μ, analysis.balanced_mu)"
            )
        else:
            details += "; no positive μ = OB/OA balances ν_τ (paper 003): pressure angles omitted"
    return panels, details


def _point_panels(mechanism: Mechanism, run: _Run, order: int) -> tuple[list[_Panel], list[str]]:
    """|d^k P/dθ^k| and, in the plane, its x and y components, for every traced joint."""
    traced = mechanism.plan.traced
    colors = _colors(len(traced))
    motions = [c.motion for c in run.circuits]

    def deriv(m: Motion, joint: str) -> Array:
        d = m.velocities if order == 1 else m.accelerations
        assert d is not None
        return d[joint]

    mark = "′" if order == 1 else "″"
    sym = "dP/dθ" if order == 1 else "d²P/dθ²"
    sphere_space = mechanism.space == "sphere"
    if sphere_space:
        unit = "rad of arc/rad" if order == 1 else "sphere radii/rad²"
    else:
        unit = "length/rad" if order == 1 else "length/rad²"
    mags = [
        _Series(j, run.closed([np.linalg.norm(deriv(m, j), axis=-1) for m in motions]), c)
        for j, c in zip(traced, colors, strict=True)
    ]
    panels = [_Panel(f"|{sym}| ({unit})", mags, clip="magnitude")]
    if not sphere_space:
        for axis, name in ((0, "x"), (1, "y")):
            comp = [
                _Series(j, run.closed([deriv(m, j)[..., axis] for m in motions]), c)
                for j, c in zip(traced, colors, strict=True)
            ]
            panels.append(
                _Panel(
                    f"{name}{mark} = d{'' if order == 1 else '²'}{name}/dθ"
                    f"{'' if order == 1 else '²'} ({unit})",
                    comp,
                    clip="signed",
                )
            )
    what = [
        f"traced point{'s' if len(traced) > 1 else ''} {', '.join(traced)}: "
        + (
            f"|{sym}| of the unit vector "
            + ("(its arc rate)" if order == 1 else "(sphere radii per rad², normal part included)")
            if sphere_space
            else f"{sym}, components and magnitude"
        )
    ]
    return panels, what


def _rate_panels(
    run: _Run, outs: _Outputs, order: int, colors: list[str], *, analogue: bool = False
) -> list[_Panel]:
    """The outputs' first (order 1) or second (order 2) derivative by θ, one panel per unit:
    labelled as velocity/acceleration ratios, or (``analogue``) as the kinematic analogues."""
    motions = [c.motion for c in run.circuits]
    panels = []
    by_unit: dict[str, list[tuple[_Quantity, str]]] = {}
    for q, c in zip(outs.quantities, colors, strict=True):
        by_unit.setdefault(q.unit, []).append((q, c))
    who = "out" if outs.single else "link"
    for unit, quantities in by_unit.items():
        series = [
            _Series(q.label, run.closed([q.rates(m)[order - 1] for m in motions]), c)
            for q, c in quantities
        ]
        angle = unit == "angle"
        sym = outs.symbol if outs.single else ("ψ" if angle else "t")
        per = ("rad" if angle else "length") + ("/rad" if order == 1 else "/rad²")
        if analogue:
            d = f"d{sym}/dθ" if order == 1 else f"d²{sym}/dθ²"
            ylabel = f"{sym}{'′' if order == 1 else '″'} = {d} ({per})"
        elif order == 1:
            ratio = f"ω_{who}/ω_in" if angle else f"v_{who}/ω_in"
            ylabel = f"{ratio} = {sym}′ ({per})"
        else:
            ratio = f"ε_{who}/ω_in²" if angle else f"a_{who}/ω_in²"
            ylabel = f"{ratio} = {sym}″ ({per})"
        panels.append(_Panel(ylabel, series, clip="signed", ideal=0.0, ideal_label="_zero"))
    return panels


def _derivative_panels(
    mechanism: Mechanism, run: _Run, outs: _Outputs, order: int
) -> tuple[list[_Panel], str]:
    panels, what = _point_panels(mechanism, run, order)
    panels += _rate_panels(run, outs, order, _colors(len(outs.quantities) + 2)[2:])
    if outs.single:
        what.append(
            f"output {outs.symbol}'s {'velocity' if order == 1 else 'acceleration'} ratio "
            f"({'ω' if order == 1 else 'ε'}_out/ω_in{'' if order == 1 else '²'} at constant "
            "input speed)"
        )
    else:
        what.append(f"{'first' if order == 1 else 'second'} derivative of each link's position")
    return panels, "; ".join(what)


def _paper003(mechanism: Mechanism) -> dict[str, float] | None:
    """Paper 003's normalisation of the output's analogues, where it applies (else None).

    Crank-rocker (input turns, output rocks through Ψ while the crank turns φΨ): Kω = φ3′·φΨ/Ψ,
    Kε = φ3″·φΨ²/Ψ (eq. 3); double crank: Kω = φ3′, Kε = 2π·φ3″. The slider-crank takes its
    stroke for Ψ. The scales and exact maxima are :func:`linkwright.analysis.coefficients`'.
    """
    if not isinstance(mechanism, FourBar | SliderCrank | SphericalFourBar):
        return None
    # A double crank has no φΨ: its time ratio divides by zero inside, harmlessly (NaN).
    with np.errstate(divide="ignore", invalid="ignore"):
        co = {k: float(v) for k, v in coefficients(mechanism).items()}
    if not math.isfinite(co["K_omega"]):
        return None
    if math.isfinite(co["phi_psi"]):
        phi, psi = co["phi_psi"], co["psi"]
        co["scale1"], co["scale2"] = phi / psi, phi**2 / psi
        co["double"] = 0.0
    else:
        co["scale1"], co["scale2"] = 1.0, 2.0 * math.pi
        co["double"] = 1.0
    return co


def _coefficient_panels(
    mechanism: Mechanism, run: _Run, outs: _Outputs
) -> tuple[list[_Panel], str, bool]:
    """Paper 003's Kω, Kε, Kp where they apply (third item True), else the analogues."""
    motions = [c.motion for c in run.circuits]
    co = _paper003(mechanism)
    if co is None:
        panels = []
        colors = _colors(len(outs.quantities))
        for order in (1, 2):
            panels += _rate_panels(run, outs, order, colors, analogue=True)
        if outs.single:
            why = (
                "the input does not turn fully, so paper 003's Kω, Kε (defined over a crank's "
                "turn) do not apply: "
                if isinstance(mechanism, FourBar | SliderCrank | SphericalFourBar)
                else ""
            )
            what = f"{why}kinematic analogues {outs.symbol}′ = d{outs.symbol}/dθ and " + (
                f"{outs.symbol}″ = d²{outs.symbol}/dθ² of the output"
            )
        elif isinstance(mechanism, DoubleSlider):
            what = "no output link: the sliders' travel rates t′ = dt/dθ and t″ = d²t/dθ²"
        else:
            what = (
                "no single output link: kinematic analogues ψ′ = dψ/dθ and ψ″ = d²ψ/dθ² of each "
                "moving link relative to the input"
            )
        return panels, what, False

    q = outs.quantities[0]
    slider = isinstance(mechanism, SliderCrank)
    sym = "s" if slider else "φ3"
    unit1 = "length/rad" if slider else "rad/rad"
    unit2 = "length/rad²" if slider else "rad/rad²"
    w = run.closed([q.rates(m)[0] for m in motions])
    e = run.closed([q.rates(m)[1] for m in motions])
    s1, s2 = co["scale1"], co["scale2"]
    k_w = [s1 * a for a in w]
    k_e = [s2 * a for a in e]
    k_p = [a * b for a, b in zip(k_w, k_e, strict=True)]
    double = bool(co["double"])
    if double:
        defs = ("Kω = φ3′", "Kε = 2π·φ3″", "Kp = Kω·Kε")
    else:
        big = "stroke" if slider else "Ψ"
        defs = (f"Kω = {sym}′·φΨ/{big}", f"Kε = {sym}″·φΨ²/{big}", "Kp = Kω·Kε")
    maxima = ("K_omega", "K_epsilon", "K_p")
    panels = []
    for values, d, key, color, raw, scale in (
        (k_w, defs[0], maxima[0], PALETTE[0], f"{sym}′ ({unit1})", s1),
        (k_e, defs[1], maxima[1], PALETTE[1], f"{sym}″ ({unit2})", s2),
        (k_p, defs[2], maxima[2], PALETTE[2], f"{sym}′·{sym}″ ({unit1} · {unit2})", s1 * s2),
    ):
        name = d.split(" = ")[0]
        top = co[key]
        extra = [f"max |{name}| = {num_text(top)} (exact, paper 003 eq. 4)"]
        if key == "K_omega" and double:
            extra.append(f"δ = max φ3′ − min φ3′ = {num_text(co['delta'])}")
        panel = _Panel(
            f"{d} (dimensionless)",
            [_Series(name, values, color)],
            ideal=0.0,
            ideal_label="_zero",
            extra=extra,
            secondary=None if scale == 1.0 else (scale, raw),
        )
        panels.append(panel)
    if double:
        what = (
            "paper 003's coefficients of the output (double crank: Kω = φ3′, Kε = 2π·φ3″, "
            "eqs. 3–4 and after eq. 7)"
        )
    else:
        span = "stroke" if slider else "Ψ"
        psi = num_text(co["psi"]) if slider else f"{deg_text(math.degrees(co['psi']))}°"
        what = (
            f"paper 003's coefficients of the output (eq. 3), φΨ = "
            f"{deg_text(math.degrees(co['phi_psi']))}°, {span} = {psi}; right axes: the analogues"
        )
    return panels, what, True


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
    mechanism: Mechanism, kind: str, run: _Run, outs: _Outputs
) -> tuple[list[_Panel], str, bool]:
    """The panels of one kind of diagram, the details line, and whether they are paper 003's."""
    paper = False
    if kind == "angles":
        panels, details = _angle_panels(mechanism, run, outs)
    elif kind == "coefficients":
        panels, details, paper = _coefficient_panels(mechanism, run, outs)
    else:
        panels, details = _derivative_panels(mechanism, run, outs, 1 if kind == "velocity" else 2)
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
    run = _legs(mechanism, _trace(mechanism, int(samples)))
    outs = _outputs(mechanism, run.circuits[0].motion)
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
                    "clip": _clip_limit(p, run) if p.clip and not run.full else None,
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
    run = _legs(mechanism, _trace(mechanism, int(samples)))
    outs = _outputs(mechanism, run.circuits[0].motion)
    panels, details, paper = _panels(mechanism, kind, run, outs)
    given = check_axes_list(ax, len(panels))
    if given is None:
        fig = new_figure((8.5, 1.6 + 2.55 * len(panels)))
        axes = list(np.atleast_1d(fig.subplots(len(panels), 1, sharex=True)))
    else:
        fig, axes = given[0].figure, given
    for ax, panel in zip(axes, panels, strict=True):
        _draw_panel(ax, panel, run, unbounded=not run.full)
    _mark_limits(axes, run)

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
