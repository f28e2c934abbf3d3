"""Analyses of the spherical four-bar: classification, input and output ranges, transmission and
pressure angles (paper 003, Dzhavakhyan, Makhsudyan, Arakelyan 2011).

Roles of paper 003: α1 crank, α2 coupler, α3 output, α4 frame, i.e. the ``crank``, ``coupler``,
``rocker`` and ``frame`` arcs of :class:`~linkwright.mechanisms.SphericalFourBar`; φ1 is its
input θ (from the frame circle towards B0) and φ3 its
:meth:`~linkwright.mechanisms.SphericalFourBar.output_angle`. The kinematic coefficients Kω, Kε,
Kp, δ are those of :func:`linkwright.analysis.coefficients`, which dispatches here.

Everything rests on one fact: with A0 = (1, 0, 0), the arc d = A B0 obeys

    cos d = cos α1 cos α4 + sin α1 sin α4 cos φ1,

so it is smallest at φ1 = 0 and largest at φ1 = 180°, and the dyad A–B–B0 closes while
|α2 − α3| ≤ d ≤ min(α2 + α3, 2π − α2 − α3) (the triangle inequalities of a spherical
triangle). The transmission angle γ and both components of the pressure angle are functions of
cos d alone, so their extremes, the limit positions and (by the same argument at B0) the output's
range are closed forms. Every function broadcasts over the mechanism's batch shape.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.analysis.extrema import CIRCUIT_SAMPLES, circuit_extremum
from linkwright.engine import InputArcs, Motion
from linkwright.engine.circuits import normalised_arcs
from linkwright.geometry import sphere
from linkwright.mechanisms import SphericalFourBar, circuit, solve

__all__ = [
    "InvalidHingeRatio",
    "NotASphericalFourBar",
    "balanced_mu",
    "grashof_terms",
    "hinge_ratio",
    "input_limits",
    "output_extremes",
    "output_limits",
    "output_rates",
    "paper003_normal_extremes",
    "paper003_tangential_extremes",
    "pressure_angles",
    "pressure_extremes",
    "spherical_class",
    "transmission_angle",
    "transmission_extremes",
]

Array = NDArray[np.float64]
TWO_PI = 2.0 * np.pi
# Arcs whose Grashof terms are within this many radians of 0 count as a change point.
CLASS_TOL = 1e-12


class NotASphericalFourBar(ValueError):
    """A spherical four-bar analysis was given another family."""


class InvalidHingeRatio(ValueError):
    """The hinge-radius ratio μ = OB/OA is not a positive finite number."""


def _check(fb: object) -> SphericalFourBar:
    if not isinstance(fb, SphericalFourBar):
        raise NotASphericalFourBar(
            f"this analysis is for a SphericalFourBar, got {type(fb).__name__}"
        )
    return fb


def _alphas(fb: SphericalFourBar) -> tuple[Array, Array, Array, Array]:
    """(α1 crank, α2 coupler, α3 output, α4 frame) of paper 003, broadcast to the batch."""
    _check(fb)
    return tuple(np.broadcast_arrays(fb.crank, fb.coupler, fb.rocker, fb.frame))  # type: ignore[return-value]


def hinge_ratio(fb: SphericalFourBar, mu: ArrayLike) -> Array:
    value = np.asarray(mu, dtype=float)
    if not np.all(np.isfinite(value) & (value > 0)):
        bad = value[~(np.isfinite(value) & (value > 0))].ravel()[:3].tolist()
        raise InvalidHingeRatio(
            f"mu: the hinge-radius ratio OB/OA must be a positive finite number, got {bad}"
        )
    try:
        return np.broadcast_to(value, np.broadcast_shapes(value.shape, fb.batch_shape))
    except ValueError:
        raise InvalidHingeRatio(
            f"mu: shape {value.shape} does not broadcast with the batch {fb.batch_shape}"
        ) from None


def grashof_terms(fb: SphericalFourBar) -> Array:
    """The four folding terms F1..F4 of each spherical four-bar (radians, last axis).

    With paper 003's α1 crank, α2 coupler, α3 output, α4 frame::

        F1 = α1 + α2 − α3 − α4,  F2 = α1 − α2 + α3 − α4,
        F3 = α1 − α2 − α3 + α4,  F4 = 2π − α1 − α2 − α3 − α4.

    Each vanishes exactly when the four joint axes can lie in one plane (a change point). The
    input turns fully iff |α4 − α1| ≥ |α2 − α3| and |π − α4 − α1| ≥ |π − α2 − α3| (the arc
    A B0 swept by the crank lies inside the arcs the dyad A–B–B0 can span), that is
    F1·F2 ≥ 0 and F3·F4 ≤ 0; the output turns fully iff F2·F3 ≤ 0 and F1·F4 ≥ 0 (the same at
    B0). Of the 16 sign patterns, the eight with F1·F2·F3·F4 < 0 let two joints turn fully
    (Grashof), the other eight none: the spherical Grashof condition. In the plane F4 > 0
    and it reduces to the product form of Grashof's s + l ≤ p + q. Flipping a joint axis
    (an arc replaced by its supplement together with an adjacent one, Chiang's reduction to
    arcs ≤ 90°; C. H. Chiang, *Kinematics of Spherical Mechanisms*, Cambridge 1988)
    permutes the terms up to sign and leaves the product unchanged.

    Examples
    --------
    >>> fb = SphericalFourBar(*np.radians([90, 15, 60, 80]))
    >>> np.degrees(grashof_terms(fb)).round(9)
    array([-95., -55., -35., 115.])
    """
    a1, a2, a3, a4 = _alphas(fb)
    return np.stack(
        (a1 + a2 - a3 - a4, a1 - a2 + a3 - a4, a1 - a2 - a3 + a4, TWO_PI - a1 - a2 - a3 - a4),
        axis=-1,
    )


def _turning(fb: SphericalFourBar) -> tuple[NDArray[np.bool_], NDArray[np.bool_], Array]:
    """(input turns, output turns, Grashof product) from the folding terms."""
    f1, f2, f3, f4 = np.moveaxis(grashof_terms(fb), -1, 0)
    inp = (f1 * f2 >= 0) & (f3 * f4 <= 0)
    out = (f2 * f3 <= 0) & (f1 * f4 >= 0)
    return inp, out, f1 * f2 * f3 * f4


def spherical_class(fb: SphericalFourBar) -> NDArray[np.str_]:
    """Name of each spherical four-bar's type, by the spherical Grashof conditions.

    ``crank-rocker`` (input turns, output rocks), ``double-crank`` (both turn: a drag link),
    ``rocker-crank`` (the output turns, the input rocks), ``double-rocker`` (Grashof, neither
    turns: the coupler turns fully relative to both), ``change-point`` (a folding term is 0,
    see :func:`grashof_terms`) and ``triple-rocker`` (no joint turns fully). Arcs over 90° need
    no special case: the conditions hold for any arcs in (0°, 180°).

    Examples
    --------
    Paper 003's Table 1 crank-rocker and its Table 3 double crank (crank arc 100°):

    >>> arcs = np.radians([[90, 15, 60, 80], [10, 100, 65, 50], [10, 80, 65, 50]])
    >>> spherical_class(SphericalFourBar(*arcs.T))
    array(['crank-rocker', 'double-crank', 'double-crank'], dtype='<U13')

    A linkage with a frame of 90° and links of 10°, 20°, 30° never assembles and turns nothing:

    >>> str(spherical_class(SphericalFourBar(*np.radians([90, 10, 20, 30]))))
    'triple-rocker'
    """
    inp, out, product = _turning(fb)
    folding = np.min(np.abs(grashof_terms(fb)), axis=-1) <= CLASS_TOL
    name = np.where(
        inp,
        np.where(out, "double-crank", "crank-rocker"),
        np.where(out, "rocker-crank", np.where(product < 0, "double-rocker", "triple-rocker")),
    )
    return np.where(folding, "change-point", name)


def _arcs_from(s_hi: Array, c_lo: Array, flip: bool) -> InputArcs:
    """Admissible angles x with sin²(x/2) ≥ s_hi and cos²(x/2) ≥ c_lo, as normalised arcs.

    ``flip`` reports the arcs of π − x instead (the output angle φ3 from the angle at B0).
    """
    never = (s_hi > 1.0) | (c_lo > 1.0) | (s_hi + c_lo > 1.0)
    full = (s_hi <= 0.0) & (c_lo <= 0.0)
    a_in = 2.0 * np.arcsin(np.sqrt(np.clip(s_hi, 0.0, 1.0)))  # |x| ≥ a_in
    a_out = 2.0 * np.arccos(np.sqrt(np.clip(c_lo, 0.0, 1.0)))  # |x| ≤ a_out
    partial = ~(never | full)
    near = partial & (s_hi <= 0.0)  # one arc about x = 0
    far = partial & (c_lo <= 0.0) & ~near  # one arc about x = π
    two = partial & ~near & ~far
    width = np.maximum(a_out - a_in, 0.0)
    lo = np.full(full.shape + (2,), np.nan)
    hi = np.full(full.shape + (2,), np.nan)
    lo[..., 0] = np.where(near, -a_out, np.where(far, a_in, np.where(two, a_in, np.nan)))
    hi[..., 0] = np.where(
        near, a_out, np.where(far, TWO_PI - a_in, np.where(two, a_in + width, np.nan))
    )
    lo[..., 1] = np.where(two, -a_in - width, np.nan)
    hi[..., 1] = np.where(two, -a_in, np.nan)
    if flip:
        lo, hi = np.pi - hi, np.pi - lo
    zero = np.zeros(lo.shape, dtype=np.int64)
    # The engine's own normalisation, so that these arcs compare one-to-one with input_range's.
    return normalised_arcs(full, never, lo, hi, zero, zero)


def input_limits(fb: SphericalFourBar) -> InputArcs:
    """The admissible input arcs and limit positions, in closed form.

    cos d = cos α1 cos α4 + sin α1 sin α4 cos φ1 must lie in [cos(α2 + α3), cos(α2 − α3)], so

        sin²(φ1/2) ≥ −sin(F1/2) sin(F2/2) / (sin α1 sin α4),
        cos²(φ1/2) ≥ sin(F3/2) sin(F4/2) / (sin α1 sin α4),

    with the folding terms of :func:`grashof_terms` (product forms: exact near a limit). The
    result is the engine's :class:`~linkwright.engine.InputArcs`, equal to what
    :func:`linkwright.mechanisms.input_range` finds numerically.

    Examples
    --------
    A double rocker (coupler 10° the shortest) swings its input over two mirror arcs:

    >>> arcs = input_limits(SphericalFourBar(*np.radians([40, 30, 10, 35])))
    >>> bool(arcs.full), np.degrees(arcs.lo).round(4), np.degrees(arcs.hi).round(4)
    (False, array([-82.1866,  40.9089]), array([-40.9089,  82.1866]))

    A linkage that cannot assemble:

    >>> bool(input_limits(SphericalFourBar(*np.radians([90, 10, 20, 30]))).never)
    True
    """
    a1, _, _, a4 = _alphas(fb)
    f1, f2, f3, f4 = np.moveaxis(grashof_terms(fb), -1, 0)
    den = np.sin(a1) * np.sin(a4)
    s_hi = -np.sin(0.5 * f1) * np.sin(0.5 * f2) / den
    c_lo = np.sin(0.5 * f3) * np.sin(0.5 * f4) / den
    return _arcs_from(s_hi, c_lo, flip=False)


def output_limits(fb: SphericalFourBar) -> InputArcs:
    """The output angles φ3 the linkage can reach (either assembly mode), in closed form.

    At B0 the arc A0 B obeys cos A0B = cos α4 cos α3 − sin α4 sin α3 cos φ3 and must lie in
    [cos(α1 + α2), cos(α1 − α2)]: the input's argument with crank and output exchanged. Its
    ends are the output's limit positions, where crank and coupler line up.

    Examples
    --------
    Paper 003's Table 1 first crank-rocker rocks through 30.65° on either side of the frame:

    >>> arcs = output_limits(SphericalFourBar(*np.radians([90, 15, 60, 80])))
    >>> np.degrees(arcs.lo).round(4), np.degrees(arcs.hi).round(4)
    (array([-135.8908,  105.237 ]), array([-105.237 ,  135.8908]))
    """
    _, _, a3, a4 = _alphas(fb)
    f1, f2, f3, f4 = np.moveaxis(grashof_terms(fb), -1, 0)
    den = np.sin(a3) * np.sin(a4)
    # Crank and output exchanged: F1 → −F3, F3 → −F1, F2 and F4 unchanged.
    s_hi = np.sin(0.5 * f3) * np.sin(0.5 * f2) / den
    c_lo = -np.sin(0.5 * f1) * np.sin(0.5 * f4) / den
    return _arcs_from(s_hi, c_lo, flip=True)


def _some_input(arcs: InputArcs) -> Array:
    """An admissible input of each linkage: 0 for a full turn, else its first arc's middle."""
    mid = 0.5 * (arcs.lo[..., 0] + arcs.hi[..., 0])
    return np.where(arcs.full, 0.0, np.where(arcs.never, 0.0, mid))


