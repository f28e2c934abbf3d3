"""The side panel's tools, used like a person would: the library (save, rename, load, delete,
import, export), paper 002's pivot study, synthesis (draw a curve with the mouse or import a
CSV, match it against the atlas, pick a candidate; fit an ellipse and browse the double
sliders with a slider) and the exports (each download's bytes read back).

The page is driven with clicks, typing, mouse drags and file choosers; assertions read what the
page shows (the panels' rows and texts, the status line, the drawing's legend) and, where the
shown number is rounded, the page's current document through ``window.lw``.
"""

from __future__ import annotations

import csv
import io
import json
import math
import tomllib
import uuid
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from playwright.sync_api import expect

from .page_helpers import (
    draw_with_mouse,
    scene_count,
    show_tab,
    status,
    wait_scene_after,
    wait_state,
)


def open_workbench(page, server_url: str, example: str = "crank-rocker") -> None:
    page.goto(server_url)
    page.wait_for_function("window.lw && Number(document.body.dataset.sceneCount) >= 1")
    page.wait_for_selector("#tab-library #lib-save")
    if page.evaluate("lw.document().title") != page.evaluate(
        f"fetch('/api/examples/{example}').then(r => r.json()).then(d => d.title)"
    ):
        before = scene_count(page)
        page.select_option("#example-select", example)
        wait_scene_after(page, before)


def lw_document(page) -> dict:
    return page.evaluate("lw.document()")


# --------------------------------------------------------------------------------------------
# Library
# --------------------------------------------------------------------------------------------


def entry(page, name: str):
    return page.locator(f"#lib-list [data-testid=lib-entry][data-name={json.dumps(name)}]")


def save_to_library(page, server_url: str, prefix: str) -> str:
    """Open the workbench's library tab and save the current mechanism under a fresh name."""
    open_workbench(page, server_url)
    show_tab(page, "library")
    name = f"{prefix} {uuid.uuid4().hex[:6]}"
    page.fill("#lib-name", name)
    page.click("#lib-save")
    page.wait_for_selector(f"text=saved “{name}” in the library")
    return name


def test_library_save_rename_load_delete(page, server_url: str):
    name = save_to_library(page, server_url, "my crank")
    row = entry(page, name)
    expect(row).to_have_count(1)
    assert "fourbar" in row.locator("[data-testid=lib-entry-meta]").inner_text()

    # Saving under the same name asks before replacing.
    page.click("#lib-save")
    page.wait_for_selector("#lib-conflict:not([hidden])")
    assert "already in the library" in page.inner_text("#lib-conflict")
    page.click("#lib-overwrite")
    page.wait_for_selector("#lib-conflict[hidden]", state="attached")
    wait_state(page, "library")
    expect(entry(page, name)).to_have_count(1)

    # Rename it inline.
    renamed = name.replace("my crank", "renamed crank")
    entry(page, name).locator("[data-testid=lib-rename]").click()
    field = page.locator("[data-testid=lib-rename-input]")
    field.fill(renamed)
    field.press("Enter")
    page.wait_for_selector(f"text=renamed “{name}” to “{renamed}”")
    expect(entry(page, name)).to_have_count(0)
    expect(entry(page, renamed)).to_have_count(1)

    # Load another mechanism, then load the saved one back.
    before = scene_count(page)
    page.select_option("#example-select", "double-crank")
    wait_scene_after(page, before)
    assert "Crank-rocker" not in page.input_value("#doc-title")
    before = scene_count(page)
    entry(page, renamed).locator("[data-testid=lib-load]").click()
    wait_scene_after(page, before)
    assert page.input_value("#doc-title") == "Crank-rocker (paper 003, Table 1)"
    assert lw_document(page)["mechanism"]["rocker"] == 6.02
    assert f"loaded “{renamed}”" in status(page)

    # Delete asks first; "Keep" keeps it, "Delete" deletes it.
    entry(page, renamed).locator("[data-testid=lib-delete]").click()
    page.click("[data-testid=lib-delete-cancel]")
    expect(entry(page, renamed)).to_have_count(1)
    entry(page, renamed).locator("[data-testid=lib-delete]").click()
    page.click("[data-testid=lib-delete-confirm]")
    page.wait_for_selector(f"text=deleted “{renamed}” from the library")
    expect(entry(page, renamed)).to_have_count(0)
    names = [e["name"] for e in page.evaluate("fetch('/api/library').then(r => r.json())")]
    assert renamed not in names


