"""Matching an open curve, a piece of some coupler curve, against the atlas's closed ones.

A closed curve's Fourier descriptor says nothing about a piece of it, so an open query is
screened against every entry directly, all at once:

1. **Screen.** Each entry's curve c (N samples over a turn) is cut into arcs of L samples
   (L = N/8 … N, from every start s); the query's m points b are laid on the arc's m evenly
   indexed samples a_s by the best similarity w·a + t ≈ b. Its relative residual is
   1 − |⟨a_s, b − b̄⟩|² / (‖b − b̄‖² ‖a_s − ā_s‖²), and every start's ⟨a_s, b − b̄⟩, Σa_s and
   Σ|a_s|² are correlations of the curve with a kernel of m spikes, so one FFT of each gives
   them for every s. The query is tried both ways round.
2. **Fit.** The best entries are traced densely and fitted by iterated closest points: each
   query point's foot on the placed curve, then the similarity that best carries those feet
   onto the points (the complex least-squares fit), until the RMS distance stops falling.

The RMS distance from the query's points to the whole placed curve ranks them.

On the sphere the arc is laid on the query by a rotation about the centre instead (no scale, no
translation): its residual needs the nine sums Σ b aᵀ, each a correlation of the curve with a
kernel of spikes as before, and the sum of their matrix's signed singular values, found for
every start at once as the largest root of a quartic (Theobald's). The fit is iterated closest
points again, each round's rotation Kabsch's, for many entries at once.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from linkwright.geometry.sphere import best_rotation

__all__ = [
    "by_length",
    "fit_piece",
    "fit_sphere_pieces",
    "kabsch",
    "resampled",
    "screen_pieces",
    "screen_sphere_pieces",
]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]

QUERY_SAMPLES = 32
"""Points the query is resampled to (evenly along its length) for the screen."""
ARC_SHARES = (0.125, 0.1875, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875, 1.0)
"""The arcs tried, as shares of the curve's samples."""
FIT_ROUNDS = 40
NEWTON_STEPS = 60
"""Newton steps to the largest root of the rotation residual's quartic: a simple root is
reached in under ten, a double one halves the error each step."""
SLIDE = 0.05
"""Weight of the point-to-point term in the fit: enough to stop sliding, small enough not to
pull the feet along the curve."""


def resampled(points: Array, count: int) -> Array:
    """``count`` points evenly spaced along the open polyline ``points`` (its ends kept)."""
    step = np.linalg.norm(np.diff(points, axis=0), axis=1)
    along = np.r_[0.0, np.cumsum(step)]
    at = np.linspace(0.0, along[-1], count)
    return np.stack([np.interp(at, along, points[:, k]) for k in range(points.shape[1])], -1)


def by_length(curves: Array, count: int) -> Array:
    """Closed curves (K, N, 2) resampled at ``count`` points evenly spaced along their length
    (the query is spaced so; a curve spaced by its input would stretch against it)."""
    closed = np.concatenate([curves, curves[:, :1]], axis=1)
    step = np.linalg.norm(np.diff(closed, axis=1), axis=-1)
    along = np.concatenate([np.zeros((len(curves), 1)), np.cumsum(step, axis=1)], axis=1)
    total = along[:, -1:]
    at = np.linspace(0.0, 1.0, count, endpoint=False)[None] * total
    # Row by row searchsorted, at once: offset every row's lengths past the one before.
    offset = np.cumsum(np.r_[0.0, total[:-1, 0] + 1.0])[:, None]
    flat = (along + offset).ravel()
    j = np.searchsorted(flat, (at + offset).ravel(), side="right").reshape(at.shape) - 1
    j = np.clip(j - np.arange(len(curves))[:, None] * closed.shape[1], 0, curves.shape[1] - 1)
    rows = np.arange(len(curves))[:, None]
    lo, hi = along[rows, j], along[rows, j + 1]
    with np.errstate(invalid="ignore", divide="ignore"):
        frac = np.nan_to_num((at - lo) / (hi - lo))
    out: Array = closed[rows, j] + frac[..., None] * (closed[rows, j + 1] - closed[rows, j])
    return out


