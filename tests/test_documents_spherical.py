"""Spherical families in mechanism documents, spherical composed linkages, and the paper examples.

Documents speak degrees, mechanisms radians: every test that reads numbers back compares them
with ``math.radians`` of what the document says, or with a closed form written out here from the
papers (paper 000's eqs. 4–6 for the four-bar, eq. 3 of paper 001 for the ternary coupler), never
with an earlier output of the code.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import tempfile
import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import event, given, settings
from hypothesis import strategies as st

from linkwright.io import (
    FAMILY_SPECS,
    Document,
    DocumentError,
    document_to_dict,
    load_document,
    load_example,
    mechanism_to_dict,
    parse_document,
    save_document,
)
from linkwright.io.documents import KINDS, SPHERE_JOINT_SPECS, WORKING_RANGE
from linkwright.mechanisms import (
    FAMILIES,
    SphericalFourBar,
    SphericalSixBar,
    SphericalStephenson3,
    circuit,
    solve,
)
from linkwright.mechanisms.linkage import (
    SPHERE_JOINT_TYPES,
    DyadJoint,
    Linkage,
    SphereCrankJoint,
    SphereRigidJoint,
)

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "linkwright" / "examples"
SPHERICAL_EXAMPLES = [
    "paper000-fig6-crank-rocker",
    "paper000-fig6-linkage",
    "paper000-fig7-drag-link",
    "paper000-fig8-sixbar",
    "paper001-stephenson3",
    "paper003-table3-drag-link",
]

FOURBAR = {
    "format": "linkwright/1",
    "title": "Fig. 6",
    "mechanism": {
        "family": "spherical-fourbar",
        "frame": 40,
        "crank": 20,
        "coupler": 45,
        "rocker": 35,
        "point": {"arc": 50, "angle": 130},
    },
}
SIXBAR = {
    "format": "linkwright/1",
    "mechanism": {
        "family": "spherical-sixbar",
        "frame": 35,
        "crank": 20,
        "coupler": 42,
        "rocker": 30,
        "point": {"arc": 72, "angle": 22},
        "link5": 45,
        "link6": 33,
        "ground": {"arc": 85, "angle": -30},
        "d": {"arc": 30, "angle": 75},
        "assembly": -1,
    },
}
STEPHENSON = {
    "format": "linkwright/1",
    "mechanism": {
        "family": "spherical-stephenson3",
        "a1": 60,
        "a2": 20,
        "a3": 50,
        "a4": 40,
        "a6": 40,
        "sigma": 100,
        "a7": 50,
        "a8": 45,
        "a9": 30,
    },
}
LINKAGE = {
    "format": "linkwright/1",
    "mechanism": {
        "family": "linkage",
        "space": "sphere",
        "joints": [
            {"name": "A0", "type": "fixed", "at": [1, 0, 0]},
            {"name": "B0", "type": "fixed", "at": [1, 1, 0]},
            {"name": "A", "type": "crank", "pivot": "A0", "arc": 20, "phase": 10},
            {"name": "B", "type": "rrr", "p1": "A", "r1": 50, "p2": "B0", "r2": 40},
            {"name": "P", "type": "rigid", "origin": "A", "toward": "B", "arc": 30, "angle": 60},
        ],
    },
}
CLASSES = {
    "spherical-fourbar": SphericalFourBar,
    "spherical-sixbar": SphericalSixBar,
    "spherical-stephenson3": SphericalStephenson3,
}


@pytest.fixture(scope="module", autouse=True)
def linkage_family():
    """Documents of family ``linkage`` need the class in FAMILIES (as test_documents does)."""
    with pytest.MonkeyPatch.context() as mp:
        if "linkage" not in FAMILIES:
            mp.setitem(FAMILIES, "linkage", Linkage)
        yield


def with_change(base: dict, path: str, value: object = ..., delete: bool = False) -> dict:
    """A deep copy of ``base`` with the dotted ``path`` set to ``value`` (or deleted); an
    integer step indexes a list (``mechanism.joints.2.arc``)."""
    doc = copy.deepcopy(base)
    *parents, last = path.split(".")
    node = doc
    for key in parents:
        node = node[int(key)] if isinstance(node, list) else node[key]
    if delete:
        del node[last]
    else:
        node[last] = value
    return doc


def _close(a, b, rel: float = 1e-13) -> bool:
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_close(a[k], b[k], rel) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_close(x, y, rel) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) or isinstance(b, float):
        # Subnormal degrees come back from radians as the nearest subnormal, hence abs_tol.
        return math.isclose(a, b, rel_tol=rel, abs_tol=1e-300)
    return a == b


# ---------------------------------------------------------------------------------------------
# The three families: building, defaults, the schema against the classes
# ---------------------------------------------------------------------------------------------


def test_spherical_fourbar_document_is_radians_inside():
    doc = parse_document(FOURBAR)
    m = doc.mechanism
    assert isinstance(m, SphericalFourBar) and m.space == "sphere"
    for field, deg in (("frame", 40), ("crank", 20), ("coupler", 45), ("rocker", 35)):
        assert float(getattr(m, field)) == math.radians(deg)
    assert float(m.point_arc) == math.radians(50) and float(m.point_angle) == math.radians(130)
    # assembly defaults to +1, paper 000's eq. 5 as printed.
    assert doc.raw["mechanism"]["assembly"] == 1 and float(m.assembly) == 1.0
    no_point = parse_document(with_change(FOURBAR, "mechanism.point", delete=True))
    assert no_point.raw["mechanism"]["point"] == {"arc": 0.0, "angle": 0.0}
    angle_only = parse_document(with_change(FOURBAR, "mechanism.point", {"arc": 10}))
    assert angle_only.raw["mechanism"]["point"] == {"arc": 10.0, "angle": 0.0}


def test_spherical_sixbar_document_maps_every_field():
    doc = parse_document(SIXBAR)
    m = doc.mechanism
    assert isinstance(m, SphericalSixBar)
    expect = {
        "frame": 35,
        "crank": 20,
        "coupler": 42,
        "rocker": 30,
        "point_arc": 72,
        "point_angle": 22,
        "link5": 45,
        "link6": 33,
        "ground_arc": 85,
        "ground_angle": -30,
        "d_arc": 30,
        "d_angle": 75,
    }
    for field, deg in expect.items():
        assert float(getattr(m, field)) == math.radians(deg), field
    assert (float(m.assembly), float(m.assembly2)) == (-1.0, 1.0)
    no_d = parse_document(with_change(SIXBAR, "mechanism.d", delete=True))
    assert no_d.raw["mechanism"]["d"] == {"arc": 0.0, "angle": 0.0}


def test_spherical_stephenson3_document_and_its_input():
    doc = parse_document(STEPHENSON)
    m = doc.mechanism
    assert isinstance(m, SphericalStephenson3)
    raw = doc.raw["mechanism"]
    assert (raw["input"], raw["assembly"], raw["assembly2"]) == ("AB", 1, 1)
    for field in ("a1", "a2", "a3", "a4", "a6", "sigma", "a7", "a8", "a9"):
        assert float(getattr(m, field)) == math.radians(STEPHENSON["mechanism"][field])
    fg = parse_document(with_change(STEPHENSON, "mechanism.input", "FG"))
    assert fg.mechanism.input == "FG" and fg.mechanism.driven == ("G", "F")
    # σ is an angle, not an arc: any finite value.
    wide = parse_document(with_change(STEPHENSON, "mechanism.sigma", -250))
    assert float(wide.mechanism.sigma) == math.radians(-250)


@pytest.mark.parametrize("family", sorted(CLASSES))
def test_schema_rows_build_exactly_the_class_fields(family):
    spec = FAMILY_SPECS[family]
    targets = {t for f in spec.fields if KINDS[f.kind].builds for t in f.targets}
    assert targets == {f.name for f in dataclasses.fields(CLASSES[family])}
    assert FAMILIES[family] is CLASSES[family]


def test_sphere_joint_schema_covers_the_sphere_joint_classes():
    assert set(SPHERE_JOINT_SPECS) == set(SPHERE_JOINT_TYPES) == {"fixed", "crank", "rrr", "rigid"}
    for kind, specs in SPHERE_JOINT_SPECS.items():
        names = {f.name for f in dataclasses.fields(SPHERE_JOINT_TYPES[kind])} - {"name"}
        assert {t for f in specs for t in f.targets} == names, kind


# ---------------------------------------------------------------------------------------------
# Validation: the document names the field before the class sees the number
# ---------------------------------------------------------------------------------------------

ARC = "must be an arc strictly between 0 and 180 degrees, got"
FAMILY_ERRORS = [
    (FOURBAR, "mechanism.crank", 0, f"mechanism.crank: {ARC} 0 (a spherical link's"),
    (FOURBAR, "mechanism.frame", 180, f"mechanism.frame: {ARC} 180"),
    (FOURBAR, "mechanism.coupler", -45, f"mechanism.coupler: {ARC} -45"),
    (FOURBAR, "mechanism.rocker", 200.5, f"mechanism.rocker: {ARC} 200.5"),
    # Positive in degrees, but 0 in radians: the class would refuse it, naming its own field.
    (FOURBAR, "mechanism.rocker", 5e-324, f"mechanism.rocker: {ARC} 5e-324"),
    (FOURBAR, "mechanism.crank", "20", 'mechanism.crank: must be an arc in degrees, got "20"'),
    (FOURBAR, "mechanism.crank", math.nan, "mechanism.crank: must be a finite number, got nan"),
    (FOURBAR, "mechanism.crank", None, "mechanism.crank: must be an arc in degrees, got null"),
    (FOURBAR, "mechanism.crank", ..., "mechanism.crank: missing required field (an arc in"),
    (
        FOURBAR,
        "mechanism.point",
        {"arc": -1, "angle": 3},
        "mechanism.point.arc: must be an arc from 0 to 180 degrees, got -1 (for a point on the "
        "other side, add 180 to its angle instead)",
    ),
    (FOURBAR, "mechanism.point", {"arc": 181}, "mechanism.point.arc: must be an arc from 0 to"),
    (FOURBAR, "mechanism.point", {"angle": 3}, "mechanism.point.arc: missing required field"),
    (FOURBAR, "mechanism.point", {"arc": 3, "u": 1}, "mechanism.point: unknown field 'u'"),
    (FOURBAR, "mechanism.point", [50, 130], "mechanism.point: must be a table {arc = .., angle"),
    (FOURBAR, "mechanism.point", {"arc": 3, "angle": "x"}, "mechanism.point.angle: must be an"),
    (FOURBAR, "mechanism.assembly", 0, "mechanism.assembly: must be 1 or -1, got 0"),
    (FOURBAR, "mechanism.A0", [0, 0], "mechanism: unknown field 'A0'"),
    (FOURBAR, "mechanism.frme", 40, "mechanism: unknown field 'frme' (did you mean 'frame'?)"),
    (SIXBAR, "mechanism.link5", 180, f"mechanism.link5: {ARC} 180"),
    (SIXBAR, "mechanism.link6", 0.0, f"mechanism.link6: {ARC} 0.0"),
    # E0 is a pivot at the end of a ground arc: a link, so 0 and 180 are refused.
    (SIXBAR, "mechanism.ground", {"arc": 0, "angle": 1}, f"mechanism.ground.arc: {ARC} 0"),
    (SIXBAR, "mechanism.ground", {"arc": 180}, f"mechanism.ground.arc: {ARC} 180"),
    (SIXBAR, "mechanism.d", {"arc": 190}, "mechanism.d.arc: must be an arc from 0 to 180"),
    (SIXBAR, "mechanism.point", ..., "mechanism.point: missing required field (a table {arc"),
    (SIXBAR, "mechanism.ground", ..., "mechanism.ground: missing required field"),
    (SIXBAR, "mechanism.assembly2", 2, "mechanism.assembly2: must be 1 or -1, got 2"),
    (STEPHENSON, "mechanism.a9", 180, f"mechanism.a9: {ARC} 180"),
    (STEPHENSON, "mechanism.a6", -1, f"mechanism.a6: {ARC} -1"),
    (STEPHENSON, "mechanism.a5", 30, "mechanism: unknown field 'a5'"),
    (STEPHENSON, "mechanism.sigma", math.inf, "mechanism.sigma: must be a finite number, got inf"),
    (STEPHENSON, "mechanism.input", "CD", "mechanism.input: unknown value 'CD' (known: AB, FG)"),
    (STEPHENSON, "mechanism.input", 1, 'mechanism.input: must be "AB" or "FG", got 1'),
    (STEPHENSON, "mechanism.input", "crank", "mechanism.input: unknown value 'crank'"),
]


@pytest.mark.parametrize(("base", "path", "value", "message"), FAMILY_ERRORS)
def test_family_validation_messages_name_the_field(base, path, value, message):
    doc = with_change(base, path, delete=True) if value is ... else with_change(base, path, value)
    with pytest.raises(DocumentError) as info:
        parse_document(doc)
    assert str(info.value).startswith(message)
    assert info.value.field == message.split(": ")[0]


# ---------------------------------------------------------------------------------------------
# Round trips: document → mechanism → document, and mechanism → document → mechanism
# ---------------------------------------------------------------------------------------------

arcs = st.floats(0, 180, exclude_min=True, exclude_max=True) | st.sampled_from(
    [1e-300, 5e-324, 179.99999999999997, 90.0, 1.0]
)
offsets = st.floats(0, 180) | st.sampled_from([0.0, 180.0, 5e-324])
angles = st.floats(-1e6, 1e6) | st.sampled_from([0.0, -180.0, 30.000000000000004, 1e-320])
signs = st.sampled_from([1, -1, 1.0, -1.0])


@st.composite
def family_documents(draw):
    family = draw(st.sampled_from(sorted(CLASSES)))
    mech: dict = {"family": family}
    strict = []
    if family == "spherical-stephenson3":
        for name in ("a1", "a2", "a3", "a4", "a6", "a7", "a8", "a9"):
            mech[name] = draw(arcs)
            strict.append(mech[name])
        mech["sigma"] = draw(angles)
        mech["input"] = draw(st.sampled_from(["AB", "FG"]))
    else:
        for name in ("frame", "crank", "coupler", "rocker"):
            mech[name] = draw(arcs)
            strict.append(mech[name])
        mech["point"] = {"arc": draw(offsets), "angle": draw(angles)}
        if family == "spherical-sixbar":
            mech["link5"], mech["link6"] = draw(arcs), draw(arcs)
            mech["ground"] = {"arc": draw(arcs), "angle": draw(angles)}
            mech["d"] = {"arc": draw(offsets), "angle": draw(angles)}
            strict += [mech["link5"], mech["link6"], mech["ground"]["arc"]]
    mech["assembly"] = draw(signs)
    if family != "spherical-fourbar":
        mech["assembly2"] = draw(signs)
    # An arc within the working range's margin of 0 or 180 (subnormal arcs included) is the one
    # value refused.
    near = WORKING_RANGE.min_arc
    refused = any(not near <= a <= 180 - near for a in strict)
    return {"format": "linkwright/1", "title": draw(st.text(max_size=8)), "mechanism": mech}, (
        refused
    )


@settings(max_examples=150, deadline=None)
@given(family_documents(), st.sampled_from([".toml", ".json"]))
def test_fuzz_family_round_trips_lose_nothing(drawn, suffix):
    raw, refused = drawn
    try:
        doc = parse_document(raw)
    except DocumentError as exc:
        assert refused, exc
        assert ARC in str(exc)
        return
    assert not refused
    assert isinstance(doc.mechanism, CLASSES[doc.family])
    # document → mechanism → document
    again = mechanism_to_dict(doc.mechanism, title=doc.title)
    assert _close(again, document_to_dict(doc)), (again, doc.raw)
    # ... and the fields it builds are the same numbers (the unit vectors derived from them,
    # E0 from a large ε say, follow to the angle's absolute rounding, not compared here).
    reparsed = parse_document(again).mechanism
    for f in dataclasses.fields(reparsed):
        ours, theirs = getattr(reparsed, f.name), getattr(doc.mechanism, f.name)
        if isinstance(ours, str):
            assert ours == theirs
        else:
            np.testing.assert_allclose(ours, theirs, rtol=1e-13, atol=1e-300, err_msg=f.name)
    # the canonical mapping and files give back the very same document
    assert parse_document(document_to_dict(doc)) == doc
    with tempfile.TemporaryDirectory() as tmp:
        assert load_document(save_document(doc, Path(tmp) / f"d{suffix}")) == doc


# Within the working range: more than 1e-6 degrees (1.7e-8 radians) from 0 and from π.
rad_arcs = st.floats(1e-7, math.pi - 1e-7)
rad_angles = st.floats(-10, 10)


@settings(max_examples=100, deadline=None)
@given(
    st.tuples(*[rad_arcs] * 4),
    st.floats(0, math.pi),
    rad_angles,
    st.sampled_from([1.0, -1.0]),
)
def test_fuzz_mechanism_to_document_and_back(links, point_arc, point_angle, assembly):
    mech = SphericalFourBar(*links, point_arc, point_angle, assembly)
    back = parse_document(mechanism_to_dict(mech)).mechanism
    for f in dataclasses.fields(mech):
        ours, theirs = getattr(back, f.name), getattr(mech, f.name)
        np.testing.assert_allclose(ours, theirs, rtol=1e-13, atol=1e-300, err_msg=f.name)


def test_mechanism_to_dict_of_each_family_is_what_the_document_said():
    for base in (FOURBAR, SIXBAR, STEPHENSON):
        doc = parse_document(base)
        assert mechanism_to_dict(doc.mechanism, title=doc.title) == document_to_dict(doc)


def test_a_batched_spherical_mechanism_cannot_be_written():
    batch = SphericalFourBar(*np.radians([40, 45, 35]), rocker=np.radians([30, 35]))
    with pytest.raises(DocumentError, match=r"^mechanism\.rocker: must be a single value"):
        mechanism_to_dict(batch)


# ---------------------------------------------------------------------------------------------
# Spherical composed linkages in documents
# ---------------------------------------------------------------------------------------------


def test_spherical_linkage_document_builds_the_linkage():
    doc = parse_document(LINKAGE)
    m = doc.mechanism
    assert isinstance(m, Linkage) and m.space == "sphere" and m.traced == ("P",)
    raw = doc.raw["mechanism"]
    # toward defaults to the first fixed joint before the crank other than its pivot, and the
    # canonical document spells it out.
    assert raw["joints"][2] == {
        "name": "A",
        "type": "crank",
        "pivot": "A0",
        "arc": 20.0,
        "ratio": 1.0,
        "phase": 10.0,
        "toward": "B0",
    }
    assert raw["joints"][4]["arc"] == 30.0 and raw["joints"][3]["assembly"] == 1
    assert m.joint("A") == SphereCrankJoint(
        "A", "A0", math.radians(20), 1.0, math.radians(10), "B0"
    )
    assert m.joint("B") == DyadJoint("B", "A", math.radians(50), "B0", math.radians(40))
    assert m.joint("P") == SphereRigidJoint("P", "A", "B", math.radians(30), math.radians(60))
    # The axis is kept as written; the plan's joint is its unit vector.
    np.testing.assert_array_equal(m.joint("B0").at, [1.0, 1.0, 0.0])
    np.testing.assert_allclose(m.params()["B0.at"], [0.5**0.5, 0.5**0.5, 0.0], rtol=0, atol=2e-16)


def test_spherical_linkage_round_trips(tmp_path):
    doc = parse_document(with_change(LINKAGE, "mechanism.traced", ["P", "B"]))
    d = mechanism_to_dict(doc.mechanism, title=doc.title)
    assert _close(d, document_to_dict(doc))
    assert d["mechanism"]["joints"][1]["at"] == [1.0, 1.0, 0.0]
    assert parse_document(d) == doc
    for suffix in (".toml", ".json"):
        path = save_document(doc, tmp_path / f"s{suffix}")
        assert load_document(path) == doc
    text = (tmp_path / "s.toml").read_text()
    assert 'space = "sphere"' in text and "at = [1.0, 1.0, 0.0]" in text


def joint_change(index: int, key: str, value: object = ..., delete: bool = False) -> dict:
    path = f"mechanism.joints.{index}.{key}"
    return with_change(LINKAGE, path, delete=True) if delete else with_change(LINKAGE, path, value)


def joints_doc(*joints: dict) -> dict:
    return with_change(LINKAGE, "mechanism.joints", list(joints))


FIXED_A0 = {"name": "A0", "type": "fixed", "at": [1, 0, 0]}
CRANK_A = {"name": "A", "type": "crank", "pivot": "A0", "arc": 20}

SPHERE_LINKAGE_ERRORS = [
    (
        joint_change(0, "at", [1, 0]),
        "mechanism.joints[0].at: must be an axis [x, y, z] (a vector from the sphere's centre "
        "along the joint's axis), got [1, 0]",
    ),
    (joint_change(0, "at", [0, 0, 0]), "mechanism.joints[0].at: must not be the zero vector"),
    (joint_change(0, "at", [0, "1", 0]), "mechanism.joints[0].at[1]: must be a number"),
    (joint_change(1, "at", [0, 0, math.inf]), "mechanism.joints[1].at[2]: must be a finite"),
    (joint_change(2, "arc", 0), f"mechanism.joints[2].arc: {ARC} 0"),
    (joint_change(2, "arc", 180), f"mechanism.joints[2].arc: {ARC} 180"),
    (joint_change(2, "ratio", 0), "mechanism.joints[2].ratio: must be a nonzero number, got 0"),
    (
        joint_change(2, "length", 20),
        "mechanism.joints[2].length: a spherical crank's length is an arc: write arc = <degrees>",
    ),
    (joint_change(2, "arc", delete=True), "mechanism.joints[2].arc: missing required field"),
    (joint_change(2, "toward", 3), "mechanism.joints[2].toward: must be a joint name"),
    (joint_change(3, "r1", 200), f"mechanism.joints[3].r1: {ARC} 200"),
    (joint_change(3, "r2", -3), f"mechanism.joints[3].r2: {ARC} -3"),
    (joint_change(3, "assembly", 0), "mechanism.joints[3].assembly: must be 1 or -1, got 0"),
    (joint_change(4, "arc", -10), "mechanism.joints[4].arc: must be an arc from 0 to 180"),
    (joint_change(4, "u", 1), "mechanism.joints[4].u: a spherical rigid point is placed by arc"),
    (joint_change(4, "zz", 1), "mechanism.joints[4]: unknown field 'zz' (known: name, type"),
    (
        joint_change(3, "type", "rrp"),
        "mechanism.joints[3].type: a slider (rrp) has no spherical counterpart: a pin on a "
        "great-circle guide is an rrr joint whose second link, 90 degrees long, turns about the "
        "guide's pole; write that instead",
    ),
    (joint_change(3, "type", "slider"), "mechanism.joints[3].type: a slider (rrp) has no"),
    (joint_change(3, "type", "rr"), "mechanism.joints[3].type: unknown joint type 'rr'"),
    # The class's structural verdicts, under the joint's path.
    (
        joints_doc(FIXED_A0, CRANK_A),
        "mechanism.joints[1].toward: missing, and no fixed joint other than the pivot is listed "
        "before this crank",
    ),
    (
        joint_change(2, "toward", "A0"),
        "mechanism.joints[2]: joint 'A': pivot and toward are both 'A0'",
    ),
    (joint_change(4, "type", "crank"), "mechanism.joints[4]: unknown field 'origin'"),
    (
        with_change(
            LINKAGE,
            "mechanism.joints",
            [*LINKAGE["mechanism"]["joints"], {**CRANK_A, "name": "G", "pivot": "A"}],
        ),
        "mechanism.joints[5]: joint 'G': a spherical crank turns about a fixed joint, and 'A' is "
        "a crank joint (pivot)",
    ),
    (
        with_change(
            LINKAGE,
            "mechanism.joints",
            [*LINKAGE["mechanism"]["joints"], {**CRANK_A, "name": "G", "toward": "B"}],
        ),
        "mechanism.joints[5]: joint 'G': a spherical crank measures its angle towards a fixed "
        "joint, and 'B' is a rrr joint (toward)",
    ),
    (
        joint_change(1, "at", [-2, 0, 0]),
        "mechanism.joints[1]: joint 'B0' repeats joint 'A0' (a ground pivot on the same axis, in "
        "the same or opposite direction)",
    ),
    (joint_change(1, "at", [3, 0, 0]), "mechanism.joints[1]: joint 'B0' repeats joint 'A0'"),
    (
        joint_change(4, "toward", "B0"),
        "mechanism.joints[4]: joint 'P' is fixed on the link 'A'→'B0', but those two joints are "
        "not on one rigid link",
    ),
    (joint_change(3, "p2", "A"), "mechanism.joints[3]: joint 'B': p1 and p2 are both 'A'"),
    (joint_change(3, "p1", "Z"), "mechanism.joints[3]: joint 'B' is built from 'Z'"),
    (with_change(LINKAGE, "mechanism.space", "Sphere"), "mechanism.space: unknown value"),
    (with_change(LINKAGE, "mechanism.space", 3), 'mechanism.space: must be "plane" or "sphere"'),
    # Planar joints in a spherical document, and the other way round.
    (
        with_change(LINKAGE, "mechanism.space", "plane"),
        "mechanism.joints[0].at: must be a point [x, y], got [1, 0, 0]",
    ),
]


@pytest.mark.parametrize(("doc", "message"), SPHERE_LINKAGE_ERRORS)
def test_spherical_linkage_validation_names_the_joint(doc, message):
    with pytest.raises(DocumentError) as info:
        parse_document(doc)
    assert str(info.value).startswith(message)
    assert info.value.field == message.split(": ")[0]


def test_toward_defaults_to_the_first_other_fixed_joint_and_a_named_one_is_kept():
    # toward may name any fixed joint placed before the crank, not only the first one.
    three = with_change(
        LINKAGE,
        "mechanism.joints",
        [
            LINKAGE["mechanism"]["joints"][0],
            {"name": "Q", "type": "fixed", "at": [0, 0, 1]},
            *LINKAGE["mechanism"]["joints"][1:],
        ],
    )
    assert parse_document(three).mechanism.joint("A").toward == "Q"
    named = with_change(three, "mechanism.joints.3.toward", "B0")
    assert parse_document(named).mechanism.joint("A").toward == "B0"


sphere_names = st.sampled_from(["A0", "B0", "A", "B", "P", "Z", "", 3])
sphere_values = (
    st.floats(1, 179)
    | st.floats(-400, 400)
    | st.sampled_from([0, 90, 180, -1, math.nan, "1", None, True])
    | st.lists(st.floats(-2, 2), max_size=4)
)


@st.composite
def damaged_sphere_linkages(draw):
    joints = copy.deepcopy(LINKAGE["mechanism"]["joints"])
    if draw(st.integers(0, 4)) == 0:
        joints = draw(st.permutations(joints))
    for _ in range(draw(st.integers(0, 2))):
        entry = joints[draw(st.integers(0, len(joints) - 1))]
        extra = draw(st.integers(0, 5)) == 0
        key = draw(st.sampled_from(["toward", "length", "u"] if extra else sorted(entry)))
        if key in ("name", "pivot", "p1", "p2", "origin", "toward"):
            entry[key] = draw(sphere_names)
        elif key == "type":
            entry[key] = draw(st.sampled_from(["fixed", "crank", "rrr", "rigid", "rrp", "x"]))
        elif draw(st.integers(0, 5)) == 0:
            entry.pop(key, None)
        else:
            entry[key] = draw(sphere_values)
    mech = {"family": "linkage", "space": "plane" if draw(st.integers(0, 7)) == 0 else "sphere"}
    mech["joints"] = joints
    return {"format": "linkwright/1", "mechanism": mech}


@settings(max_examples=200, deadline=None)
@given(damaged_sphere_linkages())
def test_fuzz_spherical_linkage_documents_only_raise_document_error(doc):
    try:
        result = parse_document(doc)
    except DocumentError as exc:
        event("refused")
        assert str(exc).startswith("mechanism")
        return
    event("built")
    assert isinstance(result, Document) and isinstance(result.mechanism, Linkage)
    assert parse_document(document_to_dict(result)) == result
    again = parse_document(mechanism_to_dict(result.mechanism))
    assert _close(again.raw["mechanism"], result.raw["mechanism"])


# ---------------------------------------------------------------------------------------------
# The bundled spherical examples, against the papers' own formulas
# ---------------------------------------------------------------------------------------------


def paper000_B(a1, a2, a3, a4, theta, assembly=1):
    """B of paper 000's four-bar from its eq. 4, θ4 from eq. 5 (assembly +1: the minus sign
    before the root, as printed). tan(θ4/2) is taken in whichever of its two equal forms,
    (p ∓ √D)/(q + u) or (u − q)/(p ± √D), has the larger terms, and θ4 = 2·atan2 of it, so
    that neither form's 0/0 spoils a sample."""
    s, c = np.sin, np.cos
    p = s(a2) * s(a4) * s(theta)
    q = s(a2) * s(a4) * c(a1) * c(theta) - c(a2) * s(a4) * s(a1)
    u = c(a3) - c(a1) * c(a2) * c(a4) - s(a2) * c(a4) * s(a1) * c(theta)
    root = np.sqrt(p * p - u * u + q * q)
    n1, d1 = p - assembly * root, q + u
    n2, d2 = u - q, p + assembly * root
    first = np.hypot(n1, d1) >= np.hypot(n2, d2)
    theta4 = 2 * np.where(first, np.arctan2(n1, d1), np.arctan2(n2, d2))
    x = c(a4) * c(a1) - s(a4) * s(a1) * c(theta4)
    y = c(a4) * s(a1) + s(a4) * c(a1) * c(theta4)
    z = s(a4) * s(theta4)
    return np.stack([x, y, z], axis=-1), theta4


