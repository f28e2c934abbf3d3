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


def spherical_fourbar_positions(frame, crank, coupler, rocker, point_arc, point_angle, assembly,
                                theta):  # fmt: skip
    """Unit vectors A, B, P of N spherical four-bars at S inputs: arrays (N, S, 3), in paper
    000's frame (A0 = x, B0 = (cos a1, sin a1, 0)), assembly the sign of (A × B0)·B.

    The obvious NumPy: B = α A + β B0 + γ (A × B0) from B·A = cos a3, B·B0 = cos a4, |B| = 1;
    P by turning the great circle A→B about OA and walking the arc AP.
    """
    col = lambda x: x[:, None]  # noqa: E731 - per-mechanism scalar against samples
    a1, a2, a3, a4 = (col(x) for x in (frame, crank, coupler, rocker))
    zeros = np.zeros((len(frame), len(theta)))
    A = np.stack((np.cos(a2) + zeros, np.sin(a2) * np.cos(theta), np.sin(a2) * np.sin(theta)), -1)
    B0 = np.stack((np.cos(a1), np.sin(a1), np.zeros_like(a1)), -1)  # (N, 1, 3)
    c = np.sum(A * B0, -1)
    w = np.cross(A, B0)
    s2 = 1.0 - c * c
    alpha = (np.cos(a3) - c * np.cos(a4)) / s2
    beta = (np.cos(a4) - c * np.cos(a3)) / s2
    gamma2 = (1.0 - alpha * np.cos(a3) - beta * np.cos(a4)) / s2
    gamma = col(assembly) * np.sqrt(np.maximum(gamma2, 0.0))
    B = alpha[..., None] * A + beta[..., None] * B0 + gamma[..., None] * w
    t = B - np.sum(B * A, -1, keepdims=True) * A
    t /= np.linalg.norm(t, axis=-1, keepdims=True)
    n = np.cross(A, t)
    arc, ang = col(point_arc)[..., None], col(point_angle)[..., None]
    P = np.cos(arc) * A + np.sin(arc) * (np.cos(ang) * t + np.sin(ang) * n)
    return A, B, P
