"""Approximate motion generation: four-bars and slider-cranks guiding a body near n ≥ 3 poses.

Exact Burmester theory (:mod:`linkwright.synthesis.burmester`) stops at five poses. With more,
or with poses no linkage meets exactly, the designer wants the linkages that come closest. The
method is the classical one of fitting dyads (Sandor and Erdman, *Advanced Mechanism Design*,
1984, §3; McCarthy and Soh, *Geometric Design of Linkages*, 2011, ch. 5):

1. **Dyads.** A body point m moves through the poses as p_i(m). An RR dyad needs them on a
   circle (its ground pivot the centre, its link the radius); a PR dyad (a slider) on a line.
   Each point's misfit is the RMS distance of p_i(m) from the best circle (line) through them,
   found in closed form (the algebraic circle fit, Kåsa's; the total-least-squares line), and
   the body points where it is least are found by a grid over the poses' neighbourhood, then
   refined by least squares in the geometric distances (point, centre and radius together).
2. **Linkages.** Every pair of distinct good dyads makes a linkage: two RR dyads a four-bar
   (the first the crank), an RR and a PR dyad a slider-crank, two PR dyads a double slider
   (an elliptic trammel, paper 004's, driven by the body's own angle).
3. **The pose error, simulated.** Each linkage is solved by the engine on the assembly of the
   first pose, its input at each pose chosen to bring the body nearest to it; the error is
   Σ_i |ΔP_i|² + (w·s)² Δα_i², ΔP the pose point's miss, Δα the body angle's, s the poses'
   spread (their diameter: the largest distance between two pose points) and w the weight the
   designer gives the angles (1: a radian counts as the spread).
   The linkages come back ranked by it, branch defects flagged.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.analysis.extrema import golden_max
from linkwright.mechanisms import DoubleSlider, FourBar, Mechanism, SliderCrank, solve
from linkwright.synthesis.precision_designs import PrecisionError, pose_set

__all__ = ["FittedDyad", "MotionFit", "fit_dyads", "fit_motion"]

Array = NDArray[np.float64]

GRID = 41
"""Body points tried per side of the grid (the box three spreads about the poses)."""
KEEP = 8
"""Dyads of each kind kept to make linkages from."""
POLISH_STEPS = 40
"""Least-squares steps of the joint fit of each of the best linkages."""
LONGEST = 20.0
"""An RR dyad longer than this many spreads is a slider in disguise: left to the PR fit."""


@dataclass(frozen=True)
class FittedDyad:
    """A dyad fitted to the poses.

    ``kind`` is ``"RR"`` (ground pivot ``centre``, link ``radius``) or ``"PR"`` (slider line
    through ``centre`` at ``angle``); ``point`` is its body point in the first pose; ``misfit``
    the RMS distance of the point's positions from the circle or line.
    """

    kind: str
    point: Array
    centre: Array
    radius: float
    angle: float
    misfit: float


@dataclass(frozen=True)
class MotionFit:
    """A linkage guiding the body near the poses.

    ``mechanism`` is a :class:`FourBar`, a :class:`SliderCrank` or a :class:`DoubleSlider`
    (P the pose point);
    ``inputs`` the input at each pose; ``position_error`` and ``angle_error`` each pose's miss
    (length, radians) simulated by the engine on the first pose's assembly; ``error`` the
    weighted sum of squares it is ranked by; ``branch_defect`` whether the poses lie on both
    branches (then the linkage cannot pass them in one motion, whatever the errors say);
    ``dyads`` the two fitted dyads it is made of; ``angle_offset`` the body's angle less the
    coupler line's (A → B; R → Q on a double slider), so that the body's angle at pose i is
    that line's angle there plus it.
    """

    mechanism: Mechanism
    inputs: Array
    position_error: Array
    angle_error: Array
    error: float
    branch_defect: bool
    dyads: tuple[FittedDyad, FittedDyad]
    angle_offset: float


def _moved(points: Array, angles: Array, body: Array) -> Array:
    """Positions (..., n, 2) of body points (..., 2), given where they are in the first pose."""
    turn = angles - angles[0]
    rel = body[..., None, :] - points[0]
    c, s = np.cos(turn), np.sin(turn)
    x = points[:, 0] + c * rel[..., 0] - s * rel[..., 1]
    y = points[:, 1] + s * rel[..., 0] + c * rel[..., 1]
    return np.stack((x, y), axis=-1)


def _circle_misfit(q: Array) -> tuple[Array, Array, Array]:
    """Kåsa's algebraic circle through points q (..., n, 2): centres, radii, RMS misfits."""
    mean = q.mean(axis=-2, keepdims=True)
    r = q - mean
    rows = np.concatenate((2 * r, np.ones(r.shape[:-1] + (1,))), axis=-1)
    rhs = np.sum(r * r, axis=-1)
    gram = np.einsum("...ij,...ik->...jk", rows, rows) + 1e-300 * np.eye(3)
    sol = np.linalg.solve(gram, np.einsum("...ij,...i->...j", rows, rhs)[..., None])[..., 0]
    centre = sol[..., :2]
    radius = np.sqrt(np.maximum(sol[..., 2] + np.sum(centre * centre, axis=-1), 0.0))
    off = np.linalg.norm(r - centre[..., None, :], axis=-1) - radius[..., None]
    return centre + mean[..., 0, :], radius, np.sqrt(np.mean(off * off, axis=-1))


