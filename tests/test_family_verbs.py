"""Every verb for every family: a matrix of (family, verb) cells, each run as a user runs it.

Rows: one bundled example per registered family (tests/family_examples.py), the composed
linkage in the plane and on the sphere, and the two linkages driven so that a triad remains
(the Stephenson III at its output, paper 001's spherical Stephenson III at FG). Columns: the
command line's verbs (``solve`` with ``--all`` and ``--derivatives``, ``curve`` also with
``--spacing path`` and ``--all``, ``analyze``, ``plot`` of each kind, ``animate``, ``export`` to
each format) and the workbench's scene and drag (its HTTP API, through FastAPI's client).

Each cell must succeed, and its answer is checked by something other than the code that made
it: solved joints against the family's constraint residuals and the driven crank's angle (to
1e-10 of the size), derivatives against central differences of solved positions, curve points
(every sixth) against the configurations ``solve --all`` lists at their inputs, the number of
circuits that pass an input against the configurations there, each limit position against the
count of configurations just beside it, the pictures decoded, the SVG parsed, the DXF read
back and audited by ezdxf, the workbench's circuits as rigid motions, and a drag by the pose
the workbench gives the document it returns. :data:`REFUSALS` lists the cells that may refuse
because the mathematics does (it is empty: none does), and docs/cli.md's family × verb table
is this matrix (:func:`markdown_table`), compared in :func:`test_the_docs_table_is_the_matrix`.
"""

from __future__ import annotations

import functools
import itertools
import json
import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import ezdxf
import numpy as np
import pytest
from family_examples import FAMILY_EXAMPLES, INPUT_EXAMPLES, family_of
from fastapi.testclient import TestClient
from PIL import Image

from linkwright.cli import main
from linkwright.engine import Motion
from linkwright.io import document_to_dict, load_example
from linkwright.mechanisms import FAMILIES, Mechanism
from linkwright.server import create_app

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs" / "cli.md"

ROWS: dict[str, str] = {**FAMILY_EXAMPLES, **INPUT_EXAMPLES}
"""Row key → bundled example."""

ROW_NAMES = {
    "fourbar": "four-bar",
    "slidercrank": "slider-crank",
    "geared-fivebar": "geared five-bar",
    "doubleslider": "double slider",
    "watt1": "Watt I",
    "watt2": "Watt II",
    "stephenson1": "Stephenson I",
    "stephenson3": "Stephenson III",
    "stephenson3-output": "Stephenson III driven at its output (a triad)",
    "spherical-fourbar": "spherical four-bar",
    "spherical-sixbar": "spherical six-bar (paper 000)",
    "spherical-stephenson3": "spherical Stephenson III driven at AB",
    "spherical-stephenson3-fg": "spherical Stephenson III driven at FG (a spherical triad)",
    "linkage-plane": "composed linkage, plane",
    "linkage-sphere": "composed linkage, sphere",
    "linkage-hinge": "composed linkage driven at a moving hinge",
    "stephenson3-hinge": "Stephenson III driven at its hinge D (a triad with a leg that follows "
    "the input)",
    "spherical-stephenson3-hinge": "spherical Stephenson III driven at its hinge E (a spherical "
    "triad whose shape follows the input)",
}
"""How docs/cli.md's table names each row."""

VERBS = (
    "solve",
    "solve --all",
    "solve --derivatives",
    "curve",
    "curve --spacing path",
    "curve --all",
    "analyze",
    "plot",
    "plot --kind angles",
    "plot --kind velocity",
    "plot --kind acceleration",
    "plot --kind coefficients",
    "animate",
    "export csv",
    "export svg",
    "export dxf",
    "workbench scene",
    "workbench drag",
)

REFUSALS: dict[tuple[str, str], str] = {}
"""(row, verb) → why the mathematics forbids that cell. None does: every verb works for every
family. (A triad has no transmission angle of a dyad to report, so ``analyze`` and the angle
diagrams show none for the two triad rows; that is an empty answer, not a refusal.)"""

REL = 1e-10  # constraint residuals, relative to the linkage's size
GRID = "7:367:40"  # solve's inputs: whole degrees off the special angles 0, 90, 180
SAMPLES = 48  # curve, picture and scene samples: enough to check, quick to draw


# ---------------------------------------------------------------------------------------------
# Running the command line
# ---------------------------------------------------------------------------------------------


def cli(capsys: pytest.CaptureFixture[str], *args: object) -> str:
    status = main([str(a) for a in args])
    out, err = capsys.readouterr()
    assert status == 0, f"linkwright {' '.join(map(str, args))} failed: {err}"
    return out


def cli_json(capsys: pytest.CaptureFixture[str], *args: object) -> Any:
    return json.loads(cli(capsys, *args, "--json"))


