"""``linkwright demo``: pictures and a summary of every bundled example, and paper 003's tables.

What ``make run`` starts until the browser workbench exists. Everything goes into one folder; the
function returns the line that says where.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

__all__ = ["run_demo"]

SUMMARY_COLUMNS = (
    ("class", "class"),
    ("input range (°)", "input_range_deg"),
    ("swing (°)", "swing_deg"),
    ("stroke", "stroke"),
    ("γ min (°)", ("transmission_angle_deg", "min")),
    ("γ max (°)", ("transmission_angle_deg", "max")),
    ("time ratio", "time_ratio"),
    ("Kω", ("coefficients", "K_omega")),
    ("Kε", ("coefficients", "K_epsilon")),
    ("Kp", ("coefficients", "K_p")),
    ("δ", ("coefficients", "delta")),
)


def _cell(report: dict[str, Any], key: Any) -> str:
    value: Any = report
    for part in key if isinstance(key, tuple) else (key,):
        value = value.get(part) if isinstance(value, dict) else None
    if value is None:
        return "—"
    if isinstance(value, list):
        return "[" + ", ".join(f"{v:.2f}" for v in value) + "]"
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


def paper003_markdown() -> str:
    """Paper 003's planar tables as a markdown page, printed values beside ours."""
    from linkwright.papers.p003 import reproduce_planar

    lines = [
        "# Paper 003, planar halves of Tables 1, 2 and 4",
        "",
        "Printed value beside linkwright's exact one (for the paper's printed inputs). "
        "`agrees`: within half a unit of the last printed digit, inputs taken within their own "
        "printed precision; `truncated`: the printed digits are ours cut, not rounded; "
        "`misprint`: listed in SEED-NOTES.md; `differs`: see the note below.",
        "",
        "| table | row | quantity | printed | linkwright | status |",
        "|---|---|---|---|---|---|",
    ]
    cells = reproduce_planar()
    for c in cells:
        lines.append(
            f"| {c.table} | {c.row} | {c.column} | {c.printed} | {c.ours:.4f} | {c.status} |"
        )
    differs = [c for c in cells if c.status == "differs"]
    lines += [
        "",
        f"{len(cells)} cells: "
        + ", ".join(
            f"{sum(c.status == s for c in cells)} {s}"
            for s in ("agrees", "agrees (truncated)", "misprint", "differs")
        )
        + ".",
        "",
        f"The {len(differs)} cells that differ are all max|Kp|, printed 0.1–0.6 % below the "
        "exact maximum, the direction in which a sampled or smoothed maximum errs. linkwright's "
        "maxima are checked against a dense closed-form (Freudenstein) sampling in the tests.",
    ]
    return "\n".join(lines) + "\n"


def _row_view(family: str, report: dict[str, Any]) -> dict[str, Any]:
    """The summary columns for a family without paper 003's report: its family as the class,
    its input arc, and the transmission angle's extremes over all its dyads."""
    if "class" in report:
        return report
    angles = report.get("transmission_angle_deg", {}).values()
    lows = [a["min"] for a in angles if a["min"] is not None]
    highs = [a["max"] for a in angles if a["max"] is not None]
    arcs = report.get("input_arcs_deg") or []
    return {
        "class": family,
        "input_range_deg": arcs[0] if arcs and not report.get("input_turns_fully") else None,
        "transmission_angle_deg": {
            "min": min(lows) if lows else None,
            "max": max(highs) if highs else None,
        },
    }


def run_demo(out_dir: str | Path = "out") -> str:
    """Write every bundled example's curve and diagram pictures and a summary into ``out_dir``.

    Returns a one-line message naming the summary file.
    """
    from linkwright.analysis import analyze
    from linkwright.io import list_examples, load_example
    from linkwright.papers import p002, p004
    from linkwright.plot import plot_curves, plot_diagrams, save_figure
    from linkwright.plot.generic import plot_linkage, plot_speed

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    names = list_examples()
    reports: dict[str, Any] = {}
    rows = []
    for i, name in enumerate(names, 1):
        print(f"[{i}/{len(names)}] {name}", file=sys.stderr, flush=True)
        doc = load_example(name)
        report = analyze(doc.mechanism)
        reports[name] = {"title": doc.title, **report}
        if doc.mechanism.space == "sphere":
            from linkwright.plot.sphere import plot_spherical_linkage

            figure = plot_spherical_linkage(doc.mechanism, title=doc.title)
            save_figure(figure, out / f"{name}-curves.png")
            diagrams = plot_speed(doc.mechanism)
        elif doc.family in ("fourbar", "slidercrank"):
            save_figure(plot_curves(doc.mechanism, title=doc.title), out / f"{name}-curves.png")
            diagrams = plot_diagrams(doc.mechanism, title=doc.title)
        else:
            save_figure(plot_linkage(doc.mechanism, title=doc.title), out / f"{name}-curves.png")
            diagrams = plot_speed(doc.mechanism)
        save_figure(diagrams, out / f"{name}-diagrams.png")
        rows.append(
            f"| [{name}]({name}-curves.png) | {doc.title or ''} | "
            + " | ".join(_cell(_row_view(doc.family, report), key) for _, key in SUMMARY_COLUMNS)
            + " |"
        )
    print(f"[{len(names)}/{len(names)}] paper 003 tables", file=sys.stderr, flush=True)
    (out / "paper003-planar.md").write_text(paper003_markdown(), encoding="utf-8")
    print(f"[{len(names)}/{len(names)}] papers 002 and 004", file=sys.stderr, flush=True)
    extra = len(p002.reproduce(out)) + len(p004.reproduce(out))
    header = "| example | title | " + " | ".join(h for h, _ in SUMMARY_COLUMNS) + " |"
    rule = "|" + "---|" * (len(SUMMARY_COLUMNS) + 2)
    summary = [
        "# linkwright demo",
        "",
        "Every bundled example analysed; pictures beside this file "
        "(`NAME-curves.png`, `NAME-diagrams.png`). Angles in degrees, measured from the frame "
        "line A0→B0 (slider: from the line's direction).",
        "",
        header,
        rule,
        *rows,
        "",
        "Paper 003's planar tables, reproduced: [paper003-planar.md](paper003-planar.md).",
        "Paper 002's five-bar study: [paper002.md](paper002.md); paper 004's double slider: "
        "[paper004.md](paper004.md).",
        "",
    ]
    (out / "summary.md").write_text("\n".join(summary), encoding="utf-8")
    (out / "summary.json").write_text(json.dumps(reports, indent=2) + "\n", encoding="utf-8")
    return f"wrote {2 * len(names) + 3 + extra} files to {out}/ — start with {out / 'summary.md'}"