def _line_misfit(q: Array) -> tuple[Array, Array, Array]:
    """Total-least-squares lines through points q (..., n, 2): points, angles, RMS misfits."""
    mean = q.mean(axis=-2)
    r = q - mean[..., None, :]
    sxx, syy = np.mean(r[..., 0] ** 2, axis=-1), np.mean(r[..., 1] ** 2, axis=-1)
    sxy = np.mean(r[..., 0] * r[..., 1], axis=-1)
    angle = 0.5 * np.arctan2(2 * sxy, sxx - syy)
    across = -np.sin(angle)[..., None] * r[..., 0] + np.cos(angle)[..., None] * r[..., 1]
    return mean, angle, np.sqrt(np.mean(across * across, axis=-1))


def fit_dyads(points: ArrayLike, angles: ArrayLike, keep: int = KEEP) -> list[FittedDyad]:
    """The RR and PR dyads that best guide a body through poses (see the module notes).

    Parameters
    ----------
    points : (n, 2) the pose point in each pose; angles : (n,) the body's angle (radians).
    keep : how many of each kind to return (best first, distinct).

    Returns
    -------
    list of FittedDyad, RR dyads then PR dyads, each kind best first.
    """
    from scipy.optimize import least_squares

    p, a, scale = pose_set(points, angles, None, "fit_dyads")
    if p.ndim != 2 or len(p) < 3:
        raise PrecisionError(f"fit_dyads: needs n ≥ 3 poses (one set), got points {p.shape}")
    s = float(scale)
    centre = p.mean(axis=0)
    ticks = np.linspace(-3.0, 3.0, GRID) * s
    body = np.stack(np.meshgrid(centre[0] + ticks, centre[1] + ticks), axis=-1).reshape(-1, 2)
    moved = _moved(p, a, body)
    found: list[FittedDyad] = []
    for kind in ("RR", "PR"):
        if kind == "RR":
            _, radius, misfit = _circle_misfit(moved)
            misfit = np.where(radius < LONGEST * s, misfit, np.inf)
        else:
            _, _, misfit = _line_misfit(moved)
        chosen: list[FittedDyad] = []
        for k in _starts(misfit, body, s)[: 6 * keep]:
            dyad = _refine(kind, p, a, body[k], s, least_squares)
            if dyad is None or any(np.linalg.norm(dyad.point - d.point) < 0.02 * s for d in chosen):
                # Noise can drain a dyad's basin into a deeper one: the grid point's own
                # circle (line) stays a candidate, for the linkage's joint fit to finish.
                dyad = _raw(kind, p, a, body[k])
            if any(np.linalg.norm(dyad.point - d.point) < 0.02 * s for d in chosen):
                continue
            chosen.append(dyad)
            if len(chosen) == keep:
                break
        found += sorted(chosen, key=lambda d: d.misfit)
    return found


def _starts(misfit: Array, body: Array, s: float) -> list[int]:
    """Grid points to start from: every local minimum, best first, then the lowest points at
    least half a spread from every start already taken."""
    starts = [int(k) for k in _basins(misfit.reshape(GRID, GRID))]
    for k in np.argsort(misfit):
        if not np.isfinite(misfit[k]):
            break
        if all(np.linalg.norm(body[k] - body[j]) >= 0.5 * s for j in starts):
            starts.append(int(k))
    return starts


