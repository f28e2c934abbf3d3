"""Analyses: pure functions of a mechanism (and its motion); nothing cached behind your back.

:func:`analyze` gathers the planar analyses into the JSON-ready report of ``linkwright analyze``;
a spherical four-bar gets the same report from :mod:`linkwright.analysis.spherical`, with both
components of paper 003's pressure angle.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from linkwright.analysis import spherical as sph
from linkwright.analysis.conic import (
    conic_invariants,
    conic_kind,
    doubleslider_conic,
    ellipse_axes,
    normalise_conic,
)
from linkwright.analysis.general import (
    _deg,
    _num,
    dyad_transmission_angles,
    general_report,
    point_speed,
)
from linkwright.analysis.planar import (
    coefficients,
    fourbar_class,
    grashof,
    output_angle,
    output_extremes,
    output_rates,
    slidercrank_class,
    stroke,
    transmission_angle,
    transmission_extremes,
)
from linkwright.analysis.spherical import (
    InvalidHingeRatio,
    NotASphericalFourBar,
    balanced_mu,
    grashof_terms,
    input_limits,
    output_limits,
    paper003_normal_extremes,
    paper003_tangential_extremes,
    pressure_angles,
    pressure_extremes,
    spherical_class,
)
from linkwright.mechanisms import (
    DoubleSlider,
    FourBar,
    GearedFiveBar,
    SliderCrank,
    SphericalFourBar,
    input_range,
)
from linkwright.mechanisms.base import Mechanism

__all__ = [
    "InvalidHingeRatio",
    "NotASphericalFourBar",
    "analyze",
    "balanced_mu",
    "coefficients",
    "conic_invariants",
    "conic_kind",
    "doubleslider_conic",
    "dyad_transmission_angles",
    "ellipse_axes",
    "fourbar_class",
    "general_report",
    "grashof",
    "grashof_terms",
    "input_limits",
    "normalise_conic",
    "output_angle",
    "output_extremes",
    "output_limits",
    "output_rates",
    "paper003_normal_extremes",
    "paper003_tangential_extremes",
    "point_speed",
    "pressure_angles",
    "pressure_extremes",
    "slidercrank_class",
    "spherical_class",
    "stroke",
    "transmission_angle",
    "transmission_extremes",
]


def _wrap_deg(x: Any) -> float | None:
    """Angle in degrees wrapped to (−180, 180]."""
    v = float(x)
    if not math.isfinite(v):
        return None
    # + 0.0 turns the −0.0 that the wrap gives for 0° into 0.0.
    return _num(-(((-np.degrees(v)) + 180.0) % 360.0 - 180.0) + 0.0)


def analyze(mechanism: Mechanism, mu: float | None = None) -> dict[str, Any]:
    """The full kinematic report of one mechanism, in degrees (JSON-ready).

    Four-bars (planar and spherical) and slider-cranks get paper 003's report below. Every other
    family gets :func:`general_report` (limit positions, each dyad's transmission angle, the
    traced points' speed), plus for a geared five-bar its ``locking`` (paper 002: whether and
    between which inputs it oscillates) and for a double slider its ``ellipse`` (paper 004:
    centre, semi-axes, orientation and the normalised conic A..F of eq. 3).

    Angles are absolute, as ``solve``, ``curve`` and ``plot`` take them: the input θ is the
    direction of A − A0 counter-clockwise from +x, the output the direction of B − B0. Paper
    003 measures both from the frame line A0→B0 (for a slider-crank: from the slider's line
    direction); the ``*_from_frame_deg`` keys give them so, and ``reference_angle_deg`` is the
    frame line's own direction (absolute = from frame + reference).

    Keys: ``family``, ``class`` (``None`` when the linkage cannot be assembled at any input: it
    has no motion to classify), ``assembles``, ``reason`` (when it does not), ``grashof``
    (s + l − p − q over l; four-bar), ``reference_angle_deg``, ``input_range_deg`` (``None``
    for a full turn), ``input_arcs_deg``, ``limit_positions_deg`` (each with its
    ``*_from_frame_deg`` twin), ``output_range_deg`` (and ``output_range_from_frame_deg``) and
    ``swing_deg`` (four-bar, ``None`` when the output turns fully), ``output_range`` and
    ``stroke`` (slider-crank, lengths along the line from the foot of A0),
    ``transmission_angle_deg`` (``min``, ``max`` and the absolute inputs where they occur),
    ``pressure_angle_deg`` (90° − γ), ``time_ratio``, ``coefficients`` (``K_omega``,
    ``K_epsilon``, ``K_p``, ``delta``).

    A spherical four-bar (paper 003's α1..α4 = crank, coupler, rocker, frame arcs; φ1 from the
    frame circle towards B0, φ3 about +OB0 from the frame circle beyond B0) gets the same keys,
    with ``grashof_terms_deg`` (F1..F4 of :func:`grashof_terms`) in place of ``grashof``, and a
    ``pressure_angle_deg`` of two components: ``normal`` and ``tangential``, each ``min``,
    ``max`` and the inputs there, for the hinge-radius ratio ``mu`` = OB/OA (the argument; by
    default paper 003's balanced μ, :func:`balanced_mu`), with ``mu`` and ``mu_source``
    (``"given"`` or ``"balanced"``; ``"none"`` when no positive μ balances, and the components
    are null).

    Examples
    --------
    Paper 003, Table 4, first row (printed: Kω 1.33, Kε 2.84, δ 0.63, ν 33.69°):

    >>> r = analyze(FourBar(A0=[0, 0], B0=[1, 0], crank=4, coupler=2, rocker=13**0.5))
    >>> r["class"], r["input_range_deg"], r["output_range_deg"]
    ('double-crank', None, None)
    >>> {k: round(v, 3) for k, v in r["coefficients"].items()}
    {'K_omega': 1.333, 'K_epsilon': 2.845, 'K_p': 3.182, 'delta': 0.631}
    >>> round(r["pressure_angle_deg"]["max"], 2)
    33.69

    A linkage that cannot be assembled says so, has no class, and every number is null:

    >>> r = analyze(FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3))
    >>> r["class"], r["assembles"], r["swing_deg"], r["coefficients"]["K_omega"]
    (None, False, None, None)
    >>> r["reason"].split(": ")[1]
    'the frame (10) is longer than the other three links together (6)'

    Paper 003's first spherical crank-rocker (Table 1: Kω 1.71, Kε 5.65; Table 2: μ 0.517,
    ν_n 23.73 / −11.25, ν_τ 3.18 / −3.19):

    >>> r = analyze(SphericalFourBar(*np.radians([90, 15, 60, 80])))
    >>> r["class"], [round(x, 3) for x in r["output_range_deg"]], round(r["swing_deg"], 3)
    ('crank-rocker', [105.237, 135.891], 30.654)
    >>> {k: round(v, 3) for k, v in r["coefficients"].items() if v is not None}
    {'K_omega': 1.711, 'K_epsilon': 5.653, 'K_p': 5.154}
    >>> p = r["pressure_angle_deg"]
    >>> round(p["mu"], 5), p["mu_source"]
    (0.51714, 'balanced')
    >>> [round(p[c][k], 2) for c in ("normal", "tangential") for k in ("max", "min")]
    [23.73, -11.25, 3.19, -3.19]
    """
    if mechanism.batch_shape != ():
        raise ValueError("analyze reports on one mechanism; index the batch first")
    if isinstance(mechanism, SphericalFourBar):
        return _report_spherical(mechanism, mu)
    if mu is not None:
        raise InvalidHingeRatio(
            f"mu: the hinge-radius ratio applies to a spherical four-bar, not to a "
            f"{mechanism.family}"
        )
    arcs = input_range(mechanism)
    is_fourbar = isinstance(mechanism, FourBar)
    if is_fourbar:
        ref = float(mechanism.frame_angle)
        cls = str(fourbar_class(mechanism))
    elif isinstance(mechanism, SliderCrank):
        ref = float(mechanism.line_angle)
        cls = str(slidercrank_class(mechanism))
    else:
        return _report_other(mechanism)
    report: dict[str, Any] = {
        "family": mechanism.family,
        # A linkage that never assembles has no motion, so no motion class (Grashof's
        # inequality alone would call frame 1, crank 1, coupler 1, rocker 5 a triple-rocker).
        "class": None if arcs.never else cls,
        "assembles": not bool(arcs.never),
        "reference_angle_deg": _deg(ref),
    }
    if is_fourbar:
        report["grashof"] = _num(grashof(mechanism))
    if arcs.never:
        report["reason"] = _never_reason(mechanism)
        _null_ranges(report)
        report["transmission_angle_deg"] = {"min": None, "max": None}
        report["pressure_angle_deg"] = {"min": None, "max": None}
        if not is_fourbar:
            report["output_range"] = None
            report["stroke"] = None
        report["coefficients"] = dict.fromkeys(("K_omega", "K_epsilon", "K_p", "delta"))
        return report

    _input_ranges(report, arcs, ref)
    ext = output_extremes(mechanism)
    if is_fourbar:
        _output_ranges(report, ext, ref)
    else:
        report["output_range"] = [_num(ext["min"]), _num(ext["max"])]
        report["stroke"] = _num(ext["max"] - ext["min"])
        report["output_range_deg"] = None
        report["output_range_from_frame_deg"] = None
        report["swing_deg"] = None

    tx = transmission_extremes(mechanism)
    report["transmission_angle_deg"] = {
        "min": _deg(tx["min"]),
        "max": _deg(tx["max"]),
        "min_at_input_deg": _wrap_deg(tx["min_at"]),
        "max_at_input_deg": _wrap_deg(tx["max_at"]),
    }
    report["pressure_angle_deg"] = {
        "min": _num(90.0 - np.degrees(tx["max"])),
        "max": _num(90.0 - np.degrees(tx["min"])),
    }
    co = coefficients(mechanism, extremes=ext)
    report["time_ratio"] = _num(co["time_ratio"])
    report["coefficients"] = {k: _num(co[k]) for k in ("K_omega", "K_epsilon", "K_p", "delta")}
    return report


def _limits_deg(arcs: Any, ref: float = 0.0) -> list[list[float | None]]:
    """Input arcs in degrees measured from the direction ``ref`` (radians), each start wrapped
    to (−180, 180] and its end the start plus the arc's width."""
    return [
        [_wrap_deg(lo - ref), _num(np.degrees(hi - lo)) + _wrap_deg(lo - ref)]  # type: ignore[operator]
        for lo, hi in zip(arcs.lo, arcs.hi, strict=True)
        if math.isfinite(lo)
    ]


