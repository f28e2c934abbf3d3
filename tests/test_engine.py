"""The engine's acceptance properties, checked on many random linkages against independent math.

Every check here recomputes what it tests from the geometry itself (link lengths from positions,
law-of-cosines limits, finite differences, the velocity-ratio formula) rather than trusting the
engine's own bookkeeping. Two kinds of tests:

* NumPy batches of thousands of random mechanisms evaluated in one call (what the batched
  engine is for): Grashof and non-Grashof proportions over a 20:1 length range, a share within
  1e-9 of the change point, scales 1e-3 .. 1e3, frames rotated at random and translated by up to
  100 times their own size.
* Hypothesis ``@given`` tests on single mechanisms drawn from the same space, which shrink a
  failure to a small example.

Tolerances are relative to the mechanism's scale (its longest link). Where a quantity is
ill-conditioned by the data themselves (a limit position near a change point, positions of a
tiny linkage far from the origin), the tolerance adds the rounding noise the data carry, computed
from the geometry and stated next to the check; for well-conditioned mechanisms it is the plain
number of the acceptance criteria.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from linkwright.engine import evaluate
from linkwright.mechanisms import (
    FourBar,
    SliderCrank,
    circuit,
    configurations,
    input_range,
    solve,
)

EPS = np.finfo(float).eps
TWO_PI = 2.0 * np.pi
RESIDUAL_TOL = 1e-10
LIMIT_MARGIN_TOL = 1e-12
DERIVATIVE_TOL = 1e-7

# ----------------------------------------------------------------------------------------------
# Random mechanisms
# ----------------------------------------------------------------------------------------------


def _direction(angle):
    angle = np.asarray(angle, dtype=float)
    return np.stack((np.cos(angle), np.sin(angle)), axis=-1)


def _perp(a):
    return np.stack((-a[..., 1], a[..., 0]), axis=-1)


def _norm(a):
    return np.hypot(a[..., 0], a[..., 1])


def _cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _dot(a, b):
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1]


def _change_point_lengths(x, y, z, longest, delta):
    """A fourth length making {x, y, z, d} a change-point four-bar, then moved by ``delta``.

    With x ≤ y ≤ z sorted, ``d = y + z − x`` (d longest: x + d = y + z) or ``d = x + z − y``
    (d in the middle: x + z = y + d); both are positive, so s + l = p + q exactly.
    """
    x, y, z = np.sort(np.stack((x, y, z)), axis=0)
    d = np.where(longest, y + z - x, x + z - y)
    return d + delta * np.maximum(d, z)


def random_fourbars(rng, n, *, near=0.25, trans=100.0, lever=2.0, scales=(-3.0, 3.0)):
    """``n`` random four-bars as one batched :class:`FourBar`.

    Lengths (frame, crank, coupler, rocker) are log-uniform on [0.05, 1], so every Grashof class
    and non-Grashof linkages occur; a share ``near`` is put within 1e-9 (relative) of the change
    point s + l = p + q, on either side or exactly on it. Everything is then scaled by
    10^U(scales), the frame turned to a random angle and moved by up to ``trans`` scales; the
    coupler point sits within ``lever`` scales of A.
    """
    lengths = np.exp(rng.uniform(np.log(0.05), 0.0, (n, 4)))
    close = rng.random(n) < near
    d = _change_point_lengths(
        lengths[:, 0],
        lengths[:, 1],
        lengths[:, 2],
        rng.random(n) < 0.5,
        rng.choice([-1e-9, 0.0, 1e-9], n),
    )
    lengths[close, 3] = d[close]
    lengths[close] = rng.permuted(lengths[close], axis=1)  # any link may be the odd one
    scale = 10.0 ** rng.uniform(*scales, n)
    lengths *= scale[:, None] / lengths.max(axis=1, keepdims=True)
    A0 = rng.uniform(-trans, trans, (n, 2)) * scale[:, None]
    B0 = A0 + lengths[:, :1] * _direction(rng.uniform(-np.pi, np.pi, n))
    return FourBar(
        A0=A0,
        B0=B0,
        crank=lengths[:, 1],
        coupler=lengths[:, 2],
        rocker=lengths[:, 3],
        u=rng.uniform(-lever, lever, n) * scale,
        v=rng.uniform(-lever, lever, n) * scale,
        assembly=rng.choice([-1.0, 1.0], n),
    )


def random_slider_cranks(rng, n, *, near=0.25, trans=100.0, lever=2.0, scales=(-3.0, 3.0)):
    """``n`` random slider-cranks as one batched :class:`SliderCrank`.

    Crank and rod log-uniform on [0.05, 1]; the eccentricity e (signed distance of A0 from the
    guide) spans ±1.2(crank + rod), so full-turn cranks, rocking cranks and linkages that never
    assemble all occur; a share ``near`` has e within 1e-9 of a degenerate value ±(rod − crank)
    or ±(rod + crank). Scaled, rotated and translated as :func:`random_fourbars`.
    """
    crank = np.exp(rng.uniform(np.log(0.05), 0.0, n))
    rod = np.exp(rng.uniform(np.log(0.05), 0.0, n))
    e = rng.uniform(-1.2, 1.2, n) * (crank + rod)
    critical = np.where(rng.random(n) < 0.5, rod + crank, np.abs(rod - crank))
    critical = critical * rng.choice([-1.0, 1.0], n) + rng.choice([-1e-9, 0.0, 1e-9], n)
    e = np.where(rng.random(n) < near, critical, e)
    size = np.maximum(crank, rod)
    scale = 10.0 ** rng.uniform(*scales, n)
    factor = scale / size
    angle = rng.uniform(-np.pi, np.pi, n)
    d = _direction(angle)
    A0 = rng.uniform(-trans, trans, (n, 2)) * scale[:, None]
    line_point = (
        A0 - (e * factor)[:, None] * _perp(d) + rng.uniform(-2, 2, (n, 1)) * scale[:, None] * d
    )
    return SliderCrank(
        A0=A0,
        crank=crank * factor,
        rod=rod * factor,
        line_point=line_point,
        line_angle=angle,
        u=rng.uniform(-lever, lever, n) * scale,
        v=rng.uniform(-lever, lever, n) * scale,
        assembly=rng.choice([-1.0, 1.0], n),
    )


def take(mech, i):
    """The ``i``-th mechanism of a batch (or a slice of the batch) as a mechanism of its own."""
    return type(mech)(**{k: np.asarray(v)[i] for k, v in mech.params().items()})


def fourbar_lengths(m):
    """(frame, crank, coupler, rocker) and the Grashof excess (s + l − p − q) / l."""
    lengths = np.stack(np.broadcast_arrays(m.frame, m.crank, m.coupler, m.rocker), axis=-1)
    s = np.sort(lengths, axis=-1)
    excess = (s[..., 0] + s[..., 3] - s[..., 1] - s[..., 2]) / s[..., 3]
    return lengths, excess


def slider_excess(m):
    """Relative distance of the eccentricity from its degenerate values |rod ± crank|."""
    e = np.abs(m.offset)
    return np.minimum(np.abs(e - (m.rod + m.crank)), np.abs(e - np.abs(m.rod - m.crank))) / m.scale


# Hypothesis strategies: one mechanism from the same space as the batches.

_unit = st.floats(0.05, 1.0)
_place = st.floats(-100.0, 100.0)


@st.composite
def fourbars(draw, trans=100.0):
    frame, crank, coupler = draw(_unit), draw(_unit), draw(_unit)
    if draw(st.booleans()):
        rocker = draw(_unit)
    else:
        rocker = float(
            _change_point_lengths(
                frame,
                crank,
                coupler,
                draw(st.booleans()),
                draw(st.sampled_from([-1e-9, 0.0, 1e-9])),
            )
        )
        order = draw(st.permutations(range(4)))
        frame, crank, coupler, rocker = ([frame, crank, coupler, rocker][k] for k in order)
    scale = 10.0 ** draw(st.floats(-3.0, 3.0))
    size = max(frame, crank, coupler, rocker)
    k = scale / size
    A0 = np.array([draw(_place), draw(_place)]) * scale * trans / 100.0
    B0 = A0 + frame * k * _direction(draw(st.floats(-np.pi, np.pi)))
    # Not the deltoid (crank = frame and coupler = rocker, to rounding): A then passes through
    # B0 itself, where the dyad is undefined: an unassembled input a few ulps wide inside an
    # arc, which a grid cannot bracket (see the engine notes). 1e-9 away is drawn like the rest.
    assume(
        not (
            math.isclose(coupler, rocker, rel_tol=1e-12)
            and math.isclose(crank * k, _norm(B0 - A0), rel_tol=1e-12)
        )
    )
    return FourBar(
        A0=A0,
        B0=B0,
        crank=crank * k,
        coupler=coupler * k,
        rocker=rocker * k,
        u=draw(st.floats(-2.0, 2.0)) * scale,
        v=draw(st.floats(-2.0, 2.0)) * scale,
        assembly=draw(st.sampled_from([1.0, -1.0])),
    )


@st.composite
def slider_cranks(draw, trans=100.0):
    crank, rod = draw(_unit), draw(_unit)
    if draw(st.booleans()):
        e = draw(st.floats(-1.2, 1.2)) * (crank + rod)
    else:
        e = draw(st.sampled_from([rod + crank, abs(rod - crank)]))
        e = e * draw(st.sampled_from([1.0, -1.0])) + draw(st.sampled_from([-1e-9, 0.0, 1e-9]))
    scale = 10.0 ** draw(st.floats(-3.0, 3.0))
    k = scale / max(crank, rod)
    angle = draw(st.floats(-np.pi, np.pi))
    d = _direction(angle)
    A0 = np.array([draw(_place), draw(_place)]) * scale * trans / 100.0
    line_point = A0 - e * k * _perp(d) + draw(st.floats(-2.0, 2.0)) * scale * d
    return SliderCrank(
        A0=A0,
        crank=crank * k,
        rod=rod * k,
        line_point=line_point,
        line_angle=angle,
        u=draw(st.floats(-2.0, 2.0)) * scale,
        v=draw(st.floats(-2.0, 2.0)) * scale,
        assembly=draw(st.sampled_from([1.0, -1.0])),
    )


def limit_inputs(mech, method="auto"):
    """Every finite limit position of ``input_range`` (NaN-padded), shape batch + (2K,)."""
    arcs = input_range(mech, method=method)
    return np.concatenate((arcs.lo, arcs.hi), axis=-1)


# ----------------------------------------------------------------------------------------------
# Independent constraint checks
# ----------------------------------------------------------------------------------------------


def fourbar_errors(m, motion, branch=None):
    """Constraint errors of a four-bar motion recomputed from positions, relative to scale.

    Returns ``(lengths, point, wrong_assembly)``: the largest |link length − its value| of the
    crank, coupler, rocker and frame pivots, the distance of P from its (u, v) place in the
    coupler frame, both relative; and where the assembly sign sign((B0 − A) × (B − A)) is not
    the expected ``branch`` (default: the mechanism's assembly), checked where that cross
    product is not lost in rounding (it is zero at a limit position, where both branches meet).
    Arrays have the motion's shape; invalid samples are NaN / False.
    """
    s = np.asarray(m.scale)[..., None]
    A0 = np.asarray(m.A0, dtype=float)[..., None, :]
    B0 = np.asarray(m.B0, dtype=float)[..., None, :]
    A, B, P = (motion.positions[k] for k in "ABP")
    lengths = np.maximum.reduce(
        [
            np.abs(_norm(A - A0) - np.asarray(m.crank)[..., None]),
            np.abs(_norm(B - A) - np.asarray(m.coupler)[..., None]),
            np.abs(_norm(B - B0) - np.asarray(m.rocker)[..., None]),
            _norm(motion.positions["A0"] - A0),
            _norm(motion.positions["B0"] - B0),
        ]
    )
    e = (B - A) / _norm(B - A)[..., None]
    rel = P - A
    point = np.hypot(
        _dot(rel, e) - np.asarray(m.u)[..., None], _cross(e, rel) - np.asarray(m.v)[..., None]
    )
    expected = np.asarray(m.assembly)[..., None] if branch is None else branch
    side = _cross(B0 - A, B - A)
    noise = 64 * EPS * (_norm(A) + _norm(B0) + s) * s
    wrong = (np.abs(side) > noise) & (np.sign(side) != expected)
    return lengths / s, point / s, wrong


def slider_errors(m, motion, branch=None):
    """As :func:`fourbar_errors` for a slider-crank: crank, rod, B on the guide, P, and the
    assembly sign sign((B − H)·d), H the foot of A on the guide and d its direction."""
    s = np.asarray(m.scale)[..., None]
    A0 = np.asarray(m.A0, dtype=float)[..., None, :]
    Lp = np.asarray(m.line_point, dtype=float)[..., None, :]
    d = _direction(np.asarray(m.line_angle))[..., None, :]
    A, B, P = (motion.positions[k] for k in "ABP")
    lengths = np.maximum.reduce(
        [
            np.abs(_norm(A - A0) - np.asarray(m.crank)[..., None]),
            np.abs(_norm(B - A) - np.asarray(m.rod)[..., None]),
            np.abs(_cross(d, B - Lp)),  # distance of B from the guide
            _norm(motion.positions["A0"] - A0),
        ]
    )
    e = (B - A) / _norm(B - A)[..., None]
    rel = P - A
    point = np.hypot(
        _dot(rel, e) - np.asarray(m.u)[..., None], _cross(e, rel) - np.asarray(m.v)[..., None]
    )
    H = Lp + _dot(A - Lp, d)[..., None] * d
    side = _dot(B - H, d)
    expected = np.asarray(m.assembly)[..., None] if branch is None else branch
    noise = 64 * EPS * (_norm(A) + _norm(Lp) + s)
    wrong = (np.abs(side) > noise) & (np.sign(side) != expected)
    return lengths / s, point / s, wrong


def assert_closes(m, motion, branch=None, tol=RESIDUAL_TOL):
    """Every valid sample satisfies its constraints: the family's residuals and ours."""
    valid = motion.valid
    for name, r in m.residuals(motion).items():
        assert np.all(np.abs(r[valid]) <= tol), (name, np.max(np.abs(r[valid])))
        assert np.all(np.isnan(r[~valid])), name
    errors = fourbar_errors if isinstance(m, FourBar) else slider_errors
    lengths, point, wrong = errors(m, motion, branch)
    assert np.all(lengths[valid] <= tol), np.max(lengths[valid])
    assert np.all(point[valid] <= tol), np.max(point[valid])
    assert not np.any(wrong[valid]), np.argwhere(wrong & valid)[:5]


# ----------------------------------------------------------------------------------------------
# 1. Every solved position satisfies its constraints
# ----------------------------------------------------------------------------------------------


def test_fourbar_batch_positions_close():
    rng = np.random.default_rng(20240101)
    m = random_fourbars(rng, 20_000)
    _, excess = fourbar_lengths(m)
    assert np.mean(excess < 0) > 0.2 and np.mean(excess > 0) > 0.2  # Grashof and non-Grashof
    assert np.mean(np.abs(excess) < 1e-8) > 0.15  # near the change point
    # Random inputs (many unassembled) and every limit position, exactly.
    theta = np.concatenate(
        (rng.uniform(-np.pi, np.pi, (20_000, 32)), np.nan_to_num(limit_inputs(m))), axis=-1
    )
    motion = solve(m, theta, order=0)
    assert 0.3 < motion.valid.mean() < 0.9
    assert_closes(m, motion)
    limits = np.isfinite(limit_inputs(m))
    assert limits.sum() > 20_000 and motion.valid[:, 32:][limits].all()
    never = input_range(m).never
    assert never.sum() > 1000 and not motion.valid[never].any()


def test_slider_crank_batch_positions_close():
    rng = np.random.default_rng(20240102)
    m = random_slider_cranks(rng, 20_000)
    theta = np.concatenate(
        (rng.uniform(-np.pi, np.pi, (20_000, 32)), np.nan_to_num(limit_inputs(m))), axis=-1
    )
    motion = solve(m, theta, order=0)
    assert 0.3 < motion.valid.mean() < 0.9
    assert_closes(m, motion)
    limits = np.isfinite(limit_inputs(m))
    assert limits.sum() > 20_000 and motion.valid[:, 32:][limits].all()


def _single_inputs(m, data):
    """A handful of inputs for one mechanism: random ones and its exact limit positions."""
    theta = data.draw(st.lists(st.floats(-np.pi, np.pi), min_size=1, max_size=8))
    limits = limit_inputs(m)
    return np.concatenate((theta, limits[np.isfinite(limits)]))


@settings(max_examples=150, deadline=None)
@given(m=fourbars(), data=st.data())
def test_fourbar_single_positions_close(m, data):
    motion = solve(m, _single_inputs(m, data), order=2)
    assert_closes(m, motion)


@settings(max_examples=150, deadline=None)
@given(m=slider_cranks(), data=st.data())
def test_slider_crank_single_positions_close(m, data):
    motion = solve(m, _single_inputs(m, data), order=2)
    assert_closes(m, motion)


def test_assembly_sign_examples():
    """The documented assembly conventions on hand-checkable cases."""
    fb = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5, assembly=1)
    B = solve(fb, [np.pi / 2], order=0).positions["B"][0]
    A = np.array([0.0, 1.0])
    assert _cross(np.array([4.0, 0.0]) - A, B - A) > 0
    assert B[1] > 0  # the "open" assembly above the frame
    sc = SliderCrank(A0=[0, 0], crank=1, rod=3, line_point=[0, -0.5], line_angle=0.0, assembly=1)
    B = solve(sc, [0.0, np.pi / 2], order=0).positions["B"]
    assert np.all(B[:, 0] > [1.0, 0.0])  # ahead of A along +x
    np.testing.assert_allclose(B[:, 1], -0.5)


