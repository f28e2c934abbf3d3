"""What every step kind of a construction plan shares: the joint state, the context a step
reads its parents and parameters from, the engine's tolerances and a few helpers.

The step kinds themselves live in :mod:`linkwright.engine.plane_steps`,
:mod:`linkwright.engine.sphere_steps` and :mod:`linkwright.engine.triad_steps`; the plan that
orders them in :mod:`linkwright.engine.plan`.

Besides placing its joint(s), every step kind answers four questions from positions alone, so
that no face re-derives them (DESIGN.md, "Each step kind owns what is known about it"):

- ``closure(positions, params)``: the quantity whose sign says whether it assembles (a dyad's
  normalised discriminant, a triad's relative determinant);
- ``residual(positions, params, theta)``: its constraint error, written from the constraints
  alone (lengths in the plane, radians or chords on the sphere; :meth:`Plan.residuals` scales
  them by the linkage's size);
- ``unassembled(positions, params)``: the sentence that explains why it cannot assemble;
- ``title``: how a sentence names it ("dyad B", "triad BCE").

``positions`` maps joint names to arrays of shape ``batch + (samples,) + (2 or 3,)`` (a
:class:`~linkwright.engine.evaluate.Motion`'s), ``params`` is the plan's parameter mapping
(batch shape, points with a trailing axis) and ``theta`` the input, ``batch + (samples,)``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "ASSEMBLY_TOL",
    "SINGULAR_MARGIN",
    "SINGULAR_SIN",
    "Context",
    "JointState",
    "Param",
    "Step",
    "param_point",
    "param_value",
]

Array = NDArray[np.float64]
Param = str | float
"""A step's numeric parameter: the name of an entry of the parameter mapping, or a constant."""

# Below this |sin| of the angle between a dyad's two links the 2×2 derivative system is treated
# as singular: the relative error of the derivatives grows like eps/sin², so past 1e-8 they are
# no longer trustworthy and are reported as masked rather than as large wrong numbers.
SINGULAR_SIN = 1e-8
# The same bound on the dyad's own margin (sin² of the angle at its first pivot, or cos² of a
# rod's angle to its guide): an exact limit position has margin ~1e-16 yet passes the test above
# by rounding, and its derivatives (infinite in truth) would come out as huge finite numbers.
SINGULAR_MARGIN = 1e-12
# A dyad whose normalised discriminant is above -ASSEMBLY_TOL still closes (rounding at an exact
# limit position must not turn the limit itself into a failure); the clamp leaves a constraint
# residual of the same relative size, far below the 1e-10 promised.
ASSEMBLY_TOL = 1e-12


@dataclass(frozen=True)
class JointState:
    """Position, first and second θ-derivatives of one joint, and where they are defined.

    ``valid`` marks samples where the joint could be placed; ``regular`` marks samples where the
    derivatives are finite (not at a singular, e.g. toggle, position). Both have the batch shape.
    """

    pos: Array
    vel: Array | None
    acc: Array | None
    valid: NDArray[np.bool_]
    regular: NDArray[np.bool_]
    margin: Array | None = None
    """For dyads: the normalised discriminant (≥ 0 where the dyad closes; 0 at a limit)."""
    branch: Array | None = None
    """For dyads: the branch sign used at each sample (for a triad: its pose index)."""
    label: Array | None = None
    """The branch's label that changes only at a limit position: a dyad's sign (its
    ``branch``, when left None), a triad's closure sign (its pose index does not)."""


class Context(Protocol):
    order: int

    def scalar(self, p: Param) -> Array: ...
    def point(self, key: str) -> Array: ...
    def joint(self, name: str) -> JointState: ...
    def branch(self, step_name: str, key: str) -> Array: ...
    def crossing(self, step_name: str) -> Array | None: ...
    @property
    def theta(self) -> Array: ...


Positions = Mapping[str, Array]
Params = Mapping[str, ArrayLike]


