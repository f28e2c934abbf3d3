"""Spherical curve descriptors: fixed-length vectors that forget how a closed curve on the unit
sphere is turned (any rotation of the sphere, SO(3)), where it starts and which way it runs —
and keep its shape *and its size* (the sphere has no scale symmetry: a small circle of 20° and
one of 40° are different curves). The coupler curves of spherical four-bars are such curves.

**Coefficients.** A curve is the closed geodesic polygon through its points (unit vectors): a
great-circle arc joins each point to the next. Parametrised by arc length s ∈ [0, L) it is a
point x(s) of R³, and its Fourier coefficients X_n = (1/L) ∫ x(s) e^{−iωs} ds, ω = 2πn/L, are
exact for such a polygon, in the manner of Kuhl and Giardina's exact polygon coefficients
("Elliptic Fourier features of a closed contour", 1982; see :mod:`linkwright.curves.fourier`).
On the arc j of length θ_j, with midpoint μ_j, unit tangent τ_j there (along the chord) and
midpoint parameter m_j, x(m_j + t) = μ_j cos t + τ_j sin t for |t| ≤ θ_j/2, so

    X_n = (1/L) Σ_j (θ_j/2) e^{−iω m_j} [(S⁻ + S⁺) μ_j − i (S⁻ − S⁺) τ_j],
    S∓ = sinc((ω ∓ 1) θ_j/2),  sinc(y) = sin(y)/y,

(derived here by integrating cos t·e^{−iωt} and sin t·e^{−iωt} over each arc) with no
resampling: inserting points on the arcs changes nothing, and the invariances hold to
rounding. X_0 is the length-weighted mean direction m = (1/L) Σ_j 2 sin(θ_j/2) μ_j, and the
curve's scatter matrix (1/L) ∫ x xᵀ ds = (1/L) Σ_j [(θ_j + sin θ_j) μ_j μ_jᵀ +
(θ_j − sin θ_j) τ_j τ_jᵀ]/2 is exact too.

**Normalisation.** A rotation Q of the sphere maps every X_n to Q X_n, a start shift of a
fraction σ multiplies X_n by e^{2πinσ}, running backwards conjugates X_n. So:

- a pole (unit vector) that turns with the curve is chosen, and the coefficients are written
  in a frame whose third axis is the pole: Z_n = X_n·e₁ + i X_n·e₂ (n = −K … K, X_−n = X̄_n)
  is the curve seen from above the pole (its orthographic projection), H_n = X_n·e₃ its height;
- rotation about the pole, start and direction are then fixed from Z_{±1} exactly as the planar
  descriptor fixes them (Z_1 and Z_−1 real and positive, four variants), the same start shift
  applied to H_n; nothing is divided by an energy, so the size stays.

The pole is the mean direction m̂ = m/|m| where that is well conditioned; for a curve near a
great circle m is small and its direction unreliable, and the scatter matrix's least
eigenvector e (the normal of the plane nearest the curve) is used instead, signed so that
e·m ≥ 0. m̂ moves by about δ/|m| when the curve moves by δ, e by about δ/(λ₂ − λ₁) (the gap
between the scatter matrix's two least eigenvalues): the canonical descriptor uses m̂ where
|m| ≥ λ₂ − λ₁, e elsewhere. The variants cover every choice — the three poles m̂, e and −e,
each with the four planar normalisations — so that a curve near either threshold, or with a
sign of e that m does not fix, still finds its stored canonical descriptor among its variants.

The brief for this module suggested the azimuthal equidistant projection of the curve and the
planar coefficients of its image. The coefficients of the curve in R³ were preferred: the
image of a great-circle arc is not a segment, so the planar exact-polygon formula would not be
exact (sampling density would matter), the projection is singular at the pole's antipode, and
the distance below would be a distance on the map, not on the sphere.

**Distance.** The descriptor (D = 6K + 3 numbers) is [Re Z_{±n}, Im Z_{±n} (the planar layout,
4K); √2·Re H_n, √2·Im H_n (n = 1 … K); Re Z_0, Im Z_0, H_0]. By Parseval's theorem its
squared Euclidean distance to another curve's is Σ_{|n| ≤ K} |X_n − Y_n|², the mean squared
chord distance between the two band-limited curves, point by point by arc length, at the
rotation and start their normalisations chose (the √2 counts H_−n = H̄_n). Nothing is
weighted by hand: the distance is in the units of :func:`sphere_align`'s ``rms`` (chords of
the unit sphere) and never below it but for the band limit, so it ranks candidates as the
aligned error does.

:func:`sphere_align` finds the best rotation for every whole start shift by the Kabsch solution
of Wahba's problem (G. Wahba, "A least squares estimate of satellite attitude", SIAM Review,
1965; W. Kabsch, Acta Cryst. A32, 1976), proper rotations only (the SVD's sign fix), with the
correlation matrices at every shift from FFTs; the best shift is then refined between samples
as :func:`linkwright.curves.aligned_error` does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.curves.fourier import (
    DEFAULT_HARMONICS,
    DEFAULT_SAMPLES,
    Complex,
    CurveError,
    circular_correlation,
    closed_choice,
    closed_phases,
    locate,
    refine_shift,
    shifted_samples,
    start_fraction,
)
from linkwright.engine.kernels import available, compiled
from linkwright.geometry.sphere import best_rotation

__all__ = [
    "SphereAlignment",
    "sphere_align",
    "sphere_descriptor_variants",
    "sphere_descriptors",
    "sphere_resample",
]

Array = NDArray[np.float64]

UNIT_TOLERANCE = 1e-6  # points further than this from the unit sphere are refused
CHUNK = 2048  # curves per pass: bounds the temporaries (chunk × points × 3) whatever the batch
POLES = 3  # m̂, e, −e
VARIANTS = 4 * POLES

prange = range  # numba.prange in the compiled kernel's own namespace


def _as_sphere_curves(points: ArrayLike, normalise: bool = True) -> Array:
    p = np.asarray(points, dtype=float)
    if p.ndim < 2 or p.shape[-1] != 3:
        raise CurveError(f"points: must have shape (..., count, 3), got {p.shape}")
    if p.shape[-2] < 3:
        raise CurveError(f"points: a curve needs at least 3 points, got {p.shape[-2]}")
    length = np.sqrt(np.einsum("...i,...i->...", p, p))
    worst = float(np.fmax.reduce(np.abs(length - 1.0), axis=None, initial=0.0))  # NaN skipped
    if worst > UNIT_TOLERANCE:
        raise CurveError(f"points: must be unit vectors, one is {worst:.3g} off")
    return _unit(p) if normalise else p


def _unit(p: Array) -> Array:
    """Exactly unit vectors: the arc formulas assume them."""
    unit: Array = p / np.sqrt(np.einsum("...i,...i->...", p, p))[..., None]
    return unit


def _arcs(p: Array, q: Array) -> tuple[Array, Array, Array]:
    """Arc length θ, midpoint μ and unit tangent τ at the midpoint (along the chord) of the
    great-circle arcs from p to q. Antipodal ends have no arc: NaN."""
    plus, minus = p + q, q - p
    np_, nm = np.linalg.norm(plus, axis=-1), np.linalg.norm(minus, axis=-1)
    theta = 2.0 * np.arctan2(nm, np_)
    with np.errstate(invalid="ignore", divide="ignore"):
        mu = plus / np_[..., None]
        tau = np.where(nm[..., None] > 0, minus / nm[..., None], 0.0)
    mu[np_ == 0] = np.nan
    return theta, mu, tau


def sphere_resample(
    points: ArrayLike, samples: int = DEFAULT_SAMPLES, closed: bool = True
) -> Array:
    """The curves through ``points`` (…, N, 3), unit vectors, resampled at ``samples`` points
    equally spaced by arc length along great circles between the given points.

    A closed curve includes the arc from the last point back to the first, and its samples
    start at the first point and stop one step short of it; an open one's run from the first
    point to the last. A curve with a NaN point, of zero length, or with two consecutive
    antipodal points (no great circle joins them) gives NaN.

    Examples
    --------
    Three corners of the octant triangle, resampled at 6 points: the corners and the midpoints
    of its sides (45° along each).

    >>> octant = np.eye(3)
    >>> (sphere_resample(octant, 6) * 2**0.5).round(12)
    array([[1.41421356, 0.        , 0.        ],
           [1.        , 1.        , 0.        ],
           [0.        , 1.41421356, 0.        ],
           [0.        , 1.        , 1.        ],
           [0.        , 0.        , 1.41421356],
           [1.        , 0.        , 1.        ]])

    Points off the unit sphere are refused:

    >>> sphere_resample([[1, 0, 0], [0, 2, 0], [0, 0, 1]])
    Traceback (most recent call last):
    ...
    linkwright.curves.fourier.CurveError: points: must be unit vectors, one is 1 off
    """
    p = _as_sphere_curves(points)
    batch = p.shape[:-2]
    p = p.reshape((-1,) + p.shape[-2:])
    if closed:
        p = np.concatenate([p, p[:, :1]], axis=1)
    theta, _, _ = _arcs(p[:, :-1], p[:, 1:])
    idx, w, bad = locate(theta, samples, closed)
    a = np.take_along_axis(p, idx[..., None], axis=1)
    b = np.take_along_axis(p, idx[..., None] + 1, axis=1)
    along = w * np.take_along_axis(theta, idx, axis=1)
    toward = b - np.sum(a * b, axis=-1, keepdims=True) * a
    size = np.linalg.norm(toward, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        toward = np.where(size > 0, toward / size, 0.0)
    out: Array = a * np.cos(along)[..., None] + toward * np.sin(along)[..., None]
    out[bad] = np.nan
    return out.reshape(batch + (samples, 3))


RESONANCE = 0.25  # |ω − 1| below which S⁻ is evaluated directly (module notes in _moments)


def _moments(p: Array, harmonics: int) -> tuple[Array, Array, Complex]:
    """Mean direction X_0 (C, 3), scatter matrix (C, 3, 3) and X_1 … X_K (C, K, 3) complex of
    the closed geodesic polygons through ``p`` (C, N, 3), exact (module docstring); NaN rows for
    curves with a NaN point, no length or an antipodal pair of neighbours.

    The compiled kernel where numba is installed, :func:`_moments_reference` otherwise.
    """
    if not available():
        return _moments_reference(p, harmonics)
    count = p.shape[0]
    mean, scatter = np.empty((count, 3)), np.empty((count, 3, 3))
    coeffs = np.empty((count, harmonics, 2, 3))
    compiled(_moments_kernel, parallel=count > 64)(
        np.ascontiguousarray(p), harmonics, RESONANCE, mean, scatter, coeffs
    )
    return mean, scatter, coeffs[:, :, 0] + 1j * coeffs[:, :, 1]


def _moments_reference(p: Array, harmonics: int) -> tuple[Array, Array, Complex]:
    """:func:`_moments` in NumPy, vectorised over the curves: the reference the kernel is tested
    against, and the path without numba."""
    theta, mu, tau = _arcs(p, np.roll(p, -1, axis=1))
    count, n_arcs = theta.shape
    length = theta.sum(axis=1)
    dead = ~np.isfinite(mu).all(axis=(1, 2)) | ~(length > 0) | ~np.isfinite(length)
    with np.errstate(invalid="ignore", divide="ignore"):
        inv = 1.0 / np.where(dead, 1.0, length)
    half = 0.5 * theta
    mean = np.einsum("cj,cjk->ck", 2.0 * np.sin(half), mu) * inv[:, None]
    sin = np.sin(theta)
    scatter = np.swapaxes(mu * (half + 0.5 * sin)[..., None], 1, 2) @ mu
    scatter += np.swapaxes(tau * (half - 0.5 * sin)[..., None], 1, 2) @ tau
    scatter *= inv[:, None, None]
    # Per arc and harmonic n: e^{−iω m_j} (ω = 2πn/L) and y = ω·θ_j/2 by angle addition from
    # n = 1 (sin(y ∓ θ_j/2) from sin y, cos y: one sine per arc, not one per harmonic).
    mid = (np.cumsum(theta, axis=1) - half) * (2.0 * np.pi * inv[:, None])
    step_r, step_i = np.cos(mid), -np.sin(mid)
    turn = (2.0 * np.pi * inv)[:, None] * half
    turn_r, turn_i = np.cos(turn), np.sin(turn)
    ch, sh = np.cos(half), np.sin(half)
    weights = np.empty((count, 2, harmonics, 2, n_arcs))
    pr, pi, yr, yi = step_r, step_i, turn_r, turn_i
    for n in range(1, harmonics + 1):
        below, above = n * turn - half, n * turn + half  # (ω ∓ 1)·θ_j/2
        with np.errstate(invalid="ignore", divide="ignore"):
            lower = np.where(below != 0, (yi * ch - yr * sh) / below, 1.0)  # S⁻
            upper = np.where(above != 0, (yi * ch + yr * sh) / above, 1.0)  # S⁺
        # Near ω = 1 the angle-addition sine loses its relative accuracy and 1/(ω − 1) would
        # magnify that: a direct sine there.
        close = np.abs(2.0 * np.pi * n * inv - 1.0) < RESONANCE
        if close.any():
            arg = below[close]
            with np.errstate(invalid="ignore", divide="ignore"):
                lower[close] = np.where(arg != 0, np.sin(arg) / arg, 1.0)
        along, across = half * (lower + upper), half * (lower - upper)
        # (along·μ − i·across·τ)·e^{−iωm}, real and imaginary parts, as weights of [μ; τ].
        weights[:, 0, n - 1, 0] = along * pr
        weights[:, 0, n - 1, 1] = across * pi
        weights[:, 1, n - 1, 0] = along * pi
        weights[:, 1, n - 1, 1] = -across * pr
        pr, pi = pr * step_r - pi * step_i, pr * step_i + pi * step_r
        yr, yi = yr * turn_r - yi * turn_i, yr * turn_i + yi * turn_r
    parts = weights.reshape(count, 2 * harmonics, 2 * n_arcs) @ np.concatenate([mu, tau], 1)
    parts *= inv[:, None, None]
    coeffs = parts[:, :harmonics] + 1j * parts[:, harmonics:]
    mean[dead], scatter[dead], coeffs[dead] = np.nan, np.nan, np.nan
    return mean, scatter, coeffs


def _moments_kernel(
    p: Array, harmonics: int, resonance: float, mean: Array, scatter: Array, coeffs: Array
) -> None:
    """:func:`_moments_reference`'s formulas one curve at a time (coeffs[c, n, 0 | 1, :] are
    the real and imaginary parts of X_{n+1}), no temporaries beyond one curve."""
    count, m = p.shape[0], p.shape[1]
    two_pi = 2.0 * math.pi
    chunk = 16
    for first in prange((count + chunk - 1) // chunk):
        geo = np.empty((m, 9))  # per arc: θ/2, μ (3), τ (3), sin(θ/2), cos(θ/2)
        acc = np.empty((harmonics, 6))  # Re X_n (3), Im X_n (3): kept local, stored once
        for c in range(first * chunk, min(count, (first + 1) * chunk)):
            length = 0.0
            good = True
            for j in range(m):
                after = j + 1 if j + 1 < m else 0
                sx, sy = p[c, j, 0] + p[c, after, 0], p[c, j, 1] + p[c, after, 1]
                sz = p[c, j, 2] + p[c, after, 2]
                dx, dy = p[c, after, 0] - p[c, j, 0], p[c, after, 1] - p[c, j, 1]
                dz = p[c, after, 2] - p[c, j, 2]
                ns = math.sqrt(sx * sx + sy * sy + sz * sz)
                nd = math.sqrt(dx * dx + dy * dy + dz * dz)
                if not ns > 0.0:  # antipodal neighbours, or a NaN
                    good = False
                    break
                half = math.atan2(nd, ns)
                geo[j, 0] = half
                geo[j, 1], geo[j, 2], geo[j, 3] = sx / ns, sy / ns, sz / ns
                if nd > 0.0:
                    geo[j, 4], geo[j, 5], geo[j, 6] = dx / nd, dy / nd, dz / nd
                else:
                    geo[j, 4], geo[j, 5], geo[j, 6] = 0.0, 0.0, 0.0
                geo[j, 7], geo[j, 8] = 0.5 * nd, 0.5 * ns  # |q − p| = 2 sin, |q + p| = 2 cos
                length += 2.0 * half
            if not good or not length > 0.0 or not math.isfinite(length):
                for a in range(3):
                    mean[c, a] = np.nan
                    for b in range(3):
                        scatter[c, a, b] = np.nan
                for n in range(harmonics):
                    for a in range(3):
                        coeffs[c, n, 0, a] = np.nan
                        coeffs[c, n, 1, a] = np.nan
                continue
            for a in range(3):
                mean[c, a] = 0.0
                for b in range(3):
                    scatter[c, a, b] = 0.0
            acc[:] = 0.0
            inv = 1.0 / length
            step_r, step_i, last_r, last_i = 1.0, 0.0, 1.0, 0.0
            for j in range(m):
                half = geo[j, 0]
                mx, my, mz = geo[j, 1], geo[j, 2], geo[j, 3]
                tx, ty, tz = geo[j, 4], geo[j, 5], geo[j, 6]
                sh, ch = geo[j, 7], geo[j, 8]
                chord = 2.0 * sh
                mean[c, 0] += chord * mx
                mean[c, 1] += chord * my
                mean[c, 2] += chord * mz
                s2 = 2.0 * sh * ch
                wm, wt = half + 0.5 * s2, half - 0.5 * s2
                for a in range(3):
                    for b in range(3):
                        scatter[c, a, b] += wm * geo[j, 1 + a] * geo[j, 1 + b]
                        scatter[c, a, b] += wt * geo[j, 4 + a] * geo[j, 4 + b]
                turn = two_pi * inv * half
                turn_r, turn_i = math.cos(turn), math.sin(turn)
                # e^{−iω m_j} for n = 1: m_j − m_{j−1} = θ_{j−1}/2 + θ_j/2, so each arc's
                # factor is the last one's times conj(e^{i·turn_{j−1}}·e^{i·turn_j}).
                if j == 0:
                    step_r, step_i = turn_r, -turn_i
                else:
                    rr = last_r * turn_r - last_i * turn_i
                    ri = last_r * turn_i + last_i * turn_r
                    step_r, step_i = step_r * rr + step_i * ri, step_i * rr - step_r * ri
                last_r, last_i = turn_r, turn_i
                pr, pi, yr, yi = step_r, step_i, turn_r, turn_i
                for n in range(1, harmonics + 1):
                    below, above = n * turn - half, n * turn + half
                    if abs(two_pi * n * inv - 1.0) < resonance:
                        lower = math.sin(below) / below if below != 0.0 else 1.0
                    else:
                        lower = (yi * ch - yr * sh) / below if below != 0.0 else 1.0
                    upper = (yi * ch + yr * sh) / above if above != 0.0 else 1.0
                    along, across = half * (lower + upper), half * (lower - upper)
                    ar, ai = along * pr, along * pi
                    cr, ci = across * pi, -across * pr
                    acc[n - 1, 0] += ar * mx + cr * tx
                    acc[n - 1, 1] += ar * my + cr * ty
                    acc[n - 1, 2] += ar * mz + cr * tz
                    acc[n - 1, 3] += ai * mx + ci * tx
                    acc[n - 1, 4] += ai * my + ci * ty
                    acc[n - 1, 5] += ai * mz + ci * tz
                    pr, pi = pr * step_r - pi * step_i, pr * step_i + pi * step_r
                    yr, yi = yr * turn_r - yi * turn_i, yr * turn_i + yi * turn_r
            for a in range(3):
                mean[c, a] *= inv
                for b in range(3):
                    scatter[c, a, b] *= inv
                for n in range(harmonics):
                    coeffs[c, n, 0, a] = acc[n, a] * inv
                    coeffs[c, n, 1, a] = acc[n, 3 + a] * inv


def _frames(poles: Array) -> Array:
    """Right-handed orthonormal frames (…, 3, 3), rows e₁, e₂, e₃ = pole."""
    # e₁ ⟂ the pole, from the coordinate axis least aligned with it (any choice will do: the
    # rotation about the pole is normalised afterwards).
    axis = np.eye(3)[np.argmin(np.abs(np.nan_to_num(poles)), axis=-1)]
    e1 = np.cross(poles, axis)
    with np.errstate(invalid="ignore", divide="ignore"):
        e1 /= np.linalg.norm(e1, axis=-1, keepdims=True)
    return np.stack([e1, np.cross(poles, e1), poles], axis=-2)


def _poles(mean: Array, scatter: Array) -> tuple[Array, NDArray[np.intp]]:
    """The three candidate poles (C, 3, 3) — m̂, e, −e — and the canonical one's index (C,)."""
    size = np.linalg.norm(mean, axis=-1)
    ok = np.isfinite(scatter).all(axis=(-2, -1)) & np.isfinite(size)
    values, vectors = np.linalg.eigh(np.where(ok[:, None, None], scatter, np.eye(3)))
    least = vectors[..., 0]
    least = np.where(np.sum(least * mean, axis=-1, keepdims=True) < 0, -least, least)
    with np.errstate(invalid="ignore", divide="ignore"):
        direction = np.where((size > 0)[:, None], mean / size[:, None], least)
    poles = np.stack([direction, least, -least], axis=1)
    # m̂ moves by δ/|m| when the curve moves by δ, e by δ/(λ₂ − λ₁): the steadier one.
    canonical = np.where(size >= values[:, 1] - values[:, 0], 0, 1)
    return np.where(ok[:, None, None], poles, np.nan), canonical


