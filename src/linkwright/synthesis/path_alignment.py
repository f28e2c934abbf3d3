"""Rigid and similar alignments of a sampled curve to target points.

The seeds of :class:`~linkwright.synthesis.path_models.GenericModel` place a member's curve
onto the targets: in the plane the least-squares similarity z ↦ w·z + t of paired points
(:func:`paired_fit`) or, by iterated closest points (P. J. Besl & N. D. McKay, *IEEE Trans.
Pattern Anal. Mach. Intell.* 14, 1992), of each target's nearest curve point
(:func:`nearest_fit`); on the sphere the same with Kabsch's least-squares rotation (W. Kabsch,
*Acta Cryst.* A32, 1976) in place of the similarity (:func:`paired_turn`,
:func:`nearest_turn`). :func:`rotation_pose`
writes a rotation as the pose a spherical model carries.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from linkwright.geometry import sphere

__all__ = [
    "axis_rotation",
    "diameter",
    "nearest_fit",
    "nearest_turn",
    "paired_fit",
    "paired_turn",
    "rotation_pose",
    "turning_rotation",
]

Array = NDArray[np.float64]


def diameter(pts: Array) -> float:
    diff = pts[:, None, :] - pts[None, :, :]
    return float(np.sqrt(np.max(np.sum(diff * diff, axis=-1))))


def paired_fit(points: Array, targets: Array) -> tuple[complex, complex, float]:
    """The least-squares similarity z ↦ w·z + t (complex) of ``points`` onto ``targets``, pair
    by pair, and its residual (in the points' units)."""
    a = points[:, 0] + 1j * points[:, 1]
    b = targets[:, 0] + 1j * targets[:, 1]
    da, db = a - a.mean(), b - b.mean()
    energy = float(np.sum(np.abs(da) ** 2))
    w = complex(np.sum(np.conj(da) * db) / energy) if energy > 0 else 1.0 + 0j
    t = b.mean() - w * a.mean()
    return w, t, float(np.sum(np.abs(w * a + t - b) ** 2) / max(abs(w), 1e-300) ** 2)


def paired_turn(points: Array, targets: Array) -> tuple[Array, float]:
    """The rotation (Kabsch) of ``points`` onto ``targets``, pair by pair, and its residual."""
    R = sphere.best_rotation(points.T @ targets)[1]
    return R, float(np.sum((points @ R.T - targets) ** 2))


def nearest_fit(
    curve: Array, targets: Array, w: complex, rounds: int = 12
) -> tuple[complex, complex, float]:
    """Iterated closest points: the similarity z ↦ w·z + t (complex) that lays the sampled
    curve over the targets, each target matched to its nearest curve point, from ``w``."""
    a = curve[:, 0] + 1j * curve[:, 1]
    b = targets[:, 0] + 1j * targets[:, 1]
    t = b.mean() - w * a.mean()
    for _ in range(rounds):
        near = a[np.argmin(np.abs((w * a + t)[None, :] - b[:, None]), axis=1)]
        da, db = near - near.mean(), b - b.mean()
        energy = float(np.sum(np.abs(da) ** 2))
        if energy <= 0:
            break
        w = complex(np.sum(np.conj(da) * db) / energy)
        t = b.mean() - w * near.mean()
    miss = np.min(np.abs((w * a + t)[None, :] - b[:, None]), axis=1)
    return w, t, float(np.sum(miss**2) / max(abs(w), 1e-300) ** 2)


def nearest_turn(curve: Array, targets: Array, R: Array, rounds: int = 12) -> tuple[Array, float]:
    """The same on the sphere: the rotation (Kabsch) laying the curve over the targets."""
    for _ in range(rounds):
        moved = curve @ R.T
        near = curve[np.argmin(np.sum((moved[None] - targets[:, None]) ** 2, axis=-1), axis=1)]
        R = sphere.best_rotation(near.T @ targets)[1]
    moved = curve @ R.T
    return R, float(np.sum(np.min(np.sum((moved[None] - targets[:, None]) ** 2, axis=-1), axis=1)))


def axis_rotation(axis: Array, angle: float) -> Array:
    """The rotation by ``angle`` about the unit vector ``axis``."""
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    turned: Array = np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * (k @ k)
    return turned


def turning_rotation(a: Array, b: Array) -> Array:
    """The least rotation carrying the unit vector a onto b."""
    axis = np.cross(a, b)
    s = float(np.linalg.norm(axis))
    if s < 1e-12:
        if float(np.dot(a, b)) > 0:
            return np.eye(3)
        other = np.eye(3)[int(np.argmin(np.abs(a)))]
        return axis_rotation(sphere.unit(np.cross(a, other)), np.pi)
    return axis_rotation(axis / s, float(np.arctan2(s, np.dot(a, b))))


def rotation_pose(R: Array) -> Array:
    """(lon, sinlat, spin) of a rotation, as :func:`~linkwright.synthesis.path_families.
    sphere_rotation` builds it from them."""
    a0, t = R[:, 0], R[:, 1]
    lon = float(np.arctan2(a0[1], a0[0]))
    east = np.array([-np.sin(lon), np.cos(lon), 0.0])
    north = np.cross(a0, east)
    return np.array([lon, float(np.clip(a0[2], -1.0, 1.0)), float(np.arctan2(t @ north, t @ east))])
