"""Documents and helpers shared by the planar document tests (tests/test_documents_*.py): the
bundled examples' names, a crank-rocker, a slider-crank and a composed linkage as documents,
``with_change`` to derive a near-valid one, and the fixture that registers the linkage family.
"""

from __future__ import annotations

import copy
import importlib
from pathlib import Path

import pytest

import linkwright.mechanisms
from linkwright.mechanisms import FAMILIES
from linkwright.mechanisms.linkage import Linkage

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "linkwright" / "examples"


EXAMPLE_NAMES = [
    "crank-rocker",
    "double-crank",
    "rocker-input",
    "triple-rocker",
    "slider-crank",
    "offset-slider-crank",
    "jansen-leg",
    "klann-leg",
]


@pytest.fixture(scope="module", autouse=True)
def linkage_family():
    """Documents of family ``linkage`` need the class in FAMILIES (the lead registers it there;
    until then this module registers it for its own tests)."""
    with pytest.MonkeyPatch.context() as mp:
        if "linkage" not in FAMILIES:
            mp.setitem(FAMILIES, "linkage", Linkage)
        yield


# Read before any fixture runs: whether the package itself registers the linkage family.
LINKAGE_REGISTERED = FAMILIES.get("linkage") is Linkage


def family_class(family: str, cls_name: str) -> type:
    """The class of a family whose schema is here, or a skip saying what is missing."""
    cls = getattr(linkwright.mechanisms, cls_name, None)
    if cls is None:
        try:
            module = importlib.import_module("linkwright.mechanisms.sixbar")
        except ImportError:
            module = None
        cls = getattr(module, cls_name, None)
    if cls is None:
        pytest.skip(f"linkwright.mechanisms.{cls_name} is not written yet")
    if FAMILIES.get(family) is not cls:
        pytest.skip(f"family {family!r} is not registered in linkwright.mechanisms.FAMILIES yet")
    return cls


FOURBAR = {
    "format": "linkwright/1",
    "title": "test four-bar",
    "units": "mm",
    "mechanism": {
        "family": "fourbar",
        "A0": [0, 0],
        "B0": [4, 0],
        "crank": 1,
        "coupler": 5,
        "rocker": 3.5,
        "point": {"u": 2, "v": 1},
        "assembly": -1,
    },
}


SLIDER = {
    "format": "linkwright/1",
    "mechanism": {
        "family": "slidercrank",
        "A0": [0, 0],
        "crank": 1,
        "rod": 3,
        "line": {"point": [0, -0.5], "angle": 30},
    },
}


def with_change(base: dict, path: str, value: object = ..., delete: bool = False) -> dict:
    """A deep copy of ``base`` with the dotted ``path`` set to ``value`` (or deleted)."""
    doc = copy.deepcopy(base)
    *parents, last = path.split(".")
    node = doc
    for key in parents:
        node = node[key]
    if delete:
        del node[last]
    else:
        node[last] = value
    return doc


# ---------------------------------------------------------------------------------------------
# Composed linkages
# ---------------------------------------------------------------------------------------------

LINKAGE = {
    "format": "linkwright/1",
    "title": "four-bar, joint by joint",
    "mechanism": {
        "family": "linkage",
        "joints": [
            {"name": "A0", "type": "fixed", "at": [0, 0]},
            {"name": "B0", "type": "fixed", "at": [4, 0]},
            {"name": "A", "type": "crank", "pivot": "A0", "length": 1, "phase": 30},
            {"name": "B", "type": "rrr", "p1": "A", "r1": 5, "p2": "B0", "r2": 3.5},
            {"name": "P", "type": "rigid", "origin": "A", "toward": "B", "u": 2, "v": 1},
            {"name": "S", "type": "rrp", "p1": "B", "r": 2, "line_point": "B0", "line_angle": 90},
        ],
    },
}