def _pole_variants(frames: Array, mean: Array, coeffs: Complex, k: int) -> Array:
    """The four planar normalisations (…, 4, D) of curves whose coefficients ``mean`` (C, 3)
    and ``coeffs`` (C, K, 3) are written in ``frames`` (C, …, 3, 3) (rows e₁, e₂, e₃)."""
    x = np.einsum("c...ab,cnb->c...na", frames, coeffs)  # (C, …, K, 3)
    x0 = np.einsum("c...ab,cb->c...a", frames, mean)
    pos = x[..., 0] + 1j * x[..., 1]  # Z_n
    neg = np.conj(x[..., 0]) + 1j * np.conj(x[..., 1])  # Z_−n = conj(X_n)·e₁ + i conj(X_n)·e₂
    height = x[..., 2]
    phi, shift = closed_phases(pos, neg)  # (…, 4)
    turn = np.exp(1j * phi)[..., None]
    # e^{inσ}, n = 1 … K, by products: one exponential per variant, not one per harmonic.
    start = np.cumprod(np.broadcast_to(np.exp(1j * shift)[..., None], phi.shape + (k,)), -1)
    backwards = np.array([False, False, True, True])[:, None]
    first = np.where(backwards, neg[..., None, :], pos[..., None, :])  # Z_n, or Z_−n backwards
    second = np.where(backwards, pos[..., None, :], neg[..., None, :])
    # Backwards conjugates every X_n, so H_n too; the start shift turns H_n as it turns Z_n.
    h = np.where(backwards, np.conj(height)[..., None, :], height[..., None, :])
    z = np.concatenate([first * start, second * np.conj(start)], axis=-1) * turn
    h = h * start * np.sqrt(2.0)
    z0 = (x0[..., 0] + 1j * x0[..., 1])[..., None] * turn[..., 0]
    h0 = np.broadcast_to(x0[..., 2][..., None], phi.shape)
    return np.concatenate(
        [z.real, z.imag, h.real, h.imag, z0.real[..., None], z0.imag[..., None], h0[..., None]],
        axis=-1,
    )


