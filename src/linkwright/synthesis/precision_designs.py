"""What the precision-point routes share: poses, the designs they return and their defects.

:func:`pose_set` and :func:`pose_positions` read and place precision positions (a pose is the
coupler point P and the coupler's angle; the coupler's frame has its origin at P);
:class:`MotionDesign` and :class:`FunctionDesign` are the results of
:mod:`linkwright.synthesis.precision` and :mod:`linkwright.synthesis.function_generation`,
measured by simulating the four-bar with the engine: the input at which it reaches each
position, the assembly sign it needs there, and the branch and order defects of Chase and Mirth
(T. R. Chase & J. A. Mirth, "Circuits and branches of single-degree-of-freedom planar
linkages", J. Mech. Des. 115 (1993) 223–230).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine import Motion, evaluate
from linkwright.geometry import plane
from linkwright.mechanisms import FourBar, input_range

__all__ = [
    "DYAD_TOL",
    "SAME_TOL",
    "SINGULAR_TOL",
    "TWO_PI",
    "FunctionDesign",
    "MotionDesign",
    "PrecisionError",
    "assembly_branches",
    "batch_place",
    "find_order_defect",
    "first_true",
    "pose_positions",
    "pose_set",
    "rotation_matrix",
    "simulate_design",
    "wrap_angle",
]

Array = NDArray[np.float64]
TWO_PI = 2.0 * np.pi
# Two poses (or pairs) closer than this, relative to the poses' spread, are one.
SAME_TOL = 1e-9
# A linear system whose determinant, relative to the product of its row norms, is below this is
# singular: the precision positions do not fix a linkage.
SINGULAR_TOL = 1e-10
# A dyad whose moving pivot's positions are off a circle about its centre by more than this
# (relative to the poses' spread) does not guide the body through the poses.
DYAD_TOL = 1e-8


class PrecisionError(ValueError):
    """Precision positions that do not define a linkage (names the positions and the numbers)."""


def wrap_angle(angle: ArrayLike) -> Array:
    """Angle in (−π, π]."""
    return np.pi - np.mod(np.pi - np.asarray(angle, dtype=float), TWO_PI)


def batch_place(index: tuple[int, ...]) -> str:
    return f" (set {list(index)} of the batch)" if index else ""


def first_true(mask: NDArray[np.bool_]) -> tuple[int, ...] | None:
    """Index of the first True of ``mask`` (None if none)."""
    if not np.any(mask):
        return None
    return tuple(int(i) for i in np.argwhere(mask)[0])


@overload
def pose_set(
    points: ArrayLike, angles: None, n: int | None, what: str
) -> tuple[Array, None, Array]: ...
@overload
def pose_set(
    points: ArrayLike, angles: ArrayLike, n: int | None, what: str
) -> tuple[Array, Array, Array]: ...
@overload
def pose_set(
    points: ArrayLike, angles: ArrayLike | None, n: int | None, what: str
) -> tuple[Array, Array | None, Array]: ...
def pose_set(
    points: ArrayLike, angles: ArrayLike | None, n: int | None, what: str
) -> tuple[Array, Array | None, Array]:
    """Checked (points (..., n, 2), angles (..., n) or None, scale (...))."""
    p = np.asarray(points, dtype=float)
    if p.ndim < 2 or p.shape[-1] != 2:
        raise PrecisionError(f"{what}: points must have shape (..., n, 2), got {p.shape}")
    count = p.shape[-2]
    if n is not None and count != n:
        raise PrecisionError(f"{what}: needs exactly {n} precision positions, got {count}")
    if not np.all(np.isfinite(p)):
        raise PrecisionError(f"{what}: points must be finite")
    a = None
    if angles is not None:
        a = np.asarray(angles, dtype=float)
        if a.shape[-1:] != (count,):
            raise PrecisionError(
                f"{what}: needs one angle per point ({count}), got angles of shape {a.shape}"
            )
        if not np.all(np.isfinite(a)):
            raise PrecisionError(f"{what}: angles must be finite")
        try:
            shape = np.broadcast_shapes(p.shape[:-2], a.shape[:-1])
        except ValueError:
            raise PrecisionError(
                f"{what}: points {p.shape} and angles {a.shape} do not broadcast"
            ) from None
        p = np.broadcast_to(p, shape + (count, 2))
        a = np.broadcast_to(a, shape + (count,))
    gap = plane.norm(p[..., :, None, :] - p[..., None, :, :])
    scale = np.max(gap, axis=(-1, -2))
    # Poses that all share one point differ only by rotations about it: size them by the point.
    scale = np.where(scale > 0, scale, np.maximum(np.max(plane.norm(p), axis=-1), 1.0))
    for i in range(count):
        for j in range(i + 1, count):
            same = gap[..., i, j] <= SAME_TOL * scale
            if a is not None:
                same = same & (np.abs(wrap_angle(a[..., i] - a[..., j])) <= SAME_TOL)
            at = first_true(same)
            if at is not None:
                kind = "poses" if a is not None else "points"
                raise PrecisionError(
                    f"{what}: {kind} {i + 1} and {j + 1} coincide{batch_place(at)}: "
                    f"{p[at + (i,)].tolist()} and {p[at + (j,)].tolist()}"
                )
    return p, a, scale


def rotation_matrix(angle: Array) -> Array:
    """Rotation matrices (..., 2, 2) by ``angle``."""
    c, s = np.cos(angle), np.sin(angle)
    return np.stack((np.stack((c, -s), -1), np.stack((s, c), -1)), -2)


def pose_positions(points: ArrayLike, angles: ArrayLike, first: ArrayLike) -> Array:
    """Where points of the coupler lie in every pose, given where they lie in the first.

    The displacement from pose 1 to pose j turns the plane by αj − α1 about the pose points:
    X ↦ Pj + R(αj − α1)(X − P1).

    Parameters
    ----------
    points : (..., n, 2) the poses' coupler points Pj.
    angles : (..., n) the poses' coupler angles αj (radians).
    first : (..., m, 2) positions of m coupler points in the first pose.

    Returns
    -------
    (..., n, m, 2): position of each point in each pose.

    Examples
    --------
    A quarter turn about the origin carries (1, 0) to (0, 1):

    >>> pose_positions([[0, 0], [0, 0]], [0, np.pi / 2], [[1, 0]]).round(12) + 0.0
    array([[[1., 0.]],
    <BLANKLINE>
           [[0., 1.]]])
    """
    p = np.asarray(points, dtype=float)
    a = np.asarray(angles, dtype=float)
    x = np.asarray(first, dtype=float)
    if p.ndim < 2 or p.shape[-1] != 2 or a.shape[-1:] != p.shape[-2:-1] or x.shape[-1:] != (2,):
        raise PrecisionError(
            f"pose_positions: needs points (..., n, 2), angles (..., n) and first (..., m, 2), "
            f"got {p.shape}, {a.shape} and {x.shape}"
        )
    if x.ndim == 1:
        x = x[None]
    rot = rotation_matrix(a - a[..., :1])  # (..., n, 2, 2)
    rel = x[..., None, :, :] - p[..., :1, None, :]  # (..., 1, m, 2)
    placed: Array = p[..., :, None, :] + np.einsum("...nij,...nmj->...nmi", rot, rel)
    return placed


# --- the report ----------------------------------------------------------------------------------


def find_order_defect(mech: FourBar, inputs: Array) -> NDArray[np.bool_]:
    """True where one sweep of the input does not meet ``inputs`` in their order."""
    arcs = input_range(mech)
    n = inputs.shape[-1]
    step = np.mod(np.diff(inputs, axis=-1), TWO_PI)
    # Round the full circle once at most, one way or the other.
    ccw = np.sum(step, axis=-1) < TWO_PI
    cw = np.sum(TWO_PI - step, axis=-1) < TWO_PI
    turning = ccw | cw
    lo, hi = np.asarray(arcs.lo), np.asarray(arcs.hi)
    if lo.shape[-1] == 0:
        never: NDArray[np.bool_] = ~turning
        return never
    span = hi - lo
    tol = 1e-9
    # s[..., j, k]: how far input j lies into arc k (NaN-padded arcs never contain it).
    s = np.mod(inputs[..., :, None] - lo[..., None, :], TWO_PI)
    inside = s <= span[..., None, :] + tol
    arc = np.argmax(inside, axis=-1)  # (..., n)
    one_arc = np.all(arc == arc[..., :1], axis=-1) & np.all(np.any(inside, axis=-1), axis=-1)
    along = np.take_along_axis(s, arc[..., None], -1)[..., 0]
    d = np.diff(along, axis=-1)
    monotone = np.all(d > 0, axis=-1) | np.all(d < 0, axis=-1) if n > 1 else np.ones_like(ccw)
    defect: NDArray[np.bool_] = np.where(np.asarray(arcs.full), ~turning, ~(one_arc & monotone))
    return defect


def assembly_branches(A0: Array, B0: Array, A: Array, B: Array, scale: Array, what: str) -> Array:
    """Assembly sign at each position: sign of (B0 − A) × (B − A), as FourBar defines it.

    Raises where the crank pin sits on the rocker pivot: the dyad is folded there and the input
    does not fix the coupler (B may be anywhere on its circle).
    """
    gap = plane.norm(B0[..., None, :] - A) / np.asarray(scale)[..., None]
    at = first_true(gap <= SAME_TOL)
    if at is not None:
        raise PrecisionError(
            f"{what}: at precision position {at[-1] + 1}{batch_place(at[:-1])} the crank pin A "
            "lies on "
            "the rocker pivot B0: the linkage is folded there and its input does not fix the "
            "coupler"
        )
    side = plane.cross(B0[..., None, :] - A, B - A)
    return np.where(side >= 0, 1.0, -1.0)


def simulate_design(mech: FourBar, inputs: Array, branches: Array) -> Motion:
    """The engine's motion at ``inputs``, each on its own assembly sign."""
    return evaluate(
        mech.plan, mech.params(), inputs, points=mech.points, branches={"B": branches}, order=0
    )


