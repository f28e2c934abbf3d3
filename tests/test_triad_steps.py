"""Triads as plan steps, and circuits followed by continuation, against independent methods.

- Every pose a triad step places is checked against a damped Newton solve of the three link
  equations from many starts (the plane: the body's position and angle; the sphere: its
  rotation), on thousands of random triads: the same count and the same poses to 1e-10.
- Derivatives against an 8th-order central difference of the positions.
- Paper 001's example driven at FG has 8, 4 and 6 configurations at −90°, 0° and 120°.
- The continuation tracer finds the same circuits and limits as the exact dyad tracer on random
  four-bars, and every triad circuit it traces is continuous: a Newton continuation in small
  substeps leads from each sample to the next.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from linkwright.engine import Crank, Fixed, Plan, Rigid, SphereCrank, evaluate
from linkwright.engine.continuation import every_circuit, every_configuration
from linkwright.engine.triad_steps import SphereTriad, Triad, triad_closure
from linkwright.geometry import plane, sphere
from linkwright.mechanisms import FourBar, circuits

TOL = 1e-10
# Triads whose poses come this close to a singular position are left out of the count
# comparison: there Newton converges only linearly, and two poses 1e-6 apart are one to it.
NEAR_SINGULAR = 1e-4

PLANE_PLAN = Plan(
    (
        Fixed("K1", "K1"),
        Fixed("K2", "K2"),
        Fixed("O", "O"),
        Crank("K3", "O", "arm"),
        Triad(("J1", "J2", "J3"), ("K1", "K2", "K3"), ("L1", "L2", "L3"), "side", "u", "v"),
    ),
    traced=("J3",),
)
PLANE_POINTS = frozenset({"K1", "K2", "O"})


def _rot(phi):
    c, s = np.cos(phi), np.sin(phi)
    return np.stack((np.stack((c, -s), -1), np.stack((s, c), -1)), -2)


def random_plane_triads(rng, n):
    """Triads with at least one real pose: lengths measured on a random pose."""
    k = rng.uniform(-3, 3, (n, 3, 2))
    side = rng.uniform(0.5, 3, n)
    u, v = rng.uniform(-2, 3, n), rng.uniform(-2, 2, n)
    body = np.stack((np.zeros((n, 2)), np.stack((side, 0 * side), -1), np.stack((u, v), -1)), 1)
    phi = rng.uniform(-np.pi, np.pi, n)
    origin = rng.uniform(-2, 2, (n, 2))
    joints = origin[:, None, :] + np.einsum("nij,nkj->nki", _rot(phi), body)
    lengths = plane.norm(joints - k)
    return k, lengths, side, u, v


def newton_plane(k, lengths, side, u, v, starts=90):
    """Every pose Newton finds from ``2·starts`` starts: J1 on its circle with the body turned
    to each of ``starts`` angles, both intersections; damped steps on (x, y, φ)."""
    n = len(k)
    body = np.stack((np.zeros((n, 2)), np.stack((side, 0 * side), -1), np.stack((u, v), -1)), 1)
    phi = np.broadcast_to(np.linspace(-np.pi, np.pi, starts, endpoint=False), (n, starts))
    c2 = np.einsum("nsij,nj->nsi", _rot(phi), body[:, 1])
    centre = k[:, None, 1] - c2  # J1 = J2 − R c2 lies on the circle of radius L2 about this
    seeds = []
    for sign in (1.0, -1.0):
        d = centre - k[:, None, 0]
        dd = np.maximum(plane.norm(d), 1e-12)
        a = (lengths[:, None, 0] ** 2 - lengths[:, None, 1] ** 2 + dd**2) / (2 * dd)
        h = np.sqrt(np.clip(lengths[:, None, 0] ** 2 - a**2, 0, None))
        p = k[:, None, 0] + (a[..., None] * d + sign * h[..., None] * plane.perp(d)) / dd[..., None]
        seeds.append(np.concatenate((p, phi[..., None]), -1))
    q = np.concatenate(seeds, axis=1)  # (n, 2·starts, 3)
    size = np.maximum.reduce([side, np.hypot(u, v), lengths.max(1)])[:, None]
    kk, ll, bb = k[:, None], lengths[:, None], body[:, None]
    for it in range(90):
        r = _rot(q[..., 2])
        rc = np.einsum("nsij,nskj->nski", r, np.broadcast_to(bb, q.shape[:2] + (3, 2)))
        j = q[..., None, :2] + rc
        e = j - kk
        f = plane.dot(e, e) - ll**2
        jac = np.concatenate((2 * e, 2 * plane.dot(e, plane.perp(rc))[..., None]), -1)
        with np.errstate(all="ignore"):
            step = np.linalg.solve(jac, -f[..., None])[..., 0]
        step = np.nan_to_num(step)
        # Damped: no step longer than a tenth of the triad's size (or 0.3 rad).
        scale = np.maximum(plane.norm(step[..., :2]) / (0.1 * size), np.abs(step[..., 2]) / 0.3)
        # The last steps are undamped: quadratic convergence to rounding.
        q = q + step / (np.maximum(scale, 1.0)[..., None] if it < 80 else 1.0)
    r = _rot(q[..., 2])
    j = q[..., None, :2] + np.einsum(
        "nsij,nskj->nski", r, np.broadcast_to(bb, q.shape[:2] + (3, 2))
    )
    err = np.max(np.abs(plane.norm(j - kk) - ll), -1) / size
    return j, err


def _distinct(joints, err, size, tol=1e-7):
    """Distinct converged poses of one triad, each from the start that converged best (some
    starts wander before they converge, and stop a little short of rounding)."""
    found = []
    best = np.argsort(err)
    for pose in joints[best][err[best] < TOL]:
        if all(np.max(np.abs(pose - f)) > tol * size for f in found):
            found.append(pose)
    return found


def _step_poses(plan, params, points, max_poses, theta=0.0):
    out = []
    for slot in range(max_poses):
        m = evaluate(plan, {**params, "pose": np.float64(slot)}, [theta], points=points, order=0)
        out.append(
            (m.valid[..., 0], np.stack([m.positions[j][..., 0, :] for j in ("J1", "J2", "J3")], -2))
        )
    return out


def test_plane_triad_poses_match_newton_from_many_starts():
    rng = np.random.default_rng(20261127)
    n = 1200
    k, lengths, side, u, v = random_plane_triads(rng, n)
    params = {
        "K1": k[:, 0],
        "K2": k[:, 1],
        "O": k[:, 2],
        "arm": np.zeros(n) + 1e-300,
        "L1": lengths[:, 0],
        "L2": lengths[:, 1],
        "L3": lengths[:, 2],
        "side": side,
        "u": u,
        "v": v,
    }
    # The crank of length ~0 keeps K3 on O at θ = 0: a fixed third anchor.
    params["O"] = k[:, 2] - np.array([1e-300, 0.0])
    slots = _step_poses(PLANE_PLAN, params, PLANE_POINTS, 6)
    newton, ok = newton_plane(k, lengths, side, u, v)
    size = np.maximum.reduce([side, np.hypot(u, v), lengths.max(1)])
    compared = 0
    for i in range(n):
        mine = [pose[i] for valid, pose in slots if valid[i]]
        # Every placed pose holds its links (relative to the size).
        for pose in mine:
            assert np.max(np.abs(plane.norm(pose - k[i]) - lengths[i])) <= TOL * size[i]
        closure = triad_closure(np.array(mine), k[i], lengths[i], "plane") if mine else []
        if len(mine) and np.min(np.abs(closure)) < NEAR_SINGULAR:
            continue
        theirs = _distinct(newton[i], ok[i], size[i])
        assert len(theirs) == len(mine), (i, len(theirs), len(mine))
        for pose in theirs:
            gap = min(np.max(np.abs(pose - p)) for p in mine)
            assert gap <= TOL * size[i]
        compared += 1
    assert compared > 0.8 * n


def random_sphere_triads(rng, n):
    anchors = sphere.unit(rng.normal(size=(n, 3, 3)))
    side = rng.uniform(0.3, 2.5, n)
    arc, angle = rng.uniform(0.3, 2.5, n), rng.uniform(-np.pi, np.pi, n)
    j1 = sphere.unit(rng.normal(size=(n, 3)))
    j2 = sphere.point_at(j1, sphere.unit(rng.normal(size=(n, 3))), side, 0.0)
    j3 = sphere.point_at(j1, j2, arc, angle)
    joints = np.stack((j1, j2, j3), 1)
    lengths = sphere.arc(joints, anchors)
    return anchors, lengths, side, arc, angle, joints


def newton_sphere(anchors, lengths, side, arc, angle, starts=400, seed=1):
    """Every pose Newton finds from random body rotations: δ·(J_k × K_k) = cos L_k − J_k·K_k."""
    rng = np.random.default_rng(seed)
    n = len(anchors)
    e1, e2 = np.array([1.0, 0, 0]), np.array([0.0, 1, 0])
    body = np.stack(
        np.broadcast_arrays(
            np.broadcast_to(e1, (n, 3)),
            sphere.point_at(e1, e2, side, 0.0),
            sphere.point_at(e1, e2, arc, angle),
        ),
        1,
    )
    q = sphere.unit(rng.normal(size=(n, starts, 4)))  # unit quaternions
    kk, ll = anchors[:, None], lengths[:, None]

    def rotate(quat, vec):
        w, xyz = quat[..., :1, None][..., 0, :], quat[..., 1:]
        t = 2 * np.cross(xyz[..., None, :], vec)
        return vec + w[..., None] * t + np.cross(xyz[..., None, :], t)

    for it in range(70):
        j = rotate(q, body[:, None])
        f = np.cos(ll) - sphere.dot(j, kk)
        rows = sphere.cross(j, kk)
        with np.errstate(all="ignore"):
            delta = np.nan_to_num(np.linalg.solve(rows, f[..., None])[..., 0])
        norm = np.linalg.norm(delta, axis=-1, keepdims=True)
        delta = delta / (np.maximum(norm / 0.3, 1.0) if it < 60 else 1.0)
        half = 0.5 * np.linalg.norm(delta, axis=-1, keepdims=True)
        axis = np.where(half > 0, delta / np.maximum(2 * half, 1e-300), 0.0)
        dq = np.concatenate((np.cos(half), np.sin(half) * axis), -1)
        w1, v1 = dq[..., :1], dq[..., 1:]
        w2, v2 = q[..., :1], q[..., 1:]
        q = np.concatenate(
            (w1 * w2 - np.sum(v1 * v2, -1, keepdims=True), w1 * v2 + w2 * v1 + np.cross(v1, v2)), -1
        )
        q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    j = rotate(q, body[:, None])
    err = np.max(np.abs(sphere.arc(j, kk) - ll), -1)
    return j, err


SPHERE_PLAN = Plan(
    (
        Fixed("K1", "K1"),
        Fixed("K2", "K2"),
        Fixed("K3", "K3"),
        SphereTriad(
            ("J1", "J2", "J3"), ("K1", "K2", "K3"), ("L1", "L2", "L3"), "side", "arc", "angle"
        ),
    ),
    traced=("J3",),
)


def test_sphere_triad_poses_match_newton_from_many_starts():
    rng = np.random.default_rng(112726)
    n = 800
    anchors, lengths, side, arc, angle, _ = random_sphere_triads(rng, n)
    params = {
        "K1": anchors[:, 0],
        "K2": anchors[:, 1],
        "K3": anchors[:, 2],
        "L1": lengths[:, 0],
        "L2": lengths[:, 1],
        "L3": lengths[:, 2],
        "side": side,
        "arc": arc,
        "angle": angle,
    }
    slots = _step_poses(SPHERE_PLAN, params, frozenset({"K1", "K2", "K3"}), 8)
    newton, ok = newton_sphere(anchors, lengths, side, arc, angle)
    compared = 0
    for i in range(n):
        mine = [pose[i] for valid, pose in slots if valid[i]]
        for pose in mine:
            assert np.max(np.abs(sphere.arc(pose, anchors[i]) - lengths[i])) <= TOL
        closure = triad_closure(np.array(mine), anchors[i], lengths[i], "sphere") if mine else []
        if len(mine) and np.min(np.abs(closure)) < NEAR_SINGULAR:
            continue
        theirs = _distinct(newton[i], ok[i], 1.0)
        assert len(theirs) == len(mine), (i, len(theirs), len(mine))
        for pose in theirs:
            assert min(np.max(np.abs(pose - p)) for p in mine) <= TOL
        compared += 1
    assert compared > 0.7 * n


# ------------------------------------------------------------------------------------------
# Derivatives
# ------------------------------------------------------------------------------------------

STEPHENSON3_OUTPUT = Plan(
    (
        Fixed("A0", "A0"),
        Fixed("B0", "B0"),
        Fixed("D0", "D0"),
        Crank("D", "D0", "link2"),
        Triad(
            ("A", "B", "C"), ("A0", "B0", "D"), ("crank", "rocker", "link1"), "coupler", "u1", "v1"
        ),
        Rigid("P", "C", "D", "u", "v"),
    ),
    traced=("P",),
)
PAPER001_FG = Plan(
    (
        Fixed("A", "A"),
        Fixed("D", "D"),
        Fixed("G", "G"),
        SphereCrank("F", "G", "a8", ref="away"),
        SphereTriad(("C", "B", "E"), ("D", "A", "F"), ("a4", "a2", "a7"), "a3", "a6", "turn"),
    ),
    traced=("E",),
)
# 8th-order central difference: coefficients of f(±kh), k = 1..4.
D1 = np.array([4 / 5, -1 / 5, 4 / 105, -1 / 280])
D2 = np.array([8 / 5, -1 / 5, 8 / 315, -1 / 560])
D2_CENTRE = -205 / 72


def _central(plan, params, points, theta, h, slot):
    """8th-order central differences of every joint of the configuration in pose ``slot`` at
    ``theta``, following that pose by continuity (the nearest pose at each offset: a pose's
    index can change where another pose's angle wraps)."""
    ks = np.arange(1, 5)
    around = np.concatenate((theta - ks[::-1] * h, [theta], theta + ks * h))
    _, m = every_configuration(plan, params, around, points=points, order=0)
    names = sorted(m.positions)
    x = np.stack([m.positions[n] for n in names], -2)  # (slots, 9, joints, d)
    centre = x[slot, 4]
    dist = np.where(
        m.valid, np.max(np.abs(np.nan_to_num(x, nan=np.inf) - centre), axis=(-1, -2)), np.inf
    )
    pick = np.argmin(dist, axis=0)
    path = x[pick, np.arange(9)]
    ok = bool(np.all(np.isfinite(dist[pick, np.arange(9)])))
    out = {}
    for i, name in enumerate(names):
        pos = path[:, i, :]
        minus, mid, plus = pos[:4][::-1], pos[4], pos[5:]
        d1 = np.tensordot(D1, plus - minus, axes=(0, 0)) / h
        d2 = (np.tensordot(D2, plus + minus, axes=(0, 0)) + D2_CENTRE * mid) / h**2
        out[name] = (d1, d2, ok)
    return out


def paper001(arcs_deg):
    from linkwright.mechanisms import SphericalStephenson3

    m = SphericalStephenson3(*np.radians(arcs_deg), input="FG")
    return {k: np.asarray(v, float) for k, v in m.params().items() if k != "input"}


PAPER001_ARCS = (71.1, 64.1, 68.6, 65.7, 69.0, 102.0, 74.1, 52.6, 19.7)
PAPER001_POINTS = frozenset({"A", "D", "G", "away"})


@pytest.mark.parametrize("theta_deg", [-90.0, 0.0, 120.0, 200.0])
def test_sphere_triad_derivatives_match_central_difference(theta_deg):
    params = paper001(PAPER001_ARCS)
    theta = np.radians(theta_deg)
    for slot in range(8):
        p = {**params, "pose": np.float64(slot)}
        m = evaluate(PAPER001_FG, p, [theta], points=PAPER001_POINTS, order=2)
        if not m.regular[0]:
            continue
        fd = _central(PAPER001_FG, params, PAPER001_POINTS, theta, 1e-3, slot)
        for joint in ("B", "C", "E", "F"):
            d1, d2, same = fd[joint]
            assert same
            assert np.max(np.abs(m.velocities[joint][0] - d1)) < 1e-8
            assert np.max(np.abs(m.accelerations[joint][0] - d2)) < 1e-6


@settings(max_examples=25)
@given(st.integers(0, 2**32 - 1))
def test_plane_triad_derivatives_match_central_difference(seed):
    rng = np.random.default_rng(seed)
    k, lengths, side, u, v = random_plane_triads(rng, 1)
    params = {
        "A0": k[0, 0],
        "B0": k[0, 1],
        "D0": k[0, 2] - [0.7, 0.0],
        "link2": 0.7,
        "crank": lengths[0, 0],
        "rocker": lengths[0, 1],
        "link1": lengths[0, 2],
        "coupler": side[0],
        "u1": u[0],
        "v1": v[0],
        "u": 0.4,
        "v": -0.3,
    }
    points = frozenset({"A0", "B0", "D0"})
    for slot in range(6):
        p = {**params, "pose": np.float64(slot)}
        m = evaluate(STEPHENSON3_OUTPUT, p, [0.0], points=points, order=2)
        if not m.regular[0]:
            continue
        closure = np.abs(m.margins["A"][0])
        if closure < 0.05:  # near a limit: tests/test_singular_*.py's business, not a difference's
            continue
        # The input is within about closure² of a limit, where the pose turns back: the
        # differences stay well inside that.
        h = min(1e-3, 0.02 * closure**2)
        fd = _central(STEPHENSON3_OUTPUT, params, points, 0.0, h, slot)
        size = float(np.max(lengths) + side[0] + np.hypot(u[0], v[0]))
        for joint in ("A", "B", "C", "P"):
            d1, d2, same = fd[joint]
            assert same
            speed = np.max(np.abs(m.velocities[joint][0])) + size
            assert np.max(np.abs(m.velocities[joint][0] - d1)) < 1e-6 * speed / closure**2
            accel = np.max(np.abs(m.accelerations[joint][0])) + size
            assert np.max(np.abs(m.accelerations[joint][0] - d2)) < 1e-4 * accel / closure**4


def test_paper001_fg_configuration_counts():
    """Paper 001's example driven at FG: 8, 4 and 6 real configurations at −90°, 0°, 120°."""
    params = paper001(PAPER001_ARCS)
    combos, motion = every_configuration(
        PAPER001_FG, params, np.radians([-90.0, 0.0, 120.0]), points=PAPER001_POINTS
    )
    assert len(combos) == 8
    assert motion.valid.sum(axis=0).tolist() == [8, 4, 6]


# ------------------------------------------------------------------------------------------
# Circuits by continuation
# ------------------------------------------------------------------------------------------


def test_continuation_agrees_with_the_dyad_tracer_on_random_fourbars():
    rng = np.random.default_rng(7)
    for _ in range(25):
        f, a, b, c = rng.uniform(0.5, 5, 4)
        fb = FourBar(A0=[0, 0], B0=[f, 0], crank=a, coupler=b, rocker=c)
        arcs, exact = circuits(fb, 64)
        other = circuits(fb.with_assembly(-1), 64)[1]
        found = every_circuit(fb.plan, fb.params(), 64, points=fb.points)
        expected = len(exact) + (len(other) if bool(arcs.full) else 0)
        assert len(found) == expected
        limits = np.sort(
            np.concatenate([arcs.lo[np.isfinite(arcs.lo)], arcs.hi[np.isfinite(arcs.hi)]])
        )
        mine = np.sort([np.angle(np.exp(1j * l.input)) for c in found for l in c.limits])
        wrapped = np.sort(np.angle(np.exp(1j * limits)))
        assert len(mine) == len(wrapped)
        assert np.allclose(mine, wrapped, atol=1e-9)


def _continues(plan, params, points, circuit, joints, substeps=16):
    """A continuation from each sample, in substeps of the input (the nearest configuration at
    each), lands on the next sample's configuration: no step crosses to another branch. A step
    that leaves a limit position is checked backwards, into the limit, where both branches meet.
    """
    motion = circuit.motion
    limits = np.array([lim.input for lim in circuit.limits])

    def at_limit(theta):
        gap = np.angle(np.exp(1j * (limits - theta))) if len(limits) else np.array([np.inf])
        return bool(np.min(np.abs(gap)) < 1e-9)

    def stack(k):
        return np.concatenate([motion.positions[j][k] for j in joints])

    for k in range(motion.shape[-1] - 1):
        start, end = (k + 1, k) if at_limit(motion.input[k]) else (k, k + 1)
        a, b = motion.input[start], motion.input[end]
        if a == b:
            continue
        here = stack(start)
        for t in np.linspace(a, b, substeps + 1)[1:]:
            _, m = every_configuration(plan, params, [t], points=points, order=0)
            cand = np.concatenate([m.positions[j][:, 0] for j in joints], -1)
            dist = np.where(m.valid[:, 0], np.max(np.abs(cand - here), -1), np.inf)
            here = cand[np.argmin(dist)]
        there = stack(end)
        # Into a limit position the two merging configurations are a hair apart, and either
        # is the continuation: the landing may be the nearest other configuration, no farther.
        # (The nearest other: the second nearest, since ``there`` is itself one of them, to
        # rounding.)
        to_there = np.sort(np.where(m.valid[:, 0], np.max(np.abs(cand - there), -1), np.inf))
        reach = max(1e-7, float(to_there[1]) if len(to_there) > 1 else np.inf)
        reach = reach if at_limit(b) else 1e-7
        assert np.max(np.abs(here - there)) <= reach * (1 + 1e-9), (k, np.degrees([a, b]))


def _passes(inputs, theta):
    """How often a closed circuit's input passes ``theta`` (modulo a turn)."""
    x = np.unwrap(np.append(inputs, inputs[0]))
    if abs(x[-1] - x[0]) > np.pi:  # a full circuit: the last step closes a whole turn on
        x[-1] = x[0] + np.sign(x[-2] - x[0]) * 2 * np.pi
    lo, hi = np.floor((x.min() - theta) / (2 * np.pi)), np.ceil((x.max() - theta) / (2 * np.pi))
    count = 0
    for k in np.arange(lo, hi + 1):
        t = theta + 2 * np.pi * k
        count += int(np.sum((x[:-1] - t) * (x[1:] - t) < 0))
    return count


def test_paper001_fg_circuits_close_and_continue():
    params = paper001(PAPER001_ARCS)
    found = every_circuit(PAPER001_FG, params, 120, points=PAPER001_POINTS)
    # Every configuration at a probe input lies on exactly one circuit: the circuits together
    # pass each input as often as it has configurations.
    probe = np.radians([-90.0, 0.0, 120.0])
    for theta, count in zip(probe, [8, 4, 6], strict=True):
        assert sum(_passes(c.motion.input, theta) for c in found) == count
    for c in found:
        assert c.motion.valid.all()
        _continues(PAPER001_FG, params, PAPER001_POINTS, c, ("B", "C", "E"))
