"""Fuzzing the document parser: arbitrary values, near-valid documents, arbitrary file text and
random composed linkages (joint lists, wrong types, missing fields, cycles) only ever raise
DocumentError; any title and numbers round-trip.
"""

from __future__ import annotations

import contextlib
import copy
import math
import tempfile
import tomllib
from pathlib import Path

from documents_helpers import (
    EXAMPLES,
    FOURBAR,
    LINKAGE,
    SLIDER,
    linkage_family,  # noqa: F401  (autouse: the linkage family)
    with_change,
)
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from linkwright.io import (
    FAMILY_SPECS,
    Document,
    DocumentError,
    document_to_dict,
    load_document,
    mechanism_to_dict,
    parse_document,
    save_document,
)
from linkwright.io.documents import JOINT_SPECS
from linkwright.mechanisms.linkage import Linkage

# ---------------------------------------------------------------------------------------------
# Fuzzing: the parser only ever raises DocumentError
# ---------------------------------------------------------------------------------------------

scalars = (
    st.none()
    | st.booleans()
    | st.integers(min_value=-(10**20), max_value=10**20)
    | st.integers()
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=12)
    | st.sampled_from(["fourbar", "slidercrank", "linkwright/1", "u", "v", "point", "angle"])
)


json_like = st.recursive(
    scalars,
    lambda children: (
        st.lists(children, max_size=4)
        | st.dictionaries(
            st.text(max_size=8) | st.sampled_from(["u", "v", "point", "angle"]),
            children,
            max_size=4,
        )
    ),
    max_leaves=12,
)


field_names = st.sampled_from(
    sorted({f.name for spec in FAMILY_SPECS.values() for f in spec.fields} | {"family", "zzz"})
)


@st.composite
def near_valid_documents(draw):
    """A valid document with a few fields replaced, removed or added at random."""
    doc = copy.deepcopy(draw(st.sampled_from([FOURBAR, SLIDER])))
    mech = doc["mechanism"]
    for _ in range(draw(st.integers(0, 3))):
        name = draw(field_names)
        action = draw(st.sampled_from(["set", "delete", "nested"]))
        if action == "delete":
            mech.pop(name, None)
        elif action == "nested" and isinstance(mech.get(name), dict):
            mech[name][draw(st.sampled_from(["u", "v", "point", "angle", "x"]))] = draw(json_like)
        else:
            mech[name] = draw(json_like)
    if draw(st.booleans()):
        doc[draw(st.sampled_from(["format", "title", "units", "other"]))] = draw(json_like)
    return doc


@settings(max_examples=300, deadline=None)
@given(json_like)
def test_fuzz_arbitrary_values_only_raise_document_error(value):
    with contextlib.suppress(DocumentError):
        parse_document(value)


@settings(max_examples=400, deadline=None)
@given(near_valid_documents())
def test_fuzz_near_valid_documents_only_raise_document_error(doc):
    try:
        result = parse_document(doc)
    except DocumentError as exc:
        assert str(exc).split(":")[0] in {"document", "format", "title", "units"} or str(
            exc
        ).startswith("mechanism")
    else:
        assert isinstance(result, Document)
        assert parse_document(document_to_dict(result)) == result


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.text(max_size=80), st.sampled_from([".toml", ".json"]))
def test_fuzz_arbitrary_file_text_only_raises_document_error(text, suffix):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"doc{suffix}"
        path.write_text(text, encoding="utf-8", errors="surrogatepass")
        with contextlib.suppress(DocumentError):
            load_document(path)


@settings(max_examples=150, deadline=None)
@given(
    title=st.text(max_size=30),
    crank=st.floats(min_value=1e-6, max_value=1e6),
    angle=st.floats(min_value=-720, max_value=720),
    suffix=st.sampled_from([".toml", ".json"]),
)
def test_fuzz_round_trip_of_any_title_and_numbers(title, crank, angle, suffix):
    doc = with_change(with_change(SLIDER, "mechanism.crank", crank), "mechanism.line.angle", angle)
    doc["title"] = title
    try:
        parsed = parse_document(doc)
    except DocumentError as exc:
        # Only a title that cannot be written as UTF-8 (a lone surrogate) is refused.
        assert str(exc).startswith("title: must be valid Unicode text")
        return
    with tempfile.TemporaryDirectory() as tmp:
        path = save_document(parsed, Path(tmp) / f"doc{suffix}")
        assert load_document(path) == parsed


# ---------------------------------------------------------------------------------------------
# Fuzzing the linkage parser: random joint lists, wrong types, missing fields, cycles
# ---------------------------------------------------------------------------------------------

