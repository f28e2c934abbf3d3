"""``linkwright analyze``: type, ranges, transmission angle, time ratio and coefficients."""

from __future__ import annotations

import math
import sys
from typing import Annotated

import typer

from linkwright.cli.shared import (
    CliError,
    FileArg,
    JsonOpt,
    app,
    document_heading,
    dump_json,
    load_file,
    to_json_ready,
)


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
    doc = load_file(file)
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
    from linkwright.io.report import analysis_report, table_lines

    try:
        found = run_analysis(doc.mechanism) if mu is None else run_analysis(doc.mechanism, mu=mu)
    except ValueError as exc:
        raise CliError(str(exc)) from None
    result = to_json_ready(analysis_report(found))
    if as_json:
        sys.stdout.write(dump_json(result))
        return
    sys.stdout.write("\n".join([document_heading(doc), *table_lines(result)]) + "\n")
