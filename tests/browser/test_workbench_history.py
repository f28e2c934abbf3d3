"""Issue 24's undo and redo, safe fields and shareable state, used as a person uses the page.

Each test drives Debian's chromium (fixtures in ``conftest.py``) from a fresh page. Documents
are compared as the JSON the page holds (``lw.document()``) against documents recorded before
each edit, or fetched from the server on their own (``/api/examples/...``); a link's payload is
decoded here with Python's zlib and base64, not by the page's own code.
"""

from __future__ import annotations

import base64
import json
import math
import re
import urllib.request
import zlib
from typing import Any

import pytest
from playwright.sync_api import expect

SCENES = "Number(document.body.dataset.sceneCount || 0)"
B0X = "[data-path='mechanism.B0.0']"


def _scenes(page: Any) -> int:
    return int(page.evaluate(SCENES))


def _settle(page: Any, after: int | None = None) -> None:
    if after is not None:
        page.wait_for_function(f"{SCENES} > {after}")
    page.wait_for_function("document.body.dataset.busy === '0'")


def _open(page: Any, url: str) -> None:
    page.goto(url)
    page.wait_for_function(f"{SCENES} >= 1")
    _settle(page)


def _doc(page: Any) -> dict[str, Any]:
    return page.evaluate("lw.document()")


def _example(page: Any, name: str) -> dict[str, Any]:
    return page.evaluate(f"fetch('/api/examples/{name}').then(r => r.json())")


def _type_and_enter(page: Any, selector: str, text: str) -> None:
    before = _scenes(page)
    page.fill(selector, text)
    page.press(selector, "Enter")
    _settle(page, before)


def _drag_point(page: Any, name: str, dx: float, dy: float) -> None:
    box = page.locator("#drawing").bounding_box()
    sx, sy = page.evaluate(f"lw.toScreen(lw.pose()['{name}'])")
    x, y = box["x"] + sx, box["y"] + sy
    page.mouse.move(x, y)
    page.mouse.down()
    for k in range(1, 9):
        page.mouse.move(x + dx * k / 8, y + dy * k / 8)
    page.mouse.up()
    _settle(page)


def _undo_count(page: Any) -> tuple[int, int]:
    return (
        int(page.evaluate("document.body.dataset.undo")),
        int(page.evaluate("document.body.dataset.redo")),
    )


def _changed(a: dict[str, Any], b: dict[str, Any]) -> set[str]:
    return {k for k in set(a) | set(b) if a.get(k) != b.get(k)}


# ---------------------------------------------------------------------------------------------


def test_undo_and_redo_a_field_a_drag_and_an_example(page: Any, server_url: str) -> None:
    _open(page, server_url)
    doc0 = _doc(page)
    assert doc0 == _example(page, "crank-rocker")
    expect(page.locator("#undo")).to_be_disabled()
    expect(page.locator("#redo")).to_be_disabled()

    _type_and_enter(page, "[data-path='mechanism.crank']", "1.25")
    doc1 = _doc(page)
    assert _changed(doc0["mechanism"], doc1["mechanism"]) == {"crank"}
    assert doc1["mechanism"]["crank"] == 1.25
    assert _undo_count(page) == (1, 0)
    assert "crank" in (page.get_attribute("#undo", "title") or "")

    # a drag of eight pointer moves (several scenes) is one step
    _drag_point(page, "P", 30, -20)
    doc2 = _doc(page)
    assert _changed(doc1["mechanism"], doc2["mechanism"]) == {"point"}
    assert _undo_count(page) == (2, 0)

    before = _scenes(page)
    page.select_option("#example-select", "double-crank")
    _settle(page, before)
    doc3 = _doc(page)
    assert doc3 == _example(page, "double-crank")
    assert _undo_count(page) == (3, 0)

    # undo three times (the keys, then the button): each earlier document exactly
    page.locator("#drawing").focus()
    for want, how in ((doc2, "key"), (doc1, "button"), (doc0, "key")):
        before = _scenes(page)
        if how == "key":
            page.keyboard.press("Control+z")
        else:
            page.click("#undo")
        _settle(page, before)
        assert _doc(page) == want
    assert page.input_value("#example-select") == "crank-rocker"
    assert page.input_value("[data-path='mechanism.crank']") == "1"
    assert "Undone: crank" in page.inner_text("#status")
    expect(page.locator("#undo")).to_be_disabled()
    assert _undo_count(page) == (0, 3)

    # and redo puts each back: Ctrl+Shift+Z, Ctrl+Y, the button
    for want, how in ((doc1, "Control+Shift+z"), (doc2, "Control+y"), (doc3, None)):
        before = _scenes(page)
        if how:
            page.keyboard.press(how)
        else:
            page.click("#redo")
        _settle(page, before)
        assert _doc(page) == want
    expect(page.locator("#redo")).to_be_disabled()

    # a new edit after an undo drops what could have been redone
    page.keyboard.press("Control+z")
    _settle(page)
    _type_and_enter(page, "[data-path='mechanism.coupler']", "4.5")
    assert _undo_count(page) == (3, 0)
    assert _doc(page)["mechanism"] == {**doc2["mechanism"], "coupler": 4.5}


