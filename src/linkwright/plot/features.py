"""What the main picture of any linkage marks, found from its circuits: assembly modes, limit
positions, dead centres and transmission-angle extremes.

:func:`find_features` gathers them once for a mechanism;
:func:`~linkwright.plot.generic.plot_linkage`, :func:`~linkwright.plot.planar.plot_curves` and
:func:`~linkwright.plot.sphere.plot_spherical_mechanism` draw the same findings. What each mark
means:

Assembly modes
    Each dyad closes on one of two branches, its assembly sign. The picture traces the circuit
    of every combination of signs (``assembly`` × ``assembly2`` for a six-bar) when the plan has
    at most two dyads, and only the document's own combination for a longer composed linkage
    (2⁵ circuits of Jansen's leg would bury the one that matters). Where the input only rocks,
    the circuit changes branch at each limit, so two modes may trace one closed curve.
Limit position
    Where the *input* cannot go on: a dyad's two links fall in line, the dyad changes branch and
    the input turns back. Only a linkage whose input rocks has them; they are the circuit's
    samples where a branch changes (exact: :func:`~linkwright.mechanisms.circuit` samples them).
Dead centre
    Where the *output* is stationary (its rate by the input is zero): a four-bar's crank and
    coupler in line, a slider at either end of its stroke. Driven from its output, the
    mechanism locks there. Only families with an output link have them: the four-bar, the
    slider-crank and the spherical four-bar (the exact extremes of
    :func:`linkwright.analysis.output_extremes`), and the six-bars, whose output is their last
    grounded link in construction order: D0D of the Watt II and Stephenson III, E0E of paper
    000's spherical six-bar, GF of paper 001's, and the rocker B0B of the Watt I and
    Stephenson I, whose other links all float. A six-bar's dead centres are the stationary
    points of that link's angle along the circuit: sign changes of its rate between samples of
    one leg, refined by Brent's method. The geared five-bar, the double slider and composed
    linkages have no output link, and nothing is marked.
Transmission-angle extremes
    Four-bar, slider-crank and spherical four-bar: the exact extremes of
    :func:`linkwright.analysis.transmission_extremes`. Every other family: the least and
    greatest of :func:`linkwright.analysis.dyad_transmission_angles` over all its dyads along
    the circuit, refined by golden section between the neighbouring samples. Each is marked on
    the traced curve where it occurs.
"""

from __future__ import annotations

import itertools
import math
import operator
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import brentq

from linkwright.analysis import (
    dyad_transmission_angles,
    output_angle,
    output_extremes,
    transmission_angle,
    transmission_extremes,
)
from linkwright.analysis.extrema import golden_max
from linkwright.engine import (
    DyadRRR,
    Fixed,
    InputArcs,
    Motion,
    SphereDyad,
    evaluate,
    input_arcs,
    trace,
)
from linkwright.geometry import plane, sphere
from linkwright.mechanisms import (
    FourBar,
    Mechanism,
    SliderCrank,
    SphericalFourBar,
    SphericalSixBar,
    SphericalStephenson3,
    circuits,
)
from linkwright.mechanisms.sixbar import SixBar
from linkwright.plot.style import MINUS, Array, deg_text

__all__ = [
    "MAX_MODE_DYADS",
    "Features",
    "closed_loop",
    "find_features",
    "input_status",
    "mechanism_size",
    "mode_curves",
    "never_modes",
]

# Combinations of branch signs are drawn for plans of at most this many dyads.
MAX_MODE_DYADS = 2


_EXACT = (FourBar, SliderCrank, SphericalFourBar)


_SIX_BARS = (SixBar, SphericalSixBar, SphericalStephenson3)


def _sign_text(sign: float) -> str:
    return "+1" if sign > 0 else MINUS + "1"


