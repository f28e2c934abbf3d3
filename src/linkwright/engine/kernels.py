"""Compiled position kernels for the two hottest cases: planar and spherical four-bars.

The construction plan (:mod:`linkwright.engine.plan`) evaluates any linkage as a sequence of
whole-array NumPy steps; each step allocates its temporaries, so a batch of n mechanisms ×
samples inputs streams through memory a few dozen times. These kernels place A, B and P of a
four-bar in one pass per sample, writing only the results, with the formulas and conventions of
the plan's steps (Crank, DyadRRR, Rigid; SphereCrank, SphereDyad, SphereRigid):

- planar: A = A0 + crank·(cos θ, sin θ); B = circle(A, coupler) ∩ circle(B0, rocker) on the
  branch sign((B0 − A) × (B − A)) = assembly; P = A + u·e + v·perp(e), e the unit vector A→B.
- spherical (paper 000's frame): A0 = (1, 0, 0), B0 = (cos a1, sin a1, 0),
  A = (cos a2, sin a2 cos θ, sin a2 sin θ); B on the coupler and rocker arcs on the branch
  sign((A × B0)·B) = assembly; P at arc ``point_arc`` from A and angle ``point_angle`` = BAP
  about +OA.

Where the dyad does not close (its margin, sin² of the angle at A, below ``-ASSEMBLY_TOL``) all
three joints are NaN, as in :class:`linkwright.engine.Motion`. Positions only: velocities and
accelerations still come from :func:`linkwright.mechanisms.solve`.

numba is optional. :func:`available` says whether the kernels are compiled; without numba the
same loops run as plain Python (correct, but only fit for a handful of samples).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine.plan import ASSEMBLY_TOL

__all__ = [
    "KernelInputError",
    "available",
    "fourbar_positions",
    "positions",
    "prepared_fourbar",
    "spherical_fourbar_positions",
]

Array = NDArray[np.float64]
Triple = tuple[Array, Array, Array]

prange = range  # replaced by numba.prange when the kernels are compiled


class KernelInputError(ValueError):
    """Arguments a kernel cannot take (names the argument and the problem)."""


def _planar_kernel(a0, b0, crank, coupler, rocker, u, v, assembly, cos_t, sin_t, tol, A, B, P):
    n = a0.shape[0]
    samples = cos_t.shape[0]
    nan = np.nan
    for i in prange(n):
        ax0, ay0, bx0, by0 = a0[i, 0], a0[i, 1], b0[i, 0], b0[i, 1]
        r0, r1, r2 = crank[i], coupler[i], rocker[i]
        sign, ui, vi = assembly[i], u[i], v[i]
        # The DyadRRR step's factored forms, hoisted out of the sample loop.
        sum2 = (r1 + r2) ** 2
        dif2 = (r1 - r2) ** 2
        prod = (r1 - r2) * (r1 + r2)
        for j in range(samples):
            ax = ax0 + r0 * cos_t[j]
            ay = ay0 + r0 * sin_t[j]
            dx = bx0 - ax
            dy = by0 - ay
            d2 = dx * dx + dy * dy
            # = h²/r1² = sin² of the angle at A; d2 = 0 (A on B0) cannot close, as in DyadRRR.
            margin = (sum2 - d2) * (d2 - dif2) / (4.0 * d2 * r1 * r1) if d2 > 0.0 else -1.0
            if not margin >= -tol:
                A[i, j, 0] = A[i, j, 1] = nan
                B[i, j, 0] = B[i, j, 1] = nan
                P[i, j, 0] = P[i, j, 1] = nan
                continue
            d = math.sqrt(d2)
            a = (prod + d2) / (2.0 * d)
            h = sign * (r1 * math.sqrt(max(margin, 0.0)))
            bx = ax + (a * dx - h * dy) / d
            by = ay + (a * dy + h * dx) / d
            ex = bx - ax
            ey = by - ay
            inv_len = 1.0 / math.hypot(ex, ey)
            cu = ui * inv_len
            cv = vi * inv_len
            A[i, j, 0] = ax
            A[i, j, 1] = ay
            B[i, j, 0] = bx
            B[i, j, 1] = by
            P[i, j, 0] = ax + (cu * ex - cv * ey)
            P[i, j, 1] = ay + (cu * ey + cv * ex)


def _spherical_kernel(
    frame, crank, coupler, rocker, point_arc, point_angle, assembly, cos_t, sin_t, tol, A, B, P
):
    n = frame.shape[0]
    samples = cos_t.shape[0]
    nan = np.nan
    for i in prange(n):
        bx0, by0 = math.cos(frame[i]), math.sin(frame[i])
        ca, sa = math.cos(crank[i]), math.sin(crank[i])
        r1, r2 = coupler[i], rocker[i]
        cr1, sr1, cr2 = math.cos(r1), math.sin(r1), math.cos(r2)
        sign = assembly[i]
        # Half-sum and half-difference of the dyad's arcs: the Gram determinant's product form
        # 4 sin s sin(s−d) sin(s−r1) sin(s−r2) (SphereDyad, sphere.gram) expanded in sin and cos
        # of d/2, so the sample loop needs no trigonometric call and stays exact at the roots.
        p, q = 0.5 * (r1 + r2), 0.5 * (r1 - r2)
        cp, sp, cq, sq = math.cos(p), math.sin(p), math.cos(q), math.sin(q)
        sl = math.sin(point_arc[i])
        cl = math.cos(point_arc[i])
        sl_c = sl * math.cos(point_angle[i])
        sl_s = sl * math.sin(point_angle[i])
        for j in range(samples):
            ax = ca
            ay = sa * cos_t[j]
            az = sa * sin_t[j]
            # w = A × B0, B0 = (bx0, by0, 0)
            wx = -az * by0
            wy = az * bx0
            wz = ax * by0 - ay * bx0
            sin_d = math.sqrt(wx * wx + wy * wy + wz * wz)
            cos_d = ax * bx0 + ay * by0
            # sin and cos of d/2 from whichever half-angle formula does not cancel.
            if cos_d >= 0.0:
                ch = math.sqrt(0.5 * (1.0 + cos_d))
                sh = sin_d / (2.0 * ch)
            else:
                sh = math.sqrt(0.5 * (1.0 - cos_d))
                ch = sin_d / (2.0 * sh)
            g = (
                4.0
                * (sp * ch + cp * sh)
                * (sp * ch - cp * sh)
                * (sh * cq - ch * sq)
                * (sh * cq + ch * sq)
            )
            ok = sin_d > 0.0
            if ok:
                margin = g / (sin_d * sr1) ** 2
                ok = margin >= -tol
            if not ok:
                for k in range(3):
                    A[i, j, k] = nan
                    B[i, j, k] = nan
                    P[i, j, k] = nan
                continue
            # Orthonormal frame at A: t towards B0 from (A × B0) × A, n = A × t.
            tx = wy * az - wz * ay
            ty = wz * ax - wx * az
            tz = wx * ay - wy * ax
            tn = 1.0 / math.sqrt(tx * tx + ty * ty + tz * tz)
            tx *= tn
            ty *= tn
            tz *= tn
            nx = ay * tz - az * ty
            ny = az * tx - ax * tz
            nz = ax * ty - ay * tx
            # (cos φ, sin φ)·sin r1 sin d = (cos r2 − cos r1 cos d, ±√G): normalise, no atan2.
            y = sign * math.sqrt(max(g, 0.0))
            x = cr2 - cr1 * cos_d
            hyp = math.sqrt(x * x + y * y)
            if hyp > 0.0:
                cphi = x / hyp
                sphi = y / hyp
            else:
                cphi = 1.0
                sphi = 0.0
            bx = cr1 * ax + sr1 * (cphi * tx + sphi * nx)
            by = cr1 * ay + sr1 * (cphi * ty + sphi * ny)
            bz = cr1 * az + sr1 * (cphi * tz + sphi * nz)
            # P = a·A + b·B + c·(A × B), SphereRigid's basis.
            ox = ay * bz - az * by
            oy = az * bx - ax * bz
            oz = ax * by - ay * bx
            sin_ot = math.sqrt(ox * ox + oy * oy + oz * oz)
            b = sl_c / sin_ot
            c = sl_s / sin_ot
            a = cl - b * (ax * bx + ay * by + az * bz)
            A[i, j, 0] = ax
            A[i, j, 1] = ay
            A[i, j, 2] = az
            B[i, j, 0] = bx
            B[i, j, 1] = by
            B[i, j, 2] = bz
            P[i, j, 0] = a * ax + b * bx + c * ox
            P[i, j, 1] = a * ay + b * by + c * oy
            P[i, j, 2] = a * az + b * bz + c * oz


_KERNELS: dict[str, Any] = {}


def _numba() -> Any | None:
    try:
        import numba
    except ImportError:
        return None
    return numba


def available() -> bool:
    """Whether numba is installed, so that the kernels run compiled.

    Without it they still give the same numbers, interpreted (about a thousand times slower).

    Examples
    --------
    >>> isinstance(available(), bool)
    True
    """
    return _numba() is not None


def _kernel(name: str, parallel: bool = True) -> Any:
    key = f"{name}-{'parallel' if parallel else 'serial'}"
    if key not in _KERNELS:
        plain = {"planar": _planar_kernel, "sphere": _spherical_kernel}[name]
        numba = _numba()
        if numba is None:
            _KERNELS[key] = plain
        else:
            global prange
            prange = numba.prange  # resolved as a global when numba compiles the loops
            _KERNELS[key] = numba.njit(cache=True, fastmath=False, parallel=parallel)(plain)
    return _KERNELS[key]


def _theta(theta: ArrayLike) -> tuple[Array, Array]:
    t = np.asarray(theta, dtype=float)
    if t.ndim != 1:
        raise KernelInputError(f"theta: must have shape (samples,), got {t.shape}")
    if not np.all(np.isfinite(t)):
        raise KernelInputError("theta: input angles must be finite")
    # One sincos per sample, shared by every mechanism of the batch.
    return np.ascontiguousarray(np.cos(t)), np.ascontiguousarray(np.sin(t))


def _per_mechanism(values: dict[str, ArrayLike], vectors: frozenset[str]) -> dict[str, Array]:
    """Broadcast each parameter to n mechanisms: (n,) scalars, (n, 2) points."""
    arrays = {k: np.asarray(v, dtype=float) for k, v in values.items()}
    for k, a in arrays.items():
        if k in vectors and a.shape[-1:] != (2,):
            raise KernelInputError(f"{k}: must be a point [x, y] or an (n, 2) array, got {a.shape}")
        if a.ndim > (2 if k in vectors else 1):
            raise KernelInputError(f"{k}: must be one value per mechanism, got shape {a.shape}")
        if not np.all(np.isfinite(a)):
            raise KernelInputError(f"{k}: must be finite")
    sizes = {a.shape[0] for k, a in arrays.items() if a.ndim == (2 if k in vectors else 1)}
    sizes.discard(1)
    if len(sizes) > 1:
        raise KernelInputError(f"per-mechanism arrays disagree on n: {sorted(sizes)}")
    n = sizes.pop() if sizes else 1
    out = {}
    for k, a in arrays.items():
        shape = (n, 2) if k in vectors else (n,)
        out[k] = np.ascontiguousarray(np.broadcast_to(a, shape))
    return out


def _check_signs(assembly: Array) -> None:
    if not np.all(np.abs(assembly) == 1):
        raise KernelInputError("assembly: must be 1 or -1")


def _outputs(out: Triple | None, shape: tuple[int, ...]) -> Triple:
    if out is None:
        return np.empty(shape), np.empty(shape), np.empty(shape)
    if len(out) != 3:
        raise KernelInputError("out: must be three arrays (A, B, P)")
    for name, a in zip("ABP", out, strict=True):
        if not (
            isinstance(a, np.ndarray)
            and a.shape == shape
            and a.dtype == np.float64
            and a.flags.c_contiguous
            and a.flags.writeable
        ):
            raise KernelInputError(
                f"out: {name} must be a writeable C-contiguous float64 array of shape {shape}"
            )
    return out[0], out[1], out[2]


def _planar_args(A0, B0, crank, coupler, rocker, u, v, assembly, theta, out) -> tuple:
    """The planar kernel's arguments, checked and broadcast, its outputs last."""
    p = _per_mechanism(
        dict(
            A0=A0, B0=B0, crank=crank, coupler=coupler, rocker=rocker, u=u, v=v, assembly=assembly
        ),
        frozenset({"A0", "B0"}),
    )
    for k in ("crank", "coupler", "rocker"):
        if np.any(p[k] <= 0):
            raise KernelInputError(f"{k}: must be a positive length")
    _check_signs(p["assembly"])
    cos_t, sin_t = _theta(theta)
    outputs = _outputs(out, (p["crank"].shape[0], cos_t.shape[0], 2))
    return (
        p["A0"], p["B0"], p["crank"], p["coupler"], p["rocker"], p["u"], p["v"],
        p["assembly"], cos_t, sin_t, ASSEMBLY_TOL, *outputs,
    )  # fmt: skip