@dataclass(frozen=True)
class MotionDesign:
    """A four-bar guiding a coupler through precision poses, and how it meets them.

    Arrays have the shape ``batch + (n,)``, n the number of poses (``branch_defect`` and
    ``order_defect`` the batch shape).

    Attributes
    ----------
    mechanism : the four-bar (crank = the first dyad, P = the poses' point, ``assembly`` the
        sign it needs at the first pose).
    inputs : the input θj (radians, in (−π, π]) at which it reaches pose j.
    branches : the assembly sign (±1) it needs at pose j.
    branch_defect : the poses need different assembly signs.
    order_defect : one sweep of the input does not meet the poses in order.
    position_error : |P(θj) − Pj| relative to the poses' spread, P(θj) simulated by the engine on
        each pose's own assembly sign.
    angle_error : |coupler angle at θj − αj| (radians), simulated likewise.
    """

    mechanism: FourBar
    inputs: Array
    branches: Array
    branch_defect: NDArray[np.bool_]
    order_defect: NDArray[np.bool_]
    position_error: Array
    angle_error: Array

    @property
    def error(self) -> Array:
        """The larger of the two errors at the worst pose (batch shape)."""
        worst: Array = np.maximum(np.max(self.position_error, -1), np.max(self.angle_error, -1))
        return worst


