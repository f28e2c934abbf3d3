"""The drawing compiler (linkwright.io.sketch): a linkage drawn joint by joint → a document.

Degrees of freedom are held to hand counts of known mechanisms (Grübler–Kutzbach, worked out in
the comments). Compiled linkages are held to an independent solution: the named family with
the same dimensions (four-bar, slider-crank, geared five-bar, spherical four-bar), evaluated
through linkwright's normal API, and the link-length constraints themselves (every link keeps
its drawn lengths at every assembled input). Random four-bars in the plane and on the sphere
compile with their drawn pose and closure to 1e-9, or are refused as drawn at a dead point
where their dyad's links are in line; every bundled composed linkage draws and compiles back
to the same motion. Triads (a ternary link held by three binary links, a Stephenson III driven
at its output) are held to the ``stephenson3`` family configuration set by configuration set
(a triad's pose index depends on how the triad is written, so sets are compared), and random
triads, in the plane and on the sphere and drawn near where two poses merge, compile with their
drawn pose and closure or are refused as drawn at a dead point.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st
from sketch_helpers import (
    STEPHENSON,
    THETA,
    angle_of,
    assert_closure,
    compiled,
    drawn,
    drive,
    ground,
    pin,
    size_of,
    unit,
)
from triad_helpers import assert_same_configurations

from linkwright.io import document_to_dict, list_examples, load_example, parse_document
from linkwright.io.sketch import (
    MAX_DRIVERS,
    MAX_JOINTS,
    MAX_LINK_JOINTS,
    MAX_LINKS,
    STATUSES,
    SketchError,
    compile_sketch,
    sketch_of_document,
)
from linkwright.io.sketch_checks import degrees_of_freedom, read_sketch
from linkwright.mechanisms import (
    FourBar,
    GearedFiveBar,
    SliderCrank,
    SphericalFourBar,
    solve,
)

FOUR_BAR = {
    "joints": [
        ground("A0", 0, 0),
        pin("A", 0.6, 0.8),
        pin("B", 3.2, 2.1),
        ground("B0", 4, 0),
        pin("P", 1.5, 2.9),
    ],
    "links": [["A0", "A"], ["A", "B", "P"], ["B", "B0"]],
    "drivers": [drive("A0", "A")],
}

FIVE_BAR = {
    "joints": [
        ground("A0", 0, 0),
        pin("A", 1, 0.5),
        pin("C", 2.2, 2.6),
        pin("B", 4.5, 1),
        ground("B0", 4, 0),
    ],
    "links": [["A0", "A"], ["A", "C"], ["C", "B"], ["B", "B0"]],
    "drivers": [drive("A0", "A")],
}

SLIDER_CRANK = {
    "joints": [ground("A0", 0, 0), pin("A", 0.8, 0.6), pin("B", 3.5, -0.5, slider=10.0)],
    "links": [["A0", "A"], ["A", "B"]],
    "drivers": [drive("A0", "A")],
}

# Watt I: the ternary coupler A-B-C and the ternary rocker B0-B-D share B (Watt's chain: the two
# ternary links adjacent), and the dyad C-E-D closes the second loop.
WATT = {
    "joints": [
        ground("A0", 0, 0),
        pin("A", 1, 0.4),
        pin("B", 3.8, 2.2),
        ground("B0", 4.5, 0),
        pin("C", 2.0, 3.6),
        pin("D", 5.9, 2.0),
        pin("E", 4.6, 4.9),
    ],
    "links": [["A0", "A"], ["A", "B", "C"], ["B0", "B", "D"], ["C", "E"], ["D", "E"]],
    "drivers": [drive("A0", "A")],
}

SPHERE_FOUR_BAR_ARCS = np.radians([40.0, 20.0, 45.0, 35.0])  # paper 000's Fig. 6


def sphere_four_bar(theta0: float, assembly: float = 1.0) -> dict:
    """Paper 000's Fig. 6 four-bar drawn at the input ``theta0`` (its own frame and convention)."""
    fam = SphericalFourBar(*SPHERE_FOUR_BAR_ARCS, assembly=assembly)
    pos = solve(fam, [theta0]).positions
    at = {name: [float(x) for x in pos[name][0]] for name in ("A0", "B0", "A", "B")}
    return {
        "space": "sphere",
        "joints": [
            ground("A0", *at["A0"]),
            ground("B0", *at["B0"]),
            pin("A", *at["A"]),
            pin("B", *at["B"]),
        ],
        "links": [["A0", "A"], ["A", "B"], ["B", "B0"]],
        "drivers": [drive("A0", "A")],
    }


# --------------------------------------------------------------------------------------------
# Degrees of freedom against hand counts
# --------------------------------------------------------------------------------------------

JANSEN = sketch_of_document(document_to_dict(load_example("jansen-leg")))


