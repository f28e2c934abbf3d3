"""Ellipse → double slider: every elliptic trammel that draws a given ellipse (paper 004).

Kiper, Akbalçık and Şen (paper 004) scale the ellipse's coefficients by k = −16Δ/δ² (eq. 10),
after which Archimedes' trammel (α = 90°, h = 0) is read off in closed form: the centre from
the gradient's zero (eq. 7), the semi-axes from A + C = a² + b², √(B² + (A − C)²) = a² − b²
(eq. 11), the axis angle from eq. 12 (printed in spreadsheet ATAN2(x, y) order; in the usual
order β = ½·atan2(−B, C − A)). Section 4 then relocates the two sliders on the moving (Cardan)
circle, which leaves the coupler's motion, and so the ellipse, as it was: an ∞² family.

Two facts the paper leaves implicit, both derived in :func:`doubleslider_family` and checked
in the tests:

- There are two Cardan circles per ellipse, not one. The paper's section 3 trammel
  (|RP| = a, |QP| = b, P between R and Q) rolls a circle of radius (a + b)/2; its section 4
  builds on |RQ| = a − b (P beyond Q, q = −b), a circle of radius (a − b)/2. Both trace the
  ellipse, and every double slider that traces it belongs to one of the two families
  (``circle="small"`` or ``"large"``).
- The family's parameters can be the directions of the two slider lines, measured from the
  ellipse's major axis: these are the paper's α2 (for R′) and α1 (for Q′), and α = α2 − α1.

Fitting the ellipse to measured points is Fitzgibbon, Pilu and Fisher's direct least squares
(*Direct least square fitting of ellipses*, IEEE TPAMI 21(5), 1999; paper 004's ref. [7]) in
the partitioned form of Halíř and Flusser (*Numerically stable direct least squares fitting of
ellipses*, WSCG 1998).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.analysis.conic import (
    conic_invariants,
    conic_kind,
    ellipse_conic,
    ellipse_distance,
)
from linkwright.mechanisms import DoubleSlider, solve
from linkwright.mechanisms.base import Mechanism

__all__ = [
    "EllipseError",
    "EllipseFit",
    "Trammel",
    "check_on_ellipse",
    "doubleslider_family",
    "doubleslider_from_ellipse",
    "ellipse_synthesis",
    "family_angles",
    "fit_ellipse",
    "trammel_from_conic",
]

Array = NDArray[np.float64]

CIRCLES = ("small", "large")
# A double slider refuses |sin α| ≤ 1e-12 (parallel slider lines); the family does the same.
_PARALLEL = 1e-12
# A fitted ellipse this many times larger than the points' RMS radius is a parabola or a line
# pair in all but rounding.
_UNBOUNDED = 1e6


class EllipseError(ValueError):
    """The input is not an ellipse a double slider can trace (names the problem and numbers)."""


@dataclass(frozen=True)
class Trammel:
    """An ellipse as Archimedes' trammel reads it (paper 004, section 3).

    ``X0``, ``Y0``: the centre (the crossing M of the slider lines); ``beta``: the major axis's
    angle (radians, in (−90°, 90°]; the line of slider Q); ``a`` ≥ ``b`` > 0: the semi-axes
    (|RP| and |QP| of the trammel). Fields may be arrays of one batch shape.
    """

    X0: Array
    Y0: Array
    beta: Array
    a: Array
    b: Array

    @property
    def center(self) -> Array:
        """The centre as a point, shape ``batch + (2,)``."""
        return np.stack(np.broadcast_arrays(self.X0, self.Y0), axis=-1)

    def conic(self) -> Array:
        """The normalised coefficients A..F of this ellipse (paper 004, eq. 6)."""
        return ellipse_conic(self.center, self.a, self.b, self.beta)


@dataclass(frozen=True)
class EllipseFit:
    """The ellipse fitted to points, and how far the points lie from it.

    ``coeffs``: A..F normalised by eq. 10 (so δ² = −16Δ); ``trammel``: its centre, axis angle
    and semi-axes; ``rms`` and ``max``: the root-mean-square and largest orthogonal distance of
    the points to the fitted ellipse (lengths, the points' units); ``count``: points used.
    """

    coeffs: Array
    trammel: Trammel
    rms: float
    max: float
    count: int


# ----------------------------------------------------------------------------------------------
# Coefficients → trammel (paper 004, eqs. 7–12)


def _conic_array(coeffs: ArrayLike) -> Array:
    try:
        c = np.asarray(coeffs, dtype=float)
    except (TypeError, ValueError) as exc:
        raise EllipseError(f"conic coefficients must be numbers A..F: {exc}") from None
    if c.ndim == 0 or c.shape[-1] != 6:
        raise EllipseError(
            f"a conic is six coefficients A, B, C, D, E, F (of AX² + BXY + CY² + DX + EY + F), "
            f"got shape {c.shape}"
        )
    if not np.all(np.isfinite(c)):
        bad = c[~np.all(np.isfinite(c), axis=-1)][:1].ravel().tolist()
        raise EllipseError(f"conic coefficients must be finite, got {bad}")
    return c


def _why_not(kind: str, c: Array) -> str:
    """A sentence naming what the conic ``c`` (one row) is, with the numbers that say so."""
    with np.errstate(all="ignore"):
        s = c / np.max(np.abs(c)) if np.any(c) else c
        delta, big = conic_invariants(s)
    shown = ", ".join(f"{x:.6g}" for x in c)
    reason = {
        "hyperbola": f"a hyperbola (δ = B² − 4AC = {delta:.6g} > 0, after scaling to max|·| = 1)",
        "parabola": "a parabola (δ = B² − 4AC = 0)",
        "imaginary ellipse": (
            f"an imaginary ellipse (δ = {delta:.6g} < 0 but C·Δ = {s[2] * big:.6g} > 0, eq. 5; "
            "no real point satisfies it)"
        ),
        "point": "a point ellipse (Δ = 0, eq. 5: it has no size)",
        "degenerate": "degenerate (a pair of lines, or A = B = C = 0: not a conic)",
    }[kind]
    return f"the conic [{shown}] is {reason}; a double slider traces only real ellipses"


def trammel_from_conic(coeffs: ArrayLike) -> Trammel:
    """Archimedes' trammel (α = 90°, h = 0) of an ellipse given by its coefficients.

    ``coeffs`` is A..F of AX² + BXY + CY² + DX + EY + F = 0 (shape ``(..., 6)``, any scale and
    sign). Following paper 004: the coefficients are scaled by k = −16Δ/δ² (eq. 10), which
    makes them eq. 6's; the centre solves the gradient's zero, X0 = (2CD − BE)/δ,
    Y0 = (2AE − BD)/δ (eq. 7); a² = (A + C + √(B² + (A − C)²))/2 (eq. 11); β is eq. 12 in the
    usual atan2 order, β = ½·atan2(−B, C − A) (the paper prints spreadsheet ATAN2(x, y) order).
    b is taken from eq. 9, ab = √(−δ)/2, rather than from eq. 11's difference, which rounds to
    a negative number on a very thin ellipse. The coefficients are first divided by their
    largest magnitude, so that δ² cannot overflow, and Δ in eq. 10 is evaluated as −δ·f0/4
    (f0 the conic's value at the centre; the same number, with a reliable sign).

    Raises :class:`EllipseError` naming the kind for a hyperbola, parabola, imaginary ellipse,
    point ellipse or degenerate conic, and for non-finite coefficients.

    Examples
    --------
    X²/9 + Y² = 1, given at any scale and sign, is the trammel with a = 3, b = 1 along +X:

    >>> t = trammel_from_conic([-2, 0, -18, 0, 0, 18])
    >>> float(t.X0), float(t.Y0), float(t.beta), float(t.a), float(t.b)
    (0.0, 0.0, 0.0, 3.0, 1.0)

    (X − 1)² + (Y − 2)²/4 = 1 is centred at (1, 2) with its major axis along +Y:

    >>> t = trammel_from_conic([4, 0, 1, -8, -4, 4])
    >>> float(t.X0), float(t.Y0), float(np.degrees(t.beta)), float(t.a), float(t.b)
    (1.0, 2.0, 90.0, 2.0, 1.0)

    A hyperbola is refused by name:

    >>> trammel_from_conic([1, 0, -1, 0, 0, -1])
    Traceback (most recent call last):
    ...
    linkwright.synthesis.ellipse.EllipseError: the conic [1, 0, -1, 0, 0, -1] is a hyperbola
    (δ = B² − 4AC = 4 > 0, after scaling to max|·| = 1); a double slider traces only real
    ellipses
    """
    c = _conic_array(coeffs)
    kind = conic_kind(c)
    bad = kind != "ellipse"
    if np.any(bad):
        first = np.argwhere(np.atleast_1d(bad))[0]
        row = np.atleast_2d(c)[tuple(first)] if c.ndim > 1 else c
        where = f" (conic {tuple(int(i) for i in first)} of the batch)" if c.ndim > 1 else ""
        raise EllipseError(_why_not(str(np.atleast_1d(kind)[tuple(first)]), row) + where)
    # Scaled and evaluated exactly as conic_kind does, so that the δ < 0 and the real centre
    # value it judged are the numbers used here, even on a segment-thin ellipse.
    quad = np.maximum.reduce([np.abs(c[..., 0]), np.abs(c[..., 1]), np.abs(c[..., 2])])
    with np.errstate(over="ignore", invalid="ignore"):
        A, B, C, D, E, F = (x / quad for x in np.moveaxis(c, -1, 0))
        delta = B * B - 4.0 * A * C
        x0 = (2.0 * C * D - B * E) / delta  # eq. 7, which is scale-free
        y0 = (2.0 * A * E - B * D) / delta
        # Eq. 10, k = −16Δ/δ², with Δ factored at the centre: Δ = −δ·f0/4, f0 the conic's
        # value there. The same number, but its sign is the one conic_kind judged real, where
        # Δ formed directly can round to 0 or to the wrong sign.
        f0 = F + 0.5 * (D * x0 + E * y0)
        k = 4.0 * f0 / delta
        A, B, C = k * A, k * B, k * C
        delta = k * k * delta
        a = np.sqrt(0.5 * (A + C + np.hypot(B, A - C)))
        b = np.sqrt(-delta) / (2.0 * a)
    sizes = np.stack(np.broadcast_arrays(x0, y0, a, b))
    if not (np.all(np.isfinite(sizes)) and np.all(b > 0)):
        raise EllipseError(
            "the ellipse's coefficients are out of floating-point range once scaled "
            f"(e.g. {np.atleast_2d(c)[0].tolist()}); scale the coordinates first"
        )
    beta = 0.5 * np.arctan2(-B, C - A)
    # atan2 gives −180° for −B = −0.0: keep β in (−90°, 90°] so an axis has one name.
    beta = np.where(beta <= -0.5 * np.pi, beta + np.pi, beta) + 0.0
    return Trammel(X0=x0 + 0.0, Y0=y0 + 0.0, beta=beta, a=a, b=b)


def _as_trammel(ellipse: ArrayLike | Trammel) -> Trammel:
    if isinstance(ellipse, Trammel):
        return ellipse
    return trammel_from_conic(ellipse)


# ----------------------------------------------------------------------------------------------
# The ∞² family (paper 004, section 4)


def _cardan(t: Trammel, circle: str) -> tuple[Array, Array]:
    """Radius r of the moving circle and distance d of P from its centre."""
    if circle not in CIRCLES:
        raise EllipseError(f"circle must be 'small' or 'large', got {circle!r}")
    a, b = np.asarray(t.a, float), np.asarray(t.b, float)
    if circle == "large":
        return 0.5 * (a + b), 0.5 * (a - b)
    round_ = a - b <= 1e-12 * a
    if np.any(round_):
        r = float(np.atleast_1d(a)[np.argmax(np.atleast_1d(round_))])
        raise EllipseError(
            f"a circle (a = b = {r:.6g}) has no small Cardan circle (its radius (a − b)/2 is 0, "
            "the sliders would coincide); use circle='large', whose trammel is the crank "
            "R–P of length a about the centre"
        )
    return 0.5 * (a - b), 0.5 * (a + b)


def doubleslider_family(
    ellipse: ArrayLike | Trammel, s1: ArrayLike, s2: ArrayLike, *, circle: str = "small"
) -> DoubleSlider:
    """The double slider of the ∞² family whose slider lines make angles s1 (R) and s2 (Q)
    with the ellipse's major axis (radians); vectorised over s1, s2 and the ellipse.

    ``ellipse`` is conic coefficients A..F (any scale) or a :class:`Trammel`. Every such
    double slider traces the ellipse.

    Derivation (Cardan motion, paper 004 section 4 and Bottema & Roth, *Theoretical
    Kinematics*, pp. 346–348). A circle of radius r rolls inside a fixed circle of radius 2r
    centred on the ellipse's centre M. In the ellipse's frame its centre is T = r·e^{iφ}, and
    rolling without slipping turns the moving plane by −φ, so the point at polar (ρ, ψ) about T
    is at r·e^{iφ} + ρ·e^{i(ψ − φ)}. For ρ = r (a point of the moving circle) this is
    2r·cos(φ − ψ/2)·e^{iψ/2}: a straight line through M at angle σ = ψ/2. A slider may
    therefore sit at any point of the moving circle, its guide the line through M at that
    point's σ. The point ρ = d, ψ = 0 runs on (r + d)·cos φ + i·(r − d)·sin φ: the ellipse with
    semi-axes r + d and |r − d| along the major axis. So r + d = a and |r − d| = b, which has
    two answers:

    - ``circle="small"``: r = (a − b)/2, d = (a + b)/2, P outside the moving circle (paper 004's
      section 4, built on the trammel p = a, q = −b);
    - ``circle="large"``: r = (a + b)/2, d = (a − b)/2, P inside it (section 3's trammel
      p = a, q = b).

    Put R and Q at the points of line angle s1 and s2. At φ = 0, R − Q = r(e^{2is1} − e^{2is2})
    = 2r·sin(s1 − s2)·e^{i(s1 + s2 + π/2)} and R − P = r·e^{2is1} − d. The double slider
    writes Q = R − (p + q)·e^{iθ}, P = R − (p + ih)·e^{iθ} with R's guide at α + β and Q's at
    β, so with e^{iθ} = e^{i(s1 + s2 + π/2)}:

        α = s1 − s2,  β = β_ellipse + s2,
        p = r·sin(s1 − s2) + d·sin(s1 + s2),  q = r·sin(s1 − s2) − d·sin(s1 + s2),
        h = d·cos(s1 + s2) − r·cos(s1 − s2).

    Then |QP|² = q² + h² = a²·sin²s2 + b²·cos²s2 and |RP|² = a²·sin²s1 + b²·cos²s1, paper
    004's eq. 14 (its f and g, with its α1 = s2 and α2 = s1), and |RQ| = 2r·|sin(s1 − s2)|, its
    d for the small circle. Since T, R, Q and P are then points of one moving plane, the
    double slider's own motion (one pose per θ) is the Cardan motion, and conversely any
    double slider's coupler moves on the Cardan circle through R, Q and M: the two families
    hold every double slider that traces the ellipse. Reflecting P in RQ (h → −h) is not in
    them: the mirror coupler traces another ellipse.

    Raises :class:`EllipseError` where s1 ≡ s2 (mod 180°): both sliders at one point of the
    circle, on one line (α = 0), and for ``circle="small"`` on a circle (a = b).

    Examples
    --------
    X²/9 + Y² = 1 with Q's guide along the major axis and R's at 90° is the paper's trammel
    p = a = 3, q = −b = −1 (P beyond Q); at 60° R's guide gives α = 60° and h ≠ 0:

    >>> m = doubleslider_family([1, 0, 9, 0, 0, -9], np.radians([90.0, 60.0]), 0.0)
    >>> np.degrees(m.alpha), m.p.round(12), m.q.round(12)
    (array([90., 60.]), array([3.      , 2.598076]), array([-1.      , -0.866025]))
    >>> m.h.round(12) + 0.0
    array([0. , 0.5])

    Both trace the ellipse:

    >>> bool(np.all(check_on_ellipse(m, [1, 0, 9, 0, 0, -9]) < 1e-14))
    True

    Equal line angles put both sliders on one line:

    >>> doubleslider_family([1, 0, 9, 0, 0, -9], 0.5, 0.5 + np.pi)
    Traceback (most recent call last):
    ...
    linkwright.synthesis.ellipse.EllipseError: slider_angles s1 = 28.6479°, s2 = 208.648° are
    equal modulo 180°: both sliders would be one point of the Cardan circle, their guides one
    line (α = 0)
    """
    t = _as_trammel(ellipse)
    try:
        s1, s2 = np.asarray(s1, dtype=float), np.asarray(s2, dtype=float)
    except (TypeError, ValueError) as exc:
        raise EllipseError(f"slider_angles must be numbers (radians): {exc}") from None
    if not (np.all(np.isfinite(s1)) and np.all(np.isfinite(s2))):
        raise EllipseError("slider_angles must be finite")
    r, d = _cardan(t, circle)
    diff, total = s1 - s2, s1 + s2
    parallel = np.abs(np.sin(diff)) <= _PARALLEL
    if np.any(parallel):
        i = np.argmax(np.atleast_1d(np.broadcast_to(parallel, np.broadcast(s1, s2).shape)))
        b1, b2 = (np.atleast_1d(np.broadcast_to(x, np.broadcast(s1, s2).shape)) for x in (s1, s2))
        raise EllipseError(
            f"slider_angles s1 = {np.degrees(b1[i]):.6g}°, s2 = {np.degrees(b2[i]):.6g}° are "
            "equal modulo 180°: both sliders would be one point of the Cardan circle, their "
            "guides one line (α = 0)"
        )
    shape = np.broadcast_shapes(np.shape(t.X0), np.shape(t.a), s1.shape, s2.shape)
    centre = np.broadcast_to(t.center, shape + (2,))
    return DoubleSlider(
        M=centre.copy(),
        alpha=np.broadcast_to(diff, shape).copy(),
        beta=np.broadcast_to(t.beta + s2, shape).copy(),
        p=np.broadcast_to(r * np.sin(diff) + d * np.sin(total), shape).copy(),
        q=np.broadcast_to(r * np.sin(diff) - d * np.sin(total), shape).copy(),
        h=np.broadcast_to(d * np.cos(total) - r * np.cos(diff), shape).copy(),
    )


def doubleslider_from_ellipse(
    ellipse: ArrayLike | Trammel, *, circle: str = "small"
) -> DoubleSlider:
    """Archimedes' trammel of an ellipse: α = 90°, h = 0, Q's guide along the major axis.

    ``circle="small"`` (the default) is paper 004's section 4 trammel p = a, q = −b (P beyond Q,
    |RQ| = a − b); ``"large"`` is section 3's p = a, q = b (P between R and Q, |RQ| = a + b).
    Both are members of :func:`doubleslider_family` (slider angles 90° and 0°), given here
    exactly. ``ellipse`` is coefficients A..F (any scale) or a :class:`Trammel`.

    Examples
    --------
    X²/9 + Y² = 1 turned by 45° and moved to (1, 2): 5X² − 8XY + 5Y² + 6X − 12Y = 0.

    >>> c = [5, -8, 5, 6, -12, 0]
    >>> m = doubleslider_from_ellipse(c)
    >>> m.M.round(12), float(np.degrees(m.alpha)), float(np.degrees(m.beta)), float(m.p), float(m.q)
    (array([1., 2.]), 90.0, 45.0, 3.0, -1.0)
    >>> float(doubleslider_from_ellipse(c, circle="large").q)
    1.0
    """
    t = _as_trammel(ellipse)
    _cardan(t, circle)  # refuses a circle for the small family
    shape = np.broadcast_shapes(np.shape(t.X0), np.shape(t.a))
    b = np.asarray(t.b) if circle == "large" else -np.asarray(t.b)
    return DoubleSlider(
        M=np.broadcast_to(t.center, shape + (2,)).copy(),
        alpha=np.full(shape, 0.5 * np.pi),
        beta=np.broadcast_to(t.beta, shape).copy(),
        p=np.broadcast_to(t.a, shape).copy(),
        q=np.broadcast_to(b, shape).copy(),
        h=np.zeros(shape),
    )


def family_angles(count: int, *, clearance_deg: float = 15.0) -> Array:
    """``count`` pairs (s1, s2) of slider angles (radians) spread over the torus [0°, 180°)²,
    keeping |s1 − s2| (mod 180°) at least ``clearance_deg`` from 0° (parallel guides).

    The pairs follow the two-dimensional additive recurrence of the plastic number (a
    low-discrepancy sequence), rounded to 0.01°, so any prefix is evenly spread and the list is
    the same on every call. Shape ``(count, 2)``.

    Examples
    --------
    >>> np.degrees(family_angles(3)).round(2)
    array([[ 45.88,  12.57],
           [  1.76, 115.14],
           [137.63,  37.71]])
    """
    if count < 0 or int(count) != count:
        raise EllipseError(f"family_samples must be a whole number ≥ 0, got {count}")
    if not 0.0 <= clearance_deg < 90.0:
        raise EllipseError(f"clearance_deg must lie in [0°, 90°), got {clearance_deg}")
    g = 1.324717957244746  # the plastic number: x³ = x + 1
    step = np.array([1.0 / g, 1.0 / g**2])
    out: list[Array] = []
    k = 0
    while len(out) < count:
        k += 1
        s = np.round(((0.5 + k * step) % 1.0) * 180.0, 2) % 180.0
        gap = abs((s[0] - s[1] + 90.0) % 180.0 - 90.0)
        if gap >= clearance_deg and s[0] != s[1]:
            out.append(np.radians(s))
    return np.reshape(np.array(out, dtype=float), (count, 2))


# ----------------------------------------------------------------------------------------------
# Checking and fitting


def check_on_ellipse(
    mech: Mechanism, ellipse: ArrayLike | Trammel, samples: int = 720
) -> float | Array:
    """The worst orthogonal distance of the traced point to the ellipse, over a full turn of
    the input, divided by the ellipse's semi-major axis.

    The mechanism (a planar one whose traced joint is P, e.g. a :class:`DoubleSlider`, batched
    or not) is simulated by :func:`linkwright.mechanisms.solve` at ``samples`` inputs over one
    turn; distances are the exact point-to-ellipse distances of
    :func:`linkwright.analysis.conic.ellipse_distance`. A float for one mechanism, an array
    of the batch shape for many; ∞ where the mechanism cannot assemble somewhere on the turn.

    Examples
    --------
    The trammel p = 3, q = 1 draws X²/9 + Y² = 1; turned by 10° it does not:

    >>> m = DoubleSlider(M=[0, 0], alpha=np.pi / 2, beta=np.radians([0.0, 10.0]), p=3, q=1)
    >>> check_on_ellipse(m, [1, 0, 9, 0, 0, -9]).round(6)
    array([0.      , 0.115762])
    """
    t = _as_trammel(ellipse)
    if mech.space != "plane":
        raise EllipseError(f"check_on_ellipse needs a planar linkage, got a {mech.space} one")
    if int(samples) != samples or samples < 3:
        raise EllipseError(f"samples must be a whole number ≥ 3, got {samples}")
    theta = np.linspace(0.0, 2.0 * np.pi, int(samples), endpoint=False)
    motion = solve(mech, theta, order=0)
    p = motion.positions[mech.traced_joint]
    dist = ellipse_distance(
        p,
        t.center[..., None, :],
        np.asarray(t.a)[..., None],
        np.asarray(t.b)[..., None],
        np.asarray(t.beta)[..., None],
    )
    worst = np.where(np.all(motion.valid, axis=-1), np.max(dist, axis=-1), np.inf)
    worst = worst / np.asarray(t.a)
    return float(worst) if np.ndim(worst) == 0 else worst


def fit_ellipse(points: ArrayLike) -> EllipseFit:
    """The ellipse that fits the points best in the algebraic sense, constrained to be an
    ellipse: Fitzgibbon, Pilu & Fisher's direct least squares, in Halíř & Flusser's stable
    partitioned form.

    ``points`` has shape ``(N, 2)``, N ≥ 5 distinct points, not all on one line. They are first
    moved to their centroid and scaled to unit RMS radius (the fit is not invariant to either,
    and the scatter matrix of raw coordinates can be badly conditioned). Writing the conic as
    a1·(x², xy, y²) + a2·(x, y, 1), the linear part is eliminated in closed form
    (a2 = −T·a1, T the least-squares solution of D2·T = D1), leaving the 3×3 generalised
    eigenproblem M·a1 = λ·C1·a1 with 4AC − B² = a1ᵀC1a1 > 0; its one eigenvector with
    4AC − B² > 0 is the ellipse. The result is mapped back to the points' frame and normalised
    by eq. 10 of paper 004.

    The residual is geometric: the RMS and the largest orthogonal distance of the points to
    the fitted ellipse.

    Raises :class:`EllipseError` for too few points, NaN or infinite coordinates, points on
    one line, and a best conic that is not a real ellipse (including points on a parabola or
    on two lines, whose best "ellipse" runs off to a semi-axis over 10⁶ times their spread).

    Examples
    --------
    Six points of X²/9 + Y² = 1 give it back, normalised (X² + 9Y² − 9 = 0), with residual 0:

    >>> t = np.radians([0, 50, 110, 170, 250, 300])
    >>> f = fit_ellipse(np.column_stack((3 * np.cos(t), np.sin(t))))
    >>> f.coeffs.round(9) + 0.0, f.rms < 1e-12
    (array([ 1.,  0.,  9.,  0.,  0., -9.]), True)
    >>> fit_ellipse([[0, 0], [1, 1], [2, 2], [3, 3], [5, 5]])
    Traceback (most recent call last):
    ...
    linkwright.synthesis.ellipse.EllipseError: the 5 points lie on one line (their spread
    across it is below 1e-10 of their spread along it): no ellipse fits them
    """
    try:
        p = np.asarray(points, dtype=float)
    except (TypeError, ValueError) as exc:
        raise EllipseError(f"points must be numbers [x, y]: {exc}") from None
    if p.ndim != 2 or p.shape[1] != 2:
        raise EllipseError(f"points must have shape (N, 2), got {p.shape}")
    if not np.all(np.isfinite(p)):
        rows = np.flatnonzero(~np.all(np.isfinite(p), axis=1))
        raise EllipseError(
            f"points must be finite: row {int(rows[0])} is {p[rows[0]].tolist()} "
            f"({rows.size} such rows)"
        )
    distinct = np.unique(p, axis=0).shape[0]
    if distinct < 5:
        raise EllipseError(
            f"an ellipse needs at least 5 distinct points, got {distinct} (of {p.shape[0]})"
        )
    mean = p.mean(axis=0)
    x = p - mean
    scale = float(np.sqrt(np.mean(np.sum(x * x, axis=1))))
    x = x / scale
    spread = np.linalg.svd(x, compute_uv=False)
    if spread[1] <= 1e-10 * spread[0]:
        raise EllipseError(
            f"the {p.shape[0]} points lie on one line (their spread across it is below 1e-10 "
            "of their spread along it): no ellipse fits them"
        )
    u, v = x[:, 0], x[:, 1]
    d1 = np.column_stack((u * u, u * v, v * v))
    d2 = np.column_stack((u, v, np.ones_like(u)))
    # a2 = −T·a1 minimises |D1·a1 + D2·a2| for fixed a1; what is left of D1 is its part
    # orthogonal to D2's columns, and M = residualᵀ·residual is symmetric by construction.
    t_mat = np.linalg.lstsq(d2, d1, rcond=None)[0]
    rest = d1 - d2 @ t_mat
    m = rest.T @ rest
    c1_inv = np.array([[0.0, 0.0, 0.5], [0.0, -1.0, 0.0], [0.5, 0.0, 0.0]])
    values, vectors = np.linalg.eig(c1_inv @ m)
    vectors = np.real(vectors)
    cond = 4.0 * vectors[0] * vectors[2] - vectors[1] ** 2
    ok = (cond > 0) & (np.abs(np.imag(values)) <= 1e-9 * max(1.0, float(np.max(np.abs(values)))))
    if not np.any(ok):
        raise EllipseError(
            f"no ellipse fits the {p.shape[0]} points: every stationary conic of the fit is a "
            "hyperbola or parabola"
        )
    # Of the admissible eigenvectors (theory says one), the one of least algebraic error.
    err = np.where(
        ok, np.einsum("ik,ij,jk->k", vectors, m, vectors) / np.where(ok, cond, 1), np.inf
    )
    a1 = vectors[:, int(np.argmin(err))]
    local = np.concatenate((a1, -t_mat @ a1))
    kind = str(conic_kind(local))
    if kind != "ellipse":
        raise EllipseError(
            f"the best conic through the {p.shape[0]} points is {kind}, not a real ellipse"
        )
    unit = trammel_from_conic(local)
    if unit.a > _UNBOUNDED:
        # The algebraic fit's limit is a parabola or a line pair (4AC − B² → 0 through
        # positive values): an "ellipse" far larger than the points is that limit, not a fit.
        raise EllipseError(
            f"the best conic through the {p.shape[0]} points is a parabola or a pair of lines "
            f"(as an ellipse its semi-major axis would be {float(unit.a):.3g} times the points' "
            "RMS radius), not an ellipse"
        )
    trammel = Trammel(
        X0=np.asarray(mean[0] + scale * unit.X0, dtype=np.float64),
        Y0=np.asarray(mean[1] + scale * unit.Y0, dtype=np.float64),
        beta=np.asarray(unit.beta, dtype=np.float64),
        a=np.asarray(scale * unit.a, dtype=np.float64),
        b=np.asarray(scale * unit.b, dtype=np.float64),
    )
    dist = ellipse_distance(p, trammel.center, trammel.a, trammel.b, trammel.beta)
    return EllipseFit(
        coeffs=trammel.conic(),
        trammel=trammel,
        rms=float(np.sqrt(np.mean(dist * dist))),
        max=float(np.max(dist)),
        count=int(p.shape[0]),
    )


# ----------------------------------------------------------------------------------------------
# The report behind ``linkwright synth ellipse``


def _member(m: DoubleSlider, i: int) -> DoubleSlider:
    return DoubleSlider(
        M=np.asarray(m.M)[i].copy(),
        alpha=float(np.asarray(m.alpha)[i]),
        beta=float(np.asarray(m.beta)[i]),
        p=float(np.asarray(m.p)[i]),
        q=float(np.asarray(m.q)[i]),
        h=float(np.asarray(m.h)[i]),
    )


def ellipse_synthesis(
    conic: ArrayLike | None = None,
    points: ArrayLike | None = None,
    family_samples: int = 0,
    *,
    circle: str = "small",
    samples: int = 720,
    progress: Callable[[float], None] | None = None,
) -> dict[str, Any]:
    """Double sliders for an ellipse given by its coefficients or by points to fit.

    Exactly one of ``conic`` (A..F, any scale) and ``points`` (``(N, 2)``) is given. Returns a
    plain dict (numbers are Python floats; mechanisms are left as :class:`DoubleSlider`
    objects for the caller to turn into documents):

    - ``source``: ``"conic"`` or ``"points"``;
    - ``conic``: the coefficients normalised by eq. 10 (the fitted ones for points);
    - ``fit`` (points only): ``count``, ``rms``, ``max`` (orthogonal distances of the points
      to the fitted ellipse) and ``rms_relative`` (over a);
    - ``trammel``: ``X0``, ``Y0``, ``beta_deg``, ``a``, ``b``;
    - ``circle``, ``cardan_radius``: which Cardan circle the family rolls (see
      :func:`doubleslider_family`) and its radius;
    - ``canonical``: ``mechanism`` (α = 90°, h = 0) and ``deviation``;
    - ``family``: ``family_samples`` entries ``slider_angles_deg`` [s1, s2], ``mechanism``,
      ``deviation``, the angles spread over the torus by :func:`family_angles`.

    Deviations are :func:`check_on_ellipse` values: the worst distance of the simulated P to
    the ellipse over a turn, relative to a. ``progress`` (optional) is called with the fraction
    done.

    Parameters
    ----------
    conic : array_like, shape (6,), optional
        The ellipse's coefficients A..F.
    points : array_like, shape (N, 2), optional
        Points to fit an ellipse to.
    family_samples : int
        How many members of the one-parameter family of double sliders to return.
    circle : {"small", "large"}
        Which Cardan circle the family rolls.
    samples : int
        Samples of a turn in each deviation check.
    progress : callable, optional
        Called with the fraction done.

    Returns
    -------
    dict
        The keys above.

    Examples
    --------
    >>> r = ellipse_synthesis(conic=[1, 0, 9, 0, 0, -9], family_samples=2)
    >>> r["trammel"], r["cardan_radius"]
    ({'X0': 0.0, 'Y0': 0.0, 'beta_deg': 0.0, 'a': 3.0, 'b': 1.0}, 1.0)
    >>> [f["slider_angles_deg"] for f in r["family"]]
    [[45.88, 12.57], [1.76, 115.14]]
    >>> max(f["deviation"] for f in r["family"]) < 1e-14
    True
    >>> ellipse_synthesis()
    Traceback (most recent call last):
    ...
    linkwright.synthesis.ellipse.EllipseError: give the ellipse either as conic coefficients
    or as points to fit, not neither
    """
    if (conic is None) == (points is None):
        which = "both" if conic is not None else "neither"
        raise EllipseError(
            f"give the ellipse either as conic coefficients or as points to fit, not {which}"
        )
    if int(family_samples) != family_samples or family_samples < 0:
        raise EllipseError(f"family_samples must be a whole number ≥ 0, got {family_samples}")

    def tick(x: float) -> None:
        if progress is not None:
            progress(x)

    tick(0.0)
    report: dict[str, Any] = {"source": "conic" if conic is not None else "points"}
    if points is not None:
        fit = fit_ellipse(points)
        t = fit.trammel
        coeffs = fit.coeffs
    else:
        assert conic is not None  # exactly one of the two is given (checked above)
        c = _conic_array(conic)
        if c.ndim != 1:
            raise EllipseError(f"give one conic (six coefficients), got shape {c.shape}")
        t = trammel_from_conic(c)
        # Normalised by eq. 10, from the trammel, so that the coefficients and the geometry
        # reported agree to the last digit.
        coeffs = t.conic()
    report["conic"] = [float(x) for x in coeffs]
    if points is not None:
        report["fit"] = {
            "count": fit.count,
            "rms": fit.rms,
            "max": fit.max,
            "rms_relative": fit.rms / float(t.a),
        }
    report["trammel"] = {
        "X0": float(t.X0),
        "Y0": float(t.Y0),
        "beta_deg": float(np.degrees(t.beta)),
        "a": float(t.a),
        "b": float(t.b),
    }
    r, _ = _cardan(t, circle)
    report["circle"] = circle
    report["cardan_radius"] = float(r)
    canonical = doubleslider_from_ellipse(t, circle=circle)
    report["canonical"] = {
        "mechanism": canonical,
        "deviation": float(check_on_ellipse(canonical, t, samples)),
    }
    tick(1.0 / (1 + family_samples))
    family: list[dict[str, Any]] = []
    angles = family_angles(int(family_samples))
    chunk = 256
    for start in range(0, len(angles), chunk):
        block = angles[start : start + chunk]
        members = doubleslider_family(t, block[:, 0], block[:, 1], circle=circle)
        dev = np.atleast_1d(check_on_ellipse(members, t, samples))
        for i, s in enumerate(block):
            family.append(
                {
                    "slider_angles_deg": [float(x) for x in np.round(np.degrees(s), 2)],
                    "mechanism": _member(members, i),
                    "deviation": float(dev[i]),
                }
            )
        tick((1 + start + len(block)) / (1 + family_samples))
    report["family"] = family
    tick(1.0)
    return report
