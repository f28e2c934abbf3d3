"""Analyses of the planar four-bar and slider-crank (and, by dispatch, the spherical four-bar).

Conventions of paper 003 (Dzhavakhyan, Makhsudyan, Arakelyan): L1 crank, L2 coupler, L3 output,
L4 frame; φ1 and φ3 are measured from the frame line A0→B0; φ3′ = dφ3/dφ1, φ3″ = d²φ3/dφ1².

Every extreme reported here is exact: closed forms where geometry gives them (transmission angle,
stroke, Grashof limits), otherwise a dense circuit bracket refined by golden section
(:mod:`linkwright.analysis.extrema`). All functions broadcast over a mechanism's batch shape.

A :class:`~linkwright.mechanisms.SphericalFourBar` given to :func:`fourbar_class`,
:func:`transmission_angle`, :func:`transmission_extremes`, :func:`output_angle`,
:func:`output_rates`, :func:`output_extremes` or :func:`coefficients` is handed to
:mod:`linkwright.analysis.spherical`, so paper 003's coefficients are computed by one code for
both spaces.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from linkwright.analysis import spherical as _sph
from linkwright.analysis.extrema import CIRCUIT_SAMPLES, circuit_extremum
from linkwright.engine import Motion, evaluate
from linkwright.geometry import plane
from linkwright.mechanisms import FourBar, SliderCrank, SphericalFourBar, circuit, input_range
from linkwright.mechanisms.base import Mechanism

__all__ = [
    "FOURBAR_CLASSES",
    "coefficients",
    "fourbar_class",
    "grashof",
    "output_angle",
    "output_extremes",
    "output_rates",
    "slidercrank_class",
    "stroke",
    "transmission_angle",
    "transmission_extremes",
]

Array = NDArray[np.float64]
TWO_PI = 2.0 * np.pi
# Lengths equal to this relative tolerance count as equal when classifying (s + l = p + q).
CLASS_TOL = 1e-12


def _slider(mechanism: Mechanism) -> SliderCrank:
    """The slider-crank a planar analysis is left with once four-bars are handled."""
    if not isinstance(mechanism, SliderCrank):
        raise TypeError(
            f"{type(mechanism).__name__}: this analysis is for four-bars and slider-cranks"
        )
    return mechanism


# Every name fourbar_class can give, planar and spherical.
FOURBAR_CLASSES = (
    "change-point",
    "crank-rocker",
    "double-crank",
    "double-rocker",
    "rocker-crank",
    "triple-rocker",
)


def _lengths(fb: FourBar) -> tuple[Array, Array, Array, Array]:
    """(L1 crank, L2 coupler, L3 rocker, L4 frame) broadcast to the batch shape."""
    return tuple(np.broadcast_arrays(fb.crank, fb.coupler, fb.rocker, fb.frame))  # type: ignore[return-value]


def grashof(fb: FourBar) -> Array:
    """Grashof's sum ``s + l − p − q`` relative to the longest link: < 0 Grashof, 0 change point.

    >>> float(grashof(FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5)))
    -0.3
    """
    links = np.stack(_lengths(fb), axis=-1)
    s, l = links.min(axis=-1), links.max(axis=-1)
    excess: Array = (2.0 * (s + l) - links.sum(axis=-1)) / l
    return excess


def fourbar_class(fb: FourBar | SphericalFourBar) -> NDArray[np.str_]:
    """Name of each four-bar's type, from Grashof's condition and which link is shortest.

    Grashof (s + l < p + q): shortest crank → ``crank-rocker``; shortest frame → ``double-crank``
    (drag link); shortest coupler → ``double-rocker``; shortest output → ``rocker-crank``.
    s + l = p + q: ``change-point``. Otherwise ``triple-rocker`` (no link turns fully).

    >>> str(fourbar_class(FourBar(A0=[0, 0], B0=[1, 0], crank=4, coupler=2, rocker=13**0.5)))
    'double-crank'
    >>> str(fourbar_class(FourBar(A0=[0, 0], B0=[4, 0], crank=3, coupler=2, rocker=2.5)))
    'triple-rocker'

    A spherical four-bar is classified by the spherical conditions
    (:func:`linkwright.analysis.spherical.spherical_class`).
    """
    if isinstance(fb, SphericalFourBar):
        return _sph.spherical_class(fb)
    g = grashof(fb)
    links = np.stack(_lengths(fb), axis=-1)
    shortest = np.argmin(links, axis=-1)
    grashof_names = np.array(["crank-rocker", "double-rocker", "rocker-crank", "double-crank"])
    out = np.where(
        np.abs(g) <= CLASS_TOL,
        "change-point",
        np.where(g < 0, grashof_names[shortest], "triple-rocker"),
    )
    return out


def slidercrank_class(sc: SliderCrank) -> NDArray[np.str_]:
    """``crank-slider`` when the crank turns fully (crank + |offset| < rod), ``change-point`` at
    equality, else ``rocker-slider``.

    >>> str(slidercrank_class(SliderCrank(A0=[0, 0], crank=1, rod=3)))
    'crank-slider'
    """
    slack = (np.asarray(sc.rod) - np.asarray(sc.crank) - np.abs(sc.offset)) / np.asarray(sc.rod)
    return np.where(
        np.abs(slack) <= CLASS_TOL,
        "change-point",
        np.where(slack > 0, "crank-slider", "rocker-slider"),
    )


def transmission_angle(mechanism: Mechanism, motion: Motion) -> Array:
    """Transmission angle γ at each sample (radians, in [0, π]; 90° transmits best).

    Four-bar: the interior angle at B between B→A and B→B0 (the same in both assembly modes).
    Slider-crank: the angle between the rod B→A and the normal of the slider's line (the line's
    direction turned +90°); its pressure angle 90° − γ keeps the side the rod leans to.
    Spherical four-bar: the angle at B between the great circles B→A and B→B0.
    """
    if isinstance(mechanism, SphericalFourBar):
        return _sph.transmission_angle(mechanism, motion)
    A, B = motion.positions["A"], motion.positions["B"]
    u = A - B
    if isinstance(mechanism, FourBar):
        w = motion.positions["B0"] - B
    else:
        w = np.broadcast_to(plane.perp(_slider(mechanism).direction)[..., None, :], u.shape)
    gamma: Array = np.arctan2(np.abs(plane.cross(u, w)), plane.dot(u, w))
    return gamma


def transmission_extremes(mechanism: Mechanism) -> dict[str, Array]:
    """Exact min and max of the transmission angle over the circuit, and the inputs there.

    Four-bar: γ grows with d = |A B0|, whose reachable range is
    [max(|L4 − L1|, |L2 − L3|), min(L4 + L1, L2 + L3)]; the ends are reached at φ1 = 0 or 180°
    (paper 003's formulas) or at a limit position where γ is 0 or 180°.
    Slider-crank: γ = acos(q/rod), q the signed distance of A from the line.

    Returns ``min``, ``max`` (radians) and ``min_at``, ``max_at`` (input angles, radians; for a
    linkage that reaches the extreme at two symmetric inputs, the one in [0, π]).
    Spherical four-bar: :func:`linkwright.analysis.spherical.transmission_extremes`.
    """
    if isinstance(mechanism, SphericalFourBar):
        return _sph.transmission_extremes(mechanism)
    arcs = input_range(mechanism)
    if isinstance(mechanism, FourBar):
        L1, L2, L3, L4 = _lengths(mechanism)
        d_lo = np.maximum(np.abs(L4 - L1), np.abs(L2 - L3))
        d_hi = np.minimum(L4 + L1, L2 + L3)

        def gamma(d: Array) -> Array:
            # Half-angle law of cosines: arccos of (L2² + L3² − d²)/(2 L2 L3) loses half the
            # digits near 0° and 180°, exactly where limit positions put γ.
            diff = np.abs(L2 - L3)
            near = np.clip((d - diff) * (d + diff), 0.0, None)
            far = np.clip((L2 + L3 - d) * (L2 + L3 + d), 0.0, None)
            return 2.0 * np.arctan2(np.sqrt(near), np.sqrt(far))

        def input_at(d: Array) -> Array:
            # |A − B0|² = L1² + L4² − 2 L1 L4 cos φ1
            c = np.clip((L1**2 + L4**2 - d**2) / (2 * L1 * L4), -1.0, 1.0)
            return np.arccos(c) + mechanism.frame_angle

        out = {
            "min": gamma(d_lo),
            "max": gamma(d_hi),
            "min_at": input_at(d_lo),
            "max_at": input_at(d_hi),
        }
    else:
        # cos γ = q/rod, q = e + crank·sin(θ − line angle) the signed distance of A from the line,
        # limited to [−rod, rod] where the input cannot turn fully.
        sc = _slider(mechanism)
        rod, crank, e = np.broadcast_arrays(sc.rod, sc.crank, sc.offset)
        q_hi = np.minimum(e + crank, rod)
        q_lo = np.maximum(e - crank, -rod)
        ang = np.asarray(sc.line_angle)

        def gam(q: Array) -> Array:
            # acos(q/rod) without the cancellation of acos near ±1.
            angle: Array = np.arctan2(np.sqrt(np.clip((rod - q) * (rod + q), 0.0, None)), q)
            return angle

        def input_at_offset(q: Array) -> Array:
            theta: Array = np.arcsin(np.clip((q - e) / crank, -1.0, 1.0)) + ang
            return theta

        out = {
            "min": gam(q_hi),
            "max": gam(q_lo),
            "min_at": input_at_offset(q_hi),
            "max_at": input_at_offset(q_lo),
        }
    never = arcs.never
    return {k: np.where(never, np.nan, v) for k, v in out.items()}


def output_angle(fb: FourBar | SphericalFourBar, motion: Motion) -> Array:
    """φ3: the angle of B − B0 measured from the frame line A0→B0 (radians, in (−π, π]).

    Spherical four-bar: the angle of B about +OB0 from the frame circle beyond B0
    (:meth:`~linkwright.mechanisms.SphericalFourBar.output_angle`).
    """
    if isinstance(fb, SphericalFourBar):
        return fb.output_angle(motion)
    rel = motion.positions["B"] - motion.positions["B0"]
    ang = np.arctan2(rel[..., 1], rel[..., 0]) - fb.frame_angle[..., None]
    phi: Array = np.angle(np.exp(1j * ang))
    return phi


def output_rates(mechanism: Mechanism, motion: Motion) -> tuple[Array, Array]:
    """(first, second) derivative of the output with respect to the input, analytically.

    Four-bar: φ3′, φ3″ from B's velocity and acceleration: for a point on a circle about B0,
    (B − B0) × B′ = φ3′ r² and (B − B0) × B″ = φ3″ r². Slider-crank: s′, s″ of the slider
    position along its line. Spherical four-bar: φ3′, φ3″ from
    :func:`linkwright.analysis.spherical.output_rates`.
    """
    if isinstance(mechanism, SphericalFourBar):
        return _sph.output_rates(mechanism, motion)
    vel, acc = motion.velocities["B"], motion.accelerations["B"]  # type: ignore[index]
    if isinstance(mechanism, FourBar):
        rel = motion.positions["B"] - motion.positions["B0"]
        r2 = np.asarray(mechanism.rocker)[..., None] ** 2
        return plane.cross(rel, vel) / r2, plane.cross(rel, acc) / r2
    d = _slider(mechanism).direction[..., None, :]
    return plane.dot(vel, d), plane.dot(acc, d)


def output_extremes(
    mechanism: Mechanism, *, motion: Motion | None = None
) -> dict[str, NDArray[Any]]:
    """Exact extremes of the output over the circuit and the inputs where they occur.

    Returns ``min``, ``max``, ``min_at``, ``max_at`` (radians, or lengths for a slider) and
    ``turns`` (True where a four-bar's output turns fully, so it has no extremes). ``motion`` is
    the mechanism's circuit (order 2, :data:`CIRCUIT_SAMPLES`) when the caller already has it.
    A spherical four-bar's extremes are closed forms
    (:func:`linkwright.analysis.spherical.output_extremes`).
    """
    if isinstance(mechanism, SphericalFourBar):
        return _sph.output_extremes(mechanism, motion=motion)
    if motion is None:
        motion = circuit(mechanism, CIRCUIT_SAMPLES)
    shape = motion.shape[:-1]
    turns = np.zeros(shape, dtype=bool)
    mid = np.zeros(shape)
    if isinstance(mechanism, FourBar):
        # The output turns fully when its angle, unwrapped along the circuit, gains 2π.
        phi = np.unwrap(output_angle(mechanism, motion), axis=-1)
        turns = np.abs(phi[..., -1] - phi[..., 0] + (phi[..., 1] - phi[..., 0])) > np.pi
        # A rocking output may straddle φ3 = ±π where the wrapped angle jumps: measure it about
        # its own middle instead.
        finite = np.isfinite(phi)
        count = np.maximum(finite.sum(axis=-1), 1)
        mid = np.angle(np.exp(1j * np.where(finite, phi, 0.0).sum(axis=-1) / count))

    def out(m: Motion) -> Array:
        if isinstance(mechanism, FourBar):
            turned: Array = np.angle(np.exp(1j * (output_angle(mechanism, m) - mid[..., None])))
            return turned
        return _slider(mechanism).slider_position(m)

    lo, lo_at, lo_branch = circuit_extremum(mechanism, out, sign=-1.0, motion=motion)
    hi, hi_at, hi_branch = circuit_extremum(mechanism, out, sign=1.0, motion=motion)
    lo, lo_at = _polish_stationary(mechanism, out, lo, lo_at, lo_branch)
    hi, hi_at = _polish_stationary(mechanism, out, hi, hi_at, hi_branch)
    nan = np.where(turns, np.nan, 0.0)
    lo, hi, lo_at, hi_at = lo + mid + nan, hi + mid + nan, lo_at + nan, hi_at + nan
    return {"min": lo, "max": hi, "min_at": lo_at, "max_at": hi_at, "turns": turns}


def _polish_stationary(
    mechanism: Mechanism,
    out: Callable[[Motion], Array],
    value: Array,
    at: Array,
    branch: Array,
    steps: int = 4,
) -> tuple[Array, Array]:
    """Newton on output′ = 0 with the analytic output″, from a golden-section estimate.

    A maximum's *value* is exact after golden section, but its *location* only to √eps (the
    function is flat there); the crank rotation φΨ and the time ratio need the location, so it is
    polished as the root of the first derivative. Extremes that sit at a limit position (not
    stationary) are left alone: there the Newton step is not small.
    """
    plan, params, points = mechanism.plan, mechanism.params(), mechanism.points
    dyad = plan.dyads[0].name
    finite = np.isfinite(at)
    x = np.where(finite, at, 0.0)
    b = np.where(finite, branch, 1.0)
    for _ in range(steps):
        m = evaluate(plan, params, x[..., None], points=points, branches={dyad: b[..., None]})
        r1, r2 = (r[..., 0] for r in output_rates(mechanism, m))
        with np.errstate(divide="ignore", invalid="ignore"):
            step = r1 / r2
        x = np.where(finite & np.isfinite(step) & (np.abs(step) < 1e-3), x - step, x)
    m = evaluate(plan, params, x[..., None], points=points, branches={dyad: b[..., None]})
    polished = out(m)[..., 0]
    # Keep the polish only where it did not lose (a saddle or a limit position).
    better = (
        finite & np.isfinite(polished) & (np.abs(polished - value) < 1e-9 * (1 + np.abs(value)))
    )
    return np.where(better, polished, value), np.where(better, x, at)


def stroke(sc: SliderCrank) -> Array:
    """Slider stroke (exact), the distance between the slider's two extreme positions."""
    ext = output_extremes(sc)
    travel: Array = ext["max"] - ext["min"]
    return travel


def _crank_rotation_between(t_a: Array, t_b: Array, through: Array) -> Array:
    """Length of the arc from t_a to t_b (either way round) that contains ``through``."""
    ccw = np.mod(t_b - t_a, TWO_PI)
    inside = np.mod(through - t_a, TWO_PI) < ccw
    return np.where(inside, ccw, TWO_PI - ccw)


def coefficients(
    mechanism: Mechanism, *, extremes: dict[str, NDArray[Any]] | None = None
) -> dict[str, Array]:
    """Paper 003's kinematic coefficients, as exact maxima over the cycle.

    Crank-rocker (input turns, output rocks through Ψ, the crank turning φΨ between the output's
    extremes on the arc that contains φ1 = 0)::

        Kω = max|φ3′|·φΨ/Ψ,  Kε = max|φ3″|·φΨ²/Ψ,  Kp = max|φ3′·φ3″|·φΨ³/Ψ²

    Double crank (both turn): Kω = max |φ3′|, Kε = 2π·max |φ3″|, Kp = 2π·max |φ3′·φ3″|,
    δ = max φ3′ − min φ3′ (paper 003 eqs. 3–4 and the text after eq. 7). A slider-crank whose
    crank turns gets the crank-rocker formulas with the stroke in place of Ψ (Levitskii's cam
    coefficients, which these generalise). Where the input cannot turn fully, all are NaN.

    Returns ``K_omega``, ``K_epsilon``, ``K_p``, ``delta`` and ``phi_psi``, ``psi`` (radians or
    length), ``time_ratio`` (≥ 1, NaN for a double crank). ``extremes`` is
    :func:`output_extremes` of the mechanism when the caller already has it.

    A spherical four-bar gets the same formulas, φ1 its input and φ3 its output angle (the crank
    rotation φΨ on the arc containing φ1 = 0, which is the frame circle towards B0).

    Examples
    --------
    Paper 003's Table 3, first cell, with the crank arc read as 100° (printed: Kω 1.27,
    Kε 2.97, Kp 3.11, δ 0.54):

    >>> fb = SphericalFourBar(*np.radians([10, 100, 65, 50]))
    >>> {k: round(float(v), 4) for k, v in coefficients(fb).items() if k[0] in "Kd"}
    {'K_omega': 1.2742, 'K_epsilon': 2.9666, 'K_p': 3.1078, 'delta': 0.538}
    """
    spherical = isinstance(mechanism, SphericalFourBar)
    if isinstance(mechanism, SphericalFourBar):
        arcs = _sph.input_limits(mechanism)
    else:
        arcs = input_range(mechanism)
    motion = circuit(mechanism, CIRCUIT_SAMPLES)
    ext = output_extremes(mechanism, motion=motion) if extremes is None else extremes

    def rate1(m: Motion) -> Array:
        return output_rates(mechanism, m)[0]

    def rate2(m: Motion) -> Array:
        return output_rates(mechanism, m)[1]

    def power(m: Motion) -> Array:
        r1, r2 = output_rates(mechanism, m)
        return r1 * r2

    def absmax(q: Callable[[Motion], Array]) -> Array:
        return np.abs(circuit_extremum(mechanism, lambda m: np.abs(q(m)), motion=motion)[0])

    w_max, e_max, p_max = absmax(rate1), absmax(rate2), absmax(power)
    w_hi = circuit_extremum(mechanism, rate1, motion=motion)[0]
    w_lo = circuit_extremum(mechanism, rate1, sign=-1.0, motion=motion)[0]
    if spherical:
        through = np.zeros(np.shape(w_max))
    elif isinstance(mechanism, FourBar):
        through = mechanism.frame_angle
    else:
        through = _slider(mechanism).line_angle
    phi_psi = _crank_rotation_between(ext["min_at"], ext["max_at"], np.asarray(through))
    psi = ext["max"] - ext["min"]
    rocking = arcs.full & ~ext["turns"]
    double = arcs.full & ext["turns"]
    nan = np.full(np.shape(w_max), np.nan)
    # A rocker whose swing or whose crank's share of the turn rounds to nothing (a crank a
    # hair long beside the rest) has no finite coefficient: NaN, reported as no value.
    swing = np.where(psi > 0, psi, np.nan)
    share = np.minimum(phi_psi, TWO_PI - phi_psi)
    share = np.where(share > 0, share, np.nan)
    k_omega = np.where(rocking, w_max * phi_psi / swing, np.where(double, w_max, nan))
    k_eps = np.where(rocking, e_max * phi_psi**2 / swing, np.where(double, TWO_PI * e_max, nan))
    k_p = np.where(rocking, p_max * phi_psi**3 / swing**2, np.where(double, TWO_PI * p_max, nan))
    delta = np.where(double, w_hi - w_lo, nan)
    ratio = np.maximum(phi_psi, TWO_PI - phi_psi) / share
    return {
        "K_omega": k_omega,
        "K_epsilon": k_eps,
        "K_p": k_p,
        "delta": delta,
        "phi_psi": np.where(rocking, phi_psi, nan),
        "psi": np.where(rocking, psi, nan),
        "time_ratio": np.where(rocking, ratio, nan),
    }
