"""The spherical triad of paper 001's Stephenson III driven at FG: every real pose, two ways.

Driven at its output link FG, the Stephenson-III spherical six-bar of paper 001 (Zong et al.)
leaves its ternary coupler BCE held by three binary links: AB (B on the small circle of arc a2
about A), CD (C on the small circle of arc a4 about D) and EF (E at arc a7 from the placed joint
F). No joint is fixed by two known ones, so no construction plan places it. In general form:

* B on a small circle: ``B = cos r_B · O_B + sin r_B (cos θ_B e1_B + sin θ_B e2_B)``, with the
  circle's *frame* (O_B, e1_B, e2_B) orthonormal (either handedness, see :func:`circle_frame`);
* C likewise on (O_C, e1_C, e2_C) with arc r_C;
* the link: B·C = cos(bc);
* E rigid with the coupler: ``E = point_at(C, B, ce, turn)`` (for paper 001, turn = π − σ);
* the last link: E·F = cos(ef) with F known.

Two independent solvers live here:

* :func:`sphere_triad` eliminates θ_C: with B = b0 + b1 cos θ_B + b2 sin θ_B and C = c0 + c1
  cos θ_C + c2 sin θ_C, and E = αC + βB + γ(C × B) with constant α, β, γ (valid wherever B·C =
  cos bc), both constraints are bilinear forms ``mᵀ M_k n = 0`` in m = (1, cos θ_B, sin θ_B)
  and n = (1, cos θ_C, sin θ_C). With half-angle tangents x and y each is a quadratic in y whose
  coefficients are quadratics in x, and the Sylvester resultant of the two quadratics in y is a
  polynomial of degree 8 in x (paper 001's eqs. 19–20 in its own unknowns, derived here
  independently). 8 is also the mixed volume of two bilinear equations on the torus, which
  bounds their isolated solutions (D. N. Bernstein, "The number of roots of a system of
  equations", Funct. Anal. Appl. 9, 1975): no triad has more isolated poses. The roots come
  from companion-matrix eigenvalues for a whole batch at once; for each real root both
  solutions θ_C of the first equation (in closed form) are tried, so that the common root is
  found even where two poses share θ_B; every candidate is polished by Newton's method on the
  two original equations and kept only if every constraint holds to :data:`RESIDUAL_TOL`.
* :func:`sphere_triad_sweep` needs no polynomial: θ_B walks a fine grid, C closes the spherical
  four-bar on both branches, and the roots of E·F − cos(ef) are bracketed and bisected by
  :func:`linkwright.engine.triad.sweep_roots`. It is the cross-check.

Angles are radians; arrays broadcast over a leading batch shape (mechanisms × input samples),
positions are unit vectors with a trailing axis of 3, and a result is NaN exactly where it does
not exist.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine.root_sweep import sweep_roots
from linkwright.engine.state import ASSEMBLY_TOL
from linkwright.geometry import sphere

# A circle's frame and a point on it are sphere geometry; named here too, where the triad's
# data are described in their terms.
circle_frame = sphere.circle_frame
on_circle = sphere.on_circle

__all__ = [
    "MAX_POSES",
    "RESIDUAL_TOL",
    "InvalidTriad",
    "SphereTriadPoses",
    "bilinear_resultant",
    "circle_frame",
    "on_circle",
    "sphere_triad",
    "sphere_triad_sweep",
]

Array = NDArray[np.float64]

MAX_POSES = 8
"""A spherical triad has at most eight real poses (the degree of its polynomial)."""

RESIDUAL_TOL = 1e-10
"""A pose is kept when every constraint (arcs in radians, unit norms, E's chord from its place on
the coupler) holds to this: it is also what tells real roots from complex ones near the axis."""

# Roots of the polynomial whose angle θ_B has an imaginary part below this are tried as real
# poses. A real double root (a pose at a singular position) splits under rounding into a
# complex pair about sqrt(eps) off the real axis, so the band is far wider than that; the
# residual test after polishing decides.
ROOT_BAND = 1e-3
# The first equation's dependence on θ_C, relative to its size, below which it is taken not to
# fix θ_C at a root θ_B (the four-bar's circles of C coincide there), so that θ_C is solved
# from the second equation instead.
FREE_PSI = 1e-8
# Newton steps on the two bilinear equations: the eigenvalue roots are accurate to about
# eps·condition, two quadratically convergent steps reach rounding, the rest is for roots near
# a double root, where convergence is only linear.
NEWTON_STEPS = 6
# Two poses closer than this (largest chord between their joints) are one pose: the two roots
# of a split double root polish towards the same place.
DEDUP_TOL = 1e-7
# Fixed irrational turns of the angle origins: a root at θ = π would be x = ∞ for the half-angle
# tangent, and mechanisms built on round angles put roots exactly there.
OFFSET_B = (np.sqrt(5.0) - 1.0) / 2.0
OFFSET_C = np.sqrt(2.0) - 1.0
# Triads solved per chunk of a large batch (16 candidates of a few 3×3 forms each).
CHUNK = 8192

# Ascending coefficients in x of the half-angle forms of (1, cos θ, sin θ), times (1 + x²):
# 1 + x², 1 − x², 2x.
_HALF = np.array([[1.0, 0.0, 1.0], [1.0, 0.0, -1.0], [0.0, 2.0, 0.0]])


class InvalidTriad(ValueError):
    """A triad's data are not a spherical triad (names the argument and the problem)."""


