"""The rooms of the package keep to their layers (DESIGN.md), checked two ways.

``lint-imports`` checks the layer contract in pyproject.toml over the real import graph; the
walk below checks, with nothing but ``ast``, that no module reaches into another's private
names (a name used by a second module is part of that module's interface, so it is public).
"""

from __future__ import annotations

import ast
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "linkwright"


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _private_imports() -> list[str]:
    """Every ``from linkwright.x import _name`` (and ``module._name`` on an imported
    linkwright module) in a module other than the one that defines it."""
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        here = _module_name(path)
        tree = ast.parse(path.read_text(encoding="utf-8"))
        modules: dict[str, str] = {}
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("linkwright"):
                for alias in node.names:
                    modules[alias.asname or alias.name] = f"{node.module}.{alias.name}"
                    private = alias.name.startswith("_") and not alias.name.startswith("__")
                    if private and node.module != here:
                        found.append(f"{here}:{node.lineno} imports {node.module}.{alias.name}")
            elif isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.name.startswith("linkwright"):
                        modules[alias.asname or alias.name] = alias.name
        for node in ast.walk(tree):
            if (
                isinstance(node, ast.Attribute)
                and node.attr.startswith("_")
                and not node.attr.startswith("__")
                and isinstance(node.value, ast.Name)
                and modules.get(node.value.id, here) != here
            ):
                found.append(f"{here}:{node.lineno} reads {modules[node.value.id]}.{node.attr}")
    return found


def test_the_walk_finds_a_private_import(tmp_path, monkeypatch):
    """The checker itself: a planted cross-module private import is reported."""
    fake = tmp_path / "linkwright"
    (fake / "plot").mkdir(parents=True)
    (fake / "__init__.py").write_text("")
    (fake / "plot" / "__init__.py").write_text("")
    (fake / "plot" / "a.py").write_text("def _deg(x):\n    return x\n")
    (fake / "plot" / "b.py").write_text(
        "from linkwright.plot.a import _deg\nfrom linkwright.plot import a\na._deg(1)\n"
    )
    monkeypatch.setattr(sys.modules[__name__], "PACKAGE", fake)
    assert _private_imports() == [
        "linkwright.plot.b:1 imports linkwright.plot.a._deg",
        "linkwright.plot.b:3 reads linkwright.plot.a._deg",
    ]


def test_no_module_imports_another_modules_private_names():
    assert _private_imports() == []


def test_the_layer_contract_is_kept():
    lint = shutil.which("lint-imports", path=str(Path(sys.executable).parent))
    if lint is None:
        pytest.skip("import-linter is not installed (it is in the dev extra)")
    done = subprocess.run(
        [lint, "--no-cache"],
        cwd=PACKAGE.parents[1],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 0, done.stdout[-3000:]
    assert "0 broken" in done.stdout
