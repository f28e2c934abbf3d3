"""``linkwright forces``: driving torque, joint reactions and shaking forces of a document."""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Annotated, Any

import numpy as np
import typer

from linkwright.cli.shared import (
    CliError,
    FileArg,
    JsonOpt,
    app,
    document_heading,
    dump_json,
    fmt_number,
    load_file,
)

if TYPE_CHECKING:
    from linkwright.dynamics import Forces, Loads, MassProps, Structure
    from linkwright.io import Document

DEFAULT_FORCE_INPUTS = [float(10 * k) for k in range(36)]


@app.command()
def forces(
    file: FileArg,
    speed: Annotated[
        float | None,
        typer.Option(
            "--speed",
            metavar="RPM",
            help="Input speed in rpm (replaces the document's loads.speed).",
            show_default=False,
        ),
    ] = None,
    inputs: Annotated[
        str | None,
        typer.Option(
            "--input",
            "-i",
            metavar="SPEC",
            help="Input angles in degrees: START:STOP:STEP or a comma list. Default: 0 to 350 "
            "every 10.",
            show_default=False,
        ),
    ] = None,
    all_: Annotated[
        bool,
        typer.Option("--all", help="Every real assembly configuration, not only the document's."),
    ] = False,
    as_json: JsonOpt = False,
    as_csv: Annotated[bool, typer.Option("--csv", help="Print CSV.")] = False,
) -> None:
    """Driving torque, joint reactions, shaking force and moment, energies (plane and sphere).

    Masses come from the document's [mechanism.mass] table, loads and speed from [loads]
    (docs/forces.md); units are the document's mass and length units and seconds (kg and m
    give N, N·m and J).
    """
    from linkwright.cli.shared import parse_inputs
    from linkwright.dynamics import forces_of
    from linkwright.engine import cost
    from linkwright.mechanisms.base import configurations, solve

    if as_csv and as_json:
        raise CliError("--csv and --json cannot be used together")
    if speed is not None and not (math.isfinite(speed) and abs(speed) <= 1e9):
        raise CliError(f"--speed: must be a finite number of rpm up to 1e9 in size, got {speed}")
    degrees = parse_inputs(inputs) if inputs is not None else list(DEFAULT_FORCE_INPUTS)
    doc = load_file(file)
    mech = doc.mechanism
    st, masses, loads = document_forces(doc, speed=speed, speed_field="loads.speed (or --speed)")
    params = mech.params()

    # Bounded before the work: solving with derivatives, then one dense solve per sample.
    unknowns = 3 * len(st.bodies)
    shape = cost.Shape.of_mechanism(mech, periodic=False)
    if all_:
        cost.check_combinations(shape)
    configs = shape.configurations if all_ else 1.0

    def estimate(n: int) -> cost.Estimate:
        found = cost.solve(shape, n, configurations=configs, order=2)
        per = configs * n
        extra = cost.Estimate(
            per * (unknowns**3 / 3.0 + unknowns**2) / 50.0,
            per * unknowns * (unknowns + 4) * 8 * 3,
            f"solving Newton–Euler ({unknowns} unknowns) at {n:,} samples",
        )
        return found + extra

    cost.with_knob(estimate, cost.CLI, len(degrees), 1, "the number of inputs (--input)").check(
        cost.CLI
    )
    theta = np.radians(np.asarray(degrees, dtype=float))
    found = configurations(mech, theta, order=2) if all_ else [(None, solve(mech, theta, order=2))]
    results = [
        (branches, forces_of(st, params, motion, masses, loads)) for branches, motion in found
    ]
    rows = [
        _row(deg, branches, f, k)
        for branches, f in results
        for k, deg in enumerate(degrees)
        if not all_ or bool(f.valid[k])
    ]
    meta = {
        "units": _units(doc),
        "speed_rpm": loads.speed_rpm,
        "inertia": loads.inertia,
        "links": list(st.names),
    }
    if as_json:
        typer.echo(dump_json({**meta, "samples": rows}))
    elif as_csv:
        typer.echo(_csv(rows), nl=False)
    else:
        typer.echo(_text(doc, meta, rows), nl=False)


