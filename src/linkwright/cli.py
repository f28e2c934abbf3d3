"""The ``linkwright`` command line: solve, trace, analyse and demo mechanism documents.

Documents and the command line speak degrees; the engine speaks radians. Errors end the program
with status 2 and one line ``error: <message>`` on standard error, never a traceback. numpy and
the engine are imported inside the commands, so ``linkwright --help`` and ``--version`` start
fast.
"""

from __future__ import annotations

import json
import math
import os
import sys
import time
from collections.abc import Mapping, Sequence
from decimal import Decimal, InvalidOperation
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

try:  # typer ≥ 0.22 vendors click; older ones depend on it
    from typer._click import exceptions as click_exceptions
except ImportError:  # pragma: no cover - depends on the installed typer
    from click import exceptions as click_exceptions  # type: ignore[no-redef]

from linkwright import __version__

if TYPE_CHECKING:
    from linkwright.io import Document
    from linkwright.mechanisms import Mechanism

__all__ = ["CliError", "app", "main", "parse_inputs"]

# Samples a --input range may ask for: far beyond any useful table, well below running out of
# memory.
MAX_SAMPLES = 1_000_000
DEFAULT_INPUTS = [float(30 * k) for k in range(12)]


class CliError(Exception):
    """A problem with how the command was used; reported as ``error: <message>``, status 2."""


app = typer.Typer(
    name="linkwright",
    help="Kinematics workbench for planar and spherical linkages: solve, trace, analyse, draw "
    "and export mechanism documents.",
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
)


def _version_callback(value: bool) -> None:
    if value:
        sys.stdout.write(f"linkwright {__version__}\n")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[
        bool,
        typer.Option(
            "--version",
            help="Print the version and exit.",
            is_eager=True,
            callback=_version_callback,
        ),
    ] = False,
) -> None:
    """Kinematics workbench for planar and spherical linkages: solve, trace, analyse, draw and
    export mechanism documents.

    FILE is a .toml or .json mechanism document (or the name of a bundled example).
    """


# --------------------------------------------------------------------------------------------
# Helpers
# --------------------------------------------------------------------------------------------


def _decimal(text: str, what: str, *, angle: bool = False) -> Decimal:
    # ``what`` names an option (``--angles``) or a part of --input's range (``START``).
    where = f"{what}:" if what.startswith("--") else f"--input: {what}"
    try:
        value = Decimal(text.strip())
    except InvalidOperation:
        raise CliError(f"{where} must be a number, got {text.strip()!r}") from None
    if not value.is_finite() or not math.isfinite(float(value)):
        raise CliError(f"{where} must be a finite number, got {text.strip()!r}")
    _in_working_range(float(value), where, angle=angle)
    return value


def _in_working_range(value: float, where: str, *, angle: bool = False) -> None:
    """The documents' working range, for numbers given on the command line or in point files."""
    from linkwright.io.documents import WORKING_RANGE

    check = WORKING_RANGE.angle_problem if angle else WORKING_RANGE.size_problem
    if problem := check(value):
        raise CliError(f"{where} {problem}")


def parse_inputs(spec: str) -> list[float]:
    """Input angles (degrees) from ``START:STOP:STEP`` or a comma-separated list.

    A range includes STOP when it lands on the grid. Arithmetic is decimal, so ``0:1:0.1`` gives
    exactly the eleven numbers written, not ten with a rounding shortfall.

    Raises
    ------
    CliError
        For a malformed spec, a zero step, a step away from STOP, or too many samples.

    Examples
    --------
    >>> parse_inputs("0:90:30")
    [0.0, 30.0, 60.0, 90.0]
    >>> parse_inputs("0:100:30")
    [0.0, 30.0, 60.0, 90.0]
    >>> parse_inputs("10, -5.5,720")
    [10.0, -5.5, 720.0]
    """
    text = spec.strip()
    if not text:
        raise CliError("--input: empty; expected START:STOP:STEP or a comma list of degrees")
    if ":" in text:
        parts = text.split(":")
        if len(parts) != 3:
            raise CliError(f"--input: expected START:STOP:STEP, got {spec!r}")
        start, stop, step = (
            _decimal(p, w, angle=True)
            for p, w in zip(parts, ("START", "STOP", "STEP"), strict=True)
        )
        if step == 0:
            raise CliError("--input: STEP must not be zero")
        span = (stop - start) / step
        if span < 0:
            raise CliError(f"--input: STEP {step} goes away from STOP ({start} to {stop})")
        if span >= MAX_SAMPLES:
            raise CliError(f"--input: {spec!r} asks for more than {MAX_SAMPLES} samples")
        return [float(start + k * step) for k in range(int(span) + 1)]
    items = text.split(",")
    if len(items) > MAX_SAMPLES:
        raise CliError(f"--input: more than {MAX_SAMPLES} samples")
    return [float(_decimal(p, "each angle", angle=True)) for p in items]


def _load(file: str) -> Document:
    from linkwright.io import list_examples, load_document, load_example

    path = Path(file)
    if not path.exists() and not path.suffix and file in list_examples():
        return load_example(file)
    return load_document(path)


def _num(x: Any) -> float | None:
    """A plain float for JSON, or None where the value is missing (NaN)."""
    value = float(x)
    return value if math.isfinite(value) else None


def _xy(row: Any) -> list[float] | None:
    """A joint's coordinates as plain floats: [x, y] in the plane, the unit vector [x, y, z] on
    the sphere; None where it has none (NaN)."""
    values = [float(v) for v in row]
    return values if all(math.isfinite(v) for v in values) else None


def _axes(mech: Mechanism) -> str:
    return "xyz" if _structure(mech).space == "sphere" else "xy"


def _jsonable(value: Any) -> Any:
    """Plain JSON values: numpy scalars and arrays unwrapped, NaN and infinities as null."""
    if isinstance(value, Mapping):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, str | bool) or value is None:
        return value
    if isinstance(value, int):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if hasattr(value, "tolist"):  # numpy scalar or array
        return _jsonable(value.tolist())
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    return str(value)


def _dump(obj: Any) -> str:
    return json.dumps(_jsonable(obj), allow_nan=False, ensure_ascii=False) + "\n"


def _fmt(x: Any, width: int = 11, places: int = 6) -> str:
    if x is None:
        return "-".rjust(width)
    if isinstance(x, bool) or not isinstance(x, int | float):
        return str(x).rjust(width)
    if not math.isfinite(x):
        return "-".rjust(width)
    if abs(x) < 0.5 * 10.0**-places:
        x = 0.0  # no "-0.000000" for a coordinate that is zero up to rounding
    return f"{x:{width}.{places}f}"


def _signs(signs: Sequence[int]) -> str:
    return ",".join(f"{s:+d}" for s in signs)


def _heading(doc: Document) -> str:
    name = f"{doc.title} [{doc.family}]" if doc.title else f"[{doc.family}]"
    return f"# {name}" + (f", lengths in {doc.units}" if doc.units else "")


def _own_signs(mech: Mechanism) -> tuple[int, ...]:
    import numpy as np

    params = mech.params()
    return tuple(int(np.asarray(params[d.branch])) for d in mech.plan.dyads)


def _structure(mech: Mechanism) -> Any:
    """The mechanism's plan as a structure (its joints and links), whatever drives it.

    A Stephenson III driven at its output has no construction plan to evaluate, but its family's
    plan still says which joints are ground pivots.
    """
    from linkwright.mechanisms.sixbar import NoConstructionPlan

    try:
        return mech.plan
    except NoConstructionPlan:
        return type(mech).plan


def _output_driven(mech: Mechanism) -> bool:
    """Driven so that a triad remains: the planar Stephenson III at its output link D0D, the
    spherical one at FG."""
    return getattr(mech, "input", "crank") in ("output", "FG")


def _ground_joints(mech: Mechanism) -> tuple[str, ...]:
    from linkwright.engine import Fixed

    fixed = {s.name for s in _structure(mech).steps if isinstance(s, Fixed)}
    return tuple(j for j in mech.reported_joints if j in fixed)


def unassembled_reason(mech: Mechanism, theta: float) -> str:
    """Why the mechanism cannot be assembled at input ``theta`` (radians): the sentence of the
    first step that fails where its parents are placed (the step kind's ``unassembled``).

    Examples
    --------
    >>> from linkwright.mechanisms import FourBar
    >>> far = FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3)
    >>> head, why = unassembled_reason(far, 0.0).split(": ", 1)
    >>> head
    'cannot be assembled at this input'
    >>> why
    'the coupler and rocker cannot reach (dyad B: |A B0| = 9 > coupler + rocker = 5)'
    """
    head = "cannot be assembled at this input"
    why = mech.plan.unassembled(mech.params(), theta, points=mech.points)
    return head if why is None else f"{head}: {why}"


# --------------------------------------------------------------------------------------------
# Commands
# --------------------------------------------------------------------------------------------

FileArg = Annotated[
    str,
    typer.Argument(
        metavar="FILE",
        help="Mechanism document (.toml or .json), or the name of a bundled example.",
        show_default=False,
    ),
]
JsonOpt = Annotated[bool, typer.Option("--json", help="Print JSON instead of text.")]


@app.command()
def solve(
    file: FileArg,
    inputs: Annotated[
        str | None,
        typer.Option(
            "--input",
            "-i",
            metavar="SPEC",
            help="Input angles in degrees: START:STOP:STEP (STOP included when on the grid) or a "
            "comma list. Default: 0 to 330 every 30.",
            show_default=False,
        ),
    ] = None,
    all_: Annotated[
        bool,
        typer.Option("--all", help="Every real assembly configuration, not only the document's."),
    ] = False,
    derivatives: Annotated[
        bool,
        typer.Option(
            "--derivatives", help="Add each joint's velocity and acceleration, per radian of input."
        ),
    ] = False,
    as_json: JsonOpt = False,
) -> None:
    """Joint positions at the given input angles."""
    degrees = parse_inputs(inputs) if inputs is not None else list(DEFAULT_INPUTS)
    doc = _load(file)
    from linkwright.cli_budget import solve_chunk, stream_solve

    # Checked against the budget first, then computed and written a chunk of inputs at a time:
    # memory stays bounded by the chunk, however many rows were asked for.
    chunk = solve_chunk(doc, len(degrees), all_configurations=all_, derivatives=derivatives)
    stream_solve(
        degrees,
        chunk,
        lambda part: solve_document(doc, part, all_configurations=all_, derivatives=derivatives),
        lambda result: _solve_text(doc, result, derivatives),
        _jsonable,
        sys.stdout,
        as_json=as_json,
    )