@pytest.mark.parametrize(
    ("sketch", "hand"),
    [
        # 3 moving links, 4 pins: 3·3 − 2·4 = 1
        (FOUR_BAR, 1),
        # 4 moving links, 5 pins: 3·4 − 2·5 = 2
        (FIVE_BAR, 2),
        # the same, less one for the gear pair: 2 − 1 = 1
        (dict(FIVE_BAR, drivers=[drive("A0", "A"), drive("B0", "B", -1)]), 1),
        # Watt I: 5 moving links, 7 pins: 3·5 − 2·7 = 1
        (WATT, 1),
        # Stephenson: 5 moving links, 7 pins: 3·5 − 2·7 = 1
        (STEPHENSON, 1),
        # two links pinned to the ground and to each other, a triangle: 3·2 − 2·3 = 0
        (
            {"joints": [ground("A0", 0, 0), pin("C", 2, 2), ground("B0", 4, 0)],
             "links": [["A0", "C"], ["C", "B0"]]},
            0,
        ),
        # crank and rod (2 links, 2 pins), the pin on its guide (one more): 6 − 4 − 1 = 1
        (SLIDER_CRANK, 1),
        # Jansen's leg: 8 links with the frame, 10 pins: 3·7 − 2·10 = 1
        (JANSEN, 1),
        # a link floating free: 3 freedoms
        ({"joints": [pin("A", 0, 0), pin("B", 1, 0)], "links": [["A", "B"]]}, 3),
    ],
)  # fmt: skip
def test_degrees_of_freedom_match_hand_counts(sketch: dict, hand: int) -> None:
    drawing = read_sketch(sketch)
    assert drawing is not None
    assert degrees_of_freedom(drawing) == hand
    assert compile_sketch(sketch).dof == hand


def test_jansen_drawing_has_its_eight_links() -> None:
    # The leg's two rigid triangles B-C-D and E-F-G are one link each, the rest binary.
    assert sorted(map(sorted, JANSEN["links"])) == sorted(
        map(sorted, [["O", "A"], ["A", "C"], ["A", "E"], ["B", "C", "D"], ["B", "E"],
                     ["D", "F"], ["E", "F", "G"]])
    )  # fmt: skip


# --------------------------------------------------------------------------------------------
# Compiled linkages against the named families
# --------------------------------------------------------------------------------------------


def test_four_bar_moves_as_the_fourbar_family() -> None:
    report, mech = compiled(FOUR_BAR)
    assert report.document["mechanism"]["traced"] == ["P"]
    at = drawn(FOUR_BAR)
    A0, A, B, B0, P = (at[n] for n in ("A0", "A", "B", "B0", "P"))
    e = (B - A) / np.linalg.norm(B - A)
    u, v = float((P - A) @ e), float(e[0] * (P - A)[1] - e[1] * (P - A)[0])
    lengths = {"crank": np.linalg.norm(A - A0), "coupler": np.linalg.norm(B - A),
               "rocker": np.linalg.norm(B - B0)}  # fmt: skip
    phase = angle_of(A - A0)
    # The family's branch is the one that puts B where it was drawn.
    family = next(
        f
        for f in (FourBar(A0=A0, B0=B0, u=u, v=v, assembly=s, **lengths) for s in (1.0, -1.0))
        if np.allclose(solve(f, [phase]).positions["B"][0], B, atol=1e-12)
    )
    ours, theirs = solve(mech, THETA), solve(family, THETA + phase)
    np.testing.assert_array_equal(ours.valid, theirs.valid)
    for name in ("A", "B", "P"):
        np.testing.assert_allclose(ours.positions[name], theirs.positions[name], atol=1e-12)
    assert_closure(FOUR_BAR, mech)


def test_slider_crank_moves_as_the_slidercrank_family() -> None:
    report, mech = compiled(SLIDER_CRANK)
    joints = report.document["mechanism"]["joints"]
    guide = next(j for j in joints if j["name"] == "B_guide")
    assert guide == {"name": "B_guide", "type": "fixed", "at": [3.5, -0.5]}
    at = drawn(SLIDER_CRANK)
    phase = angle_of(at["A"] - at["A0"])
    family = next(
        f
        for f in (
            SliderCrank(A0=at["A0"], crank=1.0, rod=float(np.linalg.norm(at["B"] - at["A"])),
                        line_point=at["B"], line_angle=math.radians(10), assembly=s)
            for s in (1.0, -1.0)
        )
        if np.allclose(solve(f, [phase]).positions["B"][0], at["B"], atol=1e-12)
    )  # fmt: skip
    ours, theirs = solve(mech, THETA), solve(family, THETA + phase)
    np.testing.assert_array_equal(ours.valid, theirs.valid)
    np.testing.assert_allclose(ours.positions["B"], theirs.positions["B"], atol=1e-12)
    assert_closure(SLIDER_CRANK, mech)


