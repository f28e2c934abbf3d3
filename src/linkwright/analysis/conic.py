"""Conics: the ellipse a double slider traces, its coefficients, invariants and axes.

A conic is the six coefficients (A, B, C, D, E, F) of A·X² + B·XY + C·Y² + D·X + E·Y + F = 0,
stacked on a last axis of length 6. Its invariants are δ = B² − 4AC and
Δ = det [[A, B/2, D/2], [B/2, C, E/2], [D/2, E/2, F]] (paper 004, eqs. 4–5).

Kiper et al. (paper 004) write the double slider's ellipse in closed form (eq. 3) and scale any
ellipse's coefficients by k = −16Δ/δ² (eq. 10), after which δ² = −16Δ (eq. 9) and
A + C = a² + b², √(B² + (A − C)²) = a² − b² (eq. 11). The coefficients of eq. 3 already satisfy
eq. 9 for every double slider, not only the α = 90°, h = 0 trammel (SEED-NOTES): with
K = h² + cot α·(p + q)·h − p·q, δ = −4K² and Δ = −K⁴.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "ConicError",
    "conic_invariants",
    "conic_kind",
    "doubleslider_conic",
    "ellipse_axes",
    "ellipse_conic",
    "ellipse_distance",
    "normalise_conic",
]

Array = NDArray[np.float64]


class ConicError(ValueError):
    """Bad input to a conic helper (names the argument and the problem)."""


def conic_invariants(coeffs: ArrayLike) -> tuple[Array, Array]:
    """δ = B² − 4AC and Δ, the 3×3 determinant of the conic (paper 004, eqs. 4–5).

    Examples
    --------
    The unit circle X² + Y² − 1 = 0:

    >>> conic_invariants([1, 0, 1, 0, 0, -1])
    (np.float64(-4.0), np.float64(-1.0))
    """
    A, B, C, D, E, F = np.moveaxis(np.asarray(coeffs, dtype=float), -1, 0)
    delta = B * B - 4.0 * A * C
    big = (B * E * D - C * D * D - A * E * E - delta * F) / 4.0
    return delta, big


def conic_kind(coeffs: ArrayLike, *, tol: float = 1e-12) -> NDArray[np.str_]:
    """What the conic is: ``ellipse``, ``point``, ``imaginary ellipse``, ``parabola``,
    ``hyperbola`` or ``degenerate`` (a pair of lines, or not a conic at all).

    Scale-free tests, each against the rounding its own quantity carries: δ against the size
    of the quadratic part; for a central conic, its value f0 at the centre (which is −a²·λ for
    an ellipse) against the terms it was computed from, so a thin ellipse far from the origin
    is still an ellipse and only a true point or line pair is degenerate.

    Examples
    --------
    >>> conic_kind([[1, 0, 4, 0, 0, -4], [1, 0, 1, 0, 0, 1], [1, 0, -1, 0, 0, -1]]).tolist()
    ['ellipse', 'imaginary ellipse', 'hyperbola']
    >>> conic_kind([0, 0, 1, -1, 0, 0]).item(), conic_kind([1, 0, 1, 0, 0, 0]).item()
    ('parabola', 'point')
    """
    c = np.asarray(coeffs, dtype=float)
    A, B, C, D, E, F = np.moveaxis(c, -1, 0)
    quad = np.maximum.reduce([np.abs(A), np.abs(B), np.abs(C)])
    finite = np.all(np.isfinite(c), axis=-1)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        a, b, cc, d, e, f = (x / quad for x in (A, B, C, D, E, F))
        delta = b * b - 4.0 * a * cc
        flat_delta = np.abs(delta) <= 8 * tol * (b * b + 4.0 * np.abs(a * cc))
        x0 = (2.0 * cc * d - b * e) / delta
        y0 = (2.0 * a * e - b * d) / delta
        f0 = f + 0.5 * (d * x0 + e * y0)
        noise = np.abs(f) + 0.5 * (np.abs(d * x0) + np.abs(e * y0))
        centred_flat = np.abs(f0) <= 64 * tol * noise
        big = (b * e * d - cc * d * d - a * e * e - delta * f) / 4.0
        scale3 = np.maximum(1.0, np.maximum.reduce([np.abs(d), np.abs(e), np.abs(f)])) ** 3
        parabola_flat = np.abs(big) <= tol * scale3
    real = -np.sign(a + cc) * f0 > 0
    kind = np.where(
        flat_delta,
        np.where(parabola_flat, "degenerate", "parabola"),
        np.where(
            delta > 0,
            np.where(centred_flat, "degenerate", "hyperbola"),
            np.where(centred_flat, "point", np.where(real, "ellipse", "imaginary ellipse")),
        ),
    )
    return np.where(finite & (quad > 0), kind, "degenerate")


def normalise_conic(coeffs: ArrayLike) -> Array:
    """The coefficients scaled by k = −16Δ/δ² (paper 004, eq. 10), so that δ² = −16Δ.

    After this scaling an ellipse's coefficients are those of eq. 3 for every double slider that
    traces it, and A + C, √(B² + (A − C)²) are a² + b², a² − b² (eq. 11). NaN where the conic
    is not an ellipse (δ ≥ 0 or Δ = 0).

    Examples
    --------
    The ellipse X²/9 + Y² = 1 written with any scale comes back as X² + 9Y² − 9 = 0:

    >>> normalise_conic([2, 0, 18, 0, 0, -18]).round(12)
    array([ 1.,  0.,  9.,  0.,  0., -9.])
    """
    c = np.asarray(coeffs, dtype=float)
    delta, big = conic_invariants(c)
    ok = (delta < 0) & (big != 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.where(ok, -16.0 * big / (delta * delta), np.nan)
    return c * k[..., None]


def ellipse_axes(coeffs: ArrayLike) -> dict[str, Array]:
    """Centre, semi-axes and orientation of the ellipse of a conic (any scale).

    Returns ``center`` (``(..., 2)``), ``semi_major``, ``semi_minor`` and ``orientation`` (the
    major axis's direction, radians in (−π/2, π/2]). The centre solves the gradient's zero
    (paper 004, eq. 7); the axes come from the eigenvalues of the quadratic part, which is
    an independent route to eq. 11. NaN where the conic is not a real ellipse.

    Examples
    --------
    >>> e = ellipse_axes([1, 0, 9, -2, 0, -8])   # (X − 1)²/9 + Y² = 1
    >>> e["center"] + 0.0, float(e["semi_major"]), float(e["semi_minor"]), float(e["orientation"])
    (array([1., 0.]), 3.0, 1.0, 0.0)
    """
    c = np.asarray(coeffs, dtype=float)
    real = conic_kind(c) == "ellipse"
    A, B, C, D, E, F = np.moveaxis(c, -1, 0)
    delta = B * B - 4.0 * A * C
    with np.errstate(divide="ignore", invalid="ignore"):
        x0 = (2.0 * C * D - B * E) / delta
        y0 = (2.0 * A * E - B * D) / delta
        # The value of the conic at its centre: the quadratic part equals −f0 on the ellipse.
        f0 = F + 0.5 * (D * x0 + E * y0)
        half = 0.5 * np.hypot(A - C, B)
        mean = 0.5 * (A + C)
        lam_small, lam_big = mean - half, mean + half
        semi_major = np.sqrt(-f0 / lam_small)
        semi_minor = np.sqrt(-f0 / lam_big)
    # The major axis is the eigenvector of the smaller eigenvalue: angle ½·atan2(B, A − C) + 90°
    # in the usual atan2 order (paper 004 prints eq. 12 in spreadsheet order).
    orientation = 0.5 * np.arctan2(B, A - C) + 0.5 * np.pi
    orientation = np.where(orientation > 0.5 * np.pi, orientation - np.pi, orientation)
    nan = np.nan
    return {
        "center": np.where(real[..., None], np.stack((x0, y0), axis=-1), nan),
        "semi_major": np.where(real, semi_major, nan),
        "semi_minor": np.where(real, semi_minor, nan),
        "orientation": np.where(real, orientation, nan),
    }


def doubleslider_conic(mechanism: Any) -> Array:
    """The coefficients A..F of the double slider's ellipse, paper 004 eq. 3, as printed.

    ``mechanism`` is a :class:`~linkwright.mechanisms.DoubleSlider` (angles in radians). The
    result is already normalised (δ² = −16Δ, see the module notes).

    Examples
    --------
    Archimedes' trammel with p = 3, q = 1 along +x: X²/9 + Y² = 1, normalised.

    >>> from linkwright.mechanisms import DoubleSlider
    >>> m = DoubleSlider(M=[0, 0], alpha=np.pi / 2, beta=0.0, p=3, q=1)
    >>> doubleslider_conic(m).round(12) + 0.0
    array([ 1.,  0.,  9.,  0.,  0., -9.])
    """
    al, be = np.asarray(mechanism.alpha, float), np.asarray(mechanism.beta, float)
    p, q, h = (np.asarray(getattr(mechanism, k), float) for k in ("p", "q", "h"))
    x0, y0 = np.moveaxis(np.asarray(mechanism.M, dtype=float), -1, 0)
    s, c = np.sin, np.cos
    pq = p + q
    r = pq / s(al)
    A = (r * s(al + be) * s(be) + h) ** 2 + (r * s(al + be) * c(be) - p) ** 2
    B = -2.0 * (
        pq * pq * c(al + be) * s(al + be) / s(al) ** 2
        + r * (s(al + 2 * be) * h - c(al + 2 * be) * p)
    )
    C = (r * c(al + be) * s(be) + p) ** 2 + (r * c(al + be) * c(be) + h) ** 2
    D = -2.0 * A * x0 - B * y0
    E = -B * x0 - 2.0 * C * y0
    F = A * x0 * x0 + B * x0 * y0 + C * y0 * y0 - (p * p + h * h - r * (p * s(al) - h * c(al))) ** 2
    return np.stack(np.broadcast_arrays(A, B, C, D, E, F), axis=-1)


def ellipse_conic(
    center: ArrayLike, semi_major: ArrayLike, semi_minor: ArrayLike, orientation: ArrayLike
) -> Array:
    """The normalised coefficients A..F of the ellipse with the given centre, semi-axes and
    major-axis angle (radians): paper 004, eq. 6, with β the major axis's angle.

    Eq. 6 is eq. 3 for Archimedes' trammel (α = 90°, h = 0, p = a, q = ±b), so the result
    satisfies δ² = −16Δ (eq. 9) and :func:`normalise_conic` leaves it as it is.

    Examples
    --------
    X²/9 + Y² = 1 is X² + 9Y² − 9 = 0 once normalised; moved to (1, 2) and turned by 90°:

    >>> ellipse_conic([0, 0], 3, 1, 0.0) + 0.0
    array([ 1.,  0.,  9.,  0.,  0., -9.])
    >>> ellipse_conic([1, 2], 3, 1, np.pi / 2).round(12) + 0.0
    array([  9.,   0.,   1., -18.,  -4.,   4.])
    """
    x0, y0 = np.moveaxis(np.asarray(center, dtype=float), -1, 0)
    a2, b2 = np.asarray(semi_major, float) ** 2, np.asarray(semi_minor, float) ** 2
    s, c = np.sin(orientation), np.cos(orientation)
    A = a2 * s * s + b2 * c * c
    B = 2.0 * (b2 - a2) * s * c
    C = a2 * c * c + b2 * s * s
    D = -2.0 * A * x0 - B * y0
    E = -B * x0 - 2.0 * C * y0
    F = A * x0 * x0 + B * x0 * y0 + C * y0 * y0 - a2 * b2
    return np.stack(np.broadcast_arrays(A, B, C, D, E, F), axis=-1)


def ellipse_distance(
    points: ArrayLike,
    center: ArrayLike,
    semi_major: ArrayLike,
    semi_minor: ArrayLike,
    orientation: ArrayLike,
    *,
    iterations: int = 200,
) -> Array:
    """Orthogonal (shortest Euclidean) distance from points to an ellipse.

    ``points`` has shape ``(..., 2)``; the ellipse (centre ``(..., 2)``, semi-axes
    a ≥ b > 0, major axis at ``orientation`` radians; a < b is read as the same ellipse with
    its axes named the other way) broadcasts against the points' leading axes, so ``points``
    of shape ``batch + (n, 2)`` take ellipse arrays of shape ``batch + (1,)``. Raises
    :class:`ConicError` for non-finite input or a semi-axis that is not positive.

    In the ellipse's own frame, folded into the first quadrant, the nearest point is
    (a²u/(a² + t), b²v/(b² + t)) for the root t of the quartic
    (au/(a² + t))² + (bv/(b² + t))² = 1 that is larger than −b². On that branch the left side
    falls monotonically and is convex, so the root is bracketed, and Newton's method from the
    right start converges to it monotonically; bisection of the bracket finishes any point
    where Newton stalls (near the centre of a thin ellipse, near the evolute).
    The axes of the frame (u = 0 or v = 0) are the cases where the quartic degenerates and
    are taken in closed form. This is the construction of D. Eberly, *Distance from a point to
    an ellipse, an ellipsoid, or a hyperellipsoid* (Geometric Tools, 2013).

    Examples
    --------
    From the centre of X²/9 + Y² = 1 the nearest points are the ends of the minor axis; from
    (5, 0), the vertex (3, 0); (0, 1) lies on the ellipse:

    >>> ellipse_distance([[0, 0], [5, 0], [0, 1]], [0, 0], 3, 1, 0.0)
    array([1., 2., 0.])

    A circle is an ellipse with a = b; the point (3, 4) is 5 from the centre of the unit circle:

    >>> float(ellipse_distance([3, 4], [0, 0], 1, 1, 0.0))
    4.0
    """
    p = np.asarray(points, dtype=float)
    e0 = np.asarray(semi_major, dtype=float)
    e1 = np.asarray(semi_minor, dtype=float)
    centre = np.asarray(center, dtype=float)
    angle = np.asarray(orientation, dtype=float)
    if p.shape[-1:] != (2,) or centre.shape[-1:] != (2,):
        raise ConicError(
            f"points and center must be [x, y] on a last axis of 2, got shapes {p.shape} and "
            f"{centre.shape}"
        )
    for name, x in (("points", p), ("center", centre), ("orientation", angle)):
        if not np.all(np.isfinite(x)):
            raise ConicError(f"ellipse_distance: {name} must be finite")
    if not (np.all(np.isfinite(e0)) and np.all(np.isfinite(e1))):
        raise ConicError("ellipse_distance: the semi-axes must be finite")
    if np.any(e0 <= 0) or np.any(e1 <= 0):
        raise ConicError(
            f"ellipse_distance: the semi-axes must be positive, got {e0.ravel()[:3].tolist()} "
            f"and {e1.ravel()[:3].tolist()}"
        )
    # Semi-axes given the other way round: the same ellipse, its major axis turned by 90°.
    swap = e1 > e0
    e0, e1 = np.where(swap, e1, e0), np.where(swap, e0, e1)
    angle = np.where(swap, angle + 0.5 * np.pi, angle)
    rel = p - centre
    c, s = np.cos(angle), np.sin(angle)
    # Fold into the first quadrant of the ellipse's frame: the distance is symmetric.
    u = np.abs(rel[..., 0] * c + rel[..., 1] * s)
    v = np.abs(-rel[..., 0] * s + rel[..., 1] * c)
    u, v, e0, e1 = np.broadcast_arrays(u, v, e0, e1)
    with np.errstate(divide="ignore", invalid="ignore"):
        # v = 0: the nearest point is off the axis (on the arc above it) while u lies inside
        # the evolute's cusp a·u < a² − b², else the vertex (a, 0).
        inside = e0 * u < (e0 - e1) * (e0 + e1)
        x = e0 * u / ((e0 - e1) * (e0 + e1))
        on_axis = np.where(
            inside, np.hypot(e0 * x - u, e1 * np.sqrt(np.maximum(1.0 - x * x, 0.0))), u - e0
        )
        # u = 0 (and v > 0): the end of the minor axis. Otherwise solve for the root.
        z0, z1 = u / e0, v / e1
        g = z0 * z0 + z1 * z1 - 1.0
        r0 = (e0 / e1) ** 2
        rm = (e0 - e1) * (e0 + e1) / (e1 * e1)  # r0 − 1 without the cancellation
        # The unknown is w = 1 + t/b², the nearest point (r0·u/(w + rm), v/w). Near the
        # centre of a flat ellipse w → z1 is small; as a variable of its own it keeps its
        # relative precision, which t/b² = w − 1 would lose. The root lies in
        # [z1, 1] inside the ellipse and in [1, |(r0·z0, z1)|] outside it, r0 = (a/b)².
        # There k0² + k1² − 1, k0 = r0·z0/(w + rm), k1 = z1/w, is convex and falling, so
        # Newton's method from w = 1 (the root itself for a point on the ellipse) lands left
        # of the root after at most one step and then climbs to it monotonically; each step
        # also tightens the bracket, and bisection finishes whatever has not converged.
        general = (u > 0) & (v > 0) & (g != 0)
        lo = np.where(general, z1, 1.0)
        hi = np.where(general & (g > 0), np.hypot(r0 * z0, z1), 1.0)
        w = np.clip(1.0, lo, hi)
        done = ~general
        for _ in range(60):
            k0, k1 = r0 * z0 / (w + rm), z1 / w
            value = k0 * k0 + k1 * k1 - 1.0
            slope = -2.0 * (k0 * k0 / (w + rm) + k1 * k1 / w)
            lo = np.where(general & (value > 0), np.maximum(lo, w), lo)
            hi = np.where(general & (value < 0), np.minimum(hi, w), hi)
            step = np.clip(w - value / slope, lo, hi) - w
            # Converged: the step is below rounding, or the value is (k0² + k1² − 1 can not
            # be told from 0 to better than a few units of its terms' last digit).
            done |= (np.abs(step) <= 4e-16 * w) | (np.abs(value) <= 8e-16)
            w = np.where(done, w, w + step)
            if np.all(done):
                break
        lo, hi = np.where(done, w, lo), np.where(done, w, hi)
        for _ in range(iterations):
            mid = 0.5 * (lo + hi)
            if np.all((mid <= lo) | (mid >= hi) | done):
                break  # every bracket is down to adjacent floats
            value = (r0 * z0 / (mid + rm)) ** 2 + (z1 / mid) ** 2 - 1.0
            lo, hi = np.where(value > 0, mid, lo), np.where(value > 0, hi, mid)
        w = np.where(done, w, 0.5 * (lo + hi))
        # (x0 − u, x1 − v) = (1 − w)·(u/(w + rm), v/w), free of the cancellation near w = 1.
        nearest = np.abs(1.0 - w) * np.hypot(u / (w + rm), v / w)
    out = np.where(v > 0, np.where(u > 0, np.where(g == 0, 0.0, nearest), v - e1), on_axis)
    return np.abs(out)