# ----------------------------------------------------------------------------------------------
# 2. Derivatives: finite differences and closed forms
# ----------------------------------------------------------------------------------------------

# Eighth-order central differences on the stencil θ + kh, k = −4..4.
D1 = np.array([1 / 280, -4 / 105, 1 / 5, -4 / 5, 0.0, 4 / 5, -1 / 5, 4 / 105, -1 / 280])
D2 = np.array([-1 / 560, 8 / 315, -1 / 5, 8 / 5, -205 / 72, 8 / 5, -1 / 5, 8 / 315, -1 / 560])
STENCIL = np.arange(-4, 5)
# h·ω: the stencil spans ±0.04 rad of the fastest link's own rotation. Truncation error
# ~ (hω)^8/630 ≈ 1e-19 relative, rounding ~ eps·(size of coordinates)/(hω)² ≈ 1e-11 for frames
# translated by 10 scales; both far below 1e-7.
H_OMEGA = 0.01


def _links(m):
    """(joint, joint, length) of each moving link whose rotation rate bounds the step."""
    if isinstance(m, FourBar):
        return [("A0", "A", m.crank), ("A", "B", m.coupler), ("B0", "B", m.rocker)]
    return [("A0", "A", m.crank), ("A", "B", m.rod)]


def check_derivatives_by_differences(m, theta, *, min_margin=0.2):
    """Compare analytic velocities and accelerations with 8th-order central differences.

    Only where the linkage is well away from singular positions: the stencil is entirely valid
    and the dyad's margin (sin² of its angle) stays above ``min_margin`` over it (the
    derivatives blow up like 1/sqrt near a limit, where differences fail). The step is scaled
    by the fastest link's angular rate ω (the engine's own rates are only used to pick h), and
    errors are relative to the natural size of the derivative, scale·ω^k. Returns the number
    of samples compared.
    """
    motion = solve(m, theta, order=2)
    s = np.asarray(m.scale)[..., None]
    omega = np.ones_like(motion.input)
    for p, q, length in _links(m):
        length = np.asarray(length)[..., None]
        dv = _norm(motion.velocities[q] - motion.velocities[p]) / length
        da = _norm(motion.accelerations[q] - motion.accelerations[p]) / length
        omega = np.fmax(omega, np.fmax(dv, np.sqrt(da)))
    h = H_OMEGA / omega
    stencil = motion.input[..., None] + STENCIL * h[..., None]
    shape = stencil.shape
    around = solve(m, stencil.reshape(*shape[:-2], -1), order=0)
    margins = around.margins["B"].reshape(shape)
    ok = motion.regular & around.valid.reshape(shape).all(-1) & (margins.min(-1) > min_margin)
    for joint in ("A", "B", "P"):
        pos = around.positions[joint].reshape(*shape, 2)
        vel = np.einsum("k,...kd->...d", D1, pos) / h[..., None]
        acc = np.einsum("k,...kd->...d", D2, pos) / h[..., None] ** 2
        ev = _norm(vel - motion.velocities[joint]) / (s * omega)
        ea = _norm(acc - motion.accelerations[joint]) / (s * omega**2)
        assert np.all(ev[ok] <= DERIVATIVE_TOL), (joint, np.max(ev[ok]))
        assert np.all(ea[ok] <= DERIVATIVE_TOL), (joint, np.max(ea[ok]))
    return int(ok.sum())