def solve_document(
    doc: Document,
    degrees: Sequence[float],
    *,
    all_configurations: bool = False,
    derivatives: bool = False,
) -> dict[str, Any]:
    """The ``solve`` command's JSON-ready result for a document at inputs in degrees."""
    import numpy as np

    from linkwright.mechanisms import configurations, solve

    mech = doc.mechanism
    theta = np.radians(np.asarray(degrees, dtype=float))
    order = 2 if derivatives else 0
    if _output_driven(mech):
        return _solve_triad(doc, degrees, theta, derivatives, own=not all_configurations)
    if all_configurations and not derivatives and doc.family == "spherical-stephenson3":
        # Paper 001's analysis: every configuration with its error against every constraint.
        return _solve_triad(doc, degrees, theta, derivatives, own=False)
    if all_configurations:
        motions = configurations(mech, theta, order=order)
    else:
        motions = [(_own_signs(mech), solve(mech, theta, order=order))]
    joints = mech.reported_joints
    samples = []
    for i, deg in enumerate(degrees):
        found = []
        for signs, m in motions:
            if not bool(m.valid[..., i]):
                continue
            entry: dict[str, Any] = {
                "assembly": [int(s) for s in signs],
                "joints": {j: _xy(m.positions[j][..., i, :]) for j in joints},
            }
            if derivatives:
                entry["velocity"] = {j: _xy(m.velocities[j][..., i, :]) for j in joints}
                entry["acceleration"] = {j: _xy(m.accelerations[j][..., i, :]) for j in joints}
            found.append(entry)
        sample: dict[str, Any] = {"input_deg": float(deg), "configurations": found}
        if not found:
            sample["reason"] = unassembled_reason(mech, float(theta[i]))
        samples.append(sample)
    return {"family": doc.family, "samples": samples}


def _solve_triad(
    doc: Document, degrees: Sequence[float], theta: Any, derivatives: bool, *, own: bool
) -> dict[str, Any]:
    """The real configurations of a Stephenson III, each verified against every constraint:
    where its input leaves a triad, and for ``solve --all`` on the spherical one (paper 001's
    configuration analysis). With ``own``, only the document's configuration (see
    :data:`TRIAD_RULE`)."""
    import numpy as np

    from linkwright.engine import evaluate
    from linkwright.mechanisms import solve_all

    mech = doc.mechanism
    found = solve_all(mech, theta)
    rates = None
    if derivatives:
        # Each configuration solved again on its own branches (a triad's pose index, a dyad's
        # sign), with the derivatives of its differentiated constraints.
        rates = evaluate(
            mech.plan,
            mech.params(),
            np.broadcast_to(np.asarray(theta)[:, None], found.valid.shape),
            points=mech.points,
            branches=found.branches,
            order=2,
        )
    pose = int(np.asarray(getattr(mech, "pose", 0)))
    triad = mech.plan.triads[0].name if mech.plan.triads else None
    joints = mech.reported_joints
    samples = []
    for i, deg in enumerate(degrees):
        entries = []
        for k in range(found.valid.shape[-1]):
            if not bool(found.valid[i, k]):
                continue
            entry: dict[str, Any] = {
                "assembly": [int(found.assembly[i, k]), int(found.assembly2[i, k])],
                "residual": float(found.residual[i, k]),
                "joints": {j: _xy(found.positions[j][i, k]) for j in joints},
            }
            if rates is not None:
                entry["velocity"] = {j: _xy(rates.velocities[j][i, k]) for j in joints}
                entry["acceleration"] = {j: _xy(rates.accelerations[j][i, k]) for j in joints}
            entries.append(entry)
        sample: dict[str, Any] = {"input_deg": float(deg), "configurations": entries}
        if own and triad is not None:
            # The document's configuration is its triad's pose index at this input (what the
            # plan solves, and what plot --at and the workbench show).
            mine = [
                e
                for k, e in zip(np.flatnonzero(found.valid[i]), entries, strict=True)
                if int(found.branches[triad][i, k]) == pose
            ]
            sample["configurations"] = mine
            if entries and not mine:
                sample["reason"] = (
                    f"the triad has {len(entries)} pose(s) at this input, no pose {pose} "
                    "(solve --all lists them)"
                )
        if not entries:
            sample["reason"] = unassembled_reason(mech, float(theta[i]))
        samples.append(sample)
    count = np.asarray(found.count)
    result: dict[str, Any] = {
        "family": doc.family,
        "input": mech.input,
        "max_configurations": int(count.max()) if count.size else 0,
    }
    if own and triad is not None:
        result["pose"] = pose
        result["rule"] = TRIAD_RULE[doc.family]
    result["samples"] = samples
    return result


# How `solve` without --all picks the document's configuration of a triad: its pose index, the
# one the plan solves. A name for one configuration at one input, stable (the same input gives
# the same answer) but not a branch followed continuously (curve and plot follow those).
TRIAD_RULE = {
    "stephenson3": (
        "the document's pose: the pose-th configuration at each input, in order of the "
        "coupler's angle (of B - A, from -180 to 180 degrees); solve --all lists every "
        "configuration"
    ),
    "spherical-stephenson3": (
        "the document's pose: the pose-th configuration at each input, in order of theta1 "
        "(angle BAD, from -180 to 180 degrees); solve --all lists every configuration"
    ),
}


def _solve_text(doc: Document, result: Mapping[str, Any], derivatives: bool) -> str:
    mech = doc.mechanism
    ground = _ground_joints(mech)
    moving = [j for j in mech.reported_joints if j not in ground]
    lines = [_heading(doc)]
    if ground:
        pivots = ", ".join(
            f"{j} = ({', '.join(_fmt(c, 0, 6) for c in xy)})"
            for j in ground
            if (xy := _ground_xy(mech, j)) is not None
        )
        lines.append(f"# ground pivots: {pivots}")
    if "rule" in result:
        lines.append(f"# driven so that a triad remains; shown: {result['rule']}")
    sections = [("joints", "positions")]
    if derivatives:
        sections += [
            ("velocity", "velocities, per radian of input"),
            ("acceleration", "accelerations, per radian of input"),
        ]
    axes = _axes(mech)
    header = f"{'input_deg':>10} {'assembly':>9} " + " ".join(
        f"{j + '.' + c:>11}" for j in moving for c in axes
    )
    for key, label in sections:
        lines += ["", f"# {label}", header]
        for sample in result["samples"]:
            deg = _fmt(sample["input_deg"], 10, 3)
            if not sample["configurations"]:
                lines.append(f"{deg} {'-':>9}  {sample['reason']}")
            for entry in sample["configurations"]:
                values = entry[key]
                cells = " ".join(
                    _fmt(None if values[j] is None else values[j][c])
                    for j in moving
                    for c in range(len(axes))
                )
                lines.append(f"{deg} {_signs(entry['assembly']):>9} {cells}")
    return "\n".join(lines) + "\n"


def _ground_xy(mech: Mechanism, joint: str) -> list[float] | None:
    import numpy as np

    from linkwright.engine import Fixed

    step = _structure(mech).step(joint)
    if not isinstance(step, Fixed):
        return None
    return _xy(np.asarray(mech.params()[step.at], dtype=float))


@app.command()
def curve(
    file: FileArg,
    points: Annotated[
        int,
        typer.Option(
            "--points",
            "-n",
            metavar="N",
            min=2,
            max=MAX_SAMPLES,
            help="Samples over the whole circuit.",
        ),
    ] = 360,
    spacing: Annotated[
        str,
        typer.Option(
            "--spacing",
            metavar="input|path",
            help="input: even steps of the input (sin² between limits); path: even steps "
            "along the path, which keeps every step short near a change point.",
        ),
    ] = "input",
    as_csv: Annotated[bool, typer.Option("--csv", help="Print CSV.")] = False,
    as_json: JsonOpt = False,
    every: Annotated[
        bool,
        typer.Option(
            "--all",
            help="Every circuit of every configuration (each assembly mode's; a triad's "
            "configurations followed through their limits), numbered in a circuit column.",
        ),
    ] = False,
) -> None:
    """The path of the traced point P over the whole closed circuit."""
    if as_csv and as_json:
        raise CliError("--csv and --json cannot be used together")
    from linkwright.engine.circuits import SPACINGS

    if spacing not in SPACINGS:
        raise CliError(f"--spacing: must be {' or '.join(SPACINGS)}, got {spacing!r}")
    doc = _load(file)
    from linkwright.cli_budget import check_trace

    if every or doc.mechanism.plan.triads:
        _check_followed(doc.mechanism, points)
    else:
        # The answer holds each sample as Python numbers, and again as text.
        check_trace(doc.mechanism, points, knob="--points", spacing=spacing, sample_bytes=400.0)
    result = curve_document(doc, points, spacing=spacing, every=every)
    if as_json:
        sys.stdout.write(_dump(result))
        return
    pieces = result["circuits"] if every else [result]
    rows = [
        (k, deg, xy, asm)
        for k, piece in enumerate(pieces, start=1)
        for deg, xy, asm in zip(piece["input_deg"], piece["points"], piece["assembly"], strict=True)
    ]
    axes = _axes(doc.mechanism)
    if as_csv:
        from linkwright.io.exports import number_text

        out = [("circuit," if every else "") + f"input_deg,{','.join(axes)},assembly"]
        for k, deg, xy, asm in rows:
            cells = [""] * len(axes) if xy is None else [number_text(c) for c in xy]
            first = [str(k)] if every else []
            out.append(",".join([*first, number_text(deg), *cells, number_text(asm)]))
        sys.stdout.write("\n".join(out) + "\n")
        return
    if every:
        full = sum(p["full_turn"] for p in pieces)
        about = (
            f"# path of {result['joint']} over every circuit of every configuration: "
            f"{len(pieces)} circuit{'s' if len(pieces) != 1 else ''}, {full} turning fully"
        )
    else:
        turn = "turns fully" if result["full_turn"] else "rocks between its limits"
        about = f"# path of {result['joint']} over the closed circuit; the input {turn}"
    out = [_heading(doc), about]
    if len(axes) == 3:
        out.append("# on the unit sphere: each point is the unit vector of the joint's axis")
    head = f"{'input_deg':>10} " + " ".join(f"{c:>11}" for c in axes) + f" {'assembly':>9}"
    out.append(f"{'circuit':>7} {head}" if every else head)
    for k, deg, xy, asm in rows:
        cells = [None] * len(axes) if xy is None else xy
        line = f"{_fmt(deg, 10, 3)} {' '.join(_fmt(c) for c in cells)} {asm:>+9d}"
        out.append(f"{k:>7} {line}" if every else line)
    sys.stdout.write("\n".join(out) + "\n")


