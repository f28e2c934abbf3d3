"""The drawing compiler places triads (issue 24 point 1): a ternary link held by three binary
links from placed joints, whose three joints no dyad can place one at a time.

A drawn Stephenson III driven at its output compiles to a triad and has the configurations of
the ``stephenson3`` family driven at its output with the drawing's dimensions (compared as sets:
a triad's pose index depends on how the triad is written). Random drawn triads, in the plane and
on the sphere, compile with every joint where it was drawn and every link's lengths kept along
the motion (to the compiler's 1e-9 of the drawing's size), or, drawn near where two poses merge,
are refused as drawn at a dead point; the least closure compiled is held to the measured rounding
(:data:`linkwright.io.sketch_place.TRIAD_ROUNDING`). Paper 001's mechanism driven at FG and the
Stephenson III driven at its output draw (``sketch_of_document``) and compile back to the same
configurations.
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from sketch_helpers import (
    STEPHENSON,
    THETA,
    angle_of,
    assert_closure,
    compiled,
    drawn,
    drive,
    pin,
    size_of,
    unit,
)
from triad_helpers import assert_same_configurations, configuration_sets

from linkwright.engine.triad_steps import triad_closure
from linkwright.io import document_to_dict, load_example, parse_document
from linkwright.io.sketch import compile_sketch, sketch_of_document
from linkwright.io.sketch_place import PRECISION, TRIAD_ROUNDING
from linkwright.mechanisms import Stephenson3, solve

coordinate = st.floats(-10.0, 10.0, allow_nan=False)
axis = st.tuples(*[st.floats(-1.0, 1.0)] * 3).filter(lambda v: np.linalg.norm(v) > 0.1)


def test_stephenson_six_bar_driven_at_its_output_is_a_triad() -> None:
    # Driven at D0-D, the coupler A-B-C is held by A0-A, B0-B and D-C: a triad.
    output = dict(STEPHENSON, drivers=[drive("D0", "D")])
    report, mech = compiled(output)
    assert {n: report.placement[n] for n in "ABC"} == dict.fromkeys("ABC", "triad")
    (triad,) = [j for j in report.document["mechanism"]["joints"] if j["type"] == "triad"]
    assert {triad["name"], triad["j2"], triad["j3"]} == {"A", "B", "C"}
    # A pose index names one pose at each input (the tracer follows a circuit, not the index):
    # it holds where that slot is real, which here is around the drawn pose.
    ok = assert_closure(output, mech)
    assert ok[0] and ok.sum() >= 5
    # The family driven at its output, with the drawing's dimensions: the same configurations.
    at = drawn(output)
    A0, A, B, B0, C, D, D0 = (at[n] for n in ("A0", "A", "B", "B0", "C", "D", "D0"))
    e = (B - A) / np.linalg.norm(B - A)
    family = Stephenson3(
        A0=A0, B0=B0, D0=D0, crank=np.linalg.norm(A - A0), coupler=np.linalg.norm(B - A),
        rocker=np.linalg.norm(B - B0), u1=float((C - A) @ e),
        v1=float(e[0] * (C - A)[1] - e[1] * (C - A)[0]), link1=np.linalg.norm(D - C),
        link2=np.linalg.norm(D - D0), input="output",
    )  # fmt: skip
    joints = ("A", "B", "C", "D")
    shift = angle_of(D - D0)
    assert_same_configurations(mech, family, THETA, joints, 1e-9 * size_of(output), shift=shift)


# --------------------------------------------------------------------------------------------
# Random triads: closure and the drawn pose, or a pose drawn where two merge refused
# --------------------------------------------------------------------------------------------

TRIAD_LINKS = [["D0", "D"], ["K1", "A"], ["K2", "B"], ["D", "C"], ["A", "B", "C"]]
"""A ternary A-B-C held by links from the ground pivots K1 and K2 and from the crank's D."""

LEAST_CLOSURE = 1e-4
"""A triad whose closure (the relative determinant of its constraints) is over this compiles:
rounding moves its joints by about 180 ε/closure of the drawing's size, 4e-10 here (at most
69 ε/closure measured). Nearer a merge it may be refused; if it compiles, it must be right."""


def _triad_closure(sketch: dict) -> float:
    at = drawn(sketch)
    joints = np.stack([at[n] for n in "ABC"])
    anchors = np.stack([at[n] for n in ("K1", "K2", "D")])
    if joints.shape[-1] == 2:
        lengths = np.linalg.norm(joints - anchors, axis=-1)
    else:
        lengths = np.arccos(np.clip(np.sum(joints * anchors, axis=-1), -1, 1))
    return abs(float(triad_closure(joints, anchors, lengths, "plane" if joints.shape[-1] == 2
                                   else "sphere")))  # fmt: skip


