"""Every ``$ linkwright ...`` line in the README's console examples runs and succeeds.

The CLI section is written in docs/cli.md and pasted into README.md; both are read, so the
examples are tested wherever they live. Paths in the examples are relative to the repository
root; they are made absolute and the command runs in a scratch folder, so an example that
writes files (``linkwright demo --out out``) leaves nothing in the checkout.
"""

from __future__ import annotations

import importlib.util
import json
import re
import shlex
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from linkwright.io import parse_document

ROOT = Path(__file__).resolve().parents[1]
DOCS = [p for p in (ROOT / "README.md", ROOT / "docs" / "cli.md") if p.exists()]
FENCE = re.compile(r"^```(\w*)[^\n]*\n(.*?)^```", re.MULTILINE | re.DOTALL)


def blocks(kind: str) -> list[tuple[str, int, str]]:
    """(file name, line number, body) of each fenced block of the given kind."""
    found = []
    for path in DOCS:
        text = path.read_text(encoding="utf-8")
        for match in FENCE.finditer(text):
            if match.group(1) == kind:
                line = text.count("\n", 0, match.start()) + 1
                found.append((path.name, line, match.group(2)))
    return found


def console_commands() -> list[tuple[str, int, str]]:
    out = []
    for name, line, body in blocks("console"):
        for offset, text in enumerate(body.splitlines(), start=1):
            if text.startswith("$ linkwright"):
                out.append((name, line + offset, text[2:].strip()))
    return out


COMMANDS = console_commands()


def linkwright_command() -> list[str]:
    script = Path(sys.executable).with_name("linkwright")
    return [str(script)] if script.exists() else [sys.executable, "-m", "linkwright"]


def needs(module: str, attr: str) -> str | None:
    """Why a command cannot run yet (its module is written elsewhere), or None."""
    try:
        spec = importlib.util.find_spec(module)
    except ModuleNotFoundError:
        spec = None
    if spec is None:
        return f"{module} is not there yet"
    mod = importlib.import_module(module)
    return None if hasattr(mod, attr) else f"{module}.{attr} is not there yet"


def test_the_docs_have_console_examples():
    assert DOCS, "neither README.md nor docs/cli.md exists"
    assert len(COMMANDS) >= 5
    used = {shlex.split(cmd)[1] for _, _, cmd in COMMANDS if len(shlex.split(cmd)) > 1}
    assert {"solve", "curve", "analyze"} <= used


@pytest.mark.parametrize(
    ("doc", "line", "command"), COMMANDS, ids=[f"{d}:{n}" for d, n, _ in COMMANDS]
)
def test_console_example_runs(doc, line, command, tmp_path):
    args = shlex.split(command)[1:]
    sub = args[0] if args else ""
    reason = {
        "analyze": needs("linkwright.analysis", "analyze"),
        "demo": needs("linkwright.demo", "run_demo"),
    }.get(sub)
    if reason:
        pytest.skip(reason)
    if sub in {"solve", "curve", "analyze"}:
        file = args[1]
        assert file.startswith("src/linkwright/examples/"), f"{doc}:{line}: use a bundled example"
        assert (ROOT / file).is_file(), f"{doc}:{line}: {file} does not exist"
    resolved = [str(ROOT / a) if not a.startswith("-") and (ROOT / a).exists() else a for a in args]
    proc = subprocess.run(
        [*linkwright_command(), *resolved],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, f"{doc}:{line}: `{command}` failed:\n{proc.stderr}"
    if "--json" in args:
        json.loads(proc.stdout)


TOML_BLOCKS = [b for b in blocks("toml") if "format = " in b[2]]


@pytest.mark.parametrize(
    ("doc", "line", "body"), TOML_BLOCKS, ids=[f"{d}:{n}" for d, n, _ in TOML_BLOCKS]
)
def test_toml_documents_in_the_docs_are_valid(doc, line, body):
    parse_document(tomllib.loads(body), source=f"{doc}:{line}")


@pytest.mark.parametrize(
    ("name", "line", "body"),
    [b for b in blocks("python") if b[0] == "README.md"],
    ids=lambda v: str(v) if isinstance(v, int) else None,
)
def test_readme_python_block_runs(name: str, line: int, body: str) -> None:
    exec(compile(body, f"{name}:{line}", "exec"), {})
