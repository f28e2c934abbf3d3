"""One mechanism's whole analysis, as typed results in radians (:mod:`.results`).

Four-bars (planar and spherical) and slider-cranks get paper 003's analysis; every other family
the general one (limit positions, each dyad's transmission angle, the traced points' speed),
with paper 002's locking for a geared five-bar and paper 004's ellipse for a double slider.
:mod:`linkwright.io.report` renders either in degrees, JSON or text.
"""

from __future__ import annotations

import math
from typing import Any, cast

import numpy as np

from linkwright.analysis import spherical as sph
from linkwright.analysis.conic import conic_kind, doubleslider_conic, ellipse_axes
from linkwright.analysis.general import REPORT_SAMPLES, dyad_transmission_angles, point_speed
from linkwright.analysis.planar import (
    coefficients,
    fourbar_class,
    grashof,
    output_extremes,
    slidercrank_class,
    transmission_extremes,
)
from linkwright.analysis.results import (
    Analysis,
    Coefficients,
    DyadLimit,
    Ellipse,
    Extremes,
    FourBarAnalysis,
    GeneralAnalysis,
    Locking,
    PressureComponents,
    TracedPath,
    TriadLimit,
    finite,
)
from linkwright.analysis.spherical import InvalidHingeRatio
from linkwright.engine import input_turns
from linkwright.engine.continuation import every_circuit
from linkwright.engine.plan import placed_joints
from linkwright.geometry import plane, sphere
from linkwright.mechanisms import (
    DoubleSlider,
    FourBar,
    SliderCrank,
    SphericalFourBar,
    input_range,
)
from linkwright.mechanisms.base import Mechanism, circuit
from linkwright.mechanisms.registry import family_of

__all__ = ["analyze", "general_analysis"]


def analyze(mechanism: Mechanism, mu: float | None = None) -> Analysis:
    """The whole kinematic analysis of one mechanism, in radians.

    Four-bars (planar and spherical) and slider-cranks get paper 003's
    :class:`~linkwright.analysis.results.FourBarAnalysis`: class, input arcs, output range,
    transmission-angle extremes, time ratio and coefficients (a spherical four-bar adds
    paper 003's two pressure-angle components for the hinge-radius ratio ``mu`` = OB/OA, by
    default the balanced one). Every other family gets :func:`general_analysis`.
    :func:`linkwright.io.report.analysis_report` gives the degrees and words of
    ``linkwright analyze``.

    Parameters
    ----------
    mechanism : Mechanism
        One mechanism of any family (not a batch).
    mu : float, optional
        A spherical four-bar's hinge-radius ratio OB/OA for the pressure-angle components.

    Returns
    -------
    Analysis
        A :class:`~linkwright.analysis.results.FourBarAnalysis` or a general analysis, in
        radians, with ``None`` where a quantity does not exist.

    Raises
    ------
    ValueError
        For a batch of mechanisms (index it first).
    InvalidHingeRatio
        For ``mu`` given to anything but a spherical four-bar, or a ``mu`` that is not a
        positive number.

    Examples
    --------
    Paper 003, Table 4, first row (printed: Kω 1.33, Kε 2.84, δ 0.63, ν 33.69°):

    >>> r = analyze(FourBar(A0=[0, 0], B0=[1, 0], crank=4, coupler=2, rocker=13**0.5))
    >>> r.kind, r.input_full, r.output_range
    ('double-crank', True, None)
    >>> round(r.coefficients.K_omega, 3), round(r.coefficients.delta, 3)
    (1.333, 0.631)
    >>> round(90 - math.degrees(r.transmission.min), 2)   # the greatest pressure angle
    33.69

    A linkage that cannot be assembled says so, has no class, and no numbers:

    >>> r = analyze(FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3))
    >>> r.kind, r.assembles, r.transmission, r.coefficients.K_omega
    (None, False, None, None)
    >>> r.reason.split(": ")[1]
    'the frame (10) is longer than the other three links together (6)'
    """
    if mechanism.batch_shape != ():
        raise ValueError("analyze reports on one mechanism; index the batch first")
    # What a family reports beyond its plan's general analysis is its registry entry's word.
    closed_form = family_of(mechanism).analysis
    if closed_form == "spherical-fourbar":
        return _spherical(cast(SphericalFourBar, mechanism), mu)
    if mu is not None:
        raise InvalidHingeRatio(
            f"mu: the hinge-radius ratio applies to a spherical four-bar, not to a "
            f"{mechanism.family}"
        )
    if closed_form not in ("fourbar", "slidercrank"):
        return general_analysis(mechanism)
    is_fourbar = closed_form == "fourbar"
    planar = cast(FourBar | SliderCrank, mechanism)
    if isinstance(planar, FourBar):  # for the type checker: the registry has said which
        ref = float(planar.frame_angle)
        cls = str(fourbar_class(planar))
    else:
        ref = float(planar.line_angle)
        cls = str(slidercrank_class(planar))
    arcs = input_range(mechanism)
    never = bool(arcs.never)
    grashof_ratio = finite(grashof(planar)) if isinstance(planar, FourBar) else None
    if never:
        return FourBarAnalysis(
            family=mechanism.family, kind=None, assembles=False,
            reason=_never_reason(planar), reference_angle=ref, grashof=grashof_ratio,
            grashof_terms=None, input_full=False, input_arcs=(), output_range=None,
            slider_range=None, transmission=None, pressure=None, time_ratio=None,
            coefficients=Coefficients.of(None),
        )  # fmt: skip
    ext = output_extremes(mechanism)
    if is_fourbar:
        output = None if bool(ext["turns"]) else _pair(ext["min"], ext["max"])
        slider = None
    else:
        output, slider = None, _pair(ext["min"], ext["max"])
    co = coefficients(mechanism, extremes=ext)
    return FourBarAnalysis(
        family=mechanism.family,
        # A linkage that never assembles has no motion, so no motion class (Grashof's
        # inequality alone would call frame 1, crank 1, coupler 1, rocker 5 a triple-rocker).
        kind=cls,
        assembles=True,
        reason=None,
        reference_angle=ref,
        grashof=grashof_ratio,
        grashof_terms=None,
        input_full=bool(arcs.full),
        input_arcs=_arcs(arcs),
        output_range=output,
        slider_range=slider,
        transmission=_extremes(transmission_extremes(mechanism)),
        pressure=None,
        time_ratio=finite(co["time_ratio"]),
        coefficients=Coefficients.of(co),
    )