def _input_at_output(fb: SphericalFourBar, phi3: Array) -> Array:
    """The input φ1 at which the output stands at a limit φ3 (crank and coupler in line)."""
    a1, a2, a3, _ = _alphas(fb)
    params = fb.params()
    a0, b0 = params["A0"], np.broadcast_to(params["B0"], a1.shape + (3,))
    beyond = -sphere.tangent(b0, np.broadcast_to(a0, b0.shape))
    b = sphere.point_at(b0, b0 + beyond, a3, phi3)
    t = sphere.tangent(np.broadcast_to(a0, b.shape), b)
    # A is on the great circle A0–B at arc α1 from A0: on B's side or the other; the right one
    # is at arc α2 from B (the other only where the linkage is degenerate).
    cands = [np.cos(a1)[..., None] * a0 + np.sin(a1)[..., None] * s * t for s in (1.0, -1.0)]
    errs = [np.abs(sphere.arc(c, b) - a2) for c in cands]
    a = np.where((errs[0] <= errs[1])[..., None], cands[0], cands[1])
    return np.arctan2(a[..., 2], a[..., 1])


def output_extremes(
    fb: SphericalFourBar, *, motion: Motion | None = None
) -> dict[str, NDArray[Any]]:
    """Exact extremes of the output φ3 over the circuit and the inputs where they occur.

    The circuit's output sweeps the whole arc of :func:`output_limits` that contains it (its
    turning points are where φ3′ = 0, i.e. crank and coupler in line, which are the arc's ends).
    Returns ``min``, ``max`` (radians; ``max − min`` is the swing Ψ, and ``min`` is in (−π, π])
    and ``min_at``, ``max_at`` (the inputs there), NaN where the output turns fully (``turns``)
    or the linkage never assembles. ``motion`` is any solved motion of the linkage's circuit, to
    pick the arc; by default one admissible input is solved.

    Examples
    --------
    >>> ext = output_extremes(SphericalFourBar(*np.radians([90, 15, 60, 80])))
    >>> [round(float(np.degrees(ext[k])), 4) for k in ("min", "max", "min_at", "max_at")]
    [105.237, 135.8908, 79.6434, -104.2159]
    """
    out = output_limits(fb)
    if motion is None:
        inputs = _some_input(input_limits(fb))
        motion = solve(fb, inputs[..., None], order=0)
    phi = fb.output_angle(motion)
    # The first assembled sample of each linkage says which arc its circuit lies on.
    k = np.argmax(np.isfinite(phi), axis=-1)[..., None]
    here = np.take_along_axis(phi, k, -1)[..., 0]
    lo, hi = out.lo, out.hi
    # A sample may sit at an arc's end (an output limit) up to rounding: allow a hair outside.
    slack = 1e-9
    inside = (np.mod(here[..., None] - lo + slack, TWO_PI) <= hi - lo + 2 * slack) & np.isfinite(lo)
    pick = np.argmax(inside, axis=-1)[..., None]
    start = np.take_along_axis(lo, pick, -1)[..., 0]
    width = np.take_along_axis(hi - lo, pick, -1)[..., 0]
    ok = ~out.full & ~out.never & np.isfinite(here) & np.any(inside, axis=-1)
    nan = np.where(ok, 0.0, np.nan)
    lo_v, hi_v = start + nan, start + width + nan
    return {
        "min": lo_v,
        "max": hi_v,
        "min_at": _input_at_output(fb, np.where(ok, lo_v, 0.0)) + nan,
        "max_at": _input_at_output(fb, np.where(ok, hi_v, 0.0)) + nan,
        "turns": out.full & ~out.never,
    }


