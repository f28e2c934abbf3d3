"""``linkwright curve``: the traced point's path over the whole closed circuit."""

from __future__ import annotations

import sys
from typing import Annotated

import typer

from linkwright.cli.shared import (
    MAX_SAMPLES,
    CliError,
    FileArg,
    JsonOpt,
    app,
    axes_of,
    document_heading,
    dump_json,
    fmt_number,
    load_file,
)


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
    doc = load_file(file)
    from linkwright.cli.budget import check_followed, check_trace
    from linkwright.io.results import NotAssembled, curve_document

    if every or doc.mechanism.plan.triads:
        check_followed(doc.mechanism, points)
    else:
        # The answer holds each sample as Python numbers, and again as text.
        check_trace(doc.mechanism, points, knob="--points", spacing=spacing, sample_bytes=400.0)
    try:
        result = curve_document(doc, points, spacing=spacing, every=every)
    except NotAssembled as exc:
        raise CliError(str(exc)) from None
    if as_json:
        sys.stdout.write(dump_json(result))
        return
    pieces = result["circuits"] if every else [result]
    rows = [
        (k, deg, xy, asm)
        for k, piece in enumerate(pieces, start=1)
        for deg, xy, asm in zip(piece["input_deg"], piece["points"], piece["assembly"], strict=True)
    ]
    axes = axes_of(doc.mechanism)
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
    out = [document_heading(doc), about]
    if len(axes) == 3:
        out.append("# on the unit sphere: each point is the unit vector of the joint's axis")
    head = f"{'input_deg':>10} " + " ".join(f"{c:>11}" for c in axes) + f" {'assembly':>9}"
    out.append(f"{'circuit':>7} {head}" if every else head)
    for k, deg, xy, asm in rows:
        shown: list[float | None] = [None] * len(axes) if xy is None else xy
        line = f"{fmt_number(deg, 10, 3)} {' '.join(fmt_number(c) for c in shown)} {asm:>+9d}"
        out.append(f"{k:>7} {line}" if every else line)
    sys.stdout.write("\n".join(out) + "\n")
