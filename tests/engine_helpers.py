"""Random four-bars and slider-cranks, and independent constraint checks, for the engine tests.

These serve tests/test_engine_*.py. Two ways to draw the same space of mechanisms: NumPy batches of
thousands evaluated in one call (what the batched engine is for), and Hypothesis strategies for
single mechanisms, which shrink a failure to a small example. Grashof and non-Grashof proportions
over a 20:1 length range, a share within 1e-9 of the change point, scales 1e-3 .. 1e3, frames
rotated at random and translated by up to 100 times their own size.

The constraint checks recompute the link lengths and branch signs from the positions rather than
trusting the engine's own bookkeeping. Tolerances are relative to the mechanism's scale (its
longest link). Where a quantity is ill-conditioned by the data themselves (a limit position near
a change point, positions of a tiny linkage far from the origin), the tolerance adds the rounding
noise the data carry, computed from the geometry and stated next to the check; for
well-conditioned mechanisms it is the plain number of the acceptance criteria.
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import assume
from hypothesis import strategies as st

from linkwright.mechanisms import (
    FourBar,
    SliderCrank,
    input_range,
)

EPS = np.finfo(float).eps


TWO_PI = 2.0 * np.pi


RESIDUAL_TOL = 1e-10


LIMIT_MARGIN_TOL = 1e-12


DERIVATIVE_TOL = 1e-7


# ----------------------------------------------------------------------------------------------
# Random mechanisms
# ----------------------------------------------------------------------------------------------


def direction(angle):
    angle = np.asarray(angle, dtype=float)
    return np.stack((np.cos(angle), np.sin(angle)), axis=-1)


def _perp(a):
    return np.stack((-a[..., 1], a[..., 0]), axis=-1)


def norm(a):
    return np.hypot(a[..., 0], a[..., 1])


def cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def dot(a, b):
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
    B0 = A0 + lengths[:, :1] * direction(rng.uniform(-np.pi, np.pi, n))
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
    d = direction(angle)
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
    B0 = A0 + frame * k * direction(draw(st.floats(-np.pi, np.pi)))
    # Not the deltoid (crank = frame and coupler = rocker, to rounding): A then passes through
    # B0 itself, where the dyad is undefined: an unassembled input a few ulps wide inside an
    # arc, which a grid cannot bracket (see the engine notes). 1e-9 away is drawn like the rest.
    assume(
        not (
            math.isclose(coupler, rocker, rel_tol=1e-12)
            and math.isclose(crank * k, norm(B0 - A0), rel_tol=1e-12)
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
    d = direction(angle)
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
            np.abs(norm(A - A0) - np.asarray(m.crank)[..., None]),
            np.abs(norm(B - A) - np.asarray(m.coupler)[..., None]),
            np.abs(norm(B - B0) - np.asarray(m.rocker)[..., None]),
            norm(motion.positions["A0"] - A0),
            norm(motion.positions["B0"] - B0),
        ]
    )
    e = (B - A) / norm(B - A)[..., None]
    rel = P - A
    point = np.hypot(
        dot(rel, e) - np.asarray(m.u)[..., None], cross(e, rel) - np.asarray(m.v)[..., None]
    )
    expected = np.asarray(m.assembly)[..., None] if branch is None else branch
    side = cross(B0 - A, B - A)
    noise = 64 * EPS * (norm(A) + norm(B0) + s) * s
    wrong = (np.abs(side) > noise) & (np.sign(side) != expected)
    return lengths / s, point / s, wrong


def slider_errors(m, motion, branch=None):
    """As :func:`fourbar_errors` for a slider-crank: crank, rod, B on the guide, P, and the
    assembly sign sign((B − H)·d), H the foot of A on the guide and d its direction."""
    s = np.asarray(m.scale)[..., None]
    A0 = np.asarray(m.A0, dtype=float)[..., None, :]
    Lp = np.asarray(m.line_point, dtype=float)[..., None, :]
    d = direction(np.asarray(m.line_angle))[..., None, :]
    A, B, P = (motion.positions[k] for k in "ABP")
    lengths = np.maximum.reduce(
        [
            np.abs(norm(A - A0) - np.asarray(m.crank)[..., None]),
            np.abs(norm(B - A) - np.asarray(m.rod)[..., None]),
            np.abs(cross(d, B - Lp)),  # distance of B from the guide
            norm(motion.positions["A0"] - A0),
        ]
    )
    e = (B - A) / norm(B - A)[..., None]
    rel = P - A
    point = np.hypot(
        dot(rel, e) - np.asarray(m.u)[..., None], cross(e, rel) - np.asarray(m.v)[..., None]
    )
    H = Lp + dot(A - Lp, d)[..., None] * d
    side = dot(B - H, d)
    expected = np.asarray(m.assembly)[..., None] if branch is None else branch
    noise = 64 * EPS * (norm(A) + norm(Lp) + s)
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


def angle(v):
    return np.arctan2(v[..., 1], v[..., 0])
