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
        return np.sum(np.isfinite(self.lo), axis=-1)
