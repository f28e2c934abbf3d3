"""Analyses of the spherical four-bar against independent derivations: the engine's numeric limits
and circuits, inverted linkages, central differences, the spherical law of cosines and paper 003's
own closed forms (eqs. 1 and 2)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st

from linkwright.analysis import (
    InvalidHingeRatio,
    NotASphericalFourBar,
    balanced_mu,
    coefficients,
    fourbar_class,
    grashof_terms,
    input_limits,
    output_angle,
    output_extremes,
    output_limits,
    output_rates,
    paper003_normal_extremes,
    paper003_tangential_extremes,
    pressure_angles,
    pressure_extremes,
    spherical_class,
    transmission_angle,
    transmission_extremes,
)
from linkwright.analysis import analyze as analyze_result
from linkwright.analysis.extrema import circuit_extremum
from linkwright.geometry import sphere
from linkwright.io.report import analysis_report
from linkwright.mechanisms import FourBar, SphericalFourBar, circuit, input_range, solve


def analyze(mechanism, **options):
    """The report ``linkwright analyze`` prints (degrees) of the typed analysis (radians)."""
    return analysis_report(analyze_result(mechanism, **options))


DEG = np.pi / 180.0
arc_deg = st.floats(5.0, 175.0)
assembly = st.sampled_from([1.0, -1.0])


def sph(a1, a2, a3, a4, asm=1.0) -> SphericalFourBar:
    """Paper 003's α1 crank, α2 coupler, α3 output, α4 frame, in degrees."""
    return SphericalFourBar(
        frame=np.radians(a4),
        crank=np.radians(a1),
        coupler=np.radians(a2),
        rocker=np.radians(a3),
        assembly=asm,
    )


def turns_fully(frame, crank, coupler, rocker) -> bool:
    """Whether the joint at the crank's ground pivot turns fully: the engine's numeric limits."""
    m = SphericalFourBar(frame=frame, crank=crank, coupler=coupler, rocker=rocker)
    return bool(input_range(m, method="numeric").full)


def joint_turning(a1, a2, a3, a4) -> dict[str, bool]:
    """Which of the four joints turns fully, each found by driving an inversion of the loop
    A0–A–B–B0 (arcs in radians) numerically: ground the link before the joint, drive the link
    after it."""
    return {
        "A0": turns_fully(a4, a1, a2, a3),  # frame grounded, crank driven
        "A": turns_fully(a1, a2, a3, a4),  # crank grounded, coupler driven about A
        "B": turns_fully(a2, a3, a4, a1),  # coupler grounded, rocker driven about B
        "B0": turns_fully(a3, a4, a1, a2),  # rocker grounded, frame driven about B0
    }


def far_from_change_point(fb: SphericalFourBar, margin: float = 1e-3) -> bool:
    return bool(np.min(np.abs(grashof_terms(fb))) > margin)


# --- classification -----------------------------------------------------------------------------

EXPECTED_TURNING = {
    "crank-rocker": {"A0", "A"},
    "double-crank": {"A0", "B0"},
    "rocker-crank": {"B0", "B"},
    "double-rocker": {"A", "B"},
    "triple-rocker": set(),
}


@settings(max_examples=60, deadline=None)
@given(arc_deg, arc_deg, arc_deg, arc_deg)
def test_classification_matches_numeric_turning_of_every_joint(a1, a2, a3, a4):
    fb = sph(a1, a2, a3, a4)
    assume(far_from_change_point(fb))
    name = str(spherical_class(fb))
    turning = joint_turning(*np.radians([a1, a2, a3, a4]))
    assert {j for j, t in turning.items() if t} == EXPECTED_TURNING[name], (name, turning)
    assert str(fourbar_class(fb)) == name  # the planar entry point dispatches