@functools.cache
def mechanism(row: str) -> Mechanism:
    return load_example(ROWS[row]).mechanism


def positions(joints: dict[str, list[float]]) -> dict[str, np.ndarray]:
    return {k: np.array(v, dtype=float) for k, v in joints.items()}


def as_motion(theta: np.ndarray, joints: list[dict[str, np.ndarray]]) -> Motion:
    """Solved joints (one dict per sample) as a Motion, for the family's own residuals."""
    n = len(joints)
    names = joints[0].keys()
    return Motion(
        input=np.asarray(theta, dtype=float),
        positions={k: np.stack([j[k] for j in joints]) for k in names},
        velocities=None,
        accelerations=None,
        valid=np.ones(n, dtype=bool),
        regular=np.ones(n, dtype=bool),
    )


def _param(params: dict[str, Any], value: Any) -> Any:
    return np.asarray(params[value] if isinstance(value, str) else value, dtype=float)


def crank_errors(m: Mechanism, theta: np.ndarray, pos: dict[str, np.ndarray]) -> list[float]:
    """Each driven crank's distance from where the input puts it: the crank steps' own
    definition (angle ``phase + ratio·θ``, in the plane from +x, on the sphere about the pivot
    from the great circle towards ``ref``), written here from that definition."""
    params = m.params()
    out = []
    for step in m.plan.steps:
        kind = type(step).__name__
        if kind not in ("Crank", "SphereCrank") or step.name not in pos:
            continue
        phi = _param(params, step.phase) + _param(params, step.ratio) * theta
        length = _param(params, step.length)
        pivot = pos[step.pivot]
        if kind == "Crank":
            want = pivot + length[..., None] * np.stack((np.cos(phi), np.sin(phi)), -1)
        else:
            ref = _param(params, step.ref)
            e1 = ref - (ref @ pivot[0]) * pivot[0]
            e1 = e1 / np.linalg.norm(e1)
            e2 = np.cross(pivot[0], e1)
            ring = np.cos(phi)[..., None] * e1 + np.sin(phi)[..., None] * e2
            want = np.cos(length)[..., None] * pivot + np.sin(length)[..., None] * ring
        out.append(float(np.max(np.linalg.norm(pos[step.name] - want, axis=-1))))
    return out + hinge_errors(m, theta, pos)


def _signed(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return np.arctan2(u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0], np.sum(u * v, -1))


def _sphere_angle(at: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The angle at ``at`` from the great circle towards ``a`` to the one towards ``b``,
    right-handed about +O·at."""
    ta = a - np.sum(a * at, -1, keepdims=True) * at
    tb = b - np.sum(b * at, -1, keepdims=True) * at
    return np.arctan2(np.sum(np.cross(ta, tb) * at, -1), np.sum(ta * tb, -1))


def hinge_errors(m: Mechanism, theta: np.ndarray, pos: dict[str, np.ndarray]) -> list[float]:
    """Each driven hinge's angle against the input, as a distance (times its arm): at the
    hinge H from H→Y to H→X for a hinge in a loop or a leg, and from the body's line J1→J2 to
    H→J3 for a link turning on a triad's body (the step kinds' definitions, written here from
    them); in the plane counter-clockwise, on the sphere right-handed about the hinge's axis."""
    params = m.params()
    out = []
    sphere = m.plan.space == "sphere"
    for step in m.plan.steps:
        kind = type(step).__name__
        if kind in ("Hinge", "SphereHinge"):
            h, y, x, arm = step.hinge, step.y, step.far, step.a
        elif kind in ("LegHingeTriad", "SphereLegHingeTriad"):
            h, y, x, arm = step.joints[3], step.anchors[2], step.joints[2], step.a
        elif kind == "BodyHingeTriad":
            j = step.joints
            got = _signed(pos[j[1]] - pos[j[0]], pos[j[2]] - pos[j[3]])
            h, arm = None, step.arm
        elif kind == "SphereBodyHingeTriad":
            j = step.joints
            got = _sphere_angle(pos[j[3]], pos[j[0]], pos[j[2]])
            h, arm = None, step.arm
        else:
            continue
        if h is not None:
            if sphere:
                got = _sphere_angle(pos[h], pos[y], pos[x])
            else:
                got = _signed(pos[y] - pos[h], pos[x] - pos[h])
        want = _param(params, step.phase) + theta
        gap = np.abs(np.angle(np.exp(1j * (got - want))))
        length = _param(params, arm)
        out.append(float(np.max(gap * (np.sin(length) if sphere else length))))
    return out


