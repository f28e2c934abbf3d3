"""What the workbench draws over a linkage when asked: its joints' velocities and accelerations,
its instant centres (the sphere: instantaneous axes), and a summary of its analysis.

A scene (:func:`linkwright.server.scene.scene`) carries these only where its request asks
(``overlays``, ``summary``), so the redraw of a plain edit stays as fast as before:

- :func:`motion_json`: along every circuit of the document's own assembly mode, sample for
  sample with the scene's ``modes[own].circuits``, each joint's dP/dθ and d²P/dθ² (per unit input
  speed: the page multiplies by ω and ω² of the input speed it shows) and the instant centres
  (:func:`linkwright.analysis.instant_centres`), and the same at the scene's pose;
- :func:`summary_json`: the class, input range, limit positions and dead centres, time ratio,
  transmission- and pressure-angle extremes and paper 003's coefficients, as rows of text with
  their numbers (those of ``linkwright analyze --json``; the dead centres those ``linkwright
  plot`` marks). A family without a quantity shows "—"; an analysis that cannot be made says so
  in a note, never as an error.

Both are estimated (:func:`estimate`) with the scene, before any work starts.
"""

from __future__ import annotations

import copy
import math
import threading
from collections import OrderedDict
from collections.abc import Sequence
from typing import Any

import numpy as np
import orjson

from linkwright.analysis import analyze, instant_centres, rigid_bodies
from linkwright.analysis.extrema import CIRCUIT_SAMPLES
from linkwright.analysis.general import REPORT_SAMPLES
from linkwright.engine import cost
from linkwright.engine.circuits import InputArcs
from linkwright.engine.evaluate import Motion, evaluate
from linkwright.io.report import analysis_report
from linkwright.mechanisms import Mechanism, solve

__all__ = [
    "ALL_PAIRS_BODIES",
    "DASH",
    "FEATURE_SAMPLES",
    "estimate",
    "motion_json",
    "summary_json",
    "with_rates",
]

ALL_PAIRS_BODIES = 6
"""Linkages of at most this many bodies (the frame included: every four-bar and six-bar) get
the centres of every pair of bodies (15 for a six-bar); larger ones each body's centre relative
to the frame only (Jansen's leg has 28 pairs, too many to read on a drawing)."""

FEATURE_SAMPLES = 180
"""Samples of the circuit the dead centres are bracketed on (then refined exactly)."""

DASH = "—"
"""What a row shows where the family has no such quantity."""

_KEPT = 32
_summaries: OrderedDict[bytes, dict[str, Any]] = OrderedDict()
_summaries_lock = threading.Lock()  # the routes run in a thread pool


def _rows(a: Any, digits: int = 12) -> np.ndarray:
    return np.ascontiguousarray(np.round(np.asarray(a, dtype=float), digits))


# --------------------------------------------------------------------------------------------
# Cost
# --------------------------------------------------------------------------------------------


def estimate(
    mechanism: Mechanism, arcs: InputArcs, samples: int, *, overlays: bool, summary: bool
) -> tuple[cost.Estimate, float]:
    """The work of the overlays and the summary of the own mode (``arcs`` its input's) and the
    numbers they answer: the circuits placed again with derivatives, their centres, and the
    analyses' own circuits (paper 003's at 1,024 samples and the general one's at 2,048, counted
    as traces with derivatives; the dead centres' at 180)."""
    shape = cost.Shape.of_mechanism(mechanism)
    count = 0 if bool(arcs.never) else 1 if bool(arcs.full) else int(arcs.count)
    # A triad's configurations are followed: up to one circuit each, each sample a triad solve.
    triad = cost.TRIAD_UNITS.get(shape.space, 2000.0) if shape.poses > 1 else 0.0
    if triad:
        count = shape.poses
    full = bool(arcs.full)
    parts: list[cost.Estimate] = []
    numbers = 0.0
    if overlays and count:
        bodies = shape.joints + 1  # at most one body per step and the frame
        pairs = bodies * (bodies - 1) / 2 if bodies <= ALL_PAIRS_BODIES else bodies - 1
        per = count * samples
        parts.append(
            cost.Estimate(
                per * (shape.joints * 2.0 + pairs * 4.0 + triad),
                per * (shape.joints * shape.dim * 3 + pairs * 6) * 8.0 * 4,
                f"the velocities and instant centres of {count:,} circuit"
                f"{'s' if count != 1 else ''} of {samples:,} samples",
            )
        )
        numbers += per * (2 * shape.joints * shape.dim + pairs * (shape.dim + 2))
    if summary:
        analysis = max(CIRCUIT_SAMPLES, REPORT_SAMPLES)
        parts.append(cost.trace(shape, analysis, circuits=max(count, 1), full=full, order=2))
        parts.append(cost.trace(shape, FEATURE_SAMPLES, circuits=max(count, 1), full=full))
        numbers += 200.0
    if not parts:  # overlays of a linkage that never assembles: nothing to compute
        return cost.Estimate(0.0, 0.0, "no overlays"), numbers
    work = parts[0]
    for part in parts[1:]:
        work = work + part
    return work, numbers


