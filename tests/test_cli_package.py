"""The command line is a package of thin commands (issue 23, item 3)."""

from __future__ import annotations

import importlib
from pathlib import Path

import typer

import linkwright.cli as cli
from linkwright.cli import budget

CLI = Path(cli.__file__).parent


def test_every_module_of_the_cli_stays_a_readable_size():
    sizes = {p.name: len(p.read_text(encoding="utf-8").splitlines()) for p in CLI.glob("*.py")}
    assert {"shared.py", "entry.py", "solve.py", "curve.py", "analyze.py"} <= set(sizes)
    assert max(sizes.values()) <= 800, sizes


def test_help_lists_the_commands_in_their_order():
    group = typer.main.get_command(cli.app)
    assert list(group.commands) == [
        "solve", "curve", "analyze", "forces", "demo", "serve", "plot", "animate", "export",
        "papers", "tolerance", "synth", "atlas",
    ]  # fmt: skip


def test_the_old_budget_module_is_the_new_one():
    old = importlib.import_module("linkwright.cli_budget")
    for name in budget.__all__:
        assert getattr(old, name) is getattr(budget, name)


def test_the_package_keeps_its_public_names():
    assert set(cli.__all__) == {"CliError", "app", "main", "parse_inputs"}
    assert cli.parse_inputs("0:90:30") == [0.0, 30.0, 60.0, 90.0]


def test_documents_split_keeps_the_old_names():
    from linkwright.io import documents, files, toml_writer

    for name in ("list_examples", "load_document", "load_example", "save_document"):
        assert getattr(documents, name) is getattr(files, name)
    assert documents.dumps_toml is toml_writer.dumps_toml
    assert files.load_example("crank-rocker").family == "fourbar"
