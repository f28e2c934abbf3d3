"""The families :func:`linkwright.synthesis.path.fit_path` can synthesise, as search models.

Each model splits a linkage into a *pose* (where it stands in the user's frame) and a *shape*
(everything else), so that a whole population is evaluated as one batched mechanism standing
in a local frame and then carried to the user's frame:

- planar: the local frame puts the crank pivot A0 at the origin and the frame line (A0→B0, or
  the slider's guide) along +x; the pose is (x, y, frame_angle), the place of A0 and the
  direction of the frame line. The input measured from the frame line is then the same number
  in both frames, and the user's absolute input is that plus ``frame_angle``.
- sphere: the local frame is paper 000's (A0 = (1, 0, 0), B0 on the frame circle in OXY); the
  pose is a rotation R, user point = R · local point. The input is measured from the frame
  circle in both frames (paper 000's θ2).

A model also states its Grashof-type constraints as inequalities g ≤ 0 on the shape
(:meth:`Model.closed_form_gaps`, :func:`path_margin`), so that the search can penalise a
violation smoothly. This module is the support of :mod:`linkwright.synthesis.path`; its users
call :func:`~linkwright.synthesis.path.fit_path`.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.mechanisms import (
    DyadJoint,
    FixedJoint,
    FourBar,
    GearedFiveBar,
    Linkage,
    Mechanism,
    SliderCrank,
    SphereCrankJoint,
    SphereRigidJoint,
    SphericalFourBar,
)

__all__ = [
    "FOURBAR_CLASSES",
    "MODELS",
    "SIGN_PATTERNS",
    "SLIDER_CLASSES",
    "Model",
    "path_margin",
    "pattern_gap",
    "rodrigues",
    "sampled_gaps",
    "sphere_rotation",
    "to_user",
]

Array = NDArray[np.float64]
TWO_PI = 2.0 * np.pi

# The classes of paper 003 / analysis.fourbar_class, as patterns of the signs of the four
# folding terms (analysis.spherical.grashof_terms; in the plane the fourth term is positive).
FOURBAR_CLASSES = ("crank-rocker", "double-crank", "rocker-crank", "double-rocker", "triple-rocker")
SLIDER_CLASSES = ("crank-slider", "rocker-slider")


def _class_of_signs(s: tuple[int, ...]) -> str:
    """analysis.spherical.spherical_class's rule, applied to a sign pattern of F1..F4."""
    f1, f2, f3, f4 = s
    inp = f1 * f2 > 0 and f3 * f4 < 0
    out = f2 * f3 < 0 and f1 * f4 > 0
    if inp:
        return "double-crank" if out else "crank-rocker"
    if out:
        return "rocker-crank"
    return "double-rocker" if f1 * f2 * f3 * f4 < 0 else "triple-rocker"


SIGN_PATTERNS: dict[str, Array] = {
    name: np.array(
        [s for s in itertools.product((1, -1), repeat=4) if _class_of_signs(s) == name], float
    )
    for name in FOURBAR_CLASSES
}
"""Class name → the sign patterns (rows of ±1 for F1..F4) that make it."""


def pattern_gap(F: Array, patterns: Array) -> Array:
    """How far the folding terms F (..., 4) are from having one of the sign patterns.

    max_i(−σ_i F_i) is ≤ 0 exactly when F has the signs σ; the least over the patterns is
    ≤ 0 exactly when F has one of them. It is piecewise linear in F, so a search can follow it.

    Examples
    --------
    Paper 003's crank-rocker (folding terms −95°, −55°, −35°, 115°) is one with 35° to spare
    (F3 is the term nearest to changing sign); a double crank needs the signs (+, +, −, +), so
    F1 would have to grow by 95°:

    >>> F = np.radians([-95.0, -55.0, -35.0, 115.0])
    >>> [round(float(np.degrees(pattern_gap(F, SIGN_PATTERNS[c]))), 9)
    ...  for c in ("crank-rocker", "double-crank")]
    [-35.0, 95.0]
    """
    gap: Array = np.min(np.max(-patterns * F[..., None, :], axis=-1), axis=-1)
    return gap