def fourbar_positions(
    A0: ArrayLike,
    B0: ArrayLike,
    crank: ArrayLike,
    coupler: ArrayLike,
    rocker: ArrayLike,
    u: ArrayLike,
    v: ArrayLike,
    assembly: ArrayLike,
    theta: ArrayLike,
    out: Triple | None = None,
) -> Triple:
    """Joints A, B, P of n planar four-bars at the shared inputs θ, in one compiled pass.

    Conventions of :class:`linkwright.mechanisms.FourBar`. All samples of all mechanisms
    share ``theta``; the sines and cosines are taken once.

    Parameters
    ----------
    A0, B0 : ground pivots, shape (2,) or (n, 2).
    crank, coupler, rocker : link lengths (> 0), shape () or (n,).
    u, v : coupler point P in the frame with origin A and x-axis along A→B, shape () or (n,).
    assembly : sign((B0 − A) × (B − A)), ±1, shape () or (n,).
    theta : input angles (radians), shape (samples,).
    out : optional preallocated (A, B, P), each float64 C-contiguous (n, samples, 2).

    Returns
    -------
    A, B, P : arrays of shape (n, samples, 2); NaN (all three) where the dyad does not close.

    Examples
    --------
    The crank-rocker of :func:`linkwright.mechanisms.solve`'s example, P the coupler's midpoint
    lifted by 1; at θ = 0, A = (1, 0) and B = (4.625, 3.443744) (|AB| = 5, |B0B| = 3.5):

    >>> A, B, P = fourbar_positions([0, 0], [4, 0], 1, 5, 3.5, 2.5, 1.0, 1, [0.0, np.pi])
    >>> B[0].round(6)
    array([[4.625   , 3.443744],
           [2.775   , 3.278624]])
    >>> P[0, 0].round(6)  # (1, 0) + 2.5·(0.725, 0.688749) + 1·(−0.688749, 0.725)
    array([2.123751, 2.446872])

    At θ = π, A = (−1, 0) is d = 5 from B0: B lies (25 − 12.25 + 25)/10 = 3.775 along A→B0 and
    √(25 − 3.775²) = 3.278624 to its left. A linkage that cannot assemble is NaN:

    >>> A, B, P = fourbar_positions([0, 0], [10, 0], 1, 2, 3, 0, 0, 1, [0.0])
    >>> A, B
    (array([[[nan, nan]]]), array([[[nan, nan]]]))
    """
    args = _planar_args(A0, B0, crank, coupler, rocker, u, v, assembly, theta, out)
    _kernel("planar")(*args)
    return args[-3:]