def output_rates(fb: SphericalFourBar, motion: Motion) -> tuple[Array, Array]:
    """(φ3′, φ3″): first and second derivative of the output angle by the input, analytically.

    B = cos α3 B0 + sin α3 (cos φ3 t + sin φ3 n) on the output's circle about B0, so
    dB/dφ3 = B0 × B and, dotting B′ and B″ with it (the centripetal part is normal to it),
    φ3′ = (B0 × B)·B′ / sin² α3 and φ3″ = (B0 × B)·B″ / sin² α3.

    Examples
    --------
    >>> fb = SphericalFourBar(*np.radians([90, 15, 60, 80]))
    >>> np.round(output_rates(fb, solve(fb, [0.0, 1.0])), 6)
    array([[-0.267949, -0.110701],
           [ 0.014691,  0.266807]])
    """
    _check(fb)
    if motion.velocities is None or motion.accelerations is None:
        raise ValueError("the motion has no derivatives: solve it with order=2")
    b0, b = motion.positions["B0"], motion.positions["B"]
    w = sphere.cross(np.broadcast_to(b0, b.shape), b)
    s2 = np.sin(np.asarray(fb.rocker, dtype=float))[..., None] ** 2
    return (
        sphere.dot(w, motion.velocities["B"]) / s2,
        sphere.dot(w, motion.accelerations["B"]) / s2,
    )