def paper000_C(A, B, ac, mu):
    """Coupler point C by paper 000's matrix T (eq. 6): B turned about OA by μ, then the arc
    AC walked from A towards B' on their great circle."""
    x, y, z = A[..., 0:1], A[..., 1:2], A[..., 2:3]
    K, cm, sm = 1 - np.cos(mu), np.cos(mu), np.sin(mu)
    rows = [
        (x * x * K + cm, x * y * K - z * sm, x * z * K + y * sm),
        (x * y * K + z * sm, y * y * K + cm, y * z * K - x * sm),
        (x * z * K - y * sm, y * z * K + x * sm, z * z * K + cm),
    ]
    Bp = np.concatenate(
        [r[0] * B[..., 0:1] + r[1] * B[..., 1:2] + r[2] * B[..., 2:3] for r in rows], -1
    )
    t = Bp - np.sum(A * Bp, -1, keepdims=True) * A
    t /= np.linalg.norm(t, axis=-1, keepdims=True)
    return np.cos(ac) * A + np.sin(ac) * t


THETA = np.radians(np.arange(0.0, 360.0, 2.5))


def example_degrees(name: str) -> dict:
    return tomllib.loads((EXAMPLES / f"{name}.toml").read_text())["mechanism"]


@pytest.mark.parametrize("name", SPHERICAL_EXAMPLES)
def test_spherical_examples_load_with_a_title_and_provenance(name):
    text = (EXAMPLES / f"{name}.toml").read_text()
    assert text.startswith("# ")
    doc = load_example(name)
    assert doc.title and doc.mechanism.space == "sphere"
    assert parse_document(document_to_dict(doc)) == doc
    motion = solve(doc.mechanism, THETA)
    assert motion.valid.all()  # every bundled example assembles over its whole input turn