def prepared_fourbar(
    A0: ArrayLike,
    B0: ArrayLike,
    crank: ArrayLike,
    coupler: ArrayLike,
    rocker: ArrayLike,
    u: ArrayLike,
    v: ArrayLike,
    assembly: ArrayLike,
    theta: ArrayLike,
) -> Callable[[], Triple]:
    """A zero-argument call that recomputes :func:`fourbar_positions` for fixed arguments.

    Everything that does not change between calls (checks, broadcasting, the sines and cosines
    of θ, the output arrays) is done once here; each call is then one compiled pass, without
    threads (starting them costs more than one short curve). This is the latency path: an
    interactive tool redrawing one curve as a dimension is dragged re-prepares only when the
    dimension changes. The returned arrays are overwritten by the next call.

    Examples
    --------
    >>> curve = prepared_fourbar([0, 0], [4, 0], 1, 5, 3.5, 2.5, 1.0, 1, [0.0, np.pi])
    >>> A, B, P = curve()
    >>> B[0].round(6)
    array([[4.625   , 3.443744],
           [2.775   , 3.278624]])
    """
    args = _planar_args(A0, B0, crank, coupler, rocker, u, v, assembly, theta, None)
    kernel = _kernel("planar", parallel=args[2].shape[0] > 1)
    outputs = args[-3:]

    def run() -> Triple:
        kernel(*args)
        return outputs

    return run