def test_a_guide_through_a_ground_pivot_adds_none() -> None:
    on_line = {**SLIDER_CRANK, "joints": [*SLIDER_CRANK["joints"][:2], pin("B", 3.5, 0, slider=0)]}
    report, mech = compiled(on_line)
    rrp = next(j for j in report.document["mechanism"]["joints"] if j["type"] == "rrp")
    assert rrp["line_point"] == "A0" and len(report.document["mechanism"]["joints"]) == 3
    assert_closure(on_line, mech)


def test_watt_six_bar_keeps_its_ternary_links() -> None:
    report, mech = compiled(WATT)
    assert report.placement == {"A0": "ground", "A": "crank", "B": "dyad", "B0": "ground",
                                "C": "rigid", "D": "rigid", "E": "dyad"}  # fmt: skip
    ok = assert_closure(WATT, mech)
    assert ok.sum() > 10  # it moves
    # Its first loop is a four-bar A0-A-B-B0: the same as the family's.
    at = drawn(WATT)
    A0, A, B, B0 = (at[n] for n in ("A0", "A", "B", "B0"))
    phase = angle_of(A - A0)
    family = next(
        f
        for f in (
            FourBar(A0=A0, B0=B0, crank=np.linalg.norm(A - A0), coupler=np.linalg.norm(B - A),
                    rocker=np.linalg.norm(B - B0), assembly=s)
            for s in (1.0, -1.0)
        )
        if np.allclose(solve(f, [phase]).positions["B"][0], B, atol=1e-12)
    )  # fmt: skip
    ours, theirs = solve(mech, THETA), solve(family, THETA + phase)
    np.testing.assert_allclose(ours.positions["B"], theirs.positions["B"], atol=1e-12)


def test_stephenson_six_bar_compiles() -> None:
    _, mech = compiled(STEPHENSON)
    assert assert_closure(STEPHENSON, mech).sum() > 10


def test_geared_five_bar_moves_as_the_geared_family() -> None:
    geared = dict(FIVE_BAR, drivers=[drive("A0", "A"), drive("B0", "B", -1.5)])
    report, mech = compiled(geared)
    assert report.placement["B"] == "crank" and report.placement["C"] == "dyad"
    at = drawn(geared)
    A0, A, C, B, B0 = (at[n] for n in ("A0", "A", "C", "B", "B0"))
    phase1, phase2 = angle_of(A - A0), angle_of(B - B0)
    family = next(
        f
        for f in (
            GearedFiveBar(A0=A0, B0=B0, crank1=np.linalg.norm(A - A0),
                          crank2=np.linalg.norm(B - B0), link1=np.linalg.norm(C - A),
                          link2=np.linalg.norm(C - B), phase1=phase1, phase2=phase2,
                          ratio=-1.5, assembly=s)
            for s in (1.0, -1.0)
        )
        if np.allclose(solve(f, [phase1]).positions["C"][0], C, atol=1e-12)
    )  # fmt: skip
    ours, theirs = solve(mech, THETA), solve(family, THETA + phase1)
    np.testing.assert_array_equal(ours.valid, theirs.valid)
    for name in ("A", "B", "C"):
        np.testing.assert_allclose(ours.positions[name], theirs.positions[name], atol=1e-12)
    # The second crank turns at −1.5 times the input (a closed form of its own).
    ok = ours.valid
    assert ok.sum() > 10
    turned = np.array([angle_of(p - B0) for p in ours.positions["B"][ok]]) - phase2
    error = np.remainder(turned + 1.5 * THETA[ok] + np.pi, 2 * np.pi) - np.pi
    np.testing.assert_allclose(error, 0.0, atol=1e-12)
    assert_closure(geared, mech)


@pytest.mark.parametrize("theta0", [0.0, 0.7, -2.0])
def test_spherical_four_bar_moves_as_the_family(theta0: float) -> None:
    for assembly in (1.0, -1.0):
        sketch = sphere_four_bar(theta0, assembly)
        _, mech = compiled(sketch)
        family = SphericalFourBar(*SPHERE_FOUR_BAR_ARCS, assembly=assembly)
        ours, theirs = solve(mech, THETA), solve(family, THETA + theta0)
        np.testing.assert_array_equal(ours.valid, theirs.valid)
        for name in ("A", "B"):
            np.testing.assert_allclose(ours.positions[name], theirs.positions[name], atol=1e-12)
        assert_closure(sketch, mech)


# --------------------------------------------------------------------------------------------
# Random four-bars: closure and the drawn pose, or a dead point refused
# --------------------------------------------------------------------------------------------