@pytest.mark.parametrize(
    ("name", "swing"), [("paper000-fig6-crank-rocker", 82.89), ("paper000-fig7-drag-link", None)]
)
def test_paper000_four_bars_follow_eqs_4_to_6(name, swing):
    m = example_degrees(name)
    a1, a2, a3, a4 = np.radians([m["frame"], m["crank"], m["coupler"], m["rocker"]])
    ac, mu = np.radians([m["point"]["arc"], m["point"]["angle"]])
    assert m["assembly"] == 1
    motion = solve(load_example(name).mechanism, THETA)
    A = np.stack(
        [np.cos(a2) + 0 * THETA, np.sin(a2) * np.cos(THETA), np.sin(a2) * np.sin(THETA)], -1
    )
    B, _ = paper000_B(a1, a2, a3, a4, THETA)
    np.testing.assert_allclose(motion.positions["A"], A, rtol=0, atol=1e-15)
    np.testing.assert_allclose(motion.positions["B"], B, rtol=0, atol=1e-13)
    np.testing.assert_allclose(motion.positions["P"], paper000_C(A, B, ac, mu), rtol=0, atol=1e-13)
    # The rocker's swing (crank-rocker) or its full turn (drag link), from eq. 5 alone.
    fine = np.linspace(0, 2 * np.pi, 100001)
    out = np.unwrap(paper000_B(a1, a2, a3, a4, fine)[1])
    if swing is None:
        assert abs(abs(out[-1] - out[0]) - 2 * np.pi) < 1e-9
    else:
        assert abs(np.degrees(out.max() - out.min()) - swing) < 0.005
        assert abs(out[-1] - out[0]) < 1e-9