def spherical_fourbar_positions(
    frame: ArrayLike,
    crank: ArrayLike,
    coupler: ArrayLike,
    rocker: ArrayLike,
    point_arc: ArrayLike,
    point_angle: ArrayLike,
    assembly: ArrayLike,
    theta: ArrayLike,
    out: Triple | None = None,
) -> Triple:
    """Joints A, B, P (unit vectors) of n spherical four-bars at the shared inputs θ.

    Conventions of :class:`linkwright.mechanisms.SphericalFourBar` (paper 000's frame; all
    angles in radians). The dyad's Gram determinant is taken in its product form, as in
    :func:`linkwright.geometry.sphere.gram`, so a limit position stays a limit position.

    Parameters
    ----------
    frame, crank, coupler, rocker : arcs a1..a4, each in (0, π), shape () or (n,).
    point_arc, point_angle : arc AP and angle BAP about +OA, shape () or (n,).
    assembly : sign((A × B0)·B), ±1, shape () or (n,).
    theta : input angles (radians), shape (samples,).
    out : optional preallocated (A, B, P), each float64 C-contiguous (n, samples, 3).

    Returns
    -------
    A, B, P : arrays of shape (n, samples, 3); NaN (all three) where the dyad does not close.

    Examples
    --------
    Paper 000's Fig. 6 crank-rocker at θ = 0 (as :class:`~linkwright.mechanisms.SphericalFourBar`
    gives it):

    >>> fig6 = np.radians([40, 20, 45, 35, 50, 130])
    >>> A, B, P = spherical_fourbar_positions(*fig6, 1, [0.0])
    >>> B.round(6)
    array([[[0.509774, 0.666849, 0.543546]]])

    Every arc is kept: |AB| = 45°, |B0B| = 35°.

    >>> b0 = np.array([np.cos(fig6[0]), np.sin(fig6[0]), 0.0])
    >>> np.degrees(np.arccos([A[0, 0] @ B[0, 0], b0 @ B[0, 0]])).round(9)
    array([45., 35.])

    A linkage that cannot assemble is NaN:

    >>> spherical_fourbar_positions(*np.radians([90, 10, 20, 30, 0, 0]), 1, [0.0])[1]
    array([[[nan, nan, nan]]])
    """
    p = _per_mechanism(
        dict(
            frame=frame, crank=crank, coupler=coupler, rocker=rocker,
            point_arc=point_arc, point_angle=point_angle, assembly=assembly,
        ),
        frozenset(),
    )  # fmt: skip
    for k in ("frame", "crank", "coupler", "rocker"):
        if np.any((p[k] <= 0) | (p[k] >= np.pi)):
            raise KernelInputError(f"{k}: a spherical link's arc must lie strictly in (0, π)")
    _check_signs(p["assembly"])
    cos_t, sin_t = _theta(theta)
    n = p["frame"].shape[0]
    A, B, P = _outputs(out, (n, cos_t.shape[0], 3))
    _kernel("sphere")(
        p["frame"], p["crank"], p["coupler"], p["rocker"], p["point_arc"], p["point_angle"],
        p["assembly"], cos_t, sin_t, ASSEMBLY_TOL, A, B, P,
    )  # fmt: skip
    return A, B, P


