"""Every real configuration of any linkage at each input, packed and checked.

:func:`~linkwright.mechanisms.configurations` solves every combination of branches (dyad signs,
triad pose indices) of a mechanism's plan; :func:`solve_all` packs the real ones into slots at
each input sample, reads each configuration's assembly signs off its positions (the dyads of the
family's crank-driven plan, the signs its documents name), and recomputes each one's error
against every constraint with the family's own ``residuals``: the check does not trust the
solver. A Stephenson III driven at its crank has at most 4 configurations (two dyads), at its
output at most 6 (a triad); paper 001's spherical Stephenson III at most 4 driven at AB and 8 at
FG. One function answers every family: there is no second solver.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine import Motion
from linkwright.engine.plan import DYAD_TYPES
from linkwright.mechanisms.base import Mechanism, configurations

__all__ = ["AllConfigurations", "InvalidInputs", "solve_all"]

Array = NDArray[np.float64]

# Two configurations at one input closer than this (largest joint distance relative to the
# mechanism's size) are one: at a limit position both branches of a dyad give the same joints.
SAME_TOL = 1e-7


class InvalidInputs(ValueError):
    """The input samples are not a usable array of finite angles."""


@dataclass(frozen=True)
class AllConfigurations:
    """Every real configuration of a batch of linkages at each input sample.

    Arrays have the shape ``batch + (samples, slots)`` (positions add a trailing 2, or 3 on the
    sphere), ``slots`` the number of branch combinations of the plan. At each sample the real
    configurations come first, in the order of their combinations (dyad signs +1 before −1,
    triad poses by index), the rest is NaN (``valid`` False).

    Attributes
    ----------
    driven : the mechanism's input word ("crank", "output", "AB", "FG"), or "crank".
    input : ``batch + (samples,)``, the input angle θ of each sample (radians).
    positions : joint → ``batch + (samples, slots, d)``.
    valid : ``batch + (samples, slots)``, the slot holds a configuration.
    count : ``batch + (samples,)``, the number of configurations.
    branches : branching step → the branch value of each configuration (dyad sign, pose index).
    signs : assembly field → its sign read off the positions (the dyads of the family's
        crank-driven plan: ``assembly`` = sign((B0 − A) × (B − A)) for a Stephenson III, and
        so on); 0 marks a configuration exactly at that dyad's limit.
    residuals : constraint → |error| of each configuration, as the family's ``residuals``
        measures it (relative to the size in the plane, radians or chords on the sphere).
    residual : the largest of ``residuals`` for each configuration.
    """

    driven: str
    input: Array
    positions: dict[str, Array]
    valid: NDArray[np.bool_]
    count: NDArray[np.int_]
    branches: dict[str, Array]
    signs: dict[str, Array]
    residuals: dict[str, Array]
    residual: Array

    @property
    def assembly(self) -> Array:
        """The first dyad's sign (``signs["assembly"]``)."""
        return self.signs["assembly"]

    @property
    def assembly2(self) -> Array:
        """The second dyad's sign (``signs["assembly2"]``)."""
        return self.signs["assembly2"]


