"""Batched evaluation of a construction plan over (mechanisms × input samples)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine.plan import JointState, Param, Plan

__all__ = ["Motion", "evaluate", "motion_of_states", "place_all", "take"]

Array = NDArray[np.float64]
Index = int | slice | NDArray[np.integer[Any]] | NDArray[np.bool_]
"""A selection of batch entries: one, a slice, or an array of indices or of flags."""


@dataclass(frozen=True)
class Motion:
    """The result of solving a linkage: every joint over a batch of mechanisms and inputs.

    Arrays have shape ``batch + (samples,)`` (positions add a trailing axis of 2). Positions are
    NaN exactly where ``valid`` is False, derivatives exactly where ``regular`` is False; nothing
    NaN is left unmasked. Derivatives are with respect to the input angle θ (per radian).

    Attributes
    ----------
    input : the input angle θ of each sample, radians.
    positions, velocities, accelerations : joint name → array.
    valid : the linkage is assembled at this sample.
    regular : the derivatives exist (the sample is not a singular position).
    branches : dyad joint name → the branch sign used at each sample (a triad's joints: the
        pose index used).
    margins : dyad joint name → normalised discriminant (0 at that dyad's limit position); a
        triad's joints: its signed closure.
    labels : joint name → the branch's label, which changes along a circuit only at a limit
        position (a dyad's sign; a triad's closure sign): where faces find a circuit's legs.

    Examples
    --------
    >>> from linkwright import FourBar, solve
    >>> motion = solve(FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=3, rocker=3.5), [0, 1, 2])
    >>> motion.positions["B"].shape, bool(motion.valid.all())
    ((3, 2), True)

    Where the linkage cannot assemble its positions are NaN and ``valid`` is False:

    >>> far = solve(FourBar(A0=[0, 0], B0=[9, 0], crank=1, coupler=3, rocker=3.5), [0.0])
    >>> bool(far.valid[0]), bool(np.isnan(far.positions["B"]).all())
    (False, True)
    """

    input: Array
    positions: dict[str, Array]
    velocities: dict[str, Array] | None
    accelerations: dict[str, Array] | None
    valid: NDArray[np.bool_]
    regular: NDArray[np.bool_]
    branches: dict[str, Array] = field(default_factory=dict)
    margins: dict[str, Array] = field(default_factory=dict)
    labels: dict[str, Array] = field(default_factory=dict)

    @property
    def shape(self) -> tuple[int, ...]:
        return self.input.shape

    def _repr_svg_(self) -> str | None:
        # Jupyter's picture of the joints' paths, drawn by the plots (above this layer) through
        # linkwright._display, which the package root fills.
        from linkwright._display import repr_svg

        return repr_svg(self)


class _Context:
    def __init__(
        self,
        params: Mapping[str, ArrayLike],
        theta: Array,
        branches: Mapping[str, ArrayLike],
        order: int,
        crossings: Mapping[str, ArrayLike] | None = None,
    ) -> None:
        self.params = params
        self._theta = theta
        self.branches = branches
        self.order = order
        self.crossings = crossings or {}
        self.states: dict[str, JointState] = {}

    @property
    def theta(self) -> Array:
        return self._theta

    def scalar(self, p: Param) -> Array:
        if isinstance(p, str):
            return np.asarray(self.params[p], dtype=float)[..., None]
        return np.asarray(p, dtype=float)

    def point(self, key: str) -> Array:
        return np.asarray(self.params[key], dtype=float)[..., None, :]

    def joint(self, name: str) -> JointState:
        return self.states[name]

    def branch(self, step_name: str, key: str) -> Array:
        if step_name in self.branches:
            b = np.asarray(self.branches[step_name], dtype=float)
        else:
            b = np.asarray(self.params[key], dtype=float)[..., None]
        return np.broadcast_to(b, self._theta.shape)

    def crossing(self, step_name: str) -> Array | None:
        """Where the dyad's parents coincide (±1: placed as the limit from the side of larger
        or smaller input, see :mod:`linkwright.engine.crossings`), 0 elsewhere; None if nowhere."""
        side = self.crossings.get(step_name)
        if side is None:
            return None
        return np.broadcast_to(np.asarray(side, dtype=float), self._theta.shape)


def take(motion: Motion, index: Index) -> Motion:
    """The motion of the batch entries at ``index`` (over the leading axes of ``input``): every
    array indexed alike, the samples' axis and the coordinates' kept.

    >>> m = Motion(np.zeros((3, 5)), {"A": np.ones((3, 5, 2))}, None, None,
    ...            np.ones((3, 5), bool), np.ones((3, 5), bool))
    >>> take(m, 1).input.shape, take(m, slice(0, 2)).positions["A"].shape
    ((5,), (2, 5, 2))
    """

    def pick(arrays: dict[str, Array] | None) -> dict[str, Array] | None:
        return None if arrays is None else {k: v[index] for k, v in arrays.items()}

    return Motion(
        input=motion.input[index],
        positions=pick(motion.positions) or {},
        velocities=pick(motion.velocities),
        accelerations=pick(motion.accelerations),
        valid=motion.valid[index],
        regular=motion.regular[index],
        branches=pick(motion.branches) or {},
        margins=pick(motion.margins) or {},
        labels=pick(motion.labels) or {},
    )


def batch_shape(params: Mapping[str, ArrayLike], points: frozenset[str]) -> tuple[int, ...]:
    """Broadcast batch shape of a parameter mapping (point parameters carry a trailing 2)."""
    shapes = []
    for key, value in params.items():
        shape = np.shape(value)
        shapes.append(shape[:-1] if key in points else shape)
    return np.broadcast_shapes(*shapes) if shapes else ()


def place_all(
    plan: Plan,
    params: Mapping[str, ArrayLike],
    theta: ArrayLike,
    *,
    points: frozenset[str] = frozenset(),
    branches: Mapping[str, ArrayLike] | None = None,
    order: int = 2,
    crossings: Mapping[str, ArrayLike] | None = None,
) -> tuple[Array, dict[str, JointState]]:
    """Run every step and return the broadcast inputs and the raw, unmasked joint states."""
    theta = np.asarray(theta, dtype=float)
    if theta.ndim == 0:
        theta = theta[None]
    shape = np.broadcast_shapes(batch_shape(params, points) + (1,), theta.shape)
    theta = np.broadcast_to(theta, shape)
    crossings = {k: v for k, v in (crossings or {}).items() if np.any(v)}
    # A joint placed as a limit where its parents coincide takes its direction from their
    # velocities, so those are computed even where only positions are asked for.
    ctx = _Context(params, theta, branches or {}, max(order, 1) if crossings else order, crossings)
    # At (near-)singular samples the derivatives overflow to inf; those samples are masked as
    # not regular, so the overflow is expected and not worth a warning.
    with np.errstate(over="ignore"):
        for step in plan.steps:
            placed = step.place(ctx)
            if isinstance(placed, JointState):
                ctx.states[step.name] = placed
            else:  # a step that places several joints at once (a triad)
                ctx.states.update(placed)
    return theta, ctx.states


def evaluate(
    plan: Plan,
    params: Mapping[str, ArrayLike],
    theta: ArrayLike,
    *,
    points: frozenset[str] = frozenset(),
    branches: Mapping[str, ArrayLike] | None = None,
    order: int = 2,
    crossings: Mapping[str, ArrayLike] | None = None,
) -> Motion:
    """Place every joint of ``plan`` at the inputs ``theta`` (radians).

    Parameters
    ----------
    plan : the construction plan.
    params : named parameters; scalars have the batch shape, point parameters (listed in
        ``points``) the batch shape plus a trailing 2.
    theta : input samples, shape ``(samples,)`` or ``batch + (samples,)``.
    branches : per-sample branch signs for some dyads (joint name → array broadcastable to the
        motion's shape), overriding their assembly parameter; used by circuit tracing.
    order : 0 for positions only, 1 to add velocities, 2 to add accelerations.
    crossings : for some dyads (joint name → array like ``branches``), the samples that lie
        exactly where the dyad's parents coincide (on the sphere: or are antipodal) and its
        joint is undetermined: +1 or −1 places it as the limit of the given branch from larger
        or smaller inputs, 0 as usual. Used by circuit tracing
        (:mod:`linkwright.engine.crossings`).
    """
    theta, states = place_all(
        plan, params, theta, points=points, branches=branches, order=order, crossings=crossings
    )
    return motion_of_states(theta, states, order)


def motion_of_states(theta: Array, states: Mapping[str, JointState], order: int) -> Motion:
    """The masked :class:`Motion` of placed joint states (what :func:`place_all` returns, or a
    compiled plan's equivalent): positions NaN exactly where the linkage is not assembled,
    derivatives exactly where it is not regular."""
    valid = np.ones(theta.shape, dtype=bool)
    regular = np.ones(theta.shape, dtype=bool)
    for state in states.values():
        valid = valid & state.valid
        regular = regular & state.regular
    # A joint of a linkage that is not assembled has no position, even a ground pivot: masking
    # every joint alike keeps "NaN exactly where not valid" a rule without exceptions.
    keep_pos, keep_der = valid[..., None], regular[..., None]

    def masked(arrays: dict[str, Array | None], keep: NDArray[np.bool_]) -> dict[str, Array]:
        return {k: np.where(keep, a, np.nan) for k, a in arrays.items() if a is not None}

    return Motion(
        input=theta,
        positions=masked({k: s.pos for k, s in states.items()}, keep_pos),
        velocities=masked({k: s.vel for k, s in states.items()}, keep_der) if order >= 1 else None,
        accelerations=(
            masked({k: s.acc for k, s in states.items()}, keep_der) if order >= 2 else None
        ),
        valid=valid,
        regular=regular,
        branches={k: s.branch for k, s in states.items() if s.branch is not None},
        margins={k: s.margin for k, s in states.items() if s.margin is not None},
        labels={
            k: s.branch if s.label is None else s.label
            for k, s in states.items()
            if s.branch is not None
        },
    )