def test_classification_of_a_random_batch_matches_the_engine():
    rng = np.random.default_rng(7)
    arcs = rng.uniform(3.0, 177.0, (4, 1500))
    fb = sph(*arcs)
    keep = np.min(np.abs(grashof_terms(fb)), axis=-1) > 1e-3
    names = spherical_class(fb)[keep]
    numeric_in = input_range(fb, method="numeric").full[keep]
    inverted = SphericalFourBar(
        frame=fb.frame, crank=fb.rocker, coupler=fb.coupler, rocker=fb.crank
    )
    numeric_out = input_range(inverted, method="numeric").full[keep]
    expect_in = np.isin(names, ["crank-rocker", "double-crank"])
    expect_out = np.isin(names, ["rocker-crank", "double-crank"])
    assert np.array_equal(numeric_in, expect_in)
    assert np.array_equal(numeric_out, expect_out)
    # Every class occurs, arcs over 90° included.
    assert set(np.unique(names)) == set(EXPECTED_TURNING)
    wide = (arcs[:, keep] > 90).any(axis=0)
    assert set(np.unique(names[wide])) == set(EXPECTED_TURNING)
    # Where it never assembles, the closed form and the engine agree.
    assert np.array_equal(input_limits(fb).never, input_range(fb, method="numeric").never)


def test_axis_flip_is_the_same_mechanism():
    # Chiang's reduction: α → 180° − α for the two links at one joint leaves the class alone.
    rng = np.random.default_rng(3)
    a1, a2, a3, a4 = rng.uniform(5.0, 175.0, (4, 500))
    base = spherical_class(sph(a1, a2, a3, a4))
    assert np.array_equal(base, spherical_class(sph(180 - a1, 180 - a2, a3, a4)))  # flip A
    assert np.array_equal(base, spherical_class(sph(a1, 180 - a2, 180 - a3, a4)))  # flip B
    swapped = spherical_class(sph(180 - a1, a2, a3, 180 - a4))  # flip A0: same joints turn
    assert np.array_equal(base, swapped)


def test_change_point_and_examples():
    # α1 + α2 = α3 + α4: the axes can all lie in one plane.
    assert str(spherical_class(sph(20, 70, 50, 40))) == "change-point"
    assert str(spherical_class(sph(100, 90, 90, 80))) == "change-point"  # Σ = 360°
    assert str(spherical_class(sph(15, 60, 80, 90))) == "crank-rocker"
    assert str(spherical_class(sph(100, 65, 50, 10))) == "double-crank"


# --- input and output ranges ----------------------------------------------------------------------


@settings(max_examples=60, deadline=None)
@given(arc_deg, arc_deg, arc_deg, arc_deg)
def test_input_limits_match_the_engine_and_close_the_dyad(a1, a2, a3, a4):
    fb = sph(a1, a2, a3, a4)
    assume(far_from_change_point(fb))
    ours, engine = input_limits(fb), input_range(fb, method="numeric")
    assert bool(ours.full) == bool(engine.full) and bool(ours.never) == bool(engine.never)
    if ours.full or ours.never:
        return
    lo, hi = ours.lo[np.isfinite(ours.lo)], ours.hi[np.isfinite(ours.hi)]
    # Where the input rocks over a sliver the two limits nearly merge (a double root of the
    # closure), and each is only defined to about √ε of the linkage (seen: an arc of 1e-7
    # rad whose ends two correct searches put 3e-8 apart); elsewhere to 1e-9. The Gram check
    # below holds every end to 1e-9 regardless.
    tol = np.where(hi - lo < 1e-5, 1e-6, 1e-9)
    assert np.all(np.abs(lo - engine.lo[np.isfinite(engine.lo)]) <= tol)
    assert np.all(np.abs(hi - engine.hi[np.isfinite(engine.hi)]) <= tol)
    # At a limit the arc A B0 is |α2 − α3| or α2 + α3 (mod the sphere): the spherical triangle
    # A B B0 is flat, its Gram determinant 0.
    ends = np.concatenate((lo, hi))
    a = np.stack((np.cos(a1 * DEG) + 0 * ends, np.sin(a1 * DEG) * np.cos(ends)), -1)
    cos_d = a[:, 0] * np.cos(a4 * DEG) + a[:, 1] * np.sin(a4 * DEG)
    d = np.arccos(np.clip(cos_d, -1, 1))
    assert np.max(np.abs(sphere.gram(d, a2 * DEG, a3 * DEG))) < 1e-9


