"""What an atlas holds for each family: the design distribution it samples, the filter that keeps
only linkages whose input turns fully, and the curve each one traces.

Every atlas mechanism stands in its family's *local frame*, the one
:mod:`linkwright.synthesis.path_families` searches in: planar linkages have the crank pivot A0 at
the origin and the frame line A0→B0 along +x with length 1 (curves are matched up to a
similarity, so the frame's length is the unit); spherical four-bars stand in paper 000's frame.
A stored row is the family's shape parameters (:data:`PARAMS`) then the assembly sign.

Design distributions (``log-uniform`` on [a, b] means exp of a uniform on [ln a, ln b]):

===================  ===========================================================================
family               parameters
===================  ===========================================================================
fourbar              frame 1; crank, coupler, rocker log-uniform on [0.2, 5]; coupler point
                     u = coupler·U(−1, 2), v = coupler·U(−1.5, 1.5); assembly ±1 (½ each)
geared-fivebar       frame 1; crank1, crank2 log-uniform on [0.1, 2]; link1, link2 log-uniform
                     on [0.3, 5]; gear ratio one of −2, −1, 1, 2 (¼ each); gear phase
                     U(−π, π); u = link1·U(−1, 2), v = link1·U(−1.5, 1.5); assembly ±1
spherical-fourbar    frame, crank, coupler, rocker U(10°, 170°); point arc U(0°, 90°); point
                     angle U(−180°, 180°); assembly ±1
===================  ===========================================================================

Kept are the linkages whose input turns fully with the dyad clear of its limit positions all
the way round: the closure margin of :func:`~linkwright.synthesis.path_families.path_margin`
(four-bars; exact over the whole turn), or the same margin of the geared five-bar's dyad
sampled at 256 inputs, at least :data:`MARGIN`. One turn of the input then traces the whole
coupler curve, a closed curve (the five-bar's gear ratios are whole numbers, so it closes after
one turn too).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import NDArray

from linkwright.curves import (
    descriptor_variants,
    descriptors,
    sphere_descriptor_variants,
    sphere_descriptors,
)
from linkwright.engine import kernels
from linkwright.mechanisms import solve
from linkwright.synthesis.path_families import MODELS, path_margin

__all__ = [
    "FAMILIES",
    "MARGIN",
    "PARAMS",
    "AtlasFamilyError",
    "curves",
    "describe",
    "describe_variants",
    "sample",
]

Array = NDArray[np.float64]

FAMILIES = ("fourbar", "geared-fivebar", "spherical-fourbar")
PARAMS: dict[str, tuple[str, ...]] = {f: MODELS[f].shape_names + ("assembly",) for f in FAMILIES}
MARGIN = 0.01
"""Least closure margin kept (a fraction of the dyad's range; see the module docstring)."""

_GEAR_RATIOS = np.array([-2.0, -1.0, 1.0, 2.0])
_CHECK_SAMPLES = 256


class AtlasFamilyError(ValueError):
    """An unknown family, or parameters that do not belong to it."""


def _family(family: str) -> str:
    if family not in FAMILIES:
        raise AtlasFamilyError(f"family: must be one of {', '.join(FAMILIES)}, got {family!r}")
    return family


def _log_uniform(rng: np.random.Generator, lo: float, hi: float, n: int) -> Array:
    return np.exp(rng.uniform(np.log(lo), np.log(hi), n))


def _draw(family: str, rng: np.random.Generator, n: int) -> dict[str, Array]:
    """n designs from the family's distribution (the module docstring's table), unfiltered."""
    sign = np.where(rng.random(n) < 0.5, -1.0, 1.0)
    if family == "fourbar":
        crank, coupler, rocker = (_log_uniform(rng, 0.2, 5.0, n) for _ in range(3))
        return {
            "frame": np.ones(n),
            "crank": crank,
            "coupler": coupler,
            "rocker": rocker,
            "u": coupler * rng.uniform(-1.0, 2.0, n),
            "v": coupler * rng.uniform(-1.5, 1.5, n),
            "assembly": sign,
        }
    if family == "geared-fivebar":
        crank1, crank2 = (_log_uniform(rng, 0.1, 2.0, n) for _ in range(2))
        link1, link2 = (_log_uniform(rng, 0.3, 5.0, n) for _ in range(2))
        return {
            "frame": np.ones(n),
            "crank1": crank1,
            "crank2": crank2,
            "link1": link1,
            "link2": link2,
            "gear_phase": rng.uniform(-np.pi, np.pi, n),
            "ratio": _GEAR_RATIOS[rng.integers(0, _GEAR_RATIOS.size, n)],
            "u": link1 * rng.uniform(-1.0, 2.0, n),
            "v": link1 * rng.uniform(-1.5, 1.5, n),
            "assembly": sign,
        }
    lo, hi = np.radians(10.0), np.radians(170.0)
    return {
        "frame": rng.uniform(lo, hi, n),
        "crank": rng.uniform(lo, hi, n),
        "coupler": rng.uniform(lo, hi, n),
        "rocker": rng.uniform(lo, hi, n),
        "point_arc": rng.uniform(0.0, np.pi / 2, n),
        "point_angle": rng.uniform(-np.pi, np.pi, n),
        "assembly": sign,
    }


def _fivebar_margin(shape: Mapping[str, Array], samples: int = _CHECK_SAMPLES) -> Array:
    """The geared five-bar's least closure margin over a turn, sampled: the dyad A–C–B closes
    while d = |AB| lies in [|link1 − link2|, link1 + link2]; the margin is path_margin's planar
    one, min((l1 + l2)² − d², d² − (l1 − l2)²)/(l1 + l2)²."""
    theta = np.linspace(0.0, 2.0 * np.pi, samples, endpoint=False)
    c = {k: np.asarray(shape[k])[:, None] for k in shape}
    phi = c["gear_phase"] + c["ratio"] * theta
    dx = c["frame"] + c["crank2"] * np.cos(phi) - c["crank1"] * np.cos(theta)
    dy = c["crank2"] * np.sin(phi) - c["crank1"] * np.sin(theta)
    d2 = dx * dx + dy * dy
    lo, hi = (c["link1"] - c["link2"]) ** 2, (c["link1"] + c["link2"]) ** 2
    return np.min(np.minimum(hi - d2, d2 - lo), axis=-1) / hi[:, 0]


def _turns_fully(family: str, shape: Mapping[str, Array]) -> NDArray[np.bool_]:
    margin = path_margin(MODELS[family], shape, 0.0, 2.0 * np.pi)
    if margin is not None:
        return margin >= MARGIN
    # Most draws fail already at one of 16 inputs: only the rest are checked at 256.
    ok = _fivebar_margin(shape, 16) >= MARGIN
    ok[ok] = _fivebar_margin({k: v[ok] for k, v in shape.items()}) >= MARGIN
    return ok


def sample(family: str, rng: np.random.Generator, count: int) -> dict[str, Array]:
    """``count`` designs of ``family`` from its distribution, keeping only those whose input
    turns fully (module docstring). Draws rounds of ``count`` candidates until enough are kept,
    so the result depends on ``rng``'s state alone.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> designs = sample("fourbar", rng, 1000)
    >>> sorted(designs) == sorted(PARAMS["fourbar"]), designs["crank"].shape
    (True, (1000,))

    Each one's crank turns fully: Grashof's condition, with the crank or the frame shortest.

    >>> lengths = np.stack([designs[k] for k in ("frame", "crank", "coupler", "rocker")])
    >>> s, l = lengths.min(0), lengths.max(0)
    >>> bool(np.all(s + l <= lengths.sum(0) - s - l))
    True
    >>> bool(np.all((designs["crank"] == s) | (designs["frame"] == s)))
    True
    """
    _family(family)
    if count < 0:
        raise AtlasFamilyError(f"count: must not be negative, got {count}")
    kept: list[dict[str, Array]] = []
    total = 0
    while total < count:
        draw = _draw(family, rng, max(count, 1))
        ok = _turns_fully(family, draw)
        kept.append({k: v[ok] for k, v in draw.items()})
        total += int(ok.sum())
    out = {k: np.concatenate([d[k] for d in kept])[:count] for k in PARAMS[family]}
    return out


def curves(family: str, params: Mapping[str, Array], samples: int) -> Array:
    """The coupler curves (n, samples, 2), or unit vectors (n, samples, 3) on the sphere, of
    the designs ``params`` in the local frame, at ``samples`` inputs equally spaced over one
    turn from the frame line. NaN where a design does not assemble.

    Examples
    --------
    The four-bar with frame 1, crank 0.5, coupler 1.2, rocker 1 and P at the coupler's B end
    traces B, 1 from B0 = (1, 0):

    >>> one = {"frame": [1.0], "crank": [0.5], "coupler": [1.2], "rocker": [1.0],
    ...        "u": [1.2], "v": [0.0], "assembly": [1.0]}
    >>> P = curves("fourbar", one, 8)
    >>> np.hypot(P[0, :, 0] - 1, P[0, :, 1]).round(12)
    array([1., 1., 1., 1., 1., 1., 1., 1.])
    """
    _family(family)
    p = {k: np.atleast_1d(np.asarray(params[k], dtype=float)) for k in PARAMS[family]}
    theta = np.linspace(0.0, 2.0 * np.pi, samples, endpoint=False)
    n = p["assembly"].shape[0]
    if family == "fourbar" and kernels.available():
        a0 = np.zeros((n, 2))
        b0 = np.stack([p["frame"], np.zeros(n)], axis=-1)
        args = (p["crank"], p["coupler"], p["rocker"], p["u"], p["v"], p["assembly"])
        return kernels.fourbar_coupler_points(a0, b0, *args, theta)
    if family == "spherical-fourbar" and kernels.available():
        names = ("frame", "crank", "coupler", "rocker", "point_arc", "point_angle", "assembly")
        return kernels.spherical_fourbar_coupler_points(*(p[k] for k in names), theta)
    mech = MODELS[family].local(p, p["assembly"])
    return solve(mech, theta, order=0).positions["P"]


def describe(family: str, points: Array, harmonics: int) -> Array:
    """Descriptors of closed curves traced by ``family`` (planar or spherical)."""
    if MODELS[_family(family)].space == "sphere":
        return sphere_descriptors(points, harmonics=harmonics)
    return descriptors(points, harmonics=harmonics)


def describe_variants(family: str, points: Array, harmonics: int) -> Array:
    """Every descriptor variant (…, V, D) of closed curves, for queries."""
    if MODELS[_family(family)].space == "sphere":
        return sphere_descriptor_variants(points, harmonics=harmonics)
    return descriptor_variants(points, harmonics=harmonics)