def transmission_angle(fb: SphericalFourBar, motion: Motion) -> Array:
    """Transmission angle γ at each sample: the angle at B between the great circles B→A and
    B→B0 (radians, in [0, π]; the same in both assembly modes).

    By the spherical law of cosines in triangle A B B0,
    cos d = cos α2 cos α3 + sin α2 sin α3 cos γ.

    Examples
    --------
    >>> fb = SphericalFourBar(*np.radians([90, 15, 60, 80]))
    >>> np.degrees(transmission_angle(fb, solve(fb, [0.0, np.pi]))).round(4)
    array([ 78.3656, 113.9081])
    """
    _check(fb)
    p = motion.positions
    b = p["B"]
    return np.abs(sphere.angle_at(b, p["A"], np.broadcast_to(p["B0"], b.shape)))


def _gamma(num: Array, den: Array) -> Array:
    """γ from tan²(γ/2) = num/den, each given as a product (accurate at 0° and 180°)."""
    return 2.0 * np.arctan2(np.sqrt(np.clip(num, 0.0, None)), np.sqrt(np.clip(den, 0.0, None)))


def transmission_extremes(fb: SphericalFourBar) -> dict[str, Array]:
    """Exact min and max of the transmission angle over the circuit, and the inputs there.

    γ grows with d (tan²(γ/2) = (cos(α2 − α3) − cos d)/(cos d − cos(α2 + α3)), from
    cos d = cos α2 cos α3 + sin α2 sin α3 cos γ), and d is smallest at φ1 = 0 and largest at
    φ1 = 180°, unless a limit position comes first, where γ is 0° or 180°. In product form::

        tan²(γ/2) = sin(F1/2) sin(F2/2)
                    / (sin((α2 + α3 + α4 − α1)/2) sin((α1 + α2 + α3 − α4)/2)),     (φ1 = 0)
        tan²(γ/2) = sin((α1 + α2 − α3 + α4)/2) sin((α1 − α2 + α3 + α4)/2)
                    / (−sin(F3/2) sin(F4/2)),                                      (φ1 = 180°)

    with the folding terms F of :func:`grashof_terms`.

    Returns ``min``, ``max`` (radians) and ``min_at``, ``max_at`` (inputs, radians, in
    [0, π]); NaN where the linkage never assembles.

    Examples
    --------
    >>> tx = transmission_extremes(SphericalFourBar(*np.radians([90, 15, 60, 80])))
    >>> [round(float(np.degrees(tx[k])), 4) for k in ("min", "max", "min_at", "max_at")]
    [78.3656, 113.9081, 0.0, 180.0]
    """
    a1, a2, a3, a4 = _alphas(fb)
    f1, f2, f3, f4 = np.moveaxis(grashof_terms(fb), -1, 0)
    arcs = input_limits(fb)
    span = np.sin(a1) * np.sin(a4)
    # cos(α2 − α3) − cos d and cos d − cos(α2 + α3), at φ1 = 0 and at 180°, as products.
    fold0 = np.sin(0.5 * f1) * np.sin(0.5 * f2)
    open0 = np.sin(0.5 * (a2 + a3 + a4 - a1)) * np.sin(0.5 * (a1 + a2 + a3 - a4))
    fold_pi = np.sin(0.5 * (a1 + a2 - a3 + a4)) * np.sin(0.5 * (a1 - a2 + a3 + a4))
    open_pi = -np.sin(0.5 * f3) * np.sin(0.5 * f4)
    # fold0 ≤ 0: at φ1 = 0 the dyad would fold past its limit (d < |α2 − α3|), which it meets
    # first, with γ = 0; open_pi ≤ 0: at 180° it would stretch too far, and γ = 180° at the
    # limit. The limits are input_limits' ends, the ones in [0, π].
    at_fold = 2.0 * np.arcsin(np.sqrt(np.clip(-fold0 / span, 0.0, 1.0)))
    at_open = 2.0 * np.arccos(np.sqrt(np.clip(-open_pi / span, 0.0, 1.0)))
    out = {
        "min": np.where(fold0 > 0, _gamma(fold0, open0), 0.0),
        "max": np.where(open_pi > 0, _gamma(fold_pi, open_pi), np.pi),
        "min_at": np.where(fold0 > 0, 0.0, at_fold),
        "max_at": np.where(open_pi > 0, np.pi, at_open),
    }
    return {k: np.where(arcs.never, np.nan, v) for k, v in out.items()}


