"""The work a workbench scene does, and the shortcuts that make it interactive (issue 22).

A scene asks for one linkage's circuits several times (to count them for the budget, to draw
every assembly mode, again with derivatives for the diagrams): the searches are done once and
shared. Each shortcut is checked against the long way round, number for number.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from linkwright.engine import arc_search, continuation
from linkwright.engine import circuits as circuits_mod
from linkwright.engine.circuits import input_arcs, trace
from linkwright.engine.continuation import every_circuit, memo_key
from linkwright.engine.limit_search import bisect_brackets
from linkwright.engine.shared import share_arcs, share_samples
from linkwright.io import document_to_dict, load_example
from linkwright.server.scene import scene
from linkwright.server.scene_io import fields, read_document, set_path
from linkwright.server.scene_modes import assembly_modes


def _forget() -> None:
    for memo in (circuits_mod.ARCS_MEMO, circuits_mod.SAMPLED_MEMO):
        memo.clear()
    continuation._GRAPHS.clear()
    continuation._RESAMPLED.clear()


def _sequential(a: np.ndarray, b: np.ndarray, go_right, steps: int = 64):
    """Bisection one step at a time: the reference the batched steps must reproduce."""
    for _ in range(steps):
        mid = 0.5 * (a + b)
        right = go_right(mid[..., None])[..., 0]
        a = np.where(right, mid, a)
        b = np.where(right, b, mid)
    return a, b


@given(
    st.lists(
        st.tuples(
            st.floats(-10, 10),
            st.floats(1e-12, 1.0),
            st.floats(0, 1),
        ),
        min_size=1,
        max_size=40,
    ),
    st.integers(0, 3),
)
def test_bisection_in_batches_takes_the_steps_one_at_a_time(brackets, wiggle) -> None:
    # A predicate that may change its mind several times inside a bracket (``wiggle`` extra
    # flips): whichever change bisection settles on, the batched steps must settle on it too.
    a = np.array([x for x, _, _ in brackets])
    b = a + np.array([w for _, w, _ in brackets])
    root = a + (b - a) * np.array([f for _, _, f in brackets])

    def go_right(mid: np.ndarray) -> np.ndarray:
        ahead = mid <= root[:, None]
        for k in range(wiggle):
            ahead ^= np.sin((k + 2) * 1e3 * mid) > 0.9
        return ahead

    got = bisect_brackets(a.copy(), b.copy(), go_right)
    want = _sequential(a.copy(), b.copy(), go_right)
    np.testing.assert_array_equal(got[0], want[0])
    np.testing.assert_array_equal(got[1], want[1])


def _changed(name: str, rel: float = 3e-5) -> dict:
    """The example's document with its first length (or angle) changed: nothing kept applies."""
    doc = document_to_dict(load_example(name))
    f = next(f for f in fields(doc) if f["kind"] in ("length", "angle"))
    set_path(doc, f["path"], f["value"] * (1 + rel))
    return doc


def _counting(monkeypatch, module, name: str) -> list[int]:
    calls = [0]
    real = getattr(module, name)

    def counted(*args, **kwargs):
        calls[0] += 1
        return real(*args, **kwargs)

    monkeypatch.setattr(module, name, counted)
    return calls


def test_scene_walks_the_circuits_of_every_assembly_mode_once(monkeypatch) -> None:
    # A spherical six-bar draws four assembly modes and the diagrams of its own: its circuits
    # were walked five times (each mode, then the own mode again with derivatives).
    _forget()
    walks = _counting(monkeypatch, circuits_mod, "walk_circuit")
    s = scene(_changed("paper000-fig8-sixbar"), samples=60)
    assert len(s["modes"]) == 4 and s["diagrams"] is not None
    assert walks[0] == 1


def test_triad_scene_follows_its_configurations_once(monkeypatch) -> None:
    # The budget's count, the drawing and the diagrams each built the graph of joins (4 times).
    _forget()
    graphs = _counting(monkeypatch, continuation, "_graph")
    s = scene(_changed("stephenson3-output"), samples=60)
    assert s["modes"] and s["diagrams"] is not None
    assert graphs[0] == 1


def _modes(name: str):
    doc = read_document(_changed(name, 7e-5))
    return [variant.mechanism for _, _, variant, _ in assembly_modes(doc)]


@pytest.mark.parametrize("name", ["paper000-fig8-sixbar", "stephenson1-example", "klann-leg"])
def test_modes_traced_together_are_traced_as_alone(name: str) -> None:
    mechs = _modes(name)
    assert len(mechs) > 1
    plan, points = mechs[0].plan, mechs[0].points

    def every(m):
        arcs = input_arcs(m.plan, m.params(), points=m.points)
        count = 0 if bool(arcs.never) else 1 if bool(arcs.full) else int(arcs.count)
        return [
            trace(m.plan, m.params(), 90, points=m.points, circuit=k, order=2) for k in range(count)
        ]

    _forget()
    alone = [every(m) for m in mechs]
    _forget()
    share_samples(plan, [m.params() for m in mechs], 90, points=points)
    walks_before = len(circuits_mod.SAMPLED_MEMO._items)
    together = [every(m) for m in mechs]
    assert len(circuits_mod.SAMPLED_MEMO._items) == walks_before  # every trace was kept
    assert [len(x) for x in alone] == [len(x) for x in together]
    for xs, ys in zip(alone, together, strict=True):
        for x, y in zip(xs, ys, strict=True):
            np.testing.assert_array_equal(x.input, y.input)
            np.testing.assert_array_equal(x.valid, y.valid)
            for j in x.positions:
                np.testing.assert_array_equal(x.positions[j], y.positions[j])
                np.testing.assert_array_equal(x.accelerations[j], y.accelerations[j])