@dataclass(frozen=True)
class _Mode:
    """One combination of branch signs (one per dyad, in plan order) and its circuits."""

    names: tuple[str, ...]
    signs: tuple[float, ...]
    own: bool
    params: dict[str, Array]
    arcs: InputArcs
    circuits: tuple[Motion, ...]

    @property
    def full(self) -> bool:
        return bool(self.arcs.full)

    @property
    def period(self) -> float:
        return float(np.asarray(self.arcs.period))

    @property
    def label(self) -> str:
        parts = []
        for name, sign in zip(self.names, self.signs, strict=True):
            # A composed linkage names its signs "<joint>.assembly".
            what = f"assembly {name[: -len('.assembly')]}" if name.endswith(".assembly") else name
            parts.append(f"{what} {_sign_text(sign)}")
        return ", ".join(parts) or "the one mode"


@dataclass(frozen=True)
class _Mark:
    """A marked configuration: ``kind`` is "limit", "dead", "gmin" or "gmax"."""

    kind: str
    theta: float
    pose: dict[str, Array]
    text: str


@dataclass(frozen=True)
class Features:
    modes: tuple[_Mode, ...]
    marks: tuple[_Mark, ...]
    output: tuple[str | None, str] | None  # (pivot, joint) of the output link; None: no output
    every_mode: bool

    @property
    def own(self) -> _Mode:
        return self.modes[0]

    def of(self, kind: str) -> list[_Mark]:
        return [m for m in self.marks if m.kind == kind]


def _modes(mechanism: Mechanism, samples: int, *, every: bool = True) -> tuple[_Mode, ...]:
    """The document's mode first, then (``every``, at most :data:`MAX_MODE_DYADS` dyads) the
    other combinations of branch signs, each with every circuit (order 2)."""
    plan = mechanism.plan
    base = mechanism.params()
    names = tuple(d.branch for d in plan.dyads)
    own = tuple(1.0 if float(np.asarray(base[n])) > 0 else -1.0 for n in names)
    if plan.triads:
        # A triad's configurations are followed, not held: one mode with every circuit of
        # every configuration. Its arcs count only the rocking circuits, so the circuits are
        # taken as found, full turns included.
        arcs, found = circuits(mechanism, samples, order=2)
        return (_Mode(names, own, True, base, arcs, tuple(found)),)
    combos = [own]
    if every and len(names) <= MAX_MODE_DYADS:
        combos += [s for s in itertools.product((1.0, -1.0), repeat=len(names)) if s != own]
    out = []
    for signs in combos:
        params = dict(base)
        params.update(
            {n: np.asarray(s, dtype=np.float64) for n, s in zip(names, signs, strict=True)}
        )
        arcs = input_arcs(plan, params, points=mechanism.points)
        count = 0 if bool(arcs.never) else 1 if bool(arcs.full) else int(arcs.count)
        traced = tuple(
            trace(plan, params, samples, points=mechanism.points, order=2, circuit=k)
            for k in range(count)
        )
        out.append(_Mode(names, signs, signs == own, params, arcs, traced))
    return tuple(out)


def _branch_keys(motion: Motion) -> Array:
    names = sorted(motion.labels)
    if not names:
        return np.zeros((motion.shape[-1], 0))
    return np.stack([motion.labels[k] for k in names], axis=-1)


def _legs(motion: Motion, full: bool) -> list[NDArray[np.int64]]:
    """Sample indices of each leg of a closed circuit: a run on one set of branches, from one
    limit position to the next, both included (a full turn is one leg, closed: 0, …, n−1, 0)."""
    n = motion.shape[-1]
    keys = _branch_keys(motion)
    starts = np.flatnonzero(np.any(keys != np.roll(keys, 1, axis=0), axis=-1))
    if full or starts.size == 0:
        return [np.r_[np.arange(n), 0]]
    legs = []
    for a, b in zip(starts, np.roll(starts, -1), strict=True):
        legs.append(np.arange(a, b + 1) if b > a else np.r_[np.arange(a, n), np.arange(0, b + 1)])
    return legs


def _leg_inputs(motion: Motion, leg: NDArray[np.int64], full: bool, period: float) -> Array:
    t = motion.input[leg].astype(float)
    if full:
        t[-1] += period  # the closing sample, one period on
    return t


def _leg_branches(motion: Motion, leg: NDArray[np.int64]) -> dict[str, Array]:
    # A leg's first sample is its limit position, which the circuit samples on the new branch.
    return {k: v[leg[:1]] for k, v in motion.branches.items()}