@dataclass(frozen=True)
class FunctionDesign:
    """A four-bar generating output angles ψ from input angles φ, and how it meets the pairs.

    Arrays have the shape ``batch + (3,)`` unless noted.

    Attributes
    ----------
    mechanism : the four-bar, A0 at the origin and B0 on +x.
    coefficients : ``batch + (3,)`` Freudenstein's K1, K2, K3.
    inputs : the four-bar's input θj (radians, in (−π, π]) at pair j: φj + ``crank_offset``.
    outputs : its output angle (of B − B0 from the frame line) there: ψj + ``rocker_offset``.
    crank_offset, rocker_offset : 0, or π where Freudenstein's equation gave the crank (rocker)
        a negative length: the pin then sits opposite the angle φ (ψ) on the same rigid link, so
        the link turns exactly as prescribed (batch shape).
    branches : the assembly sign (±1) it needs at pair j.
    branch_defect : the pairs need different assembly signs (batch shape).
    order_defect : one sweep of the input does not meet the pairs in order (batch shape).
    error : |simulated output − outputs| at each pair (radians), simulated by the engine.
    """

    mechanism: FourBar
    coefficients: Array
    inputs: Array
    outputs: Array
    crank_offset: Array
    rocker_offset: Array
    branches: Array
    branch_defect: NDArray[np.bool_]
    order_defect: NDArray[np.bool_]
    error: Array
