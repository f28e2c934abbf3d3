"""The spherical triad and every configuration of paper 001's spherical Stephenson III.

Every check recomputes what it tests from the geometry itself, written out here by hand: B and C
from paper 001's eq. 5, G beyond D on the meridian, F from θ6 about OG, and E from the three
scalar conditions that fix it on the rigid coupler (E·C = cos a6, E·B = cos a3 cos a6 − sin a3
sin a6 cos σ, (C × B)·E = sin a3 sin a6 sin σ), solved as a 3×3 linear system. Constraints are
checked as dot products, not arcs. The polynomial solver (:func:`sphere_triad`) is compared with
the sweep (:func:`sphere_triad_sweep`), which shares no step with it but the final residual
test; poses built first are looked for; counts for input AB are compared with a closed-form
count of the circle intersections; every configuration of one input is found again from the
other.

Where a pose is close to a singular position (the 2×2 Jacobian of the two closure equations in
θ1, θ4 nearly singular, or the four-bar ABCD near a limit), the number of real poses itself is
ill-conditioned, and the sweep resolves a root next to a limit only to about 1e-8: such cases are
left out of the method-against-method comparisons (and counted, so that the exclusion cannot
grow unnoticed); every pose is still checked against its constraints. The sweep is blind where
B = ±D (its four-bar's circles are concentric); those cases are left out as well.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

from linkwright.engine.sphere_triad import (
    MAX_POSES,
    OFFSET_B,
    OFFSET_C,
    InvalidTriad,
    bilinear_resultant,
    circle_frame,
    sphere_triad,
    sphere_triad_sweep,
)
from linkwright.mechanisms import SphericalStephenson3, solve, solve_all
from linkwright.mechanisms.allconfigs import InvalidInputs
from linkwright.papers.p001_angles import paper_angles, triad_of

SLOTS = {"AB": 4, "FG": 8}

EXAMPLE = np.radians([115, 105, 110, 90, 80, 70, 65, 85, 25])
TOL = 1e-12
SAME = 1e-9
# Relative Jacobian determinant and four-bar margin below which a pose counts as near-singular.
NEAR_SINGULAR = 1e-4

# ----------------------------------------------------------------------------------------------
# Independent geometry (paper 001's frame, written out)
# ----------------------------------------------------------------------------------------------


def _arcs(a):
    """Named arcs from the nine-tuple (a1, a2, a3, a4, a6, σ, a7, a8, a9)."""
    return dict(zip(("a1", "a2", "a3", "a4", "a6", "sigma", "a7", "a8", "a9"), a, strict=True))


def _fixed(p):
    a = np.array([0.0, 0.0, 1.0])
    d = np.array([0.0, np.sin(p["a1"]), np.cos(p["a1"])])
    far = p["a1"] + p["a9"]
    g = np.array([0.0, np.sin(far), np.cos(far)])
    return a, d, g


def _b(p, theta1):
    """Eq. 5's B."""
    s2 = np.sin(p["a2"])
    return np.stack(
        np.broadcast_arrays(s2 * np.sin(theta1), s2 * np.cos(theta1), np.cos(p["a2"])), -1
    )


def _c(p, theta4):
    """Eq. 5's C."""
    s1, c1, s4, c4 = np.sin(p["a1"]), np.cos(p["a1"]), np.sin(p["a4"]), np.cos(p["a4"])
    return np.stack(
        (
            s4 * np.sin(theta4),
            s1 * c4 + c1 * s4 * np.cos(theta4),
            c1 * c4 - s1 * s4 * np.cos(theta4),
        ),
        -1,
    )


def _f(p, theta6):
    """F at θ6 about +OG from the meridian beyond G (away from D): by hand, G × t = −x."""
    far = p["a1"] + p["a9"]
    g = np.array([0.0, np.sin(far), np.cos(far)])
    t = np.array([0.0, np.cos(far), -np.sin(far)])
    th = np.asarray(theta6, dtype=float)[..., None]
    x = np.array([-1.0, 0.0, 0.0])
    return np.cos(p["a8"]) * g + np.sin(p["a8"]) * (np.cos(th) * t + np.sin(th) * x)


def _theta6(p, f):
    far = p["a1"] + p["a9"]
    t = np.array([0.0, np.cos(far), -np.sin(far)])
    return np.arctan2(-f[..., 0], f @ t)