coordinate = st.floats(-10.0, 10.0, allow_nan=False)
MARGIN = 1e-4
"""A dyad whose links meet at an angle with a sine over this compiles: rounding moves its joint
by about ε/sine of the drawing's size (at most 18 ε/sine measured), 4e-11 here. Nearer its dead
point it may be refused as drawn at one; if it compiles, it must be right (to 1e-9)."""
IN_LINE = 1e-9
"""Drawn this nearly in line (a share of the dyad's size), the sine is under 1e-5 and rounding
could move the joint by more than the 1e-9 of the drawing it is checked to: refused."""


def _sine_at(j: np.ndarray, p1: np.ndarray, p2: np.ndarray) -> float:
    u, v = p1 - j, p2 - j
    if u.size == 2:
        return abs(u[0] * v[1] - u[1] * v[0]) / (np.linalg.norm(u) * np.linalg.norm(v))
    return abs(float(np.dot(np.cross(p1, p2), j))) / (
        np.linalg.norm(np.cross(j, p1)) * np.linalg.norm(np.cross(j, p2))
    )


def _check_random(sketch: dict, sine: float, in_line: bool) -> None:
    """``sine``: of the angle B's links meet at (see MARGIN); ``in_line``: drawn in line."""
    report = compile_sketch(sketch)
    assert "\n" not in report.message
    if in_line:
        assert report.status == "unplaceable", report.message
    if report.status == "ok":
        assert_closure(sketch, parse_document(report.document).mechanism)
    else:
        assert report.status == "unplaceable", report.message
        # Near its dead point B may be placed, but so loosely (rounding over the sine) that the
        # coupler point P, carried out beyond A and B, is not: refused as drawn too far out.
        dead = "dead point" in report.message and "B" in report.message
        far = "P is drawn far out" in report.message
        assert dead or far, report.message
        assert sine <= MARGIN, report.message


@settings(max_examples=60, deadline=None)
@given(
    a0=st.tuples(coordinate, coordinate),
    b0=st.tuples(coordinate, coordinate),
    crank=st.floats(0.2, 5.0),
    phi=st.floats(-math.pi, math.pi),
    b=st.tuples(coordinate, coordinate),
    near=st.one_of(st.none(), st.floats(-1e-3, 1e-3), st.floats(-1e-8, 1e-8)),
    p=st.tuples(st.floats(-2.0, 2.0), st.floats(-2.0, 2.0)),
)
@example(a0=(0, 0), b0=(4, 0), crank=1.0, phi=0.0, b=(2, 0), near=0.0, p=(0.5, 0.5))
@example(a0=(0, 0), b0=(4, 0), crank=1.0, phi=0.0, b=(2, 0), near=1e-9, p=(0.5, 0.5))
def test_random_planar_four_bars(a0, b0, crank, phi, b, near, p) -> None:
    A0, B0 = np.array(a0), np.array(b0)
    A = A0 + crank * np.array([math.cos(phi), math.sin(phi)])
    B = np.array(b)
    if near is not None:  # B drawn nearly in line with A and B0: close to a dead point
        d = (B0 - A) / np.linalg.norm(B0 - A) if np.linalg.norm(B0 - A) > 0 else np.array([1, 0])
        B = A + 0.4 * (B0 - A) + near * np.linalg.norm(B0 - A) * np.array([-d[1], d[0]])
    size = max(np.abs(np.concatenate([A0, B0, A, B])).max(), 1.0)
    # Joints of one link (and the pivots) a clear share of the drawing apart.
    for x, y in ((A0, B0), (A, B), (B, B0), (A0, A)):
        assume(np.linalg.norm(x - y) > 1e-3 * size)
    e = (B - A) / np.linalg.norm(B - A)
    P = A + p[0] * (B - A) + p[1] * np.linalg.norm(B - A) * np.array([-e[1], e[0]])
    assume(min(np.linalg.norm(P - A), np.linalg.norm(P - B)) > 1e-3 * size)
    sketch = {
        "joints": [ground("A0", *A0), pin("A", *A), pin("B", *B), ground("B0", *B0),
                   pin("P", *P)],
        "links": [["A0", "A"], ["A", "B", "P"], ["B", "B0"]],
        "drivers": [drive("A0", "A")],
    }  # fmt: skip
    _check_random(sketch, _sine_at(B, A, B0), near is not None and abs(near) <= IN_LINE)


axis = st.tuples(*[st.floats(-1.0, 1.0)] * 3).filter(lambda v: np.linalg.norm(v) > 0.1)