def test_the_fig6_linkage_example_is_the_fig6_family_example():
    named = load_example("paper000-fig6-crank-rocker").mechanism
    composed = load_example("paper000-fig6-linkage").mechanism
    assert composed.space == "sphere" and composed.traced == ("P",)
    a, b = circuit(named, 360), circuit(composed, 360)
    np.testing.assert_allclose(a.input, b.input, rtol=0, atol=1e-14)
    for joint in ("A0", "B0", "A", "B", "P"):
        np.testing.assert_allclose(a.positions[joint], b.positions[joint], rtol=0, atol=1e-14)


def test_paper000_fig8_example_reads_epsilon_as_minus_30():
    m = example_degrees("paper000-fig8-sixbar")
    assert m["ground"] == {"arc": 85.0, "angle": -30.0} and m["assembly"] == -1
    mech = load_example("paper000-fig8-sixbar").mechanism
    motion = solve(mech, THETA)
    assert motion.valid.all()
    pos = {k: v for k, v in motion.positions.items()}

    def arc_deg(a, b):
        return np.degrees(np.arccos(np.clip(np.sum(pos[a] * pos[b], -1), -1, 1)))

    a1 = np.radians(35)
    B0 = np.array([np.cos(a1), np.sin(a1), 0.0])
    beyond = np.array([-np.sin(a1), np.cos(a1), 0.0])  # the frame circle's tangent past B0
    E0 = pos["E0"][0]
    t = E0 - (E0 @ B0) * B0
    epsilon = np.degrees(np.arctan2(np.cross(B0, beyond) @ t, beyond @ t))
    assert abs(np.degrees(np.arccos(E0 @ B0)) - 85) < 1e-12 and abs(epsilon + 30) < 1e-12
    for (a, b), deg in {("C", "E"): 45, ("E0", "E"): 33, ("C", "D"): 30, ("A", "C"): 72}.items():
        np.testing.assert_allclose(arc_deg(a, b), deg, rtol=0, atol=1e-6)
    # C by paper 000's T matrix from A and B, as in the four-bar.
    np.testing.assert_allclose(
        pos["C"], paper000_C(pos["A"], pos["B"], np.radians(72), np.radians(22)), atol=1e-13
    )