def screen_pieces(curves: Array, query: Array) -> tuple[Array, CArray, CArray]:
    """For curves (K, N, 2) and an open query (m, 2): each curve's least relative residual over
    every arc and start (K,), and the similarity w, t (K,) of that best arc onto the query
    (complex: p ↦ w·p + t on the curve's points, as x + iy)."""
    c = curves[..., 0] + 1j * curves[..., 1]
    k_count, n = c.shape
    m = len(query)
    best = np.full(k_count, np.inf)
    best_w = np.full(k_count, np.nan + 0j)
    best_t = np.full(k_count, np.nan + 0j)
    fc, fc2 = np.fft.fft(np.conj(c), axis=-1), np.fft.fft(np.abs(c) ** 2, axis=-1)
    fplain = np.fft.fft(c, axis=-1)
    valid = np.all(np.isfinite(c), axis=-1)
    for forwards in (True, False):
        b = query[:, 0] + 1j * query[:, 1]
        b = b if forwards else b[::-1]
        centred = b - b.mean()
        energy = float(np.sum(np.abs(centred) ** 2))
        for share in ARC_SHARES:
            length = max(round(share * n), m // 4, 2)
            index = np.round(np.linspace(0.0, length - (share == 1.0), m)).astype(int) % n
            spikes = np.zeros(n, dtype=complex)
            np.add.at(spikes, index, centred)
            ones = np.zeros(n)
            np.add.at(ones, index, 1.0)
            # corr(u, h)[s] = Σ_k u[s + k]·conj(h[k]) = ifft(fft(u)·conj(fft(h))).
            cross = np.fft.ifft(fc * np.conj(np.fft.fft(np.conj(spikes))), axis=-1)
            counts = np.conj(np.fft.fft(ones))
            total = np.fft.ifft(fplain * counts, axis=-1)
            power = np.fft.ifft(fc2 * counts, axis=-1).real
            spread = power - np.abs(total) ** 2 / m
            with np.errstate(invalid="ignore", divide="ignore"):
                rel = 1.0 - np.abs(cross) ** 2 / (energy * spread)
            # An arc that barely moves (a cusp's neighbourhood) fixes no similarity.
            moves = spread > 1e-12 * np.max(spread, axis=-1, keepdims=True)
            rel = np.where(moves & valid[:, None], rel, np.inf)
            s = np.argmin(rel, axis=-1)
            here = rel[np.arange(k_count), s]
            better = here < best
            if not better.any():
                continue
            # ⟨a − ā, b − b̄⟩ = Σ conj(a)·(b − b̄): cross is that sum; w = it / ‖a − ā‖².
            w = cross[np.arange(k_count), s] / spread[np.arange(k_count), s]
            mean_a = total[np.arange(k_count), s] / m
            t = b.mean() - w * mean_a
            best = np.where(better, here, best)
            best_w = np.where(better, w, best_w)
            best_t = np.where(better, t, best_t)
    return best, best_w, best_t


def fit_piece(curve: Array, query: Array, w: complex, t: complex) -> tuple[complex, complex, float]:
    """Iterated closest points from the similarity (w, t): the similarity carrying the closed
    dense ``curve`` (n, 2) nearest the query's points (m, 2), and the RMS distance then.

    Each round finds every point's foot on the placed curve, then solves for the similarity
    that best moves the feet onto the points across the curve (point-to-line, which converges
    fast near the answer) with a little of the point-to-point distance (so that a nearly
    straight piece cannot slide along itself without bound): linear least squares in the four
    numbers of w and t.
    """
    c = curve[:, 0] + 1j * curve[:, 1]
    q = query[:, 0] + 1j * query[:, 1]
    c_next = np.roll(c, -1)
    rows = np.arange(len(q))
    best = (w, t, np.inf)
    for _ in range(FIT_ROUNDS):
        placed, placed_next = w * c + t, w * c_next + t
        d = placed_next - placed
        rel = q[:, None] - placed[None]
        with np.errstate(invalid="ignore", divide="ignore"):
            along = np.clip(np.real(rel * np.conj(d)) / np.abs(d) ** 2, 0.0, 1.0)
        along = np.nan_to_num(along)
        gap = np.abs(rel - along * d)
        j = np.argmin(gap, axis=1)
        rms = float(np.sqrt(np.mean(gap[rows, j] ** 2)))
        if not rms < best[2] * (1 - 1e-9):
            break
        best = (w, t, rms)
        feet = c[j] + along[rows, j] * (c_next[j] - c[j])
        tangent = d[j] / np.maximum(np.abs(d[j]), 1e-300)
        cu = np.conj(tangent)
        # Across the tangent: Im(conj(u)·(w·f + t − q)), linear in (Re w, Im w, Re t, Im t).
        across = np.stack([np.imag(cu * feet), np.real(cu * feet), np.imag(cu), np.real(cu)], -1)
        # Along both axes, lightly: w·f + t − q.
        ax = np.stack(
            [feet.real, -feet.imag, np.ones_like(feet.real), np.zeros_like(feet.real)], -1
        )
        ay = np.stack([feet.imag, feet.real, np.zeros_like(feet.real), np.ones_like(feet.real)], -1)
        system = np.concatenate([across, SLIDE * ax, SLIDE * ay])
        target = np.concatenate([np.imag(cu * q), SLIDE * q.real, SLIDE * q.imag])
        x = np.linalg.lstsq(system, target, rcond=None)[0]
        if not np.all(np.isfinite(x)):
            break
        w, t = complex(x[0], x[1]), complex(x[2], x[3])
    return best


def _nuclear_traces(h: Array) -> Array:
    """max over rotations R of tr(R·hᵀ) for 3 × 3 matrices h (..., 3, 3): σ1 + σ2 ± σ3, the
    last with the sign of det h (Kabsch), for millions of matrices in a few array operations.

    It is the largest root of the quartic (x² − p)² − 8·det(h)·x + 2·(tr(M²) − p²) (M = hᵀh,
    p = tr M), Theobald's quaternion characteristic polynomial (Acta Cryst. A61, 2005):
    expand e1² = p + 2·e2 and e2² = Σ(σiσj)² + 2·e1·e3 in the signed σ's symmetric functions.
    Newton's method from the upper bound √(3p) descends to it monotonically (the quartic's
    roots are all real, so it is convex beyond the largest); where two roots meet (a rank-
    deficient h) it still closes to about √ε of the scale, unlike the trigonometric roots of
    M's characteristic cubic, whose square roots lose half the digits of the smallest. (An SVD
    of each, :func:`~linkwright.geometry.sphere.best_rotation`, is exact but far slower for the
    screen's millions.)
    """
    m = np.einsum("...ki,...kj->...ij", h, h)
    p = np.trace(m, axis1=-2, axis2=-1)
    c1 = -8.0 * np.linalg.det(h)
    c0 = 2.0 * (np.sum(m * m, axis=(-2, -1)) - p * p)
    x = np.sqrt(3.0 * p)
    for _ in range(NEWTON_STEPS):
        square = x * x - p
        slope = 4.0 * x * square + c1
        value = square * square + c1 * x + c0
        with np.errstate(invalid="ignore", divide="ignore"):
            step = value / slope
        # Above the root the value and slope are positive. At a double root both vanish and
        # rounding may leave no root at all: a slope that small (x² − p within 1e-9 of p) is
        # as close as the digits allow, and ends it.
        x = x - np.where((value > 0) & (slope > 1e-9 * x * p), step, 0.0)
    out: Array = x
    return out


def kabsch(points: Array, onto: Array) -> Array:
    """The rotations R (..., 3, 3), det +1, that best lay ``points`` (..., m, 3) on ``onto``
    (..., m, 3): least ``Σ |R·p − q|²`` (:func:`linkwright.geometry.sphere.best_rotation`)."""
    return best_rotation(np.swapaxes(points, -1, -2) @ onto)[1]


def screen_sphere_pieces(curves: Array, query: Array) -> tuple[Array, Array]:
    """The sphere's screen: for curves (K, N, 3) and an open query (m, 3), unit vectors, each
    curve's least mean squared chord over every arc and start (K,) once the arc is turned onto
    the query by its best rotation about the centre, and that rotation (K, 3, 3).

    For a start s, with a_s the arc's m samples, the residual is Σ|a_s|² + Σ|b|² − 2·(σ1 + σ2
    ± σ3), the σ those of S = Σ b aᵀ (Kabsch); each of S's nine entries, for every s at once,
    is the correlation of one coordinate of the curve with a kernel of m spikes.
    """
    k_count, n, _ = curves.shape
    m = len(query)
    best = np.full(k_count, np.inf)
    best_s = np.zeros(k_count, dtype=int)
    best_index = np.zeros((k_count, m), dtype=int)
    best_backwards = np.zeros(k_count, dtype=bool)
    coords = np.fft.rfft(curves, axis=1)  # (K, n//2 + 1, 3)
    norms = np.fft.rfft(np.sum(curves**2, axis=-1), axis=1)
    valid = np.all(np.isfinite(curves), axis=(1, 2))
    for backwards in (False, True):
        b = query[::-1] if backwards else query
        energy = float(np.sum(b**2))
        for share in ARC_SHARES:
            length = max(round(share * n), m // 4, 2)
            index = np.round(np.linspace(0.0, length - (share == 1.0), m)).astype(int) % n
            spikes = np.zeros((n, 3))
            np.add.at(spikes, index, b)
            ones = np.zeros(n)
            np.add.at(ones, index, 1.0)
            kernel = np.conj(np.fft.rfft(spikes, axis=0))  # (n//2 + 1, 3)
            # s[k, t, i, j] = Σ_k' b_i · a_j at start t: corr(a_j, spike_i).
            cross = np.fft.irfft(
                coords[:, :, None, :] * kernel[None, :, :, None], n=n, axis=1
            )  # (K, n, 3, 3)
            power = np.fft.irfft(norms * np.conj(np.fft.rfft(ones))[None], n=n, axis=1)
            residual = power + energy - 2.0 * _nuclear_traces(cross)
            residual = np.where(valid[:, None], residual, np.inf)
            s = np.argmin(residual, axis=-1)
            here = residual[np.arange(k_count), s] / m
            better = here < best
            best = np.where(better, here, best)
            best_s = np.where(better, s, best_s)
            best_index[better] = index[None]
            best_backwards = np.where(better, backwards, best_backwards)
    rotation = np.full((k_count, 3, 3), np.nan)
    ks = np.flatnonzero(np.isfinite(best))
    arcs = curves[ks[:, None], (best_s[ks, None] + best_index[ks]) % n]
    onto = np.where(best_backwards[ks, None, None], query[::-1], query)
    rotation[ks] = kabsch(arcs, onto)
    return best, rotation


FIT_BLOCK = 256
"""Curves fitted together on the sphere (each round holds points × samples of each)."""


def fit_sphere_pieces(curves: Array, query: Array, rotations: Array) -> tuple[Array, Array]:
    """Iterated closest points on the sphere, for many curves at once: from ``rotations``
    (K, 3, 3), the rotations about the centre carrying each closed dense curve (K, n, 3)
    nearest the query's points (m, 3), and the RMS chord distances then (K,). Each round finds
    every point's foot on each turned curve (its segments), then the rotation that best lays
    the feet on the points (Kabsch); a curve keeps its best round.
    """
    if len(curves) > FIT_BLOCK:
        parts = [
            fit_sphere_pieces(curves[i : i + FIT_BLOCK], query, rotations[i : i + FIT_BLOCK])
            for i in range(0, len(curves), FIT_BLOCK)
        ]
        return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])
    k_count, n = curves.shape[:2]
    best_rotation = np.array(rotations, dtype=float)
    best_rms = np.full(k_count, np.inf)
    going = np.all(np.isfinite(best_rotation), axis=(1, 2))
    rotation = np.where(going[:, None, None], best_rotation, np.eye(3))
    for _ in range(FIT_ROUNDS):
        if not going.any():
            break
        idx = np.flatnonzero(going)
        own = curves[idx]
        sub = np.arange(len(idx))[:, None]
        # In each curve's own frame: the query turned back by its rotation. The nearest sample
        # is the one of largest dot product (unit vectors); the foot is on a segment beside it.
        back = query[None] @ rotation[idx]  # (k, m, 3)
        # A batched matrix product (BLAS), several times faster than einsum with c = 3.
        near = np.argmax(back @ own.transpose(0, 2, 1), axis=-1)
        gap = np.full(near.shape, np.inf)
        feet = np.zeros(back.shape)
        for first in (near - 1, near):
            a, b = own[sub, first % n], own[sub, (first + 1) % n]
            seg = b - a
            with np.errstate(invalid="ignore", divide="ignore"):
                t = np.clip(np.sum((back - a) * seg, -1) / np.sum(seg * seg, -1), 0.0, 1.0)
            foot = a + np.nan_to_num(t)[..., None] * seg
            here = np.linalg.norm(back - foot, axis=-1)
            nearer = here < gap
            gap = np.where(nearer, here, gap)
            feet = np.where(nearer[..., None], foot, feet)
        rms = np.sqrt(np.mean(gap**2, axis=-1))
        improved = rms < best_rms[idx] * (1 - 1e-9)
        best_rms[idx[improved]] = rms[improved]
        best_rotation[idx[improved]] = rotation[idx[improved]]
        going[idx[~improved]] = False
        rotation[idx] = kabsch(feet, np.broadcast_to(query, feet.shape))
    return best_rotation, best_rms