def _at(
    mechanism: Mechanism, params: dict[str, Array], theta: float, branches: dict[str, Array]
) -> Motion:
    return evaluate(
        mechanism.plan,
        params,
        np.array([theta]),
        points=mechanism.points,
        branches=branches or None,
        order=1,
    )


def _pose_of(motion: Motion, i: int = 0) -> dict[str, Array]:
    return {k: np.asarray(v[i], float) for k, v in motion.positions.items()}


def _same_pose(a: dict[str, Array], b: dict[str, Array], tol: float) -> bool:
    return all(float(np.max(np.abs(a[k] - b[k]))) <= tol for k in a)


def _through(mechanism: Mechanism, mode: _Mode, theta: float) -> list[Motion]:
    """One-sample motions of the mode's circuits at input ``theta``: one per leg that passes
    it (a rocking input passes each inner input twice, once on each branch)."""
    out: list[Motion] = []
    tol = 1e-9
    for motion in mode.circuits:
        for leg in _legs(motion, mode.full):
            t = _leg_inputs(motion, leg, mode.full, mode.period)
            lo, hi = float(min(t[0], t[-1])), float(max(t[0], t[-1]))
            x = lo + float(np.mod(theta - lo + tol, mode.period)) - tol
            if x > hi + tol:
                continue
            m = _at(mechanism, mode.params, min(max(x, lo), hi), _leg_branches(motion, leg))
            if bool(m.valid[0]) and not any(
                _same_pose(_pose_of(m), _pose_of(o), 1e-9 * mechanism_size(mechanism)) for o in out
            ):
                out.append(m)
    return out


def mechanism_size(mechanism: Mechanism) -> float:
    return 1.0 if mechanism.space == "sphere" else float(np.asarray(mechanism.scale))


def _output_link(mechanism: Mechanism) -> tuple[str | None, str] | None:
    """(pivot, joint) of the output link, or None for a family without one (see module doc)."""
    if isinstance(mechanism, FourBar | SphericalFourBar):
        return ("B0", "B")
    if isinstance(mechanism, SliderCrank):
        return (None, "B")
    if not isinstance(mechanism, _SIX_BARS):
        return None
    plan = mechanism.plan
    for step in reversed(plan.steps):
        if isinstance(step, DyadRRR | SphereDyad):
            for pivot in (step.p2, step.p1):
                if isinstance(plan.step(pivot), Fixed):
                    return (pivot, step.name)
    return None


def _link_rate(space: str, pivot: Array, joint: Array, velocity: Array) -> Array:
    """Rate of a grounded link's angle by the input, from its joint's velocity.

    Plane: (J − O) × J′ / |J − O|². Sphere: (O × J)·J′ / |O × J|² (the rate of J's turn about
    the pivot's axis; |O × J| is the sine of the link's arc).
    """
    if space == "sphere":
        w = sphere.cross(np.broadcast_to(pivot, joint.shape), joint)
        return sphere.dot(w, velocity) / sphere.dot(w, w)
    rel = joint - pivot
    return plane.cross(rel, velocity) / plane.dot(rel, rel)


def _wrapped(x: float) -> float:
    return abs((x + math.pi) % (2.0 * math.pi) - math.pi)


def _exact_dead_centres(
    mechanism: FourBar | SliderCrank | SphericalFourBar, mode: _Mode
) -> list[Motion]:
    """Four-bar, slider-crank, spherical four-bar: at the exact output extremes."""
    found: list[Motion] = []
    for k, motion in enumerate(mode.circuits):
        # The analysis reads the circuit it is given (by default the first).
        ext = output_extremes(mechanism, motion=motion if k else None)
        if bool(np.asarray(ext["turns"])):
            return []
        for key in ("min", "max"):
            at, value = float(ext[f"{key}_at"]), float(ext[key])
            if not (math.isfinite(at) and math.isfinite(value)):
                continue
            candidates = _through(mechanism, mode, at)
            if isinstance(mechanism, SliderCrank):
                errors = [abs(float(mechanism.slider_position(m)[0]) - value) for m in candidates]
                tol = 1e-7 * mechanism_size(mechanism)
            else:
                errors = [
                    _wrapped(float(output_angle(mechanism, m)[0]) - value) for m in candidates
                ]
                tol = 1e-7
            for m, err in zip(candidates, errors, strict=True):
                if err <= tol and not any(
                    _same_pose(_pose_of(m), _pose_of(o), 1e-9 * mechanism_size(mechanism))
                    for o in found
                ):
                    found.append(m)
    return found


