"""``linkwright papers``: a seed paper's tables and figures regenerated."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer

from linkwright.cli.shared import CliError, app

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
