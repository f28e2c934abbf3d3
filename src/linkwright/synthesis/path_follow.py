"""Following a configuration with a triad along the input, sample by sample.

A triad's pose index is only a name at one input: the poses are ordered by an angle at each
input and reorder where two cross or one wraps. :func:`follow` therefore solves every pose at
the inputs and on a grid over the input's period, and continues the branch from the coded pose
at the frame's input 0 to its nearest configuration sample by sample; where the nearest is not
clearly nearest (a limit position, two poses passing close) the branch ends there. It is how
:class:`~linkwright.synthesis.path_models.GenericModel` solves a configuration with a triad.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TypeVar

import numpy as np
from numpy.typing import NDArray

from linkwright.engine.continuation import every_configuration
from linkwright.mechanisms import Mechanism

__all__ = [
    "CLEAR",
    "FOLLOW_GRID",
    "JUMP",
    "Followed",
    "follow",
]

Array = NDArray[np.float64]
TWO_PI = 2.0 * np.pi


FOLLOW_GRID = 40
"""Samples a period of the input on which a triad's branch is followed between inputs."""
CLEAR = 0.5
"""A followed branch continues to its nearest configuration only while that is nearer than
this fraction of the distance to the next nearest."""
JUMP = 0.9
"""A followed branch's next sample may lie off the line through its last two by at most this
fraction of the step (a smooth branch: by about the step's square; a jump to another branch,
where the branch ended at a limit position between two samples: by about the whole step)."""


_Item = TypeVar("_Item", bound=np.generic)


@dataclass(frozen=True)
class Followed:
    """Positions on one configuration at each input, as a :class:`~linkwright.engine.Motion`
    has them (``positions``, ``valid``, ``margins``), and the branch values used."""

    positions: dict[str, Array]
    valid: NDArray[np.bool_]
    margins: dict[str, Array]
    branches: dict[str, Array]


# --------------------------------------------------------------------------------------------
# Following a configuration with a triad
# --------------------------------------------------------------------------------------------


def follow(
    mech: Mechanism,
    start: Mapping[str, Array],
    inputs: Array,
    anchor: Array,
    period: float = TWO_PI,
    grid: int = FOLLOW_GRID,
    around: bool = True,
) -> Followed:
    """One configuration of each linkage of a batch, followed by continuity.

    ``start`` gives, per branching step (by step name), its branch value at the input
    ``anchor`` (B,); the configuration is the branch of motion through it, continued from the
    anchor up and down the input (not taken modulo a turn: a branch between two limit positions
    may span more than one) to each of ``inputs`` (B, K), through a grid of ``grid`` samples a
    ``period`` covering at least a period either side. An input the branch does not reach
    directly (it turns back at a limit position first) is looked for a period further round,
    the other way (unless ``around`` is False): a branch that rocks about the anchor is so
    seen whole on any one turn of the input. Each step goes to the nearest configuration,
    only while it is clearly nearest (:data:`CLEAR`); past that the configuration is not
    valid.

    Examples
    --------
    A Stephenson III driven at its output (bundled ``stephenson3-output``) has two circuits; the
    one through pose 0 at the input 0 is followed for a whole turn, and closes:

    >>> from linkwright.mechanisms import Stephenson3
    >>> m = Stephenson3(A0=[0, 0], B0=[4, 0], D0=[0, 2.8], crank=1, coupler=4, rocker=3,
    ...                 u1=2, v1=2, link1=0.7, link2=1, input="output")
    >>> theta = np.linspace(0, 2 * np.pi, 9)[None]
    >>> got = follow(m, {"A": np.array([0.0])}, theta, np.zeros(1))
    >>> P = got.positions["P"][0]
    >>> bool(got.valid.all()), bool(np.allclose(P[0], P[-1]))
    (True, True)
    """
    inputs = np.asarray(inputs, dtype=float)
    anchor = np.asarray(anchor, dtype=float)
    rel = inputs - anchor[:, None]
    got, alive = _follow_once(mech, start, rel, anchor, grid * 1.0 / period)
    # Inputs the branch turns back from before reaching: a period round the other way (a
    # second, smaller walk, for the linkages that need it).
    need = np.flatnonzero(alive & ~got.valid.all(axis=1)) if around else np.zeros(0, int)
    if need.size:
        other = np.where(rel > 0, rel - period, rel + period)[need]
        sub = mech[need] if mech.batch_shape else mech
        part = {k: np.asarray(v)[need] if np.ndim(v) else v for k, v in start.items()}
        more, _ = _follow_once(sub, part, other, anchor[need], grid * 1.0 / period)
        take = ~got.valid[need] & more.valid
        rows = need[:, None]

        def merged(a: NDArray[_Item], b: NDArray[_Item]) -> NDArray[_Item]:
            out = a.copy()
            mask = take if b.ndim == 2 else take[..., None]
            out[need] = np.where(mask, b, a[rows[:, 0]])
            return out

        got = Followed(
            {n: merged(v, more.positions[n]) for n, v in got.positions.items()},
            merged(got.valid, more.valid),
            {n: merged(v, more.margins[n]) for n, v in got.margins.items()},
            {n: merged(v, more.branches[n]) for n, v in got.branches.items()},
        )
    return got