def _e(p, b, c):
    """E from its three scalar conditions on the coupler, solved as a linear system."""
    a3, a6, s = p["a3"], p["a6"], p["sigma"]
    rows = np.stack((c, b, np.cross(c, b)), -2)
    rhs = np.stack(
        np.broadcast_arrays(
            np.cos(a6),
            np.cos(a3) * np.cos(a6) - np.sin(a3) * np.sin(a6) * np.cos(s),
            np.sin(a3) * np.sin(a6) * np.sin(s),
        ),
        -1,
    )
    return np.linalg.solve(rows, rhs[..., None])[..., 0]


def _violation(p, pos):
    """Largest violation of every constraint by joints pos (name → (..., 3)), dot form."""
    a, d, g = _fixed(p)
    b, c, e, f = (pos[k] for k in "BCEF")
    parts = [
        np.abs(b @ a - np.cos(p["a2"])),
        np.abs(np.sum(b * c, -1) - np.cos(p["a3"])),
        np.abs(c @ d - np.cos(p["a4"])),
        np.abs(np.sum(e * f, -1) - np.cos(p["a7"])),
        np.abs(f @ g - np.cos(p["a8"])),
        np.abs(e - _e(p, b, c)).max(-1),
        *(np.abs(np.linalg.norm(x, axis=-1) - 1.0) for x in (b, c, e, f)),
    ]
    for k, x in zip("ADG", (a, d, g), strict=True):
        parts.append(np.abs(pos[k] - x).max(-1))
    return np.maximum.reduce(np.broadcast_arrays(*parts))


def _closure(p, theta1, theta4, f):
    """(B·C − cos a3, E·F − cos a7) at (θ1, θ4): the two equations of the triad."""
    b, c = _b(p, theta1), _c(p, theta4)
    return np.array([b @ c - np.cos(p["a3"]), _e(p, b, c) @ f - np.cos(p["a7"])])


def _conditioning(p, b, c, f):
    """(relative Jacobian determinant of the closure in θ1, θ4; four-bar margin) at a pose."""
    theta1 = np.arctan2(b[0], b[1])
    s1, c1 = np.sin(p["a1"]), np.cos(p["a1"])
    theta4 = np.arctan2(
        c[0], (c[1] - s1 * np.cos(p["a4"])) * c1 - (c[2] - c1 * np.cos(p["a4"])) * s1
    )
    h = 1e-6
    j = np.stack(
        [
            (_closure(p, theta1 + h, theta4, f) - _closure(p, theta1 - h, theta4, f)) / (2 * h),
            (_closure(p, theta1, theta4 + h, f) - _closure(p, theta1, theta4 - h, f)) / (2 * h),
        ],
        -1,
    )
    scale = np.sin(p["a2"]) * np.sin(p["a4"])
    _, d, _ = _fixed(p)
    with np.errstate(invalid="ignore", divide="ignore"):
        margin = abs(np.cross(b, d) @ c) / np.linalg.norm(np.cross(b, d)) / np.sin(p["a3"])
    return abs(np.linalg.det(j)) / scale, margin


def _near_singular(p, poses_b, poses_c, f):
    _, d, _ = _fixed(p)
    for b, c in zip(poses_b, poses_c, strict=True):
        if not np.isfinite(b).all():
            continue
        if np.linalg.norm(np.cross(b, d)) < 1e-3:  # B at ±D: the sweep's blind spot
            return True
        det, margin = _conditioning(p, b, c, f)
        if det < NEAR_SINGULAR or margin < NEAR_SINGULAR:
            return True
    return False


def _set_gap(x, y):
    """Largest distance from a pose of either set to the nearest of the other (inf if unmatched).

    x, y: (k, m) joints flattened per pose, NaN rows ignored.
    """
    x = x[np.isfinite(x).all(-1)]
    y = y[np.isfinite(y).all(-1)]
    if len(x) != len(y):
        return np.inf
    if not len(x):
        return 0.0
    gap = np.abs(x[:, None] - y[None]).max(-1)
    return max(gap.min(0).max(), gap.min(1).max())


def _random_arcs(rng, n):
    a = rng.uniform(0.15, np.pi - 0.15, (9, n))
    a[5] = rng.uniform(-np.pi, np.pi, n)
    return a


arc = st.floats(0.15, np.pi - 0.15)
angle = st.floats(-np.pi, np.pi)


