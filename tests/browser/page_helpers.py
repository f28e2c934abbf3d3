"""Page helpers shared by the workbench's browser tests (one copy, not one per file)."""

from __future__ import annotations


def scene_count(page) -> int:
    return int(page.evaluate("Number(document.body.dataset.sceneCount || 0)"))


def wait_scene_after(page, count: int) -> None:
    page.wait_for_function(f"Number(document.body.dataset.sceneCount) > {count}")
    page.wait_for_function("document.body.dataset.busy !== '1'")


def show_tab(page, name: str) -> None:
    page.click(f"#side .tabs button[data-tab={name}]")
    page.wait_for_selector(f"#tab-{name}:not([hidden])")


def status(page) -> str:
    return page.inner_text("#status")


def wait_state(page, tab: str, state: str = "done", timeout: float = 60_000) -> None:
    page.wait_for_selector(f"#tab-{tab}[data-state={state}]", timeout=timeout)


def draw_with_mouse(page, points_px: list[list[float]]) -> None:
    box = page.locator("#drawing").bounding_box()
    x0, y0 = box["x"], box["y"]
    page.mouse.move(x0 + points_px[0][0], y0 + points_px[0][1])
    page.mouse.down()
    for x, y in points_px[1:] + points_px[:1]:
        page.mouse.move(x0 + x, y0 + y, steps=2)
    page.mouse.up()
