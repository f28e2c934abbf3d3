"""Planar curve descriptors: fixed-length vectors that forget where, how big, how turned, where
it starts and which way it runs — and keep the shape.

A curve (a coupler curve, or one a user drew) is the closed polygon through its points, as
complex numbers z(s) parametrised by length s ∈ [0, L), so that how fast a mechanism runs along
it does not matter. Its Fourier coefficients Z_n = (1/L) ∫ z(s) e^{−2πins/L} ds are exact for a
polygon (Kuhl and Giardina, "Elliptic Fourier features of a closed contour", 1982, in complex
form): z″ is a sum of jumps Δu_j of the unit tangent at the vertices s_j, so

    Z_n = −L/(4π²n²) · Σ_j Δu_j · e^{−2πi n s_j/L},   n ≠ 0,

with no resampling and so no aliasing: the invariances below hold to rounding. Then
(Fourier descriptors in the manner of Zahn and Roskies, normalised as follows):

- translation lives in Z_0 alone, which is dropped;
- scale: the kept coefficients are divided by their root-sum-square, the RMS distance of the
  (band-limited) curve from its centroid, so every descriptor has unit length;
- rotation by φ multiplies every Z_n by e^{iφ}; moving the start point by a fraction s of the
  length multiplies Z_n by e^{2πins}. The pair is fixed by making Z_1 and Z_{−1} real and
  positive; of the two pairs that do, the one where the largest even harmonic's larger part
  (real or imaginary) is positive is kept;
- direction: running the curve backwards swaps Z_n and Z_{−n}; the direction with
  |Z_1| ≥ |Z_{−1}| (mostly counter-clockwise) is kept.

The normalisation's arbitrary choices can flip for nearly symmetric curves (|Z_1| ≈ |Z_{−1}|,
or a vanishing Z_{±1} or even harmonic), so :func:`descriptor_variants` gives every choice of a
query: a search compares the stored (canonical) descriptor against all of them and keeps the
nearest.

**Distance.** By Parseval's theorem, the squared Euclidean distance between two descriptors is
the mean squared distance between the two normalised, band-limited curves, point by point
(t = 0 … M − 1), at the alignment the normalisation chose. So it ranks candidates as the aligned
point-to-point error does, and it is never below :func:`aligned_error`, which finds the best
alignment (similarity transform and start point, either direction) exactly; :func:`align` also
returns that alignment (scale, rotation, translation, direction, start).

Open curves (a user's stroke) are closed by running back along themselves: the doubled curve is
symmetric, so Z_{−n} = Z_n carries nothing new, the start point is an end (two choices,
the two variants) and only the rotation is normalised, by Z_1.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine.kernels import available, compiled

__all__ = [
    "Alignment",
    "CurveError",
    "align",
    "aligned_error",
    "circular_correlation",
    "closed_choice",
    "closed_phases",
    "descriptor_variants",
    "descriptors",
    "locate",
    "refine_shift",
    "resample",
    "shifted_samples",
    "start_fraction",
]

Array = NDArray[np.float64]
Complex = NDArray[np.complex128]
Index = NDArray[np.intp]

DEFAULT_SAMPLES = 64
DEFAULT_HARMONICS = 8

prange = range  # numba.prange in the compiled kernel's own namespace


class CurveError(ValueError):
    """A curve that cannot be described (names the problem)."""


def _as_curves(points: ArrayLike) -> Array:
    p = np.asarray(points, dtype=float)
    if p.ndim < 2 or p.shape[-1] != 2:
        raise CurveError(f"points: must have shape (..., count, 2), got {p.shape}")
    if p.shape[-2] < 3:
        raise CurveError(f"points: a curve needs at least 3 points, got {p.shape[-2]}")
    return p


def resample(points: ArrayLike, samples: int = DEFAULT_SAMPLES, closed: bool = True) -> Array:
    """The curves through ``points`` (…, N, 2), resampled at ``samples`` points equally spaced
    along their length (linear between the given points).

    A closed curve includes the segment from the last point back to the first, and its samples
    start at the first point and stop one step short of it; an open one's run from the first
    point to the last. A curve with a NaN point, or of zero length, gives NaN.

    Examples
    --------
    The unit square's corners, resampled at 8 points: the corners and the midpoints of the sides.

    >>> resample([[0, 0], [1, 0], [1, 1], [0, 1]], 8)
    array([[0. , 0. ],
           [0.5, 0. ],
           [1. , 0. ],
           [1. , 0.5],
           [1. , 1. ],
           [0.5, 1. ],
           [0. , 1. ],
           [0. , 0.5]])
    >>> resample([[0, 0], [3, 0], [3, 1]], 5, closed=False)[:, 0]
    array([0., 1., 2., 3., 3.])
    """
    p = _as_curves(points)
    batch = p.shape[:-2]
    p = p.reshape((-1,) + p.shape[-2:])
    if closed:
        p = np.concatenate([p, p[:, :1]], axis=1)
    seg = np.hypot(*np.moveaxis(np.diff(p, axis=1), -1, 0))
    idx, w, bad = locate(seg, samples, closed)
    a = np.take_along_axis(p, idx[..., None], axis=1)
    b = np.take_along_axis(p, idx[..., None] + 1, axis=1)
    out = a + w[..., None] * (b - a)
    out[bad] = np.nan
    return out.reshape(batch + (samples, 2))


def locate(seg: Array, samples: int, closed: bool) -> tuple[Index, Array, NDArray[np.bool_]]:
    """Where ``samples`` points equally spaced by length fall on polylines with segment
    lengths ``seg`` (C, S): the segment (C, samples), the fraction of it, and which rows have
    no length (a NaN, or all points equal)."""
    if samples < 3:
        raise CurveError(f"samples: need at least 3, got {samples}")
    count = seg.shape[0]
    cum = np.concatenate([np.zeros((count, 1)), np.cumsum(seg, axis=1)], axis=1)
    total = cum[:, -1:]
    with np.errstate(invalid="ignore", divide="ignore"):
        frac = cum / total
    bad = ~np.isfinite(frac).all(axis=1) | ~(total[:, 0] > 0)
    frac[bad] = np.linspace(0.0, 1.0, frac.shape[1])  # any monotone fill; masked by the caller
    steps = samples if closed else samples - 1
    target = np.arange(samples) / steps
    rows = np.arange(count)[:, None]
    # One searchsorted for every row at once: row r's fractions are shifted to [2r, 2r + 1].
    idx = np.searchsorted((frac + 2.0 * rows).ravel(), (target + 2.0 * rows).ravel(), "right")
    idx = idx.reshape(count, samples) - rows * frac.shape[1] - 1
    idx = np.clip(idx, 0, frac.shape[1] - 2)
    f0 = np.take_along_axis(frac, idx, axis=1)
    f1 = np.take_along_axis(frac, idx + 1, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        w = np.where(f1 > f0, (target - f0) / (f1 - f0), 0.0)
    return idx, w, bad


def _fourier(points: ArrayLike, harmonics: int, closed: bool) -> Complex:
    """(…, 2K) complex: Z_1 … Z_K, Z_−1 … Z_−K of the polygon through ``points`` (exact)."""
    p = _as_curves(points)
    if harmonics < 1:
        raise CurveError(f"harmonics: must be at least 1, got {harmonics}")
    z = p[..., 0] + 1j * p[..., 1]
    if not closed:
        z = np.concatenate([z, z[..., -2:0:-1]], axis=-1)  # there and back: a closed curve
    dz = np.roll(z, -1, axis=-1) - z  # segment j runs from vertex j to vertex j + 1
    ds = np.abs(dz)
    length = ds.sum(axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        # A repeated point is a segment of length 0: its tangent 0 telescopes away, since both
        # jumps it takes part in sit at the same s.
        u = np.where(ds > 0, dz / ds, 0.0)
        jump = u - np.roll(u, 1, axis=-1)  # at vertex j
        s_start = np.cumsum(ds, axis=-1) - ds
        w = np.exp(-2j * np.pi * s_start / length)
    out = np.empty(z.shape[:-1] + (2 * harmonics,), dtype=complex)
    power = np.ones_like(w)
    for n in range(1, harmonics + 1):
        power = power * w
        factor = -length[..., 0] / (4.0 * np.pi**2 * n * n)
        out[..., n - 1] = factor * np.sum(jump * power, axis=-1)
        out[..., harmonics + n - 1] = factor * np.sum(jump * np.conj(power), axis=-1)
    dead = ~(length[..., 0] > 0) | ~np.isfinite(z).all(axis=-1)
    out[dead] = np.nan
    return out


def closed_phases(pos: Complex, neg: Complex) -> tuple[Array, Array]:
    """The rotation φ and start shift σ (…, 4) of the four normalisations of a closed curve's
    coefficients ``pos`` = Z_1 …, ``neg`` = Z_−1 … (… , K): variants 0, 1 run forwards, 2, 3
    backwards (Z_n and Z_−n swapped); variant v's Z_k is then multiplied by e^{i(φ_v + k·σ_v)},
    which makes Z_1 and Z_−1 real and positive (variants 1 and 3 add π to both: the other pair
    that does)."""
    phi, shift = [], []
    for first, minus in ((pos[..., 0], neg[..., 0]), (neg[..., 0], pos[..., 0])):
        a1, am1 = np.angle(first), np.angle(minus)
        for extra in (0.0, np.pi):
            phi.append(-0.5 * (am1 + a1) + extra)
            shift.append(0.5 * (am1 - a1) + extra)
    return np.stack(phi, axis=-1), np.stack(shift, axis=-1)


def _normalised(coeffs: Complex, harmonics: int, closed: bool) -> Complex:
    """(…, V, 2K) complex (K for open curves): the harmonics of every variant, start point and
    rotation normalised."""
    n = np.arange(1, harmonics + 1)
    pos, neg = coeffs[..., :harmonics], coeffs[..., harmonics:]
    if not closed:
        # The doubled curve starts at an end: no start point to fix. Its variants are the two
        # ends (start at the far end: Z_n → Z_n·(−1)^n, the doubled curve shifted by half).
        sign = (-1.0) ** n
        variants = np.stack([pos, pos * sign], axis=-2)
        phase = np.exp(-1j * np.angle(variants[..., :1]))
        turned: Complex = variants * phase
        return turned
    # Both directions: backwards swaps Z_n and Z_{−n}.
    forward = np.concatenate([pos, neg], axis=-1)
    backward = np.concatenate([neg, pos], axis=-1)
    z = np.stack([forward, forward, backward, backward], axis=-2)
    phi, shift = closed_phases(pos, neg)
    k = np.concatenate([n, -n])
    normalised: Complex = z * np.exp(1j * (phi[..., None] + k * shift[..., None]))
    return normalised


# Taylor coefficients ±1/n! of sin and cos (numba reads module-level numbers as constants).
_S3, _S5, _S7, _S9, _S11, _S13, _S15 = (
    (-1.0) ** i / math.factorial(2 * i + 1) for i in range(1, 8)
)
_C2, _C4, _C6, _C8, _C10, _C12, _C14, _C16 = (
    (-1.0) ** i / math.factorial(2 * i) for i in range(1, 9)
)


def _turn(t: float) -> tuple[float, float]:
    """(cos, sin) of −2πt for t in [0, 1]: e^{−2πit}, to a few units in the last place, from
    polynomials alone, so that a loop of them vectorises (a libm call does not).

    t is split at the nearest quarter turn q/4; the rest r lies within ±1/8 of a turn, where
    the Taylor series of sin and cos (to a^15 and a^16: the first term left out is below
    5e-17) reach double precision; e^{−2πit} = e^{−2πir}·(−i)^q.

    >>> [tuple(round(v, 15) + 0.0 for v in _turn(t)) for t in (0.0, 0.25, 0.5, 0.875, 1.0)]
    [(1.0, 0.0), (0.0, -1.0), (-1.0, 0.0), (0.707106781186548, 0.707106781186548), (1.0, 0.0)]
    """
    quarter = math.floor(4.0 * t + 0.5)
    r = t - 0.25 * quarter  # exact: r is small, or t and the quarter are within a factor 2
    a = 2.0 * math.pi * r
    b = a * a
    sin_a = a * (
        1.0 + b * (_S3 + b * (_S5 + b * (_S7 + b * (_S9 + b * (_S11 + b * (_S13 + b * _S15))))))
    )
    cos_a = 1.0 + b * (
        _C2 + b * (_C4 + b * (_C6 + b * (_C8 + b * (_C10 + b * (_C12 + b * (_C14 + b * _C16))))))
    )
    # e^{−ia} = (cos a, −sin a), turned by −90° per quarter (whole turns dropped).
    q = quarter - 4.0 * math.floor(0.25 * quarter)
    re = cos_a if q == 0.0 else (-sin_a if q == 1.0 else (-cos_a if q == 2.0 else sin_a))
    im = -sin_a if q == 0.0 else (-cos_a if q == 1.0 else (sin_a if q == 2.0 else cos_a))
    return re, im


def _descriptor_kernel(points: Array, harmonics: int, closed: bool, out: Array) -> None:
    """The canonical descriptor of each curve (``points`` (count, n_points, 2)), as
    :func:`descriptors` defines it with NumPy: the same formulas, one curve at a time, no
    temporaries beyond one curve."""
    count, n_points = points.shape[0], points.shape[1]
    k = harmonics
    m = n_points if closed else 2 * n_points - 2
    chunk = 64
    for first in prange((count + chunk - 1) // chunk):
        # Scratch for one curve at a time, allocated once per task. Every loop over the
        # vertices below carries no value from one vertex to the next (a running sum is a
        # reduction), so LLVM vectorises each of them.
        zr, zi = np.empty(m + 1), np.empty(m + 1)
        ur, ui, ds, jr, ji = np.empty(m), np.empty(m), np.empty(m), np.empty(m), np.empty(m)
        wr, wi, qr, qi = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
        acc = np.empty((4, k))
        for c in range(first * chunk, min(count, (first + 1) * chunk)):
            for j in range(n_points):
                zr[j] = points[c, j, 0]
                zi[j] = points[c, j, 1]
            for j in range(n_points, m):  # an open curve runs back along itself
                zr[j] = points[c, 2 * n_points - 2 - j, 0]
                zi[j] = points[c, 2 * n_points - 2 - j, 1]
            zr[m], zi[m] = zr[0], zi[0]  # the last segment returns to the first vertex
            length = 0.0
            for j in range(m):
                dx = zr[j + 1] - zr[j]
                dy = zi[j + 1] - zi[j]
                d = math.sqrt(dx * dx + dy * dy)
                ds[j] = d
                length += d
                inv = 1.0 / d if d > 0.0 else 0.0
                ur[j] = dx * inv
                ui[j] = dy * inv
            if not (length > 0.0) or not math.isfinite(length):
                for q in range(out.shape[1]):
                    out[c, q] = np.nan
                continue
            # The tangent's jump at each vertex (the segment before it is segment j − 1).
            jr[0], ji[0] = ur[0] - ur[m - 1], ui[0] - ui[m - 1]
            for j in range(1, m):
                jr[j] = ur[j] - ur[j - 1]
                ji[j] = ui[j] - ui[j - 1]
            # Where each vertex starts, as a fraction of the length (a prefix sum: kept apart
            # from the loop after it, which then vectorises).
            s_start = 0.0
            inv_length = 1.0 / length
            for j in range(m):
                wr[j] = s_start * inv_length
                s_start += ds[j]
            for j in range(m):
                wr[j], wi[j] = _turn(wr[j])
                qr[j], qi[j] = 1.0, 0.0
            pr, pi, nr, ni = acc[0], acc[1], acc[2], acc[3]
            for n in range(k):
                sum_pr = sum_pi = sum_nr = sum_ni = 0.0
                for j in range(m):
                    a, b = qr[j] * wr[j] - qi[j] * wi[j], qr[j] * wi[j] + qi[j] * wr[j]
                    qr[j], qi[j] = a, b
                    sum_pr += jr[j] * a - ji[j] * b
                    sum_pi += jr[j] * b + ji[j] * a
                    sum_nr += jr[j] * a + ji[j] * b  # jump · conj(w^n)
                    sum_ni += ji[j] * a - jr[j] * b
                pr[n], pi[n], nr[n], ni[n] = sum_pr, sum_pi, sum_nr, sum_ni
            # The common factor −L/(4π²n²) per harmonic (its sign and L cancel in the normalisation,
            # but 1/n² does not).
            for n in range(k):
                f = -length / (4.0 * math.pi * math.pi * (n + 1) * (n + 1))
                pr[n] *= f
                pi[n] *= f
                nr[n] *= f
                ni[n] *= f
            if closed:
                if math.hypot(pr[0], pi[0]) < math.hypot(nr[0], ni[0]):
                    pr, pi, nr, ni = acc[2], acc[3], acc[0], acc[1]  # backwards: Z_n ↔ Z_−n
                a1 = math.atan2(pi[0], pr[0])
                am1 = math.atan2(ni[0], nr[0])
                shift = 0.5 * (am1 - a1)
                phi = -0.5 * (am1 + a1)
                # e^{i(φ ± n·shift)} by repeated products: two sincos, not 4k.
                sr, si = math.cos(shift), math.sin(shift)
                ar, ai = math.cos(phi), math.sin(phi)
                br, bi = ar, ai
                for n in range(k):
                    ar, ai = ar * sr - ai * si, ar * si + ai * sr
                    br, bi = br * sr + bi * si, bi * sr - br * si
                    pr[n], pi[n] = pr[n] * ar - pi[n] * ai, pr[n] * ai + pi[n] * ar
                    nr[n], ni[n] = nr[n] * br - ni[n] * bi, nr[n] * bi + ni[n] * br
                # The other start/rotation pair negates the even harmonics: keep the one where the
                # largest even harmonic's larger part (real or imaginary) is positive.
                big, sign = -1.0, 1.0
                for n in range(1, k, 2):
                    for vr, vi in ((pr[n], pi[n]), (nr[n], ni[n])):
                        size = vr * vr + vi * vi
                        if size > big:
                            big, sign = size, vr if abs(vr) >= abs(vi) else vi
                if sign < 0.0:
                    for n in range(1, k, 2):
                        pr[n], pi[n], nr[n], ni[n] = -pr[n], -pi[n], -nr[n], -ni[n]
                energy = 0.0
                for n in range(k):
                    energy += pr[n] ** 2 + pi[n] ** 2 + nr[n] ** 2 + ni[n] ** 2
                scale = 1.0 / math.sqrt(energy)
                for n in range(k):
                    out[c, n] = pr[n] * scale
                    out[c, k + n] = nr[n] * scale
                    out[c, 2 * k + n] = pi[n] * scale
                    out[c, 3 * k + n] = ni[n] * scale
            else:
                e = -math.atan2(pi[0], pr[0])
                cr, ci = math.cos(e), math.sin(e)
                energy = 0.0
                for n in range(k):
                    pr[n], pi[n] = pr[n] * cr - pi[n] * ci, pr[n] * ci + pi[n] * cr
                    energy += pr[n] ** 2 + pi[n] ** 2
                # Starting at the other end negates the even harmonics (after the rotation's
                # normalisation): keep Re Z_2 ≥ 0.
                flip = k > 1 and pr[1] < 0.0
                scale = 1.0 / math.sqrt(energy)
                for n in range(k):
                    f = -scale if flip and n % 2 == 1 else scale
                    out[c, n] = pr[n] * f
                    out[c, k + n] = pi[n] * f


def _energy_normalise(v: Complex) -> Complex:
    with np.errstate(invalid="ignore", divide="ignore"):
        unit: Complex = v / np.sqrt(np.sum(np.abs(v) ** 2, axis=-1, keepdims=True))
    return unit


def _real(v: Complex) -> Array:
    return np.concatenate([v.real, v.imag], axis=-1)


def descriptor_variants(
    points: ArrayLike,
    *,
    closed: bool = True,
    harmonics: int = DEFAULT_HARMONICS,
) -> Array:
    """Every normalised descriptor of each curve: (…, V, D), V = 4 for closed curves (two
    directions × two start/rotation pairs), 2 for open ones (either end first).

    A query compares its variants against stored :func:`descriptors` and keeps the nearest;
    the stored descriptor is always one of its own curve's variants.

    Examples
    --------
    >>> t = np.linspace(0, 2 * np.pi, 50, endpoint=False)
    >>> ellipse = np.stack([3 * np.cos(t), np.sin(t)], -1)
    >>> v = descriptor_variants(ellipse)
    >>> v.shape, bool(np.allclose(np.linalg.norm(v, axis=-1), 1))
    ((4, 32), True)
    """
    v = _energy_normalise(_normalised(_fourier(points, harmonics, closed), harmonics, closed))
    return _real(v)


def descriptors(
    points: ArrayLike,
    *,
    closed: bool = True,
    harmonics: int = DEFAULT_HARMONICS,
) -> Array:
    """One descriptor per curve, (…, D) with D = 4·harmonics (closed) or 2·harmonics (open):
    unit vectors, unchanged by translating, turning, scaling the curve, by where it starts and
    by which way it runs (module docstring). A curve with a NaN point, or of zero length,
    gives NaN.

    Computed by a compiled kernel (one pass per curve, parallel over curves) where numba is
    installed, by NumPy otherwise.

    Examples
    --------
    An ellipse, and the same ellipse moved, turned by 40°, scaled by 7, started elsewhere and
    run backwards, have the same descriptor:

    >>> t = np.linspace(0, 2 * np.pi, 90, endpoint=False)
    >>> a = np.stack([3 * np.cos(t), np.sin(t) + 0.3 * np.cos(2 * t)], -1)
    >>> c, s = np.cos(0.7), np.sin(0.7)
    >>> b = 7 * np.roll(a[::-1], 17, axis=0) @ [[c, s], [-s, c]] + [5, -2]
    >>> float(np.abs(descriptors(a) - descriptors(b)).max()) < 1e-12
    True

    A linkage that cannot assemble leaves NaN points, and NaN descriptors:

    >>> bool(np.isnan(descriptors([[0, 0], [1, 0], [np.nan, 1]])).all())
    True
    """
    p = _as_curves(points)
    if harmonics < 1:
        raise CurveError(f"harmonics: must be at least 1, got {harmonics}")
    if not available():
        return _descriptors_reference(p, closed=closed, harmonics=harmonics)
    # No copy of a batch of curves: fresh memory costs a page fault per 4 kB, as much as the
    # descriptors themselves.
    flat = p.reshape((-1,) + p.shape[-2:])
    out = np.empty((flat.shape[0], (4 if closed else 2) * harmonics))
    compiled(_descriptor_kernel, flat.shape[0] > 64, reassociate=True, helpers=(_turn,))(
        flat, harmonics, closed, out
    )
    return out.reshape(p.shape[:-2] + out.shape[-1:])


def _descriptors_reference(
    points: ArrayLike,
    *,
    closed: bool = True,
    harmonics: int = DEFAULT_HARMONICS,
) -> Array:
    """:func:`descriptors` in NumPy, from the variants: the reference the compiled kernel is
    tested against, and the path without numba."""
    v = descriptor_variants(points, closed=closed, harmonics=harmonics)
    # An open curve may start at either end: the one whose Z_2 has the larger real part.
    choice = closed_choice(v, harmonics) if closed else np.where(v[..., 0, 1] >= v[..., 1, 1], 0, 1)
    return np.take_along_axis(v, choice[..., None, None], axis=-2)[..., 0, :]


def closed_choice(v: Array, k: int) -> Index:
    """Which of the four closed-curve variants (…, 4, D) is canonical (…,): their first 4K
    entries are Re Z_1 … Z_K, Re Z_−1 … Z_−K, then the imaginary parts, as
    :func:`descriptor_variants` lays them out."""
    # Direction: |Z_1| ≥ |Z_−1| (variants 0, 1 run forwards, 2, 3 backwards).
    re = v[..., : 2 * k]
    forwards = np.abs(re[..., 0, 0]) >= np.abs(re[..., 0, k])
    pair = np.where(forwards, 0, 2)
    # Start/rotation pair: the largest even harmonic's larger part (real or imaginary)
    # positive; the other pair negates every even harmonic.
    first = np.take_along_axis(v, pair[..., None, None], axis=-2)[..., 0, :]
    if k < 2:
        return pair
    even = np.arange(1, k, 2)  # positions of Z_2, Z_4, … among Z_1 … Z_k
    slots = np.concatenate([even, k + even])
    re, im = first[..., slots], first[..., 2 * k + slots]
    big = np.argmax(re * re + im * im, axis=-1)[..., None]
    r, i = np.take_along_axis(re, big, -1)[..., 0], np.take_along_axis(im, big, -1)[..., 0]
    flip = np.where(np.abs(r) >= np.abs(i), r, i) < 0
    return pair + flip


def refine_shift(evaluate: Callable[[Array], tuple[Array, Array]], whole: Array) -> Array:
    """The shift near ``whole`` (the best whole shift) that maximises a smooth objective, given
    ``evaluate(shift) -> (objective, slope)``, both batched.

    The slope at ``whole`` says on which side the maximum lies; where the slope changes sign
    between ``whole`` and the next whole shift that way, its zero is found by regula falsi with
    the Illinois modification (M. Dowell and P. Jarratt, "A modified regula falsi method for
    computing the root of an equation", BIT 11, 1971: superlinear, never leaves the bracket).
    A maximum's flat top pins the shift only to about √ε by values, the slope's steep crossing
    to rounding. Never worse than ``whole``.
    """
    _, g0 = evaluate(whole)
    step = np.where(g0 > 0, 1.0, -1.0)
    _, g1 = evaluate(whole + step)
    # Along t ∈ [0, 1] (shift whole + step·t) the slope G = step·g falls from G(0) > 0 to G(1) < 0.
    lo, hi = np.zeros_like(whole), np.ones_like(whole)
    g_lo, g_hi = step * g0, step * g1
    bracketed = (g_lo > 0) & (g_hi < 0)
    g_lo, g_hi = np.where(bracketed, g_lo, 1.0), np.where(bracketed, g_hi, -1.0)
    kept = np.zeros(whole.shape, dtype=int)  # which end stayed last time: −1 lo, +1 hi
    t = np.zeros_like(whole)
    for _ in range(40):
        before = t
        with np.errstate(invalid="ignore", divide="ignore"):
            t = (lo * g_hi - hi * g_lo) / (g_hi - g_lo)
        t = np.where(np.isfinite(t), t, 0.5 * (lo + hi))
        if not np.any(bracketed & (np.abs(t - before) > 1e-14)):
            break  # converged everywhere: the rest would only cost time
        g = step * evaluate(whole + step * t)[1]
        rising = g > 0  # t replaces lo; hi stays
        lo, g_lo = np.where(rising, t, lo), np.where(rising, g, g_lo)
        hi, g_hi = np.where(rising, hi, t), np.where(rising, g_hi, g)
        # Illinois: an end that stays twice in a row has its slope halved, so the next point
        # moves towards it instead of creeping from the other side.
        g_hi = np.where(rising & (kept == 1), 0.5 * g_hi, g_hi)
        g_lo = np.where(~rising & (kept == -1), 0.5 * g_lo, g_lo)
        kept = np.where(rising, 1, -1)
    best = np.where(bracketed, whole + step * t, whole)
    f_best, f_whole = evaluate(best)[0], evaluate(whole)[0]
    return np.where(f_best >= f_whole, best, whole)


def circular_correlation(spectrum: Complex, shift: Array) -> tuple[Complex, Complex]:
    """c(s) = (1/M) Σ_n spectrum_n e^{2πi f_n s/M} (f_n the FFT's frequencies) and dc/ds, the
    band-limited correlation between samples, for ``spectrum`` (…, C, M) (C correlations
    sharing a shift) and ``shift`` (…): each (…, C)."""
    m = spectrum.shape[-1]
    freq = np.fft.fftfreq(m, 1.0 / m)
    phase = np.exp(2j * np.pi * freq * shift[..., None] / m)
    basis = np.stack([phase, phase * (2j * np.pi * freq / m)], axis=-1)  # (…, M, 2)
    out = spectrum @ basis / m
    return out[..., 0], out[..., 1]


@overload
def shifted_samples(x: Complex, shift: Array, axis: int) -> Complex: ...
@overload
def shifted_samples(x: Array, shift: Array, axis: int) -> Array: ...
def shifted_samples(x: Complex | Array, shift: Array, axis: int) -> Complex | Array:
    """The samples of x(t − shift), band-limited between samples (x complex, or real and then
    the real part), over the sample axis ``axis`` (negative: counted from the end); ``shift``
    has the batch shape."""
    m = x.shape[axis]
    freq = np.fft.fftfreq(m, 1.0 / m)
    phase = np.exp(-2j * np.pi * freq * shift[..., None] / m)
    phase = phase.reshape(phase.shape + (1,) * (-axis - 1))  # axis counts from the end
    out = np.fft.ifft(np.fft.fft(x, axis=axis) * phase, axis=axis)
    return out if np.iscomplexobj(x) else out.real


def _best_correlation(spectrum: Complex) -> tuple[Array, Complex]:
    """The shift s maximising |c(s)| (whole shifts by one inverse FFT, then refined between
    samples) and c(s) there."""
    whole = np.argmax(np.abs(np.fft.ifft(spectrum, axis=-1)), axis=-1).astype(float)

    def evaluate(shift: Array) -> tuple[Array, Array]:
        c, dc = circular_correlation(spectrum[..., None, :], shift)
        return np.abs(c[..., 0]) ** 2, 2.0 * np.real(np.conj(c[..., 0]) * dc[..., 0])

    shift = refine_shift(evaluate, whole)
    return shift, circular_correlation(spectrum[..., None, :], shift)[0][..., 0]


def start_fraction(
    forwards: Array, backwards: Array, reverse: NDArray[np.bool_], samples: int
) -> Array:
    """Where on the curve the target's first point lands, as a fraction of the curve's length
    from its first point along its own direction, given the best shifts (in samples) of the
    curve run forwards and backwards and which won."""
    # A shift s lays target sample j on the direction's sample j − s, so the target's first
    # point on sample −s: at fraction −s/M of the curve forwards, +s/M backwards.
    shift = np.mod(np.where(reverse, backwards, -forwards) / samples, 1.0)
    return np.where(1.0 - shift < 1e-12, 0.0, shift)  # −1e-17 mod 1 is 1 − 1e-17: the start


@dataclass(frozen=True)
class Alignment:
    """The best similarity transform of a curve onto a target (:func:`align`), batched over the
    curves: every field has the batch shape (``translation`` one axis more).

    The transform is p ↦ ``scale``·R(``rotation``)·p + ``translation`` on the curve's points; it
    lays the curve, run backwards if ``reversed``, from the point at ``shift`` (a fraction of its
    length from its first point, along its own direction) onward, over the target from its first
    point onward. ``rms`` is the RMS distance between the two, resampled alike, in the target's
    units; ``error`` is ``rms`` over the target's RMS radius (about its centroid).
    ``reversed`` is False and the rest NaN for a curve or target with a NaN point.
    """

    error: Array
    rms: Array
    scale: Array
    rotation: Array
    translation: Array
    reversed: Array
    shift: Array


def align(
    curve: ArrayLike,
    target: ArrayLike,
    *,
    closed: bool = True,
    samples: int = 256,
) -> Alignment:
    """The best similarity transform (translation, rotation, scale), start point and direction
    of ``curve`` (…, N, 2) onto ``target`` (…, N′, 2), both resampled at ``samples`` points by
    length; batch shapes broadcast.

    For a start shift s (in samples) of the centred curve a the best transform is the complex
    least-squares fit w·a + c ≈ b, w = scale·e^{i·rotation}: w = ⟨a, b⟩_s/‖a‖² and
    c = mean(b) − w·mean(a), with residual ‖b − mean(b)‖² − abs(⟨a, b⟩_s)²/‖a‖². The correlation
    ⟨a, b⟩_s at every whole shift comes from one FFT; the best is then refined between samples
    on the band-limited correlation, so a start point between two samples costs only the
    resampling's own O(1/samples²). Open curves (``closed=False``) keep their ends: only the
    direction is chosen, and ``shift`` is 0 (forwards) or 1 (backwards: from the far end).

    Examples
    --------
    An ellipse, run backwards from its point at t = 90° (a quarter of its length), turned by
    0.5 rad, scaled by 2 and moved by (3, −1):

    >>> t = np.linspace(0, 2 * np.pi, 120, endpoint=False)
    >>> ellipse = np.stack([3 * np.cos(t), np.sin(t)], -1)
    >>> c, s = np.cos(0.5), np.sin(0.5)
    >>> backwards = ellipse[(30 - np.arange(120)) % 120]
    >>> moved = 2 * backwards @ [[c, s], [-s, c]] + [3, -1]
    >>> fit = align(ellipse, moved)
    >>> float(fit.scale), float(fit.rotation), fit.translation.round(6), bool(fit.reversed)
    (2.0, 0.5, array([ 3., -1.]), True)
    >>> float(fit.shift), float(fit.error) < 1e-12
    (0.25, True)

    A curve with a NaN point (a linkage that does not assemble there) has no alignment:

    >>> bad = align([[0, 0], [1, 0], [np.nan, 1]], moved)
    >>> float(bad.error), float(bad.scale), bool(bad.reversed)
    (nan, nan, False)
    """
    a = resample(curve, samples, closed)
    b = resample(target, samples, closed)
    a = a[..., 0] + 1j * a[..., 1]
    b = b[..., 0] + 1j * b[..., 1]
    shape = np.broadcast_shapes(a.shape, b.shape)[:-1]
    mean_a, mean_b = a.mean(axis=-1), b.mean(axis=-1)
    bc = b - mean_b[..., None]
    nb = np.sum(np.abs(bc) ** 2, axis=-1)
    fb = np.fft.fft(bc, axis=-1)
    # Backwards from the same first point (sample t of the reversed curve is sample −t), or
    # for an open curve from its other end.
    reversed_a = np.roll(a[..., ::-1], 1, axis=-1) if closed else a[..., ::-1]
    fits = []
    for x in (a, reversed_a):
        d = x - mean_a[..., None]
        na = np.sum(np.abs(d) ** 2, axis=-1)
        if closed:
            s, corr = _best_correlation(np.conj(np.fft.fft(d, axis=-1)) * fb)
        else:
            s, corr = np.zeros(shape), np.sum(np.conj(d) * bc, axis=-1)
        with np.errstate(invalid="ignore", divide="ignore"):
            fits.append((np.abs(corr) ** 2 / na, corr / na, s))
    (gain_f, w_f, s_f), (gain_b, w_b, s_b) = fits
    backwards = gain_b > gain_f  # NaN compares False: a NaN curve stays "forwards"
    w = np.where(backwards, w_b, w_f)
    if closed:
        shift = start_fraction(s_f, s_b, backwards, samples)
    else:
        shift = np.where(backwards, 1.0, 0.0)
    # The residual ‖b‖² − |⟨a, b⟩|²/‖a‖² cancels to √ε of the size on a near-perfect fit: the
    # transformed curve's distance to the target is summed instead.
    d = np.where(backwards[..., None], reversed_a, a) - mean_a[..., None]
    if closed:
        d = shifted_samples(d, np.where(backwards, s_b, s_f), axis=-1)
    residual = np.sum(np.abs(w[..., None] * d - bc) ** 2, axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        error = np.sqrt(residual / nb)
        rms = np.sqrt(residual / samples)
    c = mean_b - w * mean_a
    bad = np.isnan(error)
    shift = np.where(bad, np.nan, shift)
    return Alignment(
        error=np.broadcast_to(error, shape),
        rms=np.broadcast_to(rms, shape),
        scale=np.broadcast_to(np.abs(w), shape),
        rotation=np.broadcast_to(np.angle(w), shape),
        translation=np.broadcast_to(np.stack([c.real, c.imag], axis=-1), shape + (2,)),
        reversed=np.broadcast_to(backwards & ~bad, shape),
        shift=np.broadcast_to(shift, shape),
    )


def aligned_error(
    curve: ArrayLike,
    target: ArrayLike,
    *,
    closed: bool = True,
    samples: int = 256,
) -> Array:
    """The RMS distance from ``target`` to ``curve`` after the best similarity transform of
    ``curve`` (translation, rotation, scale) and the best start point and direction, both
    resampled at ``samples`` points by length; relative to the RMS radius of ``target``.

    The ``error`` of :func:`align`, which also gives the transform and says how it is found.

    Examples
    --------
    A curve matches itself moved and scaled exactly, and run backwards (so starting between two
    of the 256 samples) to the resampling's error:

    >>> t = np.linspace(0, 2 * np.pi, 120, endpoint=False)
    >>> ellipse = np.stack([3 * np.cos(t), np.sin(t)], -1)
    >>> float(aligned_error(ellipse, 2 * ellipse + 5)), float(aligned_error(ellipse, ellipse[::-1]))
    (0.0, 3.0e-06)

    A curve with a NaN point has no aligned error:

    >>> float(aligned_error([[0, 0], [1, 0], [np.nan, 1]], ellipse))
    nan
    """
    return align(curve, target, closed=closed, samples=samples).error
