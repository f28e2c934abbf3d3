"""Spherical named families: the four-bar of papers 000 and 003, paper 000's six-bar (Fig. 8) and
the Stephenson-III six-bar of paper 001.

Every joint of a spherical linkage is a revolute whose axis passes through the centre O of the
unit sphere; a joint is reported as the unit vector along its axis, a link's length as the
central angle (arc) between its joints' axes, in radians inside the library (documents and the
command line speak degrees). Angles about a joint X are right-handed about +OX.

Frames and letters follow the papers:

- four-bar (paper 000, Figs 1, 6, 7): A0 = (1, 0, 0), B0 = (cos a1, sin a1, 0),
  A = (cos a2, sin a2 cos θ, sin a2 sin θ); B on the coupler AB and the rocker B0B; coupler
  point P at arc AP from A and angle BAP about +OA (paper 000's C with AC and μ).
- six-bar (paper 000, Fig. 8): that four-bar with P called C, a ground pivot E0 at arc B0E0 from
  B0 and angle ε from the frame circle beyond B0, the binary links CE and E0E, and the traced
  point D on CE (arc CD, angle ECD about +OC).
- Stephenson III (paper 001): A = (0, 0, 1), D = (0, sin a1, cos a1), G on the great circle
  A→D at arc a1 + a9 from A (beyond D; the printed eq. 8 has G on the wrong side of A); input AB
  with B = (sin a2 sin θ1, sin a2 cos θ1, cos a2) (eq. 5, θ1 = angle BAD); C on BC and CD; E on
  the ternary coupler BCE; F on EF and FG.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine import Fixed, Motion, Plan, SphereCrank, SphereDyad, SphereRigid
from linkwright.engine.hinge_steps import SphereHinge
from linkwright.engine.hinge_triad_steps import SphereBodyHingeTriad, SphereLegHingeTriad
from linkwright.engine.triad_steps import SphereTriad
from linkwright.geometry import sphere
from linkwright.mechanisms.base import (
    Dimension,
    InvalidMechanism,
    Mechanism,
    PlanByInput,
    dimension,
    family_dataclass,
)
from linkwright.mechanisms.registry import Family, FieldSpec, register

__all__ = ["SphericalFourBar", "SphericalSixBar", "SphericalStephenson3"]

Array = NDArray[np.float64]
_X = np.array([1.0, 0.0, 0.0])
_Y = np.array([0.0, 1.0, 0.0])
_Z = np.array([0.0, 0.0, 1.0])


def _on_equator(angle: ArrayLike) -> Array:
    a = np.asarray(angle, dtype=float)
    axis: Array = np.stack(np.broadcast_arrays(np.cos(a), np.sin(a), np.zeros_like(a)), axis=-1)
    return axis


def _arc_error(motion: Motion, a: str, b: str, length: ArrayLike) -> Array:
    """Arc between two joints minus its length (radians)."""
    error: Array = (
        sphere.arc(motion.positions[a], motion.positions[b]) - np.asarray(length)[..., None]
    )
    return error


def _point_error(
    motion: Motion, origin: str, toward: str, point: str, arc: ArrayLike, angle: ArrayLike
) -> Array:
    o, t, p = (motion.positions[k] for k in (origin, toward, point))
    return sphere.frame_error(o, t, p, np.asarray(arc)[..., None], np.asarray(angle)[..., None])


def _unit_error(motion: Motion) -> Array:
    """Largest departure of any joint from the unit sphere."""
    errs = [np.abs(sphere.norm(p) - 1.0) for p in motion.positions.values()]
    worst: Array = np.maximum.reduce(errs)
    return worst


@family_dataclass
class SphericalFourBar(Mechanism):
    """Spherical four-bar in paper 000's frame: frame A0B0 (a1), crank A0A (a2), coupler AB (a3),
    rocker B0B (a4), coupler point P; all arcs in radians.

    Joints (unit vectors): A0 = (1, 0, 0), B0 = (cos a1, sin a1, 0), A = (cos a2, sin a2 cos θ,
    sin a2 sin θ) for the input θ (measured about +OA0 from the frame circle towards B0, so it is
    paper 003's φ1), B, and P at arc ``point_arc`` from A and angle ``point_angle`` = BAP about
    +OA (paper 000's AC and μ). ``assembly`` is the sign of (A × B0)·B; +1 is the mode that
    paper 000's eq. 5 gives as printed.

    Paper 003 names the same links α1 (crank), α2 (coupler), α3 (output), α4 (frame).

    Examples
    --------
    Paper 000's Fig. 6 crank-rocker (a1..a4 = 40°, 20°, 45°, 35°; AC = 50°, μ = 130°):

    >>> from linkwright.mechanisms import solve
    >>> fig6 = SphericalFourBar(*np.radians([40, 20, 45, 35, 50, 130]))
    >>> m = solve(fig6, [0.0])
    >>> np.round(m.positions["B"], 6)
    array([[0.509774, 0.666849, 0.543546]])

    A linkage that cannot assemble gives NaN, masked by ``valid``:

    >>> m = solve(SphericalFourBar(*np.radians([90, 10, 20, 30])), [0.0])
    >>> m.valid, m.positions["B"]
    (array([False]), array([[nan, nan, nan]]))
    """

    frame: Dimension
    crank: Dimension
    coupler: Dimension
    rocker: Dimension
    point_arc: Dimension = dimension(0.0)
    point_angle: Dimension = dimension(0.0)
    assembly: Dimension = dimension(1.0)

    family: ClassVar[str] = "spherical-fourbar"
    arc_fields: ClassVar[tuple[str, ...]] = ("frame", "crank", "coupler", "rocker")
    derived_points: ClassVar[frozenset[str]] = frozenset({"A0", "B0", "ref"})
    reported_joints: ClassVar[tuple[str, ...]] = ("A0", "B0", "A", "B", "P")
    plan: ClassVar[Plan] = Plan(
        (
            Fixed("A0", "A0"),
            Fixed("B0", "B0"),
            SphereCrank("A", "A0", "crank", ref="ref"),
            SphereDyad("B", "A", "coupler", "B0", "rocker", branch="assembly"),
            SphereRigid("P", "A", "B", "point_arc", "point_angle"),
        ),
        traced=("P",),
    )

    def params(self) -> dict[str, Array]:
        out = super().params()
        out.update(A0=_X, B0=_on_equator(self.frame), ref=_Y)
        return out

    def output_angle(self, motion: Motion) -> Array:
        """φ3: the angle of B about +OB0 from the frame circle beyond B0 (paper 000's θ4)."""
        b0 = motion.positions["B0"]
        beyond = -sphere.tangent(b0, motion.positions["A0"])
        return sphere.angle_at(b0, b0 + beyond, motion.positions["B"])

    def residuals(self, motion: Motion) -> dict[str, Array]:
        """Each constraint's error (radians of arc, or chord for the point) at every sample."""
        return {
            "crank": _arc_error(motion, "A0", "A", self.crank),
            "coupler": _arc_error(motion, "A", "B", self.coupler),
            "rocker": _arc_error(motion, "B0", "B", self.rocker),
            "point": _point_error(motion, "A", "B", "P", self.point_arc, self.point_angle),
            "unit": _unit_error(motion),
        }


@family_dataclass
class SphericalSixBar(Mechanism):
    """Paper 000's spherical six-bar (Fig. 8): its four-bar, the binary links CE (``link5``) and
    E0E (``link6``), and the point D on CE; all arcs in radians.

    The four-bar is :class:`SphericalFourBar` with its coupler point called C (``point_arc`` = AC,
    ``point_angle`` = μ = BAC). The ground pivot E0 lies at arc ``ground_arc`` (B0E0) from B0,
    at angle ``ground_angle`` (ε = E0B0K) about +OB0 from the frame circle beyond B0 (K on the
    frame circle beyond B0, the side that continues A0→B0). D is at arc ``d_arc`` (CD) from C,
    at angle ``d_angle`` (ECD) about +OC from C→E. ``assembly`` is the four-bar's sign
    (A × B0)·B, ``assembly2`` the sign (C × E0)·E. Joints: A0, B0, E0, A, B, C, E, D; traced C
    and D.

    Paper 000 prints neither ε's sense nor the assembly modes. With ε right-handed about +OB0,
    as everywhere in linkwright, Fig. 8's linkage turns its crank fully only for ε = −30° and
    the four-bar's mode ``assembly = -1`` (either ``assembly2``); the other three choices of
    (sign of ε, assembly) make the crank a rocker (``linkwright papers 000`` shows all four).
    Its mirror image in the frame plane (every angle and sign negated) is the same motion.

    Examples
    --------
    Paper 000's Fig. 8 six-bar (arcs in degrees converted): D stays on the unit sphere.

    >>> import numpy as np
    >>> from linkwright import solve
    >>> d = np.radians
    >>> six = SphericalSixBar(frame=d(35), crank=d(20), coupler=d(42), rocker=d(30),
    ...     point_arc=d(72), point_angle=d(22), link5=d(45), link6=d(33), ground_arc=d(85),
    ...     ground_angle=d(-30), d_arc=d(30), d_angle=d(75), assembly=-1)
    >>> round(float(np.linalg.norm(solve(six, [0.0]).positions["D"][0])), 12)
    1.0

    Coupler and rocker arcs too short to span the frame: it assembles nowhere.

    >>> import dataclasses
    >>> bad = dataclasses.replace(six, coupler=d(5), rocker=d(5))
    >>> bool(solve(bad, [0.0, 1.0]).valid.any())
    False
    """

    frame: Dimension
    crank: Dimension
    coupler: Dimension
    rocker: Dimension
    point_arc: Dimension
    point_angle: Dimension
    link5: Dimension
    link6: Dimension
    ground_arc: Dimension
    ground_angle: Dimension
    d_arc: Dimension = dimension(0.0)
    d_angle: Dimension = dimension(0.0)
    assembly: Dimension = dimension(1.0)
    assembly2: Dimension = dimension(1.0)

    family: ClassVar[str] = "spherical-sixbar"
    arc_fields: ClassVar[tuple[str, ...]] = (
        "frame",
        "crank",
        "coupler",
        "rocker",
        "link5",
        "link6",
        "ground_arc",
    )
    derived_points: ClassVar[frozenset[str]] = frozenset({"A0", "B0", "E0", "ref"})
    reported_joints: ClassVar[tuple[str, ...]] = ("A0", "B0", "E0", "A", "B", "C", "E", "D")
    traced_joint: ClassVar[str] = "D"
    plan: ClassVar[Plan] = Plan(
        (
            Fixed("A0", "A0"),
            Fixed("B0", "B0"),
            Fixed("E0", "E0"),
            SphereCrank("A", "A0", "crank", ref="ref"),
            SphereDyad("B", "A", "coupler", "B0", "rocker", branch="assembly"),
            SphereRigid("C", "A", "B", "point_arc", "point_angle"),
            SphereDyad("E", "C", "link5", "E0", "link6", branch="assembly2"),
            SphereRigid("D", "C", "E", "d_arc", "d_angle"),
        ),
        traced=("D", "C"),
    )

    def params(self) -> dict[str, Array]:
        out = super().params()
        b0 = _on_equator(self.frame)
        beyond = _on_equator(np.asarray(self.frame) + np.pi / 2)  # the frame circle past B0
        out.update(
            A0=_X,
            B0=b0,
            E0=sphere.point_at(b0, b0 + beyond, self.ground_arc, self.ground_angle),
            ref=_Y,
        )
        return out

    def residuals(self, motion: Motion) -> dict[str, Array]:
        """Each constraint's error (radians of arc, or chord for rigid points) at every sample."""
        return {
            "crank": _arc_error(motion, "A0", "A", self.crank),
            "coupler": _arc_error(motion, "A", "B", self.coupler),
            "rocker": _arc_error(motion, "B0", "B", self.rocker),
            "C": _point_error(motion, "A", "B", "C", self.point_arc, self.point_angle),
            "link5": _arc_error(motion, "C", "E", self.link5),
            "link6": _arc_error(motion, "E0", "E", self.link6),
            "D": _point_error(motion, "C", "E", "D", self.d_arc, self.d_angle),
            "unit": _unit_error(motion),
        }


_P001_FRAME = (Fixed("A", "A"), Fixed("D", "D"), Fixed("G", "G"))
# E at arc a6 from C, turned by π − σ from the great circle C→B (eq. 3); F closes the dyad EFG.
_P001_E = SphereRigid("E", "C", "B", "a6", "turn")
_P001_F = SphereDyad("F", "E", "a7", "G", "a8", branch="assembly2")
# The triads list C first, with ``sense = -1``: their poses in the order of θ1 = ∠BAD
# (left-handed, eq. 5).

SPHERE_PLANS: dict[str, Plan] = {
    "AB": Plan(
        (
            *_P001_FRAME,
            # Eq. 5 turns B from D towards +x: left-handed about +OA, hence ratio −1.
            SphereCrank("B", "A", "a2", ref="D", ratio=-1.0),
            SphereDyad("C", "B", "a3", "D", "a4", branch="assembly"),
            _P001_E,
            _P001_F,
        ),
        traced=("E", "F"),
    ),
    "FG": Plan(
        (
            *_P001_FRAME,
            SphereCrank("F", "G", "a8", ref="away"),
            SphereTriad(
                ("C", "B", "E"),
                ("D", "A", "F"),
                ("a4", "a2", "a7"),
                "a3",
                "a6",
                "turn",
                sense=-1.0,
            ),
        ),
        traced=("E", "F"),
    ),
    # The four-bar from its rocker: θ turns C about +OD from the great circle D→A.
    "DC": Plan(
        (
            *_P001_FRAME,
            SphereCrank("C", "D", "a4", ref="A"),
            SphereDyad("B", "C", "a3", "A", "a2", branch="assembly"),
            _P001_E,
            _P001_F,
        ),
        traced=("E", "F"),
    ),
    # Driven hinges, θ the angle at the joint, right-handed about its axis: at B from the great
    # circle B→A to B→C, at C from C→D to C→B (the four-bar's loop: a hinge step), at E from
    # E→C to E→F (EF turning on the coupler) and at F from F→G to F→E (triads).
    "B": Plan(
        (*_P001_FRAME, SphereHinge("B", "C", "D", "a4", "A", "a3", "a2"), _P001_E, _P001_F),
        traced=("E", "F"),
    ),
    "C": Plan(
        (*_P001_FRAME, SphereHinge("C", "B", "A", "a2", "D", "a3", "a4"), _P001_E, _P001_F),
        traced=("E", "F"),
    ),
    "E": Plan(
        (
            *_P001_FRAME,
            SphereBodyHingeTriad(
                ("C", "B", "F", "E"),
                ("D", "A", "G"),
                ("a4", "a2", "a8"),
                "a3",
                "a6",
                "turn",
                "a7",
                sense=-1.0,
            ),
        ),
        traced=("E", "F"),
    ),
    "F": Plan(
        (
            *_P001_FRAME,
            SphereLegHingeTriad(
                ("C", "B", "E", "F"),
                ("D", "A", "G"),
                ("a4", "a2"),
                "a3",
                "a6",
                "turn",
                "a7",
                "a8",
                sense=-1.0,
            ),
        ),
        traced=("E", "F"),
    ),
}
"""Paper 001's six-bar driven at each of its joints: at its links from the frame (AB, the
paper's; FG, the paper's; DC) and at each moving hinge (B, C, E, F)."""

SPHERE_INPUTS = tuple(SPHERE_PLANS)


@family_dataclass
class SphericalStephenson3(Mechanism):
    """The Stephenson-III spherical six-bar of paper 001 (Zong et al.); all arcs in radians.

    Fixed A = (0, 0, 1), D = (0, sin a1, cos a1) and G at arc a1 + a9 from A beyond D; input link
    AB (a2), ternary coupler BCE (BC = a3, CE = a6, with E placed by turning the great circle
    C→B about +OC by 180° − σ and walking a6 from C, so that cos BE = cos a3 cos a6 −
    sin a3 sin a6 cos σ as in eq. 3), output CD (a4), link EF (a7), output FG (a8).

    ``input = "AB"`` drives θ1 = angle BAD with B = (sin a2 sin θ1, sin a2 cos θ1, cos a2)
    (eq. 5): then the linkage is a four-bar ABCD plus the dyad EFG, with ``assembly`` the sign
    of (B × D)·C and ``assembly2`` that of (E × G)·F: at most 2 × 2 = 4 real configurations.
    Paper 001 counts "up to 8" because its system (4) fixes only cos σ and so also admits the
    mirror-image coupler (σ → −σ), a different mechanism.

    ``input = "FG"`` drives θ6, the angle of F about +OG from the great circle G→(away from D).
    The coupler BCE, held by AB, CD and EF, is then a spherical triad with up to 8 real
    configurations (a degree-8 polynomial): a plan step
    (:class:`~linkwright.engine.triad_steps.SphereTriad`) whose branch is ``pose``, 0 to 7, the
    index of the configuration in the order of paper 001's θ1 = ∠BAD at each input, from −180°
    to 180°. Joints: A, D, G, B, C, E, F (traced: E).

    A motor may sit anywhere else too (:data:`SPHERE_PLANS`): ``input = "DC"`` turns C about
    +OD from the great circle D→A (the four-bar from its rocker, ``assembly`` then the sign of
    (C × A)·B); ``"B"`` and ``"C"`` drive the hinges of the four-bar's loop (a driven hinge,
    ``pose`` 0 or 1); ``"E"`` turns EF on the coupler and ``"F"`` drives the hinge between EF
    and FG, each a spherical triad that changes with the input
    (:mod:`~linkwright.engine.hinge_triad_steps`, ``pose`` 0 to 7). At a hinge θ is the angle
    about its axis (right-handed) from one great circle to the other: at B from B→A to B→C, at
    C from C→D to C→B, at E from E→C to E→F, at F from F→G to F→E.

    Examples
    --------
    Paper 001's example driven at FG has 8, 4 and 6 real configurations at θ6 = −90°, 0° and
    120° (every pose of the triad, from :func:`~linkwright.mechanisms.configurations`):

    >>> import numpy as np
    >>> from linkwright import configurations
    >>> d = np.radians
    >>> fg = SphericalStephenson3(*d([71.1, 64.1, 68.6, 65.7, 69.0, 102.0, 74.1, 52.6, 19.7]),
    ...                           input="FG")
    >>> found = configurations(fg, d([-90, 0, 120]))
    >>> sum(motion.valid.astype(int) for _, motion in found).tolist()
    [8, 4, 6]

    With an arc a7 of 175° the linkage driven at AB assembles nowhere:

    >>> from dataclasses import replace
    >>> from linkwright import input_range
    >>> ab = replace(fg, input="AB")
    >>> bool(input_range(ab).never), bool(input_range(replace(ab, a7=d(175))).never)
    (False, True)
    """

    a1: Dimension
    a2: Dimension
    a3: Dimension
    a4: Dimension
    a6: Dimension
    sigma: Dimension
    a7: Dimension
    a8: Dimension
    a9: Dimension
    assembly: Dimension = dimension(1.0)
    assembly2: Dimension = dimension(1.0)
    input: str = "AB"
    pose: Dimension = dimension(0.0)

    family: ClassVar[str] = "spherical-stephenson3"
    arc_fields: ClassVar[tuple[str, ...]] = ("a1", "a2", "a3", "a4", "a6", "a7", "a8", "a9")
    derived_points: ClassVar[frozenset[str]] = frozenset({"A", "D", "G", "away"})
    reported_joints: ClassVar[tuple[str, ...]] = ("A", "D", "G", "B", "C", "E", "F")
    traced_joint: ClassVar[str] = "E"
    plan: ClassVar[Plan] = PlanByInput(**SPHERE_PLANS)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        # The base checks the numbers; the word that chooses the plan is checked here, first.
        if not isinstance(self.input, str) or self.input not in SPHERE_INPUTS:
            raise InvalidMechanism(
                f"input: must be one of {', '.join(SPHERE_INPUTS)} (where the motor sits), "
                f"got {self.input!r}"
            )
        super().__post_init__()
        if np.any(np.asarray(self.a1) + np.asarray(self.a9) >= 2 * np.pi):
            raise InvalidMechanism("a1 + a9: G would wrap past A (a1 + a9 ≥ 360°)")

    def params(self) -> dict[str, Array]:
        out = {
            k: v
            for k, v in super().params().items()
            if k != "input"  # a word, not a plan parameter
        }
        a1 = np.asarray(self.a1, dtype=float)
        far = a1 + np.asarray(self.a9, dtype=float)
        zeros = np.zeros_like(a1)

        def on_meridian(angle: Array) -> Array:
            return np.stack(
                np.broadcast_arrays(np.zeros_like(angle), np.sin(angle), np.cos(angle)), -1
            )

        out.update(
            A=_Z,
            D=on_meridian(a1),
            G=on_meridian(far + zeros),
            away=-on_meridian(a1),
            turn=np.pi - np.asarray(self.sigma, dtype=float),
        )
        return out

    @property
    def driven(self) -> tuple[str, str]:
        """(pivot, joint) of the driven link."""
        return {"AB": ("A", "B"), "FG": ("G", "F"), "DC": ("D", "C")}.get(
            self.input, (self.input, self.input)
        )

    def residuals(self, motion: Motion) -> dict[str, Array]:
        """Each constraint's error at every sample (radians of arc, or chord for E)."""
        return {
            "AB": _arc_error(motion, "A", "B", self.a2),
            "BC": _arc_error(motion, "B", "C", self.a3),
            "CD": _arc_error(motion, "C", "D", self.a4),
            "E": _point_error(motion, "C", "B", "E", self.a6, np.pi - np.asarray(self.sigma)),
            "EF": _arc_error(motion, "E", "F", self.a7),
            "FG": _arc_error(motion, "F", "G", self.a8),
            "unit": _unit_error(motion),
        }


# --------------------------------------------------------------------------------------------
# The registry
# --------------------------------------------------------------------------------------------

# Paper 000's four-bar: frame A0B0 (a1), crank A0A (a2), coupler AB (a3), rocker B0B (a4); its
# coupler point at arc AP from A and angle BAP about +OA (the paper's AC and μ).
_FOURBAR_ARCS = (
    FieldSpec("frame", "arc"),
    FieldSpec("crank", "arc"),
    FieldSpec("coupler", "arc"),
    FieldSpec("rocker", "arc"),
)
_NO_OFFSET = {"arc": 0.0, "angle": 0.0}
_ASSEMBLY = FieldSpec("assembly", "sign", default=1)

register(
    Family(
        name="spherical-fourbar",
        cls=SphericalFourBar,
        display="Spherical four-bar",
        group="Spherical",
        space="sphere",
        example="paper000-fig6-crank-rocker",
        fields=(
            *_FOURBAR_ARCS,
            FieldSpec("point", "arc_point", ("point_arc", "point_angle"), _NO_OFFSET),
            _ASSEMBLY,
        ),
        joints=(
            ("A0", "crank pivot, (1, 0, 0)"),
            ("B0", "rocker pivot, on the frame circle"),
            ("A", "crank-coupler joint"),
            ("B", "coupler-rocker joint"),
            ("P", "traced coupler point (paper 000's C)"),
        ),
        source="papers 000 (Özçelik & Şaka) and 003",
        analysis="spherical-fourbar",
    )
)
# Paper 000, Fig. 8: the four-bar's coupler point is C, where link5 (CE) hangs; E0 sits at
# ground = {arc = B0E0, angle = ε} from B0 (ε from the frame circle beyond B0); the traced
# point D at d = {arc = CD, angle = ECD} from C. C is required, as a planar six-bar's C is.
register(
    Family(
        name="spherical-sixbar",
        cls=SphericalSixBar,
        display="Spherical six-bar",
        group="Spherical",
        space="sphere",
        example="paper000-fig8-sixbar",
        fields=(
            *_FOURBAR_ARCS,
            FieldSpec("point", "arc_point", ("point_arc", "point_angle")),
            FieldSpec("link5", "arc"),
            FieldSpec("link6", "arc"),
            FieldSpec("ground", "arc_pivot", ("ground_arc", "ground_angle")),
            FieldSpec("d", "arc_point", ("d_arc", "d_angle"), _NO_OFFSET),
            _ASSEMBLY,
            FieldSpec("assembly2", "sign", default=1),
        ),
        joints=(
            ("A0", "crank pivot"),
            ("B0", "rocker pivot"),
            ("E0", "the second dyad's pivot"),
            ("A", "crank-coupler joint"),
            ("B", "coupler-rocker joint"),
            ("C", "on the coupler"),
            ("E", "the second dyad's joint"),
            ("D", "traced point"),
        ),
        source="paper 000, Fig. 8",
    )
)
# Paper 001: a1 = AD, a2 = AB, a3 = BC, a4 = CD, a6 = CE, σ = 180° − angle BCE, a7 = EF,
# a8 = FG, a9 = DG. No check that a1 + a9 < 360 (the class's): two arcs each below 180
# cannot reach it, in radians either (the two largest floats below π sum to less than 2π).
register(
    Family(
        name="spherical-stephenson3",
        cls=SphericalStephenson3,
        display="Spherical Stephenson III six-bar",
        group="Spherical",
        space="sphere",
        example="paper001-stephenson3",
        fields=(
            FieldSpec("a1", "arc"),
            FieldSpec("a2", "arc"),
            FieldSpec("a3", "arc"),
            FieldSpec("a4", "arc"),
            FieldSpec("a6", "arc"),
            FieldSpec("sigma", "angle_deg"),
            FieldSpec("a7", "arc"),
            FieldSpec("a8", "arc"),
            FieldSpec("a9", "arc"),
            FieldSpec("input", "spherical_input", default="AB"),
            _ASSEMBLY,
            FieldSpec("assembly2", "sign", default=1),
            FieldSpec("pose", "pose", default=0),
        ),
        joints=(
            ("A", "fixed, the input AB's pivot"),
            ("D", "fixed, the output CD's pivot"),
            ("G", "fixed, the output FG's pivot"),
            ("B", "input link's end"),
            ("C", "on the ternary coupler BCE"),
            ("E", "on the coupler, traced"),
            ("F", "link EF's joint with FG"),
        ),
        source="paper 001 (Zong, Lu, An, Zhang)",
    )
)