def test_ctrl_z_in_a_field_being_typed_is_the_browsers(page: Any, server_url: str) -> None:
    _open(page, server_url)
    _type_and_enter(page, "[data-path='mechanism.rocker']", "6.5")
    doc1 = _doc(page)
    _drag_point(page, "P", -25, 15)
    doc2 = _doc(page)
    assert doc2 != doc1
    field = page.locator("[data-path='mechanism.crank']")
    field.click()
    field.press("End")
    page.keyboard.type(".5")
    assert field.input_value() == "1.5"
    # the keystrokes are the field's own to undo; the document is not touched
    page.keyboard.press("Control+z")
    assert field.input_value() == "1"
    page.wait_for_timeout(200)
    assert _doc(page) == doc2
    # with nothing typed, Ctrl+Z in the field undoes the last edit: the drag, not a text
    before = _scenes(page)
    page.keyboard.press("Control+z")
    _settle(page, before)
    assert _doc(page) == doc1

    # a title is one step once typed (Enter), and undone like the rest
    page.fill("#doc-title", "my linkage")
    page.press("#doc-title", "Enter")
    assert _doc(page)["title"] == "my linkage"
    assert _undo_count(page) == (2, 0)
    page.locator("#drawing").focus()
    before = _scenes(page)
    page.keyboard.press("Control+z")
    _settle(page, before)
    assert _doc(page) == doc1
    assert page.input_value("#doc-title") == doc1["title"]


def test_rejected_values_leave_the_document_and_say_which_field(page: Any, server_url: str) -> None:
    _open(page, server_url)
    doc0 = _doc(page)
    scenes = _scenes(page)

    # typing does not apply: no scene for "1", "1e", "1e1" on the way to "1e12"
    page.click(B0X)
    page.fill(B0X, "")
    page.keyboard.type("1e12", delay=30)
    page.wait_for_timeout(300)
    assert _scenes(page) == scenes and _doc(page) == doc0

    for text in ("1e12", "", "abc"):
        page.fill(B0X, text)
        page.press(B0X, "Enter")
        page.wait_for_function("document.getElementById('status').dataset.kind === 'error'")
        _settle(page)
        message = page.inner_text("#status")
        assert message.startswith("B0 x: "), message
        assert "mechanism" not in message and "document:" not in message, message
        expect(page.locator(f"{B0X}.invalid")).to_have_count(1)
        # the drawing is still the last valid document: B0 where the document puts it
        assert _doc(page) == doc0
        assert _scenes(page) == scenes
        assert page.evaluate("lw.pose().B0") == pytest.approx(doc0["mechanism"]["B0"], abs=1e-12)
        assert page.input_value(B0X) == text
        page.evaluate("lw.status('', 'info')")
    # what the server objected to is named in the page's words (the crank, not its path)
    page.fill(B0X, "1e12")
    page.press(B0X, "Enter")
    page.wait_for_function("document.getElementById('status').dataset.kind === 'error'")
    assert re.match(r"B0 x: 1e12 not applied: crank is 1(\.0)?, ", page.inner_text("#status"))

    # Esc puts the document's value back; leaving the field with a good value applies it
    page.press(B0X, "Escape")
    assert page.input_value(B0X) == "3.5"
    expect(page.locator("#fields .invalid")).to_have_count(0)
    page.fill(B0X, "4")
    page.press(B0X, "Tab")
    _settle(page, scenes)
    assert _doc(page)["mechanism"] == {**doc0["mechanism"], "B0": [4.0, 0.0]}
    pose = page.evaluate("lw.pose()")
    assert math.dist(pose["B0"], pose["B"]) == pytest.approx(doc0["mechanism"]["rocker"], abs=1e-9)

    # a linkage of joints: the server's `mechanism.joints[3].r1` is the field "C r1"
    before = _scenes(page)
    page.select_option("#example-select", "jansen-leg")
    _settle(page, before)
    field = "[data-path='mechanism.joints.3.r1']"
    assert page.inner_text(f"label[for='{page.get_attribute(field, 'id')}']") == "C r1"
    for text, said in (
        ("-1", "C r1: must be a positive number, got -1"),
        ("1e12", "C r1: 1e12 not applied: A length is 15"),
    ):
        page.fill(field, text)
        page.press(field, "Enter")
        expect(page.locator("#status")).to_contain_text(said)
        assert "joints" not in page.inner_text("#status")