def _stationary(mechanism: Mechanism, mode: _Mode, pivot: str, joint: str) -> list[Motion]:
    """Where the grounded link pivot→joint stops turning along the mode's circuits: sign
    changes of its rate between neighbouring samples of one leg, refined by Brent's method."""
    space = mechanism.space
    found: list[Motion] = []

    def rate(m: Motion) -> Array:
        assert m.velocities is not None
        return _link_rate(space, m.positions[pivot], m.positions[joint], m.velocities[joint])

    for motion in mode.circuits:
        w = rate(motion)
        for leg in _legs(motion, mode.full):
            t = _leg_inputs(motion, leg, mode.full, mode.period)
            branches = _leg_branches(motion, leg)
            wl = w[leg]
            for j in range(len(leg) - 1):
                a, b = wl[j], wl[j + 1]
                if not (np.isfinite(a) and np.isfinite(b)) or a * b > 0 or (a == 0 and b == 0):
                    continue
                if a == 0:
                    x = float(t[j])
                elif b == 0:
                    x = float(t[j + 1])
                else:

                    def f(theta: float, branches: dict[str, Array] = branches) -> float:
                        return float(rate(_at(mechanism, mode.params, theta, branches))[0])

                    x = float(brentq(f, float(t[j]), float(t[j + 1]), xtol=1e-15, rtol=1e-15))
                m = _at(mechanism, mode.params, x, branches)
                if bool(m.valid[0]) and not any(
                    _same_pose(_pose_of(m), _pose_of(o), 1e-9 * mechanism_size(mechanism))
                    for o in found
                ):
                    found.append(m)
    return found


def _gamma_of(mechanism: Mechanism, motion: Motion) -> dict[str, Array]:
    """Transmission angle of every dyad (the four-bar families' own definition for theirs)."""
    if isinstance(mechanism, _EXACT):
        return {"B": transmission_angle(mechanism, motion)}
    return dyad_transmission_angles(mechanism, motion)


def _mirror(mechanism: Mechanism, theta: float) -> float:
    """The other input where a four-bar family's γ takes the same value (the closed forms give
    the one in [0, π] beyond the frame line)."""
    if isinstance(mechanism, FourBar):
        return 2.0 * float(np.asarray(mechanism.frame_angle)) - theta
    if isinstance(mechanism, SliderCrank):
        return 2.0 * float(np.asarray(mechanism.line_angle)) + math.pi - theta
    return -theta


def _exact_gamma(mechanism: Mechanism, mode: _Mode) -> list[tuple[str, float, Motion]]:
    ext = transmission_extremes(mechanism)
    out: list[tuple[str, float, Motion]] = []
    for key in ("min", "max"):
        at, value = float(ext[f"{key}_at"]), float(ext[key])
        if not (math.isfinite(at) and math.isfinite(value)):
            continue
        found: list[Motion] = []
        for x in (at, _mirror(mechanism, at)):
            for m in _through(mechanism, mode, x):
                g = float(_gamma_of(mechanism, m)["B"][0])
                if abs(g - value) <= 1e-6 and not any(
                    _same_pose(_pose_of(m), _pose_of(o), 1e-9 * mechanism_size(mechanism))
                    for o in found
                ):
                    found.append(m)
        out += [(key, value, m) for m in found]
    return out