@dataclass(frozen=True)
class SphereTriadPoses:
    """Every real pose of a batch of spherical triads.

    Attributes
    ----------
    b, c, e : ``(..., 8, 3)``, the unit vectors B, C, E of each pose; the real poses come
        first, sorted by ``theta_b``, the padding after them is NaN.
    theta_b, theta_c : ``(..., 8)``, the angles of B and C in their circles' frames, in
        (−π, π]; NaN in the padding.
    count : ``(...,)``, the number of real poses (0 to 8).
    residual : ``(..., 8)``, each pose's largest constraint error (see :data:`RESIDUAL_TOL`),
        NaN in the padding.
    """

    b: Array
    c: Array
    e: Array
    theta_b: Array
    theta_c: Array
    count: NDArray[np.int_]
    residual: Array

    @property
    def valid(self) -> NDArray[np.bool_]:
        """``(..., 8)``: which slots hold a real pose."""
        return np.arange(self.theta_b.shape[-1]) < self.count[..., None]


def _read(
    frame_b: ArrayLike,
    arc_b: ArrayLike,
    frame_c: ArrayLike,
    arc_c: ArrayLike,
    bc: ArrayLike,
    ce: ArrayLike,
    turn: ArrayLike,
    f: ArrayLike,
    ef: ArrayLike,
) -> tuple[dict[str, Array], tuple[int, ...]]:
    """Check and broadcast a triad's data; every value gets the batch shape (plus its axes)."""
    frames = {"frame_b": frame_b, "frame_c": frame_c}
    arcs = {"arc_b": arc_b, "arc_c": arc_c, "bc": bc, "ce": ce, "ef": ef}
    p: dict[str, Array] = {}
    for name, value in frames.items():
        v = np.asarray(value, dtype=float)
        if v.shape[-2:] != (3, 3):
            raise InvalidTriad(
                f"{name}: must have shape (..., 3, 3) (rows O, e1, e2), got {v.shape}"
            )
        if not np.all(np.isfinite(v)):
            raise InvalidTriad(f"{name}: must be finite")
        gram = np.einsum("...ik,...jk->...ij", v, v)
        if np.any(np.abs(gram - np.eye(3)) > 1e-9):
            raise InvalidTriad(f"{name}: rows O, e1, e2 must be orthonormal (see circle_frame)")
        p[name] = v
    for name, value in arcs.items():
        v = np.asarray(value, dtype=float)
        if not np.all(np.isfinite(v)):
            raise InvalidTriad(f"{name}: must be finite")
        if np.any((v <= 0) | (v >= np.pi)):
            raise InvalidTriad(f"{name}: an arc must lie strictly between 0 and π radians")
        p[name] = v
    t = np.asarray(turn, dtype=float)
    if not np.all(np.isfinite(t)):
        raise InvalidTriad("turn: must be finite")
    p["turn"] = t
    v = np.asarray(f, dtype=float)
    if v.shape[-1:] != (3,):
        raise InvalidTriad(f"f: must be a unit vector (..., 3), got shape {v.shape}")
    if not np.all(np.isfinite(v)) or np.any(np.abs(sphere.norm(v) - 1.0) > 1e-9):
        raise InvalidTriad("f: must be a finite unit vector")
    p["f"] = v
    try:
        batch = np.broadcast_shapes(
            p["frame_b"].shape[:-2],
            p["frame_c"].shape[:-2],
            p["f"].shape[:-1],
            *(p[k].shape for k in (*arcs, "turn")),
        )
    except ValueError as exc:
        raise InvalidTriad(f"the triad's arrays do not broadcast together: {exc}") from None
    out = {k: np.broadcast_to(p[k], batch + (3, 3)) for k in frames}
    out["f"] = np.broadcast_to(p["f"], batch + (3,))
    out.update({k: np.broadcast_to(p[k], batch) for k in (*arcs, "turn")})
    return out, batch


