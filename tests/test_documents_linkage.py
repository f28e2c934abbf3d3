"""Documents of composed linkages: what they build, round trips through ``mechanism_to_dict`` and
files, a validation message naming the joint for every way one is wrong, and the TOML writer's
layout.
"""

from __future__ import annotations

import copy
import math
import textwrap
import tomllib

import numpy as np
import pytest
from documents_helpers import (
    LINKAGE,
    linkage_family,  # noqa: F401  (autouse: the linkage family)
    with_change,
)

from linkwright.io import (
    DocumentError,
    document_to_dict,
    load_document,
    load_example,
    mechanism_to_dict,
    parse_document,
    save_document,
)
from linkwright.io.documents import dumps_toml
from linkwright.mechanisms import solve
from linkwright.mechanisms.linkage import CrankJoint, DyadJoint, FixedJoint, Linkage, RigidJoint


def test_linkage_document_builds_the_linkage():
    doc = parse_document(LINKAGE)
    m = doc.mechanism
    assert isinstance(m, Linkage) and doc.family == "linkage"
    assert m.traced == ("S",)  # the last joint by default
    raw = doc.raw["mechanism"]
    assert raw["space"] == "plane" and raw["traced"] == ["S"]
    assert raw["joints"][2] == {
        "name": "A",
        "type": "crank",
        "pivot": "A0",
        "length": 1.0,
        "ratio": 1.0,
        "phase": 30.0,
    }
    assert raw["joints"][3]["assembly"] == 1
    assert float(m.joint("A").phase) == pytest.approx(math.pi / 6, abs=1e-15)
    assert float(m.joint("S").line_angle) == pytest.approx(math.pi / 2, abs=1e-15)
    assert m == Linkage(
        joints=(
            FixedJoint("A0", [0, 0]),
            FixedJoint("B0", [4, 0]),
            CrankJoint("A", "A0", 1, phase=math.radians(30)),
            DyadJoint("B", "A", 5, "B0", 3.5),
            RigidJoint("P", "A", "B", 2, 1),
            m.joint("S"),
        )
    )


def test_the_module_docstrings_linkage_example_is_the_crank_rocker_example():
    import linkwright.io.documents as documents

    text = documents.__doc__.split("tracing its coupler point P)::")[1]
    doc = parse_document(tomllib.loads(textwrap.dedent(text)))
    assert doc.family == "linkage" and doc.mechanism.traced == ("P",)
    named = load_example("crank-rocker").mechanism
    theta = np.linspace(0, 2 * np.pi, 12)
    np.testing.assert_allclose(
        solve(doc.mechanism, theta).positions["P"],
        solve(named, theta).positions["P"],
        rtol=0,
        atol=1e-12,
    )


def test_linkage_round_trips_through_mechanism_to_dict_and_files(tmp_path):
    doc = parse_document(with_change(LINKAGE, "mechanism.traced", ["P", "B"]))
    d = mechanism_to_dict(doc.mechanism, title=doc.title)
    assert d == document_to_dict(doc)
    assert parse_document(d) == doc
    for suffix in (".toml", ".json"):
        path = save_document(doc, tmp_path / f"l{suffix}")
        assert load_document(path) == doc
    text = (tmp_path / "l.toml").read_text()
    assert text.count("[[mechanism.joints]]") == 6
    assert 'traced = ["P", "B"]' in text


def test_linkage_from_code_round_trips():
    m = Linkage(
        joints=(
            FixedJoint("O", [0.0, 0.0]),
            CrankJoint("A", "O", 1.0, ratio=-2.0, phase=math.radians(-45)),
            CrankJoint("G", "A", 0.25),
        ),
        traced=("G", "A"),
    )
    d = mechanism_to_dict(m)
    assert d["mechanism"]["joints"][1]["phase"] == -45.0
    assert d["mechanism"]["joints"][1]["ratio"] == -2.0
    assert parse_document(d).mechanism == m


def test_mechanism_to_dict_refuses_a_batched_linkage_naming_the_joint():
    m = Linkage(joints=(FixedJoint("O", [0, 0]), CrankJoint("A", "O", [1.0, 2.0])))
    with pytest.raises(DocumentError, match=r"^mechanism\.joints\[1\]\.length: must be a single"):
        mechanism_to_dict(m)


def joint_change(index: int, key: str, value: object = ..., delete: bool = False) -> dict:
    doc = copy.deepcopy(LINKAGE)
    entry = doc["mechanism"]["joints"][index]
    if delete:
        del entry[key]
    else:
        entry[key] = value
    return doc