def _sphere_variants(p: Array, harmonics: int, canonical: bool) -> Array:
    """The canonical descriptors (C, D) of the curves ``p`` (C, N, 3), or all their variants
    (C, 12, D)."""
    mean, scatter, coeffs = _moments(p, harmonics)
    poles, choice = _poles(mean, scatter)
    if canonical:
        pole = np.take_along_axis(poles, choice[:, None, None], axis=1)[:, 0]
        v = _pole_variants(_frames(pole), mean, coeffs, harmonics)  # (C, 4, D)
        pick = closed_choice(v, harmonics)
        v = np.take_along_axis(v, pick[:, None, None], axis=1)[:, 0]
        v[~np.isfinite(v).all(axis=-1)] = np.nan
        return v
    v = _pole_variants(_frames(poles), mean, coeffs, harmonics)  # (C, 3, 4, D)
    v = v.reshape(v.shape[0], VARIANTS, v.shape[-1])
    v[~np.isfinite(v).all(axis=(-2, -1))] = np.nan
    return v


def _check_harmonics(harmonics: int) -> None:
    if harmonics < 1:
        raise CurveError(f"harmonics: must be at least 1, got {harmonics}")


def _by_chunks(points: ArrayLike, harmonics: int, canonical: bool) -> Array:
    p = _as_sphere_curves(points, normalise=False)  # per chunk below: no copy of the batch
    _check_harmonics(harmonics)
    flat = p.reshape((-1,) + p.shape[-2:])
    d = 6 * harmonics + 3
    out = np.empty((flat.shape[0],) + ((d,) if canonical else (VARIANTS, d)))
    for first in range(0, flat.shape[0], CHUNK):
        out[first : first + CHUNK] = _sphere_variants(
            _unit(flat[first : first + CHUNK]), harmonics, canonical
        )
    return out.reshape(p.shape[:-2] + out.shape[1:])