@settings(max_examples=40, deadline=None)
@given(arc_deg, arc_deg, arc_deg, arc_deg, assembly)
def test_output_extremes_match_the_traced_circuit(a1, a2, a3, a4, asm):
    fb = sph(a1, a2, a3, a4, asm)
    assume(far_from_change_point(fb, 1e-2))
    assume(not input_limits(fb).never)
    ext = output_extremes(fb)
    motion = circuit(fb, 1024)
    phi = np.unwrap(fb.output_angle(motion))
    turned = abs(phi[-1] - phi[0] + (phi[1] - phi[0])) > np.pi
    assert bool(ext["turns"]) == turned
    if turned:
        assert np.isnan(ext["min"])
        return
    mid = float(ext["min"] + ext["max"]) / 2

    def rel(m):
        return np.angle(np.exp(1j * (output_angle(fb, m) - mid)))

    hi = circuit_extremum(fb, rel, motion=motion)[0] + mid
    lo = circuit_extremum(fb, rel, sign=-1.0, motion=motion)[0] + mid
    assert float(ext["max"]) == pytest.approx(float(hi), abs=1e-8)
    assert float(ext["min"]) == pytest.approx(float(lo), abs=1e-8)
    # At each extreme crank and coupler are in line: A0, A, B on one great circle.
    for key in ("min", "max"):
        for branch in (1.0, -1.0):
            m = solve(fb.with_assembly(branch), [float(ext[f"{key}_at"])])
            if m.valid[0] and abs(np.angle(np.exp(1j * (fb.output_angle(m)[0] - ext[key])))) < 1e-6:
                a0, a, b = (np.reshape(m.positions[k], (-1, 3))[0] for k in ("A0", "A", "B"))
                assert abs(np.linalg.det(np.stack([a0, a, b]))) < 1e-7
                break
        else:
            pytest.fail(f"the output's {key} is not reached at its input")


def test_output_limits_by_the_law_of_cosines():
    # At the output's limits |A0 B| = α2 ± α1: cos A0B = cos α4 cos α3 − sin α4 sin α3 cos φ3.
    fb = sph(15, 60, 80, 90)
    arcs = output_limits(fb)
    phi = np.concatenate((arcs.lo, arcs.hi))
    cos_ab = np.cos(90 * DEG) * np.cos(80 * DEG) - np.sin(90 * DEG) * np.sin(80 * DEG) * np.cos(phi)
    reach = np.arccos(cos_ab) / DEG
    assert sorted(np.round(reach, 9)) == [45.0, 45.0, 75.0, 75.0]


# --- derivatives, transmission angle ----------------------------------------------------------


# Most random arcs put a limit or a change point near the sampled input, so many draws are
# rejected by design.
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(arc_deg, arc_deg, arc_deg, arc_deg, assembly, st.floats(-np.pi, np.pi))
def test_output_rates_match_central_differences(a1, a2, a3, a4, asm, theta):
    fb = sph(a1, a2, a3, a4, asm)
    # Away from change points and limit positions, where the rates blow up and a difference
    # step of 1e-4 no longer resolves them.
    assume(far_from_change_point(fb, 0.05))
    h = 1e-4
    m = solve(fb, theta + h * np.arange(-2, 3))
    assume(bool(m.valid.all()))
    assume(float(np.min(m.margins["B"])) > 1e-3)
    phi = np.unwrap(fb.output_angle(m))
    r1, r2 = output_rates(fb, m)
    assume(abs(r1[2]) < 50 and abs(r2[2]) < 500)
    d1 = (phi[0] - 8 * phi[1] + 8 * phi[3] - phi[4]) / (12 * h)
    d2 = (-phi[0] + 16 * phi[1] - 30 * phi[2] + 16 * phi[3] - phi[4]) / (12 * h * h)
    scale = 1 + abs(r1[2]) + abs(r2[2])
    assert r1[2] == pytest.approx(d1, abs=1e-6 * scale)
    assert r2[2] == pytest.approx(d2, abs=1e-4 * scale)


