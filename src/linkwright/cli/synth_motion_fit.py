"""``linkwright synth motion`` beyond exact Burmester: the four-bars, slider-cranks and double
sliders that come closest to n ≥ 3 poses (:func:`linkwright.synthesis.motion_fit.fit_motion`),
as a report."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

MAX_POSES = 200
"""The most poses an approximate fit takes (each linkage is simulated at every one)."""


def approximate_report(
    points: NDArray[np.float64], angles: NDArray[np.float64], weight: float, top: int
) -> dict[str, Any]:
    """The ranked linkages as plain values (angles in degrees), every mechanism a document."""
    from dataclasses import replace

    from linkwright.synthesis.motion_fit import fit_motion

    fits = fit_motion(points, angles, angle_weight=weight, top=top)
    # The poses' spread: their diameter, as fit_motion weighs the angles by.
    spread = float(np.max(np.linalg.norm(points[:, None] - points[None], axis=-1)))
    designs = []
    for rank, f in enumerate(fits, start=1):
        designs.append({
            "rank": rank,
            "type": type(f.mechanism).__name__,
            "dyads": [d.kind for d in f.dyads],
            "error": f.error,
            "rms_position_error": float(np.sqrt(np.mean(f.position_error**2))),
            "largest_position_error": float(np.max(f.position_error)),
            "largest_angle_error_deg": float(np.degrees(np.max(f.angle_error))),
            "branch_defect": f.branch_defect,
            "inputs_deg": np.degrees(f.inputs),
            "angle_offset_deg": float(np.degrees(f.angle_offset)),
            # Its start, the input at the first pose, names the circuit that passes them.
            "mechanism": replace(f.mechanism, start=float(f.inputs[0])),
        })  # fmt: skip
    return {
        "method": "least squares",
        "poses": len(points),
        "angle_weight": weight,
        "spread": spread,
        "designs": designs,
    }


def approximate_text(report: dict[str, Any]) -> str:
    from linkwright.cli.shared import mechanism_toml

    lines = [
        f"# {len(report['designs'])} linkages nearest to {report['poses']} poses (least squares; "
        f"error = Σ |ΔP|² + ({report['angle_weight']:g}·spread)²·Δα², spread "
        f"{report['spread']:.6g})"
    ]
    for d in report["designs"]:
        defect = "; branch defect: the poses lie on both branches" if d["branch_defect"] else ""
        lines.append(
            f"## {d['rank']}: {d['type']} of {'+'.join(d['dyads'])} dyads, error {d['error']:.4g}, "
            f"RMS position error {d['rms_position_error']:.4g}, largest angle error "
            f"{d['largest_angle_error_deg']:.4g}°{defect}\n"
            + "inputs (deg): " + ", ".join(f"{v:.6g}" for v in d["inputs_deg"]) + "\n"
            + mechanism_toml(d["mechanism"])
        )  # fmt: skip
    return "\n".join(lines)
