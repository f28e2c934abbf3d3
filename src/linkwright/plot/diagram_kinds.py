"""The kinds of motion diagram: what each puts in its panels.

``angles`` (:func:`angle_panels`): the output and the transmission angle of every dyad, and a
spherical four-bar's pressure angles; ``velocity`` and ``acceleration``
(:func:`derivative_panels`): the traced points' derivatives by the input angle and the output's;
``coefficients`` (:func:`coefficient_panels`): paper 003's Kω, Kε and Kp where they apply, else
the kinematic analogues. Each returns its panels and the line that says what they show.

Its own room (split from :mod:`linkwright.plot.diagrams`): the content of each kind, apart from
the quantities it reads (:mod:`~linkwright.plot.diagram_quantities`) and the drawing
(:mod:`~linkwright.plot.diagram_panels`).

References
----------
Paper 003: R. P. Dzhavakhyan, A. G. Makhsudyan, V. A. Arakelyan, comparison of planar and
spherical four-hinge mechanisms, eqs. (3)–(4) (Kω, Kε, Kp) and the text after eq. (7) (the
double crank and δ); its pressure angle of the spherical four-bar and the balanced μ
(:mod:`linkwright.analysis.spherical`).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from linkwright.analysis import (
    balanced_mu,
    coefficients,
    dyad_transmission_angles,
    pressure_angles,
    transmission_angle,
)
from linkwright.engine import Motion
from linkwright.mechanisms import DoubleSlider, FourBar, Mechanism, SliderCrank, SphericalFourBar
from linkwright.plot.diagram_panels import Panel, Run, Series, minmax
from linkwright.plot.diagram_quantities import Outputs, Quantity
from linkwright.plot.planar import deg_text, num_text, unwrap_finite
from linkwright.plot.style import CURVE_COLOR, GAMMA_COLOR, OTHER_COLOR

__all__ = ["PALETTE", "angle_panels", "coefficient_panels", "derivative_panels"]

Array = NDArray[np.float64]


# One colour per plotted quantity (a traced point, an output, a link); the line style tells
# the legs of a rocking circuit apart.
PALETTE = (
    CURVE_COLOR,
    OTHER_COLOR,
    "tab:green",
    GAMMA_COLOR,
    "tab:brown",
    "tab:pink",
    "tab:olive",
    "tab:cyan",
    "tab:gray",
    "tab:red",
)


def _continuous_degrees(angle: Array) -> Array:
    """An angle along a closed circuit, in degrees, without jumps: unwrapped (a turning link
    ends 360° on), then shifted by whole turns so that its range is centred in (−180°, 180°]."""
    out = np.degrees(unwrap_finite(angle))
    span = minmax([out])
    if span is not None:
        mid = 0.5 * (span[0] + span[1])
        out = out - 360.0 * np.round(mid / 360.0)
    return out


def _colors(n: int) -> list[str]:
    return [PALETTE[i % len(PALETTE)] for i in range(n)]


def _deg_range(values: list[Array], name: str) -> str:
    span = minmax(values)
    if span is None:
        return f"{name}: not assembled"
    if span[1] - span[0] < 0.05:
        return f"{name} constant, {deg_text(span[0])}°"
    return f"{name} from {deg_text(span[0])}° to {deg_text(span[1])}°"


def angle_panels(mechanism: Mechanism, run: Run, outs: Outputs) -> tuple[list[Panel], str]:
    motions = [c.motion for c in run.circuits]
    panels: list[Panel] = []
    details = ""
    by_unit: dict[str, list[Quantity]] = {}
    for q in outs.quantities:
        by_unit.setdefault(q.unit, []).append(q)
    colors = iter(_colors(len(outs.quantities)))
    for unit, quantities in by_unit.items():
        series = []
        for q in quantities:
            values = run.closed([q.value(m) for m in motions])
            if unit == "angle":
                values = [_continuous_degrees(v) for v in values]
            series.append(Series(q.label, values, next(colors)))
        note = ""
        if len(series) == 1:
            span = minmax(series[0].values)
            sym = outs.symbol
            if span is not None and unit == "angle":
                turned = abs(span[1] - span[0]) >= 359.0
                note = (
                    f"{sym} turns fully"
                    if turned
                    else f"{sym} from {deg_text(span[0])}° to {deg_text(span[1])}° "
                    f"(swing {deg_text(span[1] - span[0])}°)"
                )
            elif span is not None:
                note = (
                    f"{sym} from {num_text(span[0])} to {num_text(span[1])} "
                    f"(stroke {num_text(span[1] - span[0])})"
                )
        if unit == "angle":
            ylabel = f"output angle {outs.symbol} (°)" if outs.single else "link angle ψ (°)"
        else:
            ylabel = "slider position s (length)" if outs.single else "slider travel t (length)"
        panels.append(Panel(ylabel, series, note=note))

    if isinstance(mechanism, FourBar | SliderCrank | SphericalFourBar):
        gammas = {"γ": [np.degrees(transmission_angle(mechanism, m)) for m in motions]}
    else:
        per = [dyad_transmission_angles(mechanism, m) for m in motions]
        gammas = {f"γ at {name}": [np.degrees(p[name]) for p in per] for name in per[0]}
    if gammas:
        colors_g = iter([GAMMA_COLOR] if len(gammas) == 1 else _colors(len(gammas)))
        series = [Series(name, run.closed(v), next(colors_g)) for name, v in gammas.items()]
        note = "sampled " + "\n".join(_deg_range(s.values, s.label) for s in series)
        panels.append(
            Panel(
                "transmission angle γ (°)",
                series,
                note=note,
                ideal=90.0,
                ideal_label="90° (ideal)",
            )
        )
        if isinstance(mechanism, FourBar | SliderCrank | SphericalFourBar):
            at = (
                "at B" if not isinstance(mechanism, SliderCrank) else "between rod and guide normal"
            )
            details = f"γ: transmission angle {at}"
        else:
            details = "γ: transmission angle of each dyad, at its joint"
    else:
        details = "no dyad, so no transmission angle"

    if isinstance(mechanism, SphericalFourBar):
        mu = float(balanced_mu(mechanism))
        if math.isfinite(mu):
            nu = [pressure_angles(mechanism, m, mu) for m in motions]
            series = [
                Series(
                    "ν_n (normal)", run.closed([np.degrees(n["normal"]) for n in nu]), "tab:brown"
                ),
                Series(
                    "ν_τ (tangential)",
                    run.closed([np.degrees(n["tangential"]) for n in nu]),
                    "tab:cyan",
                ),
            ]
            note = "sampled " + "\n".join(_deg_range(s.values, s.label) for s in series)
            panels.append(
                Panel(
                    "pressure angle ν (°)", series, note=note, ideal=0.0, ideal_label="0° (ideal)"
                )
            )
            details += (
                f"; ν_n, ν_τ: paper 003's pressure-angle components at μ = OB/OA = {num_text(mu)} "
                "(balanced μ, analysis.balanced_mu)"
            )
        else:
            details += "; no positive μ = OB/OA balances ν_τ (paper 003): pressure angles omitted"
    return panels, details


def _point_panels(mechanism: Mechanism, run: Run, order: int) -> tuple[list[Panel], list[str]]:
    """|d^k P/dθ^k| and, in the plane, its x and y components, for every traced joint."""
    traced = mechanism.plan.traced
    colors = _colors(len(traced))
    motions = [c.motion for c in run.circuits]

    def deriv(m: Motion, joint: str) -> Array:
        d = m.velocities if order == 1 else m.accelerations
        assert d is not None
        return d[joint]

    mark = "′" if order == 1 else "″"
    sym = "dP/dθ" if order == 1 else "d²P/dθ²"
    sphere_space = mechanism.space == "sphere"
    if sphere_space:
        unit = "rad of arc/rad" if order == 1 else "sphere radii/rad²"
    else:
        unit = "length/rad" if order == 1 else "length/rad²"
    mags = [
        Series(j, run.closed([np.linalg.norm(deriv(m, j), axis=-1) for m in motions]), c)
        for j, c in zip(traced, colors, strict=True)
    ]
    panels = [Panel(f"|{sym}| ({unit})", mags, clip="magnitude")]
    if not sphere_space:
        for axis, name in ((0, "x"), (1, "y")):
            comp = [
                Series(j, run.closed([deriv(m, j)[..., axis] for m in motions]), c)
                for j, c in zip(traced, colors, strict=True)
            ]
            panels.append(
                Panel(
                    f"{name}{mark} = d{'' if order == 1 else '²'}{name}/dθ"
                    f"{'' if order == 1 else '²'} ({unit})",
                    comp,
                    clip="signed",
                )
            )
    what = [
        f"traced point{'s' if len(traced) > 1 else ''} {', '.join(traced)}: "
        + (
            f"|{sym}| of the unit vector "
            + ("(its arc rate)" if order == 1 else "(sphere radii per rad², normal part included)")
            if sphere_space
            else f"{sym}, components and magnitude"
        )
    ]
    return panels, what


def _rate_panels(
    run: Run, outs: Outputs, order: int, colors: list[str], *, analogue: bool = False
) -> list[Panel]:
    """The outputs' first (order 1) or second (order 2) derivative by θ, one panel per unit:
    labelled as velocity/acceleration ratios, or (``analogue``) as the kinematic analogues."""
    motions = [c.motion for c in run.circuits]
    panels = []
    by_unit: dict[str, list[tuple[Quantity, str]]] = {}
    for q, c in zip(outs.quantities, colors, strict=True):
        by_unit.setdefault(q.unit, []).append((q, c))
    who = "out" if outs.single else "link"
    for unit, quantities in by_unit.items():
        series = [
            Series(q.label, run.closed([q.rates(m)[order - 1] for m in motions]), c)
            for q, c in quantities
        ]
        angle = unit == "angle"
        sym = outs.symbol if outs.single else ("ψ" if angle else "t")
        per = ("rad" if angle else "length") + ("/rad" if order == 1 else "/rad²")
        if analogue:
            d = f"d{sym}/dθ" if order == 1 else f"d²{sym}/dθ²"
            ylabel = f"{sym}{'′' if order == 1 else '″'} = {d} ({per})"
        elif order == 1:
            ratio = f"ω_{who}/ω_in" if angle else f"v_{who}/ω_in"
            ylabel = f"{ratio} = {sym}′ ({per})"
        else:
            ratio = f"ε_{who}/ω_in²" if angle else f"a_{who}/ω_in²"
            ylabel = f"{ratio} = {sym}″ ({per})"
        panels.append(Panel(ylabel, series, clip="signed", ideal=0.0, ideal_label="_zero"))
    return panels


def derivative_panels(
    mechanism: Mechanism, run: Run, outs: Outputs, order: int
) -> tuple[list[Panel], str]:
    panels, what = _point_panels(mechanism, run, order)
    panels += _rate_panels(run, outs, order, _colors(len(outs.quantities) + 2)[2:])
    if outs.single:
        what.append(
            f"output {outs.symbol}'s {'velocity' if order == 1 else 'acceleration'} ratio "
            f"({'ω' if order == 1 else 'ε'}_out/ω_in{'' if order == 1 else '²'} at constant "
            "input speed)"
        )
    else:
        what.append(f"{'first' if order == 1 else 'second'} derivative of each link's position")
    return panels, "; ".join(what)


def _paper003(mechanism: Mechanism) -> dict[str, float] | None:
    """Paper 003's normalisation of the output's analogues, where it applies (else None).

    Crank-rocker (input turns, output rocks through Ψ while the crank turns φΨ): Kω = φ3′·φΨ/Ψ,
    Kε = φ3″·φΨ²/Ψ (eq. 3); double crank: Kω = φ3′, Kε = 2π·φ3″. The slider-crank takes its
    stroke for Ψ. The scales and exact maxima are :func:`linkwright.analysis.coefficients`'.
    """
    if not isinstance(mechanism, FourBar | SliderCrank | SphericalFourBar):
        return None
    # A double crank has no φΨ: its time ratio divides by zero inside, harmlessly (NaN).
    with np.errstate(divide="ignore", invalid="ignore"):
        co = {k: float(v) for k, v in coefficients(mechanism).items()}
    if not math.isfinite(co["K_omega"]):
        return None
    if math.isfinite(co["phi_psi"]):
        phi, psi = co["phi_psi"], co["psi"]
        co["scale1"], co["scale2"] = phi / psi, phi**2 / psi
        co["double"] = 0.0
    else:
        co["scale1"], co["scale2"] = 1.0, 2.0 * math.pi
        co["double"] = 1.0
    return co


def coefficient_panels(
    mechanism: Mechanism, run: Run, outs: Outputs
) -> tuple[list[Panel], str, bool]:
    """Paper 003's Kω, Kε, Kp where they apply (third item True), else the analogues."""
    motions = [c.motion for c in run.circuits]
    co = _paper003(mechanism)
    if co is None:
        panels = []
        colors = _colors(len(outs.quantities))
        for order in (1, 2):
            panels += _rate_panels(run, outs, order, colors, analogue=True)
        if outs.single:
            why = (
                "the input does not turn fully, so paper 003's Kω, Kε (defined over a crank's "
                "turn) do not apply: "
                if isinstance(mechanism, FourBar | SliderCrank | SphericalFourBar)
                else ""
            )
            what = f"{why}kinematic analogues {outs.symbol}′ = d{outs.symbol}/dθ and " + (
                f"{outs.symbol}″ = d²{outs.symbol}/dθ² of the output"
            )
        elif isinstance(mechanism, DoubleSlider):
            what = "no output link: the sliders' travel rates t′ = dt/dθ and t″ = d²t/dθ²"
        else:
            what = (
                "no single output link: kinematic analogues ψ′ = dψ/dθ and ψ″ = d²ψ/dθ² of each "
                "moving link relative to the input"
            )
        return panels, what, False

    q = outs.quantities[0]
    slider = isinstance(mechanism, SliderCrank)
    sym = "s" if slider else "φ3"
    unit1 = "length/rad" if slider else "rad/rad"
    unit2 = "length/rad²" if slider else "rad/rad²"
    w = run.closed([q.rates(m)[0] for m in motions])
    e = run.closed([q.rates(m)[1] for m in motions])
    s1, s2 = co["scale1"], co["scale2"]
    k_w = [s1 * a for a in w]
    k_e = [s2 * a for a in e]
    k_p = [a * b for a, b in zip(k_w, k_e, strict=True)]
    double = bool(co["double"])
    if double:
        defs = ("Kω = φ3′", "Kε = 2π·φ3″", "Kp = Kω·Kε")
    else:
        big = "stroke" if slider else "Ψ"
        defs = (f"Kω = {sym}′·φΨ/{big}", f"Kε = {sym}″·φΨ²/{big}", "Kp = Kω·Kε")
    maxima = ("K_omega", "K_epsilon", "K_p")
    panels = []
    for values, d, key, color, raw, scale in (
        (k_w, defs[0], maxima[0], PALETTE[0], f"{sym}′ ({unit1})", s1),
        (k_e, defs[1], maxima[1], PALETTE[1], f"{sym}″ ({unit2})", s2),
        (k_p, defs[2], maxima[2], PALETTE[2], f"{sym}′·{sym}″ ({unit1} · {unit2})", s1 * s2),
    ):
        name = d.split(" = ")[0]
        top = co[key]
        extra = [f"max |{name}| = {num_text(top)} (exact, paper 003 eq. 4)"]
        if key == "K_omega" and double:
            extra.append(f"δ = max φ3′ − min φ3′ = {num_text(co['delta'])}")
        panel = Panel(
            f"{d} (dimensionless)",
            [Series(name, values, color)],
            ideal=0.0,
            ideal_label="_zero",
            extra=extra,
            secondary=None if scale == 1.0 else (scale, raw),
        )
        panels.append(panel)
    if double:
        what = (
            "paper 003's coefficients of the output (double crank: Kω = φ3′, Kε = 2π·φ3″, "
            "eqs. 3–4 and after eq. 7)"
        )
    else:
        span = "stroke" if slider else "Ψ"
        psi = num_text(co["psi"]) if slider else f"{deg_text(math.degrees(co['psi']))}°"
        what = (
            f"paper 003's coefficients of the output (eq. 3), φΨ = "
            f"{deg_text(math.degrees(co['phi_psi']))}°, {span} = {psi}; right axes: the analogues"
        )
    return panels, what, True