# ----------------------------------------------------------------------------------------------
# The triad solver
# ----------------------------------------------------------------------------------------------


@settings(max_examples=40, deadline=None)
@given(st.lists(arc, min_size=9, max_size=9), angle, angle)
def test_polynomial_and_sweep_agree_on_random_mechanisms(arcs, sigma, theta6):
    arcs[5] = sigma
    p = _arcs(arcs)
    m = SphericalStephenson3(*arcs, input="FG")
    args = triad_of(m, theta6)
    poly = sphere_triad(*args)
    swept = sphere_triad_sweep(*args, grid=2048)
    f = _f(p, theta6)
    assume(not _near_singular(p, poly.b, poly.c, f))
    assume(not _near_singular(p, swept.b, swept.c, f))
    assert int(poly.count) == int(swept.count)
    both = [np.concatenate((r.b, r.c, r.e), -1) for r in (poly, swept)]
    assert _set_gap(*both) < SAME
    pos = {"B": poly.b, "C": poly.c, "E": poly.e, "F": np.broadcast_to(f, poly.b.shape)}
    pos.update(dict(zip("ADG", _fixed(p), strict=True)))
    assert np.all(_violation(p, pos)[poly.valid] < TOL)


def test_polynomial_and_sweep_agree_on_a_random_batch():
    rng = np.random.default_rng(11)
    n = 600
    arcs = _random_arcs(rng, n)
    theta6 = rng.uniform(-np.pi, np.pi, n)
    m = SphericalStephenson3(*arcs, input="FG")
    args = triad_of(m, theta6[:, None])
    poly = sphere_triad(*args)
    swept = sphere_triad_sweep(*args, grid=1024)
    skipped = 0
    for i in range(n):
        p = _arcs(arcs[:, i])
        f = _f(p, theta6[i])
        if _near_singular(p, poly.b[i, 0], poly.c[i, 0], f) or _near_singular(
            p, swept.b[i, 0], swept.c[i, 0], f
        ):
            skipped += 1
            continue
        assert poly.count[i, 0] == swept.count[i, 0], i
        both = [np.concatenate((r.b[i, 0], r.c[i, 0], r.e[i, 0]), -1) for r in (poly, swept)]
        assert _set_gap(*both) < SAME, i
    assert skipped < 0.05 * n
    # Random mechanisms have 0, 2, 4 and 6 configurations here; the 8 of the paper's example
    # are tested below.
    assert set(np.unique(poly.count)) >= {0, 2, 4, 6}


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.floats(-1.0, 1.0), min_size=12, max_size=12),
    st.lists(arc, min_size=3, max_size=3),
    st.one_of(angle, st.sampled_from([0.0, np.pi, -np.pi / 2, OFFSET_B + np.pi, OFFSET_B])),
    st.one_of(angle, st.sampled_from([0.0, np.pi, np.pi / 2, OFFSET_C + np.pi, OFFSET_C])),
    st.sampled_from([1.0, -1.0]),
    st.sampled_from([1.0, -1.0]),
    angle,
)
def test_a_pose_built_first_is_found(vectors, arcs, theta_b, theta_c, sense_b, sense_c, turn):
    v = np.array(vectors).reshape(4, 3)
    assume(np.all(np.linalg.norm(v, axis=-1) > 0.2))
    axis_b, ref_b, axis_c, ref_c = v / np.linalg.norm(v, axis=-1)[:, None]
    assume(np.linalg.norm(np.cross(axis_b, ref_b)) > 0.1)
    assume(np.linalg.norm(np.cross(axis_c, ref_c)) > 0.1)
    frame_b = circle_frame(axis_b, ref_b, sense_b)
    frame_c = circle_frame(axis_c, ref_c, sense_c)
    arc_b, arc_c, ce = arcs

    def on(frame, r, t):
        return np.cos(r) * frame[0] + np.sin(r) * (np.cos(t) * frame[1] + np.sin(t) * frame[2])

    b, c = on(frame_b, arc_b, theta_b), on(frame_c, arc_c, theta_c)
    bc = np.arccos(np.clip(b @ c, -1, 1))
    assume(0.1 < bc < np.pi - 0.1)
    # E from its three conditions (turn = π − σ): E·C, E·B and the triple product.
    rows = np.stack((c, b, np.cross(c, b)))
    rhs = [
        np.cos(ce),
        np.cos(bc) * np.cos(ce) + np.sin(bc) * np.sin(ce) * np.cos(turn),
        np.sin(bc) * np.sin(ce) * np.sin(turn),
    ]
    e = np.linalg.solve(rows, rhs)
    f = np.cross(e, axis_b) + 0.5 * axis_c
    assume(np.linalg.norm(f) > 0.2)
    f = f / np.linalg.norm(f)
    ef = np.arccos(np.clip(e @ f, -1, 1))
    assume(0.1 < ef < np.pi - 0.1)

    def closure(tb, tc):
        bb, cc = on(frame_b, arc_b, tb), on(frame_c, arc_c, tc)
        rr = np.stack((cc, bb, np.cross(cc, bb)))
        ee = np.linalg.solve(rr, rhs)
        return np.array([bb @ cc - np.cos(bc), ee @ f - np.cos(ef)])

    h = 1e-6
    jac = np.stack(
        [
            (closure(theta_b + h, theta_c) - closure(theta_b - h, theta_c)) / (2 * h),
            (closure(theta_b, theta_c + h) - closure(theta_b, theta_c - h)) / (2 * h),
        ],
        -1,
    )
    assume(abs(np.linalg.det(jac)) > NEAR_SINGULAR * np.sin(arc_b) * np.sin(arc_c))
    poses = sphere_triad(frame_b, arc_b, frame_c, arc_c, bc, ce, turn, f, ef)
    found = np.concatenate((poses.b, poses.c, poses.e), -1)
    gap = np.abs(found - np.concatenate((b, c, e))).max(-1)
    assert np.nanmin(gap) < SAME
    assert 1 <= int(poses.count) <= MAX_POSES
    assert np.all(poses.residual[poses.valid] < 1e-10)