def pressure_angles(fb: SphericalFourBar, motion: Motion, mu: ArrayLike) -> dict[str, Array]:
    """Paper 003's pressure angle, normal and tangential components, at each sample (radians).

    The coupler's hinge centres sit at OA = 1 along axis A and OB = μ along axis B; the force on
    the output acts along the chord from A to μB, unit vector f. Its normal component is the
    part along the output axis, sin ν_n = f·B0. The tangential component is the angle, in the
    plane normal to B0, between the projected force and the line of B's velocity (B0 × B): with
    r the unit radial direction towards B in that plane, ν_τ = atan2(f·r, |f·(B0 × r)|), in
    [−90°, 90°], positive when the force leans away from the axis B0. In the plane
    (μ → ∞ aside) ν_τ plays the part of 90° − γ. The signs agree with paper 003's Table 2.

    Examples
    --------
    Paper 003's Table 2, first row, at φ1 = 0 and 180° (the normal component's extremes):

    >>> fb = SphericalFourBar(*np.radians([90, 15, 60, 80]))
    >>> nu = pressure_angles(fb, solve(fb, [0.0, np.pi]), mu=0.517)
    >>> np.degrees(nu["normal"]).round(2), np.degrees(nu["tangential"]).round(2)
    (array([-11.25,  23.73]), array([ 3.18, -3.2 ]))
    """
    m = hinge_ratio(fb, mu)[..., None]
    p = motion.positions
    a, b = p["A"], p["B"]
    b0 = np.broadcast_to(p["B0"], b.shape)
    f = sphere.unit(m[..., None] * b - a)
    radial = sphere.unit(b - sphere.dot(b, b0)[..., None] * b0)
    along = sphere.cross(b0, radial)
    normal = np.arcsin(np.clip(sphere.dot(f, b0), -1.0, 1.0))
    tangential = np.arctan2(sphere.dot(f, radial), np.abs(sphere.dot(f, along)))
    return {"normal": normal, "tangential": tangential}


