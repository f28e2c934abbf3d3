"""The Assur group of class III (the "triad"): every real pose, by a polynomial and by a sweep.

A triad is a rigid ternary body carrying three joints J1, J2, J3, each tied by a binary link of
length ``L_k`` to a known point ``K_k`` (a ground pivot, or a joint already placed). It is the
smallest group that a construction plan cannot build joint by joint: no joint is fixed by two
known ones, so the three loops close together. It appears in a Stephenson-III six-bar driven at
its output side, and in a Stephenson-II six-bar driven at a link that leaves its ternary
coupler held by three binaries.

Two independent solvers live here:

* :func:`triad_poses` eliminates the body's position and reduces the problem to one polynomial
  of degree 6 in ``z = e^{iφ}`` (φ the body's rotation), solved by eigenvalues of companion
  matrices for a whole batch at once; every root is rebuilt, polished by Newton's method on the
  original three equations, and kept only if it satisfies all three.
* :func:`sweep_roots` (with :func:`triad_poses_sweep` on top) needs no polynomial: one angle
  parametrises a one-degree-of-freedom chain, circle–circle intersections place the rest on both
  branches, and the roots of the last constraint are bracketed on a grid and bisected to the last
  bit. It is slower and serves as the cross-check (and for linkages with no polynomial form).

:func:`triad_rates` gives the joints' first and second derivatives from the differentiated
constraints, as the construction-plan steps do for dyads.

Conventions are the engine's: arrays broadcast over a leading batch shape, positions have a
trailing axis of 2, and a result is NaN exactly where it does not exist.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine.root_sweep import ResidualFn as ResidualFn
from linkwright.engine.root_sweep import SweptRoots, sweep_roots
from linkwright.engine.state import ASSEMBLY_TOL
from linkwright.geometry import plane

# A name imported `as` itself moved to a sibling module and is re-exported for older imports;
# a constant among them is read where it lives (set it there, not here).
__all__ = [
    "MAX_POSES",
    "SweptRoots",
    "TriadPoses",
    "TriadRates",
    "sweep_roots",
    "triad_poses",
    "triad_poses_sweep",
    "triad_rates",
]

Array = NDArray[np.float64]

MAX_POSES = 6
"""A triad has at most six real poses (the degree of its polynomial)."""

# A pose is kept when every link misses its length by less than this, relative to the triad's
# size: the engine's promise (DESIGN.md) for every solved position. It is also what tells the
# real roots of the polynomial from the complex ones that happen to lie near the unit circle.
RESIDUAL_TOL = 1e-10
# Roots of the polynomial within this distance of the unit circle are tried as real poses. A real
# double root (a pose at a singular position) splits under rounding into two roots about
# sqrt(eps) off the circle, so the band must be far wider than that; the residual test above,
# after polishing, is what decides.
ROOT_BAND = 1e-3
# Newton steps on the full three-equation system after the polynomial: its roots are accurate to
# about eps·condition, so two quadratically convergent steps reach rounding and a third is margin.
NEWTON_STEPS = 3
# Two poses closer than this (largest joint distance relative to the triad's size) are one pose:
# the two roots of a double root polish towards the same place, and only near-singular triads
# have genuinely distinct poses this close.
DEDUP_TOL = 1e-7
# Triads solved per chunk of a large batch (about 30 MB of work arrays each).
CHUNK = 4096
# The 3×3 derivative system is singular below this relative determinant (a pose where the triad
# gains mobility); derivatives there are reported as NaN rather than as huge wrong numbers.
SINGULAR_DET = 1e-8


@dataclass(frozen=True)
class TriadPoses:
    """Every real pose of a batch of triads.

    Attributes
    ----------
    joints : ``(..., 6, 3, 2)``, world positions of J1, J2, J3 for each pose; the real poses
        come first, sorted by ``angle``, and the padding after them is NaN.
    angle : ``(..., 6)``, the body's rotation φ in (−π, π] (the angle that turns the body's own
        frame into the world frame), NaN in the padding.
    count : ``(...,)``, the number of real poses (0 to 6).
    residual : ``(..., 6)``, the largest ``|distance − length|`` over the three links, divided by
        the triad's size, NaN in the padding.
    """

    joints: Array
    angle: Array
    count: NDArray[np.int_]
    residual: Array

    @property
    def valid(self) -> NDArray[np.bool_]:
        """``(..., 6)``: which slots hold a real pose."""
        return np.arange(MAX_POSES) < self.count[..., None]


@dataclass(frozen=True)
class TriadRates:
    """First and second derivatives of a triad's joints with respect to the input.

    Attributes
    ----------
    vel, acc : ``(..., 3, 2)``, velocity and acceleration of J1, J2, J3.
    omega, alpha : ``(...,)``, angular velocity and acceleration of the body.
    regular : ``(...,)``, the 3×3 system is regular; everything above is NaN where it is not.
    """

    vel: Array
    acc: Array
    omega: Array
    alpha: Array
    regular: NDArray[np.bool_]


# ----------------------------------------------------------------------------------------------
# Small batched helpers
# ----------------------------------------------------------------------------------------------


def _rotate(c: Array, s: Array, vec: Array) -> Array:
    """``vec`` turned by the angle whose cosine and sine are ``c`` and ``s``."""
    return np.stack((c * vec[..., 0] - s * vec[..., 1], s * vec[..., 0] + c * vec[..., 1]), axis=-1)


def _solve3(m: Array, r: Array) -> tuple[Array, Array]:
    """Solve ``m · x = r`` (3×3, batched) by Cramer's rule; returns ``(x, det)``.

    ``x`` is inf/NaN where ``det`` is 0: callers mask those, as :func:`plane.solve_2x2_rows`.
    """
    c0, c1, c2 = m[..., :, 0], m[..., :, 1], m[..., :, 2]

    def det3(a: Array, b: Array, c: Array) -> Array:
        return (
            a[..., 0] * (b[..., 1] * c[..., 2] - b[..., 2] * c[..., 1])
            - b[..., 0] * (a[..., 1] * c[..., 2] - a[..., 2] * c[..., 1])
            + c[..., 0] * (a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1])
        )

    det = det3(c0, c1, c2)
    with np.errstate(divide="ignore", invalid="ignore"):
        x = np.stack((det3(r, c1, c2), det3(c0, r, c2), det3(c0, c1, r)), axis=-1) / det[..., None]
    return x, det


def _conv(a: Array, b: Array) -> Array:
    """Product of two polynomials given by coefficient arrays (ascending powers, last axis)."""
    n, m = a.shape[-1], b.shape[-1]
    out = np.zeros(np.broadcast_shapes(a.shape[:-1], b.shape[:-1]) + (n + m - 1,), complex)
    for i in range(n):
        out[..., i : i + m] += a[..., i : i + 1] * b
    return out


def _horner(coef: Array, z: Array) -> Array:
    """Polynomial with ascending coefficients ``coef`` (..., n) at ``z`` (..., k)."""
    out = np.zeros(np.broadcast_shapes(coef.shape[:-1] + (1,), z.shape), complex)
    for i in range(coef.shape[-1] - 1, -1, -1):
        out = out * z + coef[..., i : i + 1]
    return out


def _broadcast_triad(
    anchors: ArrayLike, lengths: ArrayLike, body: ArrayLike
) -> tuple[Array, Array, Array, tuple[int, ...]]:
    anchors = np.asarray(anchors, dtype=float)
    lengths = np.asarray(lengths, dtype=float)
    body = np.asarray(body, dtype=float)
    if anchors.shape[-2:] != (3, 2) or body.shape[-2:] != (3, 2) or lengths.shape[-1:] != (3,):
        raise ValueError(
            "anchors and body must have shape (..., 3, 2) and lengths (..., 3); got "
            f"{anchors.shape}, {body.shape}, {lengths.shape}"
        )
    batch = np.broadcast_shapes(anchors.shape[:-2], lengths.shape[:-1], body.shape[:-2])
    return (
        np.broadcast_to(anchors, batch + (3, 2)),
        np.broadcast_to(lengths, batch + (3,)),
        np.broadcast_to(body, batch + (3, 2)),
        batch,
    )


def _triad_size(anchors: Array, lengths: Array, body: Array) -> Array:
    """The triad's size: its longest link, body side or anchor distance."""
    pairs = ((0, 1), (0, 2), (1, 2))
    sides = [plane.norm(body[..., i, :] - body[..., j, :]) for i, j in pairs]
    spans = [plane.norm(anchors[..., i, :] - anchors[..., j, :]) for i, j in pairs]
    size: Array = np.maximum.reduce([np.abs(lengths).max(axis=-1), *sides, *spans])
    return size