def test_reload_keeps_the_work_and_leaving_asks_first(page: Any, server_url: str) -> None:
    dialogs: list[str] = []

    def answer(dialog: Any) -> None:
        dialogs.append(dialog.type)
        dialog.accept()

    page.on("dialog", answer)
    _open(page, server_url)
    _type_and_enter(page, "[data-path='mechanism.crank']", "1.25")
    page.mouse.move(700, 400)
    page.mouse.wheel(0, -300)
    page.locator("#drawing").focus()
    for _ in range(7):
        page.keyboard.press("ArrowRight")
    doc, at, view = _doc(page), page.evaluate("lw.at()"), page.evaluate("lw.view()")

    page.reload()
    page.wait_for_function(f"{SCENES} >= 1")
    _settle(page)
    assert dialogs == ["beforeunload"]
    assert _doc(page) == doc
    assert page.evaluate("lw.at()") == at
    again = page.evaluate("lw.view()")
    assert again["scale"] == pytest.approx(view["scale"], rel=1e-12)
    assert again["origin"] == pytest.approx(view["origin"], abs=1e-6)
    assert "Restored your unsaved work" in page.inner_text("#status")
    assert page.input_value("[data-path='mechanism.crank']") == "1.25"

    # the way back to the example; then nothing is unsaved and leaving does not ask
    before = _scenes(page)
    page.click("#status-action")
    _settle(page, before)
    assert _doc(page) == _example(page, "crank-rocker")
    page.reload()
    page.wait_for_function(f"{SCENES} >= 1")
    _settle(page)
    assert dialogs == ["beforeunload"]
    assert _doc(page) == _example(page, "crank-rocker")


def _payload(link: str) -> dict[str, Any]:
    """The state a link carries, decoded here (zlib and base64), not by the page."""
    text = link.split("#s=", 1)[1]
    kind, data = text.split(".", 1)
    raw = base64.urlsafe_b64decode(data + "=" * (-len(data) % 4))
    return json.loads(zlib.decompress(raw, -15) if kind == "z" else raw)


def _copy_link(page: Any) -> str:
    page.click("#copy-link")
    expect(page.locator("#status")).to_contain_text("Link copied")
    return str(page.evaluate("navigator.clipboard.readText()"))