def pressure_extremes(
    fb: SphericalFourBar, mu: ArrayLike, *, motion: Motion | None = None
) -> dict[str, Array]:
    """Exact extremes of both pressure-angle components over the circuit (radians).

    Bracketed on the circuit and refined by golden section
    (:func:`~linkwright.analysis.extrema.circuit_extremum`); the closed forms of paper 003
    (:func:`paper003_normal_extremes`, :func:`paper003_tangential_extremes`) check them in the
    tests. Returns ``normal_min``, ``normal_max``, ``tangential_min``, ``tangential_max`` and
    the inputs where they occur (``*_at``); NaN where the linkage never assembles.

    Examples
    --------
    Paper 003's Table 2, first row (printed: 23.73, −11.25, 3.18, −3.19):

    >>> ext = pressure_extremes(SphericalFourBar(*np.radians([90, 15, 60, 80])), mu=0.517)
    >>> [round(float(np.degrees(ext[k])), 3)
    ...  for k in ("normal_max", "normal_min", "tangential_max", "tangential_min")]
    [23.731, -11.254, 3.176, -3.196]
    """
    hinge_ratio(fb, mu)
    if motion is None:
        motion = circuit(fb, CIRCUIT_SAMPLES)
    out: dict[str, Array] = {}
    for part in ("normal", "tangential"):

        def q(m: Motion, part: str = part) -> Array:
            return pressure_angles(fb, m, mu)[part]

        for key, sign in (("min", -1.0), ("max", 1.0)):
            value, at, _ = circuit_extremum(fb, q, sign=sign, motion=motion)
            out[f"{part}_{key}"] = value
            out[f"{part}_{key}_at"] = at
    return out


def _full_only(fb: SphericalFourBar, values: dict[str, Array]) -> dict[str, Array]:
    full = input_limits(fb).full
    return {k: np.where(full, v, np.nan) for k, v in values.items()}