@settings(max_examples=40, deadline=None)
@given(arc_deg, arc_deg, arc_deg, arc_deg, assembly)
# The crank as long as the other three together: the arc is a single input to rounding, both
# ends limits with γ = 180°, where the sampled γ is 5e-8 short of it.
@example(15.0, 5.0, 5.0, 5.0, 1.0)
def test_transmission_angle_law_of_cosines_and_extremes(a1, a2, a3, a4, asm):
    fb = sph(a1, a2, a3, a4, asm)
    assume(far_from_change_point(fb, 1e-2))
    assume(not input_limits(fb).never)
    motion = circuit(fb, 4096, order=0)
    gamma = transmission_angle(fb, motion)
    d = sphere.arc(motion.positions["A"], motion.positions["B0"])
    c2, s2, c3, s3 = np.cos(a2 * DEG), np.sin(a2 * DEG), np.cos(a3 * DEG), np.sin(a3 * DEG)
    np.testing.assert_allclose(np.cos(gamma), (np.cos(d) - c2 * c3) / (s2 * s3), atol=1e-9)
    tx = transmission_extremes(fb)
    # Exact extremes bound the sampled ones and are within the sampling's reach of them. An
    # extreme at a limit position (γ = 0° or 180°) is sampled from a B known there only to
    # about √ε of its arc (the dyad's half-chord is the square root of a rounded zero), so it
    # is bounded to 1e-7 there (5e-8 is seen on a crank as long as the other three links).
    slack = {k: 1e-7 if float(tx[k]) in (0.0, np.pi) else 1e-12 for k in ("min", "max")}
    assert tx["min"] <= np.nanmin(gamma) + slack["min"] and np.nanmin(gamma) - tx["min"] < 2e-3
    assert tx["max"] >= np.nanmax(gamma) - slack["max"] and tx["max"] - np.nanmax(gamma) < 2e-3
    # Each extreme is reached where the report says.
    for key in ("min", "max"):
        m = solve(fb, [float(tx[f"{key}_at"])], order=0)
        assert transmission_angle(fb, m)[0] == pytest.approx(float(tx[key]), abs=1e-6)


def test_transmission_angle_of_a_rocking_input_reaches_180_at_its_limit():
    fb = sph(60, 30, 35, 40)  # non-Grashof: the input rocks over |φ1| ≤ its limit
    assert str(spherical_class(fb)) == "triple-rocker"
    tx = transmission_extremes(fb)
    limit = input_range(fb, method="numeric").hi[0]
    assert float(tx["max"]) == np.pi and float(tx["max_at"]) == pytest.approx(limit, abs=1e-9)
    assert float(tx["min_at"]) == 0.0


# --- pressure angle -------------------------------------------------------------------------------


def crank_rocker_with_mu():
    """Random crank-rockers (arcs below 90°, as in paper 003) and hinge ratios."""
    return st.tuples(
        st.floats(5, 40), st.floats(30, 89), st.floats(30, 89), st.floats(30, 89), st.floats(0.1, 4)
    )