def _check_followed(mech: Mechanism, points: int, knob: str = "--points") -> None:
    """Refuse tracing every circuit of every configuration over the command line's budget."""
    from linkwright.engine import cost

    shape = cost.Shape.of_mechanism(mech)
    cost.check_combinations(shape)
    cost.with_knob(lambda n: cost.follow(shape, n), cost.CLI, points, 2, knob).check(cost.CLI)


def curve_document(
    doc: Document, points: int = 360, *, spacing: str = "input", every: bool = False
) -> dict[str, Any]:
    """The ``curve`` command's JSON-ready result: the traced point over the closed circuit
    (``every``: over every circuit of every configuration, each with its limit positions)."""
    import numpy as np

    from linkwright.io.documents import tidy_number
    from linkwright.mechanisms import circuit, circuits, input_range

    mech = doc.mechanism
    if every:
        return _every_curve(doc, points, spacing)
    if mech.plan.triads:
        # Its circuits are found together (none where it never assembles): the first.
        arcs, motions = circuits(mech, points, order=0, spacing=spacing)
        motion = motions[0] if motions else None
    else:
        arcs, motion = None, circuit(mech, points, order=0, spacing=spacing)
    if motion is None or not bool(np.any(motion.valid)):
        raise CliError(f"{doc.family}: the linkage cannot be assembled at any input")
    joint = mech.traced_joint
    # The first branching step's label: a dyad's sign, a triad's closure sign (both change
    # only at a limit position).
    first = next(iter(motion.labels), None)
    if first is not None:
        branch = np.broadcast_to(motion.labels[first], motion.input.shape)
    else:
        branch = np.ones(motion.input.shape)
    return {
        "family": doc.family,
        "joint": joint,
        "closed": True,
        "full_turn": bool(np.all((input_range(mech) if arcs is None else arcs).full)),
        "points": [_xy(p) for p in motion.positions[joint]],
        # Degrees as a person would write them: 30, not the 29.999999999999996 of a round trip.
        "input_deg": [tidy_number(float(d)) for d in np.degrees(motion.input)],
        "assembly": [int(b) for b in branch],
    }


def _every_curve(doc: Document, points: int, spacing: str) -> dict[str, Any]:
    """``curve --all``: every circuit of every configuration, followed by continuity through
    the limit positions where two configurations meet (a dyad's branches, a triad's poses)."""
    import numpy as np

    from linkwright.engine.circuits import input_turns
    from linkwright.engine.continuation import every_circuit
    from linkwright.io.documents import tidy_number

    mech = doc.mechanism
    params = mech.params()
    turns = int(np.max(input_turns(mech.plan, params, points=mech.points)))
    found = every_circuit(
        mech.plan,
        params,
        points,
        points=mech.points,
        order=0,
        period=2.0 * np.pi * turns,
        spacing=spacing,
    )
    if not found:
        raise CliError(f"{doc.family}: the linkage cannot be assembled at any input")
    joint = mech.traced_joint
    pieces = []
    for c in found:
        motion = c.motion
        first = next(iter(motion.labels), None)
        branch = motion.labels[first] if first is not None else np.ones(motion.input.shape)
        pieces.append(
            {
                "full_turn": c.full,
                "points": [_xy(p) for p in motion.positions[joint]],
                "input_deg": [tidy_number(float(d)) for d in np.degrees(motion.input)],
                "assembly": [int(b) for b in np.broadcast_to(branch, motion.input.shape)],
                # Where two configurations meet: the branch values (dyad signs, triad pose
                # indices) met before and after the turn, as the circuit runs.
                "limits": [
                    {
                        "input_deg": tidy_number(math.degrees(lim.input)),
                        "before": {k: int(v) for k, v in lim.before.items()},
                        "after": {k: int(v) for k, v in lim.after.items()},
                    }
                    for lim in c.limits
                ],
            }
        )
    return {"family": doc.family, "joint": joint, "closed": True, "circuits": pieces}


@app.command()
def analyze(
    file: FileArg,
    mu: Annotated[
        float | None,
        typer.Option(
            "--mu",
            metavar="RATIO",
            help="Spherical four-bar: hinge-radius ratio OB/OA for paper 003's pressure-angle "
            "components (default: the balanced ratio of its quadratic).",
            show_default=False,
        ),
    ] = None,
    as_json: JsonOpt = False,
) -> None:
    """Type, ranges, transmission angle, time ratio and coefficients of the mechanism.

    Angles are absolute, as solve, curve and plot take them (the input θ counter-clockwise from
    +x); the keys ending in _from_frame_deg measure them from the frame line, as paper 003 does.
    A linkage that never assembles has no class (null) and says why."""
    doc = _load(file)
    try:
        from linkwright.analysis import analyze as run_analysis
    except ImportError as exc:
        raise CliError(f"the analysis module is not available ({exc})") from None
    if mu is not None and doc.family != "spherical-fourbar":
        raise CliError(f"--mu: only a spherical-fourbar has a hinge-radius ratio ({doc.family})")
    if mu is not None and math.isfinite(mu) and mu > 0:
        from linkwright.io.documents import WORKING_RANGE

        if problem := WORKING_RANGE.ratio_problem(mu):
            raise CliError(f"--mu: {problem}")
    try:
        report = run_analysis(doc.mechanism) if mu is None else run_analysis(doc.mechanism, mu=mu)
    except ValueError as exc:
        raise CliError(str(exc)) from None
    result = _jsonable(report)
    if as_json:
        sys.stdout.write(_dump(result))
        return
    lines = [_heading(doc)]
    _table_lines(result, lines, indent=0)
    sys.stdout.write("\n".join(lines) + "\n")


def _table_lines(data: Mapping[str, Any], lines: list[str], indent: int) -> None:
    width = max((len(str(k)) for k in data), default=0)
    pad = " " * indent
    for key, value in data.items():
        if isinstance(value, Mapping):
            lines.append(f"{pad}{key}:")
            _table_lines(value, lines, indent + 2)
        else:
            lines.append(f"{pad}{key:<{width}}  {_show_value(value)}")


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


@app.command()
def demo(
    out: Annotated[
        Path, typer.Option("--out", metavar="DIR", help="Folder to write the demo's files into.")
    ] = Path("out"),
) -> None:
    """Run the bundled demonstration, writing its figures and tables into DIR."""
    try:
        from linkwright.demo import run_demo
    except ImportError as exc:
        raise CliError(f"the demo is not available ({exc})") from None
    result = run_demo(out)
    if result is None:
        return
    if isinstance(result, str | os.PathLike):
        sys.stdout.write(f"{os.fspath(result)}\n")
    elif isinstance(result, Mapping):
        lines: list[str] = []
        _table_lines(_jsonable(result), lines, 0)
        sys.stdout.write("\n".join(lines) + "\n")
    elif isinstance(result, list | tuple | set):
        sys.stdout.write("".join(f"{_jsonable(item)}\n" for item in result))
    else:
        sys.stdout.write(f"{result}\n")


@app.command()
def serve(
    port: Annotated[
        int, typer.Option("--port", min=1, max=65535, help="TCP port to listen on.")
    ] = 8000,
    host: Annotated[
        str,
        typer.Option(
            "--host",
            help="Address to listen on. The default serves this machine only; another "
            "address (0.0.0.0: every interface) lets other machines reach the workbench, "
            "which then asks for the token printed at start.",
        ),
    ] = "127.0.0.1",
    data_dir: Annotated[
        Path | None,
        typer.Option(
            "--data-dir",
            metavar="DIR",
            help="Where the library of saved mechanisms and the atlases live (default: "
            "$LINKWRIGHT_DATA, else the user's data directory).",
        ),
    ] = None,
    no_token: Annotated[
        bool,
        typer.Option(
            "--no-token",
            help="Beyond loopback, serve without a token: anyone who can reach the address, "
            "and any web page a browser there opens, can read and change the library.",
        ),
    ] = False,
) -> None:
    """Start the browser workbench and print its address (stop it with Ctrl-C)."""
    try:
        from linkwright.server import LOOPBACK_HOSTS, create_app, default_data_dir
        from linkwright.server.runner import make_server
    except ImportError as exc:
        raise CliError(f"the workbench needs its web server packages ({exc})") from None
    import secrets

    root = data_dir if data_dir is not None else default_data_dir()
    local = _loopback(host)
    # On loopback, only the loopback names and the address itself may reach it (no DNS
    # rebinding from a page); beyond it, any name, but only with the token.
    hosts = (*LOOPBACK_HOSTS, host.strip("[]").lower()) if local else None
    token = None if local or no_token else secrets.token_urlsafe(24)
    try:
        application = create_app(root, allowed_hosts=hosts, token=token)
    except OSError as exc:
        raise CliError(f"--data-dir: cannot use {root}: {exc.strerror or exc}") from None
    except ValueError as exc:  # a file in the way that is not a library
        raise CliError(f"--data-dir: {exc}") from None
    _check_listen(host, port)
    shown = f"[{host}]" if ":" in host else host
    if not local and no_token:
        sys.stderr.write(
            f"warning: listening on {host} without a token: anyone who can reach this machine, "
            "and any web page a browser there opens, can read and change the library\n"
        )
    address = f"http://{shown}:{port}" + (f"/?token={token}" if token else "")
    state = application.state.library.state_note()
    sys.stdout.write(
        f"linkwright workbench on {address}  (library in {root}{state}; Ctrl-C stops it)\n"
    )
    sys.stdout.flush()
    server = make_server(application, host, port)
    try:
        server.run()
    except (OSError, SystemExit):
        raise CliError(f"--port: cannot listen on {host}:{port}") from None