def paper003_normal_extremes(fb: SphericalFourBar, mu: ArrayLike) -> dict[str, Array]:
    """Paper 003's closed form for the normal component's extremes (its first formula).

    sin ν_n = f·B0 = (μ cos α3 − cos d)/√(1 + μ² − 2μ cos α2): the denominator |μB − A| is
    constant on the coupler, and cos d = cos(α4 ∓ α1) at φ1 = 0 and 180°, so::

        sin ν_n1,2 = (μ cos α3 − cos α1 cos α4 ± sin α1 sin α4) / √(1 + μ² − 2μ cos α2).

    For linkages whose input turns fully (NaN otherwise). Returns ``max`` (at φ1 = 180°) and
    ``min`` (at φ1 = 0), radians.

    Examples
    --------
    >>> nu = paper003_normal_extremes(SphericalFourBar(*np.radians([90, 15, 60, 80])), 0.517)
    >>> round(float(np.degrees(nu["max"])), 3), round(float(np.degrees(nu["min"])), 3)
    (23.731, -11.254)
    """
    a1, a2, a3, a4 = _alphas(fb)
    m = hinge_ratio(fb, mu)
    chord = np.sqrt(1.0 + m * m - 2.0 * m * np.cos(a2))
    base = m * np.cos(a3) - np.cos(a1) * np.cos(a4)
    swing = np.sin(a1) * np.sin(a4)
    return _full_only(
        fb,
        {
            "max": np.arcsin(np.clip((base + swing) / chord, -1.0, 1.0)),
            "min": np.arcsin(np.clip((base - swing) / chord, -1.0, 1.0)),
        },
    )


def paper003_tangential_extremes(fb: SphericalFourBar, mu: ArrayLike) -> dict[str, Array]:
    """Paper 003's eqs. (1) and (2) for the tangential component's extremes.

    Eq. (1), with the square that the print lost (SEED-NOTES), at φ1 = 0 and 180°::

        sin ν_τ1,2 = (μ sin² α3 − cos α2 + cos α3 cos(α4 ∓ α1))
                     / (sin α3 √(1 + μ² − 2μ cos α2 − [μ cos α3 − cos(α4 ∓ α1)]²)).

    Eq. (2), in lengths scaled by the crank radius sin α1 (so AA4 = 1, A4 the centre of A's
    circle): R = μ sin α3/sin α1, λ = √(1 + μ² − 2μ cos α2)/sin α1, d1 = cot α1 and
    d3 = μ cos α3/sin α1 (the distances of the two circles' centres from O; the print leaves
    them undefined), d4 = d1² + d3² − 2 d1 d3 cos α4, a = R² + λ² − 1 − d4, b = 2 d3 sin α4,
    m = d3 − d1 cos α4, n = sin α4, k1 = −n(mb + an), k3 = (λ² − m²) b − amn::

        sin ν_τ3,4 = (a + b k3/k1) / (2R √(λ² − (m − n k3/k1)²)),

    at the interior stationary input cos φ1 = k3/k1, which exists iff |k3| ≤ |k1| (the print's
    "k3 ± k1 ≥ 0" is a misprint; its f(φ1) = (k1 cos φ1 + k3) sin φ1 also has the sign of k3
    flipped: dν_τ/dφ1 ∝ (k1 cos φ1 − k3) sin φ1). For linkages whose input turns fully.

    Returns ``at_0``, ``at_180`` (eq. 1), ``interior`` (eq. 2, NaN where |k3| > |k1|),
    ``interior_at`` (φ1 in [0, π]), ``k1``, ``k3`` and ``min``, ``max`` over all of them
    (radians).

    Examples
    --------
    Paper 003's Table 2, first row: only the two extremes of eq. (1) (printed 3.18, −3.19):

    >>> fb = SphericalFourBar(*np.radians([90, 15, 60, 80]))
    >>> nu = paper003_tangential_extremes(fb, 0.517)
    >>> [round(float(np.degrees(nu[k])), 3) for k in ("at_0", "at_180", "interior")]
    [3.176, -3.196, nan]

    With μ = 2 eq. (2) adds a minimum near φ1 = 90°:

    >>> nu = paper003_tangential_extremes(fb, 2.0)
    >>> [round(float(np.degrees(nu[k])), 4) for k in ("at_0", "at_180", "interior", "interior_at")]
    [60.6353, 60.794, 59.4884, 90.0]
    """
    a1, a2, a3, a4 = _alphas(fb)
    m_ = hinge_ratio(fb, mu)
    chord2 = 1.0 + m_ * m_ - 2.0 * m_ * np.cos(a2)

    def eq1(cos_d: Array) -> Array:
        # sin ν = num/den taken as atan2(num, √(den² − num²)): the same angle, and no division
        # where the force runs along the output axis (den = 0, ν_τ = 0 as in pressure_angles).
        num = m_ * np.sin(a3) ** 2 - np.cos(a2) + np.cos(a3) * cos_d
        den2 = np.sin(a3) ** 2 * (chord2 - (m_ * np.cos(a3) - cos_d) ** 2)
        nu: Array = np.arctan2(num, np.sqrt(np.clip(den2 - num**2, 0.0, None)))
        return nu

    s1 = np.sin(a1)
    R = m_ * np.sin(a3) / s1
    lam2 = chord2 / s1**2
    d1 = np.cos(a1) / s1
    d3 = m_ * np.cos(a3) / s1
    d4 = d1**2 + d3**2 - 2.0 * d1 * d3 * np.cos(a4)
    a = R**2 + lam2 - 1.0 - d4
    b = 2.0 * d3 * np.sin(a4)
    m = d3 - d1 * np.cos(a4)
    n = np.sin(a4)
    k1 = -n * (m * b + a * n)
    k3 = (lam2 - m**2) * b - a * m * n
    exists = np.abs(k3) <= np.abs(k1)
    with np.errstate(divide="ignore", invalid="ignore"):
        c = np.where(exists, k3 / k1, np.nan)
        interior = np.arcsin(
            np.clip((a + b * c) / (2.0 * R * np.sqrt(lam2 - (m - n * c) ** 2)), -1.0, 1.0)
        )
    at_0, at_180 = eq1(np.cos(a4 - a1)), eq1(np.cos(a4 + a1))
    every = np.stack((at_0, at_180, np.where(exists, interior, at_0)), axis=-1)
    return _full_only(
        fb,
        {
            "at_0": at_0,
            "at_180": at_180,
            "interior": interior,
            "interior_at": np.arccos(np.clip(c, -1.0, 1.0)),
            "k1": k1,
            "k3": k3,
            "min": every.min(axis=-1),
            "max": every.max(axis=-1),
        },
    )