def test_paper001_example_assembles_only_on_its_own_mode_and_holds_eq_3():
    mech = load_example("paper001-stephenson3").mechanism
    fine = np.radians(np.arange(0.0, 360.0, 0.05))
    assert solve(mech, fine, order=0).valid.all()
    other = dataclasses.replace(mech, assembly=-1.0)
    share = solve(other, fine, order=0).valid.mean()
    assert 0.55 < share < 0.57  # "about 56 percent", as the example's comment says
    pos = solve(mech, THETA).positions
    a3, a6, sigma = np.radians([50, 40, 100])
    cos_be = np.sum(pos["B"] * pos["E"], -1)
    # Paper 001, eq. 3: OB·OE = cos a3 cos a6 − sin a3 sin a6 cos σ.
    expect = np.cos(a3) * np.cos(a6) - np.sin(a3) * np.sin(a6) * np.cos(sigma)
    np.testing.assert_allclose(cos_be, expect, rtol=0, atol=1e-14)
    for (a, b), deg in {("A", "B"): 20, ("B", "C"): 50, ("C", "D"): 40, ("E", "F"): 50}.items():
        np.testing.assert_allclose(np.sum(pos[a] * pos[b], -1), np.cos(np.radians(deg)), atol=1e-14)
    np.testing.assert_allclose(np.sum(pos["F"] * pos["G"], -1), np.cos(np.radians(45)), atol=1e-14)
    # G at 90 degrees from A, beyond D (a1 + a9).
    np.testing.assert_allclose(pos["G"][0] @ pos["A"][0], 0.0, atol=1e-15)