def _loopback(host: str) -> bool:
    """Whether ``host`` names only this machine (every address it resolves to is loopback)."""
    import ipaddress
    import socket

    try:
        infos = socket.getaddrinfo(host, None, type=socket.SOCK_STREAM)
        return all(ipaddress.ip_address(info[4][0].split("%")[0]).is_loopback for info in infos)
    except (OSError, ValueError):
        return False


def _check_listen(host: str, port: int) -> None:
    """Refuse, in one line, an address the server could not listen on (uvicorn would log a
    traceback-like error and exit)."""
    import socket

    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    except socket.gaierror as exc:
        raise CliError(f"--host: cannot resolve {host!r}: {exc.strerror}") from None
    family, kind, proto, _, address = infos[0]
    with socket.socket(family, kind, proto) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            probe.bind(address)
        except OSError as exc:
            why = "another program is using that port" if exc.errno == 98 else exc.strerror
            raise CliError(f"--port: cannot listen on {host}:{port}: {why}") from None


# --------------------------------------------------------------------------------------------
# Pictures, animations and exports
# --------------------------------------------------------------------------------------------

PLOT_KINDS = ("linkage", "angles", "velocity", "acceleration", "coefficients")
PICTURE_SUFFIXES = (".png", ".svg", ".pdf")
AtOpt = Annotated[
    float | None,
    typer.Option(
        "--at",
        metavar="DEG",
        help="Input angle of the pose drawn, degrees (default: the circuit's first sample).",
        show_default=False,
    ),
]


def _suffix(out: Path, allowed: Sequence[str], what: str) -> None:
    if out.suffix.lower() not in allowed:
        raise CliError(f"--out: {what} are written as {', '.join(allowed)}; got {out.name!r}")


def _at(value: float | None) -> float | None:
    if value is None:
        return None
    if not math.isfinite(value):
        raise CliError(f"--at: must be a finite angle in degrees, got {value}")
    _in_working_range(value, "--at:", angle=True)
    return math.radians(value)


def _wrote(path: Path | str) -> None:
    sys.stdout.write(f"wrote {os.fspath(path)}\n")


@app.command()
def plot(
    file: FileArg,
    out: Annotated[
        Path | None,
        typer.Option(
            "--out",
            metavar="X.png|X.svg|X.pdf",
            help="Picture to write (default: FILE's name, with -KIND for a diagram, as .png).",
            show_default=False,
        ),
    ] = None,
    kind: Annotated[
        str,
        typer.Option(
            "--kind",
            metavar="KIND",
            help="linkage (the linkage, its curves, limit positions, dead centres and "
            "transmission-angle extremes), angles, velocity, acceleration or coefficients "
            "(diagrams against the input).",
        ),
    ] = "linkage",
    at: AtOpt = None,
    samples: Annotated[
        int, typer.Option("--samples", metavar="N", min=16, max=100_000, help="Samples.")
    ] = 720,
    quiet: QuietOpt = False,
) -> None:
    """Draw the linkage and its coupler curves, or a diagram of its motion against the input.

    Spherical linkages get a 3-D view of the sphere and a map projection of their curves.
    """
    if kind not in PLOT_KINDS:
        raise CliError(f"--kind: expected one of {', '.join(PLOT_KINDS)}; got {kind!r}")
    doc = _load(file)
    stem = Path(file).stem
    out = out or Path(f"{stem}.png" if kind == "linkage" else f"{stem}-{kind}.png")
    _suffix(out, PICTURE_SUFFIXES, "pictures")
    if kind != "linkage" and at is not None:
        raise CliError("--at: only the linkage picture shows a pose; leave it out for a diagram")
    from linkwright.cli_budget import check_drawing

    check_drawing(doc.mechanism, samples, knob="--samples", least=16, order=2)
    if doc.mechanism.plan.triads:
        _check_followed(doc.mechanism, samples, knob="--samples")
    from linkwright.plot import save_figure
    from linkwright.plot.diagrams import DiagramError, plot_diagram
    from linkwright.plot.view import PlotError, plot_mechanism

    try:
        if kind == "linkage":
            figure = plot_mechanism(doc.mechanism, at=_at(at), samples=samples, title=doc.title)
        else:
            figure = plot_diagram(doc.mechanism, kind, samples=samples, title=doc.title)
    except (PlotError, DiagramError) as exc:
        raise CliError(f"{file}: {exc}") from None
    _wrote(save_figure(figure, out))


@app.command()
def animate(
    file: FileArg,
    out: Annotated[
        Path,
        typer.Option("--out", metavar="X.gif|X.mp4", help="Animation to write (MP4 needs ffmpeg)."),
    ],
    frames: Annotated[
        int, typer.Option("--frames", metavar="N", min=2, max=5000, help="Frames per cycle.")
    ] = 120,
    fps: Annotated[int, typer.Option("--fps", metavar="N", min=1, max=120)] = 30,
    dpi: Annotated[int, typer.Option("--dpi", metavar="N", min=20, max=600)] = 100,
    quiet: QuietOpt = False,
) -> None:
    """Animate one cycle of the mechanism, its traced curves growing as it runs."""
    _suffix(out, (".gif", ".mp4"), "animations")
    doc = _load(file)
    from linkwright.cli_budget import check_animation

    check_animation(doc.mechanism, frames, dpi, gif=out.suffix.lower() == ".gif")
    from linkwright.plot.animation import AnimationError
    from linkwright.plot.animation import animate as render

    try:
        with _Progress("animating", quiet) as progress:
            path = render(
                doc.mechanism, out, frames=frames, fps=fps, dpi=dpi, title=doc.title,
                progress=progress,
            )  # fmt: skip
    except AnimationError as exc:
        raise CliError(f"{file}: {exc}") from None
    _wrote(path)


@app.command()
def export(
    file: FileArg,
    out: Annotated[
        Path,
        typer.Option(
            "--out",
            metavar="X.csv|X.svg|X.dxf",
            help="CSV: every joint's path over the circuit; SVG and DXF: the linkage at the "
            "pose and its coupler curves, in the document's units.",
        ),
    ],
    at: AtOpt = None,
    samples: Annotated[
        int, typer.Option("--samples", metavar="N", min=8, max=100_000, help="Curve samples.")
    ] = 360,
) -> None:
    """Export the mechanism's paths (CSV) or its drawing (SVG, DXF) for CAD."""
    _suffix(out, (".csv", ".svg", ".dxf"), "exports")
    doc = _load(file)
    from linkwright.cli_budget import check_drawing

    check_drawing(doc.mechanism, samples, knob="--samples", least=8)
    if doc.mechanism.plan.triads:
        _check_followed(doc.mechanism, samples, knob="--samples")
    from linkwright.io.exports import ExportError
    from linkwright.io.exports import export as write

    try:
        path = write(
            doc.mechanism, out, at=_at(at), samples=samples, units=doc.units, title=doc.title
        )
    except ExportError as exc:
        raise CliError(f"{file}: {exc}") from None
    _wrote(path)


PAPERS = {
    "000": "spherical coupler curves: Figs 6-8 in both assembly modes, both coupler-point methods",
    "001": "spherical Stephenson III: every assembly configuration, inputs AB and FG",
    "002": "geared five-bar: the original curve, its speed, the pivot-moving study",
    "003": "four-bar tables 1-4, planar and spherical, printed beside ours; the synthesis example",
    "004": "double slider: eqs. 3-5 and 9 checked on 10,000 random linkages",
    "errata": "print what linkwright found wrong in the papers (writes nothing)",
}


@app.command()
def papers(
    paper: Annotated[
        str,
        typer.Argument(
            metavar="ID", help="Which paper: " + ", ".join(PAPERS) + ".", show_default=False
        ),
    ],
    out: Annotated[
        Path, typer.Option("--out", metavar="DIR", help="Folder to write the files into.")
    ] = Path("papers"),
) -> None:
    """Regenerate a seed paper's tables and figures with linkwright's numbers beside the printed
    ones (ID = errata prints the errata page instead)."""
    import importlib

    key = paper.strip().lower()
    if key != "errata":
        key = key.zfill(3)
    if key not in PAPERS:
        raise CliError(f"unknown paper {paper!r} (known: {', '.join(PAPERS)})")
    if key == "errata":
        from linkwright.papers import errata

        sys.stdout.write(errata())
        return
    out.mkdir(parents=True, exist_ok=True)
    module = importlib.import_module(f"linkwright.papers.p{key}")
    written = module.reproduce(out)
    sys.stdout.write("".join(f"{path}\n" for path in written))
    sys.stdout.write("errata of every paper: linkwright papers errata\n")


# --------------------------------------------------------------------------------------------
# Synthesis
# --------------------------------------------------------------------------------------------

synth_app = typer.Typer(
    help="Synthesis: from an ellipse, a path, target values or precision points to a linkage.",
    no_args_is_help=True,
)
app.add_typer(synth_app, name="synth")