@dataclass(frozen=True)
class Model:
    """One family's search model (see the module docstring)."""

    family: str
    space: str
    shape_names: tuple[str, ...]
    lengths: tuple[str, ...]
    """Shape parameters that the ``"length"`` bound covers (link lengths, or arcs)."""
    periodic: frozenset[str]
    classes: tuple[str, ...]

    @property
    def dim(self) -> int:
        return 2 if self.space == "plane" else 3

    @property
    def pose_names(self) -> tuple[str, ...]:
        return ("x", "y", "frame_angle") if self.space == "plane" else ("lon", "sinlat", "spin")

    @property
    def linear(self) -> tuple[str, ...]:
        """Shape parameters in the targets' units (they scale with them): plane only."""
        return (*self.lengths, "u", "v", "offset") if self.space == "plane" else ()

    @property
    def traced(self) -> str:
        return "P"

    def input_offset(self, pose: Any) -> float:
        """How far the user frame's input is from the local frame's: the frame's angle."""
        return 0.0 if self.space == "sphere" else float(pose[2])

    def default_bounds(self, size: float, centre: Array) -> dict[str, tuple[float, float]]:
        """Bounds of every parameter for targets of diameter ``size`` around ``centre``."""
        if self.space == "plane":
            out = {
                "x": (centre[0] - 3 * size, centre[0] + 3 * size),
                "y": (centre[1] - 3 * size, centre[1] + 3 * size),
                "frame_angle": (-np.pi, np.pi),
            }
            for n in self.lengths:
                out[n] = (0.02 * size, 5.0 * size)
            for n in ("u", "v"):
                out[n] = (-5.0 * size, 5.0 * size)
            if self.family == "slidercrank":
                out["offset"] = (-3.0 * size, 3.0 * size)
            if self.family == "geared-fivebar":
                out["gear_phase"] = (-np.pi, np.pi)
                out["ratio"] = (-1.0, -1.0)
            return out
        arc = (np.radians(2.0), np.radians(178.0))
        out = {"lon": (-np.pi, np.pi), "sinlat": (-1.0, 1.0), "spin": (-np.pi, np.pi)}
        out.update({n: arc for n in self.lengths})
        out["point_arc"] = (0.0, np.pi)
        out["point_angle"] = (-np.pi, np.pi)
        return out

    # ---------------------------------------------------------------------------------------
    # Mechanisms
    # ---------------------------------------------------------------------------------------

    def local(self, shape: Mapping[str, Array | float], assembly: Array | float) -> Mechanism:
        """The batched mechanism standing in the local frame (see the module docstring)."""
        s = shape
        if self.family == "fourbar":
            zero = np.zeros_like(s["frame"])
            return FourBar(
                A0=np.zeros(2),
                B0=np.stack((s["frame"], zero), axis=-1),
                crank=s["crank"],
                coupler=s["coupler"],
                rocker=s["rocker"],
                u=s["u"],
                v=s["v"],
                assembly=assembly,
            )
        if self.family == "slidercrank":
            # Guide along +x through (0, −e): A0 = (0, 0) sits at the signed offset e.
            zero = np.zeros_like(s["offset"])
            return SliderCrank(
                A0=np.zeros(2),
                crank=s["crank"],
                rod=s["rod"],
                line_point=np.stack((zero, -s["offset"]), axis=-1),
                line_angle=0.0,
                u=s["u"],
                v=s["v"],
                assembly=assembly,
            )
        if self.family == "geared-fivebar":
            zero = np.zeros_like(s["frame"])
            return GearedFiveBar(
                A0=np.zeros(2),
                B0=np.stack((s["frame"], zero), axis=-1),
                crank1=s["crank1"],
                crank2=s["crank2"],
                link1=s["link1"],
                link2=s["link2"],
                phase1=0.0,
                phase2=s["gear_phase"],
                ratio=s["ratio"],
                u=s["u"],
                v=s["v"],
                assembly=assembly,
            )
        return SphericalFourBar(
            frame=s["frame"],
            crank=s["crank"],
            coupler=s["coupler"],
            rocker=s["rocker"],
            point_arc=s["point_arc"],
            point_angle=s["point_angle"],
            assembly=assembly,
        )

    def placed(
        self, shape: Mapping[str, float], assembly: float, pose: Any
    ) -> tuple[Mechanism, Mechanism, Array | None]:
        """(mechanism in the user's frame, the named family's mechanism, rotation or None).

        Planar: both are the same mechanism, placed by ``pose`` = (x, y, frame_angle). Sphere:
        the named one is the :class:`SphericalFourBar` in paper 000's frame and the user's one a
        spherical :class:`Linkage` with every ground axis rotated by ``pose`` (a 3×3 matrix).
        """
        s = {k: float(v) for k, v in shape.items()}
        if self.space == "sphere":
            R = np.asarray(pose, dtype=float)
            named = self.local(s, np.float64(assembly))
            a1 = s["frame"]
            linkage = Linkage(
                joints=(
                    FixedJoint("A0", at=R[:, 0].copy()),
                    FixedJoint("B0", at=R @ np.array([np.cos(a1), np.sin(a1), 0.0])),
                    SphereCrankJoint("A", pivot="A0", arc=s["crank"], toward="B0"),
                    DyadJoint(
                        "B", p1="A", r1=s["coupler"], p2="B0", r2=s["rocker"], assembly=assembly
                    ),
                    SphereRigidJoint(
                        "P", origin="A", toward="B", arc=s["point_arc"], angle=s["point_angle"]
                    ),
                ),
                traced=("P",),
                space="sphere",
            )
            return linkage, named, R
        x, y, psi = (float(p) for p in pose)
        o = np.array([x, y])
        e = np.array([np.cos(psi), np.sin(psi)])
        n = np.array([-e[1], e[0]])
        if self.family == "fourbar":
            m: Mechanism = FourBar(
                A0=o,
                B0=o + s["frame"] * e,
                crank=s["crank"],
                coupler=s["coupler"],
                rocker=s["rocker"],
                u=s["u"],
                v=s["v"],
                assembly=assembly,
            )
        elif self.family == "slidercrank":
            m = SliderCrank(
                A0=o,
                crank=s["crank"],
                rod=s["rod"],
                line_point=o - s["offset"] * n,
                line_angle=psi,
                u=s["u"],
                v=s["v"],
                assembly=assembly,
            )
        else:
            m = GearedFiveBar(
                A0=o,
                B0=o + s["frame"] * e,
                crank1=s["crank1"],
                crank2=s["crank2"],
                link1=s["link1"],
                link2=s["link2"],
                phase1=psi,
                phase2=psi + s["gear_phase"],
                ratio=s["ratio"],
                u=s["u"],
                v=s["v"],
                assembly=assembly,
            )
        return m, m, None

    # ---------------------------------------------------------------------------------------
    # Constraints as g ≤ 0
    # ---------------------------------------------------------------------------------------

    def folding_terms(self, shape: Mapping[str, Array]) -> Array:
        """F1..F4 of :func:`linkwright.analysis.spherical.grashof_terms` (planar: over the
        longest link, with F4 = 1, since in the plane the fourth term is always positive)."""
        a1, a2, a3, a4 = (shape[k] for k in ("crank", "coupler", "rocker", "frame"))
        f = [a1 + a2 - a3 - a4, a1 - a2 + a3 - a4, a1 - a2 - a3 + a4]
        if self.space == "sphere":
            return np.stack(f + [TWO_PI - a1 - a2 - a3 - a4], axis=-1)
        longest = np.maximum(np.maximum(a1, a2), np.maximum(a3, a4))
        f = [x / longest for x in f]
        return np.stack(f + [np.ones_like(a1)], axis=-1)

    def closed_form_gaps(
        self, shape: Mapping[str, Array], classes: tuple[str, ...], full_turn: bool, mu: float
    ) -> list[Array]:
        """The constraint functions that have closed forms (each ≤ 0 when satisfied).

        ``mu`` is the least transmission angle (0: none). Transmission over the whole turn
        needs the input to turn fully; the geared five-bar's constraints are sampled instead
        (:func:`sampled_gaps`).
        """
        gaps: list[Array] = []
        if self.family == "geared-fivebar":
            return gaps
        if self.family == "slidercrank":
            r, l, e = shape["crank"], shape["rod"], shape["offset"]
            # The crank turns fully iff r + |e| < l; |e| as max(e, −e) keeps g piecewise linear.
            turns = (np.maximum(r + e, r - e) - l) / l
            if classes:
                each = {"crank-slider": turns, "rocker-slider": -turns}
                gaps.append(np.min(np.stack([each[c] for c in classes]), axis=0))
            if full_turn or mu > 0:
                gaps.append(turns)
            if mu > 0:
                # cos γ = q/l with q = e + r sin(θ − line angle) in [e − r, e + r].
                gaps.append(np.maximum(r + e, r - e) / l - np.cos(mu))
            return gaps
        F = self.folding_terms(shape)
        if classes:
            patterns = np.concatenate([SIGN_PATTERNS[c] for c in classes])
            gaps.append(pattern_gap(F, patterns))
        if full_turn or mu > 0:
            turning = np.concatenate([SIGN_PATTERNS["crank-rocker"], SIGN_PATTERNS["double-crank"]])
            gaps.append(pattern_gap(F, turning))
        if mu > 0:
            a1, a2, a3, a4 = (shape[k] for k in ("crank", "coupler", "rocker", "frame"))
            # The transmission angle γ grows with d = |A B0|, least at input 0 (d = |L4 − L1|),
            # greatest at 180° (d = L4 + L1), when the crank turns fully (paper 003).
            if self.space == "plane":
                den = 2.0 * a2 * a3
                c_lo = (a2**2 + a3**2 - (a4 - a1) ** 2) / den
                c_hi = (a2**2 + a3**2 - (a4 + a1) ** 2) / den
            else:
                den = np.sin(a2) * np.sin(a3)
                c_lo = (np.cos(a4 - a1) - np.cos(a2) * np.cos(a3)) / den
                c_hi = (np.cos(a4 + a1) - np.cos(a2) * np.cos(a3)) / den
            gaps.append(c_lo - np.cos(mu))
            gaps.append(-c_hi - np.cos(mu))
        return gaps


