"""``linkwright solve``: joint positions (and derivatives) at given input angles."""

from __future__ import annotations

import sys
from collections.abc import Mapping
from typing import TYPE_CHECKING, Annotated, Any

import typer

from linkwright.cli.shared import (
    DEFAULT_INPUTS,
    FileArg,
    JsonOpt,
    app,
    axes_of,
    document_heading,
    fmt_number,
    load_file,
    parse_inputs,
    signs_text,
    to_json_ready,
)

if TYPE_CHECKING:
    from linkwright.io import Document


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
    doc = load_file(file)
    from linkwright.cli.budget import solve_chunk, stream_solve
    from linkwright.io.results import solve_document

    # Checked against the budget first, then computed and written a chunk of inputs at a time:
    # memory stays bounded by the chunk, however many rows were asked for.
    chunk = solve_chunk(doc, len(degrees), all_configurations=all_, derivatives=derivatives)
    stream_solve(
        degrees,
        chunk,
        lambda part: solve_document(doc, part, all_configurations=all_, derivatives=derivatives),
        lambda result: _solve_text(doc, result, derivatives),
        to_json_ready,
        sys.stdout,
        as_json=as_json,
    )


def _solve_text(doc: Document, result: Mapping[str, Any], derivatives: bool) -> str:
    """``solve``'s table: ground pivots once, then a row per input and configuration."""
    from linkwright.io.results import ground_joints, ground_xy

    mech = doc.mechanism
    ground = ground_joints(mech)
    moving = [j for j in mech.reported_joints if j not in ground]
    lines = [document_heading(doc)]
    if ground:
        pivots = ", ".join(
            f"{j} = ({', '.join(fmt_number(c, 0, 6) for c in xy)})"
            for j in ground
            if (xy := ground_xy(mech, j)) is not None
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
    axes = axes_of(mech)
    header = f"{'input_deg':>10} {'assembly':>9} " + " ".join(
        f"{j + '.' + c:>11}" for j in moving for c in axes
    )
    for key, label in sections:
        lines += ["", f"# {label}", header]
        for sample in result["samples"]:
            deg = fmt_number(sample["input_deg"], 10, 3)
            if not sample["configurations"]:
                lines.append(f"{deg} {'-':>9}  {sample['reason']}")
            for entry in sample["configurations"]:
                values = entry[key]
                cells = " ".join(
                    fmt_number(None if values[j] is None else values[j][c])
                    for j in moving
                    for c in range(len(axes))
                )
                lines.append(f"{deg} {signs_text(entry['assembly']):>9} {cells}")
    return "\n".join(lines) + "\n"
