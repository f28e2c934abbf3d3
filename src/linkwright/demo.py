"""``linkwright demo``: pictures and a summary of every bundled example, and the seed papers.

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
        return "[" + ", ".join("—" if v is None else f"{v:.2f}" for v in value) + "]"
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


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


# Examples the demo also animates (a GIF each): a planar crank-rocker and a spherical one.
ANIMATED = ("crank-rocker", "paper000-fig6-crank-rocker")


def run_demo(out_dir: str | Path = "out") -> str:
    """Write every bundled example's curve and diagram pictures and a summary into ``out_dir``.

    Returns a one-line message naming the summary file.
    """
    from linkwright.analysis import analyze
    from linkwright.io import list_examples, load_example
    from linkwright.io.report import analysis_report
    from linkwright.papers import p000, p001, p002, p003, p004
    from linkwright.plot import (
        DiagramError,
        PlotError,
        animate,
        plot_diagram,
        plot_mechanism,
        save_figure,
    )

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    names = list_examples()
    reports: dict[str, Any] = {}
    rows = []
    for i, name in enumerate(names, 1):
        print(f"[{i}/{len(names)}] {name}", file=sys.stderr, flush=True)
        doc = load_example(name)
        report = analysis_report(analyze(doc.mechanism))
        reports[name] = {"title": doc.title, **report}
        try:
            save_figure(plot_mechanism(doc.mechanism, title=doc.title), out / f"{name}-curves.png")
            save_figure(
                plot_diagram(doc.mechanism, "angles", title=doc.title), out / f"{name}-diagrams.png"
            )
        except (PlotError, DiagramError) as exc:  # an example driven where no plan reaches
            print(f"  {name}: no picture ({exc})", file=sys.stderr, flush=True)
        if name in ANIMATED:
            animate(doc.mechanism, out / f"{name}.gif", frames=72, fps=24, dpi=80, title=doc.title)
        rows.append(
            f"| [{name}]({name}-curves.png) | {doc.title or ''} | "
            + " | ".join(_cell(_row_view(doc.family, report), key) for _, key in SUMMARY_COLUMNS)
            + " |"
        )
    extra = 0
    for paper in (p000, p001, p002, p003, p004):
        number = paper.__name__[-3:]
        print(f"[{len(names)}/{len(names)}] paper {number}", file=sys.stderr, flush=True)
        extra += len(paper.reproduce(out))
    header = "| example | title | " + " | ".join(h for h, _ in SUMMARY_COLUMNS) + " |"
    rule = "|" + "---|" * (len(SUMMARY_COLUMNS) + 2)
    summary = [
        "# linkwright demo",
        "",
        "Every bundled example analysed; pictures beside this file "
        "(`NAME-curves.png`, `NAME-diagrams.png`; animations `crank-rocker.gif` and "
        "`paper000-fig6-crank-rocker.gif`). Angles in degrees; input ranges are absolute "
        "(counter-clockwise from +x, as `linkwright solve --input` takes them).",
        "",
        header,
        rule,
        *rows,
        "",
        "The seed papers regenerated, our numbers beside the printed ones: "
        "[paper000.md](paper000.md) (spherical coupler curves), "
        "[paper001.md](paper001.md) (spherical Stephenson III configurations), "
        "[paper002.md](paper002.md) (geared five-bar), "
        "[paper003.md](paper003.md) (Tables 1-4, planar and spherical), "
        "[paper004.md](paper004.md) (double slider). "
        "What we found wrong in print: `linkwright papers errata`.",
        "",
    ]
    (out / "summary.md").write_text("\n".join(summary), encoding="utf-8")
    (out / "summary.json").write_text(
        json.dumps(reports, indent=2, allow_nan=False) + "\n", encoding="utf-8"
    )
    return f"wrote {2 * len(names) + 2 + extra} files to {out}/ — start with {out / 'summary.md'}"