def _null_ranges(report: dict[str, Any]) -> None:
    """The range keys of a linkage that never assembles: no arcs, no limits, no extremes."""
    for suffix in ("_deg", "_from_frame_deg"):
        report["input_range" + suffix] = None
        report["input_arcs" + suffix] = []
        report["limit_positions" + suffix] = []
    report["output_range_deg"] = report["output_range_from_frame_deg"] = None
    report["swing_deg"] = None
    report["time_ratio"] = None


def _input_ranges(report: dict[str, Any], arcs: Any, ref: float) -> None:
    """The input's arcs and limit positions, absolute (what ``solve --input`` takes) and from
    the frame line (paper 003's φ1)."""
    for suffix, origin in (("_deg", 0.0), ("_from_frame_deg", ref)):
        found = _limits_deg(arcs, origin)
        report["input_range" + suffix] = None if arcs.full else found[0]
        report["input_arcs" + suffix] = [] if arcs.full else found
        report["limit_positions" + suffix] = [a for arc in found for a in arc]


def _output_ranges(report: dict[str, Any], ext: dict[str, Any], ref: float) -> None:
    """A four-bar output's range: absolute (the direction of B − B0) and from the frame line
    (paper 003's φ3), each start wrapped to (−180, 180]; ``None`` where the output turns."""
    if bool(ext["turns"]):
        report["output_range_deg"] = report["output_range_from_frame_deg"] = None
        report["swing_deg"] = None
        return
    swing = _deg(ext["max"] - ext["min"])
    start = _wrap_deg(ext["min"] + ref)
    report["output_range_deg"] = [start, _num(start + swing)]  # type: ignore[operator]
    report["output_range_from_frame_deg"] = [_deg(ext["min"]), _deg(ext["max"])]
    report["swing_deg"] = swing