# --------------------------------------------------------------------------------------------
# Velocities, accelerations and centres along the circuits
# --------------------------------------------------------------------------------------------


def with_rates(mechanism: Mechanism, motion: Motion) -> Motion:
    """The circuit's own samples placed again with derivatives, on the branches it ran."""
    return evaluate(
        mechanism.plan,
        mechanism.params(),
        motion.input,
        points=mechanism.points,
        branches=motion.branches or None,
        order=2,
    )


def _centres_json(mechanism: Mechanism, motion: Motion, pairs: str) -> dict[str, Any]:
    ic = instant_centres(mechanism, motion, pairs=pairs)
    return {
        "centres": _rows(ic.centre),
        "directions": None if ic.direction is None else _rows(ic.direction),
        "omega": _rows(ic.omega),
    }


def _one_json(mechanism: Mechanism, motion: Motion, pairs: str) -> dict[str, Any]:
    assert motion.velocities is not None and motion.accelerations is not None
    return {
        "velocity": {k: _rows(v) for k, v in motion.velocities.items()},
        "acceleration": {k: _rows(v) for k, v in motion.accelerations.items()},
        **_centres_json(mechanism, motion, pairs),
    }


def _typical(values: list[np.ndarray]) -> float | None:
    """A size to scale arrows by: the 95th percentile of the vectors' lengths (the few samples
    next to a limit position, where they grow without bound, do not set it)."""
    lengths = np.concatenate([np.linalg.norm(v, axis=-1).reshape(-1) for v in values] or [[]])
    lengths = lengths[np.isfinite(lengths)]
    if not lengths.size:
        return None
    size = float(np.percentile(lengths, 95))
    return size if size > 0 else None


def motion_json(
    mechanism: Mechanism, motions: Sequence[Motion], at: float | None
) -> dict[str, Any]:
    """The velocities, accelerations and instant centres along the own mode's ``motions`` (the
    scene's circuits, traced without derivatives) and at the pose at ``at`` (degrees).

    Examples
    --------
    >>> from linkwright.io import load_example
    >>> from linkwright.mechanisms import circuit
    >>> fb = load_example("crank-rocker").mechanism
    >>> out = motion_json(fb, [circuit(fb, 8, order=0)], 30.0)
    >>> out["labels"], [b["name"] for b in out["bodies"]]
    (['I12', 'I13', 'I14', 'I23', 'I24', 'I34'], ['frame', 'A0–A', 'A–B–P', 'B0–B'])
    >>> out["circuits"][0]["velocity"]["A"].shape, out["pose"]["centres"].shape
    ((8, 2), (6, 2))
    """
    bodies = rigid_bodies(mechanism)
    pairs = "all" if len(bodies) <= ALL_PAIRS_BODIES else "frame"
    n = len(bodies)
    index = [(i, j) for i in range(n) for j in range(i + 1, n) if pairs == "all" or i == 0]
    many = n > 9
    circuits = []
    speeds: list[np.ndarray] = []
    accels: list[np.ndarray] = []
    for motion in motions:
        cost.check_time()
        full = with_rates(mechanism, motion)
        assert full.velocities is not None and full.accelerations is not None
        speeds += list(full.velocities.values())
        accels += list(full.accelerations.values())
        circuits.append(_one_json(mechanism, full, pairs))
    pose = None
    if at is not None and math.isfinite(at):
        here = solve(mechanism, np.radians([at]), order=2)
        if bool(np.asarray(here.valid).all()):
            one = _one_json(mechanism, here, pairs)
            pose = {
                key: (
                    {k: v[0] for k, v in value.items()}
                    if isinstance(value, dict)
                    else (None if value is None else value[0])
                )
                for key, value in one.items()
            }
    return {
        "space": mechanism.plan.space,
        "bodies": [{"name": b.name, "joints": list(b.joints), "block": b.block} for b in bodies],
        "pairs": [list(p) for p in index],
        "labels": [f"I({i + 1},{j + 1})" if many else f"I{i + 1}{j + 1}" for i, j in index],
        "circuits": circuits,
        "pose": pose,
        "scale": {"velocity": _typical(speeds), "acceleration": _typical(accels)},
    }