def _raw(kind: str, p: Array, a: Array, point: Array) -> FittedDyad:
    """The dyad of a body point as it is: its positions' closed-form circle (line)."""
    q = _moved(p, a, point)
    if kind == "RR":
        c, r, misfit = _circle_misfit(q)
        return FittedDyad("RR", point.copy(), c, float(r), 0.0, float(misfit))
    m, ang, misfit = _line_misfit(q)
    return FittedDyad("PR", point.copy(), m, math.inf, float(ang), float(misfit))


def _basins(misfit: Array) -> NDArray[np.intp]:
    """The grid's local minima (no neighbour lower), best first: one start per basin, so that
    a dyad whose basin is shallower than another's slopes is still found."""
    padded = np.pad(misfit, 1, constant_values=np.inf)
    lowest = np.ones(misfit.shape, dtype=bool)
    rows, cols = misfit.shape
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            if dr or dc:
                near = padded[1 + dr : 1 + dr + rows, 1 + dc : 1 + dc + cols]
                lowest &= misfit <= near
    flat = misfit.ravel()
    minima = np.flatnonzero(lowest.ravel() & np.isfinite(flat))
    return minima[np.argsort(flat[minima])]


def _refine(
    kind: str, p: Array, a: Array, start: Array, s: float, solver: Any
) -> FittedDyad | None:
    """Least squares in the geometric distances from a grid point: the body point with its
    circle (centre, radius) or line (point, angle)."""
    q = _moved(p, a, start)
    if kind == "RR":
        c, r, _ = _circle_misfit(q)
        x0 = np.r_[start, c, r]

        def off(x: Array) -> Array:
            return np.asarray(np.linalg.norm(_moved(p, a, x[:2]) - x[2:4], axis=-1) - x[4])
    else:
        m, ang, _ = _line_misfit(q)
        x0 = np.r_[start, m, ang]

        def off(x: Array) -> Array:
            rel = _moved(p, a, x[:2]) - x[2:4]
            return np.asarray(-math.sin(x[4]) * rel[:, 0] + math.cos(x[4]) * rel[:, 1])

    best = solver(off, x0, x_scale=np.r_[s, s, s, s, s if kind == "RR" else 1.0], max_nfev=200)
    x = best.x
    misfit = float(np.sqrt(np.mean(off(x) ** 2)))
    if not np.isfinite(misfit) or (kind == "RR" and not s * 1e-6 < abs(x[4]) < LONGEST * s):
        return None
    return FittedDyad(
        kind=kind,
        point=x[:2].copy(),
        centre=x[2:4].copy(),
        radius=abs(float(x[4])) if kind == "RR" else math.inf,
        angle=float(x[4]) if kind == "PR" else 0.0,
        misfit=misfit,
    )