class Step(Protocol):
    # Read-only: the step kinds are frozen dataclasses, and a protocol's plain attribute would
    # ask for a settable one.
    @property
    def name(self) -> str: ...

    @property
    def parents(self) -> tuple[str, ...]: ...

    @property
    def title(self) -> str:
        """How a sentence names the step: "dyad B", "triad BCE"."""
        ...

    def links(self) -> tuple[tuple[str, str], ...]: ...
    def plates(self) -> tuple[tuple[str, ...], ...]: ...
    def place(self, ctx: Context) -> JointState | dict[str, JointState]:
        """The state of the joint the step places (of each joint, for a triad)."""
        ...

    def closure(self, positions: Positions, params: Params) -> Array:
        """The quantity whose sign says whether the step assembles."""
        ...

    def residual(self, positions: Positions, params: Params, theta: ArrayLike) -> Array:
        """The largest constraint error of the placed joint(s), from the constraints alone."""
        ...

    def unassembled(self, positions: Positions | None = None, params: Params | None = None) -> str:
        """Why the step cannot place its joint(s) at an input."""
        ...


def param_value(p: Param, params: Params) -> Array:
    """A step's scalar parameter against arrays of shape ``batch + (samples,)``: a named one
    gets an axis for the samples, a constant stays a scalar."""
    if isinstance(p, str):
        return np.asarray(params[p], dtype=float)[..., None]
    return np.asarray(p, dtype=float)


def param_point(key: str, params: Params) -> Array:
    """A point parameter against positions of shape ``batch + (samples, d)``."""
    return np.asarray(params[key], dtype=float)[..., None, :]


def first(value: ArrayLike) -> float:
    """The first entry of an array, as a float: sentences speak of one linkage at one input."""
    return float(np.asarray(value, dtype=float).reshape(-1)[0])


def number(p: Param, params: Params) -> float:
    """A parameter's value for a sentence about one linkage (the first of a batch)."""
    return first(params[p]) if isinstance(p, str) else float(p)


def word(p: Param) -> str:
    """A length parameter as a sentence names it: its field's name, or "link" for a constant."""
    return p if isinstance(p, str) else "link"


class OnPivot:
    """What a crank shares in both spaces: one link from its pivot to the joint it turns."""

    name: str
    pivot: str

    @property
    def parents(self) -> tuple[str, ...]:
        return (self.pivot,)

    @property
    def title(self) -> str:
        return f"crank {self.name}"

    def links(self) -> tuple[tuple[str, str], ...]:
        """The links a drawing shows for this step, as pairs of joints."""
        return ((self.pivot, self.name),)

    def plates(self) -> tuple[tuple[str, ...], ...]:
        """The rigid bodies of three joints or more that this step makes, to fill."""
        return ()


class OnLink:
    """What a rigid point shares in both spaces: the link ``origin``→``toward`` carries it,
    and the three make one body."""

    name: str
    origin: str
    toward: str

    @property
    def parents(self) -> tuple[str, ...]:
        return (self.origin, self.toward)

    @property
    def title(self) -> str:
        return f"point {self.name}"

    def links(self) -> tuple[tuple[str, str], ...]:
        """The links a drawing shows for this step, as pairs of joints."""
        return ((self.origin, self.name), (self.toward, self.name))

    def plates(self) -> tuple[tuple[str, ...], ...]:
        """The rigid bodies of three joints or more that this step makes, to fill."""
        return ((self.origin, self.toward, self.name),)


@dataclass(frozen=True)
class TwoLinkDyad:
    """What the planar and the spherical RRR dyad share: the joint ``name`` of two binary
    links, of lengths (arcs) ``r1`` from ``p1`` and ``r2`` from ``p2``, on the branch named
    ``branch``; its links and the sentences that explain a failure or a limit."""

    name: str
    p1: str
    r1: Param
    p2: str
    r2: Param
    branch: str = "assembly"

    in_line: ClassVar[str] = "in line"
    """How the two links lie at a limit position (on the sphere: on one great circle)."""

    @property
    def parents(self) -> tuple[str, ...]:
        return (self.p1, self.p2)

    @property
    def title(self) -> str:
        return f"dyad {self.name}"

    def links(self) -> tuple[tuple[str, str], ...]:
        """The links a drawing shows for this step, as pairs of joints."""
        return ((self.p1, self.name), (self.p2, self.name))

    def plates(self) -> tuple[tuple[str, ...], ...]:
        """The rigid bodies of three joints or more that this step makes, to fill."""
        return ()

    def at_limit(self) -> str:
        """What happens at a limit position of the input."""
        return (
            f"dyad {self.name}: {self.p1}–{self.name} and {self.name}–{self.p2} fall "
            f"{self.in_line} (stretched out or folded)"
        )

    def _cannot_meet(
        self, where: str, gap: float, reach: tuple[str, float], fold: float, unit: str = ""
    ) -> str:
        """The links cannot reach across ``gap`` (beyond ``reach``, named and valued), or
        cannot fold that short (below ``fold``); ``where`` shows the gap."""
        w1, w2 = word(self.r1), word(self.r2)
        if gap > reach[1]:
            return f"the {w1} and {w2} cannot reach ({where} > {reach[0]} = {reach[1]:.6g}{unit})"
        return (
            f"the {w1} and {w2} cannot fold that short ({where} < |{w1} - {w2}| = {fold:.6g}{unit})"
        )

    def _no_numbers(self) -> str:
        return f"the {word(self.r1)} and {word(self.r2)} of dyad {self.name} cannot meet"


