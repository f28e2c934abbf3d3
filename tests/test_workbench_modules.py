"""The workbench page's script as ES modules (issue 23): served as JavaScript, every import
resolved by an export of the module it names, no module over about 800 lines."""

from __future__ import annotations

import re
from importlib import resources
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from linkwright.server import create_app

STATIC = Path(str(resources.files("linkwright.server") / "static"))
IMPORT = re.compile(r'^import \{([^}]*)\} from "\./([\w-]+\.js)";', re.M)
EXPORT = re.compile(r"^export (?:async function|function|const|let) ([A-Za-z_$][\w$]*)", re.M)


def _modules() -> dict[str, str]:
    """The page's modules: app.js and, recursively, every module it imports."""
    found: dict[str, str] = {}
    todo = ["app.js"]
    while todo:
        name = todo.pop()
        if name in found:
            continue
        found[name] = (STATIC / name).read_text(encoding="utf-8")
        todo += [m.group(2) for m in IMPORT.finditer(found[name])]
    return found


def test_page_loads_its_script_as_a_module() -> None:
    html = (STATIC / "index.html").read_text(encoding="utf-8")
    assert '<script type="module" src="/static/app.js"></script>' in html
    assert len(_modules()) > 1


def test_every_import_is_exported_by_the_module_it_names() -> None:
    modules = _modules()
    for name, text in modules.items():
        for m in IMPORT.finditer(text):
            names = {n.strip() for n in m.group(1).split(",") if n.strip()}
            exported = set(EXPORT.findall(modules[m.group(2)]))
            assert names <= exported, (name, m.group(2), sorted(names - exported))


def test_modules_stay_small() -> None:
    for name, text in _modules().items():
        assert text.count("\n") <= 820, (name, text.count("\n"))


@pytest.mark.parametrize("name", sorted(_modules()))
def test_modules_are_served_as_javascript(name: str, tmp_path: Path) -> None:
    # A browser runs a module only when its MIME type is JavaScript's.
    with TestClient(create_app(tmp_path)) as client:
        r = client.get(f"/static/{name}")
    assert r.status_code == 200
    assert r.headers["content-type"].split(";")[0] in ("text/javascript", "application/javascript")


def test_every_name_of_another_module_is_imported() -> None:
    # A name a module uses but never imports fails only when that code runs (a limit's legend
    # once drew nothing but "LIMIT_COLOUR is not defined"). Property names (after a dot) and
    # object keys (before a colon) are not uses.
    modules = _modules()
    top = re.compile(r"^(?:export )?(?:async function|function|const|let) ([A-Za-z_$][\w$]*)", re.M)
    owner = {n: name for name, text in modules.items() for n in top.findall(text)}
    for name, text in modules.items():
        imported = {
            n.strip() for m in IMPORT.finditer(text) for n in m.group(1).split(",") if n.strip()
        }
        body = IMPORT.sub("", text)
        body = re.sub(r"/\*.*?\*/", "", body, flags=re.S)
        # words inside a plain string are text, not names (a template's ${...} still counts)
        body = re.sub(r'"(?:[^"\\\n]|\\.)*"', '""', body)
        for n, where in owner.items():
            if where == name or n in imported:
                continue
            use = re.compile(r"(?<![\w$.])" + re.escape(n) + r"(?![\w$])(?!\s*:)")
            assert not use.search(body), (name, n, where)
