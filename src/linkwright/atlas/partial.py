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
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["by_length", "fit_piece", "resampled", "screen_pieces"]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]

QUERY_SAMPLES = 32
"""Points the query is resampled to (evenly along its length) for the screen."""
ARC_SHARES = (0.125, 0.1875, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875, 1.0)
"""The arcs tried, as shares of the curve's samples."""
FIT_ROUNDS = 40
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
