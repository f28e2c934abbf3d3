"""Triads in composed linkages (``type = "triad"``: TriadJoint, SphereTriadJoint; issue 21).

The Stephenson III six-bar driven at its output, written joint by joint, is held to a second
construction and a second method: the ``stephenson3`` family's own plan (configuration by
configuration; and, written from another joint of its ternary link, whose poses are numbered
otherwise, configuration set by configuration set), and the crank-driven Stephenson III, whose
four-bar and dyad place the same joints by circles alone, at every crank angle that puts the
output link at the input (bracketed on a grid, then Brent's method to the last bits). Paper
001's spherical Stephenson III driven at FG likewise, against the family driven at FG and
driven at AB, with issue 21's counts of 8, 4 and 6 configurations. Constraint residuals are
measured on the positions, derivatives against central differences, and the document form, the
checks and the verbs are exercised.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import brentq
from triad_helpers import assert_same_configurations, configuration_sets

from linkwright.cli import main
from linkwright.geometry import sphere
from linkwright.io import document_to_dict, load_example, parse_document
from linkwright.io.document_schema import DocumentError
from linkwright.io.documents import mechanism_to_dict
from linkwright.io.toml_writer import dumps_toml
from linkwright.mechanisms import (
    SphericalStephenson3,
    Stephenson3,
    circuits,
    configurations,
    solve,
)
from linkwright.mechanisms.linkage import (
    CrankJoint,
    DyadJoint,
    FixedJoint,
    InvalidLinkage,
    Linkage,
    RigidJoint,
    SphereCrankJoint,
    SphereTriadJoint,
    TriadJoint,
)

TURN = np.radians(np.arange(-180.0, 180.0, 2.0))
PLANE_JOINTS = ("A", "B", "C", "D", "P")
SPHERE_JOINTS = ("B", "C", "E", "F")

# --------------------------------------------------------------------------------------------
# The planar Stephenson III driven at its output (src/linkwright/examples/stephenson3-output)
# --------------------------------------------------------------------------------------------

FAMILY = load_example("stephenson3-output").mechanism
SIZE = 4.0  # its largest length (the coupler AB) and coordinate (B0)
GROUND = (FixedJoint("A0", [0.0, 0.0]), FixedJoint("B0", [4.0, 0.0]), FixedJoint("D0", [0.0, 2.8]))
OUTPUT = CrankJoint("D", "D0", 1.0)
POINT = RigidJoint("P", "C", "D", 0.35, 0.5)


def as_linkage() -> Linkage:
    """The example joint by joint, its ternary ABC written from A as the family writes it."""
    triad = TriadJoint("A", "B", "C", "A0", 1.0, "B0", 3.0, "D", 0.7, side=4.0, u=2.0, v=2.0)
    return Linkage(joints=(*GROUND, OUTPUT, triad, POINT), traced="P")


def from_c() -> Linkage:
    """The same ternary written from C towards A: on the family's frame A = (0, 0), B = (4, 0),
    C = (2, 2), so |CA| = √8 and B sits at (0, √8) in the frame of C→A (by hand: C→A is
    (−1, −1)/√2, B − C = (2, −2))."""
    root8 = math.sqrt(8.0)
    triad = TriadJoint("C", "A", "B", "D", 0.7, "A0", 1.0, "B0", 3.0, side=root8, u=0.0, v=root8)
    return Linkage(joints=(*GROUND, OUTPUT, triad, POINT), traced="P")


def test_written_as_the_family_writes_it_every_configuration_is_the_familys() -> None:
    ours = configuration_sets(as_linkage(), TURN, PLANE_JOINTS)
    theirs = configuration_sets(FAMILY, TURN, PLANE_JOINTS)
    for x, y in zip(ours, theirs, strict=True):
        assert x.shape == y.shape
        np.testing.assert_allclose(x, y, atol=1e-10 * SIZE, rtol=0)
    # Two configurations at every output angle (the example's own comment): D on either side.
    assert {len(x) for x in ours} == {2}


def test_written_from_another_joint_it_has_the_same_configurations() -> None:
    compared = assert_same_configurations(from_c(), FAMILY, TURN, PLANE_JOINTS, 1e-10 * SIZE)
    assert compared == 2 * TURN.size


def _crank_driven_roots(psi: float) -> list[dict[str, np.ndarray]]:
    """Every configuration of the crank-driven Stephenson III with its output D0D at ``psi``:
    on each of its four branches, the crank angles where D − D0 points at ``psi``."""
    grid = np.linspace(-np.pi, np.pi, 1441)
    found = []
    for assembly in (1.0, -1.0):
        for assembly2 in (1.0, -1.0):
            crank = replace(FAMILY, input="crank", assembly=assembly, assembly2=assembly2)

            def miss(theta: float, crank: Stephenson3 = crank) -> float:
                d = solve(crank, [theta], order=0).positions["D"][0] - np.array([0.0, 2.8])
                return math.sin(math.atan2(d[1], d[0]) - psi)

            motion = solve(crank, grid, order=0)
            d = motion.positions["D"] - np.array([0.0, 2.8])
            off = np.sin(np.arctan2(d[:, 1], d[:, 0]) - psi)
            ahead = np.cos(np.arctan2(d[:, 1], d[:, 0]) - psi) > 0
            for i in np.flatnonzero(motion.valid[:-1] & motion.valid[1:] & ahead[:-1]):
                if off[i] == 0 or off[i] * off[i + 1] < 0:
                    root = brentq(miss, grid[i], grid[i + 1], xtol=1e-16, rtol=1e-15)
                    found.append(solve(crank, [root], order=0).positions)
    return found


@pytest.mark.parametrize("psi", np.radians([-170.0, -95.0, -20.0, 0.0, 40.0, 90.0, 135.0]))
def test_each_configuration_is_the_crank_driven_six_bar_at_its_crank_angle(psi: float) -> None:
    roots = _crank_driven_roots(psi)
    rows = configuration_sets(as_linkage(), [psi], PLANE_JOINTS)[0]
    assert len(roots) == len(rows) == 2
    for pos in roots:
        row = np.concatenate([pos[j][0] for j in PLANE_JOINTS])
        assert np.min(np.max(np.abs(rows - row), axis=1)) <= 1e-10 * SIZE


def test_residuals_measured_on_the_positions_vanish_on_every_configuration() -> None:
    mech = from_c()
    for _, motion in configurations(mech, TURN, order=0):
        res = mech.residuals(motion)
        assert {"C.r1", "C.r2", "C.r3", "C.side", "C.u", "C.v", "P.u", "P.v"} <= set(res)
        for key, r in res.items():
            assert np.all(np.isnan(r) == ~motion.valid), key
            assert np.nanmax(np.abs(r), initial=0.0) < 1e-12, key
    # A wrong position shows up in the constraints it breaks, and only there.
    motion = solve(mech, [0.3])
    motion.positions["B"][...] += np.array([0.0, 0.01])
    broken = {k for k, r in mech.residuals(motion).items() if np.nanmax(np.abs(r)) > 1e-4}
    assert broken == {"C.r3", "C.u", "C.v"}


def _derivatives_match_differences(mech: Linkage, theta: np.ndarray, size: float) -> None:
    """Velocity and acceleration against 4th-order central differences on one pose followed
    across the steps. The truncation error is h⁴/30 of the fifth derivative: 3e-18 of it at
    h = 1e-4, which grows near a limit position (an acceleration of 80 of the size was met),
    hence the relative part of the tolerance; rounding adds about ε/h of the size."""
    h = 1e-4
    here = solve(mech, theta)
    steps = {k: solve(mech, theta + k * h) for k in (-2, -1, 1, 2)}
    ok = here.regular.copy()
    for k, m in steps.items():
        ok &= m.valid
        for j in mech.reported_joints:  # the same pose on either side (no slot change)
            ok &= np.linalg.norm(m.positions[j] - here.positions[j], axis=-1) < 10 * abs(k) * h
    assert ok.sum() >= theta.size // 2

    def diff(attr: str, j: str) -> np.ndarray:
        f = {k: getattr(m, attr)[j] for k, m in steps.items()}
        return (f[-2] - 8 * f[-1] + 8 * f[1] - f[2]) / (12 * h)

    for j in mech.reported_joints:
        np.testing.assert_allclose(
            here.velocities[j][ok], diff("positions", j)[ok], atol=1e-9 * size, rtol=1e-8
        )
        np.testing.assert_allclose(
            here.accelerations[j][ok], diff("velocities", j)[ok], atol=1e-8 * size, rtol=1e-7
        )


@pytest.mark.parametrize("pose", [0.0, 1.0])
def test_plane_derivatives_match_central_differences(pose: float) -> None:
    mech = as_linkage()
    joints = tuple(replace(j, pose=pose) if isinstance(j, TriadJoint) else j for j in mech.joints)
    _derivatives_match_differences(replace(mech, joints=joints), TURN[::9], SIZE)


def test_every_circuit_is_closed_and_holds_every_link() -> None:
    _, found = circuits(from_c(), 180)
    assert len(found) == 2
    for motion in found:
        pos = motion.positions
        for a, b, length in (("A0", "A", 1.0), ("B0", "B", 3.0), ("D", "C", 0.7), ("A", "B", 4.0)):
            np.testing.assert_allclose(
                np.linalg.norm(pos[a] - pos[b], axis=-1), length, atol=1e-10 * SIZE
            )


# --------------------------------------------------------------------------------------------
# Paper 001's spherical Stephenson III driven at FG (src/linkwright/examples/paper001-fg)
# --------------------------------------------------------------------------------------------

FG = load_example("paper001-fg").mechanism
ARCS = dict(
    zip(
        ("a1", "a2", "a3", "a4", "a6", "sigma", "a7", "a8", "a9"),
        np.radians([71.1, 64.1, 68.6, 65.7, 69.0, 102.0, 74.1, 52.6, 19.7]),
        strict=True,
    )
)
G_AXIS = np.array([0.0, math.sin(ARCS["a1"] + ARCS["a9"]), math.cos(ARCS["a1"] + ARCS["a9"])])
AWAY = -np.array([0.0, math.sin(ARCS["a1"]), math.cos(ARCS["a1"])])


def _meridian(t: float) -> list[float]:
    return [0.0, math.sin(t), math.cos(t)]


def sphere_linkage(first: str = "C") -> Linkage:
    """Paper 001's FG mechanism joint by joint: A, D, G on the meridian x = 0, the crank FG
    measured (as the paper's θ6) from G away from D, half a turn from the great circle G→D;
    the ternary BCE written from C (as the family does) or from B."""
    a = ARCS
    ground = (
        FixedJoint("A", _meridian(0.0)),
        FixedJoint("D", _meridian(a["a1"])),
        FixedJoint("G", _meridian(a["a1"] + a["a9"])),
    )
    crank = SphereCrankJoint("F", "G", a["a8"], phase=math.pi, toward="D")
    turn = math.pi - a["sigma"]
    if first == "C":
        triad = SphereTriadJoint(
            "C", "B", "E", "D", a["a4"], "A", a["a2"], "F", a["a7"], side=a["a3"], arc=a["a6"],
            angle=turn,
        )  # fmt: skip
    else:
        # From B towards C: E's arc from B and its angle at B, from C, B and E placed by hand
        # on a frame of their own (C at the pole, B on the meridian, E turned from it).
        c = np.array([0.0, 0.0, 1.0])
        b = sphere.point_at(c, np.array([1.0, 0.0, 0.0]), a["a3"], 0.0)
        e = sphere.point_at(c, b, a["a6"], turn)
        triad = SphereTriadJoint(
            "B", "C", "E", "A", a["a2"], "D", a["a4"], "F", a["a7"], side=a["a3"],
            arc=float(sphere.arc(b, e)), angle=float(sphere.angle_at(b, c, e)),
        )  # fmt: skip
    return Linkage(joints=(*ground, crank, triad), traced=("E", "F"), space="sphere")


def test_spherical_fg_written_joint_by_joint_is_the_familys() -> None:
    ours = configuration_sets(sphere_linkage(), TURN, SPHERE_JOINTS)
    theirs = configuration_sets(FG, TURN, SPHERE_JOINTS)
    assert_same_configurations(sphere_linkage(), FG, TURN, SPHERE_JOINTS, 1e-10)
    assert max(len(x) for x in ours) == 8 and sum(map(len, ours)) == sum(map(len, theirs))
    counts = [len(x) for x in configuration_sets(sphere_linkage(), np.radians([-90, 0, 120]),
                                                 SPHERE_JOINTS)]  # fmt: skip
    assert counts == [8, 4, 6]


def test_spherical_fg_written_from_b_has_the_same_configurations() -> None:
    assert_same_configurations(sphere_linkage("B"), FG, TURN[::3], SPHERE_JOINTS, 1e-10)


def _ab_driven_roots(theta6: float) -> list[dict[str, np.ndarray]]:
    """Every configuration of paper 001's mechanism driven at AB with F at ``theta6``: on each
    of its four branches, the inputs θ1 where F's angle about G (from G away from D) is θ6."""
    grid = np.linspace(-np.pi, np.pi, 1441)
    found = []
    for assembly in (1.0, -1.0):
        for assembly2 in (1.0, -1.0):
            ab = replace(FG, input="AB", assembly=assembly, assembly2=assembly2)

            def turned(pos: dict[str, np.ndarray]) -> np.ndarray:
                return sphere.angle_at(G_AXIS, AWAY, pos["F"]) - theta6

            def miss(t: float, ab: SphericalStephenson3 = ab) -> float:
                return float(np.sin(turned(solve(ab, [t], order=0).positions)[0]))

            motion = solve(ab, grid, order=0)
            off, ahead = np.sin(turned(motion.positions)), np.cos(turned(motion.positions)) > 0
            for i in np.flatnonzero(motion.valid[:-1] & motion.valid[1:] & ahead[:-1]):
                if off[i] == 0 or off[i] * off[i + 1] < 0:
                    root = brentq(miss, grid[i], grid[i + 1], xtol=1e-16, rtol=1e-15)
                    found.append(solve(ab, [root], order=0).positions)
    return found


@pytest.mark.parametrize(("degrees", "count"), [(-90.0, 8), (0.0, 4), (120.0, 6)])
def test_each_spherical_configuration_is_the_ab_driven_one(degrees: float, count: int) -> None:
    theta6 = math.radians(degrees)
    roots = _ab_driven_roots(theta6)
    rows = configuration_sets(sphere_linkage(), [theta6], SPHERE_JOINTS)[0]
    assert len(roots) == len(rows) == count
    for pos in roots:
        row = np.concatenate([pos[j][0] for j in SPHERE_JOINTS])
        assert np.min(np.max(np.abs(rows - row), axis=1)) <= 1e-10


def test_spherical_residuals_and_derivatives() -> None:
    mech = sphere_linkage("B")
    for _, motion in configurations(mech, TURN[::4], order=0):
        res = mech.residuals(motion)
        assert {"B.r1", "B.r2", "B.r3", "B.side", "B.point", "unit"} <= set(res)
        for key, r in res.items():
            assert np.nanmax(np.abs(r), initial=0.0) < 1e-12, key
    for pose in (0.0, 3.0):
        joints = tuple(
            replace(j, pose=pose) if isinstance(j, SphereTriadJoint) else j for j in mech.joints
        )
        _derivatives_match_differences(replace(mech, joints=joints), TURN[::9], 1.0)


# --------------------------------------------------------------------------------------------
# Documents, checks and verbs
# --------------------------------------------------------------------------------------------

DOCUMENT = {
    "format": "linkwright/1",
    "title": "Stephenson III driven at its output, joint by joint",
    "mechanism": {
        "family": "linkage",
        "traced": ["P"],
        "joints": [
            {"name": "A0", "type": "fixed", "at": [0.0, 0.0]},
            {"name": "B0", "type": "fixed", "at": [4.0, 0.0]},
            {"name": "D0", "type": "fixed", "at": [0.0, 2.8]},
            {"name": "D", "type": "crank", "pivot": "D0", "length": 1.0},
            {"name": "A", "type": "triad", "j2": "B", "j3": "C", "p1": "A0", "r1": 1.0,
             "p2": "B0", "r2": 3.0, "p3": "D", "r3": 0.7, "side": 4.0, "u": 2.0, "v": 2.0},
            {"name": "P", "type": "rigid", "origin": "C", "toward": "D", "u": 0.35, "v": 0.5},
        ],
    },
}  # fmt: skip


def _with(index: int, **changes: object) -> dict:
    doc = json.loads(json.dumps(DOCUMENT))
    doc["mechanism"]["joints"][index].update(changes)
    doc["mechanism"]["traced"] = ["A"]
    return doc


def test_a_triad_document_reads_as_the_linkage_and_writes_back() -> None:
    doc = parse_document(DOCUMENT)
    assert doc.mechanism == as_linkage()
    table = document_to_dict(doc)["mechanism"]["joints"][4]
    assert table["pose"] == 0 and table["type"] == "triad"
    assert mechanism_to_dict(doc.mechanism)["mechanism"] == document_to_dict(doc)["mechanism"]
    assert 'type = "triad"' in dumps_toml(document_to_dict(doc))
    # Traced joints may be a triad's second and third.
    assert parse_document({**DOCUMENT, "mechanism": {**DOCUMENT["mechanism"], "traced": ["B"]}})


def test_a_spherical_triad_document_speaks_degrees() -> None:
    raw = mechanism_to_dict(sphere_linkage())
    table = raw["mechanism"]["joints"][4]
    assert table["type"] == "triad" and table["r1"] == 65.7 and table["side"] == 68.6
    assert table["arc"] == 69.0 and table["angle"] == 78.0
    again = parse_document(raw).mechanism
    for key, value in sphere_linkage().params().items():
        np.testing.assert_allclose(again.params()[key], value, rtol=1e-15, atol=1e-15)


@pytest.mark.parametrize(
    ("doc", "path", "words"),
    [
        (_with(4, p3="Z"), "mechanism.joints[4]", "'Z', which is not placed before it"),
        (_with(4, p1="B"), "mechanism.joints[4]", "built from 'B', a joint it places"),
        (_with(4, j2="D0"), "mechanism.joints[4]", "j2 must be a new joint's name"),
        (_with(4, j3="B"), "mechanism.joints[4]", "j3 must be a non-empty joint name other"),
        (_with(4, j2="A"), "mechanism.joints[4]", "other than 'A'"),
        (_with(5, name="C"), "mechanism.joints[5]", "'C' is listed twice"),
        (_with(4, r2=0.0), "mechanism.joints[4].r2", "positive"),
        (_with(4, side=-1.0), "mechanism.joints[4].side", "positive"),
        (_with(4, pose=6), "mechanism.joints[4]", "from 0 to 5"),
        (_with(4, pose=0.5), "mechanism.joints[4].pose", "whole number"),
        (_with(4, u=0.0, v=0.0), "mechanism.joints[4]", "dyad (rrr)"),
        (_with(4, u=4.0, v=0.0), "mechanism.joints[4]", "placed on J2"),
        (_with(4, k1="A0"), "mechanism.joints[4]", "k1"),
    ],
)
def test_an_ill_formed_triad_document_names_the_field(doc: dict, path: str, words: str) -> None:
    with pytest.raises(DocumentError) as refused:
        parse_document(doc)
    message = str(refused.value)
    assert refused.value.field == path and words in message, message
    assert "\n" not in message and "Traceback" not in message


def test_ill_formed_triads_are_refused_by_the_class() -> None:
    base = as_linkage().joints
    triad = base[4]
    assert isinstance(triad, TriadJoint)
    cases = [
        (replace(triad, r1=-1.0), "r1 must be a positive length"),
        (replace(triad, pose=np.array([0.0, 6.0])), "pose must be a whole number from 0 to 5"),
        (replace(triad, j3=""), "j3 must be a non-empty joint name"),
        (replace(triad, p2="A"), "built from itself"),
    ]
    for spec, words in cases:
        with pytest.raises(InvalidLinkage, match=words):
            Linkage(joints=(*base[:4], spec))
    # A planar triad on the sphere (and a spherical one in the plane) says what to write.
    sphere_base = sphere_linkage().joints
    with pytest.raises(InvalidLinkage, match="use SphereTriadJoint"):
        Linkage(joints=(*sphere_base[:4], replace(triad, name="X")), space="sphere")
    with pytest.raises(InvalidLinkage, match="spherical SphereTriadJoint"):
        Linkage(joints=(*base[:4], sphere_base[4]))
    spherical = sphere_base[4]
    assert isinstance(spherical, SphereTriadJoint)
    for spec, words in [
        (replace(spherical, r3=math.pi), "strictly between 0 and π"),
        (replace(spherical, pose=8.0), "from 0 to 7"),
        (replace(spherical, arc=0.0), "placed on J1"),
    ]:
        with pytest.raises(InvalidLinkage, match=words):
            Linkage(joints=(*sphere_base[:4], spec), space="sphere")


def test_a_triad_and_a_dyad_together_and_batches() -> None:
    # A dyad hung from the triad's joints, and a batch of two output lengths.
    extra = DyadJoint("Q", "B", 2.0, "C", 2.0)
    mech = Linkage(joints=(*as_linkage().joints, extra), traced="Q")
    assert mech.reported_joints == ("A0", "B0", "D0", "D", "A", "B", "C", "P", "Q")
    assert mech.plan.joints == mech.reported_joints
    both = Linkage(
        joints=(*GROUND, CrankJoint("D", "D0", [1.0, 1.1]), *as_linkage().joints[4:]), traced="P"
    )
    motion = solve(both, TURN[:5])
    assert motion.positions["C"].shape == (2, 5, 2)
    for k, length in enumerate((1.0, 1.1)):
        single = Linkage(
            joints=(*GROUND, CrankJoint("D", "D0", length), *as_linkage().joints[4:]), traced="P"
        )
        np.testing.assert_array_equal(
            motion.positions["C"][k], solve(single, TURN[:5]).positions["C"]
        )


def _run(*args: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(list(args))
    return code, out.getvalue(), err.getvalue()


def test_every_verb_runs_a_triad_document(tmp_path) -> None:
    path = tmp_path / "triad.json"
    path.write_text(json.dumps(DOCUMENT))
    code, _, err = _run("solve", str(path), "--all", "--derivatives", "--json", "-i", "0,90")
    assert code == 0, err
    code, _, err = _run("analyze", str(path), "--json")
    assert code == 0, err
    code, _, err = _run("curve", str(path), "--all", "--json", "-n", "40")
    assert code == 0, err
    from linkwright.server import scene as scenes

    view = json.loads(scenes.to_json(scenes.scene(DOCUMENT)))
    assert view and "Traceback" not in json.dumps(view)


def test_a_document_may_trace_every_joint_a_step_places() -> None:
    # A driven hinge's far joint was refused as "unknown" (only the tables' names were known);
    # so were a triad's second and third joints.
    hinge = document_to_dict(load_example("hinge-driven-fourbar"))
    hinge["mechanism"]["traced"] = ["A", "P"]
    assert parse_document(hinge).mechanism.traced == ("A", "P")
    triad = {**DOCUMENT, "mechanism": {**DOCUMENT["mechanism"], "traced": ["C", "B"]}}
    assert parse_document(triad).mechanism.traced == ("C", "B")
    with pytest.raises(DocumentError, match="unknown joint 'Z'"):
        parse_document({**DOCUMENT, "mechanism": {**DOCUMENT["mechanism"], "traced": ["Z"]}})
