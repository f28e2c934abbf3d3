"""Results as people read them: plain JSON values, degrees and sentences.

The analyses return typed results in radians (:mod:`linkwright.analysis.results`); the command
line and the workbench show them through this module, so both say the same thing the same way.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from linkwright.analysis.results import (
    Analysis,
    Coefficients,
    DyadLimit,
    Extremes,
    FourBarAnalysis,
    GeneralAnalysis,
    PressureComponents,
    TriadLimit,
)

__all__ = ["LOCKING_NOTE", "analysis_report", "json_text", "jsonable", "table_lines"]


def jsonable(value: Any) -> Any:
    """Plain JSON values: numpy scalars and arrays unwrapped, NaN and infinities as null.

    Examples
    --------
    >>> import numpy as np
    >>> jsonable({"a": np.int64(2), "b": np.array([1.0, np.nan]), "c": (1, "x")})
    {'a': 2, 'b': [1.0, None], 'c': [1, 'x']}
    """
    if isinstance(value, Mapping):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, str | bool) or value is None:
        return value
    if isinstance(value, int):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if hasattr(value, "tolist"):  # numpy scalar or array
        return jsonable(value.tolist())
    if isinstance(value, list | tuple):
        return [jsonable(v) for v in value]
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    return str(value)


def json_text(obj: Any) -> str:
    """One line of strict JSON (no NaN), ending in a newline."""
    return json.dumps(jsonable(obj), allow_nan=False, ensure_ascii=False) + "\n"


# --------------------------------------------------------------------------------------------
# Analyses: degrees and words
# --------------------------------------------------------------------------------------------


def _number(x: float | None, digits: int = 12) -> float | None:
    """A reported number: rounded to 12 digits (what the analyses can vouch for), ``None`` for
    a value the motion does not have."""
    if x is None:
        return None
    v = float(x)
    return round(v, digits) if math.isfinite(v) else None


def _degrees(x: float | None) -> float | None:
    return None if x is None else _number(np.degrees(float(x)))


def _wrap(x: float | None) -> float | None:
    """An angle (radians) in degrees wrapped to (−180, 180]."""
    if x is None or not math.isfinite(x):
        return None
    # + 0.0 turns the −0.0 that the wrap gives for 0° into 0.0.
    return _number(-(((-np.degrees(x)) + 180.0) % 360.0 - 180.0) + 0.0)


def _arcs_deg(arcs: Sequence[tuple[float, float]], ref: float) -> list[list[float | None]]:
    """Input arcs in degrees measured from the direction ``ref`` (radians), each start wrapped
    to (−180, 180] and its end the start plus the arc's width."""
    out: list[list[float | None]] = []
    for lo, hi in arcs:
        start = _wrap(lo - ref)
        width = _number(np.degrees(hi - lo))
        out.append([start, None if start is None or width is None else width + start])
    return out


def _coefficients(c: Coefficients) -> dict[str, float | None]:
    return {
        "K_omega": _number(c.K_omega),
        "K_epsilon": _number(c.K_epsilon),
        "K_p": _number(c.K_p),
        "delta": _number(c.delta),
    }


def analysis_report(result: Analysis) -> dict[str, Any]:
    """``linkwright analyze``'s report of an analysis: degrees, JSON-ready, in its key order.

    Angles are absolute, as ``solve``, ``curve`` and ``plot`` take them: the input θ is the
    direction of A − A0 counter-clockwise from +x, the output the direction of B − B0. Paper
    003 measures both from the frame line A0→B0 (for a slider-crank: from the slider's line
    direction); the ``*_from_frame_deg`` keys give them so, and ``reference_angle_deg`` is the
    frame line's own direction (absolute = from frame + reference).

    Paper 003's families (:class:`~linkwright.analysis.results.FourBarAnalysis`) give
    ``family``, ``class`` (``None`` when the linkage cannot be assembled at any input),
    ``assembles``, ``reason`` (when it does not), ``grashof`` (planar four-bar) or
    ``grashof_terms_deg`` (spherical), ``reference_angle_deg``, ``input_range_deg`` (``None``
    for a full turn), ``input_arcs_deg``, ``limit_positions_deg`` (each with its
    ``*_from_frame_deg`` twin), ``output_range_deg`` and ``swing_deg`` (four-bars),
    ``output_range`` and ``stroke`` (slider-crank, lengths), ``transmission_angle_deg``,
    ``pressure_angle_deg`` (90° − γ; on the sphere paper 003's ``normal`` and ``tangential``
    components with ``mu`` and ``mu_source``), ``time_ratio`` and ``coefficients``. Every other
    family (:class:`~linkwright.analysis.results.GeneralAnalysis`) gives ``period_turns``,
    ``input_turns_fully``, ``input_arcs_deg``, ``limit_positions``, ``transmission_angle_deg``
    per dyad, ``traced`` per traced joint and ``samples``, with ``locking`` (geared five-bar)
    and ``ellipse`` (double slider).

    Examples
    --------
    >>> from linkwright.analysis import analyze
    >>> from linkwright.mechanisms import FourBar
    >>> r = analysis_report(analyze(FourBar(A0=[0, 0], B0=[1, 0], crank=4, coupler=2,
    ...                                     rocker=13**0.5)))
    >>> r["class"], r["input_range_deg"], r["output_range_deg"]
    ('double-crank', None, None)
    >>> round(r["pressure_angle_deg"]["max"], 2)
    33.69
    >>> r = analysis_report(analyze(FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2,
    ...                                     rocker=3)))
    >>> r["class"], r["assembles"], r["swing_deg"], r["coefficients"]["K_omega"]
    (None, False, None, None)
    """
    if isinstance(result, GeneralAnalysis):
        return _general_report(result)
    return _fourbar_report(result)