def test_library_refresh_keeps_an_open_rename(page, server_url: str):
    """A refresh of the list (another save, the ↻ button) must not throw away a half-typed name."""
    name = save_to_library(page, server_url, "kept crank")
    entry(page, name).locator("[data-testid=lib-rename]").click()
    field = page.locator("[data-testid=lib-rename-input]")
    field.fill("half typed")
    # element.click() from script refreshes without taking the focus, as a save elsewhere would.
    page.evaluate("document.querySelector('#lib-refresh').click()")
    page.wait_for_function("document.querySelector('#lib-count').textContent !== ''")
    page.wait_for_timeout(300)
    expect(field).to_have_value("half typed")
    assert page.evaluate("document.activeElement.dataset.testid") == "lib-rename-input"
    field.press("Escape")
    expect(field).to_have_count(0)
    expect(entry(page, name).locator("[data-testid=lib-rename]")).to_have_count(1)
    # The delete question survives a refresh too, and "Keep" closes it.
    entry(page, name).locator("[data-testid=lib-delete]").click()
    page.evaluate("document.querySelector('#lib-refresh').click()")
    page.wait_for_timeout(300)
    page.click("[data-testid=lib-delete-cancel]")
    expect(entry(page, name).locator("[data-testid=lib-delete]")).to_have_count(1)


def test_library_import_and_export(page, server_url: str, tmp_path: Path):
    open_workbench(page, server_url)
    show_tab(page, "library")
    stem = f"imported-{uuid.uuid4().hex[:6]}"
    doc = tmp_path / f"{stem}.toml"
    doc.write_text(
        f'format = "linkwright/1"\ntitle = "Imported four-bar {stem}"\n\n[mechanism]\n'
        'family = "fourbar"\nA0 = [0.0, 0.0]\nB0 = [4.0, 0.0]\ncrank = 1.0\ncoupler = 5.0\n'
        "rocker = 3.5\n",
        encoding="utf-8",
    )
    page.set_input_files("#lib-import-file", str(doc))
    page.wait_for_selector(f"text=imported {doc.name}")
    row = page.locator("#lib-list [data-testid=lib-entry]", has_text=stem)
    expect(row).to_have_count(1)

    with page.expect_download() as download:
        row.locator("[data-testid=lib-export-toml]").click()
    data = tomllib.loads(Path(download.value.path()).read_text(encoding="utf-8"))
    assert data["title"] == f"Imported four-bar {stem}" and data["mechanism"]["rocker"] == 3.5
    with page.expect_download() as download:
        row.locator("[data-testid=lib-export-json]").click()
    assert json.loads(Path(download.value.path()).read_bytes())["mechanism"]["coupler"] == 5.0

    # A file that is not a document is refused with the reason.
    bad = tmp_path / "broken.toml"
    bad.write_text('format = "linkwright/1"\n[mechanism]\nfamily = "fourbar"\ncrank = -1\n')
    page.set_input_files("#lib-import-file", str(bad))
    page.wait_for_selector("#status[data-kind=error]")
    assert "import:" in status(page) and "mechanism" in status(page)


# --------------------------------------------------------------------------------------------
# Paper 002's pivot study
# --------------------------------------------------------------------------------------------