LINKAGE_ERRORS = [
    (joint_change(3, "r1", -2), "mechanism.joints[3].r1: must be a positive number, got -2"),
    (
        joint_change(3, "r3", 1),
        "mechanism.joints[3]: unknown field 'r3' (known: name, type, p1, r1, p2, r2, assembly)",
    ),
    (joint_change(3, "assmbly", 1), "mechanism.joints[3]: unknown field 'assmbly' (did you mean"),
    (joint_change(3, "r1", delete=True), "mechanism.joints[3].r1: missing required field"),
    (joint_change(3, "assembly", 0), "mechanism.joints[3].assembly: must be 1 or -1, got 0"),
    (joint_change(2, "ratio", 0), "mechanism.joints[2].ratio: must be a nonzero number, got 0"),
    (joint_change(2, "phase", "30deg"), "mechanism.joints[2].phase: must be an angle in degrees"),
    (joint_change(0, "at", [0]), "mechanism.joints[0].at: must be a point [x, y], got [0]"),
    (joint_change(4, "u", None), "mechanism.joints[4].u: must be a number, got null"),
    (joint_change(5, "line_angle", delete=True), "mechanism.joints[5].line_angle: missing"),
    (
        joint_change(3, "p1", ""),
        "mechanism.joints[3].p1: must be a joint name (a non-empty string)",
    ),
    (joint_change(3, "p1", 7), "mechanism.joints[3].p1: must be a joint name (a non-empty string)"),
    (joint_change(3, "name", delete=True), "mechanism.joints[3].name: missing required field"),
    (joint_change(3, "type", delete=True), "mechanism.joints[3].type: missing required field (one"),
    (joint_change(3, "type", "rr"), "mechanism.joints[3].type: unknown joint type 'rr' (did you"),
    (joint_change(3, "type", 3), "mechanism.joints[3].type: must be a string, got 3"),
    (
        joint_change(3, "p1", "X"),
        "mechanism.joints[3]: joint 'B' is built from 'X', which is not placed before it (no "
        "joint has that name; under-constrained)",
    ),
    (
        joint_change(3, "p1", "P"),
        "mechanism.joints[3]: joint 'B' is built from 'P', which is not placed before it (it is "
        "listed after it; under-constrained)",
    ),
    (joint_change(3, "p2", "A"), "mechanism.joints[3]: joint 'B': p1 and p2 are both 'A'"),
    (joint_change(1, "name", "A0"), "mechanism.joints[1]: joint 'A0' is listed twice"),
    (
        joint_change(1, "at", [0, 0]),
        "mechanism.joints[1]: joint 'B0' repeats joint 'A0' (a ground pivot at the same place)",
    ),
    (
        joint_change(4, "toward", "B0"),
        "mechanism.joints[4]: joint 'P' is fixed on the link 'A'→'B0', but those two joints are "
        "not on one rigid link",
    ),
    (
        with_change(LINKAGE, "mechanism.joints", [{"name": "O", "type": "fixed", "at": [0, 0]}]),
        "mechanism.joints: nothing drives the linkage: none of its joints is a crank",
    ),
    (
        with_change(LINKAGE, "mechanism.joints", []),
        "mechanism.joints: a linkage needs joints",
    ),
    (with_change(LINKAGE, "mechanism.joints", {"A": 1}), "mechanism.joints: must be a list"),
    (with_change(LINKAGE, "mechanism.joints", [3]), "mechanism.joints[0]: must be a joint table"),
    (
        with_change(LINKAGE, "mechanism.joints", delete=True),
        "mechanism.joints: missing required field (a list of joint tables",
    ),
    (with_change(LINKAGE, "mechanism.traced", ["Q"]), "mechanism.traced[0]: unknown joint 'Q'"),
    (with_change(LINKAGE, "mechanism.traced", []), "mechanism.traced: must name at least one"),
    (with_change(LINKAGE, "mechanism.traced", "P"), "mechanism.traced: must be a list of joint"),
    (with_change(LINKAGE, "mechanism.traced", ["P", "P"]), "mechanism.traced[1]: joint 'P' is"),
    (with_change(LINKAGE, "mechanism.traced", [1]), "mechanism.traced[0]: must be a joint name"),
    (
        with_change(LINKAGE, "mechanism.space", "sphere"),
        "mechanism.joints[0].at: must be an axis [x, y, z]",
    ),
    (with_change(LINKAGE, "mechanism.space", "plain"), "mechanism.space: unknown value 'plain'"),
    (
        with_change(LINKAGE, "mechanism.space", 2),
        'mechanism.space: must be "plane" or "sphere", got 2',
    ),
    (with_change(LINKAGE, "mechanism.joint", []), "mechanism: unknown field 'joint' (did you"),
]


@pytest.mark.parametrize(("doc", "message"), LINKAGE_ERRORS)
def test_linkage_validation_messages(doc, message):
    with pytest.raises(DocumentError) as info:
        parse_document(doc)
    assert str(info.value).startswith(message)
    assert info.value.field == message.split(": ")[0]


def test_toml_writer_puts_arrays_of_tables_after_plain_keys():
    text = dumps_toml(
        {"format": "x", "mechanism": {"joints": [{"a": 1}, {"b": [1.0, 2.0]}], "t": 2}}
    )
    assert text == (
        'format = "x"\n\n[mechanism]\nt = 2\n\n[[mechanism.joints]]\na = 1\n\n'
        "[[mechanism.joints]]\nb = [1.0, 2.0]\n"
    )