def test_fourbar_batch_derivatives_match_differences():
    rng = np.random.default_rng(20240201)
    m = random_fourbars(rng, 4000, near=0.1, trans=10.0)
    compared = check_derivatives_by_differences(m, rng.uniform(-np.pi, np.pi, (4000, 8)))
    assert compared > 5000


def test_slider_crank_batch_derivatives_match_differences():
    rng = np.random.default_rng(20240202)
    m = random_slider_cranks(rng, 4000, near=0.1, trans=10.0)
    compared = check_derivatives_by_differences(m, rng.uniform(-np.pi, np.pi, (4000, 8)))
    assert compared > 5000


@settings(max_examples=100, deadline=None)
@given(m=st.one_of(fourbars(trans=10.0), slider_cranks(trans=10.0)), data=st.data())
def test_single_derivatives_match_differences(m, data):
    theta = np.array(data.draw(st.lists(st.floats(-np.pi, np.pi), min_size=1, max_size=6)))
    check_derivatives_by_differences(m, theta)


def _angle(v):
    return np.arctan2(v[..., 1], v[..., 0])


def test_fourbar_velocity_ratio_closed_form():
    """Rocker and coupler rates from the loop-closure velocity ratios, derived here.

    Differentiating A0 + L1·e(φ1) + L2·e(φ2) = B0 + L3·e(φ3) by θ = φ1 and dotting with e(φ2),
    resp. e(φ3), eliminates one unknown rate each:
        φ3' = L1 sin(φ1 − φ2) / (L3 sin(φ3 − φ2)),   φ2' = −L1 sin(φ3 − φ1) / (L2 sin(φ3 − φ2)).
    """
    rng = np.random.default_rng(20240203)
    m = random_fourbars(rng, 20_000)
    motion = solve(m, rng.uniform(-np.pi, np.pi, (20_000, 16)), order=1)
    A0 = np.asarray(m.A0)[..., None, :]
    B0 = np.asarray(m.B0)[..., None, :]
    A, B = motion.positions["A"], motion.positions["B"]
    L1, L2, L3 = (np.asarray(x)[..., None] for x in (m.crank, m.coupler, m.rocker))
    phi1, phi2, phi3 = _angle(A - A0), _angle(B - A), _angle(B - B0)
    np.testing.assert_allclose(
        np.where(motion.valid, np.cos(phi1 - motion.input), 1.0), 1.0, atol=1e-12
    )
    transmission = np.sin(phi3 - phi2)
    rate3 = L1 * np.sin(phi1 - phi2) / (L3 * transmission)
    rate2 = -L1 * np.sin(phi3 - phi1) / (L2 * transmission)
    engine3 = _cross(B - B0, motion.velocities["B"]) / L3**2
    engine2 = _cross(B - A, motion.velocities["B"] - motion.velocities["A"]) / L2**2
    # Away from toggle (|sin| ≥ 1e-3): the formula's own rounding is ~eps/|sin| relative.
    ok = motion.regular & (np.abs(transmission) > 1e-3)
    assert ok.sum() > 50_000
    for engine, rate in ((engine3, rate3), (engine2, rate2)):
        err = np.abs(engine - rate) / np.maximum(1.0, np.abs(rate))
        assert np.all(err[ok] <= 1e-9), np.max(err[ok])