QuietOpt = Annotated[bool, typer.Option("--quiet", help="No progress bar.")]

# Points a point file may hold: far beyond any drawn curve, well below running out of memory.
MAX_POINTS = 100_000


def read_points(path: Path, columns: tuple[int, ...] = (2,)) -> list[list[float]]:
    """Rows of numbers from a CSV (comma, semicolon or whitespace separated) point file.

    A first line that is not numbers is a header and skipped; blank lines and lines starting
    with ``#`` are skipped. Every other row must hold as many finite numbers as one of
    ``columns`` says, all rows alike; anything else is a :class:`CliError` naming the line.
    """
    if not path.exists():
        raise CliError(f"{path}: no such file")
    if path.is_dir():
        raise CliError(f"{path}: is a folder, not a point file")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        raise CliError(f"{path}: not a text file (expected CSV rows of numbers)") from None
    rows: list[list[float]] = []
    width = None
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        cells = [c for c in stripped.replace(";", ",").replace(",", " ").split() if c]
        try:
            values = [float(c) for c in cells]
        except ValueError:
            if not rows and width is None:
                width = -1  # a header line: the next line starts the data
                continue
            raise CliError(f"{path}, line {number}: not numbers: {stripped!r}") from None
        if width is None or width == -1:
            width = len(values)
            if width not in columns:
                want = " or ".join(str(c) for c in columns)
                raise CliError(f"{path}, line {number}: {width} columns, expected {want}")
        elif len(values) != width:
            raise CliError(f"{path}, line {number}: {len(values)} columns, the rows above have "
                           f"{width}")  # fmt: skip
        if not all(math.isfinite(v) for v in values):
            raise CliError(f"{path}, line {number}: coordinates must be finite numbers")
        for v in values:
            _in_working_range(v, f"{path}, line {number}: a coordinate")
        rows.append(values)
        if len(rows) > MAX_POINTS:
            raise CliError(f"{path}: more than {MAX_POINTS} points")
    if not rows:
        raise CliError(f"{path}: no points in the file")
    return rows


class _Progress:
    """A progress bar on standard error for a library call that reports fractions done; only on
    a terminal (a log or a pipe gets no bar characters), and not with ``--quiet``."""

    def __init__(self, label: str, quiet: bool) -> None:
        self.label, self.quiet = label, quiet
        self.bar: Any = None
        self.done = 0

    def __enter__(self) -> _Progress:
        if not self.quiet and sys.stderr.isatty():
            self.bar = typer.progressbar(length=1000, label=self.label, file=sys.stderr)
            self.bar.__enter__()
        return self

    def __call__(self, fraction: float) -> None:
        if self.bar is None:
            return
        target = int(1000 * min(max(float(fraction), 0.0), 1.0))
        if target > self.done:
            self.bar.update(target - self.done)
            self.done = target

    def __exit__(self, *exc: Any) -> None:
        if self.bar is not None:
            self.bar.__exit__(*exc)