def _fourbar_report(r: FourBarAnalysis) -> dict[str, Any]:
    report: dict[str, Any] = {"family": r.family, "class": r.kind}
    if r.spherical:
        report["grashof_terms_deg"] = [_degrees(f) for f in r.grashof_terms or ()]
    report["assembles"] = r.assembles
    report["reference_angle_deg"] = _degrees(r.reference_angle)
    planar_fourbar = r.family == "fourbar"
    if planar_fourbar:
        report["grashof"] = _number(r.grashof)
    empty = {"min": None, "max": None, "min_at_input_deg": None, "max_at_input_deg": None}
    if not r.assembles:
        report["reason"] = r.reason
        for suffix in ("_deg", "_from_frame_deg"):
            report["input_range" + suffix] = None
            report["input_arcs" + suffix] = []
            report["limit_positions" + suffix] = []
        report["output_range_deg"] = report["output_range_from_frame_deg"] = None
        report["swing_deg"] = None
        report["time_ratio"] = None
        if r.spherical:
            report["transmission_angle_deg"] = dict(empty)
            report["pressure_angle_deg"] = _spherical_pressure(r, empty)
        else:
            report["transmission_angle_deg"] = {"min": None, "max": None}
            report["pressure_angle_deg"] = {"min": None, "max": None}
            if not planar_fourbar:
                report["output_range"] = None
                report["stroke"] = None
        report["coefficients"] = _coefficients(r.coefficients)
        return report
    ref = r.reference_angle
    for suffix, origin in (("_deg", 0.0), ("_from_frame_deg", ref)):
        found = _arcs_deg(r.input_arcs, origin)
        report["input_range" + suffix] = None if r.input_full else found[0]
        report["input_arcs" + suffix] = [] if r.input_full else found
        report["limit_positions" + suffix] = [a for arc in found for a in arc]
    if r.family == "slidercrank":
        lo, hi = r.slider_range or (None, None)
        report["output_range"] = [_number(lo), _number(hi)]
        report["stroke"] = None if lo is None or hi is None else _number(hi - lo)
        report["output_range_deg"] = report["output_range_from_frame_deg"] = None
        report["swing_deg"] = None
    elif r.output_range is None:
        report["output_range_deg"] = report["output_range_from_frame_deg"] = None
        report["swing_deg"] = None
    elif r.spherical:
        lo, hi = r.output_range
        report["output_range_deg"] = [_degrees(lo), _degrees(hi)]
        report["output_range_from_frame_deg"] = report["output_range_deg"]
        report["swing_deg"] = _degrees(hi - lo)
    else:
        lo, hi = r.output_range
        swing = _degrees(hi - lo)
        start = _wrap(lo + ref)
        end = None if start is None or swing is None else _number(start + swing)
        report["output_range_deg"] = [start, end]
        report["output_range_from_frame_deg"] = [_degrees(lo), _degrees(hi)]
        report["swing_deg"] = swing
    tx = r.transmission or Extremes(None, None)
    report["transmission_angle_deg"] = {
        "min": _degrees(tx.min),
        "max": _degrees(tx.max),
        "min_at_input_deg": _wrap(tx.min_at),
        "max_at_input_deg": _wrap(tx.max_at),
    }
    if r.spherical:
        report["pressure_angle_deg"] = _spherical_pressure(r, empty)
    else:
        report["pressure_angle_deg"] = {
            "min": None if tx.max is None else _number(90.0 - np.degrees(tx.max)),
            "max": None if tx.min is None else _number(90.0 - np.degrees(tx.min)),
        }
    report["time_ratio"] = _number(r.time_ratio)
    report["coefficients"] = _coefficients(r.coefficients)
    return report


