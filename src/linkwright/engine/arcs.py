"""The admissible inputs of a batch of linkages: the result of every limit search."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["TWO_PI", "InputArcs"]

Array = NDArray[np.float64]
TWO_PI = 2.0 * np.pi


@dataclass(frozen=True)
class InputArcs:
    """The admissible inputs of a batch of linkages with their assembly held fixed.

    ``full`` marks linkages whose input turns fully, ``never`` those that assemble nowhere. Else
    ``lo``/``hi`` (shape ``batch + (K,)``, NaN-padded, ``lo`` in (−π, −π + period], ``hi > lo``)
    are the arcs, and ``dyad_lo``/``dyad_hi`` the index (into ``plan.dyads``) of the dyad at its
    limit there (−1 in padding). ``period`` is how far the input turns before the linkage
    repeats: 2π, or 2πq for a linkage geared at a ratio p/q (see :func:`input_turns`).

    Examples
    --------
    A crank-rocker turns fully; a triple rocker rocks between two limits; a linkage that
    cannot assemble has no arc:

    >>> from linkwright import FourBar, input_range
    >>> input_range(FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=3, rocker=3.5)).full
    array(True)
    >>> rocker = input_range(FourBar(A0=[0, 0], B0=[2, 0], crank=2, coupler=2.5, rocker=1.5))
    >>> bool(rocker.full), int(np.isfinite(rocker.lo).sum())
    (False, 1)
    >>> bool(input_range(FourBar(A0=[0, 0], B0=[9, 0], crank=1, coupler=1, rocker=1)).never)
    True
    """

    full: NDArray[np.bool_]
    never: NDArray[np.bool_]
    lo: Array
    hi: Array
    dyad_lo: NDArray[np.int64]
    dyad_hi: NDArray[np.int64]
    period: Array | float = TWO_PI

    @property
    def count(self) -> NDArray[np.int64]:
        count: NDArray[np.int64] = np.sum(np.isfinite(self.lo), axis=-1)
        return count
