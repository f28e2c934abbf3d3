"""The triad (Assur group of class III) and the all-configurations solver of the Stephenson III.

Every check recomputes what it tests from the geometry itself: link lengths and the body's shape
from the returned joint positions, poses built first and then looked for, velocities from
central differences of poses followed along a smooth motion of the anchors. The polynomial
solver (:func:`triad_poses`) is compared with the sweep (:func:`triad_poses_sweep`), which shares
no step with it but the final check of the lengths.

Random triads: link lengths log-uniform over a 30:1 range, anchors and body joints uniform in a
square, all scaled by 10^U(−3, 3) and moved by up to 100 times their own size; half are built
around a known pose (so that poses exist and can be looked for), with the body angle of that
pose exactly 0, ±π/2 or π in a share of them (the half-angle parametrisation's classic blind
spot). Tolerances are relative to the triad's size (its longest link, body side or anchor
distance).

Where a pose is close to a singular position (the three links' lines nearly concurrent or
parallel, relative Jacobian determinant below 1e-4), the number of real poses itself is
ill-conditioned: a rounding error can make a double root two real poses or none. Those triads
are left out of the method-against-method comparisons (and counted, so that the exclusion
cannot grow unnoticed); every pose of every triad is still checked against its constraints.
The Hypothesis comparison also skips the sweep's own blind spots (named where it does), which
Hypothesis's exact small numbers hit and random batches practically never do.
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from linkwright.engine.triad import (
    MAX_POSES,
    sweep_roots,
    triad_poses,
    triad_poses_sweep,
    triad_rates,
)
from linkwright.mechanisms import solve
from linkwright.mechanisms.allconfigs import solve_all
from linkwright.mechanisms.sixbar import Stephenson3

JOINTS = Stephenson3.reported_joints

RESIDUAL_TOL = 1e-10
SAME_POSE_TOL = 1e-10
# Below this relative determinant of the 3×3 constraint Jacobian a pose is "near singular":
# roots of the polynomial then cluster, and their number is at the mercy of rounding.
NEAR_SINGULAR = 1e-4

# ----------------------------------------------------------------------------------------------
# Independent geometry
# ----------------------------------------------------------------------------------------------


def _norm(a):
    return np.hypot(a[..., 0], a[..., 1])


def _cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _rotation(phi):
    c, s = np.cos(phi), np.sin(phi)
    return np.stack((np.stack((c, -s), -1), np.stack((s, c), -1)), -2)


def _size(anchors, lengths, body):
    pairs = ((0, 1), (0, 2), (1, 2))
    parts = [np.max(lengths, axis=-1)]
    parts += [_norm(body[..., i, :] - body[..., j, :]) for i, j in pairs]
    parts += [_norm(anchors[..., i, :] - anchors[..., j, :]) for i, j in pairs]
    return np.maximum.reduce(parts)


def constraint_error(anchors, lengths, body, joints):
    """Largest violation of the triad's constraints by ``joints`` (..., m, 3, 2), relative.

    The links: |J_k − K_k| = L_k. The body: its three sides keep their lengths, and its
    orientation (a mirror image of the body satisfies every length and is no pose).
    """
    size = _size(anchors, lengths, body)[..., None]
    links = np.abs(_norm(joints - anchors[..., None, :, :]) - lengths[..., None, :]).max(-1)
    pairs = ((0, 1), (0, 2), (1, 2))
    sides = [
        np.abs(
            _norm(joints[..., i, :] - joints[..., j, :])
            - _norm(body[..., None, i, :] - body[..., None, j, :])
        )
        for i, j in pairs
    ]
    area_world = _cross(
        joints[..., 1, :] - joints[..., 0, :], joints[..., 2, :] - joints[..., 0, :]
    )
    area_body = _cross(body[..., 1, :] - body[..., 0, :], body[..., 2, :] - body[..., 0, :])[
        ..., None
    ]
    # A signed area that changes sign is a mirrored body; compare areas in units of size².
    mirror = np.abs(area_world - area_body) / size
    return np.maximum.reduce([links, *sides, mirror]) / size


def jacobian_det(anchors, lengths, joints):
    """Relative determinant of the constraint Jacobian at each pose (``np.linalg.det``)."""
    e = (joints - anchors[..., None, :, :]) / lengths[..., None, :, None]
    rho = joints - joints[..., :1, :]
    arm = np.maximum(_norm(rho).max(-1), 1e-300)[..., None]
    jac = np.concatenate((e, (_cross(rho, e) / arm)[..., None]), axis=-1)
    real = np.isfinite(jac).all(axis=(-1, -2))
    det = np.abs(np.linalg.det(np.where(real[..., None, None], jac, 0.0)))
    return np.where(real, det, np.nan)  # NaN for the padding


def random_triads(rng, n, *, around_pose=0.5, scales=(-3.0, 3.0), trans=100.0):
    """``n`` random triads (anchors, lengths, body), a share built around a known pose.

    Returns the triads and the known pose's joints (NaN for triads built at random).
    """
    scale = 10.0 ** rng.uniform(*scales, n)
    body = rng.uniform(-1.0, 1.0, (n, 3, 2)) + rng.uniform(-3.0, 3.0, (n, 1, 2))
    anchors = rng.uniform(-1.0, 1.0, (n, 3, 2))
    lengths = np.exp(rng.uniform(np.log(0.05), np.log(1.5), (n, 3)))
    # Around a pose: the body placed at a random (or special) angle, anchors at random, and the
    # lengths measured.
    phi = rng.uniform(-np.pi, np.pi, n)
    special = rng.random(n) < 0.3
    phi[special] = rng.choice([0.0, np.pi / 2, -np.pi / 2, np.pi], special.sum())
    origin = rng.uniform(-0.5, 0.5, (n, 1, 2))
    pose = origin + np.einsum("nij,nkj->nki", _rotation(phi), body)
    built = rng.random(n) < around_pose
    lengths = np.where(built[:, None], _norm(pose - anchors), lengths)
    pose = np.where(built[:, None, None], pose, np.nan)
    shift = rng.uniform(-trans, trans, (n, 1, 2))
    place = lambda p: (p + shift) * scale[:, None, None]  # noqa: E731
    return place(anchors), lengths * scale[:, None], body * scale[:, None, None], place(pose)


def _contains(poses_joints, pose, size, tol):
    """Whether ``pose`` (..., 3, 2) is among ``poses_joints`` (..., 6, 3, 2), relatively."""
    gap = np.abs(poses_joints - pose[..., None, :, :]).max(axis=(-1, -2)) / size[..., None]
    return (np.where(np.isnan(gap), np.inf, gap) < tol).any(axis=-1)


def _pose_gap(p, q, size):
    """Largest distance from a pose of either result to the nearest pose of the other, relative.

    Poses are matched as sets: two poses at one body angle (where the linear equations for J1
    are singular) may be listed in either order. 0 where neither has a pose; inf where only one
    has.
    """
    gap = np.abs(p.joints[..., :, None, :, :] - q.joints[..., None, :, :, :]).max(axis=(-1, -2))
    gap = np.where(np.isnan(gap), np.inf, gap)
    p_to_q = np.where(p.valid, gap.min(axis=-1), 0.0).max(axis=-1)
    q_to_p = np.where(q.valid, gap.min(axis=-2), 0.0).max(axis=-1)
    return np.maximum(p_to_q, q_to_p) / size


def sweep_reference(anchors, lengths, body, poly):
    """The sweep's poses, refined (grid 16384) for triads where the grid of 512 disagrees.

    The coarse grid misses roots closer than about a step (three within two steps, or a pair
    next to an edge of the assembled range); the fine one is the same method, run only where
    needed to keep the test fast.
    """
    ref = triad_poses_sweep(anchors, lengths, body, grid=512)
    redo = np.flatnonzero(ref.count != poly.count)
    if redo.size:
        fine = triad_poses_sweep(anchors[redo], lengths[redo], body[redo], grid=16384)
        ref = dataclasses.replace(
            ref,
            joints=_put(ref.joints, redo, fine.joints),
            angle=_put(ref.angle, redo, fine.angle),
            count=_put(ref.count, redo, fine.count),
            residual=_put(ref.residual, redo, fine.residual),
        )
    return ref


def _put(a, idx, values):
    a = a.copy()
    a[idx] = values
    return a


# ----------------------------------------------------------------------------------------------
# The polynomial solver on its own
# ----------------------------------------------------------------------------------------------


def test_every_pose_satisfies_the_constraints_on_random_batches():
    rng = np.random.default_rng(20261122)
    anchors, lengths, body, _ = random_triads(rng, 4000)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        poses = triad_poses(anchors, lengths, body)
    assert poses.joints.shape == (4000, MAX_POSES, 3, 2)
    valid = poses.valid
    np.testing.assert_array_equal(valid, np.arange(MAX_POSES) < poses.count[:, None])
    assert set(np.unique(poses.count)) <= {0, 2, 4, 6}  # complex roots come in pairs
    assert (poses.count == 6).any() and (poses.count == 0).any()
    # NaN exactly in the padding, finite everywhere else.
    assert np.isfinite(poses.joints[valid]).all() and np.isnan(poses.joints[~valid]).all()
    assert np.isfinite(poses.angle[valid]).all() and np.isnan(poses.angle[~valid]).all()
    assert np.isnan(poses.residual[~valid]).all()
    err = constraint_error(anchors, lengths, body, poses.joints)
    assert np.max(err[valid]) < RESIDUAL_TOL
    # The reported residual is the links' error, recomputed.
    size = _size(anchors, lengths, body)[:, None]
    links = np.abs(_norm(poses.joints - anchors[:, None]) - lengths[:, None]).max(-1) / size
    np.testing.assert_allclose(poses.residual[valid], links[valid], rtol=0, atol=1e-15)
    # Sorted by the body angle, which is the angle turning the body's side J1J2 into the world's.
    angle = np.where(valid, poses.angle, 10.0)  # the padding after every angle in (−π, π]
    assert (np.diff(angle, axis=-1)[valid[:, 1:]] > 0).all()
    side_body = body[:, None, 1] - body[:, None, 0]
    side_world = poses.joints[..., 1, :] - poses.joints[..., 0, :]
    turn = np.arctan2(_cross(side_body, side_world), (side_body * side_world).sum(-1))
    diff = np.angle(np.exp(1j * (turn - poses.angle)))
    assert np.max(np.abs(diff[valid])) < 1e-9


def test_a_pose_built_first_is_found_even_at_phi_pi():
    rng = np.random.default_rng(7)
    anchors, lengths, body, pose = random_triads(rng, 3000, around_pose=1.0)
    poses = triad_poses(anchors, lengths, body)
    size = _size(anchors, lengths, body)
    regular = jacobian_det(anchors, lengths, pose[:, None])[:, 0] > NEAR_SINGULAR
    found = _contains(poses.joints, pose, size, 1e-9)
    assert regular.mean() > 0.99
    assert found[regular].all()
    # The body angles 0, ±π/2 and π were all drawn (and so found), π included.
    phi = np.arctan2(
        _cross(body[:, 1] - body[:, 0], pose[:, 1] - pose[:, 0]),
        ((body[:, 1] - body[:, 0]) * (pose[:, 1] - pose[:, 0])).sum(-1),
    )
    assert (found & regular & (np.abs(np.abs(phi) - np.pi) < 1e-12)).sum() > 100


@pytest.mark.parametrize(
    "coincide",
    ["anchors K2 = K3", "anchors K1 = K2", "collinear body"],
)
def test_special_shapes_where_the_polynomial_loses_degree(coincide):
    """Coincident anchors drop the degree (the leading coefficient is ∏|K_i − K_j|·∏|c_i − c_j|)."""
    rng = np.random.default_rng(11)
    anchors, lengths, body, pose = random_triads(rng, 600, around_pose=1.0, trans=1.0)
    if coincide == "collinear body":
        t = rng.uniform(-2.0, 2.0, (600, 1))
        body[:, 2] = body[:, 0] + t * (body[:, 1] - body[:, 0])
        pose[:, 2] = pose[:, 0] + t * (pose[:, 1] - pose[:, 0])
    else:
        i, j = (1, 2) if coincide == "anchors K2 = K3" else (0, 1)
        anchors[:, j] = anchors[:, i]
    lengths = _norm(pose - anchors)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        poses = triad_poses(anchors, lengths, body)
    size = _size(anchors, lengths, body)
    assert np.max(constraint_error(anchors, lengths, body, poses.joints)[poses.valid]) < 1e-10
    regular = jacobian_det(anchors, lengths, pose[:, None])[:, 0] > NEAR_SINGULAR
    assert _contains(poses.joints, pose, size, 1e-8)[regular].all()
    if coincide != "collinear body":
        assert poses.count.max() <= 4  # degree 4: two of the six roots are at z = 0 and ∞


def test_six_real_poses():
    """Found by searching integer triads; each pose is checked here from the lengths alone."""
    anchors = np.array([[0.0, 0.0], [1.0, -10.0], [9.0, 7.0]])
    lengths = np.array([8.0, 13.0, 14.0])
    body = np.array([[0.0, 0.0], [-6.0, 5.0], [7.0, 1.0]])
    poses = triad_poses(anchors, lengths, body)
    assert poses.count == 6
    assert constraint_error(anchors, lengths, body, poses.joints).max() < 1e-15
    # Six distinct, well separated and regular poses: the count is not a rounding accident.
    assert np.diff(poses.angle).min() > 0.05
    assert jacobian_det(anchors, lengths, poses.joints).min() > 0.1
    sweep = triad_poses_sweep(anchors, lengths, body)
    assert sweep.count == 6
    assert np.abs(sweep.joints - poses.joints).max() < 1e-12 * 14


def test_no_pose_when_the_anchors_are_too_far_apart():
    body = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    anchors = np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 10.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        poses = triad_poses(anchors, [1.0, 1.0, 1.0], body)
        sweep = triad_poses_sweep(anchors, [1.0, 1.0, 1.0], body)
    assert poses.count == 0 and sweep.count == 0
    assert np.isnan(poses.joints).all() and np.isnan(poses.angle).all()
    assert np.isnan(poses.residual).all() and np.isnan(sweep.joints).all()


def test_shapes_broadcasting_and_non_finite_input():
    rng = np.random.default_rng(3)
    anchors, lengths, body, _ = random_triads(rng, 20, trans=1.0, scales=(0.0, 0.0))
    grid = triad_poses(anchors.reshape(4, 5, 3, 2), lengths.reshape(4, 5, 3), body[0])
    flat = triad_poses(anchors, lengths, np.broadcast_to(body[0], (20, 3, 2)))
    assert grid.joints.shape == (4, 5, 6, 3, 2) and grid.count.shape == (4, 5)
    np.testing.assert_array_equal(grid.count.ravel(), flat.count)
    np.testing.assert_allclose(grid.joints.reshape(20, 6, 3, 2), flat.joints, rtol=0, atol=1e-12)
    assert triad_poses(np.zeros((0, 3, 2)), np.ones((0, 3)), body[0]).joints.shape == (0, 6, 3, 2)
    single = triad_poses(anchors[0], lengths[0], body[0])
    assert single.joints.shape == (6, 3, 2) and single.count.shape == ()
    bad = anchors[:3].copy()
    bad[1, 2, 0] = np.nan
    bad_lengths = lengths[:3].copy()
    bad_lengths[2, 0] = np.inf
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = triad_poses(bad, bad_lengths, body[:3])
    np.testing.assert_array_equal(out.count[1:], [0, 0])
    assert np.isnan(out.joints[1:]).all()
    assert out.count[0] == flat.count[0]
    with pytest.raises(ValueError, match="shape"):
        triad_poses(np.zeros((3, 3)), [1.0, 1.0, 1.0], body[0])


# ----------------------------------------------------------------------------------------------
# Polynomial against sweep
# ----------------------------------------------------------------------------------------------


def test_polynomial_and_sweep_agree_on_random_batches():
    rng = np.random.default_rng(2026)
    anchors, lengths, body, _ = random_triads(rng, 2000)
    poly = triad_poses(anchors, lengths, body)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sweep = sweep_reference(anchors, lengths, body, poly)
    size = _size(anchors, lengths, body)
    det = np.concatenate(
        (jacobian_det(anchors, lengths, poly.joints), jacobian_det(anchors, lengths, sweep.joints)),
        axis=-1,
    )
    near = (np.where(np.isnan(det), np.inf, det) < NEAR_SINGULAR).any(axis=-1)
    assert near.mean() < 0.005
    ok = ~near
    np.testing.assert_array_equal(poly.count[ok], sweep.count[ok])
    assert np.max(_pose_gap(poly, sweep, size)[ok]) < SAME_POSE_TOL
    assert np.bincount(poly.count[ok], minlength=7)[[0, 2, 4, 6]].min() > 10
    # The sweep's own poses pass the same independent check.
    valid = sweep.valid
    assert np.max(constraint_error(anchors, lengths, body, sweep.joints)[valid]) < RESIDUAL_TOL


_coord = st.floats(-1.0, 1.0)


@st.composite
def triads(draw):
    point = lambda: [draw(_coord), draw(_coord)]  # noqa: E731
    body = np.array([point() for _ in range(3)])
    anchors = np.array([point() for _ in range(3)])
    if draw(st.booleans()):
        lengths = np.array([draw(st.floats(0.05, 1.5)) for _ in range(3)])
    else:  # around a pose, at any or at a special angle
        phi = draw(st.one_of(st.floats(-np.pi, np.pi), st.sampled_from([0.0, np.pi, np.pi / 2])))
        pose = np.array(point()) + body @ _rotation(phi).T
        lengths = _norm(pose - anchors)
    scale = 10.0 ** draw(st.floats(-3.0, 3.0))
    shift = np.array([draw(st.floats(-100.0, 100.0)), draw(st.floats(-100.0, 100.0))])
    return (anchors + shift) * scale, lengths * scale, body * scale


def _well_posed(anchors, lengths, body):
    """No two body joints or anchors nearly coincide, and no link is nearly zero."""
    size = _size(anchors, lengths, body)
    pairs = ((0, 1), (0, 2), (1, 2))
    gaps = [_norm(body[i] - body[j]) for i, j in pairs]
    gaps += [_norm(anchors[i] - anchors[j]) for i, j in pairs]
    return min(*gaps, *lengths) > 0.02 * size


@settings(max_examples=150)
@given(triads())
def test_polynomial_and_sweep_agree_on_single_triads(triad):
    anchors, lengths, body = triad
    assume(_well_posed(anchors, lengths, body))
    poly = triad_poses(anchors, lengths, body)
    sweep = triad_poses_sweep(anchors, lengths, body, grid=4096)
    dets = np.concatenate(
        (jacobian_det(anchors, lengths, poly.joints), jacobian_det(anchors, lengths, sweep.joints))
    )
    assume(not (np.where(np.isnan(dets), np.inf, dets) < NEAR_SINGULAR).any())
    size = _size(anchors, lengths, body)
    # The sweep's blind spots, which Hypothesis finds with its exact small numbers: J1 on K2
    # (the circle–circle step has concentric circles, and near that J2 swings round K2 within a
    # ψ-window of about |J1 K2| / L1, far below a grid step), and J1, J2, K2 in line (that step
    # at its limit, where the residual is a square root of ψ's distance to the limit, and ψ
    # resolves it only to about 1e-8).
    j1, j2 = poly.joints[..., 0, :], poly.joints[..., 1, :]
    on_k2 = _norm(j1 - anchors[1]) < 1e-2 * size
    in_line = np.abs(_cross(j2 - j1, anchors[1] - j1)) < 1e-6 * _norm(j2 - j1) * _norm(
        anchors[1] - j1
    )
    assume(not (on_k2 | in_line).any())
    # Two poses whose first links lie within a few grid steps of each other are one sign
    # change to the sweep (no pair of roots closer than its step is resolved by it).
    psi = np.sort(np.arctan2(*(j1 - anchors[0])[poly.valid].T[::-1]))
    gaps = np.diff(np.concatenate((psi, psi[:1] + 2 * np.pi)))
    assume(not (gaps < 3 * 2 * np.pi / 4096).any())
    assert poly.count == sweep.count
    assert _pose_gap(poly, sweep, size) < SAME_POSE_TOL
    assert np.all(constraint_error(anchors, lengths, body, poly.joints)[poly.valid] < RESIDUAL_TOL)


# ----------------------------------------------------------------------------------------------
# The sweep on its own
# ----------------------------------------------------------------------------------------------


def test_sweep_roots_finds_close_pairs_and_roots_next_to_an_edge():
    # Branch +1 of a half-circle residual over |ψ| < 0.5: roots at ±0.5·√(1 − 0.3²), both within
    # a step of the edge of the domain; branch −1 has none. Plus a pair 1e-7 apart at ψ = 2.
    def residual(psi, branch):  # NaN outside both pieces (and the bump only on branch +1)
        with np.errstate(invalid="ignore"):
            arc = branch * np.sqrt(1.0 - (psi / 0.5) ** 2) - 0.3
        bump = np.where(branch > 0, (psi - 2.0) * (psi - 2.0000001) * 1e3, np.nan)
        return np.where(np.abs(psi - 2.0) < 0.2, bump, arc)

    found = sweep_roots(residual, (), grid=64)
    edge = 0.5 * math.sqrt(1.0 - 0.09)
    np.testing.assert_allclose(found.psi, [-edge, edge, 2.0, 2.0000001], rtol=0, atol=1e-15)
    np.testing.assert_array_equal(found.branch, [1.0, 1.0, 1.0, 1.0])


def test_sweep_roots_batched_and_bisected_to_the_last_bit():
    targets = np.array([[0.1, 1.0], [-3.0, 2.5], [np.nan, np.nan]])

    def residual(psi, branch):  # roots: the targets (period 2π), none for the last row
        a, b = targets[:, :1], targets[:, 1:]
        out = np.sin((psi - a) / 2) * np.sin((psi - b) / 2)
        return np.where(np.isnan(a), 1.0 + 0 * psi, out)

    found = sweep_roots(residual, (3,), branches=(1.0,), grid=100)
    np.testing.assert_array_equal(found.count, [2, 2, 0])
    np.testing.assert_allclose(found.psi[:2], np.sort(targets[:2], axis=1), rtol=0, atol=4e-16)
    assert np.isnan(found.psi[2]).all()


# ----------------------------------------------------------------------------------------------
# Velocities and accelerations
# ----------------------------------------------------------------------------------------------


def test_rates_match_central_differences_along_a_smooth_motion():
    rng = np.random.default_rng(13)
    n = 300
    base, lengths, body, _ = random_triads(rng, n, around_pose=1.0, scales=(0, 0), trans=1.0)
    v, a = rng.uniform(-1, 1, (2, n, 3, 2))

    def anchors(t):  # each anchor on its own ellipse-like path
        return base + v * np.sin(t) + a * (1.0 - np.cos(t))

    t0 = 0.3
    poses = triad_poses(anchors(t0), lengths, body)
    rates = triad_rates(
        anchors(t0)[:, None],
        (v * np.cos(t0) + a * np.sin(t0))[:, None],
        (-v * np.sin(t0) + a * np.cos(t0))[:, None],
        poses.joints,
        lengths[:, None],
    )

    def follow(t):  # the pose nearest each pose at t0
        q = triad_poses(anchors(t), lengths, body).joints
        gap = np.abs(poses.joints[:, :, None] - q[:, None]).max(axis=(-1, -2))
        nearest = np.where(np.isnan(gap), np.inf, gap).argmin(-1)
        return np.take_along_axis(q, nearest[..., None, None], axis=1)

    def differences(h):
        plus, minus = follow(t0 + h), follow(t0 - h)
        return (plus - minus) / (2 * h), (plus - 2 * poses.joints + minus) / h**2

    # Richardson's extrapolation of central differences (error h⁴) at h = 1e-4.
    (v1, a1), (v2, a2) = differences(1e-4), differences(2e-4)
    fd_vel, fd_acc = (4 * v1 - v2) / 3, (4 * a1 - a2) / 3
    det = jacobian_det(anchors(t0), lengths, poses.joints)
    check = poses.valid & (np.where(np.isnan(det), 0, det) > 0.05)
    assert check.sum() > 500
    assert rates.regular[check].all()
    vel_err = np.abs(rates.vel - fd_vel).max(axis=(-1, -2)) / (
        1 + np.abs(fd_vel).max(axis=(-1, -2))
    )
    acc_err = np.abs(rates.acc - fd_acc).max(axis=(-1, -2)) / (
        1 + np.abs(fd_acc).max(axis=(-1, -2))
    )
    assert vel_err[check].max() < 1e-5
    assert acc_err[check].max() < 1e-5
    # The body stays rigid: relative velocities are ω × (J_k − J_1).
    rho = poses.joints - poses.joints[..., :1, :]
    rigid = (
        rates.vel
        - rates.vel[..., :1, :]
        - rates.omega[..., None, None] * np.stack((-rho[..., 1], rho[..., 0]), -1)
    )
    assert np.abs(rigid[check]).max() < 1e-9 * (1 + np.abs(rates.vel[check]).max())


def test_rates_are_nan_at_a_singular_pose():
    # The three links' lines meet at O: the body can turn about O instantaneously.
    body = np.array([[0.0, 0.0], [2.0, 0.0], [0.5, 1.5]])
    o = np.array([0.7, 0.4])
    anchors = body + np.array([[1.0], [0.5], [2.0]]) * (body - o)
    lengths = _norm(body - anchors)
    rates = triad_rates(anchors, np.ones((3, 2)), np.zeros((3, 2)), body, lengths)
    assert not rates.regular
    assert np.isnan(rates.vel).all() and np.isnan(rates.acc).all() and np.isnan(rates.omega)
    # Moved off the singular position it is regular again.
    moved = triad_rates(anchors + [[0.0, 0.3], [0, 0], [0, 0]], np.ones((3, 2)), 0.0, body, lengths)
    assert moved.regular


# ----------------------------------------------------------------------------------------------
# All configurations of the Stephenson III
# ----------------------------------------------------------------------------------------------


FAMILY = Stephenson3


def random_stephenson3(rng, n, *, input="output", family=FAMILY):
    """``n`` Stephenson-III six-bars built around a configuration, and that configuration.

    All joints are drawn first; the dimensions are then measured from them, so the drawn
    configuration is a real one at its own input angles.
    """
    A0, B0, D0, A, B, C, D = rng.uniform(-1.0, 1.0, (7, n, 2))
    e = (B - A) / _norm(B - A)[:, None]
    rel = C - A
    u1, v1 = (rel * e).sum(-1), _cross(e, rel)
    u, v = rng.uniform(-1.0, 1.0, (2, n))
    f = (D - C) / _norm(D - C)[:, None]
    P = C + u[:, None] * f + v[:, None] * np.stack((-f[:, 1], f[:, 0]), -1)
    mech = family(
        A0=A0,
        B0=B0,
        D0=D0,
        crank=_norm(A - A0),
        coupler=_norm(B - A),
        rocker=_norm(B - B0),
        u1=u1,
        v1=v1,
        link1=_norm(D - C),
        link2=_norm(D - D0),
        u=u,
        v=v,
        input=input,
    )
    config = {"A0": A0, "B0": B0, "D0": D0, "A": A, "B": B, "C": C, "D": D, "P": P}
    return mech, config


def _angle(vec):
    return np.arctan2(vec[..., 1], vec[..., 0])


def _six_bar_error(mech, out):
    """Every constraint of the Stephenson III, recomputed from the positions, relative."""
    pos = out.positions
    f = lambda name: np.asarray(getattr(mech, name), dtype=float)[..., None, None]  # noqa: E731
    g = lambda name: np.asarray(getattr(mech, name), dtype=float)[..., None, None, :]  # noqa: E731
    e = pos["B"] - pos["A"]
    e = e / _norm(e)[..., None]
    c_place = (
        pos["A"]
        + f("u1")[..., None] * e
        + f("v1")[..., None] * np.stack((-e[..., 1], e[..., 0]), -1)
    )
    k = pos["D"] - pos["C"]
    k = k / _norm(k)[..., None]
    p_place = (
        pos["C"] + f("u")[..., None] * k + f("v")[..., None] * np.stack((-k[..., 1], k[..., 0]), -1)
    )
    errors = [
        np.abs(_norm(pos["A"] - g("A0")) - f("crank")),
        np.abs(_norm(pos["B"] - pos["A"]) - f("coupler")),
        np.abs(_norm(pos["B"] - g("B0")) - f("rocker")),
        np.abs(_norm(pos["D"] - pos["C"]) - f("link1")),
        np.abs(_norm(pos["D"] - g("D0")) - f("link2")),
        _norm(pos["C"] - c_place),
        _norm(pos["P"] - p_place),
        _norm(pos["A0"] - g("A0")) + _norm(pos["B0"] - g("B0")) + _norm(pos["D0"] - g("D0")),
    ]
    lengths = [f(n) for n in ("crank", "coupler", "rocker", "link1", "link2")]
    scale = np.maximum.reduce(np.broadcast_arrays(*lengths, _norm(g("A0") - g("B0"))))
    return np.maximum.reduce(errors) / scale


def test_output_driven_configurations_satisfy_every_constraint_and_include_the_built_one():
    rng = np.random.default_rng(31)
    mech, config = random_stephenson3(rng, 400)
    theta = _angle(config["D"] - config["D0"])
    inputs = np.stack((theta, theta + 0.05, theta - 0.4), axis=-1)  # (400, 3)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = solve_all(mech, inputs)
    assert out.driven == "output"
    assert out.positions["A"].shape == (400, 3, 6, 2) and out.count.shape == (400, 3)
    valid = out.valid
    for name in JOINTS:
        assert np.isfinite(out.positions[name][valid]).all()
        assert np.isnan(out.positions[name][~valid]).all()
    assert np.max(_six_bar_error(mech, out)[valid]) < 1e-10
    assert np.max(out.residual[valid]) < 1e-10 and np.isnan(out.residual[~valid]).all()
    # D is where the input puts it.
    d = (
        np.asarray(mech.D0)[:, None, None]
        + np.asarray(mech.link2)[:, None, None, None]
        * np.stack((np.cos(inputs), np.sin(inputs)), -1)[:, :, None]
    )
    assert np.abs(np.where(valid[..., None], out.positions["D"] - d, 0)).max() < 1e-12
    assert out.count.max() > 2 and (out.count[:, 0] >= 1).all()
    # The configuration the mechanism was built from is among those at its own input.
    built = np.stack([config[k] for k in ("A", "B", "C", "D", "P")], axis=-2)
    found = np.stack([out.positions[k][:, 0] for k in ("A", "B", "C", "D", "P")], axis=-2)
    gap = np.abs(found - built[:, None]).max(axis=(-1, -2))
    assert (np.where(np.isnan(gap), np.inf, gap).min(-1) < 1e-9).mean() > 0.99
    # Signs as the family defines them, read off the positions.
    s1 = np.sign(
        _cross(
            np.asarray(mech.B0)[:, None, None] - out.positions["A"],
            out.positions["B"] - out.positions["A"],
        )
    )
    np.testing.assert_array_equal(out.assembly[valid], s1[valid])


def test_output_configurations_fed_back_to_the_crank_reproduce_the_output_angle():
    rng = np.random.default_rng(37)
    mech, config = random_stephenson3(rng, 300)
    theta = _angle(config["D"] - config["D0"])[:, None] + np.array([0.0, 0.1])
    out = solve_all(mech, theta)
    # Empty slots get an angle of 0 (a NaN input is refused); only real ones are compared.
    crank_angle = np.nan_to_num(_angle(out.positions["A"] - np.asarray(mech.A0)[:, None, None]))
    by_crank = solve_all(dataclasses.replace(mech, input="crank"), crank_angle.reshape(300, -1))
    assert by_crank.driven == "crank"
    # For each output configuration, the crank-driven one on the same branch signs.
    slots = by_crank.positions["D"].reshape(300, 2, 6, 4, 2)
    same = (by_crank.assembly.reshape(300, 2, 6, 4) == out.assembly[..., None]) & (
        by_crank.assembly2.reshape(300, 2, 6, 4) == out.assembly2[..., None]
    )
    check = out.valid & (out.assembly != 0) & (out.assembly2 != 0)
    assert check.sum() > 300
    assert (same.sum(-1)[check] == 1).all()
    d = np.where(same[..., None], slots, 0.0).sum(-2)
    d_angle = _angle(d - np.asarray(mech.D0)[:, None, None])
    diff = np.angle(np.exp(1j * (d_angle - theta[..., None])))
    assert np.max(np.abs(diff[check])) < 1e-9
    for name in ("A", "B", "C", "P"):
        mine = np.where(same[..., None], by_crank.positions[name].reshape(300, 2, 6, 4, 2), 0).sum(
            -2
        )
        assert np.abs(mine - out.positions[name])[check].max() < 1e-8


def test_crank_driven_configurations():
    rng = np.random.default_rng(41)
    mech, config = random_stephenson3(rng, 300, input="crank")
    theta = _angle(config["A"] - config["A0"])[:, None] + np.linspace(-1, 1, 5)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = solve_all(mech, theta)
    assert out.positions["P"].shape == (300, 5, 4, 2)
    valid = out.valid
    assert np.max(_six_bar_error(mech, out)[valid]) < 1e-12
    assert (out.count[:, 2] >= 1).all() and (out.count == 4).any()
    # Each configuration once, each on its own pair of signs, in the documented order.
    code = np.where(valid, (1 - out.assembly) + (1 - out.assembly2) / 2, 10.0)
    assert (np.diff(code, axis=-1)[valid[..., 1:]] > 0).all()
    a = out.positions["A"]
    s2 = np.sign(
        _cross(
            np.asarray(mech.D0)[:, None, None] - out.positions["C"],
            out.positions["D"] - out.positions["C"],
        )
    )
    np.testing.assert_array_equal(out.assembly2[valid], s2[valid])
    expected_a = (
        np.asarray(mech.A0)[:, None, None]
        + np.asarray(mech.crank)[:, None, None, None]
        * np.stack((np.cos(theta), np.sin(theta)), -1)[:, :, None]
    )
    assert np.abs(np.where(valid[..., None], a - expected_a, 0)).max() < 1e-12


def test_crank_driven_configurations_match_the_family_plan():
    rng = np.random.default_rng(43)
    mech, config = random_stephenson3(rng, 200, input="crank")
    theta = _angle(config["A"] - config["A0"])[:, None] + np.linspace(-0.5, 0.5, 4)
    out = solve_all(mech, theta)
    for signs in ((1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)):
        motion = solve(dataclasses.replace(mech, assembly=signs[0], assembly2=signs[1]), theta)
        mine = (out.assembly == signs[0]) & (out.assembly2 == signs[1])
        np.testing.assert_array_equal(mine.sum(-1), motion.valid)
        for name in JOINTS:
            picked = np.where(mine[..., None], out.positions[name], 0.0).sum(-2)
            gap = np.where(motion.valid[..., None], picked - motion.positions[name], 0.0)
            assert np.abs(gap).max() < 1e-12


def test_the_family_example_driven_both_ways():
    mech = FAMILY(
        A0=np.array([0.0, 0.0]),
        B0=np.array([4.0, 0.0]),
        D0=np.array([2.0, -4.0]),
        crank=1.0,
        coupler=5.0,
        rocker=4.0,
        u1=4.0,
        v1=-2.0,
        link1=3.0,
        link2=6.0,
        u=1.5,
        v=1.0,
    )
    crank = solve_all(mech, [0.0])
    # A = (1, 0), B = (4, 4) (a 3-4-5 triangle with B0), C = (5, 2); D at 3 from C, 6 from D0.
    np.testing.assert_allclose(crank.positions["C"][0, 0], [5.0, 2.0], atol=1e-14)
    np.testing.assert_allclose(crank.positions["D"][0, :2], [[6.8, -0.4], [2.0, 2.0]], atol=1e-14)
    out = solve_all(dataclasses.replace(mech, input="output"), [np.pi / 2])
    assert out.count[0] == 2
    np.testing.assert_allclose(out.positions["A"][0, 1], [1.0, 0.0], atol=1e-14)
    np.testing.assert_allclose(out.positions["P"][0, 1], [3.5, 1.0], atol=1e-14)


def test_solve_all_refuses_what_it_cannot_solve():
    mech, _ = random_stephenson3(np.random.default_rng(1), 1)
    with pytest.raises(ValueError, match="input"):
        dataclasses.replace(mech, input="coupler")
    with pytest.raises(ValueError, match="1-D"):
        solve_all(mech, 0.0)


def test_a_limit_position_of_the_four_bar_is_one_configuration_per_second_dyad_branch():
    # At θ = 0, |A B0| = 3 = coupler − rocker: both four-bar branches give B = (5, 0).
    mech = FAMILY(
        A0=np.array([0.0, 0.0]),
        B0=np.array([4.0, 0.0]),
        D0=np.array([3.0, -3.0]),
        crank=1.0,
        coupler=4.0,
        rocker=1.0,
        u1=1.0,
        v1=1.0,
        link1=2.0,
        link2=3.0,
    )
    out = solve_all(mech, [0.0, 0.1])
    np.testing.assert_allclose(out.positions["B"][0, :2], [[5.0, 0.0]] * 2, atol=1e-15)
    assert out.count[0] == 2 and out.count[1] == 4
    np.testing.assert_array_equal(out.assembly[0, :2], [1.0, 1.0])
    np.testing.assert_array_equal(out.assembly2[0, :2], [1.0, -1.0])