def _follow_once(
    mech: Mechanism, start: Mapping[str, Array], rel: Array, anchor: Array, density: float
) -> tuple[Followed, NDArray[np.bool_]]:
    """:func:`follow` on the inputs ``anchor + rel`` directly (no second way round), with
    ``density`` grid samples a radian; also whether the start exists at the anchor."""
    b = rel.shape[0]
    step = 1.0 / density
    low = min(0.0, float(np.min(rel))) if rel.size else 0.0
    high = max(0.0, float(np.max(rel))) if rel.size else 0.0
    offsets = step * np.arange(math.floor(low / step), math.ceil(high / step) + 1)
    n_grid = len(offsets)
    # The grid first, so that the anchor (offset 0) sorts before any input equal to it.
    theta = anchor[:, None] + np.concatenate([np.broadcast_to(offsets, (b, n_grid)), rel], axis=1)
    order = np.argsort(theta, axis=1, kind="stable")
    ordered = np.take_along_axis(theta, order, axis=1)
    where = np.argsort(order, axis=1)  # each sample's place in the sorted sequence
    home = where[:, int(np.flatnonzero(offsets == 0.0)[0])]
    combos, motion = every_configuration(
        mech.plan, mech.params(), ordered, points=mech.points, order=0
    )
    c = len(combos)
    rows = np.arange(b)
    names = list(motion.positions)
    x = np.concatenate([motion.positions[n] for n in names], axis=-1)  # (C, B, S, D)
    ok = motion.valid  # (C, B, S)
    x = np.where(ok[..., None], x, np.nan)
    match = np.ones((c, b), dtype=bool)
    for name, values in start.items():
        vals = np.array([combo[name] for combo in combos])
        match &= vals[:, None] == np.broadcast_to(np.asarray(values, dtype=float), (b,))[None]
    at_home = ok[:, rows, home]
    first = np.argmax(match & at_home, axis=0)
    alive0 = np.asarray((match & at_home).any(axis=0), dtype=np.bool_)
    count = theta.shape[1]
    chosen = np.zeros((b, count), dtype=int)
    good = np.zeros((b, count), dtype=bool)
    chosen[rows, home], good[rows, home] = first, alive0
    # Each configuration's labels (a dyad's sign, a triad's closure sign) stay put along a
    # branch of motion and change only where it ends at a limit position.
    labels = np.stack([np.broadcast_to(v, ok.shape) for v in motion.labels.values()], axis=-1)
    size = float(np.nanmax(np.abs(x))) if np.isfinite(x).any() else 1.0

    def walk(sequence: range, sense: int) -> None:
        cur, alive = first.copy(), alive0.copy()
        prev = x[cur, rows, home]
        label = labels[cur, rows, home]
        at = ordered[rows, home]
        # The step before (its start and input span): the branch continues where a straight
        # line through the last two samples points, to within a fraction of the step.
        before = np.full_like(prev, np.nan)
        width = np.full(b, np.nan)
        for s in sequence:
            moving = (s - home) * sense > 0  # rows already past their anchor this way
            if not moving.any():
                continue
            d = np.sqrt(np.nansum((x[:, :, s] - prev[None]) ** 2, axis=-1))
            same = np.all(labels[:, :, s] == label[None], axis=-1)
            d = np.where(ok[:, :, s] & same, d, np.inf)
            if c > 1:
                part = np.partition(d, 1, axis=0)
                near, second = part[0], part[1]
            else:
                near, second = d[0], np.full(b, np.inf)
            nxt = np.argmin(d, axis=0)
            # Clearly the nearest, and no jump: where the branch ends at a limit position between
            # two samples, the nearest configuration left lies off the line it was running on.
            span = np.abs(ordered[:, s] - at)
            guess = prev + (prev - before) * (span / np.where(width > 0, width, np.nan))[:, None]
            off = np.sqrt(np.nansum((x[nxt, rows, s] - guess) ** 2, axis=-1))
            steady = ~np.isfinite(width) | (off <= JUMP * near) | (near <= 1e-9 * size)
            keep = np.isfinite(near) & (near < CLEAR * second) & steady
            alive = np.where(moving, alive & keep, alive)
            cur = np.where(moving & alive, nxt, cur)
            chosen[:, s] = np.where(moving, cur, chosen[:, s])
            good[:, s] = np.where(moving, alive, good[:, s])
            grows = moving & alive & (span > 1e-9)
            before = np.where(grows[:, None], prev, before)
            width = np.where(grows, span, width)
            at = np.where(grows, ordered[:, s], at)
            prev = np.where(grows[:, None], x[cur, rows, s], prev)

    walk(range(count), 1)
    walk(range(count - 1, -1, -1), -1)
    place = where[:, n_grid:]
    pick = np.take_along_axis(chosen, place, axis=1)
    valid = np.take_along_axis(good, place, axis=1)
    at = (pick, rows[:, None], place)

    def gather(array: Array) -> Array:
        out = array[at]
        mask = valid if out.ndim == 2 else valid[..., None]
        return np.where(mask, out, np.nan)

    branches = {
        step: np.where(valid, np.array([combo[step] for combo in combos])[pick], np.nan)
        for step in combos[0]
    }
    followed = Followed(
        {n: gather(motion.positions[n]) for n in names},
        valid,
        {n: gather(m) for n, m in motion.margins.items()},
        branches,
    )
    return followed, alive0