def fit_motion(
    points: ArrayLike, angles: ArrayLike, *, angle_weight: float = 1.0, top: int = 10
) -> list[MotionFit]:
    """The four-bars, slider-cranks and double sliders that best guide a body near n ≥ 3 poses,
    ranked.

    Parameters
    ----------
    points : (n, 2) the pose point in each pose; angles : (n,) the body's angle (radians).
    angle_weight : w, how much a radian of angle error weighs against the poses' spread s
        (the error is Σ |ΔP|² + (w·s)² Δα²).
    top : how many linkages to return.

    Returns
    -------
    list of MotionFit, best first (an empty list where no pair of dyads assembles).

    Raises
    ------
    PrecisionError
        For fewer than three poses, non-finite numbers, coincident poses, or a weight that is
        not a non-negative number.

    Examples
    --------
    Seven poses of a known four-bar's coupler come back as a four-bar meeting them:

    >>> fb = FourBar(A0=[0, 0], B0=[2, 0], crank=1, coupler=2.5, rocker=1.5, u=1, v=0.5)
    >>> m = solve(fb, np.radians(np.linspace(40, 160, 7)))
    >>> line = m.positions["B"] - m.positions["A"]
    >>> best = fit_motion(m.positions["P"], np.arctan2(line[:, 1], line[:, 0]))[0]
    >>> type(best.mechanism).__name__, bool(best.error < 1e-12)
    ('FourBar', True)
    """
    p, a, scale = pose_set(points, angles, None, "fit_motion")
    if not (isinstance(angle_weight, int | float) and angle_weight >= 0):
        raise PrecisionError(f"fit_motion: angle_weight must be ≥ 0, got {angle_weight!r}")
    s = float(scale)
    dyads = fit_dyads(p, a)
    rr = [d for d in dyads if d.kind == "RR"]
    pr = [d for d in dyads if d.kind == "PR"]
    pairs = [(x, y) for x in rr for y in rr if x is not y] + [(x, y) for x in rr for y in pr]
    # Two sliders make one double slider whichever is named first.
    pairs += [(x, y) for i, x in enumerate(pr) for y in pr[i + 1 :]]
    fits = [f for f in (_linkage(p, a, s, x, y, angle_weight) for x, y in pairs) if f]
    fits.sort(key=lambda f: (f.branch_defect, f.error))
    # The best few finish together: every dimension and every pose's input at once, in least
    # squares of the simulated misses (the dyads were fitted one at a time).
    polished = [_polish(f, p, a, s, angle_weight) for f in fits[: 2 * top]]
    polished.sort(key=lambda f: (f.branch_defect, f.error))
    return polished[:top]


def _numbers(mech: Mechanism) -> tuple[Array, Any]:
    """The linkage's free numbers (lengths as logarithms), and how to rebuild it from them."""
    if isinstance(mech, FourBar):
        x = np.r_[mech.A0, mech.B0, np.log([float(mech.crank), float(mech.coupler),
                  float(mech.rocker)]), float(mech.u), float(mech.v)]  # fmt: skip
        asm = float(mech.assembly)

        def four_bar(y: Array) -> Mechanism:
            return FourBar(A0=y[0:2], B0=y[2:4], crank=math.exp(y[4]), coupler=math.exp(y[5]),
                           rocker=math.exp(y[6]), u=y[7], v=y[8], assembly=asm)  # fmt: skip

        return x, four_bar
    if isinstance(mech, DoubleSlider):
        x = np.r_[mech.M, float(mech.alpha), float(mech.beta), float(mech.p), float(mech.q),
                  float(mech.h)]  # fmt: skip

        def double_slider(y: Array) -> Mechanism:
            return DoubleSlider(M=y[0:2], alpha=y[2], beta=y[3], p=y[4], q=y[5], h=y[6])

        return x, double_slider
    assert isinstance(mech, SliderCrank)
    angle = float(mech.line_angle)
    normal = np.array([-math.sin(angle), math.cos(angle)])
    base = np.asarray(mech.line_point, dtype=float)
    x = np.r_[mech.A0, np.log([float(mech.crank), float(mech.rod)]), 0.0, angle,
              float(mech.u), float(mech.v)]  # fmt: skip
    asm = float(mech.assembly)

    def slider_crank(y: Array) -> Mechanism:
        # The line moves along its normal only: a point along it would be a free gauge.
        return SliderCrank(A0=y[0:2], crank=math.exp(y[2]), rod=math.exp(y[3]),
                           line_point=base + y[4] * normal, line_angle=y[5], u=y[6], v=y[7],
                           assembly=asm)  # fmt: skip

    return x, slider_crank


