"""A document names the circuit its linkage runs on (issue 28, item 1): ``start``.

A double rocker's input rocks over two arcs, and each arc is a different coupler curve. The arcs
are computed here independently, by the law of cosines: with crank a, frame d, coupler b and
rocker c, the loop closes where |A B0|² = a² + d² − 2ad·cos θ lies in [(b − c)², (b + c)²]
(θ from the frame line), two arcs symmetric about it when |b − c| > |a − d| and b + c < a + d.
Every face that traces "the" circuit (``circuit``, ``linkwright curve``, the exports, the
workbench's scene) must trace the arc that holds ``start``; the synthesis names the arc its
answer lies on.
"""

from __future__ import annotations

import csv
import json
import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st
from synth_helpers import polyline_distance, run_cli

from linkwright.io import mechanism_to_dict, parse_document
from linkwright.io.files import load_document, save_document
from linkwright.mechanisms import FourBar, InvalidMechanism, circuit, circuits, running_circuit

# Inputs are found as exact roots (closed-form arc-cosines); the circuit's samples may reach the
# limits to rounding of the arc-cosine near ±1 (√ε of a radian).
SLACK = 1e-7


def _double_rocker(a: float, d: float, share: float, wide: float) -> FourBar:
    """A four-bar whose input rocks over two arcs: b, c with |b − c| > |a − d|, b + c < a + d."""
    low, high = abs(a - d), a + d
    diff = low + share * (high - low) * 0.5  # |b − c|, above |a − d|
    total = diff + wide * (high - diff)  # b + c, below a + d
    b, c = (total + diff) / 2, (total - diff) / 2
    return FourBar(A0=[0, 0], B0=[d, 0], crank=a, coupler=b, rocker=c, u=0.3 * b, v=0.4 * b)


def _arcs(m: FourBar) -> list[tuple[float, float]]:
    """The two input arcs (radians), by the law of cosines."""
    a, d = float(m.crank), float(m.B0[0])
    b, c = float(m.coupler), float(m.rocker)
    near = math.acos(np.clip((a * a + d * d - (b - c) ** 2) / (2 * a * d), -1, 1))
    far = math.acos(np.clip((a * a + d * d - (b + c) ** 2) / (2 * a * d), -1, 1))
    return [(-far, -near), (near, far)]


def _inside(theta: np.ndarray, arc: tuple[float, float]) -> bool:
    wrapped = np.angle(np.exp(1j * theta))
    return bool(np.all((wrapped >= arc[0] - SLACK) & (wrapped <= arc[1] + SLACK)))


shapes = st.tuples(
    st.floats(0.5, 3.0),  # crank
    st.floats(0.5, 3.0),  # frame
    st.floats(0.05, 0.95),  # where |b − c| lies between |a − d| and a + d
    st.floats(0.05, 0.95),  # where b + c lies between |b − c| and a + d
)


@given(shapes, st.integers(0, 1), st.floats(0.0, 1.0))
@example((3.0, 4.0, 0.5, 0.5), 1, 0.5)
@example((1.0, 1.0, 0.05, 0.05), 0, 0.0)  # a = d: arcs reaching the frame line's far side
def test_the_circuit_runs_on_the_arc_that_holds_start(shape, which, where):
    m = _double_rocker(*shape)
    arcs = _arcs(m)
    lo, hi = arcs[which]
    start = lo + where * (hi - lo)
    own = replace(m, start=start)
    traced = circuit(own, 64, order=0)
    assert traced.valid.all()
    assert _inside(traced.input, arcs[which])
    other = circuit(replace(m, start=arcs[1 - which][0]), 64, order=0)
    assert _inside(other.input, arcs[1 - which])


@given(shapes, st.floats(-math.pi, math.pi))
def test_a_start_outside_both_arcs_runs_on_the_nearest(shape, start):
    m = _double_rocker(*shape)
    arcs = _arcs(m)

    def gap(arc: tuple[float, float]) -> float:
        if arc[0] <= start <= arc[1]:
            return 0.0
        ends = np.array(arc)
        return float(np.min(np.abs(np.angle(np.exp(1j * (ends - start))))))

    gaps = [gap(arc) for arc in arcs]
    if abs(gaps[0] - gaps[1]) < 1e-9:  # a tie (start on the frame line): either is right
        return
    nearest = int(np.argmin(gaps))
    assert _inside(circuit(replace(m, start=start), 32, order=0).input, arcs[nearest])


def test_without_a_start_the_first_arc_and_a_full_turn_starts_at_start():
    m = _double_rocker(3.0, 4.0, 0.5, 0.5)
    assert _inside(circuit(m, 16, order=0).input, _arcs(m)[0])
    crank_rocker = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=3, rocker=3.5, start=0.5)
    assert circuit(crank_rocker, 8, order=0).input[0] == pytest.approx(0.5)
    assert running_circuit(crank_rocker) == 0


def test_a_batch_runs_on_one_circuit_number_or_says_so():
    m = _double_rocker(3.0, 4.0, 0.5, 0.5)
    batch = FourBar(A0=[0, 0], B0=[4, 0], crank=[3.0, 3.0], coupler=m.coupler, rocker=m.rocker)
    assert running_circuit(replace(batch, start=1.0)) == 1
    mirrored = FourBar(
        A0=[[0, 0], [0, 0]], B0=[[4, 0], [0, 4]], crank=3.0, coupler=m.coupler, rocker=m.rocker
    )
    with pytest.raises(ValueError, match="different circuits"):
        running_circuit(replace(mirrored, start=1.0))
    with pytest.raises(InvalidMechanism, match="start: must be one finite angle"):
        replace(m, start=float("nan"))