def _extremes(f: str, lo: Array, hi: Array) -> tuple[Array, Array]:
    """Least and greatest of cos (f = "cos") or sin over each input interval [lo, hi]."""
    shift = 0.0 if f == "cos" else np.pi / 2  # sin x = cos(x − π/2)
    a, b = lo - shift, hi - shift
    ca, cb = np.cos(a), np.cos(b)
    # cos reaches 1 at multiples of 2π and −1 at odd multiples of π inside the interval.
    top = np.floor(b / TWO_PI) * TWO_PI >= a
    bottom = np.floor((b - np.pi) / TWO_PI) * TWO_PI + np.pi >= a
    return np.where(bottom, -1.0, np.minimum(ca, cb)), np.where(top, 1.0, np.maximum(ca, cb))


def path_margin(
    model: Model, shape: Mapping[str, Array], lo: ArrayLike, hi: ArrayLike
) -> Array | None:
    """The least closure margin of the dyad while the input sweeps [lo, hi] (from the frame
    line), exactly; negative where the linkage meets a limit position on the way. None for the
    geared five-bar, whose dyad has no such closed form (its path is sampled instead).

    The dyad closes while the distance d between its pivots lies in its range: in the plane
    d² ∈ [(r1 − r2)², (r1 + r2)²], on the sphere cos d ∈ [cos(r1 + r2), cos(r1 − r2)], for the
    slider the crank pin's distance q from the guide in [−rod, rod]. d² (or cos d) is affine in
    the cosine of the input, q in its sine, so the margin, the least of two affine functions,
    is least at an extreme of that cosine (sine) over the interval.

    Examples
    --------
    A four-bar with frame 3, crank 1, coupler 1.5 and rocker 2 closes while its pivots A, B0
    are 0.5 to 3.5 apart, and d² = 10 − 6 cos θ: it reaches its limit at cos θ = −0.375
    (θ = 112.02°). Sweeping the input from 0 to 100°, 120° and 200°, the least margins are
    (12.25 − d²)/12.25 at the far end, then past the limit, then at 180° (d² = 16):

    >>> shape = {"frame": 3.0, "crank": 1.0, "coupler": 1.5, "rocker": 2.0}
    >>> path_margin(MODELS["fourbar"], shape, 0.0, np.radians([100.0, 120.0, 200.0])).round(6)
    array([ 0.098621, -0.061224, -0.306122])

    The engine agrees on either side of the limit:

    >>> from linkwright.mechanisms import FourBar, solve
    >>> fb = FourBar(A0=[0, 0], B0=[3, 0], crank=1, coupler=1.5, rocker=2)
    >>> solve(fb, np.radians([112.0, 112.1])).valid
    array([ True, False])
    """
    if model.family == "geared-fivebar":
        return None
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    if model.family == "slidercrank":
        r, l, e = shape["crank"], shape["rod"], shape["offset"]
        s_lo, s_hi, _ = np.broadcast_arrays(*_extremes("sin", lo, hi), r)
        q = np.stack((e + r * s_lo, e + r * s_hi))
        least: Array = np.min(1.0 - (q / l) ** 2, axis=0)
        return least
    a1, a2, a3, a4 = (shape[k] for k in ("crank", "coupler", "rocker", "frame"))
    c = np.stack(np.broadcast_arrays(*_extremes("cos", lo, hi), a1)[:2])
    if model.space == "plane":
        d2 = a1**2 + a4**2 - 2.0 * a1 * a4 * c
        m = np.minimum((a2 + a3) ** 2 - d2, d2 - (a2 - a3) ** 2) / (a2 + a3) ** 2
    else:
        cos_d = np.cos(a1) * np.cos(a4) + np.sin(a1) * np.sin(a4) * c
        m = np.minimum(np.cos(a2 - a3) - cos_d, cos_d - np.cos(a2 + a3))
    margin: Array = np.min(m, axis=0)
    return margin