def _sampled_gamma(mechanism: Mechanism, mode: _Mode) -> list[tuple[str, float, Motion, str]]:
    """Least and greatest dyad transmission angle along the circuits, refined by golden
    section on the neighbouring samples' bracket (kept on the sample's leg)."""
    best: dict[str, tuple[float, int, int, str] | None] = {"min": None, "max": None}
    for c, motion in enumerate(mode.circuits):
        for dyad, g in _gamma_of(mechanism, motion).items():
            if not np.isfinite(g).any():
                continue
            for key, pick, better in (
                ("min", np.nanargmin, operator.lt),
                ("max", np.nanargmax, operator.gt),
            ):
                i = int(pick(g))
                cur = best[key]
                if cur is None or better(float(g[i]), cur[0]):
                    best[key] = (float(g[i]), c, i, dyad)
    out = []
    for key, found in best.items():
        if found is None:
            continue
        _, c, i, dyad = found
        motion = mode.circuits[c]
        sign = -1.0 if key == "min" else 1.0
        legs = _legs(motion, mode.full)
        leg = next(lg for lg in legs if i in lg[:-1]) if not mode.full else legs[0]
        t = _leg_inputs(motion, leg, mode.full, mode.period)
        j = int(np.flatnonzero(leg[:-1] == i)[0]) if not mode.full else i
        if mode.full:
            n = len(leg) - 1
            step = mode.period / n
            lo_t, hi_t = float(motion.input[i]) - 1.5 * step, float(motion.input[i]) + 1.5 * step
        else:
            lo_t, hi_t = float(t[max(j - 1, 0)]), float(t[min(j + 1, len(t) - 1)])
            lo_t, hi_t = min(lo_t, hi_t), max(lo_t, hi_t)
        branches = _leg_branches(motion, leg)

        def f(
            x: Array, branches: dict[str, Array] = branches, dyad: str = dyad, sign: float = sign
        ) -> Array:
            m = evaluate(
                mechanism.plan,
                mode.params,
                x,
                points=mechanism.points,
                branches={k: np.broadcast_to(v, x.shape) for k, v in branches.items()} or None,
                order=0,
            )
            return sign * _gamma_of(mechanism, m)[dyad]

        x, v = golden_max(f, np.array([lo_t]), np.array([hi_t]))
        m = _at(mechanism, mode.params, float(x[0]), branches)
        if not bool(m.valid[0]) or float(sign * v[0]) < sign * found[0]:
            m = _at(mechanism, mode.params, float(motion.input[i]), branches)
        gamma = float(_gamma_of(mechanism, m)[dyad][0])
        out.append((key, gamma, m, dyad))
    return out


def find_features(
    mechanism: Mechanism, samples: int, *, every: bool = True, marks: bool = True
) -> Features:
    """Every assembly mode's circuits (``every``; else the document's only) and the marks of
    the document's own mode: its limit positions, and (``marks``) its dead centres and
    transmission-angle extremes."""
    found = _modes(mechanism, samples, every=every)
    if not marks:
        return Features(found, tuple(_limit_marks(mechanism, found[0])), None, len(found) > 1)
    return Features(
        found,
        tuple(_limit_marks(mechanism, found[0]) + _other_marks(mechanism, found[0])),
        _output_link(mechanism),
        len(found) > 1 or not found[0].names,
    )


def _limit_marks(mechanism: Mechanism, own: _Mode) -> list[_Mark]:
    marks: list[_Mark] = []
    many = len(mechanism.plan.dyads) > 1
    if own.full:
        return marks
    for motion in own.circuits:
        keys = _branch_keys(motion)
        names = sorted(motion.labels)
        changed = keys != np.roll(keys, 1, axis=0)
        for i in np.flatnonzero(np.any(changed, axis=-1)):
            theta = float(motion.input[i])
            # Each step kind names itself ("dyad B", "triad BCE": one name for its joints).
            steps = (mechanism.plan.step(n) for n, c in zip(names, changed[i], strict=True) if c)
            which = ", ".join(dict.fromkeys(step.title for step in steps))
            # A triad's circuit may run on past a whole turn of the input: its limits are
            # named within one turn, as analyze lists them.
            shown = math.remainder(theta, 2 * math.pi) if mechanism.plan.triads else theta
            text = f"limit θ = {deg_text(math.degrees(shown))}°" + (f" ({which})" if many else "")
            marks.append(_Mark("limit", theta, _pose_of(motion, int(i)), text))
    return marks