def check_solved(row: str, theta_deg: list[float], joints: list[dict[str, np.ndarray]]) -> None:
    """Every solved configuration closes every constraint of its family to 1e-10 of its size,
    and puts the driven crank where the input says."""
    if not joints:
        return
    m = mechanism(row)
    theta = np.radians(theta_deg)
    motion = as_motion(theta, joints)
    worst = {k: float(np.max(np.abs(v))) for k, v in m.residuals(motion).items()}
    assert max(worst.values()) <= REL, (row, worst)
    size = float(np.max(np.asarray(m.scale)))
    assert max(crank_errors(m, theta, motion.positions), default=0.0) <= REL * size, row


def solve_rows(sample_list: list[dict]) -> tuple[list[float], list[dict[str, np.ndarray]]]:
    theta, joints = [], []
    for s in sample_list:
        for c in s["configurations"]:
            theta.append(s["input_deg"])
            joints.append(positions(c["joints"]))
    return theta, joints


@functools.cache
def _every_configuration(row: str, inputs: tuple[float, ...]) -> list[list[dict[str, np.ndarray]]]:
    """``solve --all`` at the inputs (degrees): each input's configurations."""
    capture = _Capture()
    spec = ",".join(repr(float(t)) for t in inputs)
    data = json.loads(capture.run("solve", ROWS[row], "--input", spec, "--all", "--json"))
    out = []
    for s in data["samples"]:
        out.append([positions(c["joints"]) for c in s["configurations"]])
    return out


def every_configuration(row: str, inputs: list[float]) -> list[list[dict[str, np.ndarray]]]:
    return _every_configuration(row, tuple(float(t) for t in inputs))


class _Capture:
    """main() run outside a test's capsys (for the cached look-ups shared by several cells)."""

    def run(self, *args: object) -> str:
        import contextlib
        import io

        out, err = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            status = main([str(a) for a in args])
        assert status == 0, err.getvalue()
        return out.getvalue()


def size_of(row: str) -> float:
    m = mechanism(row)
    return 1.0 if m.space == "sphere" else float(np.max(np.asarray(m.scale)))


def distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.linalg.norm(np.asarray(a) - np.asarray(b), axis=-1)


# ---------------------------------------------------------------------------------------------
# The cells
# ---------------------------------------------------------------------------------------------


def cell_solve(capsys, row: str, tmp_path: Path) -> None:
    data = cli_json(capsys, "solve", ROWS[row], "--input", GRID)
    theta, joints = solve_rows(data["samples"])
    assert joints, "the document's configuration exists at some input"
    check_solved(row, theta, joints)


def cell_solve_all(capsys, row: str, tmp_path: Path) -> None:
    data = cli_json(capsys, "solve", ROWS[row], "--input", GRID, "--all")
    theta, joints = solve_rows(data["samples"])
    assert joints
    check_solved(row, theta, joints)
    # Configurations at one input are distinct, and the document's own is among them.
    own = cli_json(capsys, "solve", ROWS[row], "--input", GRID)["samples"]
    for every, mine in zip(data["samples"], own, strict=True):
        found = [positions(c["joints"]) for c in every["configurations"]]
        for a, b in itertools.combinations(found, 2):
            assert max(float(distance(a[k], b[k])) for k in a) > 1e-9 * size_of(row)
        for c in mine["configurations"]:
            j = positions(c["joints"])
            assert min(max(float(distance(j[k], f[k])) for k in j) for f in found) <= 1e-9


def cell_solve_derivatives(capsys, row: str, tmp_path: Path) -> None:
    """Velocity and acceleration against central differences of solved positions, at the
    first input of the grid where the document's configuration exists."""
    h = 1e-2  # degrees: truncation and rounding of the second difference both about 1e-9
    base = cli_json(capsys, "solve", ROWS[row], "--input", GRID, "--derivatives")["samples"]
    sample = next(s for s in base if s["configurations"])
    t = sample["input_deg"]
    around = cli_json(capsys, "solve", ROWS[row], "--input", f"{t - h!r},{t + h!r}", "--all")
    c = sample["configurations"][0]
    x0 = positions(c["joints"])

    def nearest(s: dict) -> dict[str, np.ndarray]:
        found = [positions(f["joints"]) for f in s["configurations"]]
        return min(found, key=lambda f: max(float(distance(f[k], x0[k])) for k in x0))

    lo, hi = (nearest(s) for s in around["samples"])
    step = math.radians(h)
    scale = size_of(row)
    for k in x0:
        v = np.array(c["velocity"][k])
        a = np.array(c["acceleration"][k])
        dv = (hi[k] - lo[k]) / (2 * step)
        da = (hi[k] - 2 * x0[k] + lo[k]) / step**2
        vmax = max(1.0, float(np.abs(v).max()))
        amax = max(1.0, float(np.abs(a).max()))
        assert np.abs(v - dv).max() <= 1e-6 * vmax * scale, (row, k, v, dv)
        assert np.abs(a - da).max() <= 1e-4 * amax * scale, (row, k, a, da)