def test_bilinear_resultant_vanishes_at_every_common_solution():
    # Two random bilinear forms; their common solutions by a dense 2-D grid search + Newton are
    # roots of the resultant, and the resultant has degree 8.
    rng = np.random.default_rng(5)
    m1, m2 = rng.normal(size=(2, 3, 3))
    coef = bilinear_resultant(m1, m2)
    assert coef.shape == (9,) and coef[-1] != 0
    roots = np.roots(coef[::-1])
    real = np.sort(2 * np.arctan(roots[np.abs(roots.imag) < 1e-9].real))

    def g(u, w):
        mu = np.array([1, np.cos(u), np.sin(u)])
        nu = np.array([1, np.cos(w), np.sin(w)])
        return np.array([mu @ m1 @ nu, mu @ m2 @ nu])

    grid = np.linspace(-np.pi, np.pi, 241)
    found = []
    for u0 in grid[:-1]:
        for w0 in grid[:-1]:
            u, w = u0, w0
            for _ in range(30):
                h = 1e-7
                jac = np.stack(
                    [(g(u + h, w) - g(u - h, w)) / (2 * h), (g(u, w + h) - g(u, w - h)) / (2 * h)],
                    -1,
                )
                try:
                    du, dw = np.linalg.solve(jac, g(u, w))
                except np.linalg.LinAlgError:
                    break
                u, w = u - du, w - dw
                if abs(du) + abs(dw) > 10:
                    break
            if np.abs(g(u, w)).max() < 1e-12:
                found.append(np.angle(np.exp(1j * u)))
            if len(found) > 200:
                break
    found = np.unique(np.round(found, 9))
    assert len(found) == len(real)
    assert np.abs(np.sort(found) - real).max() < 1e-7


# ----------------------------------------------------------------------------------------------
# Input FG: every configuration
# ----------------------------------------------------------------------------------------------