def _documents(value: Any) -> Any:
    """The synthesis reports with every mechanism replaced by its document."""
    from linkwright.io import mechanism_to_dict
    from linkwright.mechanisms import Mechanism

    if isinstance(value, Mechanism):
        return mechanism_to_dict(value)
    if isinstance(value, Mapping):
        return {k: _documents(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_documents(v) for v in value]
    return value


def _floats(text: str, what: str, count: int | None = None, *, angle: bool = False) -> list[float]:
    items = [t for t in text.replace(";", ",").split(",") if t.strip()]
    values = [float(_decimal(t.strip(), what, angle=angle)) for t in items]
    if count is not None and len(values) != count:
        raise CliError(f"{what}: expected {count} numbers, got {len(values)}")
    return values


@synth_app.command("ellipse")
def synth_ellipse(
    conic: Annotated[
        str | None,
        typer.Option(
            "--conic",
            metavar="A,B,C,D,E,F",
            help="Ellipse A·x² + B·xy + C·y² + D·x + E·y + F = 0 (any scale).",
        ),
    ] = None,
    points: Annotated[
        Path | None,
        typer.Option("--points", metavar="FILE.csv", help="Points to fit an ellipse to."),
    ] = None,
    family_samples: Annotated[
        int,
        typer.Option(
            "--family-samples",
            metavar="N",
            min=0,
            max=10_000,
            help="Members of the ∞² double-slider family to list.",
        ),
    ] = 0,
    circle: Annotated[
        str,
        typer.Option(
            "--circle",
            metavar="small|large",
            help="Which Cardan circle the family rolls: radius (a − b)/2 (paper 004's "
            "section 4) or (a + b)/2.",
        ),
    ] = "small",
    as_json: JsonOpt = False,
    quiet: QuietOpt = False,
) -> None:
    """Double sliders (elliptic trammels) tracing an ellipse (paper 004): the canonical one and
    members of a whole ∞² family, each as a document, with the traced curve's deviation.

    Every double slider tracing the ellipse rolls one of two Cardan circles, so the ∞²
    solutions come in two families (--circle)."""
    from linkwright.synthesis.ellipse import EllipseError, ellipse_synthesis

    if (conic is None) == (points is None):
        raise CliError("give the ellipse as --conic A,B,C,D,E,F or as --points FILE.csv")
    if circle not in ("small", "large"):
        raise CliError(f"--circle: must be small or large, got {circle!r}")
    coeffs = _floats(conic, "--conic", 6) if conic is not None else None
    pts = read_points(points) if points is not None else None
    try:
        with _Progress("double sliders", quiet or family_samples < 50) as progress:
            result = ellipse_synthesis(
                coeffs, pts, family_samples, circle=circle, progress=progress
            )
    except EllipseError as exc:
        raise CliError(str(exc)) from None
    result = _documents(result)
    if as_json:
        sys.stdout.write(_dump(result))
        return
    t = result["trammel"]
    out = [
        f"# ellipse: centre ({_fmt(t['X0']).strip()}, {_fmt(t['Y0']).strip()}), "
        f"axis angle {_fmt(t['beta_deg']).strip()} deg, semi-axes a = {_fmt(t['a']).strip()}, "
        f"b = {_fmt(t['b']).strip()}"
    ]
    if "fit" in result:
        f = result["fit"]
        out.append(f"# fitted to {f['count']} points: RMS distance {f['rms']:.3g}, "
                   f"max {f['max']:.3g}")  # fmt: skip
    out.append(f"canonical trammel: deviation {result['canonical']['deviation']:.2e} (of a)")
    out.append(_dumps_toml_mech(result["canonical"]["mechanism"]))
    for member in result["family"]:
        s1, s2 = member["slider_angles_deg"]
        out.append(f"family member ({result['circle']} circle), guides at {s1:g} and {s2:g} deg "
                   f"from the major axis: deviation {member['deviation']:.2e}")  # fmt: skip
    sys.stdout.write("\n".join(out) + "\n")


def _assignments(items: Sequence[str], what: str) -> dict[str, str]:
    """``name=value`` items (each may itself be a comma list) as a dict of strings."""
    out: dict[str, str] = {}
    for item in items:
        for part in [p for p in item.split(",") if p.strip()] if "=" in item else [item]:
            if "=" not in part:
                raise CliError(f"{what}: expected name=value, got {part!r}")
            name, value = (t.strip() for t in part.split("=", 1))
            if name in out:
                raise CliError(f"{what}: {name} given twice")
            out[name] = value
    return out


def _bounds(items: Sequence[str]) -> dict[str, tuple[float, float]]:
    """``--bound NAME=LOW:HIGH`` items as {name: (low, high)}, in the units given."""
    bounds: dict[str, tuple[float, float]] = {}
    for name, text in _assignments(items, "--bound").items():
        low, sep, high = text.partition(":")
        if not sep:
            raise CliError(f"--bound {name}: expected LOW:HIGH, got {text!r}")
        bounds[name] = (float(_decimal(low, "--bound")), float(_decimal(high, "--bound")))
    return bounds


@synth_app.command("targets")
def synth_targets(
    family: Annotated[
        str, typer.Option("--family", metavar="fourbar|spherical-fourbar", help="Family.")
    ],
    fix: Annotated[
        list[str],
        typer.Option(
            "--fix",
            metavar="LINK=VALUE[,…]",
            help="Fixed links (crank, coupler, rocker, frame); arcs in degrees.",
        ),
    ],
    free: Annotated[
        str, typer.Option("--free", metavar="LINK[,…]", help="The links to solve for.")
    ],
    target: Annotated[
        list[str],
        typer.Option(
            "--target",
            metavar="OUTPUT=VALUE",
            help="max_Kw, max_Ke, max_Kp, delta, time_ratio, swing, gamma_min, "
            "gamma_max (angles in degrees).",
        ),
    ],
    bound: Annotated[
        list[str] | None,
        typer.Option("--bound", metavar="LINK=LOW:HIGH", help="Search box of a free link."),
    ] = None,
    kind: Annotated[
        str | None,
        typer.Option("--kind", metavar="CLASS", help="Only this class, e.g. double-crank."),
    ] = None,
    grid: Annotated[
        int | None,
        typer.Option("--grid", metavar="N", min=3, max=400, help="Grid nodes per free link."),
    ] = None,
    tol: Annotated[float, typer.Option("--tol", metavar="T", min=0.0)] = 1e-9,
    as_json: JsonOpt = False,
    quiet: QuietOpt = False,
) -> None:
    """Every four-bar in the search box whose named outputs hit their target values (paper
    003's synthesis), with each solution's conditioning; least squares with more targets than
    free links."""
    from linkwright.synthesis.targets import TargetError, design_fourbar

    fixed = {k: float(_decimal(v, f"--fix {k}")) for k, v in _assignments(fix, "--fix").items()}
    goals = {
        k: float(_decimal(v, f"--target {k}")) for k, v in _assignments(target, "--target").items()
    }
    bounds = _bounds(bound or [])
    names = [n.strip() for n in free.split(",") if n.strip()]
    from linkwright.cli_budget import check_grid

    check_grid(family, grid, len(names), len(goals))
    try:
        with _Progress("searching", quiet) as progress:
            found = design_fourbar(
                family, fixed, names, goals, bounds=bounds or None, kind=kind, grid=grid,
                tol=tol, degrees=True, progress=progress,
            )  # fmt: skip
    except TargetError as exc:
        raise CliError(str(exc)) from None
    report = found.report()
    for entry, solution in zip(report["solutions"], found, strict=True):
        entry["mechanism"] = solution.mechanism
    report = _documents(report)
    if as_json:
        sys.stdout.write(_dump(report))
        return
    out = [f"# {len(report['solutions'])} solution(s) in the box; {report['evaluated']} grid "
           f"points evaluated"]  # fmt: skip
    for i, sol in enumerate(report["solutions"], start=1):
        units = report["units"]
        xs = ", ".join(f"{k} = {v:.6g} {units.get(k, '')}".rstrip() for k, v in sol["x"].items())
        vals = ", ".join(f"{k} = {v:.6g}" for k, v in sol["values"].items())
        out.append(f"solution {i}: {xs}; {vals}; residual {sol['residual']:.2e}, condition "
                   f"{sol['condition']:.3g}")  # fmt: skip
    sys.stdout.write("\n".join(out) + "\n")


@synth_app.command("reinsberg")
def synth_reinsberg(
    file: FileArg,
    solve_for: Annotated[
        str,
        typer.Option(
            "--solve",
            metavar="LINK",
            help="The link to solve for: crank, coupler, rocker or frame.",
        ),
    ],
    kind: Annotated[
        str | None,
        typer.Option("--kind", metavar="CLASS", help="Only a root of this class counts."),
    ] = None,
    as_json: JsonOpt = False,
) -> None:
    """Complete a four-bar to Reinsberg's optimal transmission (paper 003): the one length or
    arc that makes the extreme transmission angles sum to 180°."""
    import numpy as np

    from linkwright.mechanisms import FourBar, SphericalFourBar
    from linkwright.synthesis.reinsberg import (
        ReinsbergError,
        reinsberg_defect,
        reinsberg_mechanism,
    )

    doc = _load(file)
    mech = doc.mechanism
    if not isinstance(mech, FourBar | SphericalFourBar):
        raise CliError(f"reinsberg: a fourbar or spherical-fourbar document, not {mech.family}")
    try:
        done = reinsberg_mechanism(mech, solve_for, kind=kind)
    except (ReinsbergError, ValueError) as exc:
        raise CliError(str(exc)) from None
    value = float(np.asarray(getattr(done, solve_for)))
    arc = isinstance(mech, SphericalFourBar)
    result = {
        "before_deg": float(np.degrees(reinsberg_defect(mech))),
        "field": solve_for,
        "value": float(np.degrees(value)) if arc else value,
        "unit": "deg" if arc else "length",
        "after_deg": float(np.degrees(reinsberg_defect(done))),
        "mechanism": done,
    }
    result = _documents(result)
    if as_json:
        sys.stdout.write(_dump(result))
        return
    unit = " deg" if arc else ""
    sys.stdout.write(
        f"{solve_for} = {result['value']:.9g}{unit}: γ1 + γ2 − 180° goes from "
        f"{_fmt(result['before_deg'], 0, 6)} to {_fmt(result['after_deg'], 0, 9)} deg\n"
        + _dumps_toml_mech(result["mechanism"])
        + "\n"
    )


def _design_report(design: Any, index: tuple[int, ...] = ()) -> dict[str, Any]:
    """A precision design (one of a batch at ``index``) as plain values, angles in degrees."""
    import numpy as np

    from linkwright.mechanisms import FourBar

    mech = design.mechanism
    params = {k: np.asarray(v)[index] if np.ndim(v) > (1 if k in ("A0", "B0") else 0) else v
              for k, v in mech.params().items()}  # fmt: skip
    one = FourBar(**{k: params[k] for k in ("A0", "B0", "crank", "coupler", "rocker", "u", "v",
                                              "assembly")})  # fmt: skip
    out: dict[str, Any] = {
        "inputs_deg": np.degrees(np.asarray(design.inputs)[index]),
        "branches": np.asarray(design.branches)[index].astype(int),
        "branch_defect": bool(np.asarray(design.branch_defect)[index]),
        "order_defect": bool(np.asarray(design.order_defect)[index]),
        "mechanism": one,
    }
    if hasattr(design, "position_error"):
        out["position_error"] = float(np.max(np.asarray(design.position_error)[index]))
        out["angle_error_deg"] = float(np.degrees(np.max(np.asarray(design.angle_error)[index])))
    else:
        out["outputs_deg"] = np.degrees(np.asarray(design.outputs)[index])
        out["coefficients"] = np.asarray(design.coefficients)[index]
        out["error_deg"] = float(np.degrees(np.max(np.asarray(design.error)[index])))
    return out


def _design_text(report: Mapping[str, Any]) -> str:
    lines = ["inputs (deg): " + ", ".join(f"{v:.6g}" for v in report["inputs_deg"])]
    if report["branch_defect"]:
        lines.append("warning: branch defect (the positions need different assembly modes)")
    if report["order_defect"]:
        lines.append("warning: order defect (one sweep of the input does not meet them in order)")
    if "position_error" in report:
        lines.append(f"largest error: position {report['position_error']:.2e} (of the spread), "
                     f"angle {report['angle_error_deg']:.2e} deg")  # fmt: skip
    else:
        lines.append(f"largest output error: {report['error_deg']:.2e} deg")
    lines.append(_dumps_toml_mech(report["mechanism"]))
    return "\n".join(lines)


def _pairs(text: str, what: str, width: int = 2) -> list[list[float]]:
    rows = [r for r in text.replace("\n", ";").split(";") if r.strip()]
    return [_floats(r, what, width) for r in rows]


@synth_app.command("function")
def synth_function(
    pairs: Annotated[
        str,
        typer.Option(
            "--pairs",
            metavar="PHI,PSI;…",
            help="Three input/output angle pairs (deg, from the frame line).",
        ),
    ],
    frame: Annotated[float, typer.Option("--frame", metavar="D", help="Frame length.")] = 1.0,
    as_json: JsonOpt = False,
) -> None:
    """Freudenstein function generation: the four-bar whose rocker angle ψ follows the crank
    angle φ through three precision pairs."""
    import numpy as np

    from linkwright.synthesis.precision import PrecisionError, freudenstein

    rows = _pairs(pairs, "--pairs")
    if len(rows) != 3:
        raise CliError(f"--pairs: Freudenstein's method takes exactly 3 pairs, got {len(rows)}")
    if not (math.isfinite(frame) and frame > 0):
        raise CliError("--frame: must be a positive length")
    phi, psi = np.radians(np.array(rows).T)
    try:
        design = freudenstein(phi, psi, frame)
    except PrecisionError as exc:
        raise CliError(str(exc)) from None
    report = _documents(_design_report(design))
    if as_json:
        sys.stdout.write(_dump(report))
        return
    k = report["coefficients"]
    sys.stdout.write(f"Freudenstein K1 = {k[0]:.9g}, K2 = {k[1]:.9g}, K3 = {k[2]:.9g}\n"
                     + _design_text(report) + "\n")  # fmt: skip


@synth_app.command("motion")
def synth_motion(
    poses: Annotated[
        Path,
        typer.Option(
            "--poses",
            metavar="FILE.csv",
            help="Rows x, y, angle_deg: the coupler point and the body's angle.",
        ),
    ],
    circles: Annotated[
        str | None,
        typer.Option(
            "--circles",
            metavar="X1,Y1,X2,Y2",
            help="3 poses: the two moving pivots, in the first pose.",
        ),
    ] = None,
    beta2: Annotated[
        str | None,
        typer.Option(
            "--beta2",
            metavar="B1,B2",
            help="4 poses: the two dyads' β2 on the centre-point curve (deg).",
        ),
    ] = None,
    closure: Annotated[
        str, typer.Option("--closure", metavar="I,J", help="4 poses: each dyad's closure, 0 or 1.")
    ] = "0,0",
    pair: Annotated[
        int | None,
        typer.Option("--pair", metavar="K", min=0, help="5 poses: print only design K."),
    ] = None,
    as_json: JsonOpt = False,
) -> None:
    """Burmester motion generation: a four-bar guiding a body through 3, 4 or 5 poses. Four
    poses without --beta2 print the centre-point and circle-point curves as CSV."""
    import numpy as np

    from linkwright.synthesis.burmester import (
        burmester_fourbars,
        burmester_points,
        centre_point_curve,
        four_pose_fourbar,
    )
    from linkwright.synthesis.precision import PrecisionError, three_pose_fourbar

    rows = np.array(read_points(poses, (3,)))
    points, angles = rows[:, :2], np.radians(rows[:, 2])
    try:
        if len(rows) == 3:
            if circles is None:
                raise CliError("3 poses: give the moving pivots with --circles X1,Y1,X2,Y2")
            design = three_pose_fourbar(
                points, angles, np.reshape(_floats(circles, "--circles", 4), (2, 2))
            )
            report: Any = _design_report(design)
        elif len(rows) == 4:
            if beta2 is None:
                from linkwright.io.exports import number_text

                curves = centre_point_curve(points, angles)
                out = ["beta2_deg,closure,centre_x,centre_y,circle_x,circle_y"]
                for c in range(2):
                    for i in np.flatnonzero(curves.valid[c]):
                        g, m = curves.centres[c, i], curves.circles[c, i]
                        cells = (np.degrees(curves.beta2[i]), c, g[0], g[1], m[0], m[1])
                        out.append(",".join(number_text(v) for v in cells))
                sys.stdout.write("\n".join(out) + "\n")
                return
            b = np.radians(_floats(beta2, "--beta2", 2))
            ij = [int(v) for v in _floats(closure, "--closure", 2)]
            if any(v not in (0, 1) for v in ij):
                raise CliError("--closure: each must be 0 or 1")
            report = _design_report(four_pose_fourbar(points, angles, b, tuple(ij)))
        elif len(rows) == 5:
            found = burmester_points(points, angles)
            designs, pairs = burmester_fourbars(points, angles)
            count = len(pairs)
            if count == 0:
                raise CliError(
                    f"these 5 poses have {found.count} real Burmester point(s): no four-bar"
                )
            if pair is not None and pair >= count:
                raise CliError(f"--pair: there are {count} designs (0 … {count - 1})")
            chosen = range(count) if pair is None else [pair]
            report = {
                "burmester_points": int(found.count),
                "designs": [
                    {"pair": [int(v) for v in pairs[k]], **_design_report(designs, (k,))}
                    for k in chosen
                ],
            }
        else:
            raise CliError(f"--poses: 3, 4 or 5 poses, got {len(rows)}")
    except PrecisionError as exc:
        raise CliError(str(exc)) from None
    report = _documents(report)
    if as_json:
        sys.stdout.write(_dump(report))
        return
    if "designs" in report:
        text = [f"# {report['burmester_points']} real Burmester points"]
        for d in report["designs"]:
            text.append(f"## design with Burmester points {d['pair']}\n" + _design_text(d))
        sys.stdout.write("\n".join(text) + "\n")
    else:
        sys.stdout.write(_design_text(report) + "\n")


@synth_app.command("precision-path")
def synth_precision_path(
    points: Annotated[
        Path, typer.Option("--points", metavar="FILE.csv", help="Three points x, y.")
    ],
    crank: Annotated[
        str, typer.Option("--crank-rotations", metavar="A2,A3", help="From point 1 (deg).")
    ],
    coupler: Annotated[
        str, typer.Option("--coupler-rotations", metavar="B2,B3", help="Free choice (deg).")
    ],
    rocker: Annotated[
        str, typer.Option("--rocker-rotations", metavar="G2,G3", help="Free choice (deg).")
    ],
    as_json: JsonOpt = False,
) -> None:
    """Path generation with prescribed timing: the coupler point passes three points at given
    crank rotations (the coupler's and rocker's rotations are the free choices)."""
    import numpy as np

    from linkwright.synthesis.precision import PrecisionError, path_with_timing

    pts = np.array(read_points(points))
    if len(pts) != 3:
        raise CliError(f"--points: path generation with timing takes 3 points, got {len(pts)}")
    rot = [np.radians(_floats(t, w, 2)) for t, w in ((crank, "--crank-rotations"),
           (coupler, "--coupler-rotations"), (rocker, "--rocker-rotations"))]  # fmt: skip
    try:
        design = path_with_timing(pts, *rot)
    except PrecisionError as exc:
        raise CliError(str(exc)) from None
    report = _documents(_design_report(design))
    if as_json:
        sys.stdout.write(_dump(report))
        return
    sys.stdout.write(_design_text(report) + "\n")


@synth_app.command("path")
def synth_path(
    points: Annotated[
        Path,
        typer.Option(
            "--points",
            metavar="FILE.csv",
            help="Target points: rows x, y (x, y, z unit vectors on the sphere).",
        ),
    ],
    family: Annotated[
        str | None,
        typer.Option(
            "--family",
            metavar="F",
            help="Any family (fourbar, slidercrank, geared-fivebar, doubleslider, watt1, watt2, "
            "stephenson1, stephenson3, linkage, spherical-fourbar, spherical-sixbar, "
            "spherical-stephenson3); default the template's.",
        ),
    ] = None,
    angles: Annotated[
        str | None,
        typer.Option(
            "--angles",
            metavar="LIST",
            help="Crank angles (deg, from the frame line) at each point.",
        ),
    ] = None,
    free_timing: Annotated[
        bool, typer.Option("--free-timing", help="Unknown but monotonic input angles.")
    ] = False,
    no_timing: Annotated[
        bool, typer.Option("--no-timing", help="Nearest-point fit: no input angles at all.")
    ] = False,
    closed: Annotated[
        bool, typer.Option("--closed", help="The points lie on a closed curve.")
    ] = False,
    bound: Annotated[
        list[str] | None,
        typer.Option(
            "--bound",
            metavar="NAME=LOW:HIGH",
            help="Search bounds (lengths; arcs and angles in degrees).",
        ),
    ] = None,
    kind: Annotated[
        list[str] | None,
        typer.Option("--kind", metavar="CLASS", help="Allowed class(es), e.g. crank-rocker."),
    ] = None,
    full_turn: Annotated[
        bool, typer.Option("--full-turn", help="The input must turn fully.")
    ] = False,
    min_transmission: Annotated[
        float,
        typer.Option(
            "--min-transmission",
            metavar="DEG",
            min=0.0,
            max=90.0,
            help="Least transmission angle over the circuit.",
        ),
    ] = 0.0,
    seed: Annotated[int, typer.Option("--seed", metavar="N", min=0)] = 0,
    budget: Annotated[
        float, typer.Option("--budget", metavar="SECONDS", min=0.1, max=86_400.0)
    ] = 10.0,
    template: Annotated[
        str | None,
        typer.Option(
            "--template",
            metavar="FILE",
            help="A mechanism document: its family, structure and choices are kept and its "
            "numbers start the search (needed for --family linkage).",
        ),
    ] = None,
    as_json: JsonOpt = False,
    quiet: QuietOpt = False,
) -> None:
    """Path synthesis by optimisation: a global search over batched populations, then local
    least squares. Prints the error (sum of squared distances), the RMS and the mechanism."""
    import numpy as np

    from linkwright.synthesis.path import PathSynthesisError, fit_path
    from linkwright.synthesis.path_models import ModelError, model_for

    if sum((angles is not None, free_timing, no_timing)) > 1:
        raise CliError("give at most one of --angles, --free-timing and --no-timing")
    like = _load(template).mechanism if template is not None else None
    if family is None and like is None:
        raise CliError("--family: give a family, or a --template document to take it from")
    family = family if family is not None else like.family  # type: ignore[union-attr]
    if family == "linkage" and like is None:
        raise CliError(
            "--family linkage: a composed linkage's joints come from a document: give "
            "--template FILE (its structure is kept, its numbers are free)"
        )
    try:
        model = model_for(family, like)
    except ModelError as exc:
        raise CliError(str(exc)) from None
    timing = "prescribed" if angles is not None else "none" if no_timing else "free"
    pts = np.array(read_points(points, (2, 3)))
    given = np.radians(_floats(angles, "--angles", angle=True)) if angles is not None else None
    in_degrees = ANGLE_BOUNDS | set(getattr(model, "angles", ()))
    bounds = {
        name: (math.radians(lo), math.radians(hi))
        if name in in_degrees or model.space == "sphere"  # on the sphere: all angles
        else (lo, hi)
        for name, (lo, hi) in _bounds(bound or []).items()
    }
    constraints = {
        "classes": tuple(kind or ()),
        "full_turn": full_turn,
        "min_transmission": math.radians(min_transmission),
    }
    try:
        with _Progress("searching", quiet) as progress:
            fit = fit_path(
                family, pts, angles=given, timing=timing, closed=closed, bounds=bounds or None,
                constraints=constraints, seed=seed, budget=budget, progress=progress,
                template=like,
            )  # fmt: skip
    except PathSynthesisError as exc:
        raise CliError(str(exc)) from None
    # A family with a triad on the sphere stands in its paper's frame (no composed linkage
    # holds a triad): the rotation carries its curve onto the points.
    own_frame = fit.rotation is not None and fit.mechanism is fit.named
    result = _documents({
        "error": fit.error,
        "rms": fit.rms,
        **({"rotation": np.asarray(fit.rotation).tolist()} if own_frame else {}),
        "mechanism": fit.mechanism,
        "inputs_deg": np.degrees(fit.inputs),
        "angles_deg": np.degrees(fit.angles),
        "distances": fit.distances,
        "seconds": fit.elapsed,
        "evaluations": fit.evaluations,
        "stopped": fit.stopped,
    })  # fmt: skip
    if as_json:
        sys.stdout.write(_dump(result))
        return
    sys.stdout.write(
        f"error {fit.error:.6g} (sum of squared distances), RMS {fit.rms:.6g}; "
        f"{fit.evaluations} linkages in {fit.elapsed:.1f} s, stopped at the {fit.stopped}\n"
        + "inputs (deg): "
        + ", ".join(f"{v:.6g}" for v in result["inputs_deg"])
        + "\n"
        + (
            "in its paper's frame: the points are R·(its traced point), R = "
            + str(np.round(np.asarray(fit.rotation), 12).tolist())
            + "\n"
            if own_frame
            else ""
        )
        + _dumps_toml_mech(result["mechanism"])
        + "\n"
    )


# Path-synthesis bounds given in degrees on the command line.
ANGLE_BOUNDS = frozenset({"frame_angle", "gear_phase", "point_angle"})


def _dumps_toml_mech(document: Mapping[str, Any]) -> str:
    from linkwright.io.documents import dumps_toml

    return dumps_toml(document).rstrip()


# --------------------------------------------------------------------------------------------
# The curve atlas
# --------------------------------------------------------------------------------------------

atlas_app = typer.Typer(
    help="The curve atlas: build one, match a curve against it, describe it.",
    no_args_is_help=True,
)
app.add_typer(atlas_app, name="atlas")

AtlasFamilyOpt = Annotated[
    str,
    typer.Option("--family", metavar="F", help="fourbar, geared-fivebar or spherical-fourbar."),
]


@atlas_app.command("build")
def atlas_build(
    count: Annotated[int, typer.Option("--count", metavar="N", min=1, help="Mechanisms.")],
    out: Annotated[Path, typer.Option("--out", metavar="DIR", help="The atlas directory.")],
    family: Annotated[
        str | None,
        typer.Option(
            "--family",
            metavar="F",
            help="Any family (fourbar, geared-fivebar, spherical-fourbar with their own "
            "distributions; the others by their parameters); default the template's.",
        ),
    ] = None,
    seed: Annotated[int, typer.Option("--seed", metavar="S", min=0)] = 0,
    workers: Annotated[
        int | None,
        typer.Option(
            "--workers",
            metavar="N",
            min=0,
            help="Local Dask worker processes (0: this process). Default: one per core.",
        ),
    ] = None,
    scheduler: Annotated[
        str | None,
        typer.Option("--scheduler", metavar="ADDRESS", help="A running Dask scheduler."),
    ] = None,
    shard_size: Annotated[
        int, typer.Option("--shard-size", metavar="N", min=1, help="Mechanisms per shard.")
    ] = 65_536,
    samples: Annotated[
        int, typer.Option("--samples", metavar="N", min=8, help="Curve samples per turn.")
    ] = 64,
    template: Annotated[
        str | None,
        typer.Option(
            "--template",
            metavar="FILE",
            help="A mechanism document whose structure and choices the atlas keeps (needed "
            "for --family linkage; a Stephenson III's gives its input).",
        ),
    ] = None,
    as_json: JsonOpt = False,
    quiet: QuietOpt = False,
) -> None:
    """Sample a family's designs, keep those whose input turns fully, trace and describe their
    curves in shards (Dask tasks) and index them. A killed build resumes where it stopped."""
    from linkwright.atlas import AtlasBuildError, build

    like = _load(template).mechanism if template is not None else None
    if family is None and like is None:
        raise CliError("--family: give a family, or a --template document to take it from")
    family = family if family is not None else like.family  # type: ignore[union-attr]
    if family == "linkage" and like is None:
        raise CliError(
            "--family linkage: a composed linkage's joints come from a document: give "
            "--template FILE (its structure is kept, its numbers are drawn about its own)"
        )
    try:
        with _Progress("building", quiet) as progress:
            manifest = build(
                family, count, out, seed=seed, shard_size=shard_size, samples=samples,
                workers=workers, scheduler=scheduler, progress=progress, template=like,
            )  # fmt: skip
    except AtlasBuildError as exc:
        raise CliError(str(exc)) from None
    except KeyboardInterrupt:
        raise CliError(
            "interrupted: finished shards are kept; run the same command again to resume"
        ) from None
    if as_json:
        sys.stdout.write(_dump({"path": str(out), **manifest}))
        return
    sys.stdout.write(_atlas_summary(out, manifest))


def _atlas_summary(path: Path, manifest: Mapping[str, Any]) -> str:
    spec, index, figures = manifest["spec"], manifest["index"], manifest["build"]
    rate = figures["curves_computed"] / max(figures["seconds_shards"], 1e-9)
    probe = f", nprobe {index['nprobe']} of {index['nlist']} lists" if index["nlist"] else ""
    return (
        f"{path}: {spec['count']} {spec['family']} curves (seed {spec['seed']}) in "
        f"{len(manifest['shards'])} shards, {figures['bytes'] / 1e6:.1f} MB\n"
        f"index: {index['kind']}{probe}; recall@10 against exact search "
        f"{index['recall_at_10']:.3f} on {index['tuning_queries']} held-out curves\n"
        f"built {figures['curves_computed']} curves in {figures['seconds_shards']:.1f} s "
        f"({rate:.3g} curves/s), {figures['seconds_total']:.1f} s with the index; "
        f"{figures['shards_resumed']} shards resumed\n"
    )


@atlas_app.command("info")
def atlas_info(
    directory: Annotated[Path, typer.Argument(metavar="DIR", help="An atlas directory.")],
    quick: Annotated[
        bool,
        typer.Option(
            "--quick",
            help="Check the files against the manifest by their digest files and headers only, "
            "without re-hashing every shard (which reads the whole atlas).",
        ),
    ] = False,
    as_json: JsonOpt = False,
) -> None:
    """What an atlas holds: family, size, shards, index and the figures of its build, once its
    manifest, build.json, shards and index are checked against one another."""
    from linkwright.atlas import AtlasError, open_atlas

    try:
        atlas = open_atlas(directory, hashes=not quick)
    except AtlasError as exc:
        raise CliError(str(exc)) from None
    if as_json:
        sys.stdout.write(_dump({"path": str(directory), **atlas.manifest}))
        return
    sys.stdout.write(_atlas_summary(directory, atlas.manifest))


@atlas_app.command("query")
def atlas_query(
    points: Annotated[
        Path,
        typer.Option(
            "--points",
            metavar="FILE.csv",
            help="The curve: rows x, y (x, y, z unit vectors for a spherical atlas).",
        ),
    ],
    directory: Annotated[
        Path | None,
        typer.Argument(metavar="[DIR]", help="An atlas directory; default the built-in one."),
    ] = None,
    family: Annotated[
        str,
        typer.Option("--family", metavar="F", help="The built-in atlas's family (without DIR)."),
    ] = "fourbar",
    top: Annotated[int, typer.Option("--top", metavar="K", min=1, max=1000)] = 5,
    refine: Annotated[
        bool, typer.Option("--refine", help="Optimise the best matches locally.")
    ] = False,
    tolerance: Annotated[
        float,
        typer.Option(
            "--tolerance",
            metavar="FRACTION",
            min=1e-9,
            max=1.0,
            help="Refine until the RMS distance is this fraction of the curve's size.",
        ),
    ] = 0.001,
    budget: Annotated[
        float, typer.Option("--budget", metavar="SECONDS", min=0.01, max=3600.0)
    ] = 5.0,
    as_json: JsonOpt = False,
    quiet: QuietOpt = False,
) -> None:
    """Match a closed curve against an atlas: the best mechanisms, each placed where the curve
    was drawn, with its aligned error and the transform from the atlas."""
    import numpy as np

    from linkwright.atlas import (
        AtlasBuildError,
        AtlasError,
        AtlasQueryError,
        default_atlas,
        open_atlas,
        query,
    )

    pts = np.array(read_points(points, (2, 3)))
    try:
        with _Progress("matching", quiet) as progress:
            atlas = open_atlas(directory) if directory is not None else default_atlas(family)
            t0 = time.perf_counter()
            matches = query(
                atlas, pts, top=top, refine=refine, tolerance=tolerance, budget=budget,
                progress=progress,
            )  # fmt: skip
            elapsed = time.perf_counter() - t0
    except (AtlasError, AtlasQueryError, AtlasBuildError) as exc:
        raise CliError(str(exc)) from None
    rows = []
    for rank, m in enumerate(matches, start=1):
        if m.translation is None:
            transform = {"rotation_matrix": np.asarray(m.rotation)}
        else:
            transform = {
                "scale": m.scale,
                "rotation_deg": math.degrees(float(m.rotation)),
                "translation": m.translation,
            }
        rows.append({
            "rank": rank,
            "atlas_id": m.atlas_id,
            "error": m.error,
            "distance": m.distance,
            "transform": transform,
            "descriptor_distance": m.descriptor_distance,
            "refined": m.refined,
            "mechanism": m.mechanism,
        })  # fmt: skip
    result = _documents({
        "atlas": str(atlas.path),
        "family": atlas.family,
        "entries": atlas.count,
        "points": len(pts),
        "seconds": elapsed,
        "matches": rows,
    })  # fmt: skip
    if as_json:
        sys.stdout.write(_dump(result))
        return
    lines = [f"{len(matches)} matches from {atlas.count} {atlas.family} curves in {elapsed:.2f} s"]
    for row, m in zip(result["matches"], matches, strict=True):
        lines.append(
            f"#{row['rank']}  entry {m.atlas_id}: aligned error {m.error:.3%}, RMS distance "
            f"{m.distance:.4g}{' (refined)' if m.refined else ''}"
        )
    lines.append("best:\n" + _dumps_toml_mech(result["matches"][0]["mechanism"]))
    sys.stdout.write("\n".join(lines) + "\n")


# --------------------------------------------------------------------------------------------
# Entry point
# --------------------------------------------------------------------------------------------


def _fail(message: str, status: int = 2) -> int:
    line = " ".join(str(message).split())  # one line, whatever the message held
    sys.stderr.write(f"error: {line}\n")
    return status


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line with ``argv`` (default: ``sys.argv[1:]``); return the exit status.

    Click's own error display (usage block plus message) is replaced by one ``error:`` line, and
    every expected failure (bad file, bad document, bad option) exits with status 2.
    """
    from linkwright.engine import NoPeriod
    from linkwright.engine.cost import CostError
    from linkwright.io.documents import DocumentError
    from linkwright.mechanisms.sixbar import NoConstructionPlan

    # `linkwright` alone asks for the help, which is not an error.
    args = list(sys.argv[1:] if argv is None else argv) or ["--help"]
    command = typer.main.get_command(app)
    try:
        status = command.main(args=args, prog_name="linkwright", standalone_mode=False)
    except click_exceptions.ClickException as exc:
        return _fail(exc.format_message())
    except (CliError, DocumentError, NoConstructionPlan, NoPeriod, CostError) as exc:
        return _fail(str(exc))
    except typer.Abort:
        return _fail("aborted", 1)
    except BrokenPipeError:
        # The reader went away (`linkwright curve ... | head`): stop quietly, and keep Python
        # from complaining again when it flushes stdout at exit.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 1
    except OSError as exc:
        return _fail(f"{exc.filename}: {exc.strerror}" if exc.filename else str(exc))
    except Exception as exc:
        if os.environ.get("LINKWRIGHT_TRACEBACK"):
            raise
        return _fail(
            f"internal error: {type(exc).__name__}: {exc} "
            "(set LINKWRIGHT_TRACEBACK=1 to see where)",
            1,
        )
    return status if isinstance(status, int) else 0


if __name__ == "__main__":
    sys.exit(main())