def test_slider_velocity_closed_form():
    """Slider speed s' = ((B − A)·A') / ((B − A)·d), from d/dθ |B − A|² = 0 with B' = s'·d."""
    rng = np.random.default_rng(20240204)
    m = random_slider_cranks(rng, 20_000)
    motion = solve(m, rng.uniform(-np.pi, np.pi, (20_000, 16)), order=1)
    d = m.direction[..., None, :]
    A, B = motion.positions["A"], motion.positions["B"]
    crank = np.asarray(m.crank)[..., None]
    A_rate = crank[..., None] * _direction(motion.input + np.pi / 2)
    along = _dot(B - A, d)
    speed = _dot(B - A, A_rate) / along
    vB = motion.velocities["B"]
    ok = motion.regular & (np.abs(along) > 1e-3 * np.asarray(m.rod)[..., None])
    assert ok.sum() > 50_000
    s = np.asarray(m.scale)[..., None]
    err = np.abs(_dot(vB, d) - speed) / np.maximum(s, np.abs(speed))
    assert np.all(err[ok] <= 1e-9), np.max(err[ok])
    assert np.all(np.abs(_cross(d, vB))[ok] <= 1e-12 * np.maximum(s, np.abs(speed))[ok])


# ----------------------------------------------------------------------------------------------
# 3. Limit positions are roots
# ----------------------------------------------------------------------------------------------


def triangle_angle(a, b, c):
    """The angle opposite side ``c`` of the triangle with sides a, b, c (NaN if there is none).

    Kahan's formula ("Miscalculating area and angles of a needle-like triangle"): accurate to a
    few ulps for every shape, needles and flat triangles included, unlike arccos of the law of
    cosines near 0 and π. A triangle that is flat within the rounding of its sides counts as
    flat (angle 0 or π): that is a tangency, a double root.
    """
    a, b = np.maximum(a, b), np.minimum(a, b)
    flat = 8 * EPS * (a + b + c)
    with np.errstate(invalid="ignore", divide="ignore"):
        mu = np.where(b >= c, c - (a - b), b - (a - c))
        mu = np.where((mu < 0) & (mu > -flat), 0.0, mu)
        far = (a - c) + b
        far = np.where((far < 0) & (far > -flat), 0.0, far)
        return 2.0 * np.arctan(np.sqrt(((a - b) + c) * mu / ((a + (b + c)) * far)))


def circular_distance(a, b):
    return np.abs((a - b + np.pi) % TWO_PI - np.pi)