def _never_reason(mechanism: Mechanism) -> str:
    """Why a four-bar (planar or spherical) or slider-crank cannot be assembled at any input."""
    if isinstance(mechanism, SliderCrank):
        return "the rod cannot reach the slider's line at any input"
    head = "the coupler and rocker cannot reach each other at any input"
    if isinstance(mechanism, SphericalFourBar):
        unit = "°"
        frame = float(np.degrees(mechanism.frame))
        crank, coupler, rocker = (
            float(np.degrees(getattr(mechanism, k))) for k in ("crank", "coupler", "rocker")
        )
    else:
        unit = ""
        frame = float(np.hypot(*(np.asarray(mechanism.B0) - np.asarray(mechanism.A0))))
        crank, coupler, rocker = (
            float(getattr(mechanism, k)) for k in ("crank", "coupler", "rocker")
        )
    links = {"frame": frame, "crank": crank, "coupler": coupler, "rocker": rocker}
    name = max(links, key=links.__getitem__)
    rest = sum(links.values()) - links[name]
    if links[name] > rest:
        # A side of a closed loop is never longer than the other sides together (in the plane,
        # and on the sphere, whose arcs obey the triangle inequality too).
        return (
            f"{head}: the {name} ({links[name]:.6g}{unit}) is longer than the other three "
            f"links together ({rest:.6g}{unit})"
        )
    return head