def balanced_mu(fb: SphericalFourBar) -> Array:
    """Paper 003's hinge-radius ratio μ = OB/OA for the best force flow.

    The smaller positive root of p2 μ² + p1 μ + p4 = 0, the condition
    min ν_τ + max ν_τ = 0 (Reinsberg's balance, for a linkage whose ν_τ has only the two
    extremes at φ1 = 0 and 180°)::

        p2 = sin² α3 (cos α1 cos α4 − cos α2 cos α3),
        p1 = cos α3 (cos² α1 + cos² α2 − cos² α3 + cos² α4) − 2 cos α1 cos α2 cos α4,
        p4 = (cos α1 cos α3 − cos α2 cos α4)(cos α3 cos α4 − cos α1 cos α2).

    NaN where the quadratic has no positive real root.

    Examples
    --------
    Paper 003's Table 2 (printed μ = 0.517, 0.354, 0.179):

    >>> arcs = np.radians([[90, 15, 60, 80], [90, 15, 70, 80], [90, 15, 80, 80]])
    >>> balanced_mu(SphericalFourBar(*arcs.T)).round(5)
    array([0.51714, 0.35356, 0.17946])
    """
    a1, a2, a3, a4 = _alphas(fb)
    c1, c2, c3, c4 = np.cos(a1), np.cos(a2), np.cos(a3), np.cos(a4)
    p2 = np.sin(a3) ** 2 * (c1 * c4 - c2 * c3)
    p1 = c3 * (c1**2 + c2**2 - c3**2 + c4**2) - 2.0 * c1 * c2 * c4
    p4 = (c1 * c3 - c2 * c4) * (c3 * c4 - c1 * c2)
    disc = p1 * p1 - 4.0 * p2 * p4
    root = np.sqrt(np.clip(disc, 0.0, None))
    # The two roots without cancellation: q = −(p1 + sign(p1)√disc)/2, μ = q/p2 and p4/q.
    q = -0.5 * (p1 + np.where(p1 >= 0, 1.0, -1.0) * root)
    with np.errstate(divide="ignore", invalid="ignore"):
        r1 = np.where(p2 != 0, q / p2, np.nan)
        r2 = np.where(q != 0, p4 / q, np.nan)
    roots = np.stack((r1, r2), axis=-1)
    roots = np.where((roots > 0) & np.isfinite(roots) & (disc >= 0)[..., None], roots, np.inf)
    best = roots.min(axis=-1)
    return np.where(np.isfinite(best), best, np.nan)