def _closed_curve(points: list, size: float) -> np.ndarray:
    """The points of a closed curve: none missing, and no step (the closing one included)
    that jumps far beyond the others (a branch jump)."""
    assert points and all(p is not None for p in points)
    p = np.array(points, dtype=float)
    steps = distance(np.roll(p, -1, axis=0), p)
    typical = float(np.median(steps)) + 1e-12 * size
    assert steps.max() <= max(40 * typical, 0.2 * size), (steps.max(), typical)
    return p


def _on_configurations(row: str, theta_deg: list[float], points: np.ndarray, joint: str) -> None:
    """Every 6th point of a curve is the traced joint of a configuration at its input."""
    pick = list(range(0, len(theta_deg), 6))
    found = every_configuration(row, [theta_deg[i] for i in pick])
    for i, configs in zip(pick, found, strict=True):
        assert configs, (row, theta_deg[i])
        gap = min(float(distance(c[joint], points[i])) for c in configs)
        assert gap <= 1e-7 * size_of(row), (row, theta_deg[i], gap)


def cell_curve(capsys, row: str, tmp_path: Path, *extra: str) -> None:
    data = cli_json(capsys, "curve", ROWS[row], "--points", SAMPLES, *extra)
    assert data["closed"] and len(data["points"]) == SAMPLES
    p = _closed_curve(data["points"], size_of(row))
    _on_configurations(row, data["input_deg"], p, data["joint"])


def cell_curve_path(capsys, row: str, tmp_path: Path) -> None:
    cell_curve(capsys, row, tmp_path, "--spacing", "path")


def crossings(theta_deg: list[float], at: float) -> int:
    """How often a closed circuit's input passes ``at`` (modulo a turn): once per sample
    interval that holds it, the interval back to the start included."""
    t = np.radians(np.asarray(theta_deg, dtype=float))
    step = np.diff(np.r_[t, t[0]])
    step = (step + np.pi) % (2 * np.pi) - np.pi  # the closing step, within one turn
    start = (t - math.radians(at) + np.pi) % (2 * np.pi) - np.pi
    end = start + step
    return int(np.sum((np.minimum(start, end) < 0) & (np.maximum(start, end) >= 0)))


def cell_curve_all(capsys, row: str, tmp_path: Path) -> None:
    data = cli_json(capsys, "curve", ROWS[row], "--points", SAMPLES, "--all")
    pieces = data["circuits"]
    assert pieces
    for piece in pieces:
        p = _closed_curve(piece["points"], size_of(row))
        _on_configurations(row, piece["input_deg"], p, data["joint"])
    # Every configuration at an input lies on some circuit: the circuits pass each input as
    # many times as there are configurations there (inputs away from any sample and limit).
    probes = [-151.3, -53.9, 12.7, 97.1, 160.9]
    counts = [len(c) for c in every_configuration(row, probes)]
    for at, count in zip(probes, counts, strict=True):
        assert sum(crossings(piece["input_deg"], at) for piece in pieces) == count, (row, at)


def _limits(report: dict) -> list[float]:
    """The input's limit positions (degrees) that analyze lists, whatever its family's
    report looks like."""
    if report.get("limit_positions_deg"):
        return [float(x) for x in report["limit_positions_deg"]]
    return [float(x["input_deg"]) for x in report.get("limit_positions") or []]


def cell_analyze(capsys, row: str, tmp_path: Path) -> None:
    report = cli_json(capsys, "analyze", ROWS[row])
    assert report["assembles"] is True
    text = cli(capsys, "analyze", ROWS[row])
    assert "nan" not in text.lower().split()
    # At each limit position two configurations meet: just beside it there are two more
    # configurations on one side than on the other.
    delta = 1e-5  # degrees; the limits are found to about 1e-10 rad
    limits = _limits(report)
    probes = [x for lim in limits for x in (lim - delta, lim + delta)]
    counts = [len(c) for c in every_configuration(row, probes)] if probes else []
    for lim, before, after in zip(limits, counts[::2], counts[1::2], strict=True):
        assert abs(before - after) == 2, (row, lim, before, after)
    if "circuits" in report:
        every = cli_json(capsys, "curve", ROWS[row], "--points", SAMPLES, "--all")
        assert report["circuits"] == len(every["circuits"])


def _picture(path: Path) -> None:
    with Image.open(path) as image:
        assert image.format in ("PNG", "GIF")
        pixels = np.asarray(image.convert("L"), dtype=float)
    assert pixels.std() > 5, "a drawing, not a blank canvas"


