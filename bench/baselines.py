"""The yardstick for the engine's speed: the obvious hand-written NumPy four-bar.

What someone would write in ten lines for one family, without plans, derivatives, masks or
branch bookkeeping: place A on the crank circle, intersect the coupler and rocker circles for B,
put P in the coupler frame. Same conventions as ``linkwright.mechanisms.FourBar`` (assembly is
the sign of (B0 − A) × (B − A)), so the two can be checked against each other.
"""

from __future__ import annotations

import numpy as np


def fourbar_positions(A0, B0, crank, coupler, rocker, u, v, assembly, theta):
    """Positions of A, B, P of N four-bars at S inputs: arrays (N, S, 2). Inputs: points (N, 2),
    scalars (N,), theta (S,)."""
    A = A0[:, None, :] + crank[:, None, None] * np.stack((np.cos(theta), np.sin(theta)), -1)
    d = B0[:, None, :] - A
    dist = np.hypot(d[..., 0], d[..., 1])
    ex = d / dist[..., None]
    ey = np.stack((-ex[..., 1], ex[..., 0]), -1)
    along = (coupler[:, None] ** 2 - rocker[:, None] ** 2 + dist**2) / (2 * dist)
    h = assembly[:, None] * np.sqrt(np.maximum(coupler[:, None] ** 2 - along**2, 0.0))
    B = A + along[..., None] * ex + h[..., None] * ey
    e = (B - A) / coupler[:, None, None]
    P = A + u[:, None, None] * e + v[:, None, None] * np.stack((-e[..., 1], e[..., 0]), -1)
    return A, B, P
