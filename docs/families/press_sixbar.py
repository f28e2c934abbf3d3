"""A family of one's own, in one file: a crank-rocker whose coupler drives a press ram.

A four-bar (A0, B0, crank A, coupler AB, rocker B0B) carries a point C on its coupler; a rod
CD drives the ram D along a fixed guide through the point L at the angle ``guide``. It is a
six-link press (a Watt-type six-bar with a sliding output), built from the engine's own steps:
no new geometry. Registering it is all it takes for documents, the command line, the pictures
and the workbench to know it (docs/families.md).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

from linkwright.engine import Crank, DyadRRP, DyadRRR, Fixed, Motion, Plan, Rigid
from linkwright.geometry import plane
from linkwright.mechanisms import Mechanism
from linkwright.mechanisms.base import family_dataclass
from linkwright.mechanisms.registry import Family, FieldSpec, register


@family_dataclass
class PressSixBar(Mechanism):
    """A crank-rocker whose coupler point C drives a ram D along a fixed guide."""

    A0: ArrayLike
    B0: ArrayLike
    crank: ArrayLike
    coupler: ArrayLike
    rocker: ArrayLike
    u1: ArrayLike
    v1: ArrayLike
    rod: ArrayLike
    L: ArrayLike
    guide: ArrayLike
    assembly: ArrayLike = 1.0
    assembly2: ArrayLike = 1.0

    family: ClassVar[str] = "press-sixbar"
    point_fields: ClassVar[frozenset[str]] = frozenset({"A0", "B0", "L"})
    length_fields: ClassVar[tuple[str, ...]] = ("crank", "coupler", "rocker", "rod")
    reported_joints: ClassVar[tuple[str, ...]] = ("A0", "B0", "A", "B", "C", "D")
    traced_joint: ClassVar[str] = "D"
    plan: ClassVar[Plan] = Plan(
        (
            Fixed("A0", "A0"),
            Fixed("B0", "B0"),
            Fixed("L", "L"),
            Crank("A", "A0", "crank"),
            DyadRRR("B", "A", "coupler", "B0", "rocker", branch="assembly"),
            Rigid("C", "A", "B", "u1", "v1"),
            DyadRRP("D", "C", "rod", "L", "guide", branch="assembly2"),
        ),
        traced=("D", "C"),
    )

    def residuals(self, motion: Motion) -> dict[str, np.ndarray]:
        """Each link's length error and the ram's distance from its guide, at every sample."""
        p = motion.positions

        def length(a: str, b: str, size: ArrayLike) -> np.ndarray:
            return plane.norm(p[b] - p[a]) - np.asarray(size)[..., None]

        normal = plane.perp(plane.unit_direction(np.asarray(self.guide)))[..., None, :]
        return {
            "crank": length("A0", "A", self.crank),
            "coupler": length("A", "B", self.coupler),
            "rocker": length("B0", "B", self.rocker),
            "rod": length("C", "D", self.rod),
            "guide": plane.dot(p["D"] - np.asarray(self.L)[..., None, :], normal),
        }


register(
    Family(
        name="press-sixbar",
        cls=PressSixBar,
        display="Press six-bar",
        group="Six-bars",
        space="plane",
        example="crank-rocker",  # a bundled example opens a new family until it has its own
        fields=(
            FieldSpec("A0", "point"),
            FieldSpec("B0", "point"),
            FieldSpec("crank", "length"),
            FieldSpec("coupler", "length"),
            FieldSpec("rocker", "length"),
            FieldSpec("C", "uv", ("u1", "v1")),
            FieldSpec("rod", "length"),
            FieldSpec("guide", "line", ("L", "guide")),
            FieldSpec("assembly", "sign", default=1),
            FieldSpec("assembly2", "sign", default=1),
        ),
        distinct=(("B0", "A0", "the frame A0B0 must have a positive length"),),
        joints=(
            ("A0", "crank pivot"),
            ("B0", "rocker pivot"),
            ("A", "crank-coupler joint"),
            ("B", "coupler-rocker joint"),
            ("C", "on the coupler, where the rod hangs"),
            ("D", "the ram, on its guide"),
        ),
        source="docs/families.md (a worked example)",
    )
)