def positions(mechanism: Any, theta: ArrayLike) -> dict[str, Array]:
    """A, B, P of a :class:`~linkwright.mechanisms.FourBar` or
    :class:`~linkwright.mechanisms.SphericalFourBar` through the kernels.

    The mechanism's batch shape must be () or (n,); the result has the shape of
    ``solve(mechanism, theta).positions`` for those joints: batch + (samples, 2 or 3).

    Examples
    --------
    >>> from linkwright.mechanisms import FourBar
    >>> pos = positions(FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5), [0.0])
    >>> pos["B"].round(6)
    array([[4.625   , 3.443744]])
    """
    from linkwright.mechanisms.planar import FourBar
    from linkwright.mechanisms.spherical import SphericalFourBar

    batch = mechanism.batch_shape if isinstance(mechanism, FourBar | SphericalFourBar) else None
    if batch is None:
        raise KernelInputError(
            f"positions: kernels exist for FourBar and SphericalFourBar, "
            f"not {type(mechanism).__name__}"
        )
    if len(batch) > 1:
        raise KernelInputError(f"positions: batch shape must be () or (n,), got {batch}")
    m = mechanism
    if isinstance(m, FourBar):
        A, B, P = fourbar_positions(
            m.A0, m.B0, m.crank, m.coupler, m.rocker, m.u, m.v, m.assembly, theta
        )
    else:
        A, B, P = spherical_fourbar_positions(
            m.frame, m.crank, m.coupler, m.rocker, m.point_arc, m.point_angle, m.assembly, theta
        )
    if not batch:
        A, B, P = A[0], B[0], P[0]
    return {"A": A, "B": B, "P": P}