def _root_uncertainty(noise, slope, curvature):
    """How far rounding ``noise`` in f(θ) = target moves a root where f has the given slope:
    noise/|slope| for a simple root, but never more than 2·sqrt(noise/curvature), the shift of a
    double root (where f is flat and the two roots of a near-tangency merge)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        linear = noise / np.abs(slope)
        return 1e-13 + np.fmin(linear, 2 * np.sqrt(noise / curvature)), linear


def fourbar_limit_candidates(m):
    """Input angles where |A − B0| = coupler ± rocker, by the law of cosines in A0 B0 A.

    With f = |A0B0|, r the crank and g = coupler ± rocker, the angle γ at A0 opposite g gives
    θ = α ± γ, α the direction of A0→B0. Returns the angles (batch + (4,), NaN where the
    triangle does not exist), each one's θ-uncertainty implied by rounding the data, and
    whether it is a simple root known to 1e-9. q = |A − B0|² = f² + r² − 2fr·cos(θ − α) meets
    g² with slope 2fr·sin γ and curvature ≤ 2fr; q carries ~eps·((f + r + g)² + f·|position|).
    """
    f, r = np.asarray(m.frame), np.asarray(m.crank)
    frame = np.asarray(m.B0) - np.asarray(m.A0)
    alpha = _angle(frame)
    where = _norm(np.asarray(m.A0)) + _norm(np.asarray(m.B0))
    angles, uncertainty, simple = [], [], []
    for g in (m.coupler + m.rocker, np.abs(m.coupler - m.rocker)):
        gamma = triangle_angle(f, r, g)
        noise = 16 * EPS * ((f + r + g) ** 2 + 2 * f * where)
        du, linear = _root_uncertainty(noise, 2 * f * r * np.sin(gamma), 2 * f * r)
        angles += [alpha + gamma, alpha - gamma]
        uncertainty += [du, du]
        simple += [linear < 1e-9] * 2
    return np.stack(angles, -1), np.stack(uncertainty, -1), np.stack(simple, -1)


def slider_limit_candidates(m):
    """Input angles where A's distance from the guide is ±rod: e + r·sin(θ − λ) = ±rod.

    e the signed distance of A0 from the guide, λ its direction: sin(θ − λ) = (±rod − e)/r.
    Same returns as :func:`fourbar_limit_candidates` (slope r·cos(θ − λ), curvature ≤ r).
    """
    lam = np.asarray(m.line_angle)
    e, r, rod = m.offset, np.asarray(m.crank), np.asarray(m.rod)
    where = _norm(np.asarray(m.A0)) + _norm(np.asarray(m.line_point))
    noise = 16 * EPS * (r + rod + where)
    angles, uncertainty, simple = [], [], []
    for target in (rod, -rod):
        x = (target - e) / r
        x = np.where(np.abs(x) - 1 < noise / r, np.clip(x, -1, 1), x)  # tangent within rounding
        with np.errstate(invalid="ignore"):
            base = np.arcsin(x)
        du, linear = _root_uncertainty(noise, r * np.cos(base), r)
        angles += [lam + base, lam + np.pi - base]
        uncertainty += [du, du]
        simple += [linear < 1e-9] * 2
    return np.stack(angles, -1), np.stack(uncertainty, -1), np.stack(simple, -1)


def _limit_margin_tolerance(m, theta):
    """|margin| allowed at a limit: 1e-12, plus the rounding noise of the margin itself.

    margin = ((r1 + r2)² − q)(q − (r1 − r2)²)/(4q·r1²) is computed from q = |B0 − A|² (four-bar,
    r1 coupler, r2 rocker), whose rounding δq ≈ 2g·eps·(|A| + |B0| + r) grows with how far the
    frame sits from the origin; at the root q = g² the margin's sensitivity is r2/(r1·g²). For a
    slider-crank the margin is (rod² − e_A²)/rod², e_A carrying eps·(|A| + |line point|).
    """
    motion = solve(m, np.nan_to_num(theta), order=0)
    A = motion.positions["A"]
    if isinstance(m, FourBar):
        r1, r2 = (np.asarray(x)[..., None] for x in (m.coupler, m.rocker))
        B0 = np.asarray(m.B0)[..., None, :]
        g = _norm(B0 - A)
        dq = 2 * g * EPS * (_norm(A) + _norm(B0) + np.asarray(m.crank)[..., None])
        noise = r2 / (r1 * g * g) * dq
    else:
        rod = np.asarray(m.rod)[..., None]
        Lp = np.asarray(m.line_point)[..., None, :]
        noise = 2 * EPS * (_norm(A) + _norm(Lp)) / rod
    return motion, LIMIT_MARGIN_TOL + 16 * noise


def check_limits(m, method, arcs=None):
    """At every returned limit: assembled, dyad margin ~0, the limiting dyad named."""
    arcs = input_range(m, method=method) if arcs is None else arcs
    theta = np.concatenate((arcs.lo, arcs.hi), axis=-1)
    finite = np.isfinite(theta)
    motion, tol = _limit_margin_tolerance(m, theta)
    assert np.all(motion.valid[finite])
    margin = np.abs(motion.margins["B"])
    assert np.all(margin[finite] <= tol[finite]), np.max(margin[finite] / tol[finite])
    index = np.concatenate((arcs.dyad_lo, arcs.dyad_hi), axis=-1)
    assert np.all(index[finite] == 0) and np.all(index[~finite] == -1)
    # Arcs: lo in (−π, π], hi ≥ lo, sorted, disjoint; NaN padding last; full/never have none.
    # (hi = lo only for a linkage that assembles at a single input, touching its limit.)
    lo, hi = arcs.lo, arcs.hi
    assert np.all((lo[np.isfinite(lo)] > -np.pi) & (lo[np.isfinite(lo)] <= np.pi))
    assert np.array_equal(np.isfinite(lo), np.isfinite(hi))
    assert np.all(hi[np.isfinite(lo)] >= lo[np.isfinite(lo)])
    assert not np.any(np.isfinite(lo)[arcs.full | arcs.never])
    assert not np.any(arcs.full & arcs.never)
    partial = ~(arcs.full | arcs.never)
    assert np.all(arcs.count[partial] >= 1)
    if lo.shape[-1] > 1:
        both = np.isfinite(lo[..., 1])
        assert np.all(lo[..., 1][both] >= hi[..., 0][both])
        assert np.all(hi[..., 1][both] <= lo[..., 0][both] + TWO_PI)
    return arcs, int(finite.sum())


def check_against_candidates(ends, candidates, uncertainty, simple):
    """Each returned limit is one of the closed-form roots and each simple root is returned,
    within the roots' own uncertainty (both sets taken modulo 2π)."""
    dist = circular_distance(ends[..., :, None], candidates[..., None, :])
    dist = np.where(np.isfinite(dist), dist, np.inf)
    # ends → roots: the nearest root within its uncertainty.
    nearest = np.argmin(dist, axis=-1)
    d_end = np.take_along_axis(dist, nearest[..., None], -1)[..., 0]
    u_end = np.take_along_axis(np.nan_to_num(uncertainty, nan=0.0), nearest, -1)
    bad = np.isfinite(ends) & ~(d_end <= u_end)
    assert not bad.any(), (np.argwhere(bad)[:5], d_end[bad][:5], u_end[bad][:5])
    # roots → ends: every simple root is a limit (a tangency may or may not be, by rounding).
    sharp = np.isfinite(candidates) & simple
    d_root = np.min(dist, axis=-2)
    bad = sharp & ~(d_root <= uncertainty)
    assert not bad.any(), (np.argwhere(bad)[:5], d_root[bad][:5], uncertainty[bad][:5])


