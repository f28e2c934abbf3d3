"""Drawings for the drawing compiler's tests, and the checks they are held to: the drawn pose at
θ = 0 and every link's lengths along the motion (shared by ``test_sketch`` and
``test_sketch_triads``)."""

from __future__ import annotations

import math

import numpy as np

from linkwright.io import parse_document
from linkwright.io.sketch import CLOSURE, compile_sketch
from linkwright.mechanisms import solve

THETA = np.linspace(0.0, 2.0 * np.pi, 73)
"""Inputs the compiled linkages are compared at (every 5°)."""


def pin(name: str, *at: float, **extra: object) -> dict:
    return {"name": name, "at": list(at), **extra}


def ground(name: str, *at: float) -> dict:
    return pin(name, *at, ground=True)


def drive(pivot: str, joint: str, ratio: float = 1.0) -> dict:
    return {"pivot": pivot, "joint": joint, "ratio": ratio}


# Stephenson: the ternary ground (A0, B0, D0) and the ternary coupler A-B-C are not adjacent.
STEPHENSON = {
    "joints": [
        ground("A0", 0, 0),
        pin("A", 1, 0.4),
        pin("B", 3.8, 2.2),
        ground("B0", 4.5, 0),
        pin("C", 2.0, 3.6),
        pin("D", 0.2, 5.0),
        ground("D0", -1.5, 3.0),
    ],
    "links": [["A0", "A"], ["A", "B", "C"], ["B0", "B"], ["C", "D"], ["D0", "D"]],
    "drivers": [drive("A0", "A")],
}


def compiled(sketch: dict):
    """The ok report's linkage, built again from its document by the document parser."""
    report = compile_sketch(sketch)
    assert report.status == "ok", report.message
    return report, parse_document(report.document).mechanism


def drawn(sketch: dict) -> dict[str, np.ndarray]:
    out = {}
    for j in sketch["joints"]:
        at = np.asarray(j["at"], dtype=float)
        out[j["name"]] = at / np.linalg.norm(at) if len(at) == 3 else at
    return out


def size_of(sketch: dict) -> float:
    at = drawn(sketch)
    if sketch.get("space") == "sphere":
        return 1.0
    sizes = [float(np.abs(p).max()) for p in at.values()]
    for link in sketch["links"]:
        sizes += [float(np.linalg.norm(at[a] - at[b])) for a in link for b in link]
    return max(sizes)


def assert_closure(sketch: dict, mech, inputs=THETA) -> np.ndarray:
    """Every joint where it was drawn at θ = 0, and every link's lengths (and every slider's
    distance from its guide) as drawn at every assembled input; the valid mask."""
    motion = solve(mech, inputs)
    pos, ok = motion.positions, motion.valid
    at = drawn(sketch)
    tol = CLOSURE * size_of(sketch)
    zero = solve(mech, [0.0]).positions
    for name, p in at.items():
        assert np.linalg.norm(zero[name][0] - p) <= tol, name
    for link in sketch["links"]:
        for a in link:
            for b in link:
                moved = np.linalg.norm(pos[a][ok] - pos[b][ok], axis=-1)
                assert np.max(np.abs(moved - np.linalg.norm(at[a] - at[b]))) <= tol, (a, b)
    for j in sketch["joints"]:
        if "slider" in j:
            d = np.array([math.cos(math.radians(j["slider"])), math.sin(math.radians(j["slider"]))])
            off = pos[j["name"]][ok] - at[j["name"]]
            assert np.max(np.abs(d[0] * off[:, 1] - d[1] * off[:, 0])) <= tol
    return ok


def angle_of(v: np.ndarray) -> float:
    return math.atan2(v[1], v[0])


def unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)