def _other_marks(mechanism: Mechanism, own: _Mode) -> list[_Mark]:
    """Dead centres and transmission-angle extremes of the document's mode."""
    marks: list[_Mark] = []
    if not own.circuits:
        return marks
    limits = _limit_marks(mechanism, own)
    many = len(mechanism.plan.dyads) > 1

    def where(theta: float, pose: dict[str, Array]) -> str:
        # At a limit position its note already gives the input.
        for lim in limits:
            if _same_pose(pose, lim.pose, 1e-7 * mechanism_size(mechanism)):
                return ""
        return f"\n(θ = {deg_text(math.degrees(theta))}°)"

    output = _output_link(mechanism)
    if output is not None:
        pivot, joint = output
        if isinstance(mechanism, _EXACT):
            dead = _exact_dead_centres(mechanism, own)
        else:
            assert pivot is not None
            dead = _stationary(mechanism, own, pivot, joint)
        for m in dead:
            theta = float(m.input[0])
            text = f"dead centre θ = {deg_text(math.degrees(theta))}°"
            marks.append(_Mark("dead", theta, _pose_of(m), text))
    if isinstance(mechanism, _EXACT):
        gammas = [(key, value, m, "") for key, value, m in _exact_gamma(mechanism, own)]
    else:
        gammas = [
            (key, value, m, f" at {dyad}" if many else "")
            for key, value, m, dyad in _sampled_gamma(mechanism, own)
        ]
    for key, value, m, at in gammas:
        theta = float(m.input[0])
        text = f"γ{key}{at} = {deg_text(math.degrees(value))}°" + where(theta, _pose_of(m))
        marks.append(_Mark("g" + key, theta, _pose_of(m), text))
    return marks


def _same_curve(a: Array, b: Array, tol: float) -> bool:
    """Whether two sampled closed curves are one: every point of each near the other."""
    a = a[np.all(np.isfinite(a), axis=-1)]
    b = b[np.all(np.isfinite(b), axis=-1)]
    if not len(a) or not len(b):
        return False
    a, b = a[:: max(1, len(a) // 240)], b[:: max(1, len(b) // 240)]
    d = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=-1)
    return bool(d.min(axis=1).max() <= tol and d.min(axis=0).max() <= tol)


def closed_loop(p: Array) -> Array:
    return np.concatenate((p, p[:1]))


def _curve_tolerance(curves: list[Array]) -> float:
    """Twice the longest step of the sampled curves: two samplings of one curve lie within it."""
    steps = [np.linalg.norm(np.diff(c, axis=0), axis=-1) for c in curves if len(c) > 1]
    finite = np.concatenate(steps) if steps else np.zeros(1)
    finite = finite[np.isfinite(finite)]
    return 2.0 * float(finite.max()) if finite.size else 0.0


def mode_curves(feats: Features, joint: str) -> list[tuple[_Mode, int, Array, str | None]]:
    """Closed curves of ``joint`` for every mode and circuit, with the label of an earlier
    mode that traces the same curve (None if none does)."""
    out: list[tuple[_Mode, int, Array, str | None]] = []
    curves = [closed_loop(c.positions[joint]) for m in feats.modes for c in m.circuits]
    tol = _curve_tolerance(curves)
    for mode in feats.modes:
        for k, motion in enumerate(mode.circuits):
            p = closed_loop(motion.positions[joint])
            same = next((m.label for m, _, q, _ in out if _same_curve(p, q, tol)), None)
            out.append((mode, k, p, same))
    return out


def never_modes(feats: Features) -> list[str]:
    return [m.label for m in feats.modes if not m.circuits]


def input_status(arcs: InputArcs) -> str:
    if bool(arcs.full):
        return "input turns fully"
    lo, hi = arcs.lo[np.isfinite(arcs.lo)], arcs.hi[np.isfinite(arcs.hi)]
    spans = ", ".join(
        f"[{deg_text(math.degrees(a))}°, {deg_text(math.degrees(b))}°]"
        for a, b in zip(lo, hi, strict=True)
    )
    return f"input rocks over {spans}"