@settings(max_examples=60, deadline=None)
@given(
    a0=axis,
    b0=axis,
    a=axis,
    b=axis,
    near=st.one_of(st.none(), st.floats(-1e-3, 1e-3), st.floats(-1e-8, 1e-8)),
)
@example(a0=(1, 0, 0), b0=(0, 1, 0), a=(1, 0.3, 0.2), b=(0.3, 0.9, 0.1), near=0.0)
def test_random_spherical_four_bars(a0, b0, a, b, near) -> None:
    A0, B0, A, B = (unit(v) for v in (a0, b0, a, b))
    if near is not None:  # B nearly on the great circle through A and B0: a dead point
        assume(np.linalg.norm(np.cross(A, B0)) > 1e-2)
        n = unit(np.cross(A, B0))
        B = unit(0.6 * A + 0.4 * B0 + near * n)
    arc = lambda x, y: math.degrees(math.acos(max(-1.0, min(1.0, float(x @ y)))))  # noqa: E731
    for x, y in ((A0, B0), (A0, A), (A, B), (B, B0)):
        assume(1.0 < arc(x, y) < 179.0)
    sketch = {
        "space": "sphere",
        "joints": [ground("A0", *A0), ground("B0", *B0), pin("A", *A), pin("B", *B)],
        "links": [["A0", "A"], ["A", "B"], ["B", "B0"]],
        "drivers": [drive("A0", "A")],
    }
    _check_random(sketch, _sine_at(B, A, B0), near is not None and abs(near) <= IN_LINE)


@pytest.mark.parametrize("space", ["plane", "sphere"])
def test_a_dyad_near_its_dead_point_compiles_exactly_or_is_refused(space: str) -> None:
    # A short rocker drawn nearly in line with the coupler: rounding moves B by about ε/sine,
    # so close to the dead point the compiler must refuse rather than misplace it.
    for sine in 10.0 ** -np.arange(2.0, 10.0, 0.5):
        if space == "plane":
            A0, A, B0 = np.array([0.0, 0]), np.array([1.0, 0]), np.array([10.0, 0])
            B = B0 + 0.02 * np.array([math.cos(sine), math.sin(sine)])
            sketch = {"joints": [ground("A0", *A0), pin("A", *A), pin("B", *B), ground("B0", *B0)]}
        else:
            A0, A, B0 = unit([1, 0, 0]), unit([1, 0.5, 0]), unit([0, 1, 0])
            B = unit(0.5 * A + 0.5 * B0 + sine * np.array([0, 0, 1.0]))
            sketch = {"space": "sphere", "joints": [ground("A0", *A0), pin("A", *A), pin("B", *B),
                                                    ground("B0", *B0)]}  # fmt: skip
        sketch.update(links=[["A0", "A"], ["A", "B"], ["B", "B0"]], drivers=[drive("A0", "A")])
        _check_random(sketch, _sine_at(B, A, B0), _sine_at(B, A, B0) < 1e-6)


def test_a_dyad_rounding_would_misplace_is_refused_not_compiled() -> None:
    # Its links meet at a sine of 2.8e-6: the engine puts B 1.1e-9 from where it is drawn, more
    # than the drawing is held to (a rule on the sine alone, at 1e-6, compiled it, and the check
    # of the drawn pose found the misplaced joint).
    sketch = {
        "space": "sphere",
        "joints": [ground("A0", -0.826, -0.554, 0.1), ground("B0", 0.251, -0.84, -0.481),
                   pin("A", 0.441, 0.849, 0.289),
                   pin("B", 0.8895869247258579, -0.25680080969095304, -0.37774124410614957)],
        "links": [["A0", "A"], ["A", "B"], ["B", "B0"]],
        "drivers": [drive("A0", "A")],
    }  # fmt: skip
    at = drawn(sketch)
    assert 2e-6 < _sine_at(at["B"], at["A"], at["B0"]) < 3e-6
    report = compile_sketch(sketch)
    assert report.status == "unplaceable" and "dead point" in report.message


# --------------------------------------------------------------------------------------------
# The way back: every composed linkage draws and compiles to the same motion
# --------------------------------------------------------------------------------------------

LINKAGE_EXAMPLES = [
    name for name in list_examples() if load_example(name).family == "linkage"
]  # fmt: skip


def _hinged(name: str) -> bool:
    joints = document_to_dict(load_example(name))["mechanism"]["joints"]
    return any(j["type"] == "hinge" for j in joints)


@pytest.mark.parametrize("name", LINKAGE_EXAMPLES)
def test_every_linkage_example_draws_and_compiles_back(name: str) -> None:
    doc = document_to_dict(load_example(name))
    if _hinged(name):
        with pytest.raises(SketchError, match="hinge") as refused:
            sketch_of_document(doc)
        assert "\n" not in str(refused.value)
        return
    sketch = sketch_of_document(doc)
    report, mech = compiled(sketch)
    original = load_example(name).mechanism
    ours, theirs = solve(mech, THETA), solve(original, THETA)
    np.testing.assert_array_equal(ours.valid, theirs.valid)
    tol = 1e-9 * size_of(sketch)
    for joint in original.reported_joints:
        np.testing.assert_allclose(ours.positions[joint], theirs.positions[joint], atol=tol)
    assert report.document["mechanism"]["traced"] == list(original.traced)
    assert_closure(sketch, mech)


