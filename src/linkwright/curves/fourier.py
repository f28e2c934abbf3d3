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
alignment (similarity transform and start point, either direction) exactly.

Open curves (a user's stroke) are closed by running back along themselves: the doubled curve is
symmetric, so Z_{−n} = Z_n carries nothing new, the start point is an end (two choices,
the two variants) and only the rotation is normalised, by Z_1.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine.kernels import available, compiled

__all__ = [
    "CurveError",
    "aligned_error",
    "descriptor_variants",
    "descriptors",
    "resample",
]

Array = NDArray[np.float64]

DEFAULT_SAMPLES = 64
DEFAULT_HARMONICS = 8

prange = range  # numba.prange once the batch kernel is compiled


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
    if samples < 3:
        raise CurveError(f"samples: need at least 3, got {samples}")
    batch = p.shape[:-2]
    p = p.reshape((-1,) + p.shape[-2:])
    if closed:
        p = np.concatenate([p, p[:, :1]], axis=1)
    seg = np.hypot(*np.moveaxis(np.diff(p, axis=1), -1, 0))
    cum = np.concatenate([np.zeros((p.shape[0], 1)), np.cumsum(seg, axis=1)], axis=1)
    total = cum[:, -1:]
    with np.errstate(invalid="ignore", divide="ignore"):
        frac = cum / total
    bad = ~np.isfinite(frac).all(axis=1) | ~(total[:, 0] > 0)
    frac[bad] = np.linspace(0.0, 1.0, frac.shape[1])  # any monotone fill; masked below
    steps = samples if closed else samples - 1
    target = np.arange(samples) / steps
    rows = np.arange(p.shape[0])[:, None]
    # One searchsorted for every row at once: row r's fractions are shifted to [2r, 2r + 1].
    idx = np.searchsorted((frac + 2.0 * rows).ravel(), (target + 2.0 * rows).ravel(), "right")
    idx = idx.reshape(p.shape[0], samples) - rows * frac.shape[1] - 1
    idx = np.clip(idx, 0, frac.shape[1] - 2)
    f0 = np.take_along_axis(frac, idx, axis=1)
    f1 = np.take_along_axis(frac, idx + 1, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        w = np.where(f1 > f0, (target - f0) / (f1 - f0), 0.0)
    a = np.take_along_axis(p, idx[..., None], axis=1)
    b = np.take_along_axis(p, idx[..., None] + 1, axis=1)
    out = a + w[..., None] * (b - a)
    out[bad] = np.nan
    return out.reshape(batch + (samples, 2))


def _fourier(points: ArrayLike, harmonics: int, closed: bool) -> Array:
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


def _normalised(coeffs: Array, harmonics: int, closed: bool) -> Array:
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
        return variants * phase
    # Both directions: backwards swaps Z_n and Z_{−n}.
    forward = np.concatenate([pos, neg], axis=-1)
    backward = np.concatenate([neg, pos], axis=-1)
    out = []
    for z in (forward, backward):
        a1, am1 = np.angle(z[..., :1]), np.angle(z[..., harmonics : harmonics + 1])
        s = 0.5 * (am1 - a1)  # start shift (radians of the period)
        phi = -0.5 * (am1 + a1)  # rotation
        k = np.concatenate([n, -n])
        for extra in (0.0, np.pi):
            out.append(z * np.exp(1j * (phi + extra + k * (s + extra))))
    return np.stack(out, axis=-2)


def _descriptor_kernel(x, y, harmonics, closed, out):
    """The canonical descriptor of each curve (rows of x, y), as :func:`descriptors` defines it
    with NumPy: the same formulas, one curve at a time, no temporaries beyond one curve."""
    count, n_points = x.shape
    k = harmonics
    two_pi = 2.0 * math.pi
    m = n_points if closed else 2 * n_points - 2
    chunk = 64
    for first in prange((count + chunk - 1) // chunk):
        # Scratch for one curve at a time, allocated once per task.
        zr, zi, ur, ui, ds = np.empty(m), np.empty(m), np.empty(m), np.empty(m), np.empty(m)
        wr, wi, qr, qi = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
        acc = np.empty((4, k))
        for c in range(first * chunk, min(count, (first + 1) * chunk)):
            for j in range(m):
                src = j if j < n_points else 2 * n_points - 2 - j
                zr[j] = x[c, src]
                zi[j] = y[c, src]
            length = 0.0
            for j in range(m):
                after = j + 1 if j + 1 < m else 0  # no integer modulo in the loop: it is slow
                dx = zr[after] - zr[j]
                dy = zi[after] - zi[j]
                d = math.sqrt(dx * dx + dy * dy)
                ds[j] = d
                length += d
                ur[j] = dx / d if d > 0.0 else 0.0
                ui[j] = dy / d if d > 0.0 else 0.0
            if not (length > 0.0) or not math.isfinite(length):
                for q in range(out.shape[1]):
                    out[c, q] = np.nan
                continue
            # Per vertex: the tangent's jump (kept in ur, ui: the segment before is read first)
            # and w = e^{−2πi s/L}; q holds w^n as n counts up.
            s_start = 0.0
            last_r, last_i = ur[m - 1], ui[m - 1]
            for j in range(m):
                jump_r, jump_i = ur[j] - last_r, ui[j] - last_i
                last_r, last_i = ur[j], ui[j]
                ur[j], ui[j] = jump_r, jump_i
                angle = -two_pi * s_start / length
                wr[j], wi[j] = math.cos(angle), math.sin(angle)
                qr[j], qi[j] = 1.0, 0.0
                s_start += ds[j]
            pr, pi, nr, ni = acc[0], acc[1], acc[2], acc[3]
            for n in range(k):
                sum_pr = sum_pi = sum_nr = sum_ni = 0.0
                for j in range(m):
                    a, b = qr[j] * wr[j] - qi[j] * wi[j], qr[j] * wi[j] + qi[j] * wr[j]
                    qr[j], qi[j] = a, b
                    sum_pr += ur[j] * a - ui[j] * b
                    sum_pi += ur[j] * b + ui[j] * a
                    sum_nr += ur[j] * a + ui[j] * b  # jump · conj(w^n)
                    sum_ni += ui[j] * a - ur[j] * b
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


def _energy_normalise(v: Array) -> Array:
    with np.errstate(invalid="ignore", divide="ignore"):
        return v / np.sqrt(np.sum(np.abs(v) ** 2, axis=-1, keepdims=True))


def _real(v: Array) -> Array:
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
    flat = p.reshape((-1,) + p.shape[-2:])
    out = np.empty((flat.shape[0], (4 if closed else 2) * harmonics))
    x = np.ascontiguousarray(flat[..., 0])
    y = np.ascontiguousarray(flat[..., 1])
    compiled(_descriptor_kernel, parallel=flat.shape[0] > 64, reassociate=True)(
        x, y, harmonics, closed, out
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
    k = harmonics
    if closed:
        # Direction: |Z_1| ≥ |Z_−1| (variants 0, 1 run forwards, 2, 3 backwards).
        re = v[..., : 2 * k]
        forwards = np.abs(re[..., 0, 0]) >= np.abs(re[..., 0, k])
        pair = np.where(forwards, 0, 2)
        # Start/rotation pair: the largest even harmonic's larger part (real or imaginary)
        # positive; the other pair negates every even harmonic.
        first = np.take_along_axis(v, pair[..., None, None], axis=-2)[..., 0, :]
        even = np.arange(1, k, 2)  # positions of Z_2, Z_4, … among Z_1 … Z_k
        slots = np.concatenate([even, k + even])
        re, im = first[..., slots], first[..., 2 * k + slots]
        big = np.argmax(re * re + im * im, axis=-1)[..., None]
        r, i = np.take_along_axis(re, big, -1)[..., 0], np.take_along_axis(im, big, -1)[..., 0]
        flip = np.where(np.abs(r) >= np.abs(i), r, i) < 0
        choice = pair + flip
    else:
        # Either end first: the one whose Z_2 has the larger real part.
        choice = np.where(v[..., 0, 1] >= v[..., 1, 1], 0, 1)
    return np.take_along_axis(v, choice[..., None, None], axis=-2)[..., 0, :]


def _best_correlation(spectrum: Array, steps: int = 40) -> Array:
    """max over real s of |c(s)|, c(s) = (1/M) Σ_n spectrum_n e^{2πins/M}: the whole shifts by
    one inverse FFT, then golden section between the best one's neighbours."""
    m = spectrum.shape[-1]
    corr = np.abs(np.fft.ifft(spectrum, axis=-1))
    k = np.argmax(corr, axis=-1).astype(float)
    freq = np.fft.fftfreq(m, 1.0 / m)

    def value(shift: Array) -> Array:
        phase = np.exp(2j * np.pi * freq * shift[..., None] / m)
        return np.abs(np.sum(spectrum * phase, axis=-1)) / m

    lo, hi = k - 1.0, k + 1.0
    ratio = (np.sqrt(5.0) - 1.0) / 2.0
    x1, x2 = hi - ratio * (hi - lo), lo + ratio * (hi - lo)
    f1, f2 = value(x1), value(x2)
    for _ in range(steps):
        left = f1 >= f2  # the maximum lies in [lo, x2]
        hi = np.where(left, x2, hi)
        lo = np.where(left, lo, x1)
        x2n = np.where(left, x1, lo + ratio * (hi - lo))
        x1n = np.where(left, hi - ratio * (hi - lo), x2)
        x1, x2 = x1n, x2n
        f1, f2 = value(x1), value(x2)
    return np.maximum(np.max(corr, axis=-1), np.maximum(f1, f2))


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

    For a start shift s of ``curve`` the best transform is a complex least-squares fit
    w·a + c ≈ b, whose residual is ‖b‖² − |⟨a, b⟩_s|²/‖a‖² (centred a, b). The correlation at
    every whole shift comes from one FFT; the best is then refined between samples on the
    band-limited correlation (golden section), so a start point between two samples costs only
    the resampling's own O(1/samples²).

    Examples
    --------
    A curve matches itself moved and scaled exactly, and run backwards (so starting between two
    of the 256 samples) to the resampling's error:

    >>> t = np.linspace(0, 2 * np.pi, 120, endpoint=False)
    >>> ellipse = np.stack([3 * np.cos(t), np.sin(t)], -1)
    >>> float(aligned_error(ellipse, 2 * ellipse + 5)), float(aligned_error(ellipse, ellipse[::-1]))
    (0.0, 3.0e-06)
    """
    a = resample(curve, samples, closed)
    b = resample(target, samples, closed)
    a = a[..., 0] + 1j * a[..., 1]
    b = b[..., 0] + 1j * b[..., 1]
    b = b - b.mean(axis=-1, keepdims=True)
    nb = np.sum(np.abs(b) ** 2, axis=-1)
    best = np.zeros(np.broadcast_shapes(a.shape, b.shape)[:-1])
    fb = np.fft.fft(b, axis=-1)
    for direction in (a, a[..., ::-1]):
        d = direction - direction.mean(axis=-1, keepdims=True)
        na = np.sum(np.abs(d) ** 2, axis=-1)
        if closed:
            c2 = _best_correlation(np.conj(np.fft.fft(d, axis=-1)) * fb) ** 2
        else:
            c2 = np.abs(np.sum(np.conj(d) * b, axis=-1)) ** 2
        with np.errstate(invalid="ignore", divide="ignore"):
            best = np.maximum(best, c2 / na)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.sqrt(np.clip(nb - best, 0.0, None) / nb)