joint_names = st.sampled_from(["O", "Q", "A", "B", "C", "P"])


name_values = joint_names | st.sampled_from(["", "X", 3, None, ["A"]])


number_values = (
    st.floats(-10, 10, allow_nan=False)
    | st.integers(-3, 3)
    | st.sampled_from([0, -1, 1, math.nan, math.inf, 1e308, "1", True])
)


point_values = st.lists(number_values, min_size=1, max_size=3) | st.tuples(
    st.floats(-5, 5), st.floats(-5, 5)
).map(list)


FIELD_VALUES = {
    "at": point_values,
    "pivot": name_values,
    "p1": name_values,
    "far": name_values,
    "z": name_values,
    "y": name_values,
    "p2": name_values,
    "line_point": name_values,
    "origin": name_values,
    "toward": name_values,
    "length": number_values,
    "r1": number_values,
    "r2": number_values,
    "r": number_values,
    "a": number_values,
    "b": number_values,
    "ratio": number_values,
    "phase": number_values,
    "line_angle": number_values,
    "u": number_values,
    "v": number_values,
    "assembly": st.sampled_from([1, -1, 0, 2, 1.0, "1"]),
    "j2": name_values,
    "j3": name_values,
    "hinge": name_values,
    "p3": name_values,
    "hu": number_values,
    "hv": number_values,
    "arm": number_values,
    "harc": number_values,
    "hangle": number_values,
    "r3": number_values,
    "side": number_values,
    "pose": st.sampled_from([0, 1, 5, 6, -1, 0.5, "0"]),
}


@st.composite
def joint_tables(draw):
    kind = draw(st.sampled_from([*JOINT_SPECS, "rr", 7]))
    entry = {"name": draw(name_values), "type": kind}
    names = [f.name for f in JOINT_SPECS.get(kind, ())] or draw(
        st.lists(st.sampled_from(sorted(FIELD_VALUES)), max_size=3)
    )
    for field_name in names:
        if draw(st.integers(0, 9)) == 0:
            continue  # a missing field
        entry[field_name] = draw(FIELD_VALUES[field_name])
    if draw(st.integers(0, 9)) == 0:
        entry[draw(st.sampled_from(sorted(FIELD_VALUES) + ["zzz"]))] = draw(json_like)
    if draw(st.integers(0, 19)) == 0:
        del entry[draw(st.sampled_from(["name", "type"]))]
    return entry


@st.composite
def linkage_documents(draw):
    if draw(st.booleans()):
        joints = draw(st.lists(joint_tables(), max_size=7))
    else:
        # A valid leg, shuffled (forward references and cycles) and a little damaged.
        joints = copy.deepcopy(draw(st.sampled_from(LEG_JOINTS)))
        if draw(st.booleans()):
            joints = draw(st.permutations(joints))
        for _ in range(draw(st.integers(0, 2))):
            i = draw(st.integers(0, len(joints) - 1))
            key = draw(st.sampled_from(sorted(joints[i])))
            joints[i][key] = draw(FIELD_VALUES.get(key, name_values))
    mech = {"family": "linkage", "joints": joints}
    if draw(st.booleans()):
        mech["traced"] = draw(st.lists(name_values, max_size=3) | json_like)
    if draw(st.integers(0, 4)) == 0:
        mech["space"] = draw(st.sampled_from(["plane", "sphere", "", 1]))
    return {"format": "linkwright/1", "mechanism": mech}


LEG_JOINTS = [
    tomllib.loads((EXAMPLES / f"{name}.toml").read_text())["mechanism"]["joints"]
    for name in ("jansen-leg", "klann-leg")
] + [LINKAGE["mechanism"]["joints"]]


@settings(max_examples=400, deadline=None)
@given(linkage_documents())
def test_fuzz_linkage_documents_only_raise_document_error(doc):
    try:
        result = parse_document(doc)
    except DocumentError as exc:
        assert str(exc).startswith("mechanism")
    else:
        assert isinstance(result.mechanism, Linkage)
        assert parse_document(document_to_dict(result)) == result
        # From the mechanism (radians) back to degrees an angle may move by an ulp or two.
        again = parse_document(mechanism_to_dict(result.mechanism))
        assert _close(again.raw["mechanism"], result.raw["mechanism"])


def _close(a, b) -> bool:
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_close(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_close(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) or isinstance(b, float):
        return math.isclose(a, b, rel_tol=1e-13, abs_tol=1e-300)
    return a == b