def _pair(lo: Any, hi: Any) -> tuple[float, float] | None:
    a, b = finite(lo), finite(hi)
    return None if a is None or b is None else (a, b)


def _arcs(arcs: Any) -> tuple[tuple[float, float], ...]:
    """The input arcs whose ends are known (absolute radians)."""
    return tuple(
        (float(lo), float(hi))
        for lo, hi in zip(arcs.lo, arcs.hi, strict=True)
        if math.isfinite(lo) and math.isfinite(hi)
    )


def _extremes(tx: Any, prefix: str = "") -> Extremes:
    return Extremes(
        min=finite(tx[f"{prefix}min"]),
        max=finite(tx[f"{prefix}max"]),
        min_at=finite(tx[f"{prefix}min_at"]),
        max_at=finite(tx[f"{prefix}max_at"]),
    )


def _never_reason(mechanism: FourBar | SliderCrank | SphericalFourBar) -> str:
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


def _spherical(fb: SphericalFourBar, mu: float | None) -> FourBarAnalysis:
    """Paper 003's analysis of one spherical four-bar (see :func:`analyze`)."""
    arcs = sph.input_limits(fb)
    never = bool(arcs.never)
    if mu is None:
        mu_value = float(sph.balanced_mu(fb))
        source = "balanced" if math.isfinite(mu_value) else "none"
    else:
        mu_value = float(sph.hinge_ratio(fb, mu))
        source = "given"
    terms = tuple(finite(f) for f in sph.grashof_terms(fb))
    if never:
        return FourBarAnalysis(
            family=fb.family, kind=None, assembles=False, reason=_never_reason(fb),
            reference_angle=0.0, grashof=None, grashof_terms=terms, input_full=False,
            input_arcs=(), output_range=None, slider_range=None, transmission=None,
            pressure=PressureComponents(finite(mu_value), source, None, None),
            time_ratio=None, coefficients=Coefficients.of(None),
        )  # fmt: skip
    ext = sph.output_extremes(fb)
    normal = tangential = None
    if source != "none":
        nu = sph.pressure_extremes(fb, mu_value)
        normal, tangential = _extremes(nu, "normal_"), _extremes(nu, "tangential_")
    co = coefficients(fb, extremes=ext)
    return FourBarAnalysis(
        family=fb.family,
        kind=str(sph.spherical_class(fb)),
        assembles=True,
        reason=None,
        # The document's θ is already φ1, from the frame circle: absolute and from the frame agree.
        reference_angle=0.0,
        grashof=None,
        grashof_terms=terms,
        input_full=bool(arcs.full),
        input_arcs=_arcs(arcs),
        output_range=None if bool(ext["turns"]) else _pair(ext["min"], ext["max"]),
        slider_range=None,
        transmission=_extremes(sph.transmission_extremes(fb)),
        pressure=PressureComponents(finite(mu_value), source, normal, tangential),
        time_ratio=finite(co["time_ratio"]),
        coefficients=Coefficients.of(co),
    )