@settings(max_examples=25, deadline=None)
@given(crank_rocker_with_mu())
def test_pressure_extremes_match_paper003_closed_forms(args):
    a1, a2, a3, a4, mu = args
    fb = sph(a1, a2, a3, a4)
    assume(bool(input_limits(fb).full) and far_from_change_point(fb, 1e-2))
    ext = pressure_extremes(fb, mu)
    normal = paper003_normal_extremes(fb, mu)
    tangential = paper003_tangential_extremes(fb, mu)
    assert float(ext["normal_max"]) == pytest.approx(float(normal["max"]), abs=1e-9)
    assert float(ext["normal_min"]) == pytest.approx(float(normal["min"]), abs=1e-9)
    assert float(ext["tangential_max"]) == pytest.approx(float(tangential["max"]), abs=1e-9)
    assert float(ext["tangential_min"]) == pytest.approx(float(tangential["min"]), abs=1e-9)
    # Eq. (2)'s stationary input, cos φ1 = k3/k1, against a second derivation: ν_τ depends on
    # x = cos d alone and is stationary at x* = μ cos α3 − cos α3 (1 + μ² − 2μ cos α2)/(μ − cos α2).
    c1, c2, c3, c4 = np.cos(np.radians([a1, a2, a3, a4]))
    s1, s4 = np.sin(np.radians(a1)), np.sin(np.radians(a4))
    x_star = mu * c3 - c3 * (1 + mu * mu - 2 * mu * c2) / (mu - c2)
    cos_phi = (x_star - c1 * c4) / (s1 * s4)
    inside = abs(cos_phi) < 1 - 1e-9
    assert np.isfinite(tangential["interior"]) == inside or abs(abs(cos_phi) - 1) < 1e-6
    if inside:
        assert math.cos(float(tangential["interior_at"])) == pytest.approx(cos_phi, abs=1e-9)


@settings(max_examples=30, deadline=None)
@given(crank_rocker_with_mu(), assembly, st.floats(-np.pi, np.pi))
def test_pressure_angle_components_by_their_definitions(args, asm, theta):
    a1, a2, a3, a4, mu = args
    fb = sph(a1, a2, a3, a4, asm)
    m = solve(fb, [theta])
    assume(bool(m.valid[0]))
    nu = pressure_angles(fb, m, mu)
    # sin ν_n = (μ cos α3 − cos d)/|μB − A| with |μB − A|² = 1 + μ² − 2μ cos α2.
    cos_d = sphere.dot(m.positions["A"], m.positions["B0"])[0]
    chord = math.sqrt(1 + mu * mu - 2 * mu * math.cos(a2 * DEG))
    assert math.sin(nu["normal"][0]) == pytest.approx((mu * math.cos(a3 * DEG) - cos_d) / chord)
    # sin ν_τ by the law of cosines alone (no vectors): with x = cos d,
    # sin ν_τ = (μ sin² α3 − cos α2 + cos α3 x) / (sin α3 √(|μB − A|² − (μ cos α3 − x)²)).
    s3, c3 = math.sin(a3 * DEG), math.cos(a3 * DEG)
    den = s3 * math.sqrt(max(chord**2 - (mu * c3 - cos_d) ** 2, 0.0))
    assume(den > 1e-6)
    num = mu * s3**2 - math.cos(a2 * DEG) + c3 * cos_d
    assert math.sin(nu["tangential"][0]) == pytest.approx(num / den, abs=1e-9)


def test_balanced_mu_balances_the_tangential_extremes():
    rng = np.random.default_rng(11)
    a1 = rng.uniform(10, 30, 200)
    a2, a3, a4 = rng.uniform(50, 89, (3, 200))
    fb = sph(a1, a2, a3, a4)
    mu = balanced_mu(fb)
    ok = np.isfinite(mu) & input_limits(fb).full
    assert ok.sum() > 50
    nu = paper003_tangential_extremes(fb, np.where(ok, mu, 1.0))
    two = ok & ~np.isfinite(nu["interior"])
    assert two.sum() > 30
    # Reinsberg's condition min ν_τ + max ν_τ = 0, with the extremes at φ1 = 0 and 180°.
    np.testing.assert_allclose((nu["at_0"] + nu["at_180"])[two], 0.0, atol=1e-9)


