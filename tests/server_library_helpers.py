"""Documents shared by the workbench library's tests (tests/test_server_library_*.py), and the
canonical form the store must keep: :func:`linkwright.io.parse_document` of what went in (the
validator, independent of the store).
"""

from __future__ import annotations

import copy

from linkwright.io import (
    document_to_dict,
    parse_document,
)

CRANK_ROCKER = {
    "format": "linkwright/1",
    "title": "Crank-rocker",
    "mechanism": {
        "family": "fourbar",
        "A0": [0.0, 0.0],
        "B0": [3.5, 0.0],
        "crank": 1.0,
        "coupler": 5.0,
        "rocker": 6.02,
        "point": {"u": 2.5, "v": 1.5},
        "assembly": 1,
    },
}


SLIDER = {
    "format": "linkwright/1",
    "mechanism": {
        "family": "slidercrank",
        "A0": [0, 0],
        "crank": 1,
        "rod": 3,
        "line": {"point": [0, 0], "angle": 0},
    },
}


def with_mechanism(doc: dict, **fields: object) -> dict:
    out = copy.deepcopy(doc)
    out["mechanism"].update(fields)
    return out


def canonical(doc: dict) -> dict:
    """What the store must keep for ``doc``: the validator's canonical form."""
    return document_to_dict(parse_document(doc))
