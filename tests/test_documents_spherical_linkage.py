"""Spherical composed linkages in documents: what they build, round trips, a validation message
naming the joint for every way one is wrong, the default ``toward`` joint, and fuzzed documents
that only ever raise DocumentError.
"""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
from documents_spherical_helpers import (
    ARC,
    LINKAGE,
    close,
    linkage_family,  # noqa: F401  (autouse: the linkage family)
    with_change,
)
from hypothesis import event, given, settings
from hypothesis import strategies as st

from linkwright.io import (
    Document,
    DocumentError,
    document_to_dict,
    load_document,
    mechanism_to_dict,
    parse_document,
    save_document,
)
from linkwright.mechanisms.linkage import (
    DyadJoint,
    Linkage,
    SphereCrankJoint,
    SphereRigidJoint,
)

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
    assert close(d, document_to_dict(doc))
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
    assert close(again.raw["mechanism"], result.raw["mechanism"])