def solve_all(mechanism: Mechanism, inputs: ArrayLike) -> AllConfigurations:
    """Every real configuration of a batch of linkages at each input (module docstring).

    Parameters
    ----------
    mechanism : any family; dimensions may have a batch shape.
    inputs : ``(samples,)`` or ``batch + (samples,)``, radians.

    Returns
    -------
    AllConfigurations

    Examples
    --------
    The Stephenson III example: at θ = 0 on the crank, A = (1, 0), B = (4, 4) and C = (5, 2);
    the dyad C–D–D0 closes at D = (6.8, −0.4) and, on ``assembly2 = −1``, at D = (2, 2),
    straight above D0 = (2, −4). The four-bar's other branch (B = (4, −4)) leaves C too far:

    >>> from linkwright.mechanisms.sixbar import Stephenson3
    >>> m = Stephenson3(A0=[0, 0], B0=[4, 0], D0=[2, -4], crank=1, coupler=5, rocker=4, u1=4,
    ...                 v1=-2, link1=3, link2=6, u=1.5, v=1, assembly2=-1)
    >>> crank = solve_all(m, [0.0])
    >>> int(crank.count[0]), crank.assembly[0, :2].tolist(), crank.assembly2[0, :2].tolist()
    (2, [1.0, 1.0], [1.0, -1.0])
    >>> crank.positions["D"][0, :2].round(12) + 0.0
    array([[ 6.8, -0.4],
           [ 2. ,  2. ]])

    Driven at the output at θ = 90° (D = (2, 2) again) the triad has two configurations: the
    one above, with the crank back at 0, and one with the crank at 50.188°, which the
    crank-driven plan reproduces on the same signs (1, −1):

    >>> out = solve_all(Stephenson3(**m.params(), input="output"), [np.pi / 2])
    >>> int(out.count[0])
    2
    >>> out.positions["A"][0, :2].round(6) + 0.0
    array([[0.640271, 0.768149],
           [1.      , 0.      ]])
    >>> out.assembly[0, :2].tolist(), out.assembly2[0, :2].tolist()
    ([1.0, 1.0], [-1.0, -1.0])
    >>> bool(np.nanmax(out.residual) < 1e-14)
    True

    A linkage that cannot assemble has no configuration, and nothing NaN is valid:

    >>> from linkwright.mechanisms import FourBar
    >>> none = solve_all(FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3), [0.0, 1.0])
    >>> none.count, bool(none.valid.any()), bool(np.isnan(none.positions["B"]).all())
    (array([0, 0]), False, True)
    """
    theta = np.asarray(inputs, dtype=float)
    if theta.ndim == 0:
        raise InvalidInputs("inputs: give a 1-D array of samples (or batch + samples)")
    if not np.all(np.isfinite(theta)):
        raise InvalidInputs("inputs: every input angle must be finite")
    try:
        np.broadcast_shapes(mechanism.batch_shape, theta.shape[:-1])
    except ValueError as exc:
        raise InvalidInputs(f"inputs: do not broadcast with the mechanism's batch: {exc}") from None
    # A dyad whose parents meet divides by zero there: such samples are masked, not errors.
    with np.errstate(invalid="ignore", divide="ignore"):
        found = configurations(mechanism, theta, order=0)
    motions = [m for _, m in found]
    pos = {k: np.stack([m.positions[k] for m in motions], axis=-2) for k in motions[0].positions}
    valid = np.stack([m.valid for m in motions], axis=-1)
    branches = {
        k: np.stack([np.broadcast_to(m.branches[k], m.valid.shape) for m in motions], axis=-1)
        for k in motions[0].branches
    }
    scale = np.asarray(mechanism.scale, dtype=float)[..., None, None, None]  # samples, slots²
    valid = _drop_repeats(pos, valid, scale)
    order = np.argsort(~valid, axis=-1, kind="stable")
    valid = np.take_along_axis(valid, order, axis=-1)

    def packed(a: Array, trailing: bool) -> Array:
        index = order[..., None] if trailing else order
        keep = valid[..., None] if trailing else valid
        a = np.broadcast_to(a, valid.shape + (a.shape[-1:] if trailing else ()))
        return np.where(keep, np.take_along_axis(a, index, axis=-2 if trailing else -1), np.nan)

    pos = {k: packed(v, True) for k, v in pos.items()}
    branches = {k: packed(v, False) for k, v in branches.items()}
    signs = _signs(mechanism, pos, valid, branches)
    # The family's own constraint errors, measured on the packed positions.
    flat = Motion(
        input=np.broadcast_to(np.asarray(theta)[..., None], valid.shape),
        positions=pos,
        velocities=None,
        accelerations=None,
        valid=valid,
        regular=valid,
    )
    with np.errstate(invalid="ignore"):
        residuals = {
            k: np.where(valid, np.abs(_slot_axis(v, valid.shape)), np.nan)
            for k, v in mechanism.residuals(_per_slot(flat)).items()
        }
    residual = np.where(valid, np.fmax.reduce(list(residuals.values())), np.nan)
    return AllConfigurations(
        driven=str(getattr(mechanism, "input", "crank")),
        input=np.broadcast_to(theta, valid.shape[:-1]),
        positions=pos,
        valid=valid,
        count=valid.sum(axis=-1),
        branches=branches,
        signs=signs,
        residuals=residuals,
        residual=residual,
    )


def _per_slot(motion: Motion) -> Motion:
    """The packed motion with its slots as samples: ``residuals`` expects ``batch + (n,)``
    with the mechanism's batch in front, so the samples and slots are merged into one axis."""
    shape = motion.valid.shape
    n = shape[-2] * shape[-1]

    # Positions and flags alike.
    def merge(a: NDArray[Any], trailing: bool) -> NDArray[Any]:
        return a.reshape(shape[:-2] + (n,) + (a.shape[-1:] if trailing else ()))

    return Motion(
        input=merge(motion.input, False),
        positions={k: merge(v, True) for k, v in motion.positions.items()},
        velocities=None,
        accelerations=None,
        valid=merge(motion.valid, False),
        regular=merge(motion.regular, False),
    )


def _slot_axis(a: Array, shape: tuple[int, ...]) -> Array:
    return np.asarray(a).reshape(shape)


def _signs(
    mechanism: Mechanism,
    pos: dict[str, Array],
    valid: NDArray[np.bool_],
    branches: dict[str, Array],
) -> dict[str, Array]:
    """Each assembly field's sign (the dyads of the family's plan as its class declares it: the
    crank-driven one): the branch used where the mechanism's own plan has that dyad, else read
    off the positions by the dyad's own definition (0 exactly at its limit)."""
    params = {
        k: np.asarray(v, dtype=float)[..., None, None, :]
        if k in mechanism.points
        else np.asarray(v, dtype=float)[..., None, None]
        for k, v in mechanism.params().items()
    }
    out = {}
    for step in type(mechanism).plan.dyads:
        if step.name in branches and step in mechanism.plan.steps:
            out[step.branch] = branches[step.name]
        elif isinstance(step, DYAD_TYPES) and all(p in pos for p in (*step.parents, step.name)):
            with np.errstate(invalid="ignore"):
                sign = np.sign(step.branch_of(pos, params))
            out[step.branch] = np.where(valid, sign, np.nan)
    return out


def _drop_repeats(
    pos: dict[str, Array], valid: NDArray[np.bool_], scale: Array
) -> NDArray[np.bool_]:
    """Mark a configuration invalid where an earlier slot holds the same joints (two branches
    meeting at a limit position)."""
    joints = np.concatenate(list(pos.values()), axis=-1)  # (..., slots, all coordinates)
    joints = np.where(valid[..., None], joints, np.nan)
    gap = np.abs(joints[..., :, None, :] - joints[..., None, :, :]).max(axis=-1)
    n = valid.shape[-1]
    earlier = np.tril(np.ones((n, n), dtype=bool), k=-1)  # [j, i]: i < j
    with np.errstate(invalid="ignore"):
        same = (gap <= SAME_TOL * scale) & earlier
    distinct: NDArray[np.bool_] = valid & ~same.any(axis=-1)
    return distinct