def sphere_descriptor_variants(points: ArrayLike, *, harmonics: int = DEFAULT_HARMONICS) -> Array:
    """Every normalised descriptor of each closed curve on the unit sphere: (…, 12, D),
    D = 6·harmonics + 3: three poles (m̂, e, −e) × two directions × two start/rotation pairs
    (module docstring).

    A query compares its variants against stored :func:`sphere_descriptors` and keeps the
    nearest; the stored descriptor is always one of its own curve's variants. Every variant's
    distance to another curve's descriptor is the RMS chord distance between the two
    (band-limited) at some rotation and start, so extra variants never undercut the aligned
    error.

    Examples
    --------
    >>> t = np.linspace(0, 2 * np.pi, 60, endpoint=False)
    >>> rho = np.radians(30)
    >>> circle = np.stack([np.sin(rho) * np.cos(t), np.sin(rho) * np.sin(t),
    ...                    np.full_like(t, np.cos(rho))], -1)
    >>> sphere_descriptor_variants(circle).shape
    (12, 51)
    """
    return _by_chunks(points, harmonics, canonical=False)


def sphere_descriptors(points: ArrayLike, *, harmonics: int = DEFAULT_HARMONICS) -> Array:
    """One descriptor per closed curve on the unit sphere, (…, D) with D = 6·harmonics + 3,
    unchanged by any rotation of the sphere, by where the curve starts, which way it runs and
    how densely it is sampled along its arcs; its size is kept (module docstring).

    ``points`` (…, N, 3) are unit vectors (off by at most 1e-6, else :class:`CurveError`). A
    curve with a NaN point, of zero length, or with two consecutive antipodal points gives NaN.
    The coefficients come from a compiled kernel (one pass per curve, parallel over curves)
    where numba is installed, from NumPy otherwise; the normalisation is NumPy, vectorised over
    chunks of 2048 curves, so memory beyond the input's is bounded by the chunk.

    Examples
    --------
    A small circle of 20° and one of 40° about any axis: their descriptors lie 2·sin 10° apart,
    the chord between corresponding points (to the polygons' O(1/N²) and the band limit):

    >>> def circle(rho, axis):
    ...     t = np.linspace(0, 2 * np.pi, 720, endpoint=False)
    ...     a, b = np.linalg.qr(np.column_stack([axis, [1, 2, 3], [3, 1, 2]]))[0].T[[1, 2]]
    ...     c = np.cos(rho) * np.asarray(axis) / np.linalg.norm(axis)
    ...     return c + np.sin(rho) * (np.cos(t)[:, None] * a + np.sin(t)[:, None] * b)
    >>> d20 = sphere_descriptors(circle(np.radians(20), [0, 0, 1]))
    >>> d40 = sphere_descriptors(circle(np.radians(40), [1, -2, 0.5]))
    >>> float(np.linalg.norm(d20 - d40).round(5)), float((2 * np.sin(np.radians(10))).round(5))
    (0.34730, 0.34730)

    A linkage that cannot assemble leaves NaN points, and NaN descriptors:

    >>> bool(np.isnan(sphere_descriptors([[1, 0, 0], [0, 1, 0], [np.nan] * 3])).all())
    True
    """
    return _by_chunks(points, harmonics, canonical=True)


