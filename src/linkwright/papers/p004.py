"""Paper 004 (Kiper, Akbalçık, Şen): the double slider's ellipse, checked on random linkages.

The paper's analysis half is eqs. 1–5: the coupler point of a double slider (eq. 1, with the
loop closure of eq. 2) traces the conic of eq. 3, whose discriminant δ (eq. 4) is negative and
which is real (eq. 5). SEED-NOTES adds that eq. 3's coefficients are already normalised
(δ² = −16Δ, eq. 9) for every double slider. :func:`forward_check` verifies all of it on random
double sliders simulated by the engine; the synthesis half (eqs. 7–14, the ∞² family) belongs to
``linkwright synth ellipse``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from linkwright.analysis.conic import conic_invariants, doubleslider_conic, ellipse_axes
from linkwright.mechanisms import DoubleSlider, solve

__all__ = ["forward_check", "reproduce"]


def random_doublesliders(count: int, seed: int = 4) -> DoubleSlider:
    """``count`` double sliders: α in [6°, 174°], β any, p, q, h in [−4, 4], M in [−10, 10]²."""
    rng = np.random.default_rng(seed)
    return DoubleSlider(
        M=rng.uniform(-10, 10, (count, 2)),
        alpha=rng.uniform(0.1, np.pi - 0.1, count),
        beta=rng.uniform(-np.pi, np.pi, count),
        p=rng.uniform(-4, 4, count),
        q=rng.uniform(-4, 4, count),
        h=rng.uniform(-3, 3, count),
    )


def forward_check(count: int = 10_000, samples: int = 64, seed: int = 4) -> dict[str, Any]:
    """Eq. 3 on sampled curves, δ < 0 (eq. 4), the real ellipse (eq. 5) and eq. 9.

    Returns the worst relative values over ``count`` random double sliders: ``conic_residual``
    (|eq. 3| over the sum of its terms' magnitudes at each sampled point), ``eq9`` (|δ² + 16Δ|
    over δ²), ``delta_vs_K`` (|δ + 4K²| over 4K², K = h² + cot α·(p + q)·h − p·q) and the number of
    linkages whose δ is not negative or whose C·Δ is not negative (both should be 0; the
    second is judged away from segment-thin ellipses, where Δ = −K⁴ rounds to either sign).

    Examples
    --------
    >>> r = forward_check(count=200)
    >>> r["conic_residual"] < 1e-12, r["not_elliptic"], r["not_real"]
    (True, 0, 0)
    """
    m = random_doublesliders(count, seed)
    theta = np.linspace(0.0, 2.0 * np.pi, samples, endpoint=False)
    p = solve(m, theta, order=0).positions["P"]
    c = doubleslider_conic(m)
    x, y = p[..., 0], p[..., 1]
    terms = [c[..., i, None] * t for i, t in enumerate((x * x, x * y, y * y, x, y, 1.0 + 0 * x))]
    residual = np.abs(np.sum(terms, axis=0)) / np.sum(np.abs(terms), axis=0)
    delta, big = conic_invariants(c)
    k = m.h**2 + (m.p + m.q) * m.h / np.tan(m.alpha) - m.p * m.q
    clear = k**2 > 1e-3 * (c[..., 0] + c[..., 2]) ** 2  # away from segment-thin ellipses
    return {
        "count": count,
        "samples": samples,
        "conic_residual": float(residual.max()),
        "eq9": float(np.max(np.abs(delta**2 + 16 * big)[clear] / (delta**2)[clear])),
        "delta_vs_K": float(np.max(np.abs(delta + 4 * k**2)[clear] / (4 * k**2)[clear])),
        "not_elliptic": int(np.sum(delta >= 0)),
        # A thin ellipse's Δ = −K⁴ is a rounding away from 0: judged where K is clear of it.
        "not_real": int(np.sum((c[..., 2] * big >= 0) & clear)),
    }


def reproduce(out_dir: str | Path) -> list[Path]:
    """Write the forward check and a picture of a general double slider with its ellipse."""
    from linkwright.plot import new_figure, save_figure
    from linkwright.plot.generic import draw_pose

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    check = forward_check()
    m = DoubleSlider(M=[1.0, 2.0], alpha=np.radians(70), beta=np.radians(20), p=2.0, q=1.0, h=0.5)
    coeffs = doubleslider_conic(m)
    axes = ellipse_axes(coeffs)
    fig = new_figure((7, 6))
    ax = fig.add_subplot()
    curve = solve(m, np.linspace(0, 2 * np.pi, 361), order=0)
    ax.plot(*curve.positions["P"].T, color="#c0392b", lw=1.4, label="path of P (simulated)")
    # The conic of eq. 3 drawn independently, as its zero contour.
    xs = np.linspace(*ax.get_xlim(), 400)
    ys = np.linspace(*ax.get_ylim(), 400)
    gx, gy = np.meshgrid(xs, ys)
    a, b, c, d, e, f = coeffs
    ax.contour(
        gx,
        gy,
        a * gx**2 + b * gx * gy + c * gy**2 + d * gx + e * gy + f,
        [0.0],
        colors="k",
        linewidths=0.6,
        linestyles=":",
    )
    for k in (0, 90, 200):
        draw_pose(ax, m, curve, k, alpha=1.0 if k == 0 else 0.35)
    ax.set_aspect("equal")
    ax.legend(loc="best", fontsize=8)
    ax.set_title("Double slider (α = 70°, β = 20°, p = 2, q = 1, h = 0.5) and eq. 3 (dotted)")
    picture = save_figure(fig, out / "p004-doubleslider.png")
    lines = [
        "# Paper 004, forward relations",
        "",
        f"{check['count']} random double sliders (α in [6°, 174°], β any, p, q, h in [−4, 4], "
        f"M in [−10, 10]²), {check['samples']} samples of P each, simulated by the engine:",
        "",
        "| check | worst relative value |",
        "|---|---|",
        f"| eq. 3 at every sampled P | {check['conic_residual']:.2e} |",
        f"| eq. 9, δ² = −16Δ (already normalised) | {check['eq9']:.2e} |",
        f"| δ = −4K² (eq. 4) | {check['delta_vs_K']:.2e} |",
        f"| linkages with δ ≥ 0 | {check['not_elliptic']} |",
        f"| linkages with C·Δ ≥ 0 (imaginary) | {check['not_real']} |",
        "",
        f"The pictured linkage: ellipse centre {np.round(axes['center'], 6).tolist()}, semi-axes "
        f"{float(axes['semi_major']):.6f} and {float(axes['semi_minor']):.6f}, major axis at "
        f"{float(np.degrees(axes['orientation'])):.4f}°. Picture: {picture.name}.",
        "",
    ]
    page = out / "paper004.md"
    page.write_text("\n".join(lines), encoding="utf-8")
    return [picture, page]