def test_pressure_angle_errors_are_clear():
    fb = sph(15, 60, 80, 90)
    with pytest.raises(InvalidHingeRatio, match="mu"):
        pressure_extremes(fb, -1.0)
    with pytest.raises(InvalidHingeRatio, match="mu"):
        paper003_normal_extremes(fb, np.nan)
    planar = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5)
    with pytest.raises(NotASphericalFourBar, match="SphericalFourBar"):
        balanced_mu(planar)
    with pytest.raises(InvalidHingeRatio, match="spherical"):
        analyze(planar, mu=0.5)
    with pytest.raises(ValueError, match="order=2"):
        output_rates(fb, solve(fb, [0.0], order=0))


# --- coefficients ---------------------------------------------------------------------------------


def dense_output(fb: SphericalFourBar, n: int = 20_000):
    """φ3 over one crank turn and its central differences (independent of output_rates).

    The step (0.018°) balances truncation (h²) against rounding (eps/h² in the second
    difference, which a finer grid would turn into an upward bias of the sampled maximum).
    """
    theta = np.linspace(0, 2 * np.pi, n, endpoint=False)
    phi = np.unwrap(fb.output_angle(solve(fb, theta, order=0)))
    h = theta[1] - theta[0]
    # Difference φ3 less its mean turning (an output that turns gains 2π): the second difference
    # then loses no digits to a large, growing angle.
    slope = round((phi[-1] - phi[0]) / (2 * np.pi))
    rest = np.angle(np.exp(1j * (phi - slope * theta)))
    rest = np.unwrap(rest)
    d1 = (np.roll(rest, -1) - np.roll(rest, 1)) / (2 * h) + slope
    d2 = (np.roll(rest, -1) - 2 * rest + np.roll(rest, 1)) / h**2
    return theta[2:-2], phi[2:-2], d1[2:-2], d2[2:-2]


@pytest.mark.parametrize("arcs", [(15, 60, 80, 90), (25, 80, 80, 90), (20, 40, 100, 110)])
def test_crank_rocker_coefficients_against_dense_differences(arcs):
    fb = sph(*arcs)
    assert str(spherical_class(fb)) == "crank-rocker"
    co = coefficients(fb)
    theta, phi, d1, d2 = dense_output(fb)
    psi = phi.max() - phi.min()

    def vertex(i: int) -> float:
        # The extreme's input from the parabola through the three samples around it.
        f0, f1, f2 = phi[i - 1], phi[i], phi[i + 1]
        h = theta[1] - theta[0]
        return theta[i] - 0.5 * h * (f2 - f0) / (f2 - 2 * f1 + f0)

    t_lo, t_hi = vertex(int(np.argmin(phi))), vertex(int(np.argmax(phi)))
    ccw = (t_hi - t_lo) % (2 * np.pi)
    phi_psi = ccw if (0 - t_lo) % (2 * np.pi) < ccw else 2 * np.pi - ccw
    assert co["psi"] == pytest.approx(psi, rel=1e-8)
    assert co["phi_psi"] == pytest.approx(phi_psi, abs=1e-6)
    assert co["K_omega"] == pytest.approx(np.abs(d1).max() * co["phi_psi"] / psi, rel=1e-5)
    assert co["K_epsilon"] == pytest.approx(np.abs(d2).max() * co["phi_psi"] ** 2 / psi, rel=1e-5)
    kp = np.abs(d1 * d2).max() * co["phi_psi"] ** 3 / psi**2
    assert co["K_p"] == pytest.approx(kp, rel=1e-5)
    ratio = max(phi_psi, 2 * np.pi - phi_psi) / min(phi_psi, 2 * np.pi - phi_psi)
    assert co["time_ratio"] == pytest.approx(ratio, abs=1e-5)
    assert np.isnan(co["delta"])


