"""Function generation: a planar four-bar whose rocker angle follows a function of its crank angle.

:func:`freudenstein` finds the four-bar through three pairs (φi, ψi) of crank and rocker angles,
and :func:`freudenstein_fit` the one that follows more pairs best (least squares),
both measured from the frame line, from Freudenstein's equation (F. Freudenstein, "Approximate
synthesis of four-bar linkages", Trans. ASME 77 (1955) 853–861); :func:`chebyshev_spacing` and
:func:`function_pairs` turn a function y = f(x) over a range into such pairs by the textbook
route (Chebyshev spacing of the precision points), and :func:`function_error` measures the
structural error between the linkage and the function.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine import evaluate
from linkwright.geometry import plane
from linkwright.mechanisms import FourBar, solve
from linkwright.synthesis.precision_designs import (
    SAME_TOL,
    SINGULAR_TOL,
    FunctionDesign,
    PrecisionError,
    assembly_branches,
    batch_place,
    find_order_defect,
    first_true,
    simulate_design,
    wrap_angle,
)

__all__ = [
    "chebyshev_spacing",
    "freudenstein",
    "freudenstein_fit",
    "function_error",
    "function_pairs",
]

Array = NDArray[np.float64]


# --- function generation -------------------------------------------------------------------------


def freudenstein(phi: ArrayLike, psi: ArrayLike, frame: ArrayLike = 1.0) -> FunctionDesign:
    """The four-bar whose rocker angle is ψi when its crank angle is φi, i = 1, 2, 3.

    With the frame A0B0 of length d along +x, crank a at φ, rocker c at ψ (both from the frame
    line) and coupler b, the loop closes when (Freudenstein 1955)

        K1 cos ψ − K2 cos φ + K3 = cos(φ − ψ),
        K1 = d/a,  K2 = d/c,  K3 = (a² − b² + c² + d²)/(2ac),

    which is linear in K1..K3: three pairs fix them, and a = d/K1, c = d/K2,
    b² = a² + c² + d² − 2acK3 (= ‖Bj − Aj‖² at every pair, so a real four-bar exists whenever K1
    and K2 do not vanish). A negative a (c) puts the pin opposite φ (ψ) on the same link
    (``crank_offset``/``rocker_offset`` π). The assembly is the one the first pair needs; a
    branch defect (pairs needing different ones) is reported, not hidden.

    Parameters
    ----------
    phi, psi : (..., 3) the input and output angles of the precision pairs (radians).
    frame : the frame length d (batch shape), default 1.

    Raises
    ------
    PrecisionError : not exactly three pairs, coincident pairs, pairs whose equations are
        dependent, a zero K1 or K2 (an infinitely long crank or rocker: a slider), or a pair at
        which the crank pin lies on the rocker pivot (folded: the input does not fix ψ).

    Examples
    --------
    The pairs of a known four-bar (a = 1, b = 3, c = 2, d = 3) give back its links:

    >>> phi = np.radians([40.0, 75.0, 110.0])
    >>> ax, ay = np.cos(phi), np.sin(phi)
    >>> P, Q, R = 4 * (3 - ax), -4 * ay, 9 - 4 - (3 - ax) ** 2 - ay**2
    >>> psi = np.arctan2(Q, P) + np.arccos(R / np.hypot(P, Q))
    >>> d = freudenstein(phi, psi, frame=3.0)
    >>> [round(float(x), 9) for x in (d.mechanism.crank, d.mechanism.coupler, d.mechanism.rocker)]
    [1.0, 3.0, 2.0]
    >>> d.coefficients.round(9), bool(d.branch_defect), float(d.error.max()) < 1e-12
    (array([3.  , 1.5 , 1.25]), False, True)

    K3 = (1 − 9 + 4 + 9)/(2·1·2) = 1.25.

    Pairs with the same cosines give the same equation twice:

    >>> freudenstein(np.radians([30, -30, 60]), np.radians([100, -100, 120]))
    Traceback (most recent call last):
    ...
    linkwright.synthesis.precision_designs.PrecisionError: freudenstein: the equations of the pairs
    are dependent (relative determinant 0): no unique four-bar
    """
    what = "freudenstein"
    phi = np.asarray(phi, dtype=float)
    psi = np.asarray(psi, dtype=float)
    if phi.shape[-1:] != (3,) or psi.shape[-1:] != (3,):
        raise PrecisionError(
            f"{what}: needs exactly 3 (φ, ψ) pairs, got φ of shape {phi.shape} and ψ of shape "
            f"{psi.shape}"
        )
    if not (np.all(np.isfinite(phi)) and np.all(np.isfinite(psi))):
        raise PrecisionError(f"{what}: angles must be finite")
    d = np.asarray(frame, dtype=float)
    if not np.all(np.isfinite(d)) or np.any(d <= 0):
        raise PrecisionError(f"{what}: the frame must be a positive length, got {d.tolist()}")
    try:
        shape = np.broadcast_shapes(phi.shape[:-1], psi.shape[:-1], d.shape)
    except ValueError:
        raise PrecisionError(f"{what}: φ {phi.shape}, ψ {psi.shape} do not broadcast") from None
    phi = np.broadcast_to(phi, shape + (3,))
    psi = np.broadcast_to(psi, shape + (3,))
    d = np.broadcast_to(d, shape)
    for i, j in ((0, 1), (0, 2), (1, 2)):
        same = (np.abs(wrap_angle(phi[..., i] - phi[..., j])) <= SAME_TOL) & (
            np.abs(wrap_angle(psi[..., i] - psi[..., j])) <= SAME_TOL
        )
        at = first_true(same)
        if at is not None:
            raise PrecisionError(f"{what}: pairs {i + 1} and {j + 1} coincide{batch_place(at)}")
    rows = np.stack((np.cos(psi), -np.cos(phi), np.ones_like(phi)), axis=-1)
    rhs = np.cos(phi - psi)
    det = np.linalg.det(rows) / np.prod(np.linalg.norm(rows, axis=-1), axis=-1)
    at = first_true(np.abs(det) < SINGULAR_TOL)
    if at is not None:
        raise PrecisionError(
            f"{what}: the equations of the pairs are dependent (relative determinant "
            f"{abs(float(det[at])):.3g}){batch_place(at)}: no unique four-bar"
        )
    k = np.linalg.solve(rows, rhs[..., None])[..., 0]
    k1, k2, k3 = k[..., 0], k[..., 1], k[..., 2]
    # |K| = d/|a| beyond 1/SAME_TOL means a crank (rocker) too short to be a link.
    at = first_true((np.abs(k1) < SAME_TOL) | (np.abs(k2) < SAME_TOL))
    if at is not None:
        raise PrecisionError(
            f"{what}: K1 = {float(k1[at]):.6g}, K2 = {float(k2[at]):.6g}{batch_place(at)}: a zero "
            "K "
            "makes the crank or rocker infinitely long (the pairs ask for a slider)"
        )
    a = d / k1
    c = d / k2
    # b² is |Bj − Aj|² at every pair (the equation times 2ac), so never negative: it vanishes
    # only where the pairs put the crank pin on the rocker pin.
    b2 = a**2 + c**2 + d**2 - 2 * a * c * k3
    at = first_true(b2 <= (SAME_TOL * d) ** 2)
    if at is not None:
        raise PrecisionError(
            f"{what}: K = {k[at].round(9).tolist()}{batch_place(at)} gives the coupler b² = "
            f"{float(b2[at]):.3g}: the pairs put the crank pin on the rocker pin"
        )
    crank_offset = np.where(a < 0, np.pi, 0.0)
    rocker_offset = np.where(c < 0, np.pi, 0.0)
    inputs = wrap_angle(phi + crank_offset[..., None])
    outputs = wrap_angle(psi + rocker_offset[..., None])
    a, c = np.abs(a), np.abs(c)
    A0 = np.zeros(shape + (2,))
    B0 = np.stack((d, np.zeros_like(d)), axis=-1)
    A = plane.polar(a[..., None], inputs)
    B = B0[..., None, :] + plane.polar(c[..., None], outputs)
    branches = assembly_branches(A0, B0, A, B, d, what)
    mech = FourBar(A0=A0, B0=B0, crank=a, coupler=np.sqrt(b2), rocker=c, assembly=branches[..., 0])
    motion = simulate_design(mech, inputs, branches)
    rel = motion.positions["B"] - motion.positions["B0"]
    error = np.abs(wrap_angle(np.arctan2(rel[..., 1], rel[..., 0]) - outputs))
    return FunctionDesign(
        mechanism=mech,
        coefficients=k,
        inputs=inputs,
        outputs=outputs,
        crank_offset=crank_offset,
        rocker_offset=rocker_offset,
        branches=branches,
        branch_defect=np.any(branches != branches[..., :1], axis=-1),
        order_defect=find_order_defect(mech, inputs),
        error=error,
    )


def chebyshev_spacing(start: ArrayLike, end: ArrayLike, n: int = 3) -> Array:
    """Chebyshev's precision points on [start, end]: the n zeros of the Chebyshev polynomial.

    xj = (start + end)/2 − (end − start)/2 · cos((2j − 1)π/(2n)), j = 1..n: the spacing that
    (nearly) minimises the largest structural error of an n-point function generator (Freudenstein
    1955; Hartenberg and Denavit, *Kinematic Synthesis of Linkages*, 1964, §11).

    Parameters
    ----------
    start, end : the range of x (broadcast together).
    n : how many precision points (≥ 1).

    Returns
    -------
    ``broadcast(start, end).shape + (n,)``, increasing from start to end.

    Examples
    --------
    >>> chebyshev_spacing(0.0, 1.0).round(6)
    array([0.066987, 0.5     , 0.933013])
    >>> chebyshev_spacing(1.0, 1.0)
    Traceback (most recent call last):
    ...
    linkwright.synthesis.precision_designs.PrecisionError: chebyshev_spacing: the range [1.0, 1.0]
    is empty
    """
    if int(n) != n or n < 1:
        raise PrecisionError(f"chebyshev_spacing: n must be a positive integer, got {n!r}")
    s = np.asarray(start, dtype=float)
    e = np.asarray(end, dtype=float)
    s, e = np.broadcast_arrays(s, e)
    at = first_true(~np.isfinite(s) | ~np.isfinite(e) | (s == e))
    if at is not None:
        raise PrecisionError(
            f"chebyshev_spacing: the range [{float(s[at])}, {float(e[at])}] is "
            f"empty{batch_place(at)}"
        )
    j = np.arange(1, int(n) + 1)
    nodes: Array = (s + e)[..., None] / 2 - (e - s)[..., None] / 2 * np.cos(
        (2 * j - 1) * np.pi / (2 * n)
    )
    return nodes


def _linear_map(value: Array, lo: Array, hi: Array, to_lo: Array, to_hi: Array) -> Array:
    return to_lo + (value - lo) / (hi - lo) * (to_hi - to_lo)


def _ranges(
    f: Callable[[Array], ArrayLike],
    x_range: ArrayLike,
    phi_range: ArrayLike,
    psi_range: ArrayLike,
    what: str,
) -> tuple[Array, Array, Array, Array, Array, Array]:
    """x0, x1, f(x0), f(x1) and the (…, 2) angle ranges, checked to span ranges."""
    xs, phis, psis = (np.asarray(r, dtype=float) for r in (x_range, phi_range, psi_range))
    for name, r in (("x_range", xs), ("phi_range", phis), ("psi_range", psis)):
        if r.shape[-1:] != (2,):
            raise PrecisionError(f"{what}: {name} must be (start, end) pairs, got shape {r.shape}")
    x0, x1 = xs[..., 0], xs[..., 1]
    y0, y1 = np.asarray(f(x0), dtype=float), np.asarray(f(x1), dtype=float)
    for name, lo, hi in (
        ("x_range", x0, x1),
        ("f(x_range)", y0, y1),
        ("phi_range", phis[..., 0], phis[..., 1]),
        ("psi_range", psis[..., 0], psis[..., 1]),
    ):
        at = first_true(
            np.broadcast_to(~np.isfinite(lo) | ~np.isfinite(hi) | (lo == hi), np.shape(lo))
        )
        if at is not None:
            raise PrecisionError(
                f"{what}: {name} must span a range, got [{float(np.asarray(lo)[at])}, "
                f"{float(np.asarray(hi)[at])}]{batch_place(at)}"
            )
    return x0, x1, y0, y1, phis, psis


def function_pairs(
    f: Callable[[Array], ArrayLike],
    x_range: ArrayLike,
    phi_range: ArrayLike,
    psi_range: ArrayLike,
    n: int = 3,
) -> tuple[Array, Array, Array]:
    """Precision pairs (φ, ψ) for generating y = f(x) over a range: the textbook route.

    x runs over [x0, x1] as the crank turns linearly from φ0 to φ1, y = f(x) over [f(x0), f(x1)]
    as the rocker turns linearly from ψ0 to ψ1; the precision points are Chebyshev-spaced in x
    (:func:`chebyshev_spacing`).

    Parameters
    ----------
    f : the function, vectorised (called on arrays of x).
    x_range : (..., 2) the range (x0, x1).
    phi_range, psi_range : (..., 2) the crank's and the rocker's angles at x0 and at x1
        (radians, from the frame line): the designer's free choices.
    n : how many pairs (3 for :func:`freudenstein`).

    Returns
    -------
    (x, φ, ψ), each ``batch + (n,)``.

    Examples
    --------
    y = log10 x on [1, 2] (Freudenstein's own example function), the crank from 30° to 120°,
    the rocker from 60° to 150°:

    >>> x, phi, psi = function_pairs(np.log10, (1, 2), np.radians([30, 120]),
    ...                              np.radians([60, 150]))
    >>> x.round(6), np.degrees(phi).round(6), np.degrees(psi).round(6)
    (array([1.066987, 1.5     , 1.933013]), array([ 36.028857,  75.      , 113.971143]),
     array([ 68.41887 , 112.646625, 145.576601]))
    """
    what = "function_pairs"
    x0, x1, y0, y1, phis, psis = _ranges(f, x_range, phi_range, psi_range, what)
    x = chebyshev_spacing(x0, x1, n)
    y = np.asarray(f(x), dtype=float)
    if not np.all(np.isfinite(y)):
        raise PrecisionError(f"{what}: f is not finite at the precision points x = {x.tolist()}")
    phi = _linear_map(x, x0[..., None], x1[..., None], phis[..., :1], phis[..., 1:])
    psi = _linear_map(y, y0[..., None], y1[..., None], psis[..., :1], psis[..., 1:])
    return x, phi, psi


def function_error(
    design: FunctionDesign,
    f: Callable[[Array], ArrayLike],
    x_range: ArrayLike,
    phi_range: ArrayLike,
    psi_range: ArrayLike,
    samples: int = 101,
) -> tuple[Array, Array]:
    """The structural error of a function generator: generated y minus f(x), over the range.

    The design's four-bar is simulated by the engine on its own assembly at the inputs that the
    linear map of :func:`function_pairs` gives x; its output angle is mapped back to y. The
    error vanishes at the precision points.

    Returns
    -------
    (x, error), each ``batch + (samples,)``; the error is NaN where the four-bar cannot assemble
    (its input cannot reach that x).

    Examples
    --------
    >>> rng = ((1, 2), np.radians([30, 120]), np.radians([60, 150]))
    >>> design = freudenstein(*function_pairs(np.log10, *rng)[1:])
    >>> x, err = function_error(design, np.log10, *rng, samples=5)
    >>> x, (err * 1e5).round()
    (array([1.  , 1.25, 1.5 , 1.75, 2.  ]), array([141., -68.,  -0.,  -5.,  23.]))

    (in units of 1e-5, against log10 2 ≈ 0.301 over the range).

    The same route for y = x² on [0, 1] (crank 45°–135°, rocker 135°–225°) has a branch defect:
    the third pair needs the other assembly, so the four-bar, on the first pair's, misses it.

    >>> rng = ((0, 1), np.radians([45, 135]), np.radians([135, 225]))
    >>> design = freudenstein(*function_pairs(np.square, *rng)[1:])
    >>> design.branches, bool(design.branch_defect)
    (array([-1., -1.,  1.]), True)
    """
    what = "function_error"
    x0, x1, y0, y1, phis, psis = _ranges(f, x_range, phi_range, psi_range, what)
    t = np.linspace(0.0, 1.0, int(samples))
    x = x0[..., None] + (x1 - x0)[..., None] * t
    phi = _linear_map(x, x0[..., None], x1[..., None], phis[..., :1], phis[..., 1:])
    y = np.asarray(f(x), dtype=float)
    psi = _linear_map(y, y0[..., None], y1[..., None], psis[..., :1], psis[..., 1:])
    mech = design.mechanism
    theta = phi + np.asarray(design.crank_offset)[..., None]
    motion = evaluate(mech.plan, mech.params(), theta, points=mech.points, order=0)
    rel = motion.positions["B"] - motion.positions["B0"]
    out = np.arctan2(rel[..., 1], rel[..., 0]) - np.asarray(design.rocker_offset)[..., None]
    # The angle error, turned into y by the linear map's slope.
    slope = (y1 - y0)[..., None] / (psis[..., 1:] - psis[..., :1])
    return x, wrap_angle(out - psi) * slope


def freudenstein_fit(phi: ArrayLike, psi: ArrayLike, frame: float = 1.0) -> FunctionDesign:
    """The four-bar whose rocker angle best follows ψi at crank angles φi, i = 1..n (n ≥ 3).

    Three pairs are met exactly (:func:`freudenstein`). More are fitted in two steps. First
    Freudenstein's equation K1 cos ψ − K2 cos φ + K3 = cos(φ − ψ), linear in K1..K3, in least
    squares over every pair (the algebraic fit, as in the least-squares Freudenstein method of
    Hartenberg and Denavit, *Kinematic Synthesis of Linkages*, 1964, §11); its crank and rocker,
    with the coupler that best closes the loop at the pairs, start the second step: the sum of
    squared output-angle errors at the pairs (the structural error there, the quantity a
    designer reads) minimised over the crank, coupler and rocker lengths, the frame held, on the
    assembly the first pair needs. Every output is simulated by the engine.

    Parameters
    ----------
    phi, psi : (n,) input and output angles (radians, from the frame line), n ≥ 3.
    frame : the frame length d.

    Returns
    -------
    FunctionDesign
        With n pairs; ``error`` is the output-angle error at each (0 for three pairs, up to
        rounding), ``coefficients`` the final linkage's K1..K3.

    Raises
    ------
    PrecisionError
        For fewer than three pairs, non-finite angles, a frame that is not a positive length,
        pairs whose equations do not fix K1..K3 (all pairs on one line of the K-space), or an
        algebraic fit that asks for an infinite crank or rocker (a slider).

    Examples
    --------
    Seven pairs of a known four-bar (a = 1, b = 3, c = 2, d = 3) give back its links:

    >>> phi = np.radians(np.linspace(40.0, 130.0, 7))
    >>> ax, ay = np.cos(phi), np.sin(phi)
    >>> P, Q, R = 4 * (3 - ax), -4 * ay, 9 - 4 - (3 - ax) ** 2 - ay**2
    >>> psi = np.arctan2(Q, P) + np.arccos(R / np.hypot(P, Q))
    >>> d = freudenstein_fit(phi, psi, frame=3.0)
    >>> [round(float(x), 9) for x in (d.mechanism.crank, d.mechanism.coupler, d.mechanism.rocker)]
    [1.0, 3.0, 2.0]
    >>> bool(d.error.max() < 1e-10)
    True

    log10 on [1, 2] through eleven evenly spaced pairs (crank 30°–120°, rocker 60°–150°): no
    four-bar generates it exactly; the fit's largest error is under a quarter of a degree (the
    three-point Chebyshev design of :func:`function_error`'s example misses by 0.42° at x = 1):

    >>> x = np.linspace(1, 2, 11)
    >>> phi, psi = np.radians(30 + 90 * (x - 1)), np.radians(60 + 90 * np.log10(x) / np.log10(2))
    >>> fit = freudenstein_fit(phi, psi)
    >>> bool(0 < np.degrees(fit.error.max()) < 0.25)
    True
    """
    from scipy.optimize import least_squares

    what = "freudenstein_fit"
    phi = np.asarray(phi, dtype=float).ravel()
    psi = np.asarray(psi, dtype=float).ravel()
    if phi.shape != psi.shape or phi.size < 3:
        raise PrecisionError(f"{what}: needs n ≥ 3 (φ, ψ) pairs, got {phi.size} and {psi.size}")
    if phi.size == 3:
        return freudenstein(phi, psi, frame)
    if not (np.all(np.isfinite(phi)) and np.all(np.isfinite(psi))):
        raise PrecisionError(f"{what}: angles must be finite")
    d = float(frame)
    if not (np.isfinite(d) and d > 0):
        raise PrecisionError(f"{what}: the frame must be a positive length, got {frame!r}")
    rows = np.stack((np.cos(psi), -np.cos(phi), np.ones_like(phi)), axis=-1)
    scaled = rows / np.linalg.norm(rows, axis=-1, keepdims=True)
    if np.linalg.svd(scaled, compute_uv=False)[-1] < SINGULAR_TOL:
        raise PrecisionError(
            f"{what}: the equations of the pairs are dependent: they do not fix K1, K2, K3"
        )
    k = np.linalg.lstsq(rows, np.cos(phi - psi), rcond=None)[0]
    if min(abs(k[0]), abs(k[1])) < SAME_TOL:
        raise PrecisionError(
            f"{what}: the algebraic fit gives K1 = {k[0]:.6g}, K2 = {k[1]:.6g}: a zero K makes "
            "the crank or rocker infinitely long (the pairs ask for a slider)"
        )
    a, c = d / k[0], d / k[1]
    crank_offset, rocker_offset = (np.pi if a < 0 else 0.0), (np.pi if c < 0 else 0.0)
    inputs = wrap_angle(phi + crank_offset)
    outputs = wrap_angle(psi + rocker_offset)
    a, c = abs(a), abs(c)
    A0, B0 = np.zeros(2), np.array([d, 0.0])
    # The coupler that best closes the loop at the pairs (the algebraic b² may be negative).
    A, B = plane.polar(a, inputs), B0 + plane.polar(c, outputs)
    b = float(np.sqrt(np.mean(np.sum((B - A) ** 2, axis=-1))))
    assembly = float(assembly_branches(A0, B0, A, B, np.asarray(d), what)[0])

    def linkage(x: Array) -> FourBar:
        a_, b_, c_ = np.exp(x)
        return FourBar(A0=A0, B0=B0, crank=a_, coupler=b_, rocker=c_, assembly=assembly)

    def residuals(x: Array) -> Array:
        motion = solve(linkage(x), inputs, order=0)
        rel = motion.positions["B"] - B0
        miss = wrap_angle(np.arctan2(rel[..., 1], rel[..., 0]) - outputs)
        # A pair the linkage cannot reach counts as half a turn off.
        return np.where(motion.valid, miss, np.pi)

    best = least_squares(residuals, np.log([a, b, c]), method="trf", x_scale="jac")
    mech = linkage(best.x)
    a, b, c = (float(v) for v in (mech.crank, mech.coupler, mech.rocker))
    signed_a = -a if crank_offset else a
    signed_c = -c if rocker_offset else c
    coefficients = np.array(
        [d / signed_a, d / signed_c, (a * a - b * b + c * c + d * d) / (2 * signed_a * signed_c)]
    )
    branches = np.full(phi.shape, assembly)
    return FunctionDesign(
        mechanism=mech,
        coefficients=coefficients,
        inputs=inputs,
        outputs=outputs,
        crank_offset=np.asarray(crank_offset),
        rocker_offset=np.asarray(rocker_offset),
        branches=branches,
        branch_defect=np.asarray(False),
        order_defect=find_order_defect(mech, inputs),
        error=np.abs(residuals(best.x)),
    )