def test_the_bundled_linkages_include_both_spaces_and_a_hinge() -> None:
    spaces = {load_example(n).mechanism.space for n in LINKAGE_EXAMPLES}
    assert spaces == {"plane", "sphere"}
    assert any(_hinged(n) for n in LINKAGE_EXAMPLES)


@pytest.mark.parametrize("name", sorted(set(list_examples()) - set(LINKAGE_EXAMPLES)))
def test_other_families_draw_or_say_why_not(name: str) -> None:
    doc = document_to_dict(load_example(name))
    try:
        sketch = sketch_of_document(doc)
    except SketchError as exc:
        message = str(exc)
        assert "\n" not in message and any(
            word in message for word in ("triad", "slider guide", "hinge")
        ), message
        return
    _, mech = compiled(sketch)
    original = load_example(name).mechanism
    if original.plan.triads:
        # A triad's pose index depends on how it is written: compare every configuration.
        joints = [j for j in original.reported_joints if j in mech.reported_joints]
        assert_same_configurations(mech, original, THETA, joints, 1e-9 * size_of(sketch))
    elif solve(original, [0.0]).valid[0]:
        ours, theirs = solve(mech, THETA), solve(original, THETA)
        np.testing.assert_array_equal(ours.valid, theirs.valid)
        tol = 1e-9 * size_of(sketch)
        for joint in ours.positions:
            if joint in theirs.positions:
                np.testing.assert_allclose(ours.positions[joint], theirs.positions[joint], atol=tol)
    assert_closure(sketch, mech)


def test_a_coupler_point_on_a_joint_is_that_joint() -> None:
    # Paper 003's drag link leaves its coupler point at A (arc 0): the drawing traces A.
    sketch = sketch_of_document(document_to_dict(load_example("paper003-table3-drag-link")))
    assert "P" not in [j["name"] for j in sketch["joints"]] and sketch["traced"] == ["A"]
    # The slider-crank's guide point sits on the crank pivot: one ground pivot is drawn.
    sketch = sketch_of_document(document_to_dict(load_example("slider-crank")))
    assert [j["name"] for j in sketch["joints"] if j.get("ground")] == ["A0"]


@pytest.mark.parametrize(
    ("name", "needle"),
    [("hinge-driven-fourbar", "hinge"), ("elliptic-trammel", "slider guide")],
)  # fmt: skip
def test_what_cannot_be_drawn_is_refused_in_one_line(name: str, needle: str) -> None:
    with pytest.raises(SketchError) as refused:
        sketch_of_document(document_to_dict(load_example(name)))
    message = str(refused.value)
    assert needle in message and "\n" not in message and "Traceback" not in message


def test_an_invalid_document_is_refused_in_one_line() -> None:
    with pytest.raises(SketchError, match="format"):
        sketch_of_document({"mechanism": {"family": "linkage"}})


# --------------------------------------------------------------------------------------------
# Every status: one line, naming what it is about
# --------------------------------------------------------------------------------------------

# Stephenson II (its ground the binary A0-G1) driven at the crank A0-A: the ternaries G1-X2-X3
# and A-Y2-Y3 each turn about a placed joint, joined by the binaries X2-Y2 and X3-Y3, a closed
# loop of four links with no joint placed (an Assur group of class IV): no dyad places a joint
# of it, and no link of it is a ternary held by three binaries (a triad).
STEPHENSON_II = {
    "joints": [ground("A0", 0, 0), pin("A", 1, 0.5), ground("G1", 5, 0), pin("X2", 4.5, 2),
               pin("X3", 6, 1.5), pin("Y2", 2.5, 3), pin("Y3", 2.8, 1.2)],
    "links": [["A0", "A"], ["G1", "X2", "X3"], ["A", "Y2", "Y3"], ["X2", "Y2"], ["X3", "Y3"]],
    "drivers": [drive("A0", "A")],
}  # fmt: skip

REDUNDANT_AND_LOOSE = {
    # A four-bar with a link A–B0 too many (−1) and a link B0–C hanging free (+1): 1 in all.
    "joints": [*FOUR_BAR["joints"][:4], pin("C", 5, 1)],
    "links": [["A0", "A"], ["A", "B"], ["B", "B0"], ["A", "B0"], ["B0", "C"]],
    "drivers": [drive("A0", "A")],
}