def check_numeric_agrees(m, analytic):
    """The grid-and-bisection method finds the same arcs wherever its grid can see them.

    The grid has 1440 cells; arcs or gaps narrower than a few cells (only near a change point)
    can fall between its nodes, so the comparison is restricted to arcs and gaps of 3 cells or
    more. There the two must agree to 1e-11 rad: both end on the same rounded predicate.
    """
    numeric = input_range(m, method="numeric")
    check_limits(m, "numeric", numeric)
    cell = TWO_PI / 1440
    lo, hi = analytic.lo, analytic.hi  # at most two arcs
    two = np.isfinite(lo[..., 1])
    pieces = np.stack(
        (
            hi[..., 0] - lo[..., 0],
            hi[..., 1] - lo[..., 1],
            np.where(two, lo[..., 1], lo[..., 0] + TWO_PI) - hi[..., 0],
            lo[..., 0] + TWO_PI - hi[..., 1],
        ),
        axis=-1,
    )
    narrowest = np.min(np.where(np.isfinite(pieces), pieces, TWO_PI), axis=-1)
    seen = analytic.full | analytic.never | (narrowest > 3 * cell)
    assert seen.mean() > 0.6
    assert np.array_equal(numeric.full[seen], analytic.full[seen])
    assert np.array_equal(numeric.never[seen], analytic.never[seen])
    assert np.array_equal(numeric.count[seen], analytic.count[seen])
    k = analytic.lo.shape[-1]
    assert np.all(np.isnan(numeric.lo[seen][..., k:]))
    for a, b in ((analytic.lo, numeric.lo), (analytic.hi, numeric.hi)):
        a, b = a[seen], b[seen][..., :k]
        assert np.array_equal(np.isfinite(a), np.isfinite(b))
        diff = np.abs(a - b)[np.isfinite(a)]
        assert np.all(diff <= 1e-11), np.max(diff)


def test_fourbar_limits_three_ways():
    rng = np.random.default_rng(20240301)
    m = random_fourbars(rng, 20_000)
    analytic, n = check_limits(m, "analytic")
    assert n > 20_000
    ends = np.concatenate((analytic.lo, analytic.hi), axis=-1)
    check_against_candidates(ends, *fourbar_limit_candidates(m))
    # The numeric method evaluates a 1440-point grid per linkage: a fifth of the batch will do.
    few = take(m, slice(0, 4000))
    check_numeric_agrees(few, input_range(few, method="analytic"))
    # Grashof's rule: the crank turns fully exactly when s + l < p + q and the crank or the
    # frame is the shortest link (crank-rocker, double-crank).
    lengths, excess = fourbar_lengths(m)
    shortest = np.argmin(lengths, axis=-1)
    turns = (excess < 0) & ((shortest == 0) | (shortest == 1))
    clear = np.abs(excess) > 1e-8
    np.testing.assert_array_equal(analytic.full[clear], turns[clear])


def test_slider_crank_limits_three_ways():
    rng = np.random.default_rng(20240302)
    m = random_slider_cranks(rng, 20_000)
    analytic, n = check_limits(m, "analytic")
    assert n > 20_000
    ends = np.concatenate((analytic.lo, analytic.hi), axis=-1)
    check_against_candidates(ends, *slider_limit_candidates(m))
    few = take(m, slice(0, 4000))
    check_numeric_agrees(few, input_range(few, method="analytic"))
    # The crank turns fully exactly when |e| ≤ rod − crank.
    e, crank, rod = np.abs(m.offset), m.crank, m.rod
    clear = np.abs(e - (rod - crank)) > 1e-8 * m.scale
    np.testing.assert_array_equal(analytic.full[clear], (e <= rod - crank)[clear])


@pytest.mark.parametrize("make", [random_fourbars, random_slider_cranks])
def test_limit_margins_plain_tolerance(make):
    """Away from change points and with frames near the origin the rounding term is negligible:
    the margin at every returned limit is below 1e-12 outright."""
    rng = np.random.default_rng(20240303)
    m = make(rng, 20_000, near=0.0, trans=1.0)
    theta = limit_inputs(m)
    finite = np.isfinite(theta)
    motion = solve(m, np.nan_to_num(theta), order=0)
    assert finite.sum() > 10_000 and motion.valid[finite].all()
    assert np.max(np.abs(motion.margins["B"][finite])) < LIMIT_MARGIN_TOL


@settings(max_examples=150, deadline=None)
@given(m=st.one_of(fourbars(), slider_cranks()))
def test_single_limits_are_roots(m):
    analytic, _ = check_limits(m, "analytic")
    candidates = fourbar_limit_candidates if isinstance(m, FourBar) else slider_limit_candidates
    ends = np.concatenate((analytic.lo, analytic.hi), axis=-1)
    check_against_candidates(ends, *candidates(m))
    check_limits(m, "numeric")


def test_limit_hand_example():
    """Driving the long link of a crank-rocker: limits where coupler and rocker fold onto each
    other, cos θ = (f² + r² − (c − k)²)/(2fr) with f = 1, r = 3.5, coupler − rocker = 4."""
    m = FourBar(A0=[0, 0], B0=[1, 0], crank=3.5, coupler=5, rocker=1)
    arcs = input_range(m)
    lim = math.acos((1 + 3.5**2 - 16) / 7)  # |A − B0| = coupler − rocker (folded)
    np.testing.assert_allclose(arcs.lo[0], lim, rtol=0, atol=1e-15)
    np.testing.assert_allclose(arcs.hi[0], TWO_PI - lim, rtol=0, atol=1e-14)
    assert not arcs.full and not arcs.never and arcs.count == 1


# ----------------------------------------------------------------------------------------------
# 4. Circuits
# ----------------------------------------------------------------------------------------------

# Largest step between consecutive traced points, against perimeter / n (the mean step; the
# perimeter is the polygon's, which is shorter than the curve's, so the check is the stricter).
#
# Full turns: a constant multiple. The input is sampled uniformly, so a step is the curve's
# speed times 2π/n, and the bound is the ratio of the largest speed to the mean speed: measured
# ≤ 10 over 20,000 random four-bars at n = 90, 360, 1440 (≤ 2.5 for slider-cranks).
# Swinging inputs: no constant multiple is sound. Near a limit every joint moves like
# sqrt(θ − θ_limit) (the dyad's half-chord is r1·sqrt(margin), the margin linear in θ), so the
# step next to a limit is ~c·sqrt(2π/n) while perimeter/n ~ 1/n: the ratio grows like sqrt(n)
# (measured max 14.6, 32, 65 at n = 90, 360, 1440: 1.5–1.7·sqrt(n); 0.74·sqrt(n) for
# slider-cranks; a circle traced uniformly in x gives sqrt(8n)/(2π) = 0.45·sqrt(n)). Both need
# the linkage away from its change point: there the speed concentrates without limit (the
# coupler sweeps most of its curve in a vanishing input interval), so near it only the
# step-halving refinement check (continuity) and the closure checks are asserted.
FULL_STEP_MULTIPLE = 16.0
SWING_STEP_MULTIPLE = 3.0  # × sqrt(n)
STEP_CONDITION = 0.05  # |s + l − p − q| / l, resp. distance of |e| from rod ± crank, / scale


