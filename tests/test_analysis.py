"""Analyses of the planar four-bar and slider-crank against closed forms and independent methods."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from linkwright.analysis import analyze as analyze_result
from linkwright.analysis import (
    coefficients,
    fourbar_class,
    output_extremes,
    output_rates,
    slidercrank_class,
    transmission_angle,
    transmission_extremes,
)
from linkwright.io.report import analysis_report
from linkwright.mechanisms import FourBar, SliderCrank, circuit, input_range, solve
from linkwright.papers.p003 import reproduce_planar


def analyze(mechanism, **options):
    """The report ``linkwright analyze`` prints (degrees) of the typed analysis (radians)."""
    return analysis_report(analyze_result(mechanism, **options))


# --- independent closed forms (Freudenstein), written here without the engine -----------------


def freudenstein_phi3(L1, L2, L3, L4, phi1, branch):
    """Output angle of a four-bar with frame along +x, from the loop closure solved for φ3."""
    ax, ay = L1 * np.cos(phi1), L1 * np.sin(phi1)
    # B on circle(B0=(L4,0), L3) and circle(A, L2): φ3 solves  P cos φ3 + Q sin φ3 = R.
    P = 2 * L3 * (L4 - ax)
    Q = -2 * L3 * ay
    R = L2**2 - L3**2 - (L4 - ax) ** 2 - ay**2
    amp = np.hypot(P, Q)
    base = np.arctan2(Q, P)
    return base + branch * np.arccos(np.clip(R / amp, -1, 1))


def dense_rates(L1, L2, L3, L4, branch, n=200_000):
    """φ3′ and φ3″ of the closed form on a dense grid by central differences (independent)."""
    phi1 = np.linspace(0, 2 * np.pi, n, endpoint=False)
    h = phi1[1] - phi1[0]
    phi3 = np.unwrap(freudenstein_phi3(L1, L2, L3, L4, phi1, branch))
    d1 = (np.roll(phi3, -1) - np.roll(phi3, 1)) / (2 * h)
    d2 = (np.roll(phi3, -1) - 2 * phi3 + np.roll(phi3, 1)) / h**2
    # The seam samples see the 2π jump of a turning output; drop them.
    return phi1[2:-2], phi3[2:-2], d1[2:-2], d2[2:-2]


# --- paper 003 ----------------------------------------------------------------------------------


def test_paper003_planar_tables_reproduce_within_printed_precision():
    cells = reproduce_planar()
    assert len(cells) == 9 * 3 + 9 * 2 + 15 * 6
    for c in cells:
        if c.status in ("agrees", "agrees (truncated)", "misprint"):
            continue
        # The only cells that do not reproduce are max|Kp|, printed at most 0.6 % *below* the
        # exact maximum: the direction any sampled or smoothed maximum errs in.
        assert c.column == "K_p", c
        assert float(c.printed) < c.low and (c.ours - float(c.printed)) / c.ours < 0.006, c
    misprints = {(c.row, c.column) for c in cells if c.status == "misprint"}
    assert misprints == {("L2=3, L1=5.5", "L3"), ("L2=3, L1=6", "nu")}
    corrected = {(c.row, c.column): c.ours for c in cells if c.status == "misprint"}
    assert corrected[("L2=3, L1=5.5", "L3")] == pytest.approx(4.717, abs=5e-4)
    assert corrected[("L2=3, L1=6", "nu")] == pytest.approx(22.208, abs=5e-4)


@pytest.mark.parametrize(("L4", "L3"), [(3.5, 6.02), (4.0, 5.24), (4.5, 2.57), (3.5, 3.33)])
def test_crank_rocker_coefficients_match_dense_closed_form(L4, L3):
    L1, L2 = 1.0, 5.0
    fb = FourBar(A0=[0, 0], B0=[L4, 0], crank=L1, coupler=L2, rocker=L3)
    co = coefficients(fb)
    phi1, phi3, d1, d2 = dense_rates(L1, L2, L3, L4, 1.0)
    psi = phi3.max() - phi3.min()

    # The rocker's extremes are where crank and coupler are collinear, |A0 B| = L2 ± L1: the
    # crank lies along A0B (extended) or against it (folded). Pick the triangle's mirror whose
    # crank angle is nearest the dense grid's extreme.
    def collinear_crank_angle(reach, folded, near):
        ang = math.acos((L4**2 + reach**2 - L3**2) / (2 * L4 * reach))
        cands = [ang + math.pi * folded, -ang + math.pi * folded]
        return min(cands, key=lambda t: abs(math.remainder(t - near, 2 * math.pi)))

    grid_max, grid_min = phi1[np.argmax(phi3)], phi1[np.argmin(phi3)]
    b = collinear_crank_angle(L2 + L1, False, grid_max)
    a = collinear_crank_angle(L2 - L1, True, grid_min)
    if abs(math.remainder(b - grid_max, 2 * math.pi)) > 1e-3:  # extremes the other way round
        b = collinear_crank_angle(L2 - L1, True, grid_max)
        a = collinear_crank_angle(L2 + L1, False, grid_min)
    ccw = (b - a) % (2 * np.pi)
    phi_psi = ccw if (0 - a) % (2 * np.pi) < ccw else 2 * np.pi - ccw
    assert co["psi"] == pytest.approx(psi, rel=1e-8)
    assert co["phi_psi"] == pytest.approx(phi_psi, rel=1e-9)
    assert co["K_omega"] == pytest.approx(np.abs(d1).max() * phi_psi / psi, rel=1e-5)
    assert co["K_epsilon"] == pytest.approx(np.abs(d2).max() * phi_psi**2 / psi, rel=1e-5)
    assert co["K_p"] == pytest.approx(np.abs(d1 * d2).max() * phi_psi**3 / psi**2, rel=1e-5)
    assert np.isnan(co["delta"])
    # The refined maximum is never below one sampled by the engine itself on a fine grid.
    m = solve(fb, np.linspace(0, 2 * np.pi, 100_001))
    r1, r2 = output_rates(fb, m)
    sampled = np.abs(r1 * r2).max() * co["phi_psi"] ** 3 / co["psi"] ** 2
    assert sampled <= co["K_p"] * (1 + 1e-13)


def test_swing_matches_law_of_cosines():
    rng = np.random.default_rng(3)
    n = 300
    L1 = np.ones(n)
    L2, L3, L4 = rng.uniform(2, 6, (3, n))
    fb = FourBar(A0=[0, 0], B0=np.stack([L4, np.zeros(n)], -1), crank=L1, coupler=L2, rocker=L3)
    keep = fourbar_class(fb) == "crank-rocker"
    ext = output_extremes(fb)
    with np.errstate(invalid="ignore"):  # non-crank-rockers have no such triangle
        psi = np.arccos((L4**2 + L3**2 - (L2 + L1) ** 2) / (2 * L4 * L3)) - np.arccos(
            (L4**2 + L3**2 - (L2 - L1) ** 2) / (2 * L4 * L3)
        )
    np.testing.assert_allclose((ext["max"] - ext["min"])[keep], np.abs(psi)[keep], rtol=1e-10)
    assert keep.sum() > 50


def test_double_crank_coefficients_match_dense_closed_form():
    L1, L2, L4 = 4.0, 2.5, 1.0
    L3 = math.sqrt(L4**2 + L1**2 - L2**2)
    fb = FourBar(A0=[0, 0], B0=[L4, 0], crank=L1, coupler=L2, rocker=L3)
    co = coefficients(fb)
    _, _, d1, d2 = dense_rates(L1, L2, L3, L4, 1.0)
    assert co["K_omega"] == pytest.approx(np.abs(d1).max(), rel=1e-6)
    assert co["K_epsilon"] == pytest.approx(2 * np.pi * np.abs(d2).max(), rel=1e-5)
    assert co["K_p"] == pytest.approx(2 * np.pi * np.abs(d1 * d2).max(), rel=1e-5)
    assert co["delta"] == pytest.approx(d1.max() - d1.min(), rel=1e-6)
    assert np.isnan(co["time_ratio"])


# --- transmission angle ---------------------------------------------------------------------


def random_fourbars(rng, n):
    return FourBar(
        A0=rng.normal(size=(n, 2)),
        B0=rng.normal(size=(n, 2)) * 2,
        crank=rng.uniform(0.2, 3, n),
        coupler=rng.uniform(0.2, 3, n),
        rocker=rng.uniform(0.2, 3, n),
        u=rng.normal(size=n),
        v=rng.normal(size=n),
        assembly=rng.choice([-1.0, 1.0], n),
    )


def test_transmission_extremes_bound_and_are_attained():
    fb = random_fourbars(np.random.default_rng(5), 2000)
    tx = transmission_extremes(fb)
    motion = circuit(fb, 2048, order=0)
    gamma = transmission_angle(fb, motion)
    ok = ~input_range(fb).never
    lo = np.nanmin(np.where(motion.valid, gamma, np.nan)[ok], axis=-1)
    hi = np.nanmax(np.where(motion.valid, gamma, np.nan)[ok], axis=-1)
    # Never exceeded by any sample, and approached to the grid's resolution.
    assert np.all(lo >= tx["min"][ok] - 1e-9)
    assert np.all(hi <= tx["max"][ok] + 1e-9)
    assert np.median(lo - tx["min"][ok]) < 1e-4
    assert np.median(tx["max"][ok] - hi) < 1e-4


def test_paper003_transmission_formulas_for_crank_rockers():
    # Paper 003: γmin = acos((L2² + L3² − (L4 − L1)²)/(2 L2 L3)), γmax with (L1 + L4).
    L1, L2, L3, L4 = 1.0, 5.0, 4.11, 3.5
    tx = transmission_extremes(FourBar(A0=[0, 0], B0=[L4, 0], crank=L1, coupler=L2, rocker=L3))
    assert tx["min"] == pytest.approx(math.acos((L2**2 + L3**2 - (L4 - L1) ** 2) / (2 * L2 * L3)))
    assert tx["max"] == pytest.approx(math.acos((L2**2 + L3**2 - (L4 + L1) ** 2) / (2 * L2 * L3)))
    assert tx["min_at"] == pytest.approx(0.0) and tx["max_at"] == pytest.approx(math.pi)


# --- classification ---------------------------------------------------------------------------


def test_classes_agree_with_motion():
    fb = random_fourbars(np.random.default_rng(11), 4000)
    cls = fourbar_class(fb)
    full = input_range(fb).full
    turns = output_extremes(fb)["turns"]
    assert np.all(full[cls == "crank-rocker"]) and not np.any(turns[cls == "crank-rocker"])
    assert np.all(full[cls == "double-crank"]) and np.all(turns[cls == "double-crank"])
    assert not np.any(full[(cls == "triple-rocker") | (cls == "double-rocker")])
    assert not np.any(full[cls == "rocker-crank"])
    assert {
        "crank-rocker",
        "double-crank",
        "triple-rocker",
        "double-rocker",
        "rocker-crank",
    } <= set(cls.tolist())


def test_change_point_is_classified():
    fb = FourBar(A0=[0, 0], B0=[4, 0], crank=2, coupler=4, rocker=2)  # 2 + 4 = 4 + 2
    assert str(fourbar_class(fb)) == "change-point"


# --- slider-crank ------------------------------------------------------------------------------


@settings(max_examples=40, deadline=None)
@given(
    crank=st.floats(0.1, 2.0),
    extra=st.floats(0.05, 3.0),
    offset=st.floats(-1.0, 1.0),
    angle=st.floats(-3.0, 3.0),
)
def test_slider_stroke_and_time_ratio_closed_form(crank, extra, offset, angle):
    rod = crank + abs(offset) + extra
    d = np.array([math.cos(angle), math.sin(angle)])
    n = np.array([-d[1], d[0]])
    sc = SliderCrank(
        A0=[0.3, -0.2],
        crank=crank,
        rod=rod,
        line_point=np.array([0.3, -0.2]) - offset * n,
        line_angle=angle,
    )
    assert str(slidercrank_class(sc)) == "crank-slider"
    out = analyze(sc)
    far = math.sqrt((rod + crank) ** 2 - offset**2)
    near = math.sqrt((rod - crank) ** 2 - offset**2)
    assert out["stroke"] == pytest.approx(far - near, rel=1e-9)
    # Extremes where crank and rod are collinear: θ = asin(−e/(r ± c)) (+π for the folded one).
    t_far = math.asin(-offset / (rod + crank))
    t_near = math.asin(-offset / (rod - crank)) + math.pi
    fwd = (t_near - t_far) % (2 * math.pi)
    assert out["time_ratio"] == pytest.approx(
        max(fwd, 2 * math.pi - fwd) / min(fwd, 2 * math.pi - fwd), rel=1e-7
    )


def test_rocker_slider_has_limits_and_no_coefficients():
    out = analyze(SliderCrank(A0=[0, 0], crank=2, rod=3, line_point=[0, -1.5]))
    assert out["class"] == "rocker-slider"
    # Limits where the rod stands perpendicular to the line: 1.5 + 2 sin θ = ±3.
    lo, hi = out["input_range_deg"]
    assert math.sin(math.radians(lo)) == pytest.approx(0.75) and math.sin(
        math.radians(hi)
    ) == pytest.approx(0.75)
    assert out["coefficients"]["K_omega"] is None


# --- the report ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "mech",
    [
        FourBar(A0=[0, 0], B0=[3.5, 0], crank=1, coupler=5, rocker=6.02, u=2.5, v=1.5),
        FourBar(A0=[0, 0], B0=[1, 0], crank=3.5, coupler=5, rocker=1),
        FourBar(A0=[1, 2], B0=[3, 4], crank=3, coupler=2, rocker=2.5, assembly=-1),
        FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3),
        SliderCrank(A0=[0, 0], crank=1, rod=3, line_point=[0, -0.5]),
        SliderCrank(A0=[0, 0], crank=1, rod=0.5, line_point=[0, -3]),
    ],
)
def test_report_is_strict_json_with_contract_keys(mech):
    out = analyze(mech)
    text = json.dumps(out, allow_nan=False)
    for key in (
        "class",
        "input_range_deg",
        "output_range_deg",
        "swing_deg",
        "transmission_angle_deg",
        "time_ratio",
        "coefficients",
    ):
        assert key in out
    assert set(out["coefficients"]) >= {"K_omega", "K_epsilon", "K_p", "delta"}
    assert {"min", "max"} <= set(out["transmission_angle_deg"])
    assert json.loads(text) == out


def test_report_angles_are_absolute_and_from_the_frame_line_under_their_own_names():
    # The same linkages, rotated by 40° and moved: the *_from_frame_deg angles and the figures
    # are unchanged, the absolute angles turn by 40°.
    r = np.radians(40)
    b0 = [3.5 * math.cos(r) + 1, 3.5 * math.sin(r) - 2]
    for crank, coupler, rocker in ((1, 5, 4.11), (3.5 * 3.5 / 4, 5 * 3.5 / 4, 3.5 / 4)):
        a = analyze(FourBar(A0=[0, 0], B0=[3.5, 0], crank=crank, coupler=coupler, rocker=rocker))
        b = analyze(FourBar(A0=[1, -2], B0=b0, crank=crank, coupler=coupler, rocker=rocker))
        assert b["reference_angle_deg"] == pytest.approx(40)
        for key in ("swing_deg", "time_ratio", "output_range_from_frame_deg",
                    "input_arcs_from_frame_deg", "limit_positions_from_frame_deg"):  # fmt: skip
            assert np.allclose(
                np.asarray(a[key], dtype=float),
                np.asarray(b[key], dtype=float),
                atol=1e-9,
                equal_nan=True,
            ), key
        for key in ("output_range_deg", "input_arcs_deg", "limit_positions_deg"):
            if a[key] is None:
                assert b[key] is None
                continue
            turned = (np.asarray(a[key], dtype=float) + 40 + 180) % 360 - 180
            assert np.allclose((np.asarray(b[key]) + 180) % 360 - 180, turned, atol=1e-9), key