def _coupler(bc: Array, ce: Array, turn: Array) -> tuple[Array, Array, Array]:
    """(α, β, γ) with E = αC + βB + γ(C × B), from :func:`sphere.point_at` (origin C, toward B).

    The great circle C→B has the tangent (B − cos bc · C)/sin bc at C and the normal
    (C × B)/sin bc; E = cos ce · C + sin ce (cos turn · tangent + sin turn · normal).
    """
    k = np.sin(ce) / np.sin(bc)
    beta = k * np.cos(turn)
    return np.cos(ce) - beta * np.cos(bc), beta, k * np.sin(turn)


def _residual(p: dict[str, Array], b: Array, c: Array, e: Array) -> Array:
    """Largest constraint error of poses ``b, c, e`` (..., m, 3): arcs, norms and E's place."""
    q = {k: v[..., None] for k, v in p.items() if v.ndim == len(b.shape) - 2}
    fb, fc = p["frame_b"][..., None, :, :], p["frame_c"][..., None, :, :]
    f = p["f"][..., None, :]
    parts = [
        np.abs(sphere.arc(fb[..., 0, :], b) - q["arc_b"]),
        np.abs(sphere.arc(fc[..., 0, :], c) - q["arc_c"]),
        np.abs(sphere.arc(b, c) - q["bc"]),
        np.abs(sphere.arc(e, f) - q["ef"]),
        sphere.frame_error(c, b, e, q["ce"], q["turn"]),
        *(np.abs(sphere.norm(v) - 1.0) for v in (b, c, e)),
    ]
    worst: Array = np.maximum.reduce(parts)
    return worst


def _poly_mul(a: Array, b: Array) -> Array:
    """Product of polynomials given by ascending coefficients on the last axis (batched)."""
    n, m = a.shape[-1], b.shape[-1]
    out = np.zeros(np.broadcast_shapes(a.shape[:-1], b.shape[:-1]) + (n + m - 1,))
    for i in range(n):
        out[..., i : i + m] += a[..., i : i + 1] * b
    return out


def _forms(p: dict[str, Array]) -> tuple[Array, Array, Array, Array]:
    """The bilinear forms M1, M2 (N, 3, 3) and the turned circle bases (N, 3, 3) of B and C.

    Row i of a basis is the vector multiplying m_i (resp. n_j): B = Σ m_i u_i, C = Σ n_j v_j,
    with the angle origins turned by :data:`OFFSET_B` and :data:`OFFSET_C`.
    """

    def basis(frame: Array, arc: Array, offset: float) -> Array:
        o, e1, e2 = frame[..., 0, :], frame[..., 1, :], frame[..., 2, :]
        r = np.sin(arc)[..., None]
        co, so = np.cos(offset), np.sin(offset)
        return np.stack(
            (np.cos(arc)[..., None] * o, r * (co * e1 + so * e2), r * (co * e2 - so * e1)), -2
        )

    u = basis(p["frame_b"], p["arc_b"], OFFSET_B)
    v = basis(p["frame_c"], p["arc_c"], OFFSET_C)
    f = p["f"]
    alpha, beta, gamma = _coupler(p["bc"], p["ce"], p["turn"])
    m1 = np.einsum("nik,njk->nij", u, v)
    m1[:, 0, 0] -= np.cos(p["bc"])
    # (C × B)·F = Σ n_j m_i (v_j × u_i)·F = Σ n_j m_i (u_i × F)·v_j.
    uf = sphere.cross(u, f[:, None, :])
    m2 = gamma[:, None, None] * np.einsum("nik,njk->nij", uf, v)
    m2[:, 0, :] += alpha[:, None] * np.einsum("njk,nk->nj", v, f)
    m2[:, :, 0] += beta[:, None] * np.einsum("nik,nk->ni", u, f)
    m2[:, 0, 0] -= np.cos(p["ef"])
    return m1, m2, u, v