def circuit_steps(motion, joint):
    pos = motion.positions[joint]
    steps = _norm(np.roll(pos, -1, axis=-2) - pos)
    return steps.max(axis=-1), steps.sum(axis=-1)


def check_circuit(m, n, *, well_conditioned):
    arcs = input_range(m)
    motion = circuit(m, n, order=2)
    full, never = arcs.full, arcs.never
    partial = ~(full | never)
    assembly = np.broadcast_to(np.asarray(m.assembly), full.shape)
    up = (n + 1) // 2  # ceil(n / 2)
    # Never assembled: nothing but NaN, every joint.
    assert not motion.valid[never].any() and not motion.regular[never].any()
    for name, pos in motion.positions.items():
        assert np.all(np.isnan(pos[never])), name
    # Everything else is valid at every sample, limits included, and closes.
    assert np.all(motion.valid[~never])
    branch = np.where(np.arange(n) < up, 1.0, -1.0) * assembly[..., None]
    branch = np.where(full[..., None], assembly[..., None], branch)
    assert_closes(m, motion, branch=np.where(never[..., None], 0.0, branch))
    # The sweep: lower limit at sample 0, upper at sample ceil(n/2), both exact, monotonic.
    theta = motion.input[partial]
    np.testing.assert_array_equal(theta[..., 0], arcs.lo[partial][..., 0])
    np.testing.assert_array_equal(theta[..., up], arcs.hi[partial][..., 0])
    ulps = 4 * np.spacing(np.abs(theta[..., 1:]) + 1.0)  # lo·(1 − w) + hi·w rounds
    assert np.all(np.diff(theta[..., : up + 1], axis=-1) >= -ulps[..., :up])
    assert np.all(np.diff(theta[..., up:], axis=-1) <= ulps[..., up:])
    # Branch: flips once up→down at ceil(n/2) and back at the wrap; constant for full turns.
    b = motion.branches["B"]
    np.testing.assert_array_equal(b[partial], branch[partial])
    flips = np.sum(b != np.roll(b, -1, axis=-1), axis=-1)
    assert np.all(flips[partial] == 2) and np.all(flips[full] == 0)
    # Full turns: one turn at the mechanism's assembly.
    np.testing.assert_allclose(
        motion.input[full], np.broadcast_to(TWO_PI * np.arange(n) / n, motion.input[full].shape)
    )
    # Closed and continuous.
    for joint in ("B", "P"):
        largest, perimeter = circuit_steps(motion, joint)
        sel = ~never & well_conditioned & (perimeter > 0)
        multiple = np.where(full, FULL_STEP_MULTIPLE, SWING_STEP_MULTIPLE * np.sqrt(n))
        bound = multiple * perimeter / n
        assert np.all(largest[sel] <= bound[sel]), np.max(largest[sel] / bound[sel])
    return motion, arcs


def check_refinement(m, sel):
    """Refining 4× shrinks the largest step (square-root singular at the limits: ×1/2, smooth:
    ×1/4); a jump (a wrong branch, a missed limit) would not shrink. Measured ≤ 0.54 on
    well-conditioned linkages."""
    coarse, fine = circuit(m, 360, order=0), circuit(m, 1440, order=0)
    for joint in ("B", "P"):
        big, _ = circuit_steps(coarse, joint)
        small, _ = circuit_steps(fine, joint)
        assert np.all(small[sel] <= 0.6 * big[sel]), np.max(small[sel] / big[sel])


def test_fourbar_batch_circuits():
    rng = np.random.default_rng(20240401)
    m = random_fourbars(rng, 3000)
    _, excess = fourbar_lengths(m)
    well = np.abs(excess) > STEP_CONDITION
    for n in (360, 361):
        _, arcs = check_circuit(m, n, well_conditioned=well)
    partial = ~(arcs.full | arcs.never)
    assert arcs.full.sum() > 400 and partial.sum() > 1500 and arcs.never.sum() > 400
    check_refinement(m, well & ~arcs.never)
    # The second arc of linkages with two: traced from its own lower limit.
    two = arcs.count == 2
    assert two.sum() > 100
    second = circuit(m, 64, order=0, circuit=1)
    np.testing.assert_array_equal(second.input[two, 0], arcs.lo[two, 1])
    np.testing.assert_array_equal(second.input[two, 32], arcs.hi[two, 1])
    assert np.all(second.valid[two]) and not np.any(second.valid[arcs.count == 1])


def test_slider_crank_batch_circuits():
    rng = np.random.default_rng(20240402)
    m = random_slider_cranks(rng, 3000)
    well = slider_excess(m) > STEP_CONDITION
    for n in (360, 361):
        _, arcs = check_circuit(m, n, well_conditioned=well)
    assert arcs.full.sum() > 400 and arcs.never.sum() > 400
    check_refinement(m, well & ~arcs.never)


@settings(max_examples=100, deadline=None)
@given(m=st.one_of(fourbars(), slider_cranks()), n=st.integers(2, 400))
def test_single_circuit(m, n):
    if isinstance(m, FourBar):
        well = np.abs(fourbar_lengths(m)[1]) > STEP_CONDITION
    else:
        well = slider_excess(m) > STEP_CONDITION
    check_circuit(m, n, well_conditioned=well)


def test_circuit_hand_example():
    """Never-assembling linkage: all NaN; a rocking input: closed at both limits."""
    never = FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3)
    motion = circuit(never, 12)
    assert not motion.valid.any()
    assert all(np.isnan(p).all() for p in motion.positions.values())
    assert all(np.isnan(v).all() for v in motion.velocities.values())
    rocking = FourBar(A0=[0, 0], B0=[1, 0], crank=3.5, coupler=5, rocker=1)
    motion = circuit(rocking, 8)
    B = motion.positions["B"]
    # At both limits coupler and rocker are folded: |B0 − A| = coupler − rocker.
    for k in (0, 4):
        assert abs(_norm(motion.positions["A"][k] - [1.0, 0.0]) - 4.0) < 1e-14
    # Mirroring in the frame line maps (θ, branch) to (−θ, −branch): sample 1 to sample 5.
    np.testing.assert_allclose(motion.input[1] + motion.input[5], 2 * np.pi)
    np.testing.assert_allclose(B[1], B[5] * [1, -1], atol=1e-14)


# ----------------------------------------------------------------------------------------------
# 5. Masking invariants
# ----------------------------------------------------------------------------------------------


