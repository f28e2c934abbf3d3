"""Documents and helpers shared by the spherical document tests
(tests/test_documents_spherical_*.py): a spherical four-bar, six-bar, Stephenson III and composed
linkage as documents, ``with_change`` to derive a near-valid one, and the fixture that registers
the linkage family.

Documents speak degrees, mechanisms radians: the tests compare numbers read back with
``math.radians`` of what the document says, or with a closed form written out from the papers.
"""

from __future__ import annotations

import copy
import math
from pathlib import Path

import pytest

from linkwright.mechanisms import (
    FAMILIES,
    SphericalFourBar,
    SphericalSixBar,
    SphericalStephenson3,
)
from linkwright.mechanisms.linkage import (
    Linkage,
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


def close(a, b, rel: float = 1e-13) -> bool:
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(close(a[k], b[k], rel) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(close(x, y, rel) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) or isinstance(b, float):
        # Subnormal degrees come back from radians as the nearest subnormal, hence abs_tol.
        return math.isclose(a, b, rel_tol=rel, abs_tol=1e-300)
    return a == b


# The start of the message for an arc out of range, as the validation tests expect it.

ARC = "must be an arc strictly between 0 and 180 degrees, got"
