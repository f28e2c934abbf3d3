"""What every joint spec of a composed linkage shares (:mod:`.joints`, :mod:`.hinge_joints`):
equality by value, and the triads' names of the joints they read and place."""

from __future__ import annotations

from dataclasses import fields
from typing import Any, ClassVar

import numpy as np

__all__ = ["JointSpec", "TriadSpec"]


class JointSpec:
    """Equality by value, arrays included: two specs are equal when every field is.

    The dataclass default compares field tuples with ``==``, which for a point (an array of
    two) has no single truth value; comparing the arrays whole makes linkages comparable.
    """

    # Every spec is a dataclass: this tells the type checker so (dataclasses sets it).
    __dataclass_fields__: ClassVar[dict[str, Any]]

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return all(_same_value(getattr(self, f.name), getattr(other, f.name)) for f in fields(self))

    __hash__ = None  # type: ignore[assignment]  # specs may hold arrays


def _same_value(a: Any, b: Any) -> bool:
    if isinstance(a, str) or isinstance(b, str):
        return bool(a == b)
    try:
        return bool(np.array_equal(np.asarray(a), np.asarray(b)))
    except (TypeError, ValueError):
        return bool(a == b)


class TriadSpec(JointSpec):
    """What the triads share, driven at a hinge or not: the joints it places and reads."""

    name: str
    j2: str
    j3: str
    p1: str
    p2: str
    p3: str

    type: ClassVar[str] = "triad"

    @property
    def parents(self) -> tuple[str, ...]:
        return (self.p1, self.p2, self.p3)

    @property
    def placed(self) -> tuple[str, ...]:
        """The joints it places: J1 (its name), J2, J3 (and a driven hinge)."""
        return (self.name, self.j2, self.j3)