def _polish(fit: MotionFit, p: Array, a: Array, s: float, weight: float) -> MotionFit:
    """``fit`` with its dimensions, body-angle offset and inputs fitted together."""
    from scipy.optimize import least_squares

    from linkwright.mechanisms import InvalidMechanism

    x0, build = _numbers(fit.mechanism)
    delta0 = fit.angle_offset
    n, k = len(p), len(x0)
    z0 = np.r_[x0, delta0, fit.inputs]

    def residuals(z: Array) -> Array:
        try:
            mech = build(z[:k])
        except InvalidMechanism:
            return np.full(3 * n, 10.0 * s)
        motion = solve(mech, z[k + 1 :], order=0)
        dpos = np.asarray(motion.positions["P"]) - p
        dang = np.angle(np.exp(1j * (_body_angle(motion) + z[k] - a)))
        out = np.c_[dpos, weight * s * dang].ravel()
        return np.where(np.isfinite(out), out, 10.0 * s)

    # A pose's residuals depend on the dimensions and on its own input only: with that
    # pattern the Jacobian costs k + 2 evaluations, not k + n + 1.
    pattern = np.zeros((3 * n, k + 1 + n), dtype=bool)
    pattern[:, : k + 1] = True
    for i in range(n):
        pattern[3 * i : 3 * i + 3, k + 1 + i] = True
    best = least_squares(
        residuals, z0, method="trf", jac_sparsity=pattern, max_nfev=POLISH_STEPS, x_scale="jac"
    )
    if not np.sum(best.fun**2) < fit.error:
        return fit
    mech = build(best.x[:k])
    inputs = best.x[k + 1 :]
    dp, da = _misses(mech, float(best.x[k]), p, a, inputs)
    if not np.all(np.isfinite(dp)):
        return fit
    error = float(np.sum(dp * dp + (weight * s * da) ** 2))
    if not error < fit.error:
        return fit
    return MotionFit(mech, inputs, dp, da, error, fit.branch_defect, fit.dyads, float(best.x[k]))


def _linkage(
    p: Array, a: Array, s: float, first: FittedDyad, second: FittedDyad, weight: float
) -> MotionFit | None:
    """The linkage of two dyads, simulated at every pose (None where it cannot be built)."""
    if first.kind == second.kind == "PR":
        return _double_slider(p, a, s, first, second, weight)
    A, B = first.point, second.point
    coupler = float(np.linalg.norm(B - A))
    if coupler < 1e-6 * s or np.linalg.norm(first.centre - (second.centre)) < 1e-6 * s:
        return None
    ex = (B - A) / coupler
    ey = np.array([-ex[1], ex[0]])
    u, v = float((p[0] - A) @ ex), float((p[0] - A) @ ey)
    mech: Mechanism
    guide = np.array([math.cos(second.angle), math.sin(second.angle)])
    if second.kind == "RR":
        gap0, arm = second.centre - A, B - A
        side = 1.0 if gap0[0] * arm[1] - gap0[1] * arm[0] >= 0 else -1.0
        mech = FourBar(A0=first.centre, B0=second.centre, crank=first.radius, coupler=coupler,
                       rocker=second.radius, u=u, v=v, assembly=side)  # fmt: skip
    else:
        foot = second.centre + ((A - second.centre) @ guide) * guide
        mech = SliderCrank(A0=first.centre, crank=first.radius, rod=coupler,
                           line_point=second.centre, line_angle=second.angle, u=u, v=v,
                           assembly=1.0 if (B - foot) @ guide >= 0 else -1.0)  # fmt: skip
    base = math.atan2(ex[1], ex[0])
    moved_a = _moved(p, a, first.point)
    natural = np.arctan2(moved_a[:, 1] - first.centre[1], moved_a[:, 0] - first.centre[0])
    # The branch each pose asks for, from the dyads' own positions.
    moved_b = _moved(p, a, second.point)
    if second.kind == "RR":
        gap = second.centre - moved_a
        sides = np.sign(
            gap[:, 0] * (moved_b - moved_a)[:, 1] - gap[:, 1] * (moved_b - moved_a)[:, 0]
        )
    else:
        sides = np.sign((moved_b - moved_a) @ guide)

    delta = float(a[0] - base)
    return _simulated(mech, delta, p, a, s, weight, natural, (first, second), sides)


def _simulated(
    mech: Mechanism,
    delta: float,
    p: Array,
    a: Array,
    s: float,
    weight: float,
    natural: Array,
    dyads: tuple[FittedDyad, FittedDyad],
    sides: Array,
) -> MotionFit | None:
    """``mech`` solved at the input nearest each pose (near ``natural``): its fit, or None
    where it cannot reach one. ``sides``: the branch each pose asks for."""
    inputs = _nearest_inputs(mech, delta, p, a, s, weight, natural)
    dp, da = _misses(mech, delta, p, a, inputs)
    if not np.all(np.isfinite(dp)):
        return None
    return MotionFit(
        mechanism=mech,
        inputs=inputs,
        position_error=dp,
        angle_error=da,
        error=float(np.sum(dp * dp + (weight * s * da) ** 2)),
        branch_defect=bool(np.any(sides != sides[0])),
        dyads=dyads,
        angle_offset=delta,
    )