def test_study_overlays_one_curve_per_step(page, server_url: str):
    """The crank-rocker's B0 moved right 1 at a time: the crank turns fully up to frame 10.02,
    rocks to 12.02 and cannot assemble beyond (closed form, see the API tests)."""
    open_workbench(page, server_url)
    show_tab(page, "study")
    page.select_option("#study-pivot", "B0")
    page.select_option("#study-direction", "right")
    page.fill("#study-step", "1")
    page.fill("#study-count", "10")
    page.click("#study-run")
    wait_state(page, "study")
    rows = page.locator("[data-testid=study-row]")
    expect(rows).to_have_count(11)
    states = [rows.nth(i).locator("[data-testid=study-state]").inner_text() for i in range(11)]
    assert states == ["turns fully"] * 7 + ["locks: rocks"] * 2 + ["cannot assemble"] * 2
    assert rows.nth(3).locator(".study-text").inner_text() == "step 3: (3, 0)"
    legend = page.inner_text("#legend")
    assert "study: start (0, 0)" in legend and "step 10 (10, 0)" in legend
    assert "4 where the input no longer turns fully" in page.inner_text("#study-note")

    # Load step 2: B0 has moved 2 to the right, the rest is as it was.
    before = scene_count(page)
    rows.nth(2).locator("[data-testid=study-load]").click()
    wait_scene_after(page, before)
    mech = lw_document(page)["mechanism"]
    assert mech["B0"] == [5.5, 0.0] and mech["A0"] == [0.0, 0.0] and mech["rocker"] == 6.02
    assert page.is_visible("#study-stale")

    page.click("#study-clear")
    expect(rows).to_have_count(0)
    assert "study" not in page.inner_text("#legend")


def test_study_geared_fivebar_by_angle(page, server_url: str):
    open_workbench(page, server_url, "geared-fivebar")
    show_tab(page, "study")
    page.select_option("#study-pivot", "A0")
    page.select_option("#study-direction", "angle")
    page.fill("#study-angle", "180")
    page.fill("#study-step", "0.5")
    page.fill("#study-count", "3")
    page.click("#study-run")
    wait_state(page, "study")
    assert "paper 002" in page.inner_text("#study-note")
    texts = page.locator("[data-testid=study-row] .study-text").all_inner_texts()
    assert texts == ["start: (0, 0)", "step 1: (−0.5, 0)", "step 2: (−1, 0)", "step 3: (−1.5, 0)"]
    # Another family's curves say nothing about a four-bar: choosing one clears the study.
    before = scene_count(page)
    page.select_option("#example-select", "crank-rocker")
    wait_scene_after(page, before)
    expect(page.locator("[data-testid=study-row]")).to_have_count(0)
    assert "study" not in page.inner_text("#legend")


# --------------------------------------------------------------------------------------------
# Synthesis
# --------------------------------------------------------------------------------------------


