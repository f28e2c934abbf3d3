"""The README's atlas picture: a drawn curve, its best matches from the built-in atlas, and the
refined linkage at one pose.

    python bench/atlas_figure.py [--out docs/img/atlas-match.png]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from linkwright.atlas import default_atlas, query
from linkwright.mechanisms import solve

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "img" / "atlas-match.png")
    args = parser.parse_args()
    text = (ROOT / "src/linkwright/examples/drawn-curve.csv").read_text().splitlines()
    drawn = np.array([[float(v) for v in line.split(",")] for line in text[2:]])
    atlas = default_atlas("fourbar")
    plain = query(atlas, drawn, top=3)
    refined = query(atlas, drawn, top=1, refine=True)[0]
    theta = np.linspace(0.0, 2.0 * np.pi, 720)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.8))
    ax = axes[0]
    for k, m in enumerate(plain):
        P = solve(m.mechanism, theta, order=0).positions["P"]
        ax.plot(*P.T, lw=1.2, label=f"match {k + 1}: aligned error {m.error:.1%}")
    ax.plot(*np.vstack([drawn, drawn[:1]]).T, "k.", ms=5, label="drawn points")
    ax.set_title(f"best of {atlas.count:,} four-bar curves (no refinement)")
    ax.legend(fontsize=8, loc="lower left")
    ax = axes[1]
    motion = solve(refined.mechanism, theta, order=0)
    ax.plot(*motion.positions["P"].T, "C3", lw=1.5, label=f"refined: {refined.error:.2%}")
    ax.plot(*drawn.T, "k.", ms=5)
    pose = solve(refined.mechanism, [1.0], order=0).positions
    chain = [pose[j][0] for j in ("A0", "A", "B", "B0")]
    ax.plot(*np.array(chain).T, "o-", color="0.3", lw=2, ms=5)
    ax.fill(*np.array([pose[j][0] for j in ("A", "B", "P")]).T, color="C0", alpha=0.3)
    ax.plot(*pose["P"][0], "C0o")
    ax.set_title("refined and placed where the curve was drawn")
    ax.legend(fontsize=8, loc="lower left")
    for ax in axes:
        ax.set_aspect("equal")
        ax.grid(alpha=0.3)
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=110)
    print(args.out)


if __name__ == "__main__":
    main()
