"""Planar named families: the four-bar and the slider-crank.

Joint letters follow the foundation contract (paper 003's roles: crank, coupler, output, frame).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine import Crank, DyadRRP, DyadRRR, Fixed, Motion, Plan, Rigid
from linkwright.geometry import plane
from linkwright.mechanisms.base import Mechanism

__all__ = ["FourBar", "SliderCrank"]

Array = NDArray[np.float64]


def _link_error(motion: Motion, a: str, b: str, length: Array) -> Array:
    return plane.norm(motion.positions[b] - motion.positions[a]) - np.asarray(length)[..., None]


def _frame_error(motion: Motion, origin: str, toward: str, point: str, u, v) -> Array:
    """How far the traced point is from its place (u, v) in the frame origin→toward."""
    o, t, p = (motion.positions[k] for k in (origin, toward, point))
    e = (t - o) / plane.norm(t - o)[..., None]
    rel = p - o
    return np.hypot(
        plane.dot(rel, e) - np.asarray(u)[..., None], plane.cross(e, rel) - np.asarray(v)[..., None]
    )


@dataclass(frozen=True)
class FourBar(Mechanism):
    """Planar four-bar: crank A0A, coupler AB, rocker B0B, frame A0B0, coupler point P.

    Input θ is the angle of A − A0, counter-clockwise from +x. P sits at (u, v) in the coupler
    frame with origin A and x-axis along A→B (v to the left). ``assembly`` is the sign of
    (B0 − A) × (B − A). Joints: A0, B0, A, B, P.
    """

    A0: ArrayLike
    B0: ArrayLike
    crank: ArrayLike
    coupler: ArrayLike
    rocker: ArrayLike
    u: ArrayLike = 0.0
    v: ArrayLike = 0.0
    assembly: ArrayLike = 1.0

    family: ClassVar[str] = "fourbar"
    point_fields: ClassVar[frozenset[str]] = frozenset({"A0", "B0"})
    length_fields: ClassVar[tuple[str, ...]] = ("crank", "coupler", "rocker")
    reported_joints: ClassVar[tuple[str, ...]] = ("A0", "B0", "A", "B", "P")
    plan: ClassVar[Plan] = Plan(
        (
            Fixed("A0", "A0"),
            Fixed("B0", "B0"),
            Crank("A", "A0", "crank"),
            DyadRRR("B", "A", "coupler", "B0", "rocker", branch="assembly"),
            Rigid("P", "A", "B", "u", "v"),
        ),
        traced=("P",),
    )

    @property
    def frame(self) -> Array:
        """Frame length |A0B0|."""
        return plane.norm(np.asarray(self.B0) - np.asarray(self.A0))

    @property
    def frame_angle(self) -> Array:
        """Direction of A0→B0 (radians): paper 003 measures φ1 and φ3 from it."""
        d = np.asarray(self.B0) - np.asarray(self.A0)
        return np.arctan2(d[..., 1], d[..., 0])

    @property
    def scale(self) -> Array:
        return np.maximum(super().scale, self.frame)

    def residuals(self, motion: Motion) -> dict[str, Array]:
        s = np.asarray(self.scale)[..., None]
        return {
            "crank": _link_error(motion, "A0", "A", self.crank) / s,
            "coupler": _link_error(motion, "A", "B", self.coupler) / s,
            "rocker": _link_error(motion, "B0", "B", self.rocker) / s,
            "point": _frame_error(motion, "A", "B", "P", self.u, self.v) / s,
        }


@dataclass(frozen=True)
class SliderCrank(Mechanism):
    """Slider-crank: crank A0A, rod AB, slider pin B on a line, rod point P.

    The slider's line passes through ``line_point`` at ``line_angle`` (radians). P sits at (u, v)
    in the rod frame (origin A, x along A→B). ``assembly`` is the sign of (B − H)·d, H the foot
    of A on the line and d its direction. Joints: A0, A, B, P.
    """

    A0: ArrayLike
    crank: ArrayLike
    rod: ArrayLike
    line_point: ArrayLike = (0.0, 0.0)
    line_angle: ArrayLike = 0.0
    u: ArrayLike = 0.0
    v: ArrayLike = 0.0
    assembly: ArrayLike = 1.0

    family: ClassVar[str] = "slidercrank"
    point_fields: ClassVar[frozenset[str]] = frozenset({"A0", "line_point"})
    length_fields: ClassVar[tuple[str, ...]] = ("crank", "rod")
    reported_joints: ClassVar[tuple[str, ...]] = ("A0", "A", "B", "P")
    plan: ClassVar[Plan] = Plan(
        (
            Fixed("A0", "A0"),
            Fixed("L", "line_point"),
            Crank("A", "A0", "crank"),
            DyadRRP("B", "A", "rod", "L", "line_angle", branch="assembly"),
            Rigid("P", "A", "B", "u", "v"),
        ),
        traced=("P",),
    )

    @property
    def direction(self) -> Array:
        return plane.unit_direction(self.line_angle)

    @property
    def offset(self) -> Array:
        """Signed distance of A0 from the slider's line (the eccentricity)."""
        return plane.cross(self.direction, np.asarray(self.A0) - np.asarray(self.line_point))

    def slider_position(self, motion: Motion) -> Array:
        """Position of B along the line, measured from the foot of A0 (positive along d)."""
        d = self.direction[..., None, :]
        a0 = np.asarray(self.A0)[..., None, :]
        return plane.dot(motion.positions["B"] - a0, d)

    def residuals(self, motion: Motion) -> dict[str, Array]:
        s = np.asarray(self.scale)[..., None]
        n = plane.perp(self.direction)[..., None, :]
        on_line = plane.dot(motion.positions["B"] - np.asarray(self.line_point)[..., None, :], n)
        return {
            "crank": _link_error(motion, "A0", "A", self.crank) / s,
            "rod": _link_error(motion, "A", "B", self.rod) / s,
            "line": on_line / s,
            "point": _frame_error(motion, "A", "B", "P", self.u, self.v) / s,
        }
