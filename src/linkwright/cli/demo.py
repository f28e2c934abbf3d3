"""``linkwright demo``: the bundled demonstration."""

from __future__ import annotations

import os
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Annotated

import typer

from linkwright.cli.shared import CliError, app, to_json_ready


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
        from linkwright.io.report import table_lines

        lines = table_lines(to_json_ready(result))
        sys.stdout.write("\n".join(lines) + "\n")
    elif isinstance(result, list | tuple | set):
        sys.stdout.write("".join(f"{to_json_ready(item)}\n" for item in result))
    else:
        sys.stdout.write(f"{result}\n")