def general_analysis(mechanism: Mechanism, *, samples: int = REPORT_SAMPLES) -> GeneralAnalysis:
    """The analysis of any single linkage the engine builds (radians).

    Its input arcs and limit positions (exact roots, each with the dyad that reaches its limit
    there; for a linkage with a triad every limit of every circuit, with the two pose indices
    that merge there as the circuit arrives and leaves), each dyad's transmission-angle extremes
    and each traced joint's path length and speed per radian of input, read from ``samples``
    circuit samples (sampled, not refined: good to about (period/samples)² of the curvature).

    Examples
    --------
    >>> from linkwright.mechanisms import GearedFiveBar
    >>> r = general_analysis(GearedFiveBar(A0=[0, 0], B0=[1, 0], crank1=4, crank2=4,
    ...                                    link1=3, link2=5, ratio=1))
    >>> r.assembles, r.reason, r.samples
    (False, 'some dyad cannot close at any input', 0)
    """
    if mechanism.batch_shape != ():
        raise ValueError("a report is on one mechanism; index the batch first")
    plan = mechanism.plan
    arcs = input_range(mechanism)
    turns = int(input_turns(plan, mechanism.params(), points=mechanism.points))
    dyads = plan.dyads
    finite_arcs = [
        (lo, hi, dl, dh)
        for lo, hi, dl, dh in zip(arcs.lo, arcs.hi, arcs.dyad_lo, arcs.dyad_hi, strict=True)
        if math.isfinite(lo)
    ]
    limits: tuple[DyadLimit | TriadLimit, ...] = tuple(
        DyadLimit(finite(x), dyads[int(d)].name if d >= 0 else None)
        for lo, hi, dl, dh in finite_arcs
        for x, d in ((lo, dl), (hi, dh))
    )
    count = None
    if plan.triads:
        # A triad's configurations are followed: every limit of every circuit, where two of
        # its poses merge (the circuit may turn there more often than at its arc's ends).
        found = every_circuit(plan, mechanism.params(), 360, points=mechanism.points, order=0)
        count = len(found)
        limits = tuple(
            TriadLimit(
                finite(limit.input),
                "".join(placed_joints(triad)),
                k,
                (int(limit.before[triad.name]), int(limit.after[triad.name])),
            )
            for k, c in enumerate(found)
            for limit in c.limits
            for triad in plan.triads
            if limit.before[triad.name] != limit.after[triad.name]
        )
    never = bool(arcs.never)
    reason = None
    if never:
        reason = (
            "some dyad cannot close at any input"
            if not plan.triads
            else f"{plan.triads[0].unassembled()} at any input"
        )
    transmission: dict[str, Extremes] = {}
    traced: dict[str, TracedPath] = {}
    if never:
        transmission = {d.name: Extremes(None, None) for d in dyads}
        traced = {j: TracedPath(None, None, None) for j in plan.traced}
    else:
        motion = circuit(mechanism, samples, order=1)
        for name, a in dyad_transmission_angles(mechanism, motion).items():
            transmission[name] = Extremes(_extreme(a, False), _extreme(a, True))
        for joint in plan.traced:
            pos = motion.positions[joint]
            closed = np.concatenate((pos, pos[:1]), axis=0)
            if plan.space == "sphere":  # arc length on the unit sphere, radians
                length = np.nansum(sphere.arc(closed[:-1], closed[1:]))
            else:
                length = np.nansum(plane.norm(np.diff(closed, axis=0)))
            speed = point_speed(motion, joint)
            traced[joint] = TracedPath(
                finite(length), _extreme(speed, False), _extreme(speed, True)
            )
    locking = ellipse = None
    extra = family_of(mechanism).analysis
    if extra == "locking":
        locking = Locking(
            oscillates=not never and not bool(arcs.full),
            locking_positions=tuple(limit.input for limit in limits),
            repeats_after_turns=turns,
        )
    if extra == "ellipse":
        coeffs = doubleslider_conic(cast(DoubleSlider, mechanism))
        axes = ellipse_axes(coeffs)
        ellipse = Ellipse(
            center=(finite(axes["center"][0]), finite(axes["center"][1])),
            semi_major=finite(axes["semi_major"]),
            semi_minor=finite(axes["semi_minor"]),
            orientation=finite(axes["orientation"]),
            conic=tuple(finite(c) for c in coeffs),
            kind=str(conic_kind(coeffs)),
        )
    return GeneralAnalysis(
        family=mechanism.family,
        assembles=not never,
        period_turns=turns,
        input_turns_fully=bool(arcs.full),
        input_arcs=tuple(
            (float(lo), float(hi)) for lo, hi, _, _ in finite_arcs if math.isfinite(hi)
        ),
        limit_positions=limits,
        circuits=count,
        reason=reason,
        transmission=transmission,
        traced=traced,
        samples=0 if never else samples,
        locking=locking,
        ellipse=ellipse,
    )


def _extreme(values: Any, largest: bool) -> float | None:
    """The least or greatest finite value, ``None`` when there is none (every sample at a
    toggle, say) rather than NumPy's all-NaN warning."""
    kept = np.asarray(values, dtype=float)
    kept = kept[np.isfinite(kept)]
    if kept.size == 0:
        return None
    return float(kept.max() if largest else kept.min())
