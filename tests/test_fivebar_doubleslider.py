"""The geared five-bar (paper 002), the double slider (paper 004) and the circuit walker.

Every check recomputes its truth from the geometry in the test: link lengths from positions,
the gear relation from the crank angles, the ellipse from its conjugate semi-diameters (an
independent elimination of θ), derivatives from central differences.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from linkwright.analysis import analyze as analyze_result
from linkwright.analysis import (
    conic_invariants,
    doubleslider_conic,
    ellipse_axes,
    normalise_conic,
)
from linkwright.engine import Crank, DyadRRR, Fixed, Plan, Rigid, evaluate, input_arcs, trace
from linkwright.io.report import analysis_report
from linkwright.mechanisms import (
    DoubleSlider,
    GearedFiveBar,
    InvalidMechanism,
    circuit,
    input_range,
    solve,
)


def analyze(mechanism, **options):
    """The report ``linkwright analyze`` prints (degrees) of the typed analysis (radians)."""
    return analysis_report(analyze_result(mechanism, **options))


RESIDUAL_TOL = 1e-10


def _norm(a):
    return np.hypot(a[..., 0], a[..., 1])


def _cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def random_fivebars(rng, n, ratios=(-1.0, 1.0, 2.0, -2.0, 1.5, -0.5, 2 / 3)):
    return GearedFiveBar(
        A0=rng.uniform(-2, 2, (n, 2)),
        B0=rng.uniform(-2, 2, (n, 2)) + [3.0, 0.0],
        crank1=rng.uniform(0.3, 2, n),
        crank2=rng.uniform(0.3, 2, n),
        link1=rng.uniform(1, 5, n),
        link2=rng.uniform(1, 5, n),
        phase1=rng.uniform(-np.pi, np.pi, n),
        phase2=rng.uniform(-np.pi, np.pi, n),
        ratio=rng.choice(ratios, n),
        u=rng.uniform(-3, 3, n),
        v=rng.uniform(-3, 3, n),
        assembly=rng.choice([-1.0, 1.0], n),
    )


def fivebar_errors(m, motion):
    """Largest constraint error per sample, relative, from positions alone."""
    p = motion.positions
    th = motion.input
    theta2 = np.asarray(m.phase2)[..., None] + np.asarray(m.ratio)[..., None] * (
        th - np.asarray(m.phase1)[..., None]
    )
    want_a = np.asarray(m.A0)[..., None, :] + np.asarray(m.crank1)[..., None, None] * np.stack(
        (np.cos(th), np.sin(th)), -1
    )
    want_b = np.asarray(m.B0)[..., None, :] + np.asarray(m.crank2)[..., None, None] * np.stack(
        (np.cos(theta2), np.sin(theta2)), -1
    )
    e = (p["C"] - p["A"]) / _norm(p["C"] - p["A"])[..., None]
    rel = p["P"] - p["A"]
    errs = [
        _norm(p["A"] - want_a),
        _norm(p["B"] - want_b),
        np.abs(_norm(p["C"] - p["A"]) - np.asarray(m.link1)[..., None]),
        np.abs(_norm(p["C"] - p["B"]) - np.asarray(m.link2)[..., None]),
        np.abs((rel * e).sum(-1) - np.asarray(m.u)[..., None]),
        np.abs(_cross(e, rel) - np.asarray(m.v)[..., None]),
    ]
    side = np.sign(_cross(p["B"] - p["A"], p["C"] - p["A"]))
    return np.maximum.reduce(errs) / np.asarray(m.scale)[..., None], side


# ----------------------------------------------------------------------------------------------
# Geared five-bar
# ----------------------------------------------------------------------------------------------


def test_fivebar_batch_positions_and_branch():
    rng = np.random.default_rng(2002)
    m = random_fivebars(rng, 4000)
    motion = solve(m, np.linspace(-np.pi, np.pi, 73), order=0)
    err, side = fivebar_errors(m, motion)
    valid = motion.valid
    assert 0.2 < valid.mean() < 0.95
    assert np.all(err[valid] < RESIDUAL_TOL)
    for name, r in m.residuals(motion).items():
        assert np.all(np.abs(r[valid]) < RESIDUAL_TOL), name
    # The assembly is the side of C relative to A→B (samples away from a limit, where the
    # side is a rounding).
    margin = motion.margins["C"]
    clear = valid & (margin > 1e-9)
    assert np.all(
        side[clear] == np.broadcast_to(np.asarray(m.assembly)[..., None], side.shape)[clear]
    )
    assert all(np.all(np.isnan(pos[~valid])) for pos in motion.positions.values())


def test_fivebar_derivatives_against_central_differences():
    rng = np.random.default_rng(2003)
    m = random_fivebars(rng, 2000)
    theta = rng.uniform(-np.pi, np.pi, (2000, 1))
    h = 1e-5
    motion = solve(m, theta, order=2)
    plus = solve(m, theta + h, order=0)
    minus = solve(m, theta - h, order=0)
    ok = motion.regular & plus.valid & minus.valid & (motion.margins["C"] > 1e-3)
    assert ok.mean() > 0.3
    for joint in ("A", "B", "C", "P"):
        scale = np.asarray(m.scale)[..., None, None]
        fd_v = (plus.positions[joint] - minus.positions[joint]) / (2 * h)
        fd_a = (plus.positions[joint] - 2 * motion.positions[joint] + minus.positions[joint]) / h**2
        v, a = motion.velocities[joint], motion.accelerations[joint]
        # Central differences: error O(h²)·(third derivative) for v, plus rounding eps/h² for a.
        size = 1.0 + _norm(v)[..., None] + _norm(a)[..., None]
        assert np.all((np.abs(fd_v - v) / (scale * size))[ok] < 1e-6), joint
        assert np.all((np.abs(fd_a - a) / (scale * size))[ok] < 1e-3), joint


def test_fivebar_locking_positions_are_exact_roots():
    """At each locking position |AB| is exactly link1 + link2 or |link1 − link2|."""
    rng = np.random.default_rng(2004)
    m = random_fivebars(rng, 200)
    arcs = input_range(m)
    partial = ~(arcs.full | arcs.never)
    assert partial.sum() > 25
    ends = np.concatenate((arcs.lo, arcs.hi), -1)
    motion = solve(m, np.where(np.isfinite(ends), ends, 0.0), order=0)
    ab = _norm(motion.positions["B"] - motion.positions["A"])
    l1, l2 = np.asarray(m.link1)[..., None], np.asarray(m.link2)[..., None]
    gap = np.minimum(np.abs(ab - (l1 + l2)), np.abs(ab - np.abs(l1 - l2)))
    has = np.isfinite(ends) & partial[..., None]
    assert np.all(motion.valid[has])
    # A root to the last bits of θ: |AB| moves by at most (crank1 + |ratio|·crank2)·ulp(θ).
    assert np.all(gap[has] / np.asarray(m.scale)[..., None].repeat(ends.shape[-1], -1)[has] < 1e-12)


def test_fivebar_circuit_oscillates_between_locking_positions():
    rng = np.random.default_rng(2005)
    m = random_fivebars(rng, 600, ratios=(-1.0, 2.0))
    arcs = input_range(m)
    n = 401
    motion = circuit(m, n, order=0)
    partial = ~(arcs.full | arcs.never)
    assert np.all(motion.valid[~arcs.never])
    up = (n + 1) // 2
    np.testing.assert_array_equal(motion.input[partial, 0], arcs.lo[partial, 0])
    np.testing.assert_array_equal(motion.input[partial, up], arcs.hi[partial, 0])
    b = motion.branches["C"]
    flips = np.sum(b != np.roll(b, -1, -1), -1)
    assert np.all(flips[partial] == 2) and np.all(flips[arcs.full] == 0)
    err, _ = fivebar_errors(m, motion)
    assert np.all(err[motion.valid] < RESIDUAL_TOL)


def test_fractional_ratio_repeats_after_its_period():
    m = GearedFiveBar(
        A0=[0, 0], B0=[3, 0], crank1=0.5, crank2=0.6, link1=3, link2=3, ratio=1.5, u=4, v=1
    )
    assert input_range(m).full
    motion = circuit(m, 720, order=0)
    # Two input turns, evenly: the last sample is one step short of 4π.
    assert motion.input[-1] == pytest.approx(4 * np.pi * 719 / 720)
    p = solve(m, [0.3, 0.3 + 2 * np.pi, 0.3 + 4 * np.pi], order=0).positions["P"]
    assert np.linalg.norm(p[0] - p[2]) < 1e-12
    assert np.linalg.norm(p[0] - p[1]) > 1e-3  # after one turn it is elsewhere


def test_irrational_ratio_and_zero_ratio_are_refused():
    m = GearedFiveBar(A0=[0, 0], B0=[3, 0], crank1=1, crank2=1, link1=3, link2=3, ratio=2**0.5)
    with pytest.raises(ValueError, match="never repeats"):
        circuit(m, 100)
    assert solve(m, [0.1]).valid.all()  # solving at given inputs still works
    with pytest.raises(InvalidMechanism, match="ratio"):
        GearedFiveBar(A0=[0, 0], B0=[3, 0], crank1=1, crank2=1, link1=3, link2=3, ratio=0)


def test_fivebar_report_names_locking():
    m = GearedFiveBar(
        A0=[0, 0], B0=[3, 0], crank1=1, crank2=1.5, link1=2, link2=2.5, ratio=-1, phase2=np.pi
    )
    r = analyze(m)
    assert r["locking"]["oscillates"] is True
    arcs = input_range(m)
    assert r["locking"]["locking_positions_deg"][0] == pytest.approx(np.degrees(arcs.lo[0]))


@settings(max_examples=60, deadline=None)
@given(
    lengths=st.lists(st.floats(0.2, 5.0), min_size=4, max_size=4),
    frame=st.floats(0.0, 6.0),
    ratio=st.sampled_from([-1.0, 1.0, -2.0, 0.5, 3.0]),
    phase=st.floats(-3.0, 3.0),
    n=st.integers(8, 300),
)
def test_single_fivebar_circuit_closes(lengths, frame, ratio, phase, n):
    c1, c2, l1, l2 = lengths
    # Both cranks on one pivot turning together with their ends within rounding of each other
    # (a fresh run drew lengths 1, frame 0, ratio 1, phase 2e-64): the ends are 2e-64 apart at
    # every input, so the closed-form range sees a dyad that assembles, but the placement, in
    # coordinates of size 1, sees the two centres coincide (no direction for C) at all but θ = 0.
    # Not a five-bar that floating point can place; exact coincidence is checked elsewhere.
    ends_apart = abs(c2 * np.exp(1j * phase) - c1)
    assume(not (ratio == 1.0 and frame < 1e-9 and ends_apart < 1e-9 * (c1 + c2)))
    m = GearedFiveBar(
        A0=[0, 0],
        B0=[frame, 0],
        crank1=c1,
        crank2=c2,
        link1=l1,
        link2=l2,
        ratio=ratio,
        phase2=phase,
        u=1.0,
        v=0.5,
    )
    arcs = input_range(m)
    motion = circuit(m, n, order=0)
    if arcs.never:
        assert not motion.valid.any()
        return
    assert motion.valid.all()
    err, _ = fivebar_errors(m, motion)
    assert np.all(err < RESIDUAL_TOL)


# ----------------------------------------------------------------------------------------------
# Double slider
# ----------------------------------------------------------------------------------------------


def random_doublesliders(rng, n):
    alpha = rng.uniform(0.1, np.pi - 0.1, n)
    return DoubleSlider(
        M=rng.uniform(-10, 10, (n, 2)),
        alpha=alpha,
        beta=rng.uniform(-np.pi, np.pi, n),
        p=rng.uniform(-4, 4, n),
        q=rng.uniform(-4, 4, n),
        h=rng.uniform(-3, 3, n),
    )


def test_doubleslider_forward_relations_hold():
    """Sampled P satisfies eq. 3 to 1e-12 relative; the coefficients are normalised (eq. 9)."""
    rng = np.random.default_rng(4004)
    m = random_doublesliders(rng, 5000)
    motion = solve(m, np.linspace(0, 2 * np.pi, 64, endpoint=False), order=0)
    assert motion.valid.all()
    for name, r in m.residuals(motion).items():
        assert np.all(np.abs(r) < RESIDUAL_TOL), name
    c = doubleslider_conic(m)
    x, y = motion.positions["P"][..., 0], motion.positions["P"][..., 1]
    terms = [
        c[..., i, None] * t for i, t in enumerate((x * x, x * y, y * y, x, y, np.ones_like(x)))
    ]
    value = np.sum(terms, axis=0)
    size = np.sum(np.abs(terms), axis=0)
    assert np.all(np.abs(value) / size < 1e-12)
    delta, big = conic_invariants(c)
    k = np.asarray(m.h) ** 2 + (np.asarray(m.p + m.q) * np.asarray(m.h)) / np.tan(m.alpha)
    k = k - np.asarray(m.p) * np.asarray(m.q)
    np.testing.assert_allclose(delta, -4 * k**2, rtol=1e-9, atol=1e-12 * np.max(np.abs(c)))
    np.testing.assert_allclose(big, -(k**4), rtol=1e-8, atol=1e-12 * np.max(np.abs(c)) ** 2)
    # Normalising is a no-op; δ = B² − 4AC cancels like (A + C)²/K², so keep clear of the
    # segment-thin ellipses where that eats the digits.
    far = k**2 > 1e-3 * (c[..., 0] + c[..., 2]) ** 2
    np.testing.assert_allclose(normalise_conic(c)[far], c[far], rtol=1e-9)


def test_doubleslider_ellipse_axes_from_conjugate_diameters():
    """P = M + U cos θ + V sin θ: the semi-axes are the singular values of [U V]."""
    rng = np.random.default_rng(4005)
    m = random_doublesliders(rng, 500)
    p0, p1 = (solve(m, [t], order=0).positions["P"][..., 0, :] for t in (0.0, np.pi / 2))
    centre = np.asarray(m.M)
    w = np.stack((p0 - centre, p1 - centre), -1)  # columns U, V
    s = np.linalg.svd(w, compute_uv=False)
    e = ellipse_axes(doubleslider_conic(m))
    # From coefficients the axes lose digits like (a/b)²·(1 + |M|²/b²): keep to ratios ≥ 1:20.
    ok = s[:, 1] > 0.05 * s[:, 0]
    np.testing.assert_allclose(e["semi_major"][ok], s[ok, 0], rtol=1e-8)
    np.testing.assert_allclose(e["semi_minor"][ok], s[ok, 1], rtol=1e-6)
    np.testing.assert_allclose(e["center"][ok], centre[ok], atol=1e-8 * np.max(np.abs(centre)))
    # The major axis: the point of the ellipse farthest from the centre lies along it.
    theta = np.linspace(0, 2 * np.pi, 1024, endpoint=False)
    far = solve(m, theta, order=0).positions["P"] - centre[:, None, :]
    k = np.argmax(_norm(far), -1)
    d = np.take_along_axis(far, k[:, None, None], 1)[:, 0]
    axis = np.stack((np.cos(e["orientation"]), np.sin(e["orientation"])), -1)
    clear = ok & (s[:, 1] < 0.9 * s[:, 0])
    assert np.all(np.abs(_cross(axis, d / _norm(d)[:, None]))[clear] < 1e-2)


def test_doubleslider_derivatives_and_refusals():
    rng = np.random.default_rng(4006)
    m = random_doublesliders(rng, 1000)
    theta = rng.uniform(-np.pi, np.pi, (1000, 1))
    h = 1e-5
    mo = solve(m, theta)
    plus, minus = solve(m, theta + h, order=0), solve(m, theta - h, order=0)
    for joint in "RQP":
        fd = (plus.positions[joint] - minus.positions[joint]) / (2 * h)
        scale = np.asarray(m.scale)[:, None, None] / np.abs(np.sin(m.alpha))[:, None, None]
        assert np.all(np.abs(fd - mo.velocities[joint]) / scale < 1e-6), joint
        fd2 = (plus.positions[joint] - 2 * mo.positions[joint] + minus.positions[joint]) / h**2
        assert np.all(np.abs(fd2 - mo.accelerations[joint]) / scale < 1e-3), joint
    with pytest.raises(InvalidMechanism, match="alpha"):
        DoubleSlider(M=[0, 0], alpha=np.pi, beta=0, p=1, q=1)
    with pytest.raises(InvalidMechanism, match="p \\+ q"):
        DoubleSlider(M=[0, 0], alpha=1.0, beta=0, p=1, q=-1)


def test_doubleslider_report():
    r = analyze(DoubleSlider(M=[1, 2], alpha=np.pi / 2, beta=np.pi / 6, p=3, q=1))
    e = r["ellipse"]
    assert e["center"] == [1.0, 2.0]
    assert e["semi_major"] == pytest.approx(3) and e["semi_minor"] == pytest.approx(1)
    assert e["orientation_deg"] == pytest.approx(30.0)
    assert e["kind"] == "ellipse"


# ----------------------------------------------------------------------------------------------
# The circuit walker on plans of two dyads (four-bar + dyad from the coupler to ground)
# ----------------------------------------------------------------------------------------------

TWO_DYADS = Plan(
    (
        Fixed("A0", "A0"),
        Fixed("B0", "B0"),
        Fixed("D0", "D0"),
        Crank("A", "A0", "crank"),
        DyadRRR("B", "A", "coupler", "B0", "rocker", branch="s1"),
        Rigid("C", "A", "B", "u1", "v1"),
        DyadRRR("D", "C", "l1", "D0", "l2", branch="s2"),
    ),
    traced=("D",),
)
POINTS = frozenset({"A0", "B0", "D0"})


def random_two_dyads(rng, n):
    return dict(
        A0=np.zeros((n, 2)),
        B0=np.stack([rng.uniform(1, 4, n), np.zeros(n)], -1),
        D0=rng.uniform(-3, 3, (n, 2)),
        crank=rng.uniform(0.5, 2, n),
        coupler=rng.uniform(1, 4, n),
        rocker=rng.uniform(1, 4, n),
        u1=rng.uniform(-2, 2, n),
        v1=rng.uniform(-2, 2, n),
        l1=rng.uniform(1, 4, n),
        l2=rng.uniform(1, 4, n),
        s1=rng.choice([-1.0, 1.0], n),
        s2=rng.choice([-1.0, 1.0], n),
    )


def test_walker_closes_every_circuit_without_a_jump():
    rng = np.random.default_rng(3003)
    params = random_two_dyads(rng, 150)
    arcs = input_arcs(TWO_DYADS, params, points=POINTS)
    ok = ~arcs.never
    steps = {}
    for n in (256, 1024):
        motion = trace(TWO_DYADS, params, n, points=POINTS, order=0)
        assert np.all(motion.valid[ok]) and not motion.valid[~ok].any()
        # Constraints from positions.
        p = motion.positions
        for a, b, length in (("A", "B", "coupler"), ("B0", "B", "rocker"), ("C", "D", "l1")):
            err = np.abs(_norm(p[b] - p[a]) - params[length][:, None])
            assert np.all(err[ok] < 1e-10 * 8)
        # Each branch change happens at a limit of the dyad that changes: its margin is ~0.
        for name in ("B", "D"):
            b = motion.branches[name]
            change = b != np.roll(b, 1, -1)
            assert np.all(motion.margins[name][change & ok[:, None]] < 1e-9)
        closed = np.concatenate((p["D"], p["D"][:, :1]), 1)
        steps[n] = np.max(np.nan_to_num(_norm(np.diff(closed, axis=1))), -1)
    # Refining 4× shrinks the largest step: a jump between branches would not shrink.
    assert np.all(steps[1024][ok] <= 0.6 * steps[256][ok])


def test_walker_agrees_with_single_dyad_sweep():
    """With the second dyad never limiting, the walk is the four-bar's own sweep."""
    rng = np.random.default_rng(3004)
    params = random_two_dyads(rng, 200)
    params["l1"] = params["l2"] = np.full(200, 50.0)  # a dyad that always closes
    arcs = input_arcs(TWO_DYADS, params, points=POINTS)
    motion = trace(TWO_DYADS, params, 64, points=POINTS, order=0)
    partial = ~(arcs.full | arcs.never)
    assert partial.sum() > 20
    np.testing.assert_array_equal(motion.input[partial, 0], arcs.lo[partial, 0])
    # The upper limit is a sample too (found again by the walker: to a few ulps).
    gap = np.min(np.abs(motion.input[partial] - arcs.hi[partial, :1]), -1)
    assert np.all(gap < 1e-13)
    four = evaluate(
        TWO_DYADS, params, motion.input, points=POINTS, branches={"B": motion.branches["B"]}
    )
    np.testing.assert_array_equal(four.positions["C"][partial], motion.positions["C"][partial])