def bilinear_resultant(m1: ArrayLike, m2: ArrayLike) -> Array:
    """The degree-8 polynomial in x = tan(φ/2) whose roots are the φ of the common solutions
    (φ, ψ) of ``mᵀ M1 n = 0`` and ``mᵀ M2 n = 0``, m = (1, cos φ, sin φ), n = (1, cos ψ, sin ψ).

    Times (1 + x²)(1 + y²), with y = tan(ψ/2), each equation is ``Σ K[p, q] x^p y^q`` with
    K = Hᵀ M H (H the half-angle table of 1 + x², 1 − x², 2x), i.e. the quadratic in y
    ``A(x) y² + B(x) y + C(x)``. Two quadratics share a root iff their Sylvester resultant
    ``(A1 C2 − A2 C1)² − (A1 B2 − A2 B1)(B1 C2 − B2 C1)`` vanishes (paper 001's eq. 19); with A,
    B, C quadratic in x it has degree 8 (eq. 20). A root at φ = π is one at x = ∞: the degree
    drops there.

    Parameters
    ----------
    m1, m2 : ``(..., 3, 3)``, the forms, rows for m (φ), columns for n (ψ).

    Returns
    -------
    ``(..., 9)``, ascending coefficients in x.

    Examples
    --------
    cos φ − cos ψ = 0 and sin φ + sin ψ − 1 = 0 meet where ψ = φ and sin φ = 1/2 (ψ = −φ
    would need 0 = 1): φ = 30° and 150°; the other six roots are complex.

    >>> m1 = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 0]])
    >>> m2 = np.array([[-1.0, 0, 1], [0, 0, 0], [1, 0, 0]])
    >>> x = np.roots(bilinear_resultant(m1, m2)[::-1])
    >>> np.degrees(2 * np.arctan(np.sort(x[np.abs(x.imag) < 1e-9].real))).round(9)
    array([ 30., 150.])
    """
    k1 = np.einsum("ip,...ij,jq->...pq", _HALF, np.asarray(m1, dtype=float), _HALF)
    k2 = np.einsum("ip,...ij,jq->...pq", _HALF, np.asarray(m2, dtype=float), _HALF)
    a1, b1, c1 = k1[..., 2], k1[..., 1], k1[..., 0]
    a2, b2, c2 = k2[..., 2], k2[..., 1], k2[..., 0]
    ac = _poly_mul(a1, c2) - _poly_mul(a2, c1)
    ab = _poly_mul(a1, b2) - _poly_mul(a2, b1)
    bc = _poly_mul(b1, c2) - _poly_mul(b2, c1)
    return _poly_mul(ac, ac) - _poly_mul(ab, bc)