def _spherical_pressure(r: FourBarAnalysis, empty: Mapping[str, None]) -> dict[str, Any]:
    """Paper 003's two pressure-angle components, each with the inputs of its extremes."""

    def where(x: float | None) -> float | None:
        # A flat extreme's value is exact but its input only to ~√eps (1e-6°): say no more.
        w = _wrap(x)
        if w is None:
            return None
        w = round(w, 5) + 0.0
        return 180.0 if w == -180.0 else w

    def part(e: Extremes | None) -> dict[str, Any]:
        if e is None:
            return dict(empty)
        return {
            "min": _degrees(e.min),
            "max": _degrees(e.max),
            "min_at_input_deg": where(e.min_at),
            "max_at_input_deg": where(e.max_at),
        }

    p = r.pressure or PressureComponents(None, "none", None, None)
    return {
        "normal": part(p.normal),
        "tangential": part(p.tangential),
        "mu": _number(p.mu),
        "mu_source": p.mu_source,
    }


def _general_report(r: GeneralAnalysis) -> dict[str, Any]:
    report: dict[str, Any] = {
        "family": r.family,
        "assembles": r.assembles,
        "period_turns": r.period_turns,
        "input_turns_fully": r.input_turns_fully,
        "input_arcs_deg": [[_degrees(lo), _degrees(hi)] for lo, hi in r.input_arcs],
        "limit_positions": [_limit(limit) for limit in r.limit_positions],
    }
    if r.circuits is not None:
        report["circuits"] = r.circuits
    if r.reason is not None:
        report["reason"] = r.reason
    report["transmission_angle_deg"] = {
        name: {"min": _degrees(e.min), "max": _degrees(e.max)} for name, e in r.transmission.items()
    }
    report["traced"] = {
        joint: {
            "path_length": _number(t.path_length),
            "speed_min": _number(t.speed_min),
            "speed_max": _number(t.speed_max),
        }
        for joint, t in r.traced.items()
    }
    report["samples"] = r.samples
    if r.locking is not None:
        lock = r.locking
        report["locking"] = {
            "oscillates": lock.oscillates,
            "locking_positions_deg": [_degrees(x) for x in lock.locking_positions],
            "note": LOCKING_NOTE if lock.oscillates else None,
            "repeats_after_turns": lock.repeats_after_turns,
        }
    if r.ellipse is not None:
        e = r.ellipse
        report["ellipse"] = {
            "center": [_number(c) for c in e.center],
            "semi_major": _number(e.semi_major),
            "semi_minor": _number(e.semi_minor),
            "orientation_deg": _degrees(e.orientation),
            "conic": dict(zip("ABCDEF", (_number(c) for c in e.conic), strict=True)),
            "kind": e.kind,
        }
    return report


LOCKING_NOTE = (
    "the dyad A–C–B cannot close beyond the locking positions; the linkage oscillates between "
    "them, as paper 002's tool does"
)


def _limit(limit: DyadLimit | TriadLimit) -> dict[str, Any]:
    if isinstance(limit, TriadLimit):
        return {
            "input_deg": _degrees(limit.input),
            "triad": limit.triad,
            "circuit": limit.circuit,
            "poses": list(limit.poses),
        }
    return {"input_deg": _degrees(limit.input), "dyad": limit.dyad}


def table_lines(data: Mapping[str, Any], indent: int = 0) -> list[str]:
    """A JSON-ready mapping as aligned ``key  value`` lines, nested mappings indented under
    their key (``-`` for a missing value, ``yes``/``no`` for booleans).

    Examples
    --------
    >>> print("\\n".join(table_lines({"class": None, "turns": True, "arc": {"lo": -0.0}})))
    class  -
    turns  yes
    arc:
      lo  0
    """
    lines: list[str] = []
    width = max((len(str(k)) for k in data), default=0)
    pad = " " * indent
    for key, value in data.items():
        if isinstance(value, Mapping):
            lines.append(f"{pad}{key}:")
            lines += table_lines(value, indent + 2)
        else:
            lines.append(f"{pad}{key:<{width}}  {_show_value(value)}")
    return lines


def _show_value(value: Any) -> str:
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value + 0.0:.6g}"  # + 0.0: no "-0"
    if isinstance(value, list):
        return "[" + ", ".join(_show_value(v) for v in value) + "]"
    return str(value)
