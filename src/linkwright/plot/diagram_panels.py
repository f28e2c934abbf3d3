"""A motion diagram's circuit and panels: the legs against the input angle, and one panel drawn.

:func:`circuit_legs` reads the traced circuits as lines against the input angle in degrees: a
full turn is one line, a rocking input one line per leg (solid up, dashed back), split at the
limit positions where the input turns back. A :class:`Panel` is one axis of a diagram, its
:class:`Series` per plotted quantity; :func:`draw_panel` draws one, clipping derivatives that
grow without bound next to the limits (:func:`clip_limit`), and :func:`mark_limits` marks the
limits on every panel.

Its own room (split from :mod:`linkwright.plot.diagrams`): the drawing of any panel, apart
from what each kind of diagram puts in its panels (:mod:`~linkwright.plot.diagram_kinds`).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np
from matplotlib.axes import Axes
from numpy.typing import NDArray

from linkwright.mechanisms import Mechanism, input_range
from linkwright.plot.planar import TracedCircuit, deg_text, speed_limit, unwrap_finite
from linkwright.plot.style import LIMIT_COLOR, MINUS

__all__ = [
    "BACK_STYLE",
    "IDEAL_COLOR",
    "NOTE_COLOR",
    "UP_STYLE",
    "Panel",
    "Run",
    "Series",
    "circuit_legs",
    "clip_limit",
    "draw_panel",
    "mark_limits",
    "minmax",
]

Array = NDArray[np.float64]
UP_STYLE = "-"
BACK_STYLE = (0, (5, 2.5))
IDEAL_COLOR = "0.45"
NOTE_COLOR = "0.3"


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
class Run:
    """The traced circuits, their input axis (degrees) and how they split into legs."""

    circuits: list[TracedCircuit]
    x: list[Array]
    legs: list[_Leg]
    limits: list[float]
    full: bool
    period_deg: float

    def closed(self, values: list[Array]) -> list[Array]:
        return [v[c.closed()] for v, c in zip(values, self.circuits, strict=True)]


def circuit_legs(mechanism: Mechanism, circuits: list[TracedCircuit]) -> Run:
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
    return Run(circuits, xs, legs, sorted(limits), full, period)


# --------------------------------------------------------------------------------------------
# Panels
# --------------------------------------------------------------------------------------------


@dataclass
class Series:
    label: str
    values: list[Array]  # per circuit, on the closed circuit's samples
    color: str


@dataclass
class Panel:
    ylabel: str
    series: list[Series]
    note: str = ""
    ideal: float | None = None
    ideal_label: str = ""
    clip: str | None = None  # "magnitude" or "signed": derivatives that blow up at limits
    secondary: tuple[float, str] | None = None  # (scale, label): right axis = left / scale
    extra: list[str] = field(default_factory=list)


def minmax(values: list[Array]) -> tuple[float, float] | None:
    v = np.concatenate([np.ravel(a) for a in values])
    v = v[np.isfinite(v)]
    if v.size == 0:
        return None
    return float(v.min()), float(v.max())


def clip_limit(panel: Panel, run: Run) -> float | None:
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


def draw_panel(ax: Axes, panel: Panel, run: Run, *, unbounded: bool) -> None:
    for s in panel.series:
        first = True
        for leg in run.legs:
            x = run.x[leg.circuit][leg.index]
            y = s.values[leg.circuit][leg.index]
            label = s.label if first else f"_{s.label} | {leg.name}"
            ax.plot(x, y, color=s.color, ls=leg.style, lw=1.6, label=label)
            first = False
    span = minmax([v for s in panel.series for v in s.values])
    # A zero line only where the quantity changes sign: else it would squash the curves.
    crosses = span is not None and span[0] < 0.0 < span[1]
    if panel.ideal is not None and (panel.ideal_label != "_zero" or crosses):
        ax.axhline(panel.ideal, color=IDEAL_COLOR, lw=0.9, ls=":", label=panel.ideal_label)
    notes = [panel.note] if panel.note else []
    if panel.clip and unbounded:
        top = clip_limit(panel, run)
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
        right = ax.secondary_yaxis(
            "right", functions=(lambda y: np.divide(y, scale), lambda y: np.multiply(y, scale))
        )
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


def mark_limits(axes: list[Axes], run: Run) -> None:
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
