"""Paper 000: its linear system for coupler points (eqs. 6–13) and its θ4 formula (eq. 5),
implemented from the print in linkwright.papers.p000, against linkwright's own construction
and against closed forms; the regenerated figures and page."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import matplotlib.image as mpimg
import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from linkwright.geometry import sphere
from linkwright.mechanisms import SphericalFourBar, circuit, solve
from linkwright.papers import p000, p000_formulas
from linkwright.papers.p000 import (
    InvalidInput,
    eq4_rocker_joint,
    eq5_theta4,
    eq13_coupler_point,
    figure_fourbar,
    figure_sixbar,
)

TOL = 1e-13
# Exclusions, measured on 1.8 million random links (see the p000 module docstring):
# - eq. 3's plane cannot contain OZ (α = 90°, tan α infinite): keep the plane OAC at least
#   1e-10 from it, |ẑ · unit(A × C)| ≥ 1e-10 (eq13_coupler_point reports NaN within ~1e-12);
# - the system of eqs. 9–11 is singular for every input at μ = ±90° and ill-conditioned where
#   AB, AC or BC nears 0° or 180°; its difference from the rotation stays below
#   ~8e-16 / CONDITION, CONDITION = |cos μ| · sin AB · min(sin AC, sin BC): keep it ≥ 0.02;
# - eq. 7's first line alone adds a factor 1/|z_A| (its 0/0 at z_A = 0, i.e. θ2 = 0°, 180° for
#   the four-bar's crank): keep CONDITION · |z_A| ≥ 0.01 for it.
MIN_CONDITION = 0.02
MIN_CONDITION_FIRST_LINE = 0.01
MIN_TILT = 1e-10

degrees = st.floats(5.0, 175.0)


def condition(A, B, C, ab, mu):
    """CONDITION where the plane OAC is clear of OZ, else 0 (excluded)."""
    bc = sphere.arc(B, C)
    ac = sphere.arc(A, C)
    tilt = np.abs(sphere.unit(sphere.cross(A, C))[..., 2])
    value = np.abs(np.cos(mu)) * np.sin(ab) * np.minimum(np.sin(ac), np.sin(bc))
    return np.where(tilt >= MIN_TILT, value, 0.0)


# --------------------------------------------------------------------------------------------
# Eqs. 6–13 against the rotation about OA
# --------------------------------------------------------------------------------------------


def test_eq13_on_a_right_angled_link():
    # A = +X, B = +Y, AB = 90°: C at 90° from A, turned 45° about +X from the great circle
    # towards +Y, is (0, cos 45°, sin 45°) (right-handed: from +Y towards +Z).
    c = eq13_coupler_point([1.0, 0, 0], [0.0, 1, 0], math.pi / 2, math.pi / 2, math.pi / 4)
    np.testing.assert_allclose(c, [0, math.sqrt(0.5), math.sqrt(0.5)], atol=1e-15)
    # μ = −30°, AC = 40°: the closed form cos AC·A + sin AC (cos μ·Y + sin μ·Z).
    ac, mu = math.radians(40), math.radians(-30)
    c = eq13_coupler_point([1.0, 0, 0], [0.0, 1, 0], math.pi / 2, ac, mu)
    expect = [math.cos(ac), math.sin(ac) * math.cos(mu), math.sin(ac) * math.sin(mu)]
    np.testing.assert_allclose(c, expect, atol=1e-15)


def test_eq13_reports_a_plane_through_oz_as_singular():
    # A folded linkage lying in the plane OXZ: A, B and C all have y = 0, so eq. 3 (which
    # needs tan α finite) cannot describe their plane; noise would be returned otherwise.
    m = SphericalFourBar(*np.radians([6, 25, 25, 6, 3, 0]))
    motion = solve(m, [1.5 * math.pi], order=0)
    pos = motion.positions
    assert np.max(np.abs(np.stack([pos[k][0, 1] for k in "ABP"]))) < 1e-15
    c = eq13_coupler_point(pos["A"], pos["B"], m.coupler, m.point_arc, m.point_angle)
    assert np.all(np.isnan(c))


def test_eq13_is_singular_for_every_input_at_mu_90():
    # The plane OAC's normal then lies in the plane OAB: the three rows are dependent, and in
    # floating point (cos 90° ≈ 6e-17) eq. 13 would return a point off the sphere.
    A = sphere.unit(np.array([0.3, 0.5, 0.2]))
    B = sphere.point_at(A, np.array([0.0, 0, 1]), 0.8, 0.3)
    for a, b in (([1.0, 0, 0], [0.0, 1, 0]), (A, B)):
        ab = float(sphere.arc(np.array(a), np.array(b)))
        assert np.all(np.isnan(eq13_coupler_point(a, b, ab, 0.7, math.pi / 2)))
        assert np.all(np.isnan(eq13_coupler_point(a, b, ab, 0.7, -math.pi / 2)))


@pytest.mark.parametrize("number", [6, 7])
@pytest.mark.parametrize("assembly", [1.0, -1.0])
def test_figure_fourbars_agree_with_rotation_over_the_whole_turn(number, assembly):
    m = figure_fourbar(number, assembly)
    motion = circuit(m, 720, order=0)
    assert motion.valid.all()
    pos = motion.positions
    c = eq13_coupler_point(pos["A"], pos["B"], m.coupler, m.point_arc, m.point_angle)
    assert np.max(sphere.norm(c - pos["P"])) <= TOL
    # The circuit holds θ2 = 0° and 180°, eq. 7's 0/0 inputs.
    assert np.any(np.isclose(motion.input, 0.0)) and np.any(np.isclose(motion.input, math.pi))


def test_sixbar_points_agree_in_the_full_turn_reading():
    for assembly2 in (1.0, -1.0):
        m = figure_sixbar(-1.0, -1.0, assembly2)
        motion = circuit(m, 720, order=0)
        pos = motion.positions
        c = eq13_coupler_point(pos["A"], pos["B"], m.coupler, m.point_arc, m.point_angle)
        d = eq13_coupler_point(pos["C"], pos["E"], m.link5, m.d_arc, m.d_angle)
        assert np.max(sphere.norm(c - pos["C"])) <= TOL
        assert np.max(sphere.norm(d - pos["D"])) <= TOL


def test_first_line_of_eq7_is_0_over_0_at_theta2_0_and_the_better_line_is_not():
    m = figure_fourbar(6)
    motion = solve(m, [0.0], order=0)
    pos = motion.positions
    args = (pos["A"], pos["B"], m.coupler, m.point_arc, m.point_angle)
    assert pos["A"][0, 2] == 0.0  # A lies exactly in OXY
    assert np.all(np.isnan(eq13_coupler_point(*args, alpha_from="first")))
    assert np.max(sphere.norm(eq13_coupler_point(*args) - pos["P"])) <= 1e-15


def test_degradation_table_is_monotone_enough_and_the_better_line_never_degrades():
    for d in p000.degradation():
        assert max(d.better) <= TOL
        assert d.first[-1] > 1e-3  # at the singular input itself: wrong or NaN
        assert d.first[0] <= TOL  # 10° away: fine
        assert 0 < d.onset < 1.0
        # Past the onset the first line is within tolerance at every tabulated distance.
        for delta, err in zip(d.deltas, d.first, strict=True):
            if delta > d.onset:
                assert err <= TOL


def test_right_next_to_a_plane_through_oz_eq13_is_exact_and_on_it_reported_singular():
    sweeps = p000.alpha90_sweep(deltas=(1e-2, 1e-6, 1e-8, 0.0))
    # Figs 6 (mode −1) and 7 (both modes) and Fig. 8's D cross α = 90° twice per turn each.
    assert len(sweeps) == 8
    for s in sweeps:
        assert max(s.errors[:3]) <= TOL
        assert s.errors[-1] == math.inf
        if s.case.startswith("Fig. 8"):
            m = figure_sixbar()
        else:
            m = figure_fourbar(int(s.case[5]), -1.0 if "−1" in s.case else 1.0)
        origin = "C" if s.point == "D" else "A"
        pos = solve(m, [math.radians(s.crossing)], order=0).positions
        normal = sphere.unit(sphere.cross(pos[origin], pos[s.point]))
        assert abs(float(normal[0, 2])) < 1e-12  # the plane really contains OZ there


@st.composite
def fourbars_at_inputs(draw):
    a = [math.radians(draw(degrees)) for _ in range(4)]
    ac = math.radians(draw(st.floats(0.0, 180.0)))
    mu = math.radians(draw(st.floats(-180.0, 180.0)))
    assembly = draw(st.sampled_from([1.0, -1.0]))
    phase = draw(st.floats(0.0, 2 * math.pi))
    m = SphericalFourBar(*a, ac, mu, assembly=assembly)
    return m, phase + np.linspace(0.0, 2 * math.pi, 48, endpoint=False)


@settings(max_examples=150, deadline=None)
@given(fourbars_at_inputs())
def test_eq13_agrees_with_rotation_on_random_fourbars(case):
    m, theta = case
    motion = solve(m, theta, order=0)
    pos = motion.positions
    # Where the crank end A meets the pivot B0 or its antipode (crank = frame or 180° − frame)
    # the dyad A–B–B0 is indeterminate: the engine's B there is not tested.
    ok = motion.valid & (np.sin(sphere.arc(pos["A"], pos["B0"])) >= 1e-6)
    assume(ok.any())
    A, B, P = (pos[k][ok] for k in "ABP")
    # The engine's B closes the coupler to rounding, so both methods see the same link.
    assert np.max(np.abs(sphere.arc(A, B) - m.coupler)) < 1e-13
    keep = condition(A, B, P, m.coupler, m.point_angle) >= MIN_CONDITION
    assume(keep.any())
    c = eq13_coupler_point(A[keep], B[keep], m.coupler, m.point_arc, m.point_angle)
    assert np.max(sphere.norm(c - P[keep])) <= TOL


@settings(max_examples=100, deadline=None)
@given(fourbars_at_inputs())
def test_first_line_of_eq7_agrees_away_from_its_0_over_0(case):
    m, theta = case
    motion = solve(m, theta, order=0)
    pos = motion.positions
    ok = motion.valid & (np.sin(sphere.arc(pos["A"], pos["B0"])) >= 1e-6)  # as above
    assume(ok.any())
    A, B, P = (pos[k][ok] for k in "ABP")
    # z_A = sin a2 sin θ2: the first line's 0/0 is at θ2 = 0°, 180°.
    z = np.abs(A[:, 2])
    keep = condition(A, B, P, m.coupler, m.point_angle) * z >= MIN_CONDITION_FIRST_LINE
    assume(keep.any())
    c = eq13_coupler_point(
        A[keep], B[keep], m.coupler, m.point_arc, m.point_angle, alpha_from="first"
    )
    assert np.max(sphere.norm(c - P[keep])) <= TOL


# --------------------------------------------------------------------------------------------
# Eqs. 4–5
# --------------------------------------------------------------------------------------------


@st.composite
def fourbars(draw):
    return [math.radians(draw(degrees)) for _ in range(4)]


@settings(max_examples=200, deadline=None)
@given(fourbars(), st.floats(0.0, 2 * math.pi))
def test_eq5_closes_the_linkage_and_is_mode_plus_one(arcs, theta2):
    a1, a2, a3, a4 = arcs
    A = np.array([math.cos(a2), math.sin(a2) * math.cos(theta2), math.sin(a2) * math.sin(theta2)])
    B0 = np.array([math.cos(a1), math.sin(a1), 0.0])
    # Eq. 5 solves q cos θ4 + p sin θ4 = u by the half-angle substitution; its quotient is 0/0
    # where q + u = 0 (identically so when a1 = a4 and a2 = a3), so keep clear of that.
    p, q, u = p000_formulas.eq5_pqu(a1, a2, a3, a4, theta2)
    assume(abs(q + u) >= 1e-3 * (abs(p) + abs(q) + abs(u)))
    assume(math.sin(float(sphere.arc(A, B0))) >= 1e-6)  # A on ±B0: the dyad is indeterminate
    for sign, mode in ((-1, 1.0), (1, -1.0)):
        t4 = eq5_theta4(a1, a2, a3, a4, theta2, sign=sign)
        motion = solve(SphericalFourBar(a1, a2, a3, a4, assembly=mode), [theta2], order=0)
        # Where eq. 5's root is real the linkage assembles, and conversely (away from an exact
        # limit position, where rounding decides).
        margin = float(motion.margins["B"][0])
        assume(abs(margin) > 1e-9)
        assert np.isfinite(t4) == bool(motion.valid[0])
        if not np.isfinite(t4):
            continue
        B = eq4_rocker_joint(a1, a4, t4)
        # Constraint residuals: B on the rocker circle about B0 (by eq. 4's construction) and
        # at arc a3 from A (what eq. 5 solves).
        assert abs(float(sphere.arc(B0, B)) - a4) < 1e-12
        assert abs(float(q * np.cos(t4) + p * np.sin(t4) - u)) < 1e-12
        # The printed minus sign is linkwright's mode +1, the plus sign mode −1.
        side = float(sphere.dot(sphere.cross(A, B0), B))
        assert side * mode > 0


def test_eq5_checks_on_the_figures():
    for c in p000.eq5_checks():
        assert c.printed <= 2e-13 and c.other_sign <= 2e-13 and c.printed_theta4 <= 2e-13
    fig7 = next(c for c in p000.eq5_checks() if c.case == "Fig. 7")
    assert fig7.q_plus_u < 1e-3  # its worst input is next to eq. 5's own 0/0


def test_eq4_puts_theta4_zero_on_the_frame_circle_beyond_b0():
    a1, a4 = math.radians(40), math.radians(35)
    np.testing.assert_allclose(
        eq4_rocker_joint(a1, a4, 0.0), [math.cos(a1 + a4), math.sin(a1 + a4), 0.0], atol=1e-15
    )


# --------------------------------------------------------------------------------------------
# Fig. 8's reading
# --------------------------------------------------------------------------------------------


def test_only_epsilon_minus_30_with_assembly_minus_1_turns_fully():
    modes = p000.fig8_modes()
    full = [(m.epsilon, m.assembly) for m in modes if m.full]
    assert full == [(-30.0, -1.0)]
    # Independently of the limit finder: the engine assembles at every one of 3600 inputs for
    # that reading only.
    theta = np.linspace(0.0, 2 * math.pi, 3600, endpoint=False)
    for m in modes:
        linkage = figure_sixbar(1.0 if m.epsilon > 0 else -1.0, m.assembly, 1.0)
        everywhere = bool(solve(linkage, theta, order=0).valid.all())
        assert everywhere == m.full


def test_the_dyad_modes_are_one_circuit_exactly_where_the_modes_say_so():
    for mode in p000.fig8_modes():
        eps = 1.0 if mode.epsilon > 0 else -1.0
        paths = [
            circuit(figure_sixbar(eps, mode.assembly, a2), 240, order=0).positions["D"]
            for a2 in (1.0, -1.0)
        ]
        # Distance from each point of one D path to the nearest point of the other.
        gap = np.min(np.linalg.norm(paths[0][:, None] - paths[1][None], axis=-1), axis=1)
        if mode.e_branches_distinct:
            assert gap.max() > 0.1
        else:
            assert gap.max() < 0.05  # one closed path, sampled differently


def test_epsilon_is_measured_right_handed_about_ob0():
    # ε = −30° puts E0 below the frame plane (right-handed about +OB0, starting from the frame
    # circle beyond B0 and turning towards −Z).
    e0 = figure_sixbar(-1.0).params()["E0"]
    b0 = np.array([math.cos(math.radians(35)), math.sin(math.radians(35)), 0.0])
    assert e0[2] < 0
    assert abs(float(sphere.arc(b0, e0)) - math.radians(85)) < 1e-14


# --------------------------------------------------------------------------------------------
# Bad input
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: eq13_coupler_point([2.0, 0, 0], [0, 1.0, 0], 1.0, 0.5, 0.3), "unit vectors"),
        (lambda: eq13_coupler_point([1.0, 0], [0, 1.0, 0], 1.0, 0.5, 0.3), "length 3"),
        (lambda: eq13_coupler_point([1.0, 0, 0], [0, 1.0, 0], 0.0, 0.5, 0.3), "AB"),
        (lambda: eq13_coupler_point([1.0, 0, 0], [0, 1.0, 0], 1.0, np.inf, 0.3), "AC"),
        (
            lambda: eq13_coupler_point([1.0, 0, 0], [0, 1.0, 0], 1.0, 0.5, 0.3, alpha_from="x"),
            "alpha_from",
        ),
        (lambda: eq5_theta4(0.5, 4.0, 0.5, 0.5, 0.0), "a2"),
        (lambda: eq5_theta4(0.5, 0.5, 0.5, 0.5, 0.0, sign=0), "sign"),
        (lambda: eq4_rocker_joint(0.5, 0.5, np.inf), "theta4"),
        (lambda: figure_fourbar(8), "Figs 6 and 7"),
        (lambda: figure_sixbar(0.5), "epsilon_sign"),
    ],
)
def test_bad_input_is_a_clear_error(call, match):
    with pytest.raises(InvalidInput, match=match):
        call()


def test_unassembled_samples_stay_nan():
    c = eq13_coupler_point([[np.nan] * 3, [1.0, 0, 0]], [[np.nan] * 3, [0, 1.0, 0]], 1.0, 0.5, 0.3)
    assert np.all(np.isnan(c[0])) and np.all(np.isfinite(c[1]))


# --------------------------------------------------------------------------------------------
# The regenerated figures and page
# --------------------------------------------------------------------------------------------


def test_reproduce_writes_the_figures_and_the_page(tmp_path):
    written = p000.reproduce(tmp_path / "out")
    assert [p.name for p in written] == [
        "p000-fig6.png",
        "p000-fig6.svg",
        "p000-fig7.png",
        "p000-fig7.svg",
        "p000-fig8.png",
        "p000-fig8.svg",
        "paper000.md",
        "paper000-point-checks.csv",
        "paper000-eq5-checks.csv",
        "paper000-fig8-readings.csv",
    ]
    for path in written:
        assert path.is_file() and path.parent == tmp_path / "out"
    for path in written[0:6:2]:
        image = mpimg.imread(path)
        assert image.shape[-1] == 4 and image[..., :3].std() > 0.05
    for path in written[1:6:2]:
        assert ET.parse(path).getroot().tag == "{http://www.w3.org/2000/svg}svg"
    page = written[6].read_text(encoding="utf-8")
    for needed in ("| 6 (crank-rocker) | 40 | 20 | 45 | 35 | 50 | 130 |", "ε = −30°", "Check 1"):
        assert needed in page
    assert "**turns fully**" in page
    for name in (p.name for p in written[:6]):
        assert name in page
    import csv

    with written[7].open(encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    # The paper's own method (eqs. 6-13, better line of eq. 7) against linkwright's, per curve.
    assert rows and max(float(r["better"]) for r in rows) < 1e-13