def _report_spherical(fb: SphericalFourBar, mu: float | None) -> dict[str, Any]:
    """Paper 003's report of one spherical four-bar (see :func:`analyze`)."""
    arcs = sph.input_limits(fb)
    report: dict[str, Any] = {
        "family": fb.family,
        "class": None if arcs.never else str(sph.spherical_class(fb)),
        "grashof_terms_deg": [_deg(f) for f in sph.grashof_terms(fb)],
        "assembles": not bool(arcs.never),
        # The document's θ is already φ1, from the frame circle: absolute and from the frame agree.
        "reference_angle_deg": 0.0,
    }
    if mu is None:
        mu_value = float(sph.balanced_mu(fb))
        source = "balanced" if math.isfinite(mu_value) else "none"
    else:
        mu_value = float(sph._mu(fb, mu))
        source = "given"
    empty = {"min": None, "max": None, "min_at_input_deg": None, "max_at_input_deg": None}
    pressure: dict[str, Any] = {
        "normal": dict(empty),
        "tangential": dict(empty),
        "mu": _num(mu_value),
        "mu_source": source,
    }
    if arcs.never:
        report["reason"] = _never_reason(fb)
        _null_ranges(report)
        report["transmission_angle_deg"] = dict(empty)
        report["pressure_angle_deg"] = pressure
        report["coefficients"] = dict.fromkeys(("K_omega", "K_epsilon", "K_p", "delta"))
        return report
    _input_ranges(report, arcs, 0.0)
    ext = sph.output_extremes(fb)
    rocking = not bool(ext["turns"])
    report["output_range_deg"] = [_deg(ext["min"]), _deg(ext["max"])] if rocking else None
    report["output_range_from_frame_deg"] = report["output_range_deg"]
    report["swing_deg"] = _deg(ext["max"] - ext["min"]) if rocking else None
    tx = sph.transmission_extremes(fb)
    report["transmission_angle_deg"] = {
        "min": _deg(tx["min"]),
        "max": _deg(tx["max"]),
        "min_at_input_deg": _wrap_deg(tx["min_at"]),
        "max_at_input_deg": _wrap_deg(tx["max_at"]),
    }
    if source != "none":
        nu = sph.pressure_extremes(fb, mu_value)

        def where(x: Any) -> float | None:
            # A flat extreme's value is exact but its input only to ~√eps (1e-6°): say no more.
            w = _wrap_deg(x)
            if w is None:
                return None
            w = round(w, 5) + 0.0
            return 180.0 if w == -180.0 else w

        for part in ("normal", "tangential"):
            pressure[part] = {
                "min": _deg(nu[f"{part}_min"]),
                "max": _deg(nu[f"{part}_max"]),
                "min_at_input_deg": where(nu[f"{part}_min_at"]),
                "max_at_input_deg": where(nu[f"{part}_max_at"]),
            }
    report["pressure_angle_deg"] = pressure
    co = coefficients(fb, extremes=ext)
    report["time_ratio"] = _num(co["time_ratio"])
    report["coefficients"] = {k: _num(co[k]) for k in ("K_omega", "K_epsilon", "K_p", "delta")}
    return report


def _report_other(mechanism: Mechanism) -> dict[str, Any]:
    report = general_report(mechanism)
    if isinstance(mechanism, GearedFiveBar):
        turns = report["period_turns"]
        report["locking"] = {
            "oscillates": report["assembles"] and not report["input_turns_fully"],
            "locking_positions_deg": [p["input_deg"] for p in report["limit_positions"]],
            "note": (
                "the dyad A–C–B cannot close beyond the locking positions; the linkage "
                "oscillates between them, as paper 002's tool does"
                if report["assembles"] and not report["input_turns_fully"]
                else None
            ),
            "repeats_after_turns": turns,
        }
    if isinstance(mechanism, DoubleSlider):
        coeffs = doubleslider_conic(mechanism)
        axes = ellipse_axes(coeffs)
        report["ellipse"] = {
            "center": [_num(c) for c in axes["center"]],
            "semi_major": _num(axes["semi_major"]),
            "semi_minor": _num(axes["semi_minor"]),
            "orientation_deg": _deg(axes["orientation"]),
            "conic": dict(zip("ABCDEF", (_num(c) for c in coeffs), strict=True)),
            "kind": str(conic_kind(coeffs)),
        }
    return report
