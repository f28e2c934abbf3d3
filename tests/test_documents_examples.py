"""The bundled planar examples, checked against their stated geometry (paper 003's tables, Grashof
classes, slider offsets), and the schemas against the family registry.
"""

from __future__ import annotations

import dataclasses
import math

import pytest
from documents_helpers import (
    EXAMPLE_NAMES,
    EXAMPLES,
    LINKAGE_REGISTERED,
    family_class,
    linkage_family,  # noqa: F401  (autouse: the linkage family)
)

from linkwright.io import (
    FAMILY_SPECS,
    Document,
    DocumentError,
    list_examples,
    load_example,
)
from linkwright.io.documents import JOINT_SPECS, KINDS
from linkwright.mechanisms.linkage import Linkage

# ---------------------------------------------------------------------------------------------
# Bundled examples, checked against their stated geometry
# ---------------------------------------------------------------------------------------------


def test_list_examples():
    assert set(list_examples()) >= set(EXAMPLE_NAMES)
    assert load_example("crank-rocker.toml") == load_example("crank-rocker")
    with pytest.raises(DocumentError, match=r"^example: unknown example 'crank-rocke' \(did you"):
        load_example("crank-rocke")


@pytest.mark.parametrize("name", EXAMPLE_NAMES)
def test_examples_have_a_title_and_a_provenance_comment(name):
    text = (EXAMPLES / f"{name}.toml").read_text()
    assert text.startswith("# ")
    assert load_example(name).title


def four_lengths(doc: Document) -> tuple[float, float, float, float]:
    m = doc.raw["mechanism"]
    frame = math.dist(m["A0"], m["B0"])
    return m["crank"], m["coupler"], m["rocker"], frame


def test_crank_rocker_is_paper_003_table_1():
    doc = load_example("crank-rocker")
    assert four_lengths(doc) == (1.0, 5.0, 6.02, 3.5)
    links = sorted(four_lengths(doc))
    assert links[0] + links[3] < links[1] + links[2]  # Grashof
    assert min(four_lengths(doc)) == doc.raw["mechanism"]["crank"]  # crank shortest


def test_double_crank_is_paper_003_table_4():
    crank, coupler, rocker, frame = four_lengths(load_example("double-crank"))
    assert (crank, coupler, frame) == (4.0, 2.0, 1.0)
    assert rocker == pytest.approx(math.sqrt(13), abs=1e-15)
    assert frame == min(crank, coupler, rocker, frame)


def test_triple_rocker_is_not_grashof():
    s, p, q, l = sorted(four_lengths(load_example("triple-rocker")))
    assert s + l > p + q


def test_rocker_input_is_grashof_driven_at_a_rocker():
    crank, coupler, rocker, frame = four_lengths(load_example("rocker-input"))
    s, p, q, l = sorted((crank, coupler, rocker, frame))
    assert s + l < p + q  # Grashof
    assert rocker == s  # the output is shortest: it turns, the driven link only rocks
    # At θ = 0 the driven link puts A at (3.5, 0): 0.5 from B0, less than coupler − rocker = 4.
    m = load_example("rocker-input").raw["mechanism"]
    a = (m["A0"][0] + m["crank"], m["A0"][1])
    assert math.dist(a, m["B0"]) < m["coupler"] - m["rocker"]


def test_slider_examples_offsets():
    assert load_example("slider-crank").raw["mechanism"]["line"] == {
        "point": [0.0, 0.0],
        "angle": 0.0,
    }
    offset = load_example("offset-slider-crank")
    assert float(offset.mechanism.offset) == pytest.approx(0.5)


CLASS_NAMES = {
    "fourbar": "FourBar",
    "slidercrank": "SliderCrank",
    "geared-fivebar": "GearedFiveBar",
    "doubleslider": "DoubleSlider",
    "watt1": "Watt1",
    "watt2": "Watt2",
    "stephenson1": "Stephenson1",
    "stephenson3": "Stephenson3",
    "linkage": "Linkage",
    "spherical-fourbar": "SphericalFourBar",
    "spherical-sixbar": "SphericalSixBar",
    "spherical-stephenson3": "SphericalStephenson3",
}


def test_every_schema_names_its_class():
    assert set(CLASS_NAMES) == set(FAMILY_SPECS)


@pytest.mark.parametrize("family", sorted(FAMILY_SPECS))
def test_family_specs_cover_the_mechanism_families(family):
    cls = Linkage if family == "linkage" else family_class(family, CLASS_NAMES[family])
    spec = FAMILY_SPECS[family]
    # Fields that only say how to read the document (a linkage's space) build nothing; every
    # family's start (where it runs) is read by the document module itself.
    targets = {t for f in spec.fields if KINDS[f.kind].builds for t in f.targets}
    assert targets | {"start"} == {f.name for f in dataclasses.fields(cls)}, family


def test_linkage_is_registered_as_a_family():
    if not LINKAGE_REGISTERED:
        pytest.skip("Linkage is not registered in linkwright.mechanisms.FAMILIES yet")
    assert Linkage.family == "linkage"


def test_joint_specs_cover_the_joint_classes():
    from linkwright.mechanisms.linkage import JOINT_TYPES

    assert set(JOINT_SPECS) == set(JOINT_TYPES)
    for kind, specs in JOINT_SPECS.items():
        names = {f.name for f in dataclasses.fields(JOINT_TYPES[kind])} - {"name"}
        assert {t for f in specs for t in f.targets} == names, kind