def test_kept_results_are_the_callers_own() -> None:
    # What a caller does to its answer must not reach the next caller's.
    _forget()
    m = _modes("stephenson3-example")[0]
    arcs = input_arcs(m.plan, m.params(), points=m.points)
    lo = arcs.lo.copy()
    arcs.lo[...] = 0.0
    np.testing.assert_array_equal(input_arcs(m.plan, m.params(), points=m.points).lo, lo)
    motion = trace(m.plan, m.params(), 40, points=m.points, order=0)
    before = _spoil(motion)
    _same(trace(m.plan, m.params(), 40, points=m.points, order=0), before)

    t = _modes("stephenson3-output")[0]
    found = every_circuit(t.plan, t.params(), 40, points=t.points, order=0)
    before = _spoil(found[0].motion)
    _same(every_circuit(t.plan, t.params(), 40, points=t.points, order=0)[0].motion, before)


def _arrays(motion) -> dict[str, np.ndarray]:
    out = {"input": motion.input}
    out |= {f"branch {k}": v for k, v in motion.branches.items()}
    out |= {f"position {k}": v for k, v in motion.positions.items()}
    return out


def _spoil(motion) -> dict[str, np.ndarray]:
    """Every writable array of the motion overwritten; what they held."""
    before = {k: np.array(v, copy=True) for k, v in _arrays(motion).items()}
    spoiled = 0
    for v in _arrays(motion).values():
        if isinstance(v, np.ndarray) and v.flags.writeable:
            v[...] = 0.0
            spoiled += 1
    assert spoiled
    return before


def _same(motion, before: dict[str, np.ndarray]) -> None:
    for k, v in _arrays(motion).items():
        np.testing.assert_array_equal(v, before[k], err_msg=k)


def test_kept_results_tell_nearby_linkages_apart() -> None:
    # A drag changes a field by a hair: the kept circuit of the linkage before it must not be
    # served for the linkage after it.
    m = _modes("stephenson3-example")[0]
    params = m.params()
    nudged = copy.copy(params)
    name = next(k for k, v in params.items() if np.ndim(v) == 0 and float(v) > 0)
    nudged[name] = np.nextafter(float(params[name]), np.inf)
    assert memo_key(m.plan, params, m.points) != memo_key(m.plan, nudged, m.points)
    _forget()
    trace(m.plan, params, 40, points=m.points, order=0)
    kept = trace(m.plan, nudged, 40, points=m.points, order=0)
    _forget()
    fresh = trace(m.plan, nudged, 40, points=m.points, order=0)
    np.testing.assert_array_equal(kept.input, fresh.input)


def test_large_batches_are_not_kept() -> None:
    # An atlas batch of thousands of linkages is traced once: keeping it would hold its memory.
    m = _modes("stephenson3-example")[0]
    params = {k: np.repeat(np.asarray(v)[None], 5000, axis=0) for k, v in m.params().items()}
    assert memo_key(m.plan, params, m.points) is None


def test_geared_linkages_are_not_searched_ahead_of_the_budget(monkeypatch) -> None:
    # A crank geared at 1000 has thousands of arcs: the caller's budget must see it before any
    # search, so the shared search leaves geared linkages alone.
    from linkwright.engine import Crank, DyadRRR, Fixed, Plan

    plan = Plan(
        (
            Fixed("A0", "A0"),
            Fixed("B0", "B0"),
            Crank("A", "A0", 1.0, ratio="k"),
            DyadRRR("B", "A", 3.0, "B0", 2.5, branch="s"),
            DyadRRR("C", "B", 2.0, "A0", 3.0),
        ),
        traced=("C",),
    )
    points = frozenset({"A0", "B0"})

    def linkages(ratio: float) -> list[dict]:
        return [
            {"A0": [0.0, 0.0], "B0": [4.0, 0.0], "k": ratio, "s": s, "assembly": 1.0}
            for s in (1.0, -1.0)
        ]

    _forget()
    searches = _counting(monkeypatch, arc_search, "numeric_arcs")
    share_arcs(plan, linkages(1000.0), points=points)
    assert searches[0] == 0
    share_arcs(plan, linkages(1.0), points=points)
    assert searches[0] == 1


def test_kept_configurations_do_not_follow_the_callers_arrays() -> None:
    # A triad's kept graph solves again for other sample counts: with numbers of its own, not
    # the caller's arrays, which the caller may since have changed in place.
    t = _modes("stephenson3-output")[0]
    mine = {k: np.array(v, dtype=float) for k, v in t.params().items()}
    _forget()
    every_circuit(t.plan, mine, 40, points=t.points, order=0)
    for v in mine.values():
        v[...] = 0.0  # the caller reuses its arrays (for a linkage that never assembles)
    kept = every_circuit(t.plan, t.params(), 50, points=t.points, order=0)
    _forget()
    fresh = every_circuit(t.plan, t.params(), 50, points=t.points, order=0)
    assert len(kept) == len(fresh)
    for a, b in zip(kept, fresh, strict=True):
        np.testing.assert_array_equal(a.motion.input, b.motion.input)
        for j in b.motion.positions:
            np.testing.assert_array_equal(a.motion.positions[j], b.motion.positions[j])