MODELS: dict[str, Model] = {
    "fourbar": Model(
        "fourbar",
        "plane",
        ("frame", "crank", "coupler", "rocker", "u", "v"),
        ("frame", "crank", "coupler", "rocker"),
        frozenset(),
        FOURBAR_CLASSES,
    ),
    "slidercrank": Model(
        "slidercrank",
        "plane",
        ("offset", "crank", "rod", "u", "v"),
        ("crank", "rod"),
        frozenset(),
        SLIDER_CLASSES,
    ),
    "geared-fivebar": Model(
        "geared-fivebar",
        "plane",
        ("frame", "crank1", "crank2", "link1", "link2", "gear_phase", "ratio", "u", "v"),
        ("frame", "crank1", "crank2", "link1", "link2"),
        frozenset({"gear_phase"}),
        (),
    ),
    "spherical-fourbar": Model(
        "spherical-fourbar",
        "sphere",
        ("frame", "crank", "coupler", "rocker", "point_arc", "point_angle"),
        ("frame", "crank", "coupler", "rocker"),
        frozenset({"point_angle"}),
        FOURBAR_CLASSES,
    ),
}


def sampled_gaps(
    positions: Mapping[str, Array], margins: Mapping[str, Array], full_turn: bool, mu: float
) -> list[Array]:
    """The geared five-bar's constraints from a sampled turn (positions and margins of C).

    Its dyad A–C–B closes while the margin (sin² of the angle at A) is ≥ 0, and at its limits
    C lies on the line AB, where the transmission angle at C is 0° or 180°: a least
    transmission angle therefore also asks for a full turn.
    """
    gaps: list[Array] = []
    if full_turn or mu > 0:
        gaps.append(-np.min(margins["C"], axis=-1))
    if mu > 0:
        a = positions["A"] - positions["C"]
        b = positions["B"] - positions["C"]
        cos_g = np.sum(a * b, axis=-1) / np.sqrt(np.sum(a * a, -1) * np.sum(b * b, -1))
        worst = np.max(np.where(np.isfinite(cos_g), np.abs(cos_g), -1.0), axis=-1)
        gaps.append(worst - np.cos(mu))
    return gaps


