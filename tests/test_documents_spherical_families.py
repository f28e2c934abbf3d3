"""Spherical families in mechanism documents: what they build (radians inside), the schema against
the classes, validation messages naming the field before the class sees the number, and round
trips document → mechanism → document and back, compared with ``math.radians`` of what the
document says.
"""

from __future__ import annotations

import dataclasses
import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
from documents_spherical_helpers import (
    ARC,
    CLASSES,
    FOURBAR,
    SIXBAR,
    STEPHENSON,
    close,
    linkage_family,  # noqa: F401  (autouse: the linkage family)
    with_change,
)
from hypothesis import given, settings
from hypothesis import strategies as st

from linkwright.io import (
    FAMILY_SPECS,
    DocumentError,
    document_to_dict,
    load_document,
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
)
from linkwright.mechanisms.linkage import (
    SPHERE_JOINT_TYPES,
)

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
    # Every field but start (where it runs), which the document module reads itself.
    assert targets | {"start"} == {f.name for f in dataclasses.fields(CLASSES[family])}
    assert FAMILIES[family] is CLASSES[family]


def test_sphere_joint_schema_covers_the_sphere_joint_classes():
    assert (
        set(SPHERE_JOINT_SPECS)
        == set(SPHERE_JOINT_TYPES)
        == {"fixed", "crank", "rrr", "rigid", "hinge", "triad", "hinge-triad", "turning-triad"}
    )
    for kind, specs in SPHERE_JOINT_SPECS.items():
        names = {f.name for f in dataclasses.fields(SPHERE_JOINT_TYPES[kind])} - {"name"}
        assert {t for f in specs for t in f.targets} == names, kind


# ---------------------------------------------------------------------------------------------
# Validation: the document names the field before the class sees the number
# ---------------------------------------------------------------------------------------------

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
    (
        STEPHENSON,
        "mechanism.input",
        "output",
        "mechanism.input: unknown value 'output' (known: AB, FG, DC, B, C, E, F)",
    ),
    (
        STEPHENSON,
        "mechanism.input",
        1,
        'mechanism.input: must be one of "AB", "FG", "DC", "B", "C", "E" or "F", got 1',
    ),
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
    assert close(again, document_to_dict(doc)), (again, doc.raw)
    # ... and the fields it builds are the same numbers (the unit vectors derived from them,
    # E0 from a large ε say, follow to the angle's absolute rounding, not compared here).
    reparsed = parse_document(again).mechanism
    for f in dataclasses.fields(reparsed):
        ours, theirs = getattr(reparsed, f.name), getattr(doc.mechanism, f.name)
        if isinstance(ours, str) or ours is None:
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
        if ours is None:  # no start given, none written back
            assert theirs is None
            continue
        np.testing.assert_allclose(ours, theirs, rtol=1e-13, atol=1e-300, err_msg=f.name)


def test_mechanism_to_dict_of_each_family_is_what_the_document_said():
    for base in (FOURBAR, SIXBAR, STEPHENSON):
        doc = parse_document(base)
        assert mechanism_to_dict(doc.mechanism, title=doc.title) == document_to_dict(doc)


def test_a_batched_spherical_mechanism_cannot_be_written():
    batch = SphericalFourBar(*np.radians([40, 45, 35]), rocker=np.radians([30, 35]))
    with pytest.raises(DocumentError, match=r"^mechanism\.rocker: must be a single value"):
        mechanism_to_dict(batch)