STATUS_CASES = [
    ("empty", {}, ("place",)),
    ("invalid", {"joints": [ground("A0", 0, 0)], "links": [["A0", "X"]]}, ("X",)),
    ("under", dict(FIVE_BAR), ("2 degrees of freedom", "C", "B")),
    ("under", {"joints": FOUR_BAR["joints"], "links": [["A0", "A"], ["A", "B", "P"]],
               "drivers": [drive("A0", "A")]}, ("B", "P", "not held")),
    ("under", {"joints": [*FOUR_BAR["joints"], pin("Q", 7, 7), pin("R", 8, 7)],
               "links": [*FOUR_BAR["links"], ["Q", "R"]], "drivers": [drive("A0", "A")]},
     ("Q–R", "not joined to the ground")),
    ("under", {"joints": [pin("A", 0, 0), pin("B", 1, 0)], "links": [["A", "B"]]},
     ("ground pivot",)),
    ("under", REDUNDANT_AND_LOOSE, ("C", "A–B0", "can still move")),
    ("over", {"joints": [ground("A0", 0, 0), pin("C", 2, 2), ground("B0", 4, 0)],
              "links": [["A0", "C"], ["C", "B0"]]}, ("0 degrees", "C–B0")),
    ("over", {"joints": [ground("A0", 0, 0)]}, ("only the ground pivot A0",)),
    ("over", dict(FOUR_BAR, links=[*FOUR_BAR["links"], ["A0", "B0"]]),
     ("A0–B0", "ground pivots")),
    ("over", dict(FOUR_BAR, drivers=[drive("A0", "A"), drive("B0", "B", 2)]),
     ("B0–B", "gear")),
    ("over", dict(FOUR_BAR, links=[*FOUR_BAR["links"], ["A", "B0"]]), ("A–B0", "locks")),
    ("no-driver", dict(FOUR_BAR, drivers=[]), ("A0–A", "driver")),
    ("unplaceable", {**FOUR_BAR, "joints": [ground("A0", 0, 0), pin("A", 1, 0), pin("B", 2, 0),
                                            ground("B0", 4, 0), pin("P", 1.5, 1)]},
     ("B", "A–B", "B–B0", "dead point")),
    ("unplaceable", {**SLIDER_CRANK, "joints": [ground("A0", 0, 0), pin("A", 0, 1),
                                                pin("B", 0, 4, slider=0.0)]},
     ("slider B", "A–B", "dead point")),
    ("unplaceable", STEPHENSON_II, ("triad", "class IV", "X2", "Y3", "G1–X2–X3")),
    ("unplaceable", {**sphere_four_bar(0.3), "joints": [ground("A0", 1, 0, 0), pin("A", 1, 1, 0)],
                     "links": [["A0", "A"]]}, ("second ground pivot", "A0")),
    ("ok", FOUR_BAR, ("A0–A", "ready")),
]  # fmt: skip


@pytest.mark.parametrize(("status", "sketch", "needles"), STATUS_CASES)
def test_each_status_says_what_it_is_about_in_one_line(
    status: str, sketch: dict, needles: tuple[str, ...]
) -> None:
    report = compile_sketch(sketch)
    assert report.status == status, report.message
    message = report.message
    assert "\n" not in message and "Traceback" not in message and "mechanism." not in message
    for needle in needles:
        assert needle in message, (needle, message)
    assert (report.document is not None) == (status == "ok")
    assert (report.dof is None) == (status in ("empty", "invalid"))
    as_json = report.as_json()
    assert set(as_json) == {"status", "dof", "message", "document", "placement", "joints", "links"}
    names = {j["name"] for j in sketch.get("joints", [])}
    assert set(report.joints) <= names and all(0 <= k < len(sketch["links"]) for k in report.links)


def test_every_status_is_met() -> None:
    assert {case[0] for case in STATUS_CASES} == set(STATUSES)


def _with(**parts: object) -> dict:
    return {**FOUR_BAR, **parts}