# ------------------------------------------------------------------------------------------
# Poses
# ------------------------------------------------------------------------------------------


def sphere_rotation(lon: Array, sinlat: Array, spin: Array) -> Array:
    """Rotations (..., 3, 3) whose first column is the axis at (lon, asin sinlat) and whose
    second is the tangent there turned by ``spin`` from east towards north."""
    cl = np.sqrt(np.clip(1.0 - sinlat**2, 0.0, None))
    a0 = np.stack((cl * np.cos(lon), cl * np.sin(lon), sinlat), axis=-1)
    east = np.stack((-np.sin(lon), np.cos(lon), np.zeros_like(lon)), axis=-1)
    north = np.cross(a0, east)
    t = np.cos(spin)[..., None] * east + np.sin(spin)[..., None] * north
    return np.stack((a0, t, np.cross(a0, t)), axis=-1)


def rodrigues(w: Array) -> Array:
    """Rotation matrices (..., 3, 3) of rotation vectors w (..., 3)."""
    theta = np.sqrt(np.sum(w * w, axis=-1))[..., None, None]
    K = np.zeros(w.shape[:-1] + (3, 3))
    K[..., 0, 1], K[..., 0, 2], K[..., 1, 2] = -w[..., 2], w[..., 1], -w[..., 0]
    K[..., 1, 0], K[..., 2, 0], K[..., 2, 1] = w[..., 2], -w[..., 1], w[..., 0]
    small = theta < 1e-8
    safe = np.where(small, 1.0, theta)
    a = np.where(small, 1.0 - theta**2 / 6.0, np.sin(safe) / safe)
    b = np.where(small, 0.5 - theta**2 / 24.0, (1.0 - np.cos(safe)) / safe**2)
    rotation: Array = np.eye(3) + a * K + b * (K @ K)
    return rotation


def to_user(space: str, local: Array, pose: Array) -> Array:
    """Carry local positions (B, K, d) to the user's frame by poses (B, 3) or (B, 3, 3)."""
    if space == "sphere":
        turned: Array = np.einsum("bij,bkj->bki", pose, local)
        return turned
    c, s = np.cos(pose[:, 2])[:, None], np.sin(pose[:, 2])[:, None]
    x, y = local[..., 0], local[..., 1]
    return np.stack((pose[:, :1] + c * x - s * y, pose[:, 1:2] + s * x + c * y), axis=-1)