def _double_slider(
    p: Array, a: Array, s: float, first: FittedDyad, second: FittedDyad, weight: float
) -> MotionFit | None:
    """Two PR dyads: the body's points R and Q slide on two fixed lines, an elliptic trammel
    (:class:`DoubleSlider`, paper 004) driven by the body's own angle. Its guides are the
    dyads' lines, met at M; its coupler is R − Q = (p + q)·e^{iθ} in the first pose, and the
    pose point P = R − (p + i·h)·e^{iθ} there."""
    alpha = first.angle - second.angle
    if abs(math.sin(alpha)) < 1e-6:
        return None  # parallel guides: no trammel
    e1 = np.array([math.cos(first.angle), math.sin(first.angle)])
    e2 = np.array([math.cos(second.angle), math.sin(second.angle)])
    # M = c1 + t1·e1 = c2 + t2·e2.
    t1 = np.linalg.solve(np.c_[e1, -e2], second.centre - first.centre)[0]
    M = first.centre + t1 * e1
    R, Q = first.point, second.point
    rod = complex(*(R - Q))
    if abs(rod) < 1e-6 * s:
        return None
    theta0 = math.atan2(rod.imag, rod.real)
    arm = complex(*(R - p[0])) * complex(math.cos(theta0), -math.sin(theta0))
    mech = DoubleSlider(M=M, alpha=alpha, beta=second.angle, p=arm.real, q=abs(rod) - arm.real,
                        h=arm.imag)  # fmt: skip
    # The body line R → Q runs at θ + π; the input is the body's angle, less its offset.
    delta = float(a[0] - (theta0 + math.pi))
    natural = theta0 + (a - a[0])
    return _simulated(mech, delta, p, a, s, weight, natural, (first, second), np.ones(len(p)))


def _body_angle(motion: Any) -> Array:
    """The angle of the coupler line the body's angle is offset from: A → B (four-bar,
    slider-crank), R → Q (double slider, which has no A)."""
    ends = ("A", "B") if "A" in motion.positions else ("R", "Q")
    line = np.asarray(motion.positions[ends[1]]) - np.asarray(motion.positions[ends[0]])
    return np.asarray(np.arctan2(line[..., 1], line[..., 0]))


def _misses(mech: Mechanism, delta: float, p: Array, a: Array, theta: Array) -> tuple[Array, Array]:
    """Position and angle misses at inputs ``theta`` (n, ...) of pose i along the first axis;
    the body's angle is the coupler line's plus ``delta``. Infinite where it cannot assemble."""
    flat = np.asarray(theta, dtype=float)
    motion = solve(mech, flat.ravel(), order=0)
    pos = np.asarray(motion.positions["P"]).reshape(flat.shape + (2,))
    turn = _body_angle(motion).reshape(flat.shape) + delta
    shape = (len(p),) + (1,) * (flat.ndim - 1)
    dp = np.linalg.norm(pos - p.reshape(shape + (2,)), axis=-1)
    da = np.abs(np.angle(np.exp(1j * (turn - a.reshape(shape)))))
    ok = np.asarray(motion.valid).reshape(flat.shape)
    return np.where(ok, dp, np.inf), np.where(ok, da, np.inf)


def _nearest_inputs(
    mech: Mechanism, delta: float, p: Array, a: Array, s: float, weight: float, natural: Array
) -> Array:
    """Each pose's input that brings the body nearest it (within half a radian of where the
    first dyad's own point puts the crank): a grid, then golden-section search, all poses at
    once."""

    def cost(theta: Array) -> Array:
        dp, da = _misses(mech, delta, p, a, theta)
        out = dp * dp + (weight * s * da) ** 2
        return np.where(np.isfinite(out), out, np.inf)

    offsets = np.linspace(-0.5, 0.5, 33)
    grid = natural[:, None] + offsets
    k = np.argmin(cost(grid), axis=1)
    step = offsets[1] - offsets[0]
    nearest = grid[np.arange(len(p)), k]
    best, least = golden_max(lambda t: -cost(t), nearest - step, nearest + step, steps=30)
    return np.asarray(np.where(-least <= cost(nearest), best, nearest))
