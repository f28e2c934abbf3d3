"""The sphere nearest to measured points: where spherical targets come from in practice.

A designer's spherical path is measured, not drawn on the unit sphere: a wing-flap tip, say, a
few centimetres from its hinge. :func:`fit_sphere` finds the sphere's centre and radius, so
that the points become directions about the centre (the unit vectors a spherical linkage's
joints are) and the answer can be said in the points' own units.

The fit is the algebraic one, linear in the centre c and in k = r² − |c|²
(|p|² = 2 c·p + k for every point p on the sphere; Pratt, "Direct least-squares fitting of
algebraic surfaces", SIGGRAPH 1987), refined by least squares in the geometric distance
|p − c| − r. Points in one plane fix no sphere, and are refused.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["FittedSphere", "SphereFitError", "fit_sphere"]

Array = NDArray[np.float64]

FLAT = 1e-9
"""Below this relative spread out of their best plane, points fix no sphere."""


class SphereFitError(ValueError):
    """The points fix no sphere (too few, not finite, or all in one plane)."""


class FittedSphere(NamedTuple):
    """A fitted sphere: ``centre`` (3,), ``radius``, the ``rms`` distance of the points from
    it, and the points as ``directions`` (N, 3) unit vectors from the centre."""

    centre: Array
    radius: float
    rms: float
    directions: Array


def fit_sphere(points: ArrayLike) -> FittedSphere:
    """The sphere nearest to (N, 3) points, N ≥ 4, in least squares.

    Parameters
    ----------
    points : (N, 3) the points.

    Returns
    -------
    FittedSphere

    Raises
    ------
    SphereFitError
        For fewer than four points, points that are not finite, or points in one plane (a
        plane is a sphere of infinite radius: no centre).

    Examples
    --------
    Five points of the sphere of radius 2 about (1, 0, 0):

    >>> s = fit_sphere([[3, 0, 0], [1, 2, 0], [1, 0, 2], [-1, 0, 0], [1, -2, 0]])
    >>> s.centre.round(12) + 0.0, round(s.radius, 12), s.rms < 1e-12
    (array([1., 0., 0.]), 2.0, True)
    >>> s.directions[0].round(12) + 0.0
    array([1., 0., 0.])

    Points in one plane are refused:

    >>> fit_sphere([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    Traceback (most recent call last):
    ...
    linkwright.geometry.sphere_fit.SphereFitError: the points lie in one plane: they fix no \
sphere (a plane is a sphere of infinite radius)
    """
    from scipy.optimize import least_squares

    try:
        p = np.array(points, dtype=float)
    except (TypeError, ValueError):
        raise SphereFitError("the points must be numbers") from None
    if p.ndim != 2 or p.shape[1] != 3:
        raise SphereFitError(f"the points must be (N, 3) rows, got shape {p.shape}")
    if len(p) < 4:
        raise SphereFitError(f"a sphere needs at least 4 points, got {len(p)}")
    if not np.all(np.isfinite(p)):
        raise SphereFitError("the points must be finite")
    # Work about the points' mean and in units of their spread, for the conditioning.
    mean = p.mean(axis=0)
    spread = float(np.max(np.linalg.norm(p - mean, axis=1)))
    if spread == 0:
        raise SphereFitError("the points all coincide: they fix no sphere")
    q = (p - mean) / spread
    if np.linalg.svd(q, compute_uv=False)[-1] <= FLAT * np.sqrt(len(q)):
        raise SphereFitError(
            "the points lie in one plane: they fix no sphere (a plane is a sphere of infinite "
            "radius)"
        )
    rows = np.c_[2.0 * q, np.ones(len(q))]
    (cx, cy, cz, k), *_ = np.linalg.lstsq(rows, np.sum(q * q, axis=1), rcond=None)
    c0 = np.array([cx, cy, cz])
    r0 = float(np.sqrt(max(k + c0 @ c0, 1e-300)))

    def off(x: Array) -> Array:
        return np.asarray(np.linalg.norm(q - x[:3], axis=1) - x[3])

    best = least_squares(off, np.r_[c0, r0], method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15)
    centre = mean + spread * best.x[:3]
    radius = float(spread * abs(best.x[3]))
    away = p - centre
    distance = np.linalg.norm(away, axis=1)
    if np.any(distance == 0):
        raise SphereFitError("a point lies at the fitted centre: it has no direction")
    rms = float(np.sqrt(np.mean((distance - radius) ** 2)))
    return FittedSphere(centre, radius, rms, away / distance[:, None])