def _triad_sketch(space: str, points: dict[str, np.ndarray]) -> dict:
    grounds = ("K1", "K2", "D0")
    return {
        "space": space,
        "joints": [pin(n, *map(float, p), **({"ground": True} if n in grounds else {}))
                   for n, p in points.items()],
        "links": TRIAD_LINKS,
        "drivers": [drive("D0", "D")],
    }  # fmt: skip


def _check_random_triad(sketch: dict) -> None:
    report = compile_sketch(sketch)
    assert "\n" not in report.message
    assume(report.status != "invalid")  # joints of one link drawn too close together
    closure = _triad_closure(sketch)
    if report.status == "ok":
        assert report.placement["A"] == "triad"
        assert_closure(sketch, parse_document(report.document).mechanism)
    else:
        assert report.status == "unplaceable", report.message
        if "not found in its drawn pose" in report.message:
            # The solvers' own rounding, beyond what the closure foresees: the compiler checks
            # the pose it would write and refuses in a line rather than write a wrong one (a
            # fresh run met one such spherical triad, not reproduced in 30,000 draws since).
            return
        assert "poses merge" in report.message, report.message
        assert closure <= LEAST_CLOSURE * 10, (closure, report.message)


plane_point = st.tuples(coordinate, coordinate).map(np.array)


@settings(max_examples=40, deadline=None)
@given(points=st.fixed_dictionaries({n: plane_point for n in ("K1", "K2", "D0", "D", "A", "B",
                                                                "C")}))  # fmt: skip
def test_random_planar_triads(points: dict[str, np.ndarray]) -> None:
    size = max(float(np.abs(np.stack(list(points.values()))).max()), 1.0)
    for link in TRIAD_LINKS:
        for i, a in enumerate(link):
            for b in link[i + 1 :]:
                assume(np.linalg.norm(points[a] - points[b]) > 1e-2 * size)
    _check_random_triad(_triad_sketch("plane", points))


@settings(max_examples=40, deadline=None)
@given(points=st.fixed_dictionaries({n: axis.map(unit) for n in ("K1", "K2", "D0", "D", "A",
                                                                   "B", "C")}))  # fmt: skip
def test_random_spherical_triads(points: dict[str, np.ndarray]) -> None:
    for link in TRIAD_LINKS:
        for i, a in enumerate(link):
            for b in link[i + 1 :]:
                arc = math.degrees(math.acos(max(-1.0, min(1.0, float(points[a] @ points[b])))))
                assume(2.0 < arc < 178.0)
    _check_random_triad(_triad_sketch("sphere", points))


def _turned(v: np.ndarray, angle: float, axis3: np.ndarray | None = None) -> np.ndarray:
    """``v`` turned by ``angle``: in the plane about the origin, on the sphere about ``axis3``."""
    if axis3 is None:
        c, s = math.cos(angle), math.sin(angle)
        return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])
    k = unit(axis3)
    return (
        v * math.cos(angle) + np.cross(k, v) * math.sin(angle) + k * (k @ v) * (1 - math.cos(angle))
    )


@settings(max_examples=40, deadline=None)
@given(
    space=st.sampled_from(["plane", "sphere"]),
    seed=st.integers(0, 2**32 - 1),
    off=st.floats(-7.0, -1.0),
    sides=st.tuples(*[st.sampled_from([-1.0, 1.0])] * 3),
)
def test_triads_drawn_near_a_merge_compile_exactly_or_are_refused(space, seed, off, sides):
    # Two poses merge where the three links' lines meet at one point (on the sphere: their
    # great circles pass through one point); one link turned by 10^off off that point puts the
    # drawn pose a closure of about that far from a merge.
    rng = np.random.default_rng(seed)
    if space == "plane":
        body, meet = rng.uniform(-3, 3, (3, 2)), rng.uniform(-3, 3, 2)
        ways = [unit(body[k] - meet) for k in range(3)]
        ways[0] = _turned(ways[0], 10.0**off)
    else:
        body = np.array([unit(rng.normal(size=3)) for _ in range(3)])
        meet = unit(rng.normal(size=3))
        normals = [unit(np.cross(body[k], meet)) for k in range(3)]
        normals[0] = _turned(normals[0], 10.0**off, body[0])
    anchors = []
    for k in range(3):
        reach = sides[k] * rng.uniform(0.5, 1.5)
        if space == "plane":
            anchors.append(body[k] + 2 * reach * ways[k])
        else:
            anchors.append(_turned(body[k], reach, normals[k]))
    pivot = anchors[2] + 0.5 * rng.normal(size=anchors[2].size)
    if space == "sphere":
        pivot = unit(pivot)
    points = dict(zip(("K1", "K2", "D", "A", "B", "C"), [*anchors, *body], strict=True))
    points["D0"] = pivot
    sketch = _triad_sketch(space, points)
    report = compile_sketch(sketch)
    assume(report.status != "invalid")
    closure = _triad_closure(sketch)
    if closure > 10 * LEAST_CLOSURE:
        assert report.status == "ok", (closure, report.message)
    _check_random_triad(sketch)