def test_eight_real_configurations_of_the_example():
    p = _arcs(EXAMPLE)
    m = SphericalStephenson3(*EXAMPLE, input="FG")
    theta6 = np.radians(280.0)
    every = solve_all(m, [theta6])
    assert every.driven == "FG" and SLOTS["FG"] == 8
    assert int(every.count[0]) == 8
    pos = {k: v[0] for k, v in every.positions.items()}
    assert np.all(_violation(p, pos) < TOL)
    assert np.abs(_f(p, theta6) - pos["F"]).max() < TOL
    joints = np.concatenate([pos[k] for k in "BCE"], -1)
    gap = np.abs(joints[:, None] - joints[None]).max(-1) + 9 * np.eye(8)
    assert gap.min() > 0.1  # eight distinct configurations, far apart
    # The sweep finds the same eight.
    swept = sphere_triad_sweep(*triad_of(m, theta6))
    assert int(swept.count) == 8
    assert _set_gap(joints, np.concatenate((swept.b, swept.c, swept.e), -1)) < SAME
    # Signs read off the positions.
    _, d, g = _fixed(p)
    sign1 = np.sign(np.einsum("ki,ki->k", np.cross(pos["B"], d), pos["C"]))
    sign2 = np.sign(np.einsum("ki,ki->k", np.cross(pos["E"], g), pos["F"]))
    assert np.array_equal(every.assembly[0], sign1)
    assert np.array_equal(every.assembly2[0], sign2)


def test_a_mechanism_with_eight_configurations_at_every_input():
    m = SphericalStephenson3(*np.radians([120, 100, 100, 90, 90, 80, 75, 80, 30]), input="FG")
    every = solve_all(m, np.radians(np.arange(0.0, 360.0, 15.0)))
    assert np.all(every.count == 8)
    assert np.nanmax(every.residual) < TOL


def _feed_back(arcs, theta6, every):
    """Largest |Δθ6| when each FG configuration is rebuilt by the AB plan on its signs."""
    p = _arcs(arcs)
    worst = 0.0
    valid = np.argwhere(every.valid)
    for idx in valid:
        idx = tuple(idx)
        s1, s2 = every.assembly[idx], every.assembly2[idx]
        b, c, e, f = (every.positions[k][idx] for k in "BCEF")
        _, margin = _conditioning(p, b, c, f)
        _, _, g = _fixed(p)
        dyad = abs(np.cross(e, g) @ f) / np.linalg.norm(np.cross(e, g)) / np.sin(p["a7"])
        # Near a limit of either dyad the plan's branch is ill-conditioned; with B on ±D (a
        # pose that a1 = a2, a3 = a4 allows) C is not determined by θ1 at all.
        off_d = np.linalg.norm(np.cross(b, _fixed(p)[1]))
        if s1 == 0 or s2 == 0 or off_d < 1e-6:
            continue
        if not (margin >= NEAR_SINGULAR and dyad >= NEAR_SINGULAR):
            continue
        theta1 = np.arctan2(b[0], b[1])
        plan = SphericalStephenson3(*arcs, assembly=s1, assembly2=s2)
        again = solve(plan, [theta1], order=0).positions["F"][0]
        diff = np.angle(np.exp(1j * (_theta6(p, again) - theta6[idx[:-1]])))
        worst = max(worst, abs(diff))
    return worst


def test_fg_configurations_feed_back_into_the_ab_plan_on_the_example():
    theta6 = np.radians(np.arange(0.0, 360.0, 5.0))
    every = solve_all(SphericalStephenson3(*EXAMPLE, input="FG"), theta6)
    assert every.count.max() == 8
    assert _feed_back(EXAMPLE, np.broadcast_to(theta6, every.count.shape), every) < 1e-9


@settings(max_examples=30, deadline=None)
@given(st.lists(arc, min_size=9, max_size=9), angle, st.lists(angle, min_size=3, max_size=3))
def test_fg_configurations_feed_back_into_the_ab_plan(arcs, sigma, theta6):
    arcs[5] = sigma
    theta6 = np.array(theta6)
    every = solve_all(SphericalStephenson3(*arcs, input="FG"), theta6)
    assert _feed_back(np.array(arcs), theta6, every) < 1e-9
    p = _arcs(arcs)
    violation = _violation(p, dict(every.positions))
    # A pose at a singular configuration (a double root: Newton converges only linearly
    # there) is held to the solver's promise, 1e-10; every other one to 1e-11.
    for idx in np.argwhere(every.valid):
        b, c, f = (every.positions[k][tuple(idx)] for k in "BCF")
        det, margin = _conditioning(p, b, c, f)
        regular = det >= NEAR_SINGULAR and margin >= NEAR_SINGULAR
        # Regular: the conditioning (>= 1e-4) amplifies rounding at most 1e4-fold, so a few
        # ulp become ~1e-12; seen 1.46e-12 with det ~1e-3: hold it to 1e-11.
        assert violation[tuple(idx)] < (1e-11 if regular else 1e-10)