def double_crank_coefficients(crank_deg: float) -> tuple[float, float, float, float]:
    """Paper 003's double-crank coefficients (max |Kω|, max |Kε|, max |Kp|, δ) of Table 3's
    row α2 = 65°, α3 = 60° with frame α4 = 10°, from paper 000's closed form of the output
    angle (eq. 5) differentiated by central differences on a fine grid."""
    a1, a2, a3, a4 = np.radians([10, crank_deg, 65, 60])
    n = 40000
    h = 2 * np.pi / n
    theta = np.arange(n) * h
    phi = np.unwrap(paper000_B(a1, a2, a3, a4, theta)[1])
    ahead = np.unwrap(paper000_B(a1, a2, a3, a4, theta + h)[1])
    behind = np.unwrap(paper000_B(a1, a2, a3, a4, theta - h)[1])
    # Each difference is small: wrap it to (−π, π] instead of unwrapping across arrays.
    d_up = np.angle(np.exp(1j * (ahead - phi)))
    d_down = np.angle(np.exp(1j * (phi - behind)))
    w = (d_up + d_down) / (2 * h)
    e = 2 * np.pi * (d_up - d_down) / h**2
    return (
        float(np.abs(w).max()),
        float(np.abs(e).max()),
        float(np.abs(w * e).max()),
        float(w.max() - w.min()),
    )