def test_a_triad_its_solver_loses_is_refused_in_a_line_not_raised() -> None:
    # Each joint of the ternary drawn on another's anchor (A on D, B on K1, C on K2): the
    # spherical solver's circles for J1 coincide in every order of the joints, and it misses
    # the drawn pose (the compiler raised SketchBug, its "misplaced joint" error, before).
    a, b, c, d0 = [0.375, 0.897, 0.236], [0.306, 0.632, -0.712], [-0.208, 0.444, 0.871], [
        0.266, 0.959, 0.1]  # fmt: skip
    points = {n: np.array(v) for n, v in zip(("A", "B", "C", "D0"), (a, b, c, d0), strict=True)}
    points.update(K1=points["B"], K2=points["C"], D=points["A"])
    report = compile_sketch(_triad_sketch("sphere", points))
    assert report.status == "unplaceable", report.message
    assert "triad A–B–C is not found in its drawn pose" in report.message
    assert set(report.joints) == {"A", "B", "C"} and "\n" not in report.message


# --------------------------------------------------------------------------------------------
# The way back: triad families draw and compile to the same configurations
# --------------------------------------------------------------------------------------------


def test_the_least_closure_compiled_is_where_rounding_stays_within_the_precision() -> None:
    # 180 ε over a closure of 1e-4 is 4e-10 of the size: the placement's precision.
    assert math.isclose(
        TRIAD_ROUNDING * np.finfo(float).eps / LEAST_CLOSURE, PRECISION, rel_tol=0.01
    )


def test_stephenson3_driven_at_its_output_draws_and_compiles_back() -> None:
    original = load_example("stephenson3-output").mechanism
    sketch = sketch_of_document(document_to_dict(load_example("stephenson3-output")))
    assert sorted(map(sorted, sketch["links"])) == sorted(
        map(sorted, [["D0", "D"], ["A0", "A"], ["B0", "B"], ["D", "C", "P"], ["A", "B", "C"]])
    )
    assert sketch["drivers"] == [{"pivot": "D0", "joint": "D", "ratio": 1.0}]
    report, mech = compiled(sketch)
    assert {n: report.placement[n] for n in "ABC"} == dict.fromkeys("ABC", "triad")
    # The drawing is the document's pose at θ = 0, and the same mechanism everywhere else.
    at = solve(original, [0.0]).positions
    for name, p in drawn(sketch).items():
        assert np.linalg.norm(at[name][0] - p) <= 1e-9 * size_of(sketch)
    joints = ("A", "B", "C", "D", "P")
    assert_same_configurations(mech, original, THETA, joints, 1e-9 * size_of(sketch))
    assert_closure(sketch, mech)


def test_paper001_fg_draws_and_compiles_back() -> None:
    original = load_example("paper001-fg").mechanism
    sketch = sketch_of_document(document_to_dict(load_example("paper001-fg")))
    assert sketch["space"] == "sphere"
    assert ["C", "B", "E"] in sketch["links"] and sketch["drivers"][0]["joint"] == "F"
    report, mech = compiled(sketch)
    assert {n: report.placement[n] for n in "BCE"} == dict.fromkeys("BCE", "triad")
    (triad,) = [j for j in report.document["mechanism"]["joints"] if j["type"] == "triad"]
    assert 0 <= triad["pose"] <= 7
    assert_same_configurations(mech, original, THETA, ("B", "C", "E", "F"), 1e-9)
    counts = [len(x) for x in configuration_sets(mech, np.radians([-90, 0, 120]), ("B",))]
    # θ = 0 of the drawing is the document's θ6 = 0: issue 21's counts at the same inputs.
    assert counts == [8, 4, 6]
    assert_closure(sketch, mech)