# --------------------------------------------------------------------------------------------
# The analysis summary
# --------------------------------------------------------------------------------------------


def _deg(x: float | None, digits: int = 2) -> str:
    if x is None or not math.isfinite(x):
        return DASH
    return f"{x:.{digits}f}°".replace("-", "−")


def _num(x: float | None, digits: int = 4) -> str:
    if x is None or not math.isfinite(x):
        return DASH
    return f"{x:.{digits}g}".replace("-", "−")


def _row(key: str, label: str, text: str, value: Any = None) -> dict[str, Any]:
    return {"key": key, "label": label, "text": text or DASH, "value": value}


def _list(values: Sequence[float | None]) -> str:
    shown = [_deg(v) for v in values if v is not None]
    return "θ = " + ", ".join(shown) if shown else DASH


def _dead_centres(mechanism: Mechanism) -> list[float]:
    """The inputs (degrees) where the output link stops, as ``linkwright plot`` marks them."""
    from linkwright.plot.features import find_features

    feats = find_features(mechanism, FEATURE_SAMPLES, every=False, marks=True)
    return sorted(
        {round(math.degrees(m.theta), 9) for m in feats.marks if m.kind == "dead"},
    )


def _fourbar_rows(report: dict[str, Any]) -> list[dict[str, Any]]:
    rows = [_row("class", "Class", report.get("class") or DASH, report.get("class"))]
    if "grashof" in report:
        g = report["grashof"]
        kind = (
            DASH
            if g is None
            else "Grashof"
            if g < 0
            else "change point"
            if g == 0
            else "non-Grashof"
        )
        rows.append(_row("grashof", "Grashof", f"{kind} (s + l − p − q = {_num(g)}·l)", g))
    elif "grashof_terms_deg" in report:
        terms = report["grashof_terms_deg"]
        rows.append(_row("grashof", "Folding terms", ", ".join(_deg(t, 1) for t in terms), terms))
    rng = report.get("input_range_deg")
    arcs = report.get("input_arcs_deg") or []
    text = "turns fully" if report.get("assembles") and rng is None else DASH
    if arcs:
        text = "; ".join(f"[{_deg(a)}, {_deg(b)}]" for a, b in arcs)
    rows.append(_row("input_range", "Input range", text, rng))
    limits = report.get("limit_positions_deg") or []
    rows.append(_row("limits", "Limit positions", _list(limits), limits))
    if report.get("swing_deg") is not None:
        rows.append(_row("swing", "Output swing", _deg(report["swing_deg"]), report["swing_deg"]))
    if report.get("stroke") is not None:
        rows.append(_row("stroke", "Stroke", _num(report["stroke"]), report["stroke"]))
    ratio = report.get("time_ratio")
    rows.append(_row("time_ratio", "Time ratio", _num(ratio), ratio))
    tx = report.get("transmission_angle_deg") or {}
    text = DASH
    if tx.get("min") is not None:
        text = f"{_deg(tx['min'])} … {_deg(tx['max'])}"
        if tx.get("min_at_input_deg") is not None:
            text += f" (at θ = {_deg(tx['min_at_input_deg'])}, {_deg(tx['max_at_input_deg'])})"
    rows.append(_row("transmission", "Transmission angle", text, [tx.get("min"), tx.get("max")]))
    pa = report.get("pressure_angle_deg") or {}
    if "normal" in pa:  # the sphere: paper 003's two components at the hinge ratio μ
        parts = []
        for part in ("normal", "tangential"):
            e = pa[part]
            if e.get("min") is not None:
                parts.append(f"{part} {_deg(e['min'])} … {_deg(e['max'])}")
        text = "; ".join(parts) + (f" (μ = {_num(pa.get('mu'))})" if parts else "")
        value = [pa["normal"].get("max"), pa["tangential"].get("max")]
    else:
        text = DASH if pa.get("min") is None else f"{_deg(pa['min'])} … {_deg(pa['max'])}"
        value = [pa.get("min"), pa.get("max")]
    rows.append(_row("pressure", "Pressure angle", text, value))
    co = report.get("coefficients") or {}
    for key, label in (("K_omega", "Kω"), ("K_epsilon", "Kε"), ("K_p", "Kp"), ("delta", "δ")):
        rows.append(_row(key, label, _num(co.get(key)), co.get(key)))
    return rows