def test_synthesis_draw_match_and_choose(page, server_url: str):
    """Trace the crank-rocker's own coupler curve with the mouse, match it, load the best
    candidate: its curve lies within 2 % of the drawn curve's size."""
    open_workbench(page, server_url)
    show_tab(page, "synthesis")
    page.wait_for_selector("#tab-synthesis[data-atlas]", state="attached")
    target = page.evaluate(
        """() => {
          const P = lw.scene().modes.find((m) => m.own).circuits[0].positions.P;
          return P.filter((_, i) => i % 8 === 0);
        }"""
    )
    curve_px = page.evaluate("(pts) => pts.map((p) => lw.toScreen(p))", target)
    assert len(curve_px) >= 40
    page.click("#synth-draw")
    draw_with_mouse(page, curve_px)
    page.wait_for_selector("#tab-synthesis[data-target]")
    assert "points (drawn)" in page.inner_text("#synth-target-info")
    assert "target curve" in page.inner_text("#legend")

    page.click("#synth-match")
    wait_state(page, "synthesis", timeout=120_000)
    cands = page.locator("[data-testid=synth-candidate]")
    assert cands.count() >= 1
    assert "Atlas:" in page.inner_text("#synth-atlas")
    best = float(cands.first.get_attribute("data-error"))
    assert best < 0.02, best
    assert "off by" in cands.first.inner_text()

    before = scene_count(page)
    cands.first.click()
    wait_scene_after(page, before)
    doc = lw_document(page)
    assert doc["mechanism"]["family"] == "fourbar" and doc["title"].startswith("Atlas match 1")
    assert "loaded candidate #1" in status(page)
    # The loaded four-bar's own curve, as the page draws it, runs along the drawn target.
    gap = page.evaluate(
        """(model) => {
          const sc = lw.scene();
          const P = sc.modes.find((m) => m.own).circuits[0].positions.P.filter(Boolean);
          let worst = 0;
          for (const q of model) {
            let best = Infinity;
            for (const p of P) best = Math.min(best, Math.hypot(p[0] - q[0], p[1] - q[1]));
            worst = Math.max(worst, best);
          }
          const xs = model.map((q) => q[0]), ys = model.map((q) => q[1]);
          const span = (v) => Math.max(...v) - Math.min(...v);
          const size = Math.max(span(xs), span(ys));
          return worst / size;
        }""",
        target,
    )
    assert gap < 0.05, gap


def ellipse_csv(path: Path, centre=(1.0, 2.0), axes=(3.0, 1.2), angle=25.0, n=36) -> Path:
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    c, s = math.cos(math.radians(angle)), math.sin(math.radians(angle))
    x, y = axes[0] * np.cos(t), axes[1] * np.sin(t)
    rows = np.column_stack((centre[0] + c * x - s * y, centre[1] + s * x + c * y))
    path.write_text("x,y\n" + "\n".join(f"{float(a)!r},{float(b)!r}" for a, b in rows) + "\n")
    return path


def test_synthesis_csv_ellipse_and_family_slider(page, server_url: str, tmp_path: Path):
    open_workbench(page, server_url)
    show_tab(page, "synthesis")
    page.set_input_files("#synth-csv", str(ellipse_csv(tmp_path / "ellipse.csv")))
    page.wait_for_selector("#tab-synthesis[data-target='36']")
    assert "36 points (ellipse.csv)" in page.inner_text("#synth-target-info")

    before = scene_count(page)
    page.click("#synth-ellipse")
    page.wait_for_selector("#tab-synthesis[data-s1]")
    wait_scene_after(page, before)
    info = page.inner_text("#synth-ellipse-info")
    assert "(1, 2)" in info and "3, 1.2" in info and "25°" in info
    assert "fitted ellipse" in page.inner_text("#legend")
    mech = lw_document(page)["mechanism"]
    assert mech["family"] == "doubleslider" and mech["alpha"] == pytest.approx(90.0)
    chips = page.locator("[data-testid=synth-family-member]")
    expect(chips).to_have_count(13)

    # Drag R's slider (s1) from 90° to about a quarter of its travel.
    track = page.locator("#synth-s1").bounding_box()
    y = track["y"] + track["height"] / 2
    page.mouse.move(track["x"] + track["width"] * 90 / 179.5, y)
    page.mouse.down()
    page.mouse.move(track["x"] + track["width"] * 0.25, y, steps=6)
    page.mouse.up()
    page.wait_for_function(
        "Number(document.querySelector('#tab-synthesis').dataset.s1) < 60"
        " && document.body.dataset.busy !== '1'"
    )
    s1 = float(page.get_attribute("#tab-synthesis", "data-s1"))
    s2 = float(page.get_attribute("#tab-synthesis", "data-s2"))
    assert s2 == 0.0 and 30 < s1 < 60
    assert page.inner_text("#synth-s1-value") == f"{s1:g}°"
    page.wait_for_function(
        f"Math.abs(lw.document().mechanism.alpha - {s1 - s2}) < 1e-9"
        " && lw.scene() && lw.scene().document.mechanism.alpha === lw.document().mechanism.alpha"
    )
    # The linkage now drawn traces the ellipse: its curve satisfies the ellipse's equation.
    curve = np.array(
        page.evaluate("lw.scene().modes.find((m) => m.own).circuits[0].positions.P"), dtype=float
    )
    c, s = math.cos(math.radians(25)), math.sin(math.radians(25))
    rel = curve - [1.0, 2.0]
    xp, yp = rel @ [c, s], rel @ [-s, c]
    assert np.abs((xp / 3.0) ** 2 + (yp / 1.2) ** 2 - 1).max() < 1e-8

    # A chip chooses a member of the family.
    chips.nth(2).click()
    s1c, s2c = (float(chips.nth(2).get_attribute(f"data-{k}")) for k in ("s1", "s2"))
    page.wait_for_function(f"Math.abs(lw.document().mechanism.alpha - ({s1c - s2c})) < 1e-9")


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        ("x,y\n0,0\n1,0\nabc,1\n", 'CSV line 4: "abc" is not a number'),
        ("x,y\n0,0\n1,0,5\n", "CSV line 3: 3 values; each line must be x, y"),
        ("0,0\n1,1\n", "CSV: 2 points"),
    ],
)
def test_synthesis_csv_errors(page, server_url: str, tmp_path: Path, text: str, needle: str):
    open_workbench(page, server_url)
    show_tab(page, "synthesis")
    path = tmp_path / "curve.csv"
    path.write_text(text)
    page.set_input_files("#synth-csv", str(path))
    page.wait_for_selector("#status[data-kind=error]")
    assert needle in status(page)
    assert page.is_disabled("#synth-match")