def _real_angles(coef: Array) -> Array:
    """φ = 2 arctan x at the (nearly) real roots x of each row of ``coef`` (N, 9); NaN else.

    The polynomial is solved in x or, where its leading coefficient is the smaller end, in 1/x
    (a root near x = ∞, i.e. φ near π, is then an ordinary root near 0). Returns (N, 8).
    """
    n = coef.shape[0]
    flip = np.abs(coef[:, -1]) < np.abs(coef[:, 0])
    c = np.where(flip[:, None], coef[:, ::-1], coef)
    lead = c[:, -1]
    usable = (lead != 0) & np.isfinite(c).all(axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        monic = np.where(usable[:, None], c[:, :-1] / np.where(usable, lead, 1.0)[:, None], 0.0)
    comp = np.zeros((n, 8, 8))
    comp[:, 1:, :-1] = np.eye(7)
    comp[:, :, -1] = -monic
    roots = np.linalg.eigvals(comp) if n else np.zeros((0, 8), complex)
    # φ for x: 2·atan2(x, 1); for u = 1/x: 2·atan2(1, u). Its imaginary part, to first order,
    # is 2·Im(root)/(1 + |root|²) in both cases.
    re = roots.real
    phi = np.where(flip[:, None], 2.0 * np.arctan2(1.0, re), 2.0 * np.arctan2(re, 1.0))
    im = 2.0 * np.abs(roots.imag) / (1.0 + np.abs(roots) ** 2)
    return np.where(usable[:, None] & (im < ROOT_BAND), phi, np.nan)


def _trig(phi: Array) -> tuple[Array, Array]:
    """(1, cos φ, sin φ) and its derivative (0, −sin φ, cos φ), stacked on a last axis."""
    c, s = np.cos(phi), np.sin(phi)
    return np.stack((np.ones_like(c), c, s), -1), np.stack((np.zeros_like(c), -s, c), -1)


def _solve_chunk(p: dict[str, Array]) -> tuple[Array, Array]:
    """θ_B and θ_C (N, 16) of the polished candidates of a flat chunk (NaN where none)."""
    m1, m2, _, _ = _forms(p)
    phi = _real_angles(bilinear_resultant(m1, m2))  # (N, 8)
    # Both solutions ψ of the first equation at each φ: l0 + l1 cos ψ + l2 sin ψ = 0.
    mv, _ = _trig(phi)
    row = np.einsum("nki,nij->nkj", mv, m1)
    # Where it does not depend on ψ at that φ (B on ±D's circle of C, with BC = CD or their
    # sum π: C anywhere on its circle as far as the four-bar goes), ψ comes from the second.
    other = np.einsum("nki,nij->nkj", mv, m2)
    size = np.abs(m1).max(axis=(-2, -1))[..., None]
    loose = np.hypot(row[..., 1], row[..., 2]) <= FREE_PSI * size
    row = np.where(loose[..., None], other, row)
    rho = np.hypot(row[..., 1], row[..., 2])
    with np.errstate(divide="ignore", invalid="ignore"):
        half = np.arccos(np.clip(-row[..., 0] / rho, -1.0, 1.0))
    mid = np.arctan2(row[..., 2], row[..., 1])
    phi = np.concatenate((phi, phi), axis=-1)
    psi = np.concatenate((mid + half, mid - half), axis=-1)
    for _ in range(NEWTON_STEPS):
        # Both equations mᵀ M_e n = 0 with m = (1, cos φ, sin φ), n = (1, cos ψ, sin ψ), written
        # out term by term: an einsum over these 3 × 3 forms costs several times more.
        cp, sp, cq, sq = np.cos(phi), np.sin(phi), np.cos(psi), np.sin(psi)
        g, j_phi, j_psi = [], [], []
        for form in (m1, m2):
            k = form[:, None, :, :]  # (N, 1, 3, 3) against (N, 16)
            mn = [k[..., i, 0] + k[..., i, 1] * cq + k[..., i, 2] * sq for i in range(3)]
            dmn = [k[..., i, 2] * cq - k[..., i, 1] * sq for i in range(3)]
            g.append(mn[0] + cp * mn[1] + sp * mn[2])
            j_phi.append(cp * mn[2] - sp * mn[1])
            j_psi.append(dmn[0] + cp * dmn[1] + sp * dmn[2])
        det = j_phi[0] * j_psi[1] - j_phi[1] * j_psi[0]
        with np.errstate(divide="ignore", invalid="ignore"):
            d_phi = (g[0] * j_psi[1] - g[1] * j_psi[0]) / det
            d_psi = (j_phi[0] * g[1] - j_phi[1] * g[0]) / det
        # A singular Jacobian (exactly at a double root) stops that candidate where it is.
        step_ok = np.isfinite(d_phi) & np.isfinite(d_psi)
        phi = np.where(step_ok, phi - d_phi, phi)
        psi = np.where(step_ok, psi - d_psi, psi)
    return _wrap(phi + OFFSET_B), _wrap(psi + OFFSET_C)


def _wrap(angle: Array) -> Array:
    """``angle`` in (−π, π]."""
    return np.pi - np.mod(np.pi - angle, 2.0 * np.pi)


def _select(
    p: dict[str, Array], theta_b: Array, theta_c: Array, batch: tuple[int, ...]
) -> SphereTriadPoses:
    """Build, check, deduplicate and pack candidate poses (batch + (k,)) into 8 slots."""
    fb, fc = p["frame_b"][..., None, :, :], p["frame_c"][..., None, :, :]
    b = on_circle(fb, p["arc_b"][..., None], theta_b)
    c = on_circle(fc, p["arc_c"][..., None], theta_c)
    alpha, beta, gamma = (v[..., None, None] for v in _coupler(p["bc"], p["ce"], p["turn"]))
    e = alpha * c + beta * b + gamma * sphere.cross(c, b)
    resid = _residual(p, b, c, e)
    ok = np.isfinite(resid) & (resid < RESIDUAL_TOL)
    # Candidates that polish to one pose are a cluster: the most accurate of it is kept (a
    # start far from its root may still be converging when the Newton steps end).
    order = np.argsort(np.where(ok, resid, np.inf), axis=-1, kind="stable")

    # Float and boolean arrays alike.
    def take(a: NDArray[Any]) -> NDArray[Any]:
        if a.ndim == order.ndim:
            return np.take_along_axis(a, order, axis=-1)
        return np.take_along_axis(a, order[..., None], axis=-2)

    b, c, e, theta_b, theta_c, resid, ok = map(take, (b, c, e, theta_b, theta_c, resid, ok))
    # The largest coordinate difference of (B, C) between every two candidates, one
    # coordinate at a time: the (…, k, k, 6) array at once is the bulk of a batch's memory.
    gap = np.zeros(b.shape[:-1] + b.shape[-2:-1])
    for joint in (b, c):
        for axis in range(3):
            x = joint[..., axis]
            np.maximum(gap, np.abs(x[..., :, None] - x[..., None, :]), out=gap)
    k = ok.shape[-1]
    earlier = np.tril(np.ones((k, k), dtype=bool), k=-1)  # [j, i]: i < j
    with np.errstate(invalid="ignore"):
        repeat = ((gap < DEDUP_TOL) & ok[..., None, :] & earlier).any(axis=-1)
    keep = ok & ~repeat
    order = np.argsort(np.where(keep, theta_b, np.inf), axis=-1, kind="stable")[..., :MAX_POSES]
    b, c, e, theta_b, theta_c, resid, keep = map(take, (b, c, e, theta_b, theta_c, resid, keep))
    if keep.shape[-1] < MAX_POSES:
        pad = MAX_POSES - keep.shape[-1]

        def padded(a: NDArray[Any], axis: int, fill: float) -> NDArray[Any]:

            width = [(0, 0)] * a.ndim
            width[axis] = (0, pad)
            return np.pad(a, width, constant_values=fill)

        b, c, e = (padded(v, -2, np.nan) for v in (b, c, e))
        theta_b, theta_c, resid = (padded(v, -1, np.nan) for v in (theta_b, theta_c, resid))
        keep = padded(keep, -1, False)
    nan3 = ~keep[..., None]
    return SphereTriadPoses(
        b=np.where(nan3, np.nan, b).reshape(batch + (MAX_POSES, 3)),
        c=np.where(nan3, np.nan, c).reshape(batch + (MAX_POSES, 3)),
        e=np.where(nan3, np.nan, e).reshape(batch + (MAX_POSES, 3)),
        theta_b=np.where(keep, theta_b, np.nan).reshape(batch + (MAX_POSES,)),
        theta_c=np.where(keep, theta_c, np.nan).reshape(batch + (MAX_POSES,)),
        count=keep.sum(axis=-1).reshape(batch),
        residual=np.where(keep, resid, np.nan).reshape(batch + (MAX_POSES,)),
    )


def _flat(p: dict[str, Array], batch: tuple[int, ...]) -> dict[str, Array]:
    size = int(np.prod(batch, dtype=int))
    return {
        k: np.ascontiguousarray(v).reshape((size,) + v.shape[len(batch) :]) for k, v in p.items()
    }


def sphere_triad(
    frame_b: ArrayLike,
    arc_b: ArrayLike,
    frame_c: ArrayLike,
    arc_c: ArrayLike,
    bc: ArrayLike,
    ce: ArrayLike,
    turn: ArrayLike,
    f: ArrayLike,
    ef: ArrayLike,
) -> SphereTriadPoses:
    """Every real pose of a batch of spherical triads, from their degree-8 polynomial.

    B lies on the small circle of arc ``arc_b`` in ``frame_b``, C on that of ``arc_c`` in
    ``frame_c`` (frames as :func:`circle_frame` builds them), with B·C = cos ``bc``; E sits on
    the coupler at arc ``ce`` from C and angle ``turn`` from the great circle C→B (as
    :func:`linkwright.geometry.sphere.point_at`), and E·F = cos ``ef`` for the known unit
    vector ``f``. See the module's text for the method; each returned pose satisfies every
    constraint to :data:`RESIDUAL_TOL`.

    Parameters
    ----------
    frame_b, frame_c : ``(..., 3, 3)``, orthonormal rows (O, e1, e2).
    arc_b, arc_c, bc, ce, ef : arcs in (0, π), radians.
    turn : radians (paper 001's coupler: π − σ).
    f : ``(..., 3)``, unit vector.

    Returns
    -------
    SphereTriadPoses
        Batch shape: all arguments broadcast together.

    Raises
    ------
    InvalidTriad
        Arrays of the wrong shape, non-finite values, arcs outside (0, π), frames that are not
        orthonormal, ``f`` not a unit vector, or shapes that do not broadcast.

    Notes
    -----
    Where the triad is degenerate (the two equations share a factor: a continuum of poses at
    one input, a mechanism that moves with its input held), the polynomial vanishes
    identically, and what is returned is at most 8 arbitrary poses of the continuum.

    Examples
    --------
    A triad with all eight poses real: the spherical Stephenson III of ``linkwright papers 001``
    driven at FG, at θ6 = 280°. Every pose is found and holds every constraint; θ_B and θ_C are
    paper 001's θ1 = ∠BAD and θ4 = ∠CDG.

    >>> from linkwright.mechanisms import SphericalStephenson3
    >>> from linkwright.papers.p001_angles import triad_of
    >>> m = SphericalStephenson3(*np.radians([115, 105, 110, 90, 80, 70, 65, 85, 25]))
    >>> poses = sphere_triad(*triad_of(m, np.radians(280.0)))
    >>> int(poses.count), bool(poses.residual.max() < 1e-14)
    (8, True)
    >>> np.degrees(poses.theta_b).round(3)
    array([-171.04 , -168.477, -106.71 ,  -91.611,  -18.477,   18.475,   46.259,  149.416])
    >>> np.degrees(poses.theta_c).round(3)
    array([ 108.19 , -137.955, -179.386,   34.371,   62.693,  -63.754,  -25.364,  156.55 ])

    Where the link EF cannot close there is no pose, and nothing NaN is marked valid. Here E
    stays within CD + CE = 25° of D, while F is at least FG − DG = 130° from D, and EF is 5°:

    >>> short = SphericalStephenson3(*np.radians([40, 20, 30, 20, 5, 90, 5, 150, 20]))
    >>> none = sphere_triad(*triad_of(short, 0.0))
    >>> int(none.count), bool(np.isnan(none.b).all()), bool(none.valid.any())
    (0, True, False)
    """
    p, batch = _read(frame_b, arc_b, frame_c, arc_c, bc, ce, turn, f, ef)
    flat = _flat(p, batch)
    size = int(np.prod(batch, dtype=int))
    tb = np.full((size, 2 * MAX_POSES), np.nan)
    tc = np.full((size, 2 * MAX_POSES), np.nan)
    for start in range(0, size, CHUNK):
        part = {k: v[start : start + CHUNK] for k, v in flat.items()}
        tb[start : start + CHUNK], tc[start : start + CHUNK] = _solve_chunk(part)
    return _reshape(_select(flat, tb, tc, (size,)), batch)


def _reshape(poses: SphereTriadPoses, batch: tuple[int, ...]) -> SphereTriadPoses:
    return SphereTriadPoses(
        b=poses.b.reshape(batch + poses.b.shape[-2:]),
        c=poses.c.reshape(batch + poses.c.shape[-2:]),
        e=poses.e.reshape(batch + poses.e.shape[-2:]),
        theta_b=poses.theta_b.reshape(batch + poses.theta_b.shape[-1:]),
        theta_c=poses.theta_c.reshape(batch + poses.theta_c.shape[-1:]),
        count=poses.count.reshape(batch),
        residual=poses.residual.reshape(batch + poses.residual.shape[-1:]),
    )


def sphere_triad_sweep(
    frame_b: ArrayLike,
    arc_b: ArrayLike,
    frame_c: ArrayLike,
    arc_c: ArrayLike,
    bc: ArrayLike,
    ce: ArrayLike,
    turn: ArrayLike,
    f: ArrayLike,
    ef: ArrayLike,
    *,
    grid: int = 1024,
) -> SphereTriadPoses:
    """Every real pose of a batch of spherical triads by a sweep: the check of the polynomial.

    θ_B walks ``grid`` equal steps of a turn; C closes the spherical four-bar (circle of arc
    ``bc`` about B ∩ the circle of C) on both branches, sign((B × O_C)·C) = ±1; E follows
    rigidly, and the roots of E·F − cos ``ef`` are bracketed and bisected to adjacent floats by
    :func:`linkwright.engine.triad.sweep_roots` (with its limits: three roots within two steps
    or an assembled window narrower than a step are missed). Arguments and result as
    :func:`sphere_triad`, which shares no step with this but the final residual test.

    Blind where a pose has B at ±O_C (the four-bar's circles are concentric there).

    Examples
    --------
    >>> from linkwright.mechanisms import SphericalStephenson3
    >>> from linkwright.papers.p001_angles import triad_of
    >>> m = SphericalStephenson3(*np.radians([115, 105, 110, 90, 80, 70, 65, 85, 25]))
    >>> swept = sphere_triad_sweep(*triad_of(m, np.radians(280.0)))
    >>> poly = sphere_triad(*triad_of(m, np.radians(280.0)))
    >>> int(swept.count), float(np.abs(swept.b - poly.b).max()) < 1e-12
    (8, True)
    """
    p, batch = _read(frame_b, arc_b, frame_c, arc_c, bc, ce, turn, f, ef)
    q = {k: v[..., None] for k, v in p.items() if v.ndim == len(batch)}
    fb, fc = p["frame_b"][..., None, :, :], p["frame_c"][..., None, :, :]
    axis_c = fc[..., 0, :]
    f_ = p["f"][..., None, :]
    cos_ef = np.cos(q["ef"])

    def place(theta: Array, branch: Array) -> tuple[Array, Array, Array]:
        b = on_circle(fb, q["arc_b"], theta)
        c = sphere.small_circles(
            b, q["bc"], axis_c, q["arc_c"], np.broadcast_to(branch, theta.shape), tol=ASSEMBLY_TOL
        ).point
        e = sphere.point_at(c, b, q["ce"], q["turn"])
        return b, c, e

    def residual(theta: Array, branch: Array) -> Array:
        return sphere.dot(place(theta, branch)[2], f_) - cos_ef

    found = sweep_roots(residual, batch, grid=grid)
    _, c, _ = place(found.psi, np.where(np.isnan(found.branch), 1.0, found.branch))
    theta_c = np.arctan2(sphere.dot(c, fc[..., 2, :]), sphere.dot(c, fc[..., 1, :]))
    size = int(np.prod(batch, dtype=int))
    flat = _flat(p, batch)
    k = found.psi.shape[-1]
    return _reshape(
        _select(
            flat,
            found.psi.reshape(size, k),
            theta_c.reshape(size, k),
            (size,),
        ),
        batch,
    )