def combine(*states: JointState) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """Where all of ``states`` are valid, and where all are regular."""
    valid = states[0].valid
    regular = states[0].regular
    for s in states[1:]:
        valid = valid & s.valid
        regular = regular & s.regular
    return valid, regular


def at_crossing(
    at: Array,
    limit: Array,
    pos: Array,
    valid: NDArray[np.bool_],
    margin: Array,
    j1: JointState,
    j2: JointState,
) -> tuple[Array, NDArray[np.bool_], Array]:
    """A dyad's joint where its parents coincide: ``limit`` at the samples marked in ``at``.

    Its two links then lie on each other, at right angles to the parents' line in the limit:
    the margin (sin² of the angle at P1) is 1, far from a limit position.
    """
    on = at != 0
    ok = j1.valid & j2.valid & np.isfinite(limit).all(axis=-1)
    pos = np.where(on[..., None], np.where(ok[..., None], limit, np.nan), pos)
    return pos, np.where(on, ok, valid), np.where(on, 1.0, margin)


def mask_derivatives(
    vel: Array | None, acc: Array | None, regular: NDArray[np.bool_]
) -> tuple[Array | None, Array | None]:
    """Velocities and accelerations NaN where ``regular`` is False."""
    keep = regular[..., None]
    if vel is not None:
        vel = np.where(keep, vel, np.nan)
    if acc is not None:
        acc = np.where(keep, acc, np.nan)
    return vel, acc


def pose_slot(ctx: Context, step_name: str, key: str, most: int) -> tuple[NDArray[np.int_], Array]:
    """The pose index a step with ``most`` poses is asked for at each sample (as an int usable
    for indexing) and as given (a value that is not a whole number in range matches no pose)."""
    asked = np.asarray(ctx.branch(step_name, key), dtype=float)
    usable = np.where(np.isfinite(asked), asked, 0.0)
    index = np.clip(np.rint(usable), 0, most - 1).astype(np.int64)
    return index, asked


def pose_states(
    joints: tuple[str, ...],
    pos: Array,
    vel: Array | None,
    acc: Array | None,
    valid: NDArray[np.bool_],
    regular: NDArray[np.bool_],
    closure: Array,
    slot: Array,
) -> dict[str, JointState]:
    """The states of the joints a pose step places (a triad, a driven hinge): ``pos``, ``vel``
    and ``acc`` are ``(..., len(joints), d)``; positions NaN where not valid, derivatives where
    not regular; every joint carries the step's signed closure as its margin, the pose asked
    for as its branch, and the closure's sign as its label (it changes only where two poses
    merge)."""
    pos = np.where(valid[..., None, None], pos, np.nan)
    vel, acc = mask_derivatives(vel, acc, regular[..., None])
    return {
        name: JointState(
            pos[..., k, :],
            None if vel is None else vel[..., k, :],
            None if acc is None else acc[..., k, :],
            valid,
            regular,
            margin=closure,
            branch=slot,
            label=np.where(closure >= 0, 1.0, -1.0),
        )
        for k, name in enumerate(joints)
    }


def always(positions: Positions, name: str) -> Array:
    """The closure of a step that assembles wherever its parents do: 1 at every sample."""
    return np.ones(np.shape(positions[name])[:-1])


def derivative(x: Array | None) -> Array:
    """A parent's velocity or acceleration, read where the context's order asked for it.

    A context of order n places every parent to order n, so the derivative is there; None here
    is a bug in a step kind, not bad input.
    """
    if x is None:
        raise RuntimeError("a step read a derivative above its context's order")
    return x