def test_paper003_table3_example_as_printed_and_its_supplement():
    m = example_degrees("paper003-table3-drag-link")
    assert (m["crank"], m["coupler"], m["rocker"], m["frame"]) == (80.0, 65.0, 60.0, 10.0)
    # The numbers quoted in the example's comment.
    printed = double_crank_coefficients(80.0)
    np.testing.assert_allclose(printed, [1.086, 0.790, 0.777, 0.203], rtol=0, atol=6e-4)
    supplement = double_crank_coefficients(100.0)
    np.testing.assert_allclose(supplement, [1.161, 1.466, 1.493, 0.325], rtol=0, atol=6e-4)
    # Paper 003's Table 3 row (1.16, 1.47, 1.49, 0.32) is the supplement's, to its digits.
    np.testing.assert_allclose(supplement, [1.16, 1.47, 1.49, 0.32], rtol=0, atol=0.0075)
    # And the document's linkage turns both cranks: the output angle goes once round.
    mech = load_example("paper003-table3-drag-link").mechanism
    motion = circuit(mech, 720)
    assert motion.valid.all()
    out = mech.output_angle(motion)
    turned = np.unwrap(np.append(out, out[0]))
    assert abs(abs(turned[-1] - turned[0]) - 2 * np.pi) < 1e-9


def test_the_module_docstrings_spherical_examples_are_the_fig6_examples():
    import textwrap

    import linkwright.io.documents as documents

    text = documents.__doc__
    family = text.split("Fig. 6 spherical crank-rocker::")[1].split("The same linkage")[0]
    composed = text.split("listed before it)::")[1].split("A composed linkage")[0]
    named = parse_document(tomllib.loads(textwrap.dedent(family)))
    assert named.raw["mechanism"] == load_example("paper000-fig6-crank-rocker").raw["mechanism"]
    spelled = parse_document(tomllib.loads(textwrap.dedent(composed)))
    example = load_example("paper000-fig6-linkage").raw["mechanism"]
    assert spelled.raw["mechanism"] == example