# ----------------------------------------------------------------------------------------------
# Input AB
# ----------------------------------------------------------------------------------------------


def _meet(p1, c1, p2, c2):
    """Unit vectors X with X·p1 = c1, X·p2 = c2: (the pair, γ²); γ² < 0 when they do not meet.

    In the frame p1, t (p2's part normal to p1, of length s = |p1 × p2|), n = p1 × t:
    X = c1·p1 + u·t ± √(1 − c1² − u²)·n with u = (c2 − k·c1)/s, k = p1·p2, 1 − k = s²/(1 + k).
    Dividing by s once (not by 1 − k² = s²) keeps X good to ε/s where p1 nears p2 (B near D:
    the test's poses then agreed with the solver's only to 1.4e-10, their own constraints
    held to 2.5e-11). γ² is (1 − c1² − u²)/s², the squared multiple of p1 × p2 added.
    """
    w = np.cross(p1, p2)
    s = np.sqrt(w @ w)
    k = p1 @ p2
    t = np.cross(w, p1) / s
    n = np.cross(p1, t)
    u = ((c2 - c1) + c1 * (s * s) / (1.0 + k)) / s
    rest = 1.0 - c1 * c1 - u * u
    gamma2 = rest / (s * s)
    if gamma2 < 0:
        return [], gamma2
    base = c1 * p1 + u * t
    gam = np.sqrt(rest)
    return [base + gam * n, base - gam * n], gamma2


@settings(max_examples=60, deadline=None)
@given(st.lists(arc, min_size=9, max_size=9), angle, angle)
# A rhombus ABCD with B 0.2° from D: C where two near-concentric circles cross (see _meet).
@example([0.5, 0.5, 0.5, 0.5, 1.0, 1.0, 1.0, 1.0, 1.0], 1.0, 0.0078125)
def test_ab_configurations_match_a_closed_form_count(arcs, sigma, theta1):
    arcs[5] = sigma
    p = _arcs(arcs)
    _, d, g = _fixed(p)
    b = _b(p, theta1)
    expected = []
    assume(np.linalg.norm(np.cross(b, d)) > 1e-6)  # B on ±D: C on a whole circle, or nowhere
    cs, gam = _meet(b, np.cos(p["a3"]), d, np.cos(p["a4"]))
    assume(abs(gam) > 1e-6)
    for c in cs:
        e = _e(p, b, c)
        assume(np.linalg.norm(np.cross(e, g)) > 1e-6)
        fs, gam2 = _meet(e, np.cos(p["a7"]), g, np.cos(p["a8"]))
        assume(abs(gam2) > 1e-6)
        expected += [np.concatenate((b, c, e, f)) for f in fs]
    every = solve_all(SphericalStephenson3(*arcs), [theta1])
    assert every.driven == "AB" and every.count.shape == (1,)
    assert int(every.count[0]) == len(expected) <= SLOTS["AB"]
    found = np.concatenate([every.positions[k][0] for k in "BCEF"], -1)
    if expected:
        assert _set_gap(found, np.array(expected)) < 1e-10
    pos = dict(every.positions)
    assert np.all(_violation(p, pos)[every.valid] < TOL)
    # The signs are those of the positions.
    v = every.valid[0]
    bb, cc, ee, ff = (every.positions[k][0][v] for k in "BCEF")
    assert np.array_equal(every.assembly[0][v], np.sign(np.einsum("ki,ki->k", np.cross(bb, d), cc)))
    assert np.array_equal(
        every.assembly2[0][v], np.sign(np.einsum("ki,ki->k", np.cross(ee, g), ff))
    )


# B on D with BC = CD (an exact spherical kite ABCD at θ1 = 0): C is anywhere on its circle,
# and the two AB configurations given are two points of that continuum.
B_ON_D = (1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0), 0.0, 4.7106088300044544e-85
# The same, with the returned C where E·F − cos EF touches zero along C's circle (a double root).
B_ON_D_TANGENT = (
    (2.8788103052908447, 2.8788103052908447, 0.9178944000340368, 0.9178944000340368,
     0.8233080121070255, 0.25, 2.0958611933289655, 2.0958611933289655, 1.15594017822109),
    -2.6104094373251123e-204,
    -1.3662441876424376e-125,
)  # fmt: skip


