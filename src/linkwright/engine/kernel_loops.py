"""The per-sample loops of the compiled four-bar kernels, written for numba.

Each loop places A, B and P of a batch of planar or spherical four-bars (P alone for the coupler
curves; with velocities and accelerations for the planar motion) in one pass per sample, with
the formulas and conventions of the construction plan's steps; :mod:`linkwright.engine.kernels`
describes them, checks the arguments and runs the loops through
:func:`~linkwright.engine.kernels.compiled`. They are plain Python in this module: ``prange``
is ``range`` here, and the streaming-store helpers (:data:`STREAMING`) are plain stores;
compiled, each loop runs in a namespace of its own where ``prange`` is numba's and the helpers
are their LLVM forms (a non-temporal 16-byte store, a memory fence).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "CHUNK",
    "STREAMING",
    "planar_kernel",
    "planar_motion_kernel",
    "spherical_kernel",
]

Array = NDArray[np.float64]


prange = range  # numba.prange in the compiled kernels' own namespace (see compiled)

# Mechanisms per parallel task: each task fills a scratch block that stays in cache.
CHUNK = 16


def _stream_pair(out: Array, index: int, x: float, y: float) -> None:
    """Store (x, y) as pair ``index`` of the doubles of ``out`` (C-contiguous, last axis 2,
    16-byte aligned). Compiled, this is one streaming (non-temporal) 16-byte store."""
    pairs = out.reshape(-1, 2)
    pairs[index, 0] = x
    pairs[index, 1] = y


def _store_fence() -> None:
    """Compiled, a full memory fence: streaming stores are weakly ordered, and must be visible
    before a thread reports its part of a parallel loop done. Interpreted, nothing to do."""


def _stream_pair_form(numba: Any) -> Any:
    from llvmlite import ir

    # numba's typing and LLVM's builders are untyped: Any throughout (and the decorator is
    # applied by a call, which mypy does not take for an untyped decorator).
    def stream_pair(typingctx: Any, out: Any, index: Any, x: Any, y: Any) -> tuple[Any, Any]:
        def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
            array, position, first, second = args
            data = context.make_array(signature.args[0])(context, builder, array).data
            pair = ir.VectorType(ir.DoubleType(), 2)
            address = builder.gep(builder.bitcast(data, pair.as_pointer()), [position])
            value = ir.Constant(pair, ir.Undefined)
            for lane, part in enumerate((first, second)):
                value = builder.insert_element(value, part, ir.Constant(ir.IntType(32), lane))
            store = builder.store(value, address, align=16)
            flag = builder.module.add_metadata([ir.Constant(ir.IntType(32), 1)])
            store.set_metadata("nontemporal", flag)
            return context.get_dummy_value()

        return numba.types.void(out, index, x, y), codegen

    return numba.extending.intrinsic(stream_pair)


def _store_fence_form(numba: Any) -> Any:
    def store_fence(typingctx: Any) -> tuple[Any, Any]:
        def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
            builder.fence("seq_cst")
            return context.get_dummy_value()

        return numba.types.void(), codegen

    return numba.extending.intrinsic(store_fence)


_stream_pair.numba_form = _stream_pair_form  # type: ignore[attr-defined]
_store_fence.numba_form = _store_fence_form  # type: ignore[attr-defined]
STREAMING = (_stream_pair, _store_fence)


def planar_kernel(
    params: Array,
    cos_t: Array,
    sin_t: Array,
    tol: float,
    store_ab: bool,
    stream: bool,
    A: Array,
    B: Array,
    P: Array,
) -> None:
    n = params.shape[0]
    samples = cos_t.shape[0]
    nan = np.nan
    for c in prange((n + CHUNK - 1) // CHUNK):
        # Components go to separate scratch rows first: the sample loop then has no interleaved
        # stores and no branch, so LLVM vectorises it (4-8 samples per instruction); the
        # interleaving copy that follows runs from cache.
        rows = np.empty((6, samples))
        for i in range(c * CHUNK, min(n, (c + 1) * CHUNK)):
            # Columns as PLANAR_FIELDS: A0, B0, crank, coupler, rocker, u, v, assembly.
            ax0, ay0, bx0, by0 = params[i, 0], params[i, 1], params[i, 2], params[i, 3]
            r0, r1, r2 = params[i, 4], params[i, 5], params[i, 6]
            # The DyadRRR step's factored forms, hoisted out of the sample loop.
            sum2 = (r1 + r2) ** 2
            dif2 = (r1 - r2) ** 2
            prod = (r1 - r2) * (r1 + r2)
            half_sign = 0.5 * params[i, 9]
            quarter_r1 = 0.25 / (r1 * r1)
            # P = A + (u·e + v·perp(e))/r1 with e = B − A, whose length is r1 by construction.
            ui, vi = params[i, 7] / r1, params[i, 8] / r1
            for j in range(samples):
                ax = ax0 + r0 * cos_t[j]
                ay = ay0 + r0 * sin_t[j]
                dx = bx0 - ax
                dy = by0 - ay
                d2 = dx * dx + dy * dy
                inv_d2 = 1.0 / d2
                k = (sum2 - d2) * (d2 - dif2)  # = 4·d²·h², exact near either root
                # margin = h²/r1² = sin² of the angle at A; d2 = 0 makes it NaN: not closed.
                bad = 0.0 if k * inv_d2 * quarter_r1 >= -tol else nan
                along = 0.5 * (prod + d2) * inv_d2  # a/d
                across = half_sign * math.sqrt(max(k, 0.0)) * inv_d2  # ±h/d
                ex = along * dx - across * dy
                ey = along * dy + across * dx
                rows[0, j] = ax + bad
                rows[1, j] = ay + bad
                rows[2, j] = ax + ex + bad
                rows[3, j] = ay + ey + bad
                rows[4, j] = ax + (ui * ex - vi * ey) + bad
                rows[5, j] = ay + (ui * ey + vi * ex) + bad
            if stream:
                first = i * samples
                if store_ab:
                    for j in range(samples):
                        _stream_pair(A, first + j, rows[0, j], rows[1, j])
                        _stream_pair(B, first + j, rows[2, j], rows[3, j])
                for j in range(samples):
                    _stream_pair(P, first + j, rows[4, j], rows[5, j])
                continue
            if store_ab:
                for j in range(samples):
                    A[i, j, 0] = rows[0, j]
                    A[i, j, 1] = rows[1, j]
                    B[i, j, 0] = rows[2, j]
                    B[i, j, 1] = rows[3, j]
            for j in range(samples):
                P[i, j, 0] = rows[4, j]
                P[i, j, 1] = rows[5, j]
        if stream:
            _store_fence()


def planar_motion_kernel(
    params: Array, cos_t: Array, sin_t: Array, tol: float, sing_sin: float, sing_margin: float,
    A: Array, B: Array, P: Array, VA: Array, VB: Array, VP: Array, AA: Array, AB: Array,
    AP: Array,
) -> None:  # fmt: skip
    n = params.shape[0]
    samples = cos_t.shape[0]
    nan = np.nan
    for c in prange((n + CHUNK - 1) // CHUNK):
        rows = np.empty((18, samples))
        for i in range(c * CHUNK, min(n, (c + 1) * CHUNK)):
            ax0, ay0, bx0, by0 = params[i, 0], params[i, 1], params[i, 2], params[i, 3]
            r0, r1, r2 = params[i, 4], params[i, 5], params[i, 6]
            sum2 = (r1 + r2) ** 2
            dif2 = (r1 - r2) ** 2
            prod = (r1 - r2) * (r1 + r2)
            half_sign = 0.5 * params[i, 9]
            quarter_r1 = 0.25 / (r1 * r1)
            inv_r1r2 = 1.0 / (r1 * r2)
            ui, vi = params[i, 7] / r1, params[i, 8] / r1
            for j in range(samples):
                cj, sj = cos_t[j], sin_t[j]
                ax = ax0 + r0 * cj
                ay = ay0 + r0 * sj
                dx = bx0 - ax
                dy = by0 - ay
                d2 = dx * dx + dy * dy
                inv_d2 = 1.0 / d2
                k = (sum2 - d2) * (d2 - dif2)
                margin = k * inv_d2 * quarter_r1
                bad = 0.0 if margin >= -tol else nan
                along = 0.5 * (prod + d2) * inv_d2
                across = half_sign * math.sqrt(max(k, 0.0)) * inv_d2
                ex = along * dx - across * dy
                ey = along * dy + across * dx
                bx, by = ax + ex, ay + ey
                # The DyadRRR step's derivatives: rows B − A and B − B0 of the differentiated
                # constraints, solved by Cramer's rule; singular (NaN) where the step says so.
                fx, fy = bx - bx0, by - by0
                det = ex * fy - ey * fx
                regular = (abs(det * inv_r1r2) > sing_sin) & (margin > sing_margin)
                bad_d = bad if regular else nan
                inv_det = 1.0 / det
                vax, vay = -r0 * sj, r0 * cj
                rhs = ex * vax + ey * vay
                vbx = rhs * fy * inv_det
                vby = -fx * rhs * inv_det
                wx, wy = vbx - vax, vby - vay
                aax, aay = -r0 * cj, -r0 * sj
                rhs1 = ex * aax + ey * aay - (wx * wx + wy * wy)
                rhs2 = -(vbx * vbx + vby * vby)
                abx = (rhs1 * fy - rhs2 * ey) * inv_det
                aby = (ex * rhs2 - fx * rhs1) * inv_det
                gx, gy = abx - aax, aby - aay
                rows[0, j] = ax + bad
                rows[1, j] = ay + bad
                rows[2, j] = bx + bad
                rows[3, j] = by + bad
                rows[4, j] = ax + (ui * ex - vi * ey) + bad
                rows[5, j] = ay + (ui * ey + vi * ex) + bad
                rows[6, j] = vax + bad_d
                rows[7, j] = vay + bad_d
                rows[8, j] = vbx + bad_d
                rows[9, j] = vby + bad_d
                rows[10, j] = vax + (ui * wx - vi * wy) + bad_d
                rows[11, j] = vay + (ui * wy + vi * wx) + bad_d
                rows[12, j] = aax + bad_d
                rows[13, j] = aay + bad_d
                rows[14, j] = abx + bad_d
                rows[15, j] = aby + bad_d
                rows[16, j] = aax + (ui * gx - vi * gy) + bad_d
                rows[17, j] = aay + (ui * gy + vi * gx) + bad_d
            for j in range(samples):
                for k2 in range(2):
                    A[i, j, k2] = rows[k2, j]
                    B[i, j, k2] = rows[2 + k2, j]
                    P[i, j, k2] = rows[4 + k2, j]
                    VA[i, j, k2] = rows[6 + k2, j]
                    VB[i, j, k2] = rows[8 + k2, j]
                    VP[i, j, k2] = rows[10 + k2, j]
                    AA[i, j, k2] = rows[12 + k2, j]
                    AB[i, j, k2] = rows[14 + k2, j]
                    AP[i, j, k2] = rows[16 + k2, j]


def spherical_kernel(
    params: Array,
    cos_t: Array,
    sin_t: Array,
    tol: float,
    store_ab: bool,
    A: Array,
    B: Array,
    P: Array,
) -> None:
    n = params.shape[0]
    samples = cos_t.shape[0]
    nan = np.nan
    for c in prange((n + CHUNK - 1) // CHUNK):
        rows = np.empty((9, samples))  # as in the planar kernel: branch-free, vectorised
        for i in range(c * CHUNK, min(n, (c + 1) * CHUNK)):
            # Columns as SPHERE_FIELDS: frame, crank, coupler, rocker, point arc and angle, sign.
            frame, crank, r1, r2 = params[i, 0], params[i, 1], params[i, 2], params[i, 3]
            point_arc, point_angle = params[i, 4], params[i, 5]
            bx0, by0 = math.cos(frame), math.sin(frame)
            ca, sa = math.cos(crank), math.sin(crank)
            cr1, sr1, cr2 = math.cos(r1), math.sin(r1), math.cos(r2)
            sign = params[i, 6]
            inv_sr1_2 = 1.0 / (sr1 * sr1)
            # Half-sum and half-difference of the dyad's arcs: the Gram determinant's product
            # form 4 sin s sin(s−d) sin(s−r1) sin(s−r2) (SphereDyad, sphere.gram) expanded in
            # sin and cos of d/2, so the sample loop needs no trigonometric call and stays exact
            # at the roots.
            p, q = 0.5 * (r1 + r2), 0.5 * (r1 - r2)
            cp, sp, cq, sq = math.cos(p), math.sin(p), math.cos(q), math.sin(q)
            cl = math.cos(point_arc)
            # P = cos(arc)·A' + … in SphereRigid's basis A, B, A × B; |A × B| = sin r1.
            pb = math.sin(point_arc) * math.cos(point_angle) / sr1
            pc = math.sin(point_arc) * math.sin(point_angle) / sr1
            for j in range(samples):
                ax = ca
                ay = sa * cos_t[j]
                az = sa * sin_t[j]
                # w = A × B0, B0 = (bx0, by0, 0); |w| = sin d
                wx = -az * by0
                wy = az * bx0
                wz = ax * by0 - ay * bx0
                sin_d = math.sqrt(wx * wx + wy * wy + wz * wz)
                cos_d = ax * bx0 + ay * by0
                # sin and cos of d/2 from whichever half-angle formula does not cancel.
                big = math.sqrt(0.5 * (1.0 + abs(cos_d)))
                small = sin_d / (2.0 * big)
                ch = big if cos_d >= 0.0 else small
                sh = small if cos_d >= 0.0 else big
                g = (
                    4.0
                    * (sp * ch + cp * sh)
                    * (sp * ch - cp * sh)
                    * (sh * cq - ch * sq)
                    * (sh * cq + ch * sq)
                )
                # A on B0 (sin d = 0) cannot close: bad is NaN there, and no division fails.
                inv_sd = 1.0 / sin_d if sin_d > 0.0 else nan
                # margin = G/(sin d sin r1)², sin² of the angle at A; sin d = 0 cannot close.
                margin = g * inv_sd * inv_sd * inv_sr1_2
                bad = 0.0 if (sin_d > 0.0) & (margin >= -tol) else nan
                # Orthonormal frame at A: t towards B0 is (A × B0) × A / sin d, n = A × t.
                tx = (wy * az - wz * ay) * inv_sd
                ty = (wz * ax - wx * az) * inv_sd
                tz = (wx * ay - wy * ax) * inv_sd
                nx = ay * tz - az * ty
                ny = az * tx - ax * tz
                nz = ax * ty - ay * tx
                # (cos φ, sin φ)·sin r1 sin d = (cos r2 − cos r1 cos d, ±√G): normalise, no atan2.
                y = sign * math.sqrt(max(g, 0.0))
                x = cr2 - cr1 * cos_d
                hyp = math.sqrt(x * x + y * y)
                inv_hyp = 1.0 / hyp if hyp > 0.0 else 0.0
                cphi = x * inv_hyp if hyp > 0.0 else 1.0
                sphi = y * inv_hyp if hyp > 0.0 else 0.0
                bx = cr1 * ax + sr1 * (cphi * tx + sphi * nx)
                by = cr1 * ay + sr1 * (cphi * ty + sphi * ny)
                bz = cr1 * az + sr1 * (cphi * tz + sphi * nz)
                ox = ay * bz - az * by
                oy = az * bx - ax * bz
                oz = ax * by - ay * bx
                pa = cl - pb * (ax * bx + ay * by + az * bz)
                rows[0, j] = ax + bad
                rows[1, j] = ay + bad
                rows[2, j] = az + bad
                rows[3, j] = bx + bad
                rows[4, j] = by + bad
                rows[5, j] = bz + bad
                rows[6, j] = pa * ax + pb * bx + pc * ox + bad
                rows[7, j] = pa * ay + pb * by + pc * oy + bad
                rows[8, j] = pa * az + pb * bz + pc * oz + bad
            if store_ab:
                for j in range(samples):
                    for k in range(3):
                        A[i, j, k] = rows[k, j]
                        B[i, j, k] = rows[3 + k, j]
            for j in range(samples):
                for k in range(3):
                    P[i, j, k] = rows[6 + k, j]