@pytest.mark.parametrize("arcs", [(100, 65, 50, 10), (80, 65, 60, 10), (120, 100, 70, 20)])
def test_double_crank_coefficients_against_dense_differences(arcs):
    fb = sph(*arcs)
    assert str(spherical_class(fb)) == "double-crank"
    co = coefficients(fb)
    _, _, d1, d2 = dense_output(fb)
    assert co["K_omega"] == pytest.approx(np.abs(d1).max(), rel=1e-5)
    assert co["K_epsilon"] == pytest.approx(2 * np.pi * np.abs(d2).max(), rel=1e-5)
    assert co["K_p"] == pytest.approx(2 * np.pi * np.abs(d1 * d2).max(), rel=1e-5)
    assert co["delta"] == pytest.approx(d1.max() - d1.min(), abs=1e-6)
    assert np.isnan(co["time_ratio"])


def test_coefficients_are_nan_where_the_input_rocks():
    co = coefficients(sph(60, 30, 35, 40))
    assert all(np.isnan(co[k]) for k in ("K_omega", "K_epsilon", "K_p", "delta"))


# --- the report -----------------------------------------------------------------------------------


def test_report_of_a_crank_rocker():
    fb = sph(15, 60, 80, 90)
    r = analyze(fb)
    json.dumps(r)  # JSON-ready
    planar = analyze(FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5))
    shared = set(planar) - {"grashof"}
    assert shared <= set(r)
    assert r["class"] == "crank-rocker" and r["assembles"] and r["input_range_deg"] is None
    ext = output_extremes(fb)
    assert r["swing_deg"] == pytest.approx(np.degrees(ext["max"] - ext["min"]), abs=1e-9)
    p = r["pressure_angle_deg"]
    assert p["mu_source"] == "balanced" and p["mu"] == pytest.approx(float(balanced_mu(fb)))
    assert p["tangential"]["max"] == pytest.approx(-p["tangential"]["min"], abs=1e-9)
    given_mu = analyze(fb, mu=0.517)["pressure_angle_deg"]
    assert given_mu["mu_source"] == "given" and given_mu["mu"] == 0.517
    assert given_mu["normal"]["max"] == pytest.approx(23.731, abs=1e-3)
    tx = r["transmission_angle_deg"]
    assert tx["min_at_input_deg"] == 0.0 and tx["max_at_input_deg"] == 180.0
    assert r["time_ratio"] == pytest.approx(coefficients(fb)["time_ratio"])


def test_report_of_a_rocking_input_and_of_a_linkage_that_cannot_assemble():
    r = analyze(sph(60, 30, 35, 40))
    assert r["class"] == "triple-rocker" and r["input_range_deg"] is not None
    assert len(r["limit_positions_deg"]) == 2 and r["coefficients"]["K_omega"] is None
    lo, hi = r["input_range_deg"]
    engine = input_range(sph(60, 30, 35, 40))
    assert lo == pytest.approx(np.degrees(engine.lo[0]), abs=1e-8)
    assert hi == pytest.approx(np.degrees(engine.hi[0]), abs=1e-8)
    bad = analyze(sph(10, 20, 30, 90))
    assert not bad["assembles"] and "cannot reach" in bad["reason"]
    assert bad["pressure_angle_deg"]["normal"]["max"] is None
    assert bad["coefficients"]["K_p"] is None and bad["swing_deg"] is None


def test_report_without_a_balancing_mu_says_so():
    fb = sph(28, 87, 56, 60)
    assert str(spherical_class(fb)) == "crank-rocker" and np.isnan(balanced_mu(fb))
    r = analyze(fb)
    assert r["pressure_angle_deg"]["mu_source"] == "none"
    assert r["pressure_angle_deg"]["tangential"]["max"] is None
    assert analyze(fb, mu=1.0)["pressure_angle_deg"]["tangential"]["max"] is not None