def test_a_copied_link_opens_the_same_state_in_a_fresh_page(
    page: Any, browser: Any, server_url: str
) -> None:
    page.context.grant_permissions(["clipboard-read", "clipboard-write"])
    _open(page, server_url)
    _type_and_enter(page, "[data-path='mechanism.coupler']", "4.75")
    before = _scenes(page)
    page.locator("#modes [aria-checked='false']").click()
    _settle(page, before)
    page.mouse.move(650, 380)
    page.mouse.wheel(0, 250)
    page.fill("#input-slider", "200")
    state = page.evaluate("({doc: lw.document(), at: lw.at(), view: lw.view()})")
    link = _copy_link(page)
    assert link.startswith(server_url) and "#s=z." in link
    carried = _payload(link)
    assert carried["d"] == state["doc"] and carried["a"] == state["at"]

    fresh = browser.new_context(viewport={"width": 1400, "height": 900})
    try:
        other = fresh.new_page()
        _open(other, link)
        assert _doc(other) == state["doc"]
        assert other.evaluate("lw.document().mechanism.assembly") == -1
        assert other.evaluate("lw.at()") == state["at"]
        view = other.evaluate("lw.view()")
        assert view["scale"] == pytest.approx(state["view"]["scale"], rel=1e-12)
        assert view["origin"] == pytest.approx(state["view"]["origin"], abs=1e-6)
        assert other.input_value("#input-slider") == page.input_value("#input-slider")
        assert "Opened a shared link" in other.inner_text("#status")
        # the link is spent: the address no longer carries it
        assert "#s=" not in other.url

        # a spherical linkage turned by the mouse: the same rotation and zoom
        before = _scenes(page)
        page.select_option("#example-select", "paper000-fig6-crank-rocker")
        _settle(page, before)
        page.mouse.move(600, 420)
        page.mouse.down()
        page.mouse.move(660, 380, steps=5)
        page.mouse.up()
        page.mouse.wheel(0, -200)
        view = page.evaluate("lw.view()")
        link = _copy_link(page)
        # pasted into the address bar of a page at work: only the fragment changes
        before = _scenes(other)
        other.goto(link)
        _settle(other, before)
        assert _doc(other) == _doc(page)
        got = other.evaluate("lw.view()")
        assert got["rotation"] == pytest.approx(view["rotation"], abs=1e-12)
        assert got["zoom"] == pytest.approx(view["zoom"], rel=1e-12)
        assert other.evaluate("lw.at()") == page.evaluate("lw.at()")
        # a damaged one pasted there says so and leaves the work on screen
        other.goto(f"{server_url}/#s=j.e30")
        expect(other.locator("#status")).to_contain_text("This link cannot be opened")
        assert _doc(other) == _doc(page)
    finally:
        fresh.close()


def _plain_link(server_url: str, payload: Any) -> str:
    data = base64.urlsafe_b64encode(json.dumps(payload).encode()).decode().rstrip("=")
    return f"{server_url}/#s=j.{data}"


@pytest.mark.parametrize(
    ("case", "said"),
    [
        ("damaged", "not a linkwright state"),
        ("cut", "not a linkwright state"),
        ("version", "another version of linkwright (state format 7)"),
        ("refused", "crank: must be a positive number"),
    ],
)
def test_a_bad_link_says_so_and_opens_the_default_example(
    page: Any, server_url: str, case: str, said: str
) -> None:
    good = {"v": 1, "d": {"format": "linkwright/1", "mechanism": {"family": "fourbar"}}}
    if case == "damaged":
        link = f"{server_url}/#s=z.@@not-base64"
    elif case == "cut":
        deflated = zlib.compressobj(9, zlib.DEFLATED, -15)
        raw = deflated.compress(json.dumps(good).encode()) + deflated.flush()
        data = base64.urlsafe_b64encode(raw[: len(raw) // 2]).decode().rstrip("=")
        link = f"{server_url}/#s=z.{data}"
    elif case == "version":
        link = _plain_link(server_url, {**good, "v": 7})
    else:
        with urllib.request.urlopen(f"{server_url}/api/examples/crank-rocker") as r:
            doc = json.load(r)
        doc["mechanism"]["crank"] = -1
        link = _plain_link(server_url, {"v": 1, "d": doc})
    _open(page, link)
    message = page.inner_text("#status")
    assert page.get_attribute("#status", "data-kind") == "error"
    assert "\n" not in message and said in message, message
    assert "default example" in message
    assert _doc(page) == _example(page, "crank-rocker")


def test_the_history_keeps_the_last_200_steps(page: Any, server_url: str) -> None:
    _open(page, server_url)
    # titles are steps that need no scene, so 205 of them take no time
    page.evaluate(
        """() => {
        const box = document.getElementById('doc-title');
        for (let k = 1; k <= 205; k++) {
            box.value = `title ${k}`;
            box.dispatchEvent(new Event('input', {bubbles: true}));
            box.dispatchEvent(new Event('change', {bubbles: true}));
        }
    }"""
    )
    assert page.evaluate("lw.history()") == {"undo": 199, "redo": 0, "dirty": True}
    assert _doc(page)["title"] == "title 205"
    page.locator("#drawing").focus()
    for k in (204, 203):
        before = _scenes(page)
        page.keyboard.press("Control+z")
        _settle(page, before)
        assert _doc(page)["title"] == f"title {k}"