# --------------------------------------------------------------------------------------------
# Exports
# --------------------------------------------------------------------------------------------


def test_export_buttons_download_files(page, server_url: str):
    from PIL import Image

    open_workbench(page, server_url)
    show_tab(page, "export")
    files: dict[str, bytes] = {}
    for fmt in ("png", "svg", "dxf", "csv", "gif", "toml", "json"):
        with page.expect_download(timeout=60_000) as download:
            page.click(f"#export-{fmt}")
        assert download.value.suggested_filename == f"Crank-rocker-paper-003-Table-1.{fmt}"
        files[fmt] = Path(download.value.path()).read_bytes()
        wait_state(page, "export")
        assert f"{len(files[fmt]):,} bytes" in page.inner_text("#export-last")

    with Image.open(io.BytesIO(files["png"])) as im:
        assert im.format == "PNG" and im.size[0] > 300
    assert ET.fromstring(files["svg"]).tag.endswith("svg")

    import ezdxf

    assert not ezdxf.read(io.StringIO(files["dxf"].decode())).audit().has_errors
    rows = list(csv.reader(io.StringIO(files["csv"].decode())))
    assert rows[0][:3] == ["sample", "theta_deg", "theta_rad"] and len(rows) == 361
    with Image.open(io.BytesIO(files["gif"])) as gif:
        assert gif.n_frames == 48
    doc = lw_document(page)
    assert tomllib.loads(files["toml"].decode()) == doc
    assert json.loads(files["json"]) == doc


def test_export_reports_an_input_where_the_linkage_cannot_be(page, server_url: str):
    open_workbench(page, server_url, "rocker-input")
    show_tab(page, "export")
    # The rocker-input four-bar rocks over two arcs; the page's input angle is on the circuit,
    # so the drawing exports; the error path is shown for an input off it.
    with page.expect_download() as download:
        page.click("#export-svg")
    assert ET.fromstring(Path(download.value.path()).read_bytes()).tag.endswith("svg")
    page.evaluate("lw.at = () => 0")  # an input the linkage cannot take
    page.click("#export-png")
    page.wait_for_selector("#status[data-kind=error]")
    assert "export PNG: at θ = 0.0° the linkage does not assemble" in status(page)