@settings(max_examples=30, deadline=None)
@given(st.lists(arc, min_size=9, max_size=9), angle, angle)
@example(list(B_ON_D[0]), *B_ON_D[1:])
@example(list(B_ON_D_TANGENT[0]), *B_ON_D_TANGENT[1:])
def test_every_ab_configuration_is_found_again_driving_fg(arcs, sigma, theta1):
    arcs[5] = sigma
    p = _arcs(arcs)
    _, d, _ = _fixed(p)
    ab = solve_all(SphericalStephenson3(*arcs), [theta1])
    for k in range(int(ab.count[0])):
        b, c, e, f = (ab.positions[j][0, k] for j in "BCEF")
        det, margin = _conditioning(p, b, c, f)
        if det < NEAR_SINGULAR:
            continue
        # B at ±D: the input fixes no C when the four-bar's circles of C coincide, so the pose
        # is one point of a continuum, picked by rounding, and the FG problem may be tangent
        # there (B_ON_D_TANGENT: a double root, which splits off the real axis under rounding
        # and no solver can promise). Left out, as test_ab_configurations_match_a_closed_
        # form_count leaves B = ±D out; test_fg_finds_both_poses_with_b_on_d keeps the rest.
        if np.linalg.norm(np.cross(b, d)) < 1e-6:
            continue
        fg = solve_all(SphericalStephenson3(*arcs, input="FG"), [_theta6(p, f)])
        found = np.concatenate([fg.positions[j][0] for j in "BCEF"], -1)
        gap = np.abs(found - np.concatenate((b, c, e, f))).max(-1)
        assert np.nanmin(gap) < SAME
        slot = int(np.nanargmin(gap))
        assert fg.assembly[0, slot] == ab.assembly[0, k] or margin < NEAR_SINGULAR