INVALID_CASES = [
    ([], ("table",)),
    (_with(joints=[*FOUR_BAR["joints"], pin("A", 9, 9)]), ("two joints are named A",)),
    (_with(links=[["A0", "A"], ["A", "A"], ["B", "B0"]]), ("link 2", "fewer than two")),
    (_with(joints=[pin("A0", 0, float("nan"), ground=True), *FOUR_BAR["joints"][1:]]),
     ("A0", "finite")),
    (_with(joints=[ground("A0", 0, 0, 0), *FOUR_BAR["joints"][1:]]), ("A0", "[x, y]")),
    (_with(joints=[ground("A0", 0, True), *FOUR_BAR["joints"][1:]]), ("A0", "number")),
    (_with(joints=[ground("A0", 2e12, 0), *FOUR_BAR["joints"][1:]]), ("A0", "working range")),
    ({**sphere_four_bar(0.0), "joints": [ground("A0", 0, 0, 0), *sphere_four_bar(0)["joints"][1:]]},
     ("A0", "centre")),
    ({**sphere_four_bar(0.0),
      "joints": [*sphere_four_bar(0)["joints"][:3], pin("B", 0, 1, 1, slider=0.0)]},
     ("B", "spherical")),
    (_with(drivers=[drive("A", "B")]), ("A", "not a ground pivot")),
    (_with(drivers=[drive("A0", "B0")]), ("B0", "ground pivot")),
    (_with(drivers=[drive("A0", "B")]), ("no link joins", "A0–B")),
    (_with(drivers=[drive("A0", "A", 0)]), ("ratio is 0",)),
    (_with(drivers=[drive("A0", "A", float("inf"))]), ("ratio", "finite")),
    (_with(joints=[*FOUR_BAR["joints"], pin("Q", 5, 5)]), ("joint Q is on no link",)),
    (_with(joints=[*FOUR_BAR["joints"][:4], pin("P", 0.6, 0.8)]), ("A and P", "same place")),
    (_with(joints=[*FOUR_BAR["joints"], ground("G", 4, 0)]), ("B0 and G", "same place")),
    (_with(joints=[*FOUR_BAR["joints"][:4], pin("P", 1, 2, ground=True, slider=3)]),
     ("P", "ground pivot and a slider")),
    (_with(traced=["Z"]), ("traced", "Z")),
    (_with(joints=[*FOUR_BAR["joints"][:4], pin("P\n", 1, 2)]), ("line break",)),
    (_with(colour="red"), ("colour",)),
    (_with(space="torus"), ("space", "torus")),
    (_with(joints=[*FOUR_BAR["joints"], {"at": [1, 1]}]), ("no name",)),
]  # fmt: skip


@pytest.mark.parametrize(("sketch", "needles"), INVALID_CASES)
def test_a_drawing_that_cannot_be_read_is_invalid(sketch: object, needles: tuple[str, ...]) -> None:
    report = compile_sketch(sketch)
    assert report.status == "invalid" and report.dof is None
    assert "\n" not in report.message
    for needle in needles:
        assert needle in report.message, (needle, report.message)


def _chain(n: int, sliders: int = 0) -> dict:
    """A drawing of ``n`` joints: two ground pivots and a chain of pins, ``sliders`` of them on
    guides through no ground pivot."""
    joints = [ground("G0", 0, 0), ground("G1", 1, 0)]
    joints += [pin(f"J{i}", i, 1 + (i < sliders), **({"slider": 0.0} if i < sliders else {}))
               for i in range(n - 2)]  # fmt: skip
    names = [j["name"] for j in joints]
    links = [[names[i], names[i + 1]] for i in range(1, n - 1)] + [["G0", names[2]]]
    return {"joints": joints, "links": links}


@pytest.mark.parametrize(
    ("sketch", "limit"),
    [
        (_chain(MAX_JOINTS + 1), MAX_JOINTS),
        (_chain(MAX_JOINTS - 1, sliders=2), MAX_JOINTS),
        ({**_chain(4), "links": [["G0", "J0"]] * (MAX_LINKS + 1)}, MAX_LINKS),
        (
            {**_chain(MAX_JOINTS), "links": [[f"J{i}" for i in range(MAX_LINK_JOINTS + 1)]]},
            MAX_LINK_JOINTS,
        ),
        ({**_chain(4), "drivers": [drive("G0", "J0")] * (MAX_DRIVERS + 1)}, MAX_DRIVERS),
    ],
)
def test_a_drawing_over_a_limit_is_invalid_naming_it(sketch: dict, limit: int) -> None:
    report = compile_sketch(sketch)
    assert report.status == "invalid" and f"at most {limit}" in report.message, report.message


def test_a_drawing_at_the_limits_is_read() -> None:
    assert compile_sketch(_chain(MAX_JOINTS)).status != "invalid"
    assert compile_sketch(_chain(MAX_JOINTS - 2, sliders=2)).status != "invalid"


def test_traced_defaults_to_the_coupler_points() -> None:
    report, _ = compiled(dict(FOUR_BAR, links=[["A0", "A"], ["A", "B"], ["B", "B0"], ["B", "P"],
                                               ["A", "P"]]))  # fmt: skip
    assert report.document["mechanism"]["traced"] == ["P"]  # no joint on one link: the last
    report, _ = compiled(SLIDER_CRANK)
    assert report.document["mechanism"]["traced"] == ["B"]
    report, _ = compiled(dict(FOUR_BAR, traced=["B", "P", "B"]))
    assert report.document["mechanism"]["traced"] == ["B", "P"]


def test_a_guide_name_never_clashes() -> None:
    taken = {**SLIDER_CRANK, "joints": [*SLIDER_CRANK["joints"], ground("B_guide", -3, -3)]}
    report, mech = compiled(taken)
    rrp = next(j for j in report.document["mechanism"]["joints"] if j["type"] == "rrp")
    assert rrp["line_point"] == "guide1"
    assert_closure(taken, mech)
