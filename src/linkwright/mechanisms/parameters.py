"""A named parameter vector for every plan: the free numbers of a mechanism, with their kinds,
their bounds and the symmetries a search must forget.

The kinds of a free number, the roles of a plan's numbers, :class:`Parameter` and
:class:`ParameterVector` (with its symmetries) are in :mod:`.parameter_types`; deriving a
family's vector (:func:`parameter_vector`, :func:`family_template`) is in
:mod:`.parameter_derivation`. Both are re-exported here, with :func:`encode` and :func:`decode`
(a mechanism as plain data).

Discrete choices stay out of the vector: assembly signs, a triad's pose index, the word that
chooses a plan (a Stephenson III's ``input``) and a composed linkage's structure (joint names,
types, parents, traced joints). :meth:`ParameterVector.from_vector` takes them from a template.

This module is the hook the family registry can feed: where a family declares its fields' kinds
itself, :func:`parameter_vector` can read them there instead of deriving them.

Examples
--------
>>> from linkwright.mechanisms import FourBar
>>> m = FourBar(A0=[1, 2], B0=[1, 6], crank=1, coupler=4, rocker=3.5, u=2, v=1)
>>> vector = parameter_vector(m)
>>> vector.names
('A0.x', 'A0.y', 'B0.x', 'B0.y', 'crank', 'coupler', 'rocker', 'u', 'v')
>>> vector.kinds[:5], vector.discrete
(('coordinate', 'coordinate', 'coordinate', 'coordinate', 'length'), ('assembly',))
>>> vector.to_vector(m)
array([1. , 2. , 1. , 6. , 1. , 4. , 3.5, 2. , 1. ])
>>> vector.from_vector(m, vector.to_vector(m)) == m
True

Normalised, A0 is at the origin, B0 on +x and the largest link (here the frame, 4) is 1:

>>> vector.to_vector(vector.normalise(m)).round(12) + 0.0
array([0.   , 0.   , 1.   , 0.   , 0.25 , 1.   , 0.875, 0.5  , 0.25 ])
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import fields
from typing import Any

import numpy as np

from linkwright.mechanisms.base import Mechanism
from linkwright.mechanisms.parameter_derivation import family_template, parameter_vector
from linkwright.mechanisms.parameter_types import (
    KINDS,
    ROLES,
    Parameter,
    ParameterError,
    ParameterVector,
    is_linkage,
)

__all__ = [
    "KINDS",
    "ROLES",
    "Parameter",
    "ParameterError",
    "ParameterVector",
    "decode",
    "encode",
    "family_template",
    "parameter_vector",
]


# --------------------------------------------------------------------------------------------
# A mechanism as plain data (a template kept in an atlas's JSON spec)
# --------------------------------------------------------------------------------------------


def _plain(value: Any) -> Any:
    if isinstance(value, str) or value is None:
        return value
    if isinstance(value, tuple | list):
        return [_plain(v) for v in value]
    return np.asarray(value, dtype=float).tolist()


def encode(mech: Mechanism) -> dict[str, Any]:
    """One mechanism as plain JSON data (radians, every field; a composed linkage joint by
    joint), which :func:`decode` turns back into an equal mechanism.

    >>> from linkwright.mechanisms import FourBar
    >>> m = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=4, rocker=3.5, u=2, v=1)
    >>> decode(encode(m)) == m
    True
    """
    if mech.batch_shape:
        raise ParameterError("a template is one mechanism, not a batch")
    out: dict[str, Any] = {"family": mech.family}
    if is_linkage(mech):
        out["space"] = mech.space
        out["traced"] = list(mech.traced or ())
        out["start"] = mech.start
        out["joints"] = [
            {"spec": type(j).__name__, **{f.name: _plain(getattr(j, f.name)) for f in fields(j)}}
            for j in mech.joints
        ]
        return out
    for f in fields(mech):
        out[f.name] = _plain(getattr(mech, f.name))
    return out


def decode(data: Mapping[str, Any]) -> Mechanism:
    """The mechanism :func:`encode` wrote (an :class:`InvalidMechanism` if it is not one)."""
    from linkwright.mechanisms import FAMILIES
    from linkwright.mechanisms.joints import ALL_SPECS
    from linkwright.mechanisms.linkage import Linkage

    if not isinstance(data, Mapping) or data.get("family") not in FAMILIES:
        raise ParameterError(f"not an encoded mechanism: {str(data)[:80]}")
    body = {k: v for k, v in data.items() if k != "family"}
    if data["family"] != "linkage":
        return FAMILIES[data["family"]](**body)

    specs = {cls.__name__: cls for cls in ALL_SPECS}
    joints = []
    for entry in body["joints"]:
        fields_ = {k: v for k, v in entry.items() if k != "spec"}
        joints.append(specs[entry["spec"]](**fields_))
    return Linkage(
        joints=tuple(joints),
        traced=tuple(body["traced"]),
        space=body["space"],
        start=body.get("start"),
    )
