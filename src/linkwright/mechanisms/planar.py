"""Planar named families: four-bar, slider-crank, geared five-bar and double slider.

Joint letters follow paper 003's roles for the four-bar and slider-crank, paper 002's for the
geared five-bar (its two cranks A0A and B0B, the links AC and BC) and paper 004's for the double
slider (M, R, Q, P).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine import Crank, DyadRRP, DyadRRR, Fixed, Motion, Plan, Rigid, Trammel
from linkwright.geometry import plane
from linkwright.mechanisms.base import (
    Dimension,
    InvalidMechanism,
    Mechanism,
    dimension,
    family_dataclass,
)
from linkwright.mechanisms.registry import Family, FieldSpec, register

__all__ = ["DoubleSlider", "FourBar", "GearedFiveBar", "SliderCrank"]

Array = NDArray[np.float64]


def _link_error(motion: Motion, a: str, b: str, length: Array) -> Array:
    return plane.norm(motion.positions[b] - motion.positions[a]) - np.asarray(length)[..., None]


def _frame_error(
    motion: Motion, origin: str, toward: str, point: str, u: ArrayLike, v: ArrayLike
) -> Array:
    """How far the traced point is from its place (u, v) in the frame origin→toward."""
    o, t, p = (motion.positions[k] for k in (origin, toward, point))
    return plane.frame_error(o, t, p, np.asarray(u)[..., None], np.asarray(v)[..., None])


@family_dataclass
class FourBar(Mechanism):
    """Planar four-bar: crank A0A, coupler AB, rocker B0B, frame A0B0, coupler point P.

    Input θ is the angle of A − A0, counter-clockwise from +x. P sits at (u, v) in the coupler
    frame with origin A and x-axis along A→B (v to the left). ``assembly`` is the sign of
    (B0 − A) × (B − A). Joints: A0, B0, A, B, P.

    Examples
    --------
    A crank-rocker; its coupler B stays at the coupler's and the rocker's lengths:

    >>> import numpy as np
    >>> from linkwright import solve
    >>> fb = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=3, rocker=3.5, u=1, v=0.5)
    >>> B = solve(fb, [0.0, np.pi / 2]).positions["B"]
    >>> np.allclose(np.hypot(*(B - [4, 0]).T), 3.5)
    True

    One whose links cannot reach (1 + 1 + 1 < 5) assembles at no input:

    >>> bool(solve(FourBar(A0=[0, 0], B0=[5, 0], crank=1, coupler=1, rocker=1), [0.0]).valid.any())
    False
    """

    A0: Dimension
    B0: Dimension
    crank: Dimension
    coupler: Dimension
    rocker: Dimension
    u: Dimension = dimension(0.0)
    v: Dimension = dimension(0.0)
    assembly: Dimension = dimension(1.0)

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


@family_dataclass
class SliderCrank(Mechanism):
    """Slider-crank: crank A0A, rod AB, slider pin B on a line, rod point P.

    The slider's line passes through ``line_point`` at ``line_angle`` (radians). P sits at (u, v)
    in the rod frame (origin A, x along A→B). ``assembly`` is the sign of (B − H)·d, H the foot
    of A on the line and d its direction. Joints: A0, A, B, P.

    Examples
    --------
    An in-line slider-crank at θ = 0: the slider sits at crank + rod along the line:

    >>> from linkwright import solve
    >>> sc = SliderCrank(A0=[0, 0], crank=1, rod=3, line_point=[0, 0], line_angle=0)
    >>> solve(sc, [0.0]).positions["B"].round(12).tolist()
    [[4.0, 0.0]]

    A rod shorter than the line's offset never reaches it:

    >>> far = SliderCrank(A0=[0, 0], crank=1, rod=1, line_point=[0, 5], line_angle=0)
    >>> bool(solve(far, [0.0, 1.0]).valid.any())
    False
    """

    A0: Dimension
    crank: Dimension
    rod: Dimension
    line_point: Dimension = dimension((0.0, 0.0))
    line_angle: Dimension = dimension(0.0)
    u: Dimension = dimension(0.0)
    v: Dimension = dimension(0.0)
    assembly: Dimension = dimension(1.0)

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


@family_dataclass
class GearedFiveBar(Mechanism):
    """Geared five-bar (paper 002): cranks A0A and B0B geared together, links AC and BC.

    Input θ1 is the angle of A − A0 from +x; the second crank turns with it through gears,
    θ2 = phase2 + ratio·(θ1 − phase1) being the angle of B − B0 (paper 002 uses ratio −1: equal
    speeds, opposite senses). C closes the dyad A–C–B; P sits at (u, v) in the frame with origin
    A and x-axis along A→C (paper 002's traced point 6 lies on the line AC, beyond C). The
    ``assembly`` is the sign of (B − A) × (C − A). Joints: A0, B0, A, B, C, P.

    Where |AB| leaves [|link1 − link2|, link1 + link2] the dyad cannot close: those are the
    locking positions of paper 002, where its tool stops and lets the linkage oscillate. A
    fractional ratio p/q repeats only after q input turns (:func:`linkwright.engine.input_turns`).

    Examples
    --------
    >>> import numpy as np
    >>> from linkwright.mechanisms import solve
    >>> m = GearedFiveBar(A0=[0, 0], B0=[4, 0], crank1=1, crank2=1, link1=3, link2=3,
    ...                   ratio=-1)
    >>> motion = solve(m, [np.pi / 2])
    >>> motion.positions["B"].round(12) + 0.0, motion.positions["C"].round(6)
    (array([[ 4., -1.]]), array([[2.894427, 1.788854]]))

    At θ1 = 90°, A = (0, 1) and θ2 = −90° puts B at (4, −1); C is 3 from both, on the left of
    A→B: the midpoint (2, 0) plus √(9 − 5) = 2 along the unit normal (2, 4)/√20.

    A member whose frame pivots lie too far apart for its links assembles nowhere, and says so:

    >>> from dataclasses import replace
    >>> from linkwright.mechanisms import input_range
    >>> bool(input_range(replace(m, B0=[40.0, 0.0])).never)
    True
    """

    A0: Dimension
    B0: Dimension
    crank1: Dimension
    crank2: Dimension
    link1: Dimension
    link2: Dimension
    phase1: Dimension = dimension(0.0)
    phase2: Dimension = dimension(0.0)
    ratio: Dimension = dimension(-1.0)
    u: Dimension = dimension(0.0)
    v: Dimension = dimension(0.0)
    assembly: Dimension = dimension(1.0)

    family: ClassVar[str] = "geared-fivebar"
    point_fields: ClassVar[frozenset[str]] = frozenset({"A0", "B0"})
    length_fields: ClassVar[tuple[str, ...]] = ("crank1", "crank2", "link1", "link2")
    reported_joints: ClassVar[tuple[str, ...]] = ("A0", "B0", "A", "B", "C", "P")
    plan: ClassVar[Plan] = Plan(
        (
            Fixed("A0", "A0"),
            Fixed("B0", "B0"),
            Crank("A", "A0", "crank1"),
            Crank("B", "B0", "crank2", ratio="ratio", phase="gear_phase"),
            DyadRRR("C", "A", "link1", "B", "link2", branch="assembly"),
            Rigid("P", "A", "C", "u", "v"),
        ),
        traced=("P", "C"),
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        if np.any(self.ratio == 0):
            raise InvalidMechanism(
                "ratio: must not be 0 (the second crank would not turn: that is a four-bar)"
            )

    def params(self) -> dict[str, Array]:
        p = super().params()
        # θ2 = phase2 + ratio·(θ1 − phase1) as the crank step's phase + ratio·θ1.
        p["gear_phase"] = p["phase2"] - p["ratio"] * p["phase1"]
        return p

    @classmethod
    def from_drawing(
        cls,
        A0: ArrayLike,
        A: ArrayLike,
        B0: ArrayLike,
        B: ArrayLike,
        P: ArrayLike,
        *,
        ratio: ArrayLike = -1.0,
    ) -> GearedFiveBar:
        """The five-bar a user draws in paper 002's tool: points 1, 2, 3, 4 and the traced 6.

        The user places the crank pivots A0 (point 1) and B0 (3), the crank ends A (2) and B (4)
        and the traced point P (6); C (5) is the midpoint of A–P, so link1 = |AP|/2,
        link2 = |BC|, and P lies on the line AC beyond C (u = 2·link1, v = 0). The cranks'
        drawn angles become the phases, and the drawn side of C the assembly.

        Examples
        --------
        C is the midpoint (1, 3) of A = (0, 1) and P = (2, 5): link1 = √5, link2 = |(−3, 1.8)|,
        and C lies left of A→B.

        >>> m = GearedFiveBar.from_drawing([0, 0], [0, 1], [4, 0], [4, 1.2], [2, 5])
        >>> round(float(m.link1) ** 2, 12), round(float(m.link2) ** 2, 12), float(m.assembly)
        (5.0, 12.24, 1.0)
        """
        a0, a, b0, b, p = (np.asarray(x, dtype=float) for x in (A0, A, B0, B, P))
        c = 0.5 * (a + p)
        arm1, arm2 = a - a0, b - b0
        link1 = plane.norm(c - a)
        return cls(
            A0=a0,
            B0=b0,
            crank1=plane.norm(arm1),
            crank2=plane.norm(arm2),
            link1=link1,
            link2=plane.norm(c - b),
            phase1=np.arctan2(arm1[..., 1], arm1[..., 0]),
            phase2=np.arctan2(arm2[..., 1], arm2[..., 0]),
            ratio=ratio,
            u=2.0 * link1,
            v=0.0,
            assembly=np.where(plane.cross(b - a, c - a) >= 0, 1.0, -1.0),
        )

    def crank2_angle(self, theta1: ArrayLike) -> Array:
        """θ2, the angle of B − B0, at the inputs θ1 (radians; shape ``batch + (samples,)``,
        like a motion's ``input``)."""
        phase1, phase2, ratio = (
            np.asarray(x)[..., None] for x in (self.phase1, self.phase2, self.ratio)
        )
        return phase2 + ratio * (np.asarray(theta1) - phase1)

    def residuals(self, motion: Motion) -> dict[str, Array]:
        s = np.asarray(self.scale)[..., None]
        b = motion.positions["B"] - motion.positions["B0"]
        theta2 = self.crank2_angle(motion.input)
        gear = plane.cross(plane.unit_direction(theta2), b)  # B − B0 off its geared direction
        return {
            "crank1": _link_error(motion, "A0", "A", self.crank1) / s,
            "crank2": _link_error(motion, "B0", "B", self.crank2) / s,
            "gear": gear / s,
            "link1": _link_error(motion, "A", "C", self.link1) / s,
            "link2": _link_error(motion, "B", "C", self.link2) / s,
            "point": _frame_error(motion, "A", "C", "P", self.u, self.v) / s,
        }


@family_dataclass
class DoubleSlider(Mechanism):
    """Double slider (elliptic trammel) of paper 004, driven by its coupler angle θ.

    Slider R runs on the line through M = (X0, Y0) at angle α + β, slider Q on the line through
    M at angle β (radians). The coupler carries R, Q and P: with θ the input (paper 004, eq. 1),
    Q = R − (p + q)·e^{iθ} and P = R − (p + i·h)·e^{iθ}, and the loop closes with
    R = M + t·e^{i(α+β)}, t = (p + q)·sin(θ − β)/sin α (eq. 2). p, q and h are signed; P traces
    an ellipse (eq. 3; :func:`linkwright.analysis.ellipse`). Joints: M, R, Q, P.

    Examples
    --------
    Archimedes' trammel (α = 90°, h = 0): P traces the ellipse with semi-axes p and q.

    >>> import numpy as np
    >>> from linkwright.mechanisms import solve
    >>> m = DoubleSlider(M=[0, 0], alpha=np.pi / 2, beta=0.0, p=3, q=1)
    >>> solve(m, [0.0, np.pi / 2]).positions["P"].round(12) + 0.0
    array([[-3.,  0.],
           [ 0.,  1.]])

    Parallel guides make no trammel: refused, with the reason:

    >>> DoubleSlider(M=[0, 0], alpha=0.0, beta=0.0, p=3, q=1)
    Traceback (most recent call last):
    ...
    linkwright.mechanisms.base.InvalidMechanism: alpha: must not be a multiple of 180° (the slider \
lines would be parallel)
    """

    M: Dimension
    alpha: Dimension
    beta: Dimension
    p: Dimension
    q: Dimension
    h: Dimension = dimension(0.0)

    family: ClassVar[str] = "doubleslider"
    point_fields: ClassVar[frozenset[str]] = frozenset({"M"})
    reported_joints: ClassVar[tuple[str, ...]] = ("M", "R", "Q", "P")
    plan: ClassVar[Plan] = Plan(
        (
            Fixed("M", "M"),
            Trammel("R", "M", "angle_R", "M", "beta", "pq", phase=np.pi),
            Crank("Q", "R", "pq", phase=np.pi),
            Crank("P", "R", "arm_P", phase="phase_P"),
        ),
        traced=("P",),
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        if np.any(np.abs(np.sin(self.alpha)) <= 1e-12):
            raise InvalidMechanism(
                "alpha: must not be a multiple of 180° (the slider lines would be parallel)"
            )
        if np.any(self.p + self.q == 0):
            raise InvalidMechanism("p, q: p + q must not be 0 (the sliders R and Q would coincide)")

    def params(self) -> dict[str, Array]:
        p = super().params()
        p["angle_R"] = p["alpha"] + p["beta"]
        p["pq"] = p["p"] + p["q"]
        # P − R = −(p + i·h)·e^{iθ} = |p + ih|·e^{i(θ + π + atan2(h, p))}.
        p["arm_P"] = np.hypot(p["p"], p["h"])
        p["phase_P"] = np.pi + np.arctan2(p["h"], p["p"])
        return p

    @property
    def scale(self) -> Array:
        sizes = np.broadcast_arrays(*(np.abs(np.asarray(x)) for x in (self.p, self.q, self.h)))
        return np.maximum(np.maximum.reduce(sizes), np.abs(self.p + self.q))

    def slider_travel(self, theta: ArrayLike) -> Array:
        """t = |MR| signed along e^{i(α+β)} at the inputs θ (paper 004, eq. 2; shape
        ``batch + (samples,)``, like a motion's ``input``)."""
        pq, beta, alpha = (
            np.asarray(x)[..., None] for x in (self.p + self.q, self.beta, self.alpha)
        )
        return pq * np.sin(np.asarray(theta) - beta) / np.sin(alpha)

    def residuals(self, motion: Motion) -> dict[str, Array]:
        s = np.asarray(self.scale)[..., None]
        m = np.asarray(self.M)[..., None, :]
        R, Q, P = (motion.positions[k] for k in "RQP")
        e_r = plane.unit_direction(np.asarray(self.alpha + self.beta))[..., None, :]
        e_q = plane.unit_direction(np.asarray(self.beta))[..., None, :]
        turn = plane.unit_direction(motion.input)
        pq = np.asarray(self.p + self.q)[..., None]
        want_p = R - np.asarray(self.p)[..., None, None] * turn
        want_p = want_p - np.asarray(self.h)[..., None, None] * plane.perp(turn)
        return {
            "R on its line": plane.cross(e_r, R - m) / s,
            "Q on its line": plane.cross(e_q, Q - m) / s,
            "RQ": plane.norm(Q - R + pq[..., None] * turn) / s,
            "point": plane.norm(P - want_p) / s,
        }


# --------------------------------------------------------------------------------------------
# The registry: each family's document fields, names and example
# --------------------------------------------------------------------------------------------

# The four-bar's fields, shared by every planar six-bar (each starts from the very same one).
FOURBAR_FIELDS = (
    FieldSpec("A0", "point"),
    FieldSpec("B0", "point"),
    FieldSpec("crank", "length"),
    FieldSpec("coupler", "length"),
    FieldSpec("rocker", "length"),
)
FRAME_DISTINCT = (("B0", "A0", "the frame A0B0 must have a positive length"),)
POINT_FIELD = FieldSpec("point", "uv", ("u", "v"), {"u": 0.0, "v": 0.0})
ASSEMBLY_FIELD = FieldSpec("assembly", "sign", default=1)
FOURBAR_JOINTS = (
    ("A0", "crank pivot"),
    ("B0", "rocker pivot"),
    ("A", "crank-coupler joint"),
    ("B", "coupler-rocker joint"),
    ("P", "traced coupler point"),
)

register(
    Family(
        name="fourbar",
        cls=FourBar,
        display="Four-bar",
        group="Four-bars",
        space="plane",
        example="crank-rocker",
        fields=(*FOURBAR_FIELDS, POINT_FIELD, ASSEMBLY_FIELD),
        distinct=FRAME_DISTINCT,
        joints=FOURBAR_JOINTS,
        source="papers 002 and 003 (the four-bar of their analyses)",
        analysis="fourbar",
    )
)
register(
    Family(
        name="slidercrank",
        cls=SliderCrank,
        display="Slider-crank",
        group="Slider linkages",
        space="plane",
        example="offset-slider-crank",
        fields=(
            FieldSpec("A0", "point"),
            FieldSpec("crank", "length"),
            FieldSpec("rod", "length"),
            FieldSpec("line", "line", ("line_point", "line_angle")),
            POINT_FIELD,
            ASSEMBLY_FIELD,
        ),
        joints=(("A0", "crank pivot"), ("A", "crank pin"), ("B", "slider"), ("P", "traced point")),
        source="paper 003 (its slider-crank tables)",
        analysis="slidercrank",
    )
)
# A0 and B0 may coincide: two cranks on one axis still make a five-bar.
register(
    Family(
        name="geared-fivebar",
        cls=GearedFiveBar,
        display="Geared five-bar",
        group="Geared linkages",
        space="plane",
        example="geared-fivebar",
        fields=(
            FieldSpec("A0", "point"),
            FieldSpec("B0", "point"),
            FieldSpec("crank1", "length"),
            FieldSpec("crank2", "length"),
            FieldSpec("link1", "length"),
            FieldSpec("link2", "length"),
            FieldSpec("phase1", "angle_deg", default=0.0),
            FieldSpec("phase2", "angle_deg", default=0.0),
            FieldSpec("ratio", "ratio", default=-1.0),
            POINT_FIELD,
            ASSEMBLY_FIELD,
        ),
        joints=(
            ("A0", "first crank's pivot"),
            ("B0", "second crank's pivot"),
            ("A", "first crank's end"),
            ("B", "second crank's end"),
            ("C", "the links' joint"),
            ("P", "traced point"),
        ),
        source="paper 002 (Abhyankar & Gajjal)",
        analysis="locking",
    )
)
register(
    Family(
        name="doubleslider",
        cls=DoubleSlider,
        display="Double slider",
        group="Slider linkages",
        space="plane",
        example="elliptic-trammel",
        fields=(
            FieldSpec("M", "point"),
            FieldSpec("alpha", "angle_deg"),
            FieldSpec("beta", "angle_deg"),
            FieldSpec("p", "number"),
            FieldSpec("q", "number"),
            FieldSpec("h", "number", default=0.0),
        ),
        joints=(
            ("M", "the guides' crossing"),
            ("R", "first slider"),
            ("Q", "second slider"),
            ("P", "traced point"),
        ),
        source="paper 004 (Kiper, Akbalçık, Şen)",
        analysis="ellipse",
    )
)