@dataclass(frozen=True)
class SphereAlignment:
    """The best rotation of the sphere taking a curve onto a target (:func:`sphere_align`),
    batched over the curves: every field has the batch shape (``rotation`` two axes more).

    ``rotation`` (…, 3, 3) is proper (det +1) and acts on column vectors: R·p lays the curve,
    run backwards if ``reversed``, from its point at ``shift`` (a fraction of its length from
    its first point, along its own direction) onward, over the target from its first point
    onward. ``rms`` is the RMS chord distance between the two, resampled alike by arc length;
    ``error`` is ``rms`` over the target's RMS chord distance from its own mean direction,
    √(2 − 2|mean|). ``reversed`` is False and the rest NaN for a curve or target with a NaN point.
    """

    error: Array
    rms: Array
    rotation: Array
    reversed: Array
    shift: Array


def sphere_align(curve: ArrayLike, target: ArrayLike, *, samples: int = 256) -> SphereAlignment:
    """The best rotation of the sphere (proper), start point and direction taking the closed
    curve ``curve`` (…, N, 3) onto ``target`` (…, N′, 3), both resampled at ``samples`` points
    by arc length (:func:`sphere_resample`); batch shapes broadcast.

    For a start shift, the best rotation R minimises Σ_t ‖R·a_t − b_t‖² (Wahba's problem): with
    H = Σ_t a_t b_tᵀ = U Σ Vᵀ, R = V diag(1, 1, ±1) Uᵀ, the sign making det R = +1 (Kabsch),
    and the residual is Σ|a|² + Σ|b|² − 2 tr(R H). H at every whole shift comes from nine
    FFT correlations; the best shift is refined between samples on the band-limited H (the
    slope of the trace is tr(R·dH/ds), R held: the envelope theorem). ``rms`` is then summed
    from the turned curve itself, not from that residual, which cancels on a close fit.

    Examples
    --------
    A coupler curve of paper 000's Fig. 6 crank-rocker, and the same curve turned by 1 rad
    about (1, 1, 1) and run backwards from its point at θ = 90°:

    >>> from linkwright.engine.kernels import spherical_fourbar_positions
    >>> theta = np.linspace(0, 2 * np.pi, 180, endpoint=False)
    >>> fig6 = np.radians([40, 20, 45, 35, 50, 130])
    >>> curve = spherical_fourbar_positions(*fig6, 1, theta)[2][0]
    >>> from scipy.spatial.transform import Rotation
    >>> turn = Rotation.from_rotvec(np.ones(3) / 3**0.5).as_matrix()
    >>> target = curve[(45 - np.arange(180)) % 180] @ turn.T
    >>> fit = sphere_align(curve, target)
    >>> bool(fit.reversed), float(np.abs(fit.rotation - turn).max()) < 1e-4
    (True, True)
    >>> float(fit.rms) < 1e-5, float(np.linalg.det(fit.rotation))
    (True, 1.0)

    A curve with a NaN point (a linkage that does not assemble there) has no alignment:

    >>> bad = sphere_align([[1, 0, 0], [0, 1, 0], [np.nan] * 3], target)
    >>> float(bad.error), bool(np.isnan(bad.rotation).all())
    (nan, True)
    """
    a = sphere_resample(curve, samples)
    b = sphere_resample(target, samples)
    shape = np.broadcast_shapes(a.shape, b.shape)[:-2]
    fb = np.fft.fft(b, axis=-2)
    reversed_a = np.roll(a[..., ::-1, :], 1, axis=-2)  # sample t of the reversed curve is −t
    fits = []
    for x in (a, reversed_a):
        fx = np.fft.fft(x, axis=-2)
        # spectrum[..., 3i + j, n]: its inverse FFT over n is Σ_t x_i(t) b_j(t + k) at shift k.
        spectrum = np.einsum("...ni,...nj->...ijn", np.conj(fx), fb)
        spectrum = spectrum.reshape(spectrum.shape[:-3] + (9, samples))
        whole_h = np.fft.ifft(spectrum, axis=-1).real  # (…, 9, M)
        whole_h = np.moveaxis(whole_h, -1, -2).reshape(whole_h.shape[:-2] + (samples, 3, 3))
        whole = np.argmax(best_rotation(whole_h)[0], axis=-1).astype(float)

        def evaluate(s: Array, spectrum: Complex = spectrum) -> tuple[Array, Array]:
            h, dh = circular_correlation(spectrum, s)
            value, r = best_rotation(h.real.reshape(h.shape[:-1] + (3, 3)))
            return value, np.einsum("...ij,...ji->...", r, dh.real.reshape(r.shape))

        s = refine_shift(evaluate, whole)
        h = circular_correlation(spectrum, s)[0].real
        value, r = best_rotation(h.reshape(h.shape[:-1] + (3, 3)))
        fits.append((value, r, s))
    (v_f, r_f, s_f), (v_b, r_b, s_b) = fits
    backwards = v_b > v_f  # NaN compares False: a NaN curve stays "forwards"
    rotation = np.where(backwards[..., None, None], r_b, r_f)
    shift = start_fraction(s_f, s_b, backwards, samples)
    # Σ|a|² + Σ|b|² − 2 tr(R H) cancels to √ε on a near-perfect fit: the turned curve's chord
    # distance to the target is summed instead.
    chosen: Array = np.where(backwards[..., None, None], reversed_a, a)
    x = shifted_samples(chosen, np.where(backwards, s_b, s_f), axis=-2)
    residual = np.sum((x @ np.swapaxes(rotation, -1, -2) - b) ** 2, axis=(-2, -1))
    spread = np.sqrt(np.clip(2.0 - 2.0 * np.linalg.norm(b.mean(axis=-2), axis=-1), 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        rms = np.sqrt(residual / samples)
        error = rms / spread
    bad = np.isnan(error)
    return SphereAlignment(
        error=np.broadcast_to(error, shape),
        rms=np.broadcast_to(rms, shape),
        rotation=np.broadcast_to(np.where(bad[..., None, None], np.nan, rotation), shape + (3, 3)),
        reversed=np.broadcast_to(backwards & ~bad, shape),
        shift=np.broadcast_to(np.where(bad, np.nan, shift), shape),
    )