def document_forces(
    doc: Document,
    *,
    speed: float | None = None,
    speed_field: str = "loads.speed",
    unsupported: str = "forces: ",
    invalid: str = "",
) -> tuple[Structure, dict[str, MassProps], Loads]:
    """A document's bodies, masses and loads for a forces run
    (:func:`linkwright.dynamics.forces_setup`), every refusal a one-line :class:`CliError`:
    ``unsupported`` prefixes a plan forces cannot set up, ``invalid`` a bad mass or load."""
    from linkwright.dynamics import ForcesInputError, UnsupportedPlan, forces_setup

    mass = doc.raw["mechanism"].get("mass", {})
    try:
        return forces_setup(
            doc.mechanism, mass, doc.raw.get("loads"), speed=speed, speed_field=speed_field
        )
    except UnsupportedPlan as exc:
        raise CliError(f"{unsupported}{exc}") from None
    except ForcesInputError as exc:
        raise CliError(f"{invalid}{exc}") from None


def _units(doc: Document) -> dict[str, str]:
    length = doc.units or "length unit"
    return {
        "length": length,
        "mass": "the document's mass unit (kg)",
        "force": f"mass unit·{length}/s² (N for kg and m)",
        "torque": f"mass unit·{length}²/s² (N·m for kg and m)",
        "energy": f"mass unit·{length}²/s² (J for kg and m)",
    }


def _num(x: Any) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def _row(deg: float, branches: tuple[int, ...] | None, f: Forces, k: int) -> dict[str, Any]:
    row: dict[str, Any] = {"input_deg": deg}
    if branches is not None:
        row["assembly"] = list(branches)
    row["input_torque"] = _num(f.input_torque[k])
    row["energy_torque"] = _num(f.energy_torque[k])
    row["reactions"] = {n: [_num(v) for v in f.reactions[n][k]] for n in f.reactions}
    if f.moments:
        row["moments"] = {n: [_num(v) for v in f.moments[n][k]] for n in f.moments}
    if f.guides:
        row["guides"] = {n: [_num(v) for v in f.guides[n][k]] for n in f.guides}
    if f.gears:
        row["gears"] = {n: _num(f.gears[n][k]) for n in f.gears}
    row["shaking_force"] = [_num(v) for v in f.shaking_force[k]]
    shaking = f.shaking_moment[k]
    row["shaking_moment"] = _num(shaking) if np.ndim(shaking) == 0 else [_num(v) for v in shaking]
    row["kinetic_energy"] = _num(f.kinetic[k])
    row["potential_energy"] = _num(f.potential[k])
    return row


def _flat(row: Mapping[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = {"input_deg": row["input_deg"]}
    if "assembly" in row:
        out["assembly"] = ",".join(f"{s:+d}" for s in row["assembly"])
    out["input_torque"] = row["input_torque"]
    for name, force in row["reactions"].items():
        out.update({f"{name}.{axis}": v for axis, v in zip("xyz", force, strict=False)})
    for name, moment in row.get("moments", {}).items():
        out.update({f"{name}.m{axis}": v for axis, v in zip("xyz", moment, strict=False)})
    for name, (n, m) in row.get("guides", {}).items():
        out[f"{name}.normal"], out[f"{name}.moment"] = n, m
    for name, t in row.get("gears", {}).items():
        out[f"{name}.gear_torque"] = t
    out.update({f"shaking.{a}": v for a, v in zip("xyz", row["shaking_force"], strict=False)})
    moment = row["shaking_moment"]
    if isinstance(moment, list):
        out.update({f"shaking_moment.{a}": v for a, v in zip("xyz", moment, strict=False)})
    else:
        out["shaking_moment"] = moment
    out["kinetic_energy"] = row["kinetic_energy"]
    out["potential_energy"] = row["potential_energy"]
    return out


def _csv(rows: list[dict[str, Any]]) -> str:
    flat = [_flat(r) for r in rows]
    if not flat:
        return ""
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=list(flat[0]), lineterminator="\n")
    writer.writeheader()
    for r in flat:
        writer.writerow({k: "" if v is None else v for k, v in r.items()})
    return buf.getvalue()


def _text(doc: Document, meta: Mapping[str, Any], rows: list[dict[str, Any]]) -> str:
    units = meta["units"]
    lines = [
        document_heading(doc),
        f"# input speed {meta['speed_rpm']:g} rpm"
        + ("" if meta["inertia"] else " (static: no inertia forces)")
        + f"; torque in {units['torque']}, forces in {units['force']}",
    ]
    flat = [_flat(r) for r in rows]
    if not flat:
        return "\n".join([*lines, "# no sample assembles"]) + "\n"
    keys = list(flat[0])
    lines.append(" ".join(f"{k:>14}" for k in keys))
    for r in flat:
        lines.append(
            " ".join(
                f"{r[k]:>14}" if isinstance(r[k], str) else fmt_number(r[k], 14, 6) for k in keys
            )
        )
    return "\n".join(lines) + "\n"