def _general_rows(report: dict[str, Any]) -> list[dict[str, Any]]:
    rows = [_row("class", "Class", DASH), _row("grashof", "Grashof", DASH)]
    arcs = report.get("input_arcs_deg") or []
    text = "turns fully" if report.get("input_turns_fully") else DASH
    if arcs and not report.get("input_turns_fully"):
        text = "; ".join(f"[{_deg(a)}, {_deg(b)}]" for a, b in arcs)
    if report.get("period_turns", 1) > 1:
        text += f" (repeats after {report['period_turns']} turns)"
    rows.append(_row("input_range", "Input range", text, arcs or None))
    limits = [lim["input_deg"] for lim in report.get("limit_positions") or []]
    rows.append(_row("limits", "Limit positions", _list(limits), limits))
    rows.append(_row("time_ratio", "Time ratio", DASH))
    tx = report.get("transmission_angle_deg") or {}
    shown = [
        f"{name} {_deg(e['min'])} … {_deg(e['max'])}"
        for name, e in tx.items()
        if e["min"] is not None
    ]
    value = {name: [e["min"], e["max"]] for name, e in tx.items()}
    rows.append(_row("transmission", "Transmission angle", "; ".join(shown), value))
    pressure = [
        f"{name} {_deg(90 - e['max'])} … {_deg(90 - e['min'])}"
        for name, e in tx.items()
        if e["min"] is not None
    ]
    rows.append(_row("pressure", "Pressure angle", "; ".join(pressure)))
    for key, label in (("K_omega", "Kω"), ("K_epsilon", "Kε"), ("K_p", "Kp"), ("delta", "δ")):
        rows.append(_row(key, label, DASH))
    return rows


def summary_json(mechanism: Mechanism) -> dict[str, Any]:
    """The analysis summary of one linkage (module docstring), kept for the last few linkages
    (an undo, a second look): ``rows`` of ``{key, label, text, value}``, the ``report`` of
    ``linkwright analyze --json`` and a ``note`` where part of it could not be made.

    Examples
    --------
    >>> from linkwright.io import load_example
    >>> s = summary_json(load_example("crank-rocker").mechanism)
    >>> [(r["label"], r["text"]) for r in s["rows"] if r["key"] in ("class", "K_omega", "delta")]
    [('Class', 'crank-rocker'), ('Kω', '1.796'), ('δ', '—')]
    >>> next(r["text"] for r in s["rows"] if r["key"] == "dead_centres")
    'θ = 73.38°, 286.58°'
    """
    key = orjson.dumps(
        {k: np.asarray(v).tolist() for k, v in mechanism.params().items()}
        | {"family": mechanism.family, "of": repr(mechanism)},
        option=orjson.OPT_SORT_KEYS,
    )
    with _summaries_lock:
        kept = _summaries.get(key)
        if kept is not None:
            _summaries.move_to_end(key)
            return copy.deepcopy(kept)
    notes = []
    report: dict[str, Any] | None = None
    try:
        report = analysis_report(analyze(mechanism))
    except ValueError as exc:  # no plan, no period, an analysis the family cannot have
        notes.append(f"analysis: {exc}")
    dead: list[float] = []
    try:
        dead = _dead_centres(mechanism)
    except ValueError as exc:
        notes.append(f"dead centres: {exc}")
    if report is None:
        rows = [
            _row(k, label, DASH)
            for k, label in (("class", "Class"), ("input_range", "Input range"))
        ]
    elif "coefficients" in report:
        rows = _fourbar_rows(report)
    else:
        rows = _general_rows(report)
    where = next((k for k, r in enumerate(rows) if r["key"] == "limits"), len(rows) - 1) + 1
    rows.insert(where, _row("dead_centres", "Dead centres", _list(dead), dead))
    if report is not None and not report.get("assembles", True):
        notes.append(report.get("reason") or "the linkage cannot be assembled at any input")
    out = {"rows": rows, "report": report, "note": "; ".join(notes) or None}
    with _summaries_lock:
        _summaries[key] = copy.deepcopy(out)
        while len(_summaries) > _KEPT:
            _summaries.popitem(last=False)
    return out