def cell_plot(capsys, row: str, tmp_path: Path, kind: str = "linkage") -> None:
    out = tmp_path / f"{row}-{kind}.png"
    said = cli(capsys, "plot", ROWS[row], "--kind", kind, "--samples", SAMPLES, "--quiet",
               "--out", out)  # fmt: skip
    assert said.strip() == f"wrote {out}"
    _picture(out)


def cell_animate(capsys, row: str, tmp_path: Path) -> None:
    out = tmp_path / f"{row}.gif"
    cli(capsys, "animate", ROWS[row], "--out", out, "--frames", 6, "--dpi", 30, "--quiet")
    with Image.open(out) as gif:
        frames = []
        for k in range(gif.n_frames):
            gif.seek(k)
            frames.append(np.asarray(gif.convert("L"), dtype=float))
    assert len(frames) == 6
    assert any(np.abs(a - b).max() > 0 for a, b in itertools.pairwise(frames)), "it moves"


def cell_export_csv(capsys, row: str, tmp_path: Path) -> None:
    out = tmp_path / f"{row}.csv"
    cli(capsys, "export", ROWS[row], "--out", out, "--samples", SAMPLES)
    lines = out.read_text().splitlines()
    header = lines[0].split(",")
    assert header[:3] == ["sample", "theta_deg", "theta_rad"]
    rows = np.array([[float(x) for x in line.split(",")] for line in lines[1:]])
    assert len(rows) >= SAMPLES - 2 and np.isfinite(rows).all()
    names = list(dict.fromkeys(h.rsplit("_", 1)[0] for h in header[3:]))
    dim = 3 if mechanism(row).space == "sphere" else 2
    joints = []
    for r in rows:
        j = {}
        for n in names:
            cols = [header.index(f"{n}_{a}") for a in "xyz"[:dim]]
            j[n] = r[cols]
        joints.append(j)
    check_solved(row, list(rows[:, 1]), joints)


def cell_export_svg(capsys, row: str, tmp_path: Path) -> None:
    out = tmp_path / f"{row}.svg"
    cli(capsys, "export", ROWS[row], "--out", out, "--samples", SAMPLES)
    root = ET.parse(out).getroot()
    assert root.tag == "{http://www.w3.org/2000/svg}svg"
    drawn = [e for e in root.iter() if e.tag.endswith(("path", "polyline", "line", "circle"))]
    assert len(drawn) >= 3


def cell_export_dxf(capsys, row: str, tmp_path: Path) -> None:
    out = tmp_path / f"{row}.dxf"
    cli(capsys, "export", ROWS[row], "--out", out, "--samples", SAMPLES)
    drawing = ezdxf.readfile(out)
    auditor = drawing.audit()
    assert not auditor.has_errors and not auditor.has_fixes
    layers = {layer.dxf.name for layer in drawing.layers}
    assert {"LINKS", "JOINTS"} <= layers and any(n.startswith("CURVE") for n in layers)
    assert len(drawing.modelspace()) > 3


@functools.cache
def client() -> TestClient:
    import tempfile

    return TestClient(create_app(Path(tempfile.mkdtemp(prefix="family-verbs-"))))


def _scene(row: str, **more: Any) -> dict:
    document = document_to_dict(load_example(ROWS[row]))
    answer = client().post("/api/scene", json={"document": document, "samples": SAMPLES, **more})
    assert answer.status_code == 200, answer.text
    return answer.json()


def cell_scene(capsys, row: str, tmp_path: Path) -> None:
    s = _scene(row)
    assert s["modes"] and s["modes"][0]["own"], s["message"]
    assert s["message"] is None, s["message"]
    assert s["pose"] is not None and s["diagrams"]
    # Every body keeps its shape along every circuit of every mode (a rigid motion).
    for mode in s["modes"]:
        for c in mode["circuits"]:
            pos = {k: np.array(v, dtype=float) for k, v in c["positions"].items()}
            assert all(np.isfinite(p).all() for p in pos.values())
            for body in s["bodies"]:
                for a, b in itertools.combinations(body["joints"], 2):
                    d = distance(pos[a], pos[b])
                    assert np.ptp(d) <= 1e-9 * max(1.0, d.max()), (row, body, a, b)
    # A triad's configurations are followed, not chosen: one mode holds every circuit.
    if mechanism(row).plan.triads:
        every = cli_json(capsys, "curve", ROWS[row], "--points", SAMPLES, "--all")
        assert len(s["modes"]) == 1
        assert len(s["modes"][0]["circuits"]) == len(every["circuits"])


