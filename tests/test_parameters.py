"""The named parameter vector of every plan: round trips, the symmetries it forgets, its bounds.

Independent checks: a normalised (or moved) linkage is compared with the original by a
least-squares similarity fitted to their traced points (Umeyama/Procrustes, written here), not
by the transform the module applied; the kinds are checked by what a similarity does to every
plan parameter (the engine's own numbers).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from linkwright.io.documents import list_examples, load_example
from linkwright.mechanisms import FAMILIES, solve
from linkwright.mechanisms.parameters import (
    KINDS,
    ParameterError,
    decode,
    encode,
    family_template,
    parameter_vector,
)

EXAMPLES = list_examples()


def _example(name: str):
    return load_example(name).mechanism


def _similarity_residual(a: np.ndarray, b: np.ndarray) -> float:
    """Largest distance left after the least-squares similarity of points a onto b (plane:
    complex least squares; sphere: the Kabsch rotation), pair by pair."""
    if a.shape[-1] == 2:
        za, zb = a[:, 0] + 1j * a[:, 1], b[:, 0] + 1j * b[:, 1]
        da, db = za - za.mean(), zb - zb.mean()
        w = np.sum(np.conj(da) * db) / np.sum(np.abs(da) ** 2)
        return float(np.max(np.abs(w * da - db)))
    u, _, vt = np.linalg.svd(b.T @ a)
    R = u @ np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))]) @ vt
    return float(np.max(np.linalg.norm(a @ R.T - b, axis=1)))


def test_every_family_has_a_vector_and_every_bundled_example_covers_them():
    covered = {_example(name).family for name in EXAMPLES}
    assert covered == set(FAMILIES)
    for name, cls in FAMILIES.items():
        if name == "linkage":
            with pytest.raises(ParameterError, match="give the linkage itself"):
                parameter_vector(name)
            continue
        vector = parameter_vector(cls)
        assert set(vector.kinds) <= set(KINDS) and len(vector) > 0
        assert vector == parameter_vector(name)


@pytest.mark.parametrize("name", EXAMPLES)
def test_round_trip_gives_the_mechanism_back(name):
    m = _example(name)
    vector = parameter_vector(m)
    x = vector.to_vector(m)
    assert x.shape == (len(vector),)
    assert vector.from_vector(m, x) == m
    # A batch: each row its own mechanism.
    moves = np.array(vector.kinds) != "ratio"
    rows = x + np.outer([0.0, 1e-3, 2e-3], np.ones(len(x))) * moves
    batch = vector.from_vector(m, rows)
    # Exact but for a spherical axis, which goes through its unit vector (rounding only).
    np.testing.assert_allclose(vector.to_vector(batch), rows, rtol=0, atol=1e-15)
    assert batch[0] == m


@pytest.mark.parametrize("name", EXAMPLES)
def test_the_normalised_vector_lies_in_its_bounds_and_limits(name):
    m = _example(name)
    vector = parameter_vector(m)
    x = vector.to_vector(vector.normalise(m))
    lo, hi = vector.bounds()
    low, high = vector.limits()
    outside = [n for n, v, a, b in zip(vector.names, x, lo, hi, strict=True) if not a <= v <= b]
    assert outside == []
    assert np.all((low <= x) & (x <= high))


@pytest.mark.parametrize("name", EXAMPLES)
def test_normalise_keeps_the_curve_up_to_the_symmetry(name):
    m = _example(name)
    vector = parameter_vector(m)
    n = vector.normalise(m)
    joint = m.traced_joint
    if vector.in_family_frame:
        assert n is m  # a named spherical family stands in its paper's frame already
        return
    theta = np.linspace(-np.pi, np.pi, 97)
    if vector.space == "plane":
        base, angle, size = vector.frame(n)
        np.testing.assert_allclose(base, 0.0, atol=1e-12)
        assert abs(float(angle)) <= 1e-12 and abs(float(size) - 1.0) <= 1e-12
        shift = vector.input_turn * -float(vector.frame(m)[1])
    else:
        shift = 0.0
    if m.plan.triads:
        return  # its circuits are compared, descriptor by descriptor, in the test below
    a = solve(m, theta, order=0).positions[joint]
    b = solve(n, theta + shift, order=0).positions[joint]
    ok = np.isfinite(a).all(axis=1)
    assert np.array_equal(ok, np.isfinite(b).all(axis=1)) and ok.sum() >= 3
    assert _similarity_residual(a[ok], b[ok]) <= 1e-9 * max(1.0, float(np.max(np.abs(b[ok]))))


@pytest.mark.parametrize("name", EXAMPLES)
def test_normalise_keeps_the_closed_curves_descriptors(name):
    """A second, correspondence-free check: the whole circuit's Fourier descriptors (which
    forget position, turn, scale and start) are the same before and after."""
    from linkwright.curves import descriptors, sphere_descriptors
    from linkwright.mechanisms import circuits

    m = _example(name)
    vector = parameter_vector(m)
    if vector.in_family_frame:
        pytest.skip("a named spherical family stands in its paper's frame: nothing to fix")
    joint = m.traced_joint
    # Every circuit (a linkage with a triad has several, one per branch of motion): the same
    # set of closed curves, so the same set of descriptors.
    a = [mo.positions[joint] for mo in circuits(m, 512, order=0)[1]]
    b = [mo.positions[joint] for mo in circuits(vector.normalise(m), 512, order=0)[1]]
    assert len(a) == len(b) >= 1
    describe = descriptors if a[0].shape[-1] == 2 else sphere_descriptors
    da = np.array(sorted(describe(c).round(6).tolist() for c in a))
    db = np.array(sorted(describe(c).round(6).tolist() for c in b))
    np.testing.assert_allclose(da, db, atol=1e-5)


PLANAR = [n for n in EXAMPLES if parameter_vector(_example(n)).space == "plane"]


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    name=st.sampled_from(PLANAR),
    scale=st.floats(0.05, 20.0),
    angle=st.floats(-np.pi, np.pi),
    shift=st.tuples(st.floats(-50.0, 50.0), st.floats(-50.0, 50.0)),
)
def test_a_similarity_of_the_fields_is_a_similarity_of_the_motion(name, scale, angle, shift):
    """transformed() turns the fields; the engine then traces s·R·P + t at the input shifted by
    input_turn·angle. Tolerance: 1e-9 of the moved linkage's size (the positions' rounding)."""
    m = _example(name)
    vector = parameter_vector(m)
    moved = vector.transformed(m, scale, angle, shift)
    theta = np.linspace(-np.pi, np.pi, 41)
    c, s = np.cos(angle), np.sin(angle)
    for joint in m.reported_joints:
        if m.plan.triads:
            break
        p = solve(m, theta, order=0).positions[joint]
        q = solve(moved, theta + vector.input_turn * angle, order=0).positions[joint]
        want = scale * np.stack((c * p[:, 0] - s * p[:, 1], s * p[:, 0] + c * p[:, 1]), -1)
        want = want + np.asarray(shift)
        ok = np.isfinite(p).all(axis=1)
        size = max(1.0, float(np.max(np.abs(want[ok]))) if ok.any() else 1.0)
        assert np.array_equal(ok, np.isfinite(q).all(axis=1))
        np.testing.assert_allclose(q[ok], want[ok], atol=1e-9 * size)


def test_the_kinds_follow_the_plan_not_a_list():
    """Fields the plan reads only through params() get the kind of what they move."""
    ds = parameter_vector("doubleslider")
    assert [ds.parameter(n).kind for n in ("alpha", "beta", "p", "q", "h")] == [
        "angle", "angle", "coordinate", "coordinate", "coordinate",
    ]  # fmt: skip
    # alpha is the angle between the guides (it stays when the trammel turns); beta is a
    # direction (it turns with it), the reference normalise() turns to 0.
    assert (ds.parameter("alpha").turns, ds.parameter("beta").turns) == (0.0, 1.0)
    assert ds.reference == ("direction", "beta")
    five = parameter_vector("geared-fivebar")
    assert five.parameter("phase1").turns == five.parameter("phase2").turns == 1.0
    assert five.parameter("ratio").kind == "ratio"
    sc = parameter_vector("slidercrank")
    assert sc.reference == ("direction", "line_angle")
    six = parameter_vector("spherical-sixbar")
    assert six.parameter("ground_angle").kind == "angle" and six.in_family_frame
    fg = parameter_vector(_example("paper001-fg"))
    assert "pose" in fg.discrete and "input" in fg.discrete
    jansen = parameter_vector(_example("jansen-leg"))
    assert jansen.parameter("C.r1").kind == "length" and "C.assembly" in jansen.discrete


def test_a_spherical_linkage_is_turned_into_paper_000s_frame():
    m = _example("paper000-fig6-linkage")
    vector = parameter_vector(m)
    rng = np.random.default_rng(4)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    R = q * np.sign(np.linalg.det(q))
    turned = vector.rotated(m, R)
    theta = np.linspace(0, 2 * np.pi, 50)
    a = solve(m, theta, order=0).positions["P"]
    b = solve(turned, theta, order=0).positions["P"]
    np.testing.assert_allclose(b, a @ R.T, atol=1e-12)
    n = vector.normalise(turned)
    x = vector.to_vector(n)
    assert abs(x[vector.index("A0.lon")]) < 1e-12 and abs(x[vector.index("A0.lat")]) < 1e-12
    assert abs(x[vector.index("B0.lat")]) < 1e-12 and x[vector.index("B0.lon")] > 0
    assert _similarity_residual(solve(n, theta, order=0).positions["P"], a) <= 1e-12


def test_encoded_templates_come_back_equal():
    import json

    for name in EXAMPLES:
        m = _example(name)
        assert decode(json.loads(json.dumps(encode(m)))) == m
    for family in FAMILIES:
        if family != "linkage":
            assert family_template(family).family == family


def test_bad_input_is_one_line():
    m = _example("crank-rocker")
    vector = parameter_vector(m)
    cases = [
        (lambda: vector.from_vector(m, [1.0, 2.0]), "a parameter vector has 9 numbers"),
        (lambda: parameter_vector("four-bar"), "family: unknown 'four-bar'"),
        (lambda: family_template("linkage"), "give a document of family linkage"),
        (lambda: vector.to_vector(_example("slider-crank")), "does not fit"),
        (lambda: vector.index("crank_length"), "no parameter 'crank_length'"),
        (lambda: vector.from_vector(m, vector.to_vector(m), {"pose": 1}), "not a discrete"),
    ]
    for call, words in cases:
        with pytest.raises(ParameterError) as info:
            call()
        assert words in str(info.value) and "\n" not in str(info.value)
