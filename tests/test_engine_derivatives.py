"""The engine's velocities and accelerations against eighth-order central finite differences of
its positions, and against the closed-form velocity ratios of the four-bar and the slider-crank.
"""

from __future__ import annotations

import numpy as np
from engine_helpers import (
    DERIVATIVE_TOL,
    angle,
    cross,
    direction,
    dot,
    fourbars,
    norm,
    random_fourbars,
    random_slider_cranks,
    slider_cranks,
)
from hypothesis import given, settings
from hypothesis import strategies as st

from linkwright.mechanisms import (
    FourBar,
    solve,
)

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
        dv = norm(motion.velocities[q] - motion.velocities[p]) / length
        da = norm(motion.accelerations[q] - motion.accelerations[p]) / length
        omega = np.fmax(omega, np.fmax(dv, np.sqrt(da)))
    h = H_OMEGA / omega
    stencil = motion.input[..., None] + STENCIL * h[..., None]
    shape = stencil.shape
    around = solve(m, stencil.reshape(*shape[:-2], -1), order=0)
    margins = around.margins["B"].reshape(shape)
    ok = motion.regular & around.valid.reshape(shape).all(-1) & (margins.min(-1) > min_margin)
    if "B0" in around.positions:
        # Where the dyad's pivots A and B0 meet (a crank as long as the frame), its branch, a
        # side of the line through them, changes meaning and B jumps across on a fixed branch:
        # a stencil over the meeting differences the jump (seen: 71 % off). Keep them apart.
        apart = norm(around.positions["A"] - around.positions["B0"]).reshape(shape)
        ok &= apart.min(-1) > 0.05 * s
    for joint in ("A", "B", "P"):
        pos = around.positions[joint].reshape(*shape, 2)
        vel = np.einsum("k,...kd->...d", D1, pos) / h[..., None]
        acc = np.einsum("k,...kd->...d", D2, pos) / h[..., None] ** 2
        ev = norm(vel - motion.velocities[joint]) / (s * omega)
        ea = norm(acc - motion.accelerations[joint]) / (s * omega**2)
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
    phi1, phi2, phi3 = angle(A - A0), angle(B - A), angle(B - B0)
    np.testing.assert_allclose(
        np.where(motion.valid, np.cos(phi1 - motion.input), 1.0), 1.0, atol=1e-12
    )
    transmission = np.sin(phi3 - phi2)
    rate3 = L1 * np.sin(phi1 - phi2) / (L3 * transmission)
    rate2 = -L1 * np.sin(phi3 - phi1) / (L2 * transmission)
    engine3 = cross(B - B0, motion.velocities["B"]) / L3**2
    engine2 = cross(B - A, motion.velocities["B"] - motion.velocities["A"]) / L2**2
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
    A_rate = crank[..., None] * direction(motion.input + np.pi / 2)
    along = dot(B - A, d)
    speed = dot(B - A, A_rate) / along
    vB = motion.velocities["B"]
    ok = motion.regular & (np.abs(along) > 1e-3 * np.asarray(m.rod)[..., None])
    assert ok.sum() > 50_000
    s = np.asarray(m.scale)[..., None]
    err = np.abs(dot(vB, d) - speed) / np.maximum(s, np.abs(speed))
    assert np.all(err[ok] <= 1e-9), np.max(err[ok])
    assert np.all(np.abs(cross(d, vB))[ok] <= 1e-12 * np.maximum(s, np.abs(speed))[ok])
