"""The ``linkwright`` command line: a package of thin commands over the library.

:mod:`~linkwright.cli.shared` holds the typer app, its shared options and helpers; each command
group has its module (``solve``, ``curve``, ``analyze``, ``demo``, ``serve``, ``plot`` with
``animate`` and ``export``, ``papers``, ``synth``, ``atlas``); :mod:`~linkwright.cli.entry`
registers them all and turns every expected failure into one ``error:`` line. What the commands
compute lives in the library (:mod:`linkwright.io.results`, :mod:`linkwright.io.report`).
"""

from linkwright.cli.entry import main
from linkwright.cli.shared import CliError, app, parse_inputs

__all__ = ["CliError", "app", "main", "parse_inputs"]