def cell_drag(capsys, row: str, tmp_path: Path) -> None:
    """A moving joint dragged a little lands under the pointer (or as near as it can reach),
    checked by the pose of the scene of the document the drag returns (the configuration the
    page draws: for a triad, the document's pose index)."""
    first = _scene(row, diagrams=False)
    # A quarter of the way round the first circuit: a circuit may start at a limit position,
    # where any change of a dimension loses the configuration on one side.
    at = first["modes"][0]["circuits"][0]["input"][SAMPLES // 4]
    s = _scene(row, diagrams=False, at=at)
    assert s["pose"] is not None
    moving = [j for j in s["handles"] if j not in s["fixed"]]
    assert moving, s["handles"]
    joint = moving[-1]
    p = np.array(s["pose"][joint], dtype=float)
    if p.size == 3:
        axis = np.cross(p, [0.3, -0.5, 0.8])
        axis /= np.linalg.norm(axis)
        target = math.cos(0.01) * p + math.sin(0.01) * np.cross(axis, p)
    else:
        target = p + 0.01 * size_of(row) * np.array([1.0, -0.6])
    body = {"document": document_to_dict(load_example(ROWS[row])), "joint": joint,
            "to": target.tolist(), "at": s["at"]}  # fmt: skip
    answer = client().post("/api/drag", json=body)
    assert answer.status_code == 200, answer.text
    moved = answer.json()
    # The page draws the returned document at the returned input: its pose there.
    again = client().post("/api/scene", json={"document": moved["document"], "samples": 16,
                                              "at": moved["at"], "diagrams": False})  # fmt: skip
    assert again.status_code == 200, again.text
    after = np.array(again.json()["pose"][joint], dtype=float)
    miss = float(distance(after, target))
    if moved["exact"]:
        assert miss <= 1e-7 * size_of(row), (row, joint, miss)
    else:
        assert miss < float(distance(p, target)), (row, joint, miss)


CELLS = {
    "solve": cell_solve,
    "solve --all": cell_solve_all,
    "solve --derivatives": cell_solve_derivatives,
    "curve": cell_curve,
    "curve --spacing path": cell_curve_path,
    "curve --all": cell_curve_all,
    "analyze": cell_analyze,
    "plot": cell_plot,
    "plot --kind angles": functools.partial(cell_plot, kind="angles"),
    "plot --kind velocity": functools.partial(cell_plot, kind="velocity"),
    "plot --kind acceleration": functools.partial(cell_plot, kind="acceleration"),
    "plot --kind coefficients": functools.partial(cell_plot, kind="coefficients"),
    "animate": cell_animate,
    "export csv": cell_export_csv,
    "export svg": cell_export_svg,
    "export dxf": cell_export_dxf,
    "workbench scene": cell_scene,
    "workbench drag": cell_drag,
}


# ---------------------------------------------------------------------------------------------
# The matrix, and its table in docs/cli.md
# ---------------------------------------------------------------------------------------------


def test_the_matrix_covers_every_family_and_verb():
    assert set(CELLS) == set(VERBS)
    assert {family_of(row) for row in ROWS} == set(FAMILIES)
    assert set(ROW_NAMES) == set(ROWS)
    # A refusal would need its reason here and a test that the verb gives it; none is needed.
    assert REFUSALS == {}
    # The two triad rows really are driven so that a triad remains.
    for row in INPUT_EXAMPLES:
        assert mechanism(row).plan.triads, row
    for row in FAMILY_EXAMPLES:
        assert not mechanism(row).plan.triads, row


@pytest.mark.parametrize("verb", VERBS)
@pytest.mark.parametrize("row", list(ROWS))
def test_cell(capsys, tmp_path, row, verb):
    CELLS[verb](capsys, row, tmp_path)


@pytest.mark.parametrize("key", list(INPUT_EXAMPLES))
def test_gallery_picture_of_each_triad_row(key, tmp_path):
    """The README's gallery shows the two triad rows too, compared as tests/test_cli_pictures.py
    compares the families' pictures (LINKWRIGHT_UPDATE_GALLERY=1 redraws the references)."""
    import os

    import test_cli_pictures as gallery
    from matplotlib.testing.compare import compare_images

    from linkwright.plot import save_figure
    from linkwright.plot.view import plot_mechanism

    def render(path: Path) -> Path:
        doc = load_example(INPUT_EXAMPLES[key])
        figure = plot_mechanism(doc.mechanism, samples=gallery.GALLERY_SAMPLES, title=doc.title)
        figure.set_dpi(gallery.GALLERY_DPI)
        return save_figure(figure, path, dpi=gallery.GALLERY_DPI)

    reference = gallery.GALLERY / f"{key}.png"
    if os.environ.get("LINKWRIGHT_UPDATE_GALLERY"):
        render(reference)
    actual = render(tmp_path / f"{key}.png")
    assert reference.exists(), f"no reference picture {reference}"
    failed = compare_images(
        str(reference), str(actual), tol=gallery.GALLERY_TOLERANCE, in_decorator=True
    )
    assert failed is None, failed


def test_the_picture_draws_every_circuit_of_a_triad():
    """Driven at its output, the Stephenson III's two configurations turn fully side by side:
    the picture draws both circuits (each closed curve that curve --all prints is a drawn line,
    point for point)."""
    from linkwright.plot.view import plot_mechanism

    row = "stephenson3-output"
    figure = plot_mechanism(mechanism(row), samples=SAMPLES)
    lines = [np.asarray(line.get_xydata(), float) for line in figure.axes[0].get_lines()]
    capture = _Capture()
    every = json.loads(capture.run("curve", ROWS[row], "--points", SAMPLES, "--all", "--json"))
    assert len(every["circuits"]) == 2
    for piece in every["circuits"]:
        p = np.array(piece["points"])
        drawn = [q for q in lines if len(q) >= len(p)]
        assert any(
            max(float(np.min(distance(q[:, None], x[None]))) for x in p) <= 1e-9 for q in drawn
        ), "a circuit is missing from the picture"


def test_triad_limits_are_named_within_one_turn_in_pictures_and_the_workbench():
    """Paper 001's example at FG: the picture's limit notes and the workbench's limit sentences
    give each limit's input as analyze lists it (a circuit's inputs run on past a turn), and the
    workbench names the triad there, not a dyad."""
    from matplotlib.text import Text

    from linkwright.plot.view import plot_mechanism

    row = "spherical-stephenson3-fg"
    capture = _Capture()
    report = json.loads(capture.run("analyze", ROWS[row], "--json"))
    listed = sorted(round(x, 1) for x in _limits(report))
    assert len(listed) == 10
    figure = plot_mechanism(mechanism(row), samples=SAMPLES)
    notes = [t.get_text() for t in figure.findobj(Text) if t.get_text().startswith("limit θ = ")]
    shown = [float(re.search(r"= (\S+)°", n).group(1).replace("−", "-")) for n in notes]
    assert sorted(shown) == listed
    s = _scene(row, diagrams=False)
    texts = [x["text"] for x in s["limits"]]
    assert len(texts) == 10
    said = sorted(round(float(re.search(r"θ = (\S+)°", t).group(1)), 1) for t in texts)
    assert said == listed
    assert all("triad CBE" in t for t in texts)
    assert not any("dyad" in t for t in texts)


def test_triad_diagrams_say_what_happens_at_a_limit():
    """At a triad's limit position two configurations meet; no dyad changes branch there."""
    from matplotlib.text import Text

    from linkwright.plot import plot_diagram

    figure = plot_diagram(mechanism("spherical-stephenson3-fg"), "angles", samples=SAMPLES)
    said = " ".join(" ".join(t.get_text().split()) for t in figure.findobj(Text))
    assert "at each limit two configurations meet" in said
    assert "dyad changes branch" not in said


def test_the_stephenson3_output_example_turns_fully_on_two_configurations():
    """What stephenson3-output.toml says of itself: driven at D0D it turns fully, with two
    configurations at every whole degree (both with the four-bar's assembly +1, one for each
    side of the line C D0), on two circuits without a limit position."""
    from linkwright.mechanisms import solve_all

    m = mechanism("stephenson3-output")
    found = solve_all(m, np.radians(np.arange(360.0)))
    assert np.all(found.count == 2)
    assert np.all(found.assembly[found.valid] == 1)
    assert sorted(set(found.assembly2[found.valid].tolist())) == [-1.0, 1.0]
    every = json.loads(
        _Capture().run("curve", ROWS["stephenson3-output"], "-n", 36, "--all", "--json")
    )
    assert [(c["full_turn"], c["limits"]) for c in every["circuits"]] == [(True, [])] * 2


NEVER = {
    "stephenson3-output": {"link1": 0.05, "link2": 0.05},  # D's tiny circle: C never reaches
    "spherical-stephenson3-fg": {"a2": 1.0, "a3": 1.0, "a4": 1.0},  # C near A and near D
}


@pytest.mark.parametrize(
    "args",
    [
        ["solve", "-i", "0:360:90"],
        ["solve", "-i", "0:360:90", "--all", "--derivatives"],
        ["curve", "-n", "12"],
        ["curve", "-n", "12", "--all"],
        ["curve", "-n", "12", "--spacing", "path"],
        ["analyze"],
        ["plot", "--out", "{tmp}/p.png", "--quiet"],
        ["plot", "--kind", "angles", "--out", "{tmp}/a.png", "--quiet"],
        ["animate", "--out", "{tmp}/a.gif", "--quiet"],
        ["export", "--out", "{tmp}/e.csv"],
        ["export", "--out", "{tmp}/e.dxf"],
    ],
    ids=lambda a: " ".join(x for x in a if "{" not in x),
)
@pytest.mark.parametrize("row", list(NEVER))
def test_a_triad_that_never_assembles_gets_one_clear_line(capsys, tmp_path, row, args):
    """Where the triad cannot be held at any input, each verb either answers (solve and
    analyze say so) or refuses in one line: never an internal error."""
    raw = document_to_dict(load_example(ROWS[row]))
    raw["mechanism"].update(NEVER[row])
    doc = tmp_path / "never.json"
    doc.write_text(json.dumps(raw))
    assert not any(len(c) for c in _every_configuration_of(doc, "0:360:5"))
    verb, *rest = args
    status = main([verb, str(doc), *(a.format(tmp=tmp_path) for a in rest)])
    out, err = capsys.readouterr()
    assert "internal error" not in err and "Traceback" not in err, err
    if status == 0:
        assert verb in ("solve", "analyze"), (verb, out)
        assert "assembled" in out or "assembles" in out or "configuration" in out
    else:
        assert status == 2 and len(err.splitlines()) == 1 and err.startswith("error: "), err
        assert "cannot be assembled" in err, err


@pytest.mark.parametrize("row", list(NEVER))
def test_the_workbench_says_why_a_triad_never_assembles(row):
    raw = document_to_dict(load_example(ROWS[row]))
    raw["mechanism"].update(NEVER[row])
    answer = client().post("/api/scene", json={"document": raw, "samples": SAMPLES})
    assert answer.status_code == 200, answer.text
    s = answer.json()
    assert s["modes"] == [] and s["pose"] is None
    assert "cannot be assembled at any input angle" in s["message"]
    assert "triad" in s["message"] and "dyad" not in s["message"], s["message"]


def _every_configuration_of(doc: Path, spec: str) -> list[list[dict]]:
    data = json.loads(_Capture().run("solve", doc, "--input", spec, "--all", "--json"))
    return [s["configurations"] for s in data["samples"]]


@pytest.mark.parametrize(
    ("example", "args", "knob"),
    [
        ("paper001-fg", ["curve", "--points", "100000"], "--points"),
        ("paper001-fg", ["curve", "--all", "--points", "100000"], "--points"),
        ("stephenson3-output", ["curve", "--points", "1000000"], "--points"),
        ("jansen-leg", ["curve", "--all", "--points", "62200"], "--points"),
        ("paper001-fg", ["plot", "--samples", "100000", "--out", "{tmp}/p.png"], "--samples"),
        ("paper001-fg", ["export", "--samples", "100000", "--out", "{tmp}/e.csv"], "--samples"),
    ],
)
def test_following_every_configuration_is_bounded_before_it_starts(
    capsys, tmp_path, example, args, knob
):
    """Tracing by continuation re-solves every configuration at every sample of every circuit
    (a triad's many times dearer than a dyad's): asked for more than the command line's budget
    (paper 001's example at FG took 3.2 GB and 100 s for curve --all at 100,000 points), it is
    refused before the work starts, naming what to lower."""
    verb, *rest = args
    status = main([verb, example, *(a.format(tmp=tmp_path) for a in rest)])
    _, err = capsys.readouterr()
    assert status == 2, err
    assert (
        err.startswith("error: too costly: tracing every circuit of") and len(err.splitlines()) == 1
    )
    assert f"lower {knob} to" in err


def markdown_table() -> str:
    """docs/cli.md's family × verb table, from :data:`ROWS`, :data:`VERBS` and
    :data:`REFUSALS`."""
    head = "| family (example) | " + " | ".join(f"`{v}`" for v in VERBS) + " |"
    lines = [head, "|" + " --- |" * (len(VERBS) + 1)]
    for row, example in ROWS.items():
        cells = ["refuses: " + REFUSALS[row, v] if (row, v) in REFUSALS else "yes" for v in VERBS]
        lines.append(f"| {ROW_NAMES[row]} (`{example}`) | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def test_the_docs_table_is_the_matrix():
    text = DOCS.read_text(encoding="utf-8")
    found = re.search(r"<!-- family-verbs -->\n(.*?)\n<!-- /family-verbs -->", text, re.DOTALL)
    assert found, "docs/cli.md has no family × verb table between its markers"
    assert found.group(1).strip() == markdown_table(), (
        "docs/cli.md's family × verb table differs from tests/test_family_verbs.py's matrix; "
        "paste markdown_table() between the markers"
    )