def test_documents_keep_start_and_every_face_traces_its_arc(tmp_path):
    m = _double_rocker(3.0, 4.0, 0.5, 0.5)
    arcs = _arcs(m)
    path = tmp_path / "second-arc.toml"
    save_document(mechanism_to_dict(replace(m, start=sum(arcs[1]) / 2)), path)
    assert "start = " in path.read_text()
    doc = load_document(path)
    assert doc.mechanism.start == pytest.approx(sum(arcs[1]) / 2, abs=1e-12)
    assert doc.raw["mechanism"]["start"] == pytest.approx(math.degrees(sum(arcs[1]) / 2))

    code, out, err = run_cli("curve", str(path), "--json", "-n", "40")
    assert code == 0, err
    assert _inside(np.radians(json.loads(out)["input_deg"]), arcs[1])

    exported = tmp_path / "second-arc.csv"
    code, out, err = run_cli("export", str(path), "--out", str(exported), "--samples", "40")
    assert code == 0, err
    with exported.open() as handle:
        theta = [float(row["theta_rad"]) for row in csv.DictReader(handle)]
    assert _inside(np.array(theta), arcs[1])

    from linkwright.server.scene import scene

    shown = scene(doc.raw, samples=60)
    pose_at = math.radians(shown["at"]) if "at" in shown else None
    crank = np.asarray(shown["pose"]["A"])
    assert _inside(np.array([math.atan2(crank[1], crank[0])]), arcs[1]), pose_at

    # Every circuit is still there for the tools that draw them all.
    assert len(circuits(doc.mechanism, 16, order=0)[1]) == 2


def test_a_start_that_is_not_an_angle_is_one_line():
    body = mechanism_to_dict(_double_rocker(3.0, 4.0, 0.5, 0.5))
    body["mechanism"]["start"] = "left"
    with pytest.raises(ValueError, match=r"mechanism.start: must be an angle in degrees"):
        parse_document(body)


def test_a_synthesised_double_rocker_traces_its_own_answer(tmp_path):
    # Points on a double rocker's second arc. The search finds an exact fit (here another
    # double rocker, whose answer lies on its second arc too): `curve` on the printed document
    # must trace the arc the answer is on, not the linkage's first.
    m = _double_rocker(3.0, 4.0, 0.5, 0.5)
    angles = np.linspace(45.0, 72.0, 6)
    from linkwright.mechanisms import solve

    points = solve(m, np.radians(angles), order=0).positions["P"]
    table = tmp_path / "points.csv"
    np.savetxt(table, points, delimiter=",")
    code, out, err = run_cli(
        "synth", "path", "--family", "fourbar", "--points", str(table), "--json", "--quiet",
        "--angles", ",".join(f"{a:.12f}" for a in angles), "--seed", "1",
        "--budget", "600", "--evaluations", "100000",
    )  # fmt: skip
    assert code == 0, err
    result = json.loads(out)
    assert "start" in result["mechanism"]["mechanism"]
    document = tmp_path / "fit.json"
    document.write_text(json.dumps(result["mechanism"]))
    code, out, err = run_cli("curve", str(document), "--json", "-n", "4000")
    assert code == 0, err
    drawn = np.array([p for p in json.loads(out)["points"] if p is not None])
    size = float(np.ptp(points, axis=0).max())
    gap = polyline_distance(points, drawn)
    # The fit is exact (its error is printed); the 4,000-sample polyline's chords add at most
    # (curve length / 4000)² over its curvature radius, far below 1e-6 of the size.
    assert result["error"] <= 1e-12 * size**2
    assert float(np.max(gap)) <= 1e-6 * size


@given(shapes, st.floats(0.1, 0.9), st.integers(0, 1))
def test_targets_on_the_return_leg_are_found_there(shape, where, which):
    # A nearest-point fit meets its targets on the assembly's leg of the circuit; a target that
    # lies on the return leg (the other branch) is at distance 0 from the traced curve, and the
    # report must say so (issue 28, item 6).
    from linkwright.mechanisms import solve
    from linkwright.synthesis.path_verify import nearest_on_circuit

    m = _double_rocker(*shape)
    lo, hi = _arcs(m)[which]
    theta = np.array([lo + where * (hi - lo)])
    own = replace(m, start=float(theta[0]))
    other = solve(replace(own, assembly=-1.0), theta, order=0).positions["P"]
    here = solve(own, theta, order=0).positions["P"]
    size = float(max(m.coupler, m.crank, m.B0[0]))
    apart = float(np.linalg.norm(other - here))
    if apart < 1e-3 * size:  # the two legs cross here: nothing to find
        return
    inputs, reached, dist, branches = nearest_on_circuit(own, other, theta, here, np.array([apart]))
    assert float(dist[0]) < 1e-7 * size
    np.testing.assert_allclose(reached, other, atol=1e-7 * size)
    assert branches is not None and int(branches["B"][0]) == -1
    assert abs(float(inputs[0] - theta[0])) < 1e-6