def _link_residual(joints: Array, anchors: Array, lengths: Array, size: Array) -> Array:
    """Largest ``|distance − length|`` over the three links, relative to ``size``."""
    gap = np.abs(plane.norm(joints - anchors) - lengths).max(axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        relative: Array = gap / size
    return relative


# ----------------------------------------------------------------------------------------------
# The polynomial solver
# ----------------------------------------------------------------------------------------------


def _triad_polynomial(k: Array, l: Array, c: Array) -> tuple[Array, Array, Array]:
    """Coefficients of the triad's polynomial and of the body position's numerator and divisor.

    Inputs are normalised (``k[..., 0] = c[..., 0] = 0``, size about 1) and complex: ``k`` the
    anchors, ``c`` the body joints, ``l`` the lengths. With ``Y = J1 − K1`` and the body turned
    by ``z = e^{iφ}``, link k (2, 3) reads ``|Y + z c_k − k_k|² = l_k²``; subtracting link 1
    (``Y Ȳ = l_1²``) leaves ``Ȳ w_k + Y w̄_k = 2 b_k``, linear in (Y, Ȳ), with
    ``w_k = z c_k − k_k`` and ``b_k = β_k + Re(k̄_k c_k z)``. Treating Y and Ȳ as independent
    (isotropic coordinates) gives ``Y = 2 num / Δ`` and ``Ȳ = −2 num* / Δ`` (num* the
    polynomial with conjugated coefficients and reversed powers, Δ imaginary on the circle),
    and link 1 becomes ``4 num num* + l_1² Δ² = 0``: a Laurent polynomial in z with powers
    −3..3, real on the unit circle (``4 |num|² − 4 l_1² (w_2 × w_3)²``).

    Returns ``(F, num, Δ)``: ascending coefficients for powers −3..3, −1..2 and −1..1.
    """
    g2, g3 = c[..., 1], c[..., 2]
    d2, d3 = k[..., 1], k[..., 2]

    def w(g: Array, d: Array) -> Array:  # powers 0..1
        return np.stack((-d, g), axis=-1)

    def wbar(g: Array, d: Array) -> Array:  # powers −1..0
        return np.stack((np.conj(g), -np.conj(d)), axis=-1)

    def b(g: Array, d: Array, lk: Array) -> Array:  # powers −1..1
        beta = 0.5 * (lk * lk - l[..., 0] ** 2 - abs(g) ** 2 - abs(d) ** 2)
        return np.stack((0.5 * d * np.conj(g), beta.astype(complex), 0.5 * np.conj(d) * g), axis=-1)

    b2, b3 = b(g2, d2, l[..., 1]), b(g3, d3, l[..., 2])
    num = _conv(b2, w(g3, d3)) - _conv(b3, w(g2, d2))  # powers −1..2
    # num* is num with conjugated coefficients and reversed powers (its value on the circle is
    # the conjugate of num's); F built from it is self-reciprocal by construction.
    num_star = np.conj(num[..., ::-1])  # powers −2..1
    delta = _conv(wbar(g2, d2), w(g3, d3)) - _conv(w(g2, d2), wbar(g3, d3))  # powers −1..1
    f = 4.0 * _conv(num, num_star)  # powers −3..3
    f[..., 1:6] += (l[..., 0] ** 2)[..., None] * _conv(delta, delta)
    f = 0.5 * (f + np.conj(f[..., ::-1]))
    return f, num, delta


def _tan_half_basis() -> Array:
    """``B[k + 3]``: ascending coefficients in t of ``(1 + it)^(3+k) (1 − it)^(3−k)``.

    With ``t = tan(φ/2)``, ``e^{iφ} = (1 + it)/(1 − it)``, so ``(1 + t²)³ Σ f_k e^{ikφ}`` is
    ``Σ f_k B_k(t)``, a polynomial of degree 6 in t.
    """
    plus, minus = np.array([1.0, 1j]), np.array([1.0, -1j])
    rows = []
    for k in range(-3, 4):
        poly = np.ones(1, complex)
        for _ in range(3 + k):
            poly = np.convolve(poly, plus)
        for _ in range(3 - k):
            poly = np.convolve(poly, minus)
        rows.append(poly)
    return np.array(rows)


_TAN_HALF = _tan_half_basis()
# Where the rotated parametrisation's t = ∞ may sit: the one of these angles at which |F| is
# largest. A trigonometric polynomial of degree 3 that is not zero cannot be small at 8 equally
# spaced angles, so the degree-6 polynomial in t keeps a leading coefficient of the size of the
# others and has no root near infinity.
_PIVOTS = np.arange(8) * (np.pi / 4)


def _real_angle_roots(f: Array) -> Array:
    """The roots ``z`` of ``Σ_{k=-3..3} f_k z^k`` (``f`` ascending, self-reciprocal), batched.

    The unit circle is mapped onto the real line by ``z = e^{iφ0} (1 + it)/(1 − it)``, with
    ``φ0 + π`` the pivot where |F| is largest, and the roots in t are the eigenvalues of
    companion matrices. Rows that are all zero or not finite give NaN. Where F has degree
    below 3 (two anchors or two body joints coincide), the polynomial in t keeps its degree 6
    and gains the root pair ``t = ±i``, i.e. ``z = 0`` and ``z = ∞``, far from the circle.
    """
    scale = np.abs(f).max(axis=-1)
    ok = np.isfinite(scale) & (scale > 0)
    f = np.where(ok[..., None], f, 1.0)
    at_pivots = (f[..., None, :] * np.exp(1j * np.outer(_PIVOTS, np.arange(-3, 4)))).sum(-1)
    phi0 = _PIVOTS[np.abs(at_pivots).argmax(axis=-1)] - np.pi
    turned = f * np.exp(1j * np.arange(-3, 4) * phi0[..., None])
    poly = (turned @ _TAN_HALF).real  # imaginary part is rounding: F is real on the circle
    comp = np.zeros(f.shape[:-1] + (6, 6))
    comp[..., 0, :] = -poly[..., 5::-1] / poly[..., 6:7]
    comp[..., np.arange(1, 6), np.arange(5)] = 1.0
    comp = np.where(ok[..., None, None], comp, 0.0)
    t = np.linalg.eigvals(comp) if comp.size else np.zeros(f.shape[:-1] + (6,), complex)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.exp(1j * phi0)[..., None] * (1.0 + 1j * t) / (1.0 - 1j * t)
    return np.where(ok[..., None], z, np.nan)


def _newton(x: Array, phi: Array, k: Array, l: Array, c: Array, steps: int) -> tuple[Array, Array]:
    """Polish poses (``x`` = J1, ``phi``) on the three link equations ``|J_k − K_k|² = l_k²``.

    Arrays: x (..., m, 2), phi (..., m); k, c (..., 1, 3, 2), l (..., 1, 3). A step is taken only
    where the Jacobian is regular and the step finite, so a pose at a singular position keeps
    its (already accurate) value.
    """
    for _ in range(steps):
        cs, sn = np.cos(phi)[..., None], np.sin(phi)[..., None]
        arm = _rotate(cs, sn, c)  # R c_k, (..., m, 3, 2)
        e = x[..., None, :] + arm - k
        r = 0.5 * (plane.dot(e, e) - l * l)
        jac = np.concatenate((e, plane.dot(e, plane.perp(arm))[..., None]), axis=-1)
        step, det = _solve3(jac, r)
        # Coordinates are normalised (size 1), so det is relative; below 1e-14 the step would be
        # rounding noise amplified, at a pose that is a double root and already accurate.
        good = np.isfinite(step).all(axis=-1) & (np.abs(det) > 1e-14)
        step = np.where(good[..., None], step, 0.0)
        x = x - step[..., :2]
        phi = phi - step[..., 2]
    return x, phi


def _line_circle(w: Array, b: Array, radius: Array) -> tuple[Array, Array]:
    """Both points Y with ``Y·w = b`` and ``|Y| = radius`` (NaN where the line misses)."""
    ww = plane.dot(w, w)
    with np.errstate(divide="ignore", invalid="ignore"):
        foot = (b / ww)[..., None] * w
        half = np.sqrt((radius * radius - b * b / ww) / ww)
    side = half[..., None] * plane.perp(w)
    return foot + side, foot - side


def _pose_candidates(
    roots: Array, f_num: Array, delta: Array, k: Array, l: Array, c: Array
) -> tuple[Array, Array]:
    """Rebuild (J1, φ) from each root: ``Y = 2 num/Δ``, and the line ∩ circle points.

    Returns x (..., 18, 2) and phi (..., 18): 6 Cramer candidates, then 12 from one of the two
    linear equations (the better conditioned) and the first link's circle. Where Δ(φ) vanishes
    with the numerators (the two lines coincide) there are two poses at one φ, which Cramer's
    rule cannot give and the circle can; elsewhere one of the two points is the pose again and
    the other is discarded by the residual test (or polishes to a pose already found). Roots
    off the band around the unit circle give NaN.
    """
    near = np.abs(np.abs(roots) - 1.0) < ROOT_BAND
    phi = np.where(near, np.angle(roots), np.nan)
    z = np.exp(1j * phi)
    with np.errstate(divide="ignore", invalid="ignore"):
        n_val = _horner(f_num, z) / z  # powers start at −1
        d_val = _horner(delta, z) / z
        y = 2.0 * n_val / d_val
    x_cramer = np.stack((y.real, y.imag), axis=-1)
    cs, sn = np.cos(phi)[..., None], np.sin(phi)[..., None]
    arm = _rotate(cs, sn, c[..., None, :, :])  # (..., 6, 3, 2)
    kk2, kk3 = k[..., None, 1, :], k[..., None, 2, :]
    w2, w3 = arm[..., 1, :] - kk2, arm[..., 2, :] - kk3
    lk = l[..., None, :]
    c2, c3 = c[..., None, 1, :], c[..., None, 2, :]
    # Y·w_k = b_k: the difference of link k's circle equation and link 1's.
    b2 = 0.5 * (lk[..., 1] ** 2 - lk[..., 0] ** 2 - plane.dot(c2, c2) - plane.dot(kk2, kk2))
    b3 = 0.5 * (lk[..., 2] ** 2 - lk[..., 0] ** 2 - plane.dot(c3, c3) - plane.dot(kk3, kk3))
    b2 = b2 + plane.dot(kk2, arm[..., 1, :])
    b3 = b3 + plane.dot(kk3, arm[..., 2, :])
    use2 = plane.norm(w2) >= plane.norm(w3)
    pa, pb = _line_circle(np.where(use2[..., None], w2, w3), np.where(use2, b2, b3), lk[..., 0])
    x = np.concatenate((x_cramer, pa, pb), axis=-2)
    return x, np.concatenate((phi, phi, phi), axis=-1)


def _select(
    joints: Array, angle: Array, residual: Array, size: Array, limit: int
) -> tuple[Array, Array, Array, NDArray[np.int_]]:
    """Keep the verified candidates, merge duplicates, sort by angle, pack into ``limit`` slots.

    ``joints`` (..., m, 3, 2) and ``angle``, ``residual`` (..., m) are candidates; NaN marks
    those already rejected. Of two candidates within ``DEDUP_TOL`` the one with the smaller
    residual stays.
    """
    keep = residual < RESIDUAL_TOL
    resid = np.where(keep, residual, np.inf)
    joints = np.where(keep[..., None, None], joints, np.nan)  # rejected ones may hold inf
    # Pairwise: j is a duplicate if some kept i is within tolerance and better (ties: lower i).
    # One coordinate at a time: a (..., m, m, 3, 2) block would cost 6 times the memory.
    diff = np.zeros(joints.shape[:-2] + joints.shape[-3:-2])
    for j in range(3):
        for axis in range(2):
            coord = joints[..., j, axis]
            diff = np.fmax(diff, np.abs(coord[..., :, None] - coord[..., None, :]))
    diff = np.where(keep[..., :, None] & keep[..., None, :], diff, np.inf)
    close = diff <= DEDUP_TOL * size[..., None, None]
    m = joints.shape[-3]
    idx = np.arange(m)
    better = (resid[..., :, None] < resid[..., None, :]) | (
        (resid[..., :, None] == resid[..., None, :]) & (idx[:, None] < idx[None, :])
    )
    dup = (close & better & keep[..., :, None]).any(axis=-2)
    keep &= ~dup
    order = np.argsort(np.where(keep, angle, np.inf), axis=-1, kind="stable")[..., :limit]
    kept = np.take_along_axis(keep, order, axis=-1)
    count = keep.sum(axis=-1).clip(max=limit)
    joints = np.take_along_axis(joints, order[..., None, None], axis=-3)
    joints = np.where(kept[..., None, None], joints, np.nan)
    angle = np.where(kept, np.take_along_axis(angle, order, axis=-1), np.nan)
    residual = np.where(kept, np.take_along_axis(residual, order, axis=-1), np.nan)
    return joints, angle, residual, count


def _pad(a: Array, width: int, axis: int) -> Array:
    """Pad ``a`` with NaN along ``axis`` (negative) up to ``width`` entries."""
    missing = width - a.shape[axis]
    if missing <= 0:
        return a
    pad = [(0, 0)] * a.ndim
    pad[axis] = (0, missing)
    return np.pad(a, pad, constant_values=np.nan)


def triad_poses(anchors: ArrayLike, lengths: ArrayLike, body: ArrayLike) -> TriadPoses:
    """Every real pose of a triad (the class III Assur group), batched.

    The body carries J1, J2, J3 at ``body[..., k, :]`` in its own frame; J_k is tied to the
    point ``anchors[..., k, :]`` by a link of length ``lengths[..., k]``. Writing
    ``J_k = J_1 + R(φ)(c_k − c_1)``, the differences of the three circle equations are linear
    in J_1 for a given φ; substituting their solution into the first equation leaves one
    equation in φ. In isotropic (complex) coordinates, ``z = e^{iφ}``, it is a Laurent
    polynomial with powers −3..3, i.e. degree 6: a triad has at most 6 real poses. The
    formulation (links as vectors in the complex plane, each with its conjugate as a separate
    unknown) is C. W. Wampler's, "Solving the kinematics of planar mechanisms", J. Mech. Des.
    121 (1999) 387–391; the problem is also the forward kinematics of the planar 3-RPR
    platform, whose bound of six poses goes back to K. H. Hunt.

    The roots are found in ``t = tan((φ − φ0)/2)``, the half-angle parametrisation turned by
    φ0 so that t = ∞ lies where the polynomial is largest: φ = π, or any angle, is no special
    case, and no root runs off to infinity. They are the eigenvalues of companion matrices (one
    batched call). Each root near the unit circle gives φ, and J_1 follows from the linear
    equations and also from one of them and the first circle (both points): the elimination is
    exact except where those equations are singular (their determinant Δ(φ) vanishes with the
    numerators), and there two poses share one φ. Three Newton steps on the three original
    equations polish every candidate, and a pose is kept only if every link then has its
    length to ``1e-10`` of the triad's size, which discards complex roots near the circle and
    the spurious candidates alike. Poses closer than ``1e-7`` of the size are merged (a double
    root, i.e. a pose at a singular position, counts once).

    Parameters
    ----------
    anchors : ``(..., 3, 2)``, the known points K1, K2, K3.
    lengths : ``(..., 3)``, the link lengths |K_k J_k|.
    body : ``(..., 3, 2)``, J1, J2, J3 in the body's own frame.

    Returns
    -------
    TriadPoses
        Joints ``(..., 6, 3, 2)``, the body angle, the count and each pose's residual; the real
        poses come first, sorted by the body angle, and the rest is NaN. A triad whose
        polynomial vanishes identically (a continuum of poses: a body and anchor triangle that
        are similar and collinear, for instance) reports no pose.

    Examples
    --------
    Anchors on a circle of radius 2 and body joints on one of radius 1, both 120° apart, with
    links of length √3: the body centred and turned by φ puts J_k at distance
    ``√(4 + 1 − 4 cos φ)`` from K_k, which is √3 at φ = ±60°; there is no other pose.

    >>> ring = np.array([[0.0, 1.0], [-0.75**0.5, -0.5], [0.75**0.5, -0.5]])
    >>> poses = triad_poses(2 * ring, [3**0.5] * 3, ring)
    >>> int(poses.count), np.degrees(poses.angle[:2]).round(9)
    (2, array([-60.,  60.]))
    >>> poses.joints[1].round(6) + 0.0  # φ = 60°: J_k at 150°, 270° and 30° on the unit circle
    array([[-0.866025,  0.5     ],
           [ 0.      , -1.      ],
           [ 0.866025,  0.5     ]])
    >>> bool(poses.residual[1] < 1e-15)
    True

    A triad with six real poses (found by searching integer-coordinate triads, and confirmed by
    :func:`triad_poses_sweep`):

    >>> six = triad_poses([[0, 0], [1, -10], [9, 7]], [8, 13, 14], [[0, 0], [-6, 5], [7, 1]])
    >>> int(six.count), np.degrees(six.angle).round(3)
    (6, array([-176.956,  -24.415,    2.871,   68.62 ,   96.304,  167.902]))

    Anchors too far apart for the links give no pose:

    >>> none = triad_poses(10 * ring, [1.0, 1.0, 1.0], ring)
    >>> int(none.count), bool(np.isnan(none.joints).all())
    (0, True)
    """
    anchors, lengths, body, batch = _broadcast_triad(anchors, lengths, body)
    n = int(np.prod(batch, dtype=int))
    flat = (anchors.reshape(n, 3, 2), lengths.reshape(n, 3), body.reshape(n, 3, 2))
    # In chunks: each triad carries 18 candidates and their pairwise distances, so memory, not
    # time, is what limits the size of one call.
    parts = [_triad_poses_flat(*(a[i : i + CHUNK] for a in flat)) for i in range(0, n, CHUNK)]
    if not parts:
        parts = [_triad_poses_flat(*flat)]
    joined = [np.concatenate(field) for field in zip(*parts, strict=True)]
    joints, angle, count, residual = (a.reshape(batch + a.shape[1:]) for a in joined)
    return TriadPoses(joints=joints, angle=angle, count=count, residual=residual)


def _triad_poses_flat(
    anchors: Array, lengths: Array, body: Array
) -> tuple[Array, Array, NDArray[np.int_], Array]:
    """:func:`triad_poses` on a flat batch: (joints, angle, count, residual)."""
    size = _triad_size(anchors, lengths, body)
    origin = anchors[..., :1, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        k = (anchors - origin) / size[..., None, None]
        l = lengths / size[..., None]
        c = (body - body[..., :1, :]) / size[..., None, None]
    kz = k[..., 0] + 1j * k[..., 1]
    cz = c[..., 0] + 1j * c[..., 1]
    f, num, delta = _triad_polynomial(kz, l, cz)
    roots = _real_angle_roots(f)
    # Rebuilding, polishing and verifying run on every candidate, real or not: divisions by a
    # vanishing Δ and overflows from a far-off root are expected there and masked by the checks.
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        x, phi = _pose_candidates(roots, num, delta, k, l, c)
        x, phi = _newton(
            x, phi, k[..., None, :, :], l[..., None, :], c[..., None, :, :], NEWTON_STEPS
        )
        phi = np.angle(np.exp(1j * phi))
        cs, sn = np.cos(phi)[..., None], np.sin(phi)[..., None]
        local = x[..., None, :] + _rotate(cs, sn, c[..., None, :, :])
        joints = origin[..., None, :, :] + size[..., None, None, None] * local
        residual = _link_residual(
            joints, anchors[..., None, :, :], lengths[..., None, :], size[..., None]
        )
    residual = np.where(np.isfinite(residual), residual, np.nan)
    joints, angle, residual, count = _select(joints, phi, residual, size, MAX_POSES)
    return joints, angle, count, residual


# ----------------------------------------------------------------------------------------------
# Derivatives
# ----------------------------------------------------------------------------------------------


def triad_rates(
    anchor_pos: ArrayLike,
    anchor_vel: ArrayLike,
    anchor_acc: ArrayLike,
    joints: ArrayLike,
    lengths: ArrayLike,
    *,
    leg_rates: tuple[ArrayLike, ArrayLike] | None = None,
    body_rates: tuple[ArrayLike, ArrayLike] | None = None,
) -> TriadRates:
    """Velocities and accelerations of a triad's joints from those of its anchors.

    With ``ρ_k = J_k − J_1`` and ``e_k = J_k − K_k``, the body moves as
    ``J̇_k = V + ω ρ_k^⊥`` and ``J̈_k = A + α ρ_k^⊥ − ω² ρ_k``; differentiating
    ``|e_k|² = L_k²`` once and twice gives, for the unknowns (V, ω) and then (A, α),

    ``e_k·V + ω (ρ_k × e_k) = e_k·K̇_k`` and
    ``e_k·A + α (ρ_k × e_k) = e_k·K̈_k − |J̇_k − K̇_k|² + ω² e_k·ρ_k``,

    one 3×3 solve each (rows scaled by ``L_k``, the angular column by the body's size, so that
    the determinant is relative). Where ``|det|`` is below 1e-8 the triad is at a singular
    position (its links' lines meet in one point, or are parallel), and every output is NaN.

    A triad driven at a hinge changes with the input: a leg's length (``leg_rates``: the
    derivatives (L²)′/2 and (L²)″/2 of each leg, added to the right-hand sides) or a joint's
    place on the body (``body_rates``: each joint's velocity w_k and acceleration a_k relative
    to the body, in the plane's axes). Then ``J̇_k = V + ω ρ_k^⊥ + w_k`` and
    ``J̈_k = A + α ρ_k^⊥ − ω² ρ_k + 2ω w_k^⊥ + a_k``, and the rows' right-hand sides lose
    ``e_k·w_k`` and ``e_k·(2ω w_k^⊥ + a_k)``.

    Parameters
    ----------
    anchor_pos, anchor_vel, anchor_acc : ``(..., 3, 2)``, the anchors K_k and their first and
        second derivatives with respect to the input.
    joints : ``(..., 3, 2)``, one pose (e.g. ``poses.joints``, with the anchors given an axis
        for the poses: ``anchor_pos[..., None, :, :]``).
    lengths : ``(..., 3)``, the link lengths.
    leg_rates, body_rates : optional, ``(..., 3)`` twice and ``(..., 3, 2)`` twice.

    Returns
    -------
    TriadRates
        ``vel`` and ``acc`` of J1..J3 ``(..., 3, 2)``, the body's ``omega`` and ``alpha``, and
        ``regular``.

    Examples
    --------
    Anchors translating together at unit speed along +x carry the whole triad with them, and
    spinning about the origin at unit rate they turn it rigidly (J at radius 1: speed 1,
    centripetal acceleration 1):

    >>> ring = np.array([[0.0, 1.0], [-0.75**0.5, -0.5], [0.75**0.5, -0.5]])
    >>> pose = triad_poses(2 * ring, [3**0.5] * 3, ring).joints[1]
    >>> shift = triad_rates(2 * ring, [[1.0, 0.0]] * 3, np.zeros((3, 2)), pose, [3**0.5] * 3)
    >>> shift.vel.round(12) + 0.0, float(shift.omega.round(12) + 0.0)
    (array([[1., 0.],
           [1., 0.],
           [1., 0.]]), 0.0)
    >>> turn = 2 * ring @ [[0.0, 1.0], [-1.0, 0.0]]  # the anchors' velocities: ω × K
    >>> spin = triad_rates(2 * ring, turn, -2 * ring, pose, [3**0.5] * 3)
    >>> float(spin.omega.round(12)), bool(np.allclose(spin.acc, -pose))
    (1.0, True)
    """
    k = np.asarray(anchor_pos, dtype=float)
    j = np.asarray(joints, dtype=float)
    shape = np.broadcast_shapes(k.shape, j.shape)
    kv = np.broadcast_to(np.asarray(anchor_vel, dtype=float), shape)
    ka = np.broadcast_to(np.asarray(anchor_acc, dtype=float), shape)
    lengths = np.asarray(lengths, dtype=float)
    e = j - k
    rho = j - j[..., :1, :]
    body = np.maximum(plane.norm(rho[..., 1, :]), plane.norm(rho[..., 2, :]))
    c1, c2 = (0.0, 0.0) if leg_rates is None else (np.asarray(r, dtype=float) for r in leg_rates)
    w, wa = (
        (np.zeros_like(rho), np.zeros_like(rho))
        if body_rates is None
        else (np.asarray(r, dtype=float) for r in body_rates)
    )
    with np.errstate(divide="ignore", invalid="ignore"):
        row_scale = 1.0 / lengths  # each row is then a unit direction and a lever arm / size
        ang_scale = 1.0 / body
        ex, ey = e[..., 0] * row_scale, e[..., 1] * row_scale
        m = np.stack(
            np.broadcast_arrays(ex, ey, plane.cross(rho, e) * row_scale * ang_scale[..., None]),
            axis=-1,
        )
        r1 = (plane.dot(e, kv - w) + c1) * row_scale
        sol1, det = _solve3(m, r1)
        v = sol1[..., :2]
        omega = sol1[..., 2] * ang_scale
        vel = v[..., None, :] + omega[..., None, None] * plane.perp(rho) + w
        rel_vel = vel - kv
        carried = 2.0 * omega[..., None, None] * plane.perp(w) + wa
        r2 = (
            plane.dot(e, ka - carried)
            - plane.dot(rel_vel, rel_vel)
            + (omega**2)[..., None] * plane.dot(e, rho)
            + c2
        )
        sol2, _ = _solve3(m, r2 * row_scale)
        a = sol2[..., :2]
        alpha = sol2[..., 2] * ang_scale
        acc = (
            a[..., None, :]
            + alpha[..., None, None] * plane.perp(rho)
            - (omega**2)[..., None, None] * rho
            + carried
        )
    regular = np.abs(det) > SINGULAR_DET
    regular &= np.isfinite(vel).all(axis=(-1, -2)) & np.isfinite(acc).all(axis=(-1, -2))
    keep = regular[..., None, None]
    return TriadRates(
        vel=np.where(keep, vel, np.nan),
        acc=np.where(keep, acc, np.nan),
        omega=np.where(regular, omega, np.nan),
        alpha=np.where(regular, alpha, np.nan),
        regular=regular,
    )


def _triad_chain(
    psi: Array, branch: Array, anchors: Array, lengths: Array, body: Array
) -> tuple[Array, ...]:
    """The triad with its first link at angle ψ: J1 on it, J2 by circle ∩ circle, J3 rigid.

    ``psi``, ``branch``: ``(..., m)``; anchors ``(..., 3, 2)``, lengths ``(..., 3)`` and body
    ``(..., 3, 2)`` have the batch shape only. Returns the coordinates x1, y1, x2, y2, x3, y3 of
    J1, J2, J3, each ``(..., m)``, NaN where J2 cannot be placed (separate coordinates: this is
    the sweep's inner loop).
    """
    kx, ky = anchors[..., 0, None], anchors[..., 1, None]  # (..., 3, 1) each
    l1, l2 = lengths[..., 0, None], lengths[..., 1, None]
    side = body - body[..., :1, :]
    r12 = np.hypot(side[..., 1, 0], side[..., 1, 1])[..., None]
    j1x = kx[..., 0, :] + l1 * np.cos(psi)
    j1y = ky[..., 0, :] + l1 * np.sin(psi)
    k2 = np.stack((kx[..., 1, :], ky[..., 1, :]), axis=-1)
    j2 = plane.circle_circle(
        np.stack((j1x, j1y), axis=-1), r12, k2, l2, branch, tol=ASSEMBLY_TOL
    ).point
    j2x, j2y = j2[..., 0], j2[..., 1]
    # The rotation taking the body's side J1J2 onto the world's: cos and sin from dot and cross.
    with np.errstate(divide="ignore", invalid="ignore"):
        ux = side[..., 1, 0, None] / (r12 * r12)
        uy = side[..., 1, 1, None] / (r12 * r12)
    ax, ay = j2x - j1x, j2y - j1y
    cs, sn = ux * ax + uy * ay, ux * ay - uy * ax
    tx, ty = side[..., 2, 0, None], side[..., 2, 1, None]
    j3x = j1x + cs * tx - sn * ty
    j3y = j1y + sn * tx + cs * ty
    return j1x, j1y, j2x, j2y, j3x, j3y


def triad_poses_sweep(
    anchors: ArrayLike, lengths: ArrayLike, body: ArrayLike, *, grid: int = 512
) -> TriadPoses:
    """Every real pose of a triad by :func:`sweep_roots`: the independent check of the polynomial.

    ψ is the angle of link K1J1; J2 is placed on both branches of circle(J1, |J1J2|) ∩
    circle(K2, L2), J3 rigidly with the body, and the residual is ``(|J3 K3| − L3)/size``.
    The result has the layout of :func:`triad_poses` (the body angle computed from the pose),
    and its poses pass the same residual test.

    Besides :func:`sweep_roots`' own limits, this chain is blind where a pose has J1 on K2
    (the two circles are concentric and J2 is not determined by ψ) and ill-conditioned where a
    pose has J1, J2 and K2 in line (the circle–circle step at its limit).

    Examples
    --------
    >>> six = triad_poses_sweep([[0, 0], [1, -10], [9, 7]], [8, 13, 14], [[0, 0], [-6, 5], [7, 1]])
    >>> int(six.count), np.degrees(six.angle).round(3)
    (6, array([-176.956,  -24.415,    2.871,   68.62 ,   96.304,  167.902]))
    """
    anchors, lengths, body, batch = _broadcast_triad(anchors, lengths, body)
    size = _triad_size(anchors, lengths, body)
    # Work relative to K1 in units of the size, as the polynomial solver does: far from the
    # origin, absolute coordinates would cost digits the residual cannot afford.
    origin = anchors[..., :1, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        k = (anchors - origin) / size[..., None, None]
        l = lengths / size[..., None]
        c = body / size[..., None, None]

    k3x, k3y, l3 = k[..., 2, 0, None], k[..., 2, 1, None], l[..., 2, None]

    def residual(psi: Array, branch: Array) -> Array:
        x3, y3 = _triad_chain(psi, branch, k, l, c)[4:]
        return np.hypot(x3 - k3x, y3 - k3y) - l3

    found = sweep_roots(residual, batch, grid=grid)
    x1, y1, x2, y2, x3, y3 = _triad_chain(found.psi, found.branch, k, l, c)
    local = np.stack((np.stack((x1, y1), -1), np.stack((x2, y2), -1), np.stack((x3, y3), -1)), -2)
    joints = origin[..., None, :, :] + size[..., None, None, None] * local
    side_body = body[..., 1, :] - body[..., 0, :]
    side_world = joints[..., 1, :] - joints[..., 0, :]
    angle = np.arctan2(
        plane.cross(side_body[..., None, :], side_world),
        plane.dot(side_body[..., None, :], side_world),
    )
    resid = _link_residual(joints, anchors[..., None, :, :], lengths[..., None, :], size[..., None])
    width = max(found.psi.shape[-1], MAX_POSES)
    joints = _pad(joints, width, -3)
    angle, resid = _pad(angle, width, -1), _pad(resid, width, -1)
    resid = np.where(np.isfinite(resid), resid, np.nan)
    joints, angle, resid, count = _select(joints, angle, resid, size, MAX_POSES)
    return TriadPoses(joints=joints, angle=angle, count=count, residual=resid)