def test_fg_finds_both_poses_with_b_on_d():
    """At B = D with BC = CD the first closure equation holds for every C on its circle, so at a
    root θ_B the solver takes θ_C from the second one: for the F of an AB configuration there,
    both poses with B on D are found (one of them was missed: every C root came from the first
    equation, indeterminate there). Checked against a scan of C along its circle."""
    arcs, sigma, theta1 = B_ON_D
    arcs = list(arcs)
    arcs[5] = sigma
    p = _arcs(arcs)
    _, d, _ = _fixed(p)
    ab = solve_all(SphericalStephenson3(*arcs), [theta1])
    b, f = ab.positions["B"][0, 0], ab.positions["F"][0, 0]
    assert np.linalg.norm(np.cross(b, d)) < 1e-15
    # C on the circle of arc a4 about D = B, where E·F = cos a7: bracketed on a fine scan.
    u = np.cross(d, [1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    w = np.cross(d, u)
    t = np.linspace(-np.pi, np.pi, 200001)
    c = np.cos(p["a4"]) * d + np.sin(p["a4"]) * (np.cos(t)[:, None] * u + np.sin(t)[:, None] * w)
    h = _e(p, np.broadcast_to(b, c.shape), c) @ f - np.cos(p["a7"])
    roots = c[np.flatnonzero(np.sign(h[1:]) != np.sign(h[:-1]))]
    assert len(roots) == 2
    fg = solve_all(SphericalStephenson3(*arcs, input="FG"), [_theta6(p, f)])
    v = fg.valid[0]
    on_d = np.linalg.norm(np.cross(fg.positions["B"][0][v], d), axis=-1) < 1e-9
    found = fg.positions["C"][0][v][on_d]
    gaps = np.abs(found[:, None, :] - roots[None, :, :]).max(-1)
    assert found.shape[0] == 2 and np.all(gaps.min(axis=0) < 1e-4)


def test_mirror_coupler_doubles_the_ab_count():
    m = SphericalStephenson3(*EXAMPLE)
    mirror = replace(m, sigma=-m.sigma)
    theta = np.radians(np.arange(0.0, 360.0, 2.0))
    own, other = solve_all(m, theta), solve_all(mirror, theta)
    assert own.count.max() == 4 and other.count.max() == 4
    assert (own.count + other.count).max() == 8
    # A mirror configuration is never one of the mechanism's: its E is off the coupler.
    p = _arcs(EXAMPLE)
    v = other.valid
    b, c, e = (other.positions[k][v] for k in "BCE")
    assert np.abs(e - _e(p, b, c)).max(-1).min() > 0.1


# ----------------------------------------------------------------------------------------------
# Edge cases, shapes and errors
# ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("driven", ["AB", "FG"])
def test_a_linkage_that_cannot_assemble_has_no_configuration(driven):
    short = SphericalStephenson3(*np.radians([90, 10, 20, 30, 30, 90, 40, 50, 40]), input=driven)
    every = solve_all(short, np.linspace(-np.pi, np.pi, 7))
    assert np.all(every.count == 0) and not every.valid.any()
    for v in (*every.positions.values(), every.residual, every.assembly, every.assembly2):
        assert np.isnan(v).all()


@pytest.mark.parametrize("driven", ["AB", "FG"])
def test_nan_exactly_where_no_configuration_in_a_batch(driven):
    arcs = np.stack([EXAMPLE, np.radians([90, 10, 20, 30, 30, 90, 40, 50, 40])], -1)
    m = SphericalStephenson3(*arcs, input=driven)
    theta = np.radians(np.arange(0.0, 360.0, 30.0))
    every = solve_all(m, theta)
    assert every.valid.shape == (2, 12, SLOTS[driven])
    assert every.positions["E"].shape == (2, 12, SLOTS[driven], 3)
    for v in every.positions.values():
        assert np.array_equal(np.isfinite(v).all(-1), every.valid)
    for v in (every.residual, every.assembly, every.assembly2, *every.residuals.values()):
        assert np.array_equal(np.isfinite(v), every.valid)
    assert np.array_equal(every.count, every.valid.sum(-1))
    # Valid slots come first.
    assert np.array_equal(every.valid, np.arange(SLOTS[driven]) < every.count[..., None])
    # The batch row equals the mechanism solved alone.
    alone = solve_all(SphericalStephenson3(*EXAMPLE, input=driven), theta)
    assert np.array_equal(alone.count, every.count[0])
    assert np.allclose(alone.positions["F"], every.positions["F"][0], atol=1e-15, equal_nan=True)


def test_inputs_with_their_own_batch_axis():
    m = SphericalStephenson3(*np.stack([EXAMPLE, EXAMPLE], -1), input="FG")
    theta = np.radians([[280.0, 100.0], [0.0, 175.0]])
    every = solve_all(m, theta)
    assert every.count.shape == (2, 2)
    one = solve_all(SphericalStephenson3(*EXAMPLE, input="FG"), theta[1])
    assert np.array_equal(every.count[1], one.count)
    assert np.allclose(
        paper_angles(m, every)["theta6"][every.valid],
        np.angle(np.exp(1j * np.broadcast_to(theta[..., None], every.valid.shape)[every.valid])),
        atol=1e-12,
    )


def test_bad_inputs_raise_clear_errors():
    m = SphericalStephenson3(*EXAMPLE, input="FG")
    with pytest.raises(InvalidInputs, match="1-D"):
        solve_all(m, 0.5)
    with pytest.raises(InvalidInputs, match="finite"):
        solve_all(m, [0.0, np.nan])
    with pytest.raises(InvalidInputs, match="broadcast"):
        solve_all(SphericalStephenson3(*np.stack([EXAMPLE] * 2, -1)), np.zeros((3, 4)))
    # Any family is answered: a spherical four-bar has its two assembly modes.
    from linkwright.mechanisms import SphericalFourBar

    assert solve_all(SphericalFourBar(*np.radians([40, 20, 45, 35])), [0.0]).count[0] == 2
    args = list(triad_of(m, 0.3))
    for index, value, words in [
        (0, np.eye(3) * 2, "orthonormal"),
        (0, np.zeros((3, 2)), "shape"),
        (1, 0.0, "arc"),
        (4, np.pi, "arc"),
        (6, np.nan, "finite"),
        (7, np.array([1.0, 1.0, 0.0]), "unit"),
        (8, np.array([0.5, 0.6, 0.7, 0.8]), "broadcast"),  # against arc_b's (2,) below
    ]:
        bad = list(args)
        if words == "broadcast":
            bad[1] = np.array([0.5, 0.6])
        bad[index] = value
        with pytest.raises(InvalidTriad, match=words):
            sphere_triad(*bad)
        with pytest.raises(InvalidTriad, match=words):
            sphere_triad_sweep(*bad)
    assert issubclass(InvalidTriad, ValueError) and issubclass(InvalidInputs, ValueError)
