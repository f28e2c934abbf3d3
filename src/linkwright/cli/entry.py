"""The ``linkwright`` entry point: every command registered, Click's errors as one line."""

from __future__ import annotations

import os
import sys
from collections.abc import Sequence
from typing import Any

import typer

try:  # typer ≥ 0.22 vendors click; older ones depend on it
    from typer._click import exceptions as click_exceptions
except ImportError:  # pragma: no cover - depends on the installed typer
    from click import exceptions as click_exceptions  # type: ignore[no-redef]

# Imported for the commands they register on the app.
from linkwright.cli import analyze as _analyze  # noqa: F401
from linkwright.cli import atlas as _atlas  # noqa: F401
from linkwright.cli import curve as _curve  # noqa: F401
from linkwright.cli import demo as _demo  # noqa: F401
from linkwright.cli import forces as _forces  # noqa: F401
from linkwright.cli import papers as _papers  # noqa: F401
from linkwright.cli import plot as _plot  # noqa: F401
from linkwright.cli import serve as _serve  # noqa: F401
from linkwright.cli import solve as _solve  # noqa: F401
from linkwright.cli import synth as _synth  # noqa: F401
from linkwright.cli import synth_function as _synth_function  # noqa: F401
from linkwright.cli import synth_more as _synth_more  # noqa: F401
from linkwright.cli import tolerance as _tolerance  # noqa: F401
from linkwright.cli.shared import CliError, app

# The order `linkwright --help` lists them in, whatever order their modules were imported in
# (typer lists commands as they were registered, and import order is the linter's to sort).
COMMANDS = (
    "solve",
    "curve",
    "analyze",
    "forces",
    "demo",
    "serve",
    "plot",
    "animate",
    "export",
    "papers",
    "tolerance",
)
GROUPS = ("synth", "atlas")


def _command_name(info: Any) -> str:
    return str(info.name or info.callback.__name__)


app.registered_commands.sort(key=lambda info: COMMANDS.index(_command_name(info)))
app.registered_groups.sort(key=lambda info: GROUPS.index(info.name))


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