def check_masks(motion):
    valid, regular = motion.valid, motion.regular
    assert not np.any(regular & ~valid)
    for name, pos in motion.positions.items():
        assert pos.shape == (*valid.shape, 2)
        np.testing.assert_array_equal(np.isnan(pos), np.broadcast_to(~valid[..., None], pos.shape))
        assert np.all(np.isfinite(pos[valid])), name
    for derivatives in (motion.velocities, motion.accelerations):
        for name, d in (derivatives or {}).items():
            np.testing.assert_array_equal(
                np.isnan(d), np.broadcast_to(~regular[..., None], d.shape)
            )
            assert np.all(np.isfinite(d[regular])), name


def test_masks_batch():
    rng = np.random.default_rng(20240501)
    for m in (random_fourbars(rng, 5000), random_slider_cranks(rng, 5000)):
        theta = np.concatenate(
            (rng.uniform(-np.pi, np.pi, (5000, 16)), np.nan_to_num(limit_inputs(m))), axis=-1
        )
        motion = solve(m, theta, order=2)
        check_masks(motion)
        assert 0.2 < motion.valid.mean() < 0.9
        check_masks(circuit(m, 37, order=2))
        for _, config in configurations(m, theta[:, :4], order=2):
            check_masks(config)
        check_masks(solve(m, theta, order=1))
        zero = solve(m, theta, order=0)
        assert zero.velocities is None and zero.accelerations is None
        check_masks(zero)


@settings(max_examples=100, deadline=None)
@given(m=st.one_of(fourbars(), slider_cranks()), data=st.data())
def test_masks_single(m, data):
    theta = _single_inputs(m, data)
    check_masks(solve(m, theta))
    check_masks(circuit(m, data.draw(st.integers(2, 50))))


def test_exact_toggle_is_valid_but_not_regular():
    """A limit hit exactly: valid, but the derivatives do not exist and are masked.

    At θ = 0, A = (3, 0) and |B0 − A| = |(3, 4)| = 5 = coupler + rocker, all exact in binary:
    the margin is exactly 0, B lies on the line A–B0 and the 2×2 velocity system is singular.
    """
    m = FourBar(A0=[0, 0], B0=[6, 4], crank=3, coupler=2, rocker=3)
    motion = solve(m, [0.0, 0.1])
    assert motion.margins["B"][0] == 0.0
    np.testing.assert_array_equal(motion.valid, [True, True])
    np.testing.assert_array_equal(motion.regular, [False, True])
    check_masks(motion)
    arcs = input_range(m)
    assert np.nanmin(np.abs(np.concatenate((arcs.lo, arcs.hi)))) < 1e-15


# ----------------------------------------------------------------------------------------------
# 6. Batched equals one-by-one
# ----------------------------------------------------------------------------------------------


def _same(a, b):
    if a is None or b is None:
        return a is b
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    return np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True)


def _row(x, i):
    if x is None:
        return None
    if isinstance(x, dict):
        return {k: v[i] for k, v in x.items()}
    return np.asarray(x)[i]


@pytest.mark.parametrize("family", ["fourbar", "slidercrank"])
def test_batch_equals_one_by_one(family):
    rng = np.random.default_rng(20240601)
    make = random_fourbars if family == "fourbar" else random_slider_cranks
    m = make(rng, 50)
    theta = rng.uniform(-np.pi, np.pi, 24)
    batch = {
        "solve": solve(m, theta, order=2),
        "circuit": circuit(m, 25, order=2),
        "analytic": input_range(m, method="analytic"),
        "numeric": input_range(m, method="numeric"),
        "configurations": configurations(m, theta[:5], order=1),
    }
    for i in range(50):
        one = take(m, i)
        for name, whole in (("solve", solve(one, theta, order=2)), ("circuit", circuit(one, 25))):
            part = batch[name]
            for field in (
                "input",
                "valid",
                "regular",
                "positions",
                "velocities",
                "accelerations",
                "branches",
                "margins",
            ):
                assert _same(getattr(whole, field), _row(getattr(part, field), i)), (name, field)
        for name in ("analytic", "numeric"):
            arcs, part = input_range(one, method=name), batch[name]
            k = arcs.lo.shape[-1]
            for field in ("full", "never"):
                assert _same(getattr(arcs, field), _row(getattr(part, field), i))
            for field in ("lo", "hi", "dyad_lo", "dyad_hi"):
                row = _row(getattr(part, field), i)
                assert _same(getattr(arcs, field), row[:k]), (name, field)
                pad = -1 if field.startswith("dyad") else np.nan
                assert _same(row[k:], np.full(row[k:].shape, pad))
        for (signs, whole), (signs_b, part) in zip(
            configurations(one, theta[:5], order=1), batch["configurations"], strict=True
        ):
            assert signs == signs_b
            assert _same(whole.positions, _row(part.positions, i))
            assert _same(whole.velocities, _row(part.velocities, i))


def test_batch_shapes_broadcast():
    """Scalar fields broadcast against batched ones; inputs may be per-mechanism."""
    rng = np.random.default_rng(20240602)
    crank = rng.uniform(0.1, 0.5, (3, 4))
    m = FourBar(A0=[0, 0], B0=[2, 0], crank=crank, coupler=2.0, rocker=1.5)
    assert m.batch_shape == (3, 4)
    theta = rng.uniform(-np.pi, np.pi, (3, 4, 7))
    motion = solve(m, theta)
    assert motion.positions["P"].shape == (3, 4, 7, 2)
    one = FourBar(A0=[0, 0], B0=[2, 0], crank=crank[1, 2], coupler=2.0, rocker=1.5)
    assert _same(solve(one, theta[1, 2]).positions, _row(_row(motion.positions, 1), 2))


# ----------------------------------------------------------------------------------------------
# Plans directly
# ----------------------------------------------------------------------------------------------


def test_evaluate_branch_override_matches_assembly():
    """A per-sample branch override is the same as rebuilding with that assembly."""
    rng = np.random.default_rng(20240701)
    m = random_fourbars(rng, 200, near=0.0)
    theta = rng.uniform(-np.pi, np.pi, 16)
    flipped = evaluate(
        m.plan,
        m.params(),
        theta,
        points=m.point_fields,
        branches={"B": -np.asarray(m.assembly)[:, None]},
    )
    other = solve(m.with_assembly(-np.asarray(m.assembly)), theta)
    assert _same(flipped.positions, other.positions)
    assert _same(flipped.accelerations, other.accelerations)


def test_plan_rejects_bad_order():
    from linkwright.engine import Crank, Fixed, Plan

    with pytest.raises(ValueError, match="not placed before"):
        Plan((Crank("A", "A0", 1.0), Fixed("A0", "A0")), traced=("A",))
    with pytest.raises(ValueError, match="placed twice"):
        Plan((Fixed("A0", "A0"), Fixed("A0", "A0")), traced=("A0",))
    with pytest.raises(ValueError, match="traced joint"):
        Plan((Fixed("A0", "A0"),), traced=("P",))
