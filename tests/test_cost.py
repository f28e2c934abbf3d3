"""The cost model (linkwright.engine.cost): its estimates against measured reality, its budgets,
its refusals, and the deadline a request's loops check.

The work an estimate predicts is compared with the work the engine is seen to do: every call
of the engine's ``place_all`` is counted (plan steps × (inputs + the per-call cost)), an
independent tally of what ran. Its memory is compared with tracemalloc's peak. Both must agree
within a factor of 3 on moderate sizes; no timings are asserted.
"""

from __future__ import annotations

import importlib
import time
import tracemalloc
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from linkwright.engine import cost
from linkwright.engine.continuation import forget_kept
from linkwright.io import document_to_dict, load_example, parse_document
from linkwright.mechanisms import circuits, configurations, solve

_evaluate = importlib.import_module("linkwright.engine.evaluate")
_limit_search = importlib.import_module("linkwright.engine.limit_search")


@contextmanager
def counted() -> Iterator[dict[str, float]]:
    """Count the engine's work while the body runs: plan steps × (inputs + per-call cost)."""
    tally = {"units": 0.0, "calls": 0}
    original = _evaluate.place_all

    def place_all(plan, params, theta, **kw):
        theta, states = original(plan, params, theta, **kw)
        tally["units"] += len(plan.steps) * (np.size(theta) + cost.CALL_UNITS)
        tally["calls"] += 1
        return theta, states

    patched = [(_evaluate, "place_all"), (_limit_search, "place_all")]
    for module, name in patched:
        setattr(module, name, place_all)
    try:
        yield tally
    finally:
        for module, name in patched:
            setattr(module, name, original)


def peak_bytes(fn) -> float:
    tracemalloc.start()
    try:
        fn()
        return float(tracemalloc.get_traced_memory()[1])
    finally:
        tracemalloc.stop()


def geared(ratio: float):
    doc = document_to_dict(load_example("geared-fivebar"))
    doc["mechanism"]["ratio"] = ratio
    return parse_document(doc).mechanism


CASES = [
    ("crank-rocker", "input", 20_000),
    ("rocker-input", "path", 4_096),
    ("jansen-leg", "input", 20_000),
    ("paper000-fig8-sixbar", "path", 4_096),
    ("paper000-fig6-crank-rocker", "input", 20_000),
    ("geared ratio 8", "input", 4_096),
    ("geared ratio 16", "path", 2_048),
]


def _mechanism(name: str):
    if name.startswith("geared ratio"):
        return geared(float(name.split()[-1]))
    return load_example(name).mechanism


@pytest.mark.parametrize(("name", "spacing", "samples"), CASES)
def test_tracing_estimate_matches_the_work_and_memory_measured(name, spacing, samples) -> None:
    mech = _mechanism(name)
    shape = cost.Shape.of_mechanism(mech)
    # The model bounds the work done afresh: results kept from earlier calls (the workbench's
    # memo of arcs and samples) would make the measurement smaller than what it bounds.
    forget_kept()
    with counted() as tally:
        arcs, motions = circuits(mech, samples, order=0, spacing=spacing)
    estimate = cost.trace(
        shape, samples, circuits=len(motions), spacing=spacing, full=bool(arcs.full)
    )
    assert tally["units"] / 3 <= estimate.work <= 3 * tally["units"], (estimate, tally)

    def afresh() -> object:
        forget_kept()
        return circuits(mech, samples, order=0, spacing=spacing)

    peak = peak_bytes(afresh)
    assert peak / 3 <= estimate.bytes <= 3 * peak, (estimate.bytes, peak)


@pytest.mark.parametrize("name", ["crank-rocker", "jansen-leg", "paper000-fig8-sixbar"])
def test_solve_estimate_matches_the_work_and_memory_measured(name) -> None:
    mech = load_example(name).mechanism
    shape = cost.Shape.of_mechanism(mech)
    theta = np.linspace(-3.0, 3.0, 20_000)
    with counted() as tally:
        configurations(mech, theta, order=2)
    estimate = cost.solve(shape, theta.size, configurations=shape.configurations, order=2)
    assert tally["units"] / 3 <= estimate.work <= 3 * tally["units"], (estimate, tally)
    peak = peak_bytes(lambda: solve(mech, theta, order=2))
    one = cost.solve(shape, theta.size, order=2)
    assert peak / 3 <= one.bytes <= 3 * peak, (one.bytes, peak)


def test_triad_estimate_matches_the_memory_measured() -> None:
    from linkwright.mechanisms import solve_all

    doc = document_to_dict(load_example("paper001-stephenson3"))
    doc["mechanism"]["input"] = "FG"
    mech = parse_document(doc).mechanism
    theta = np.linspace(-3.0, 3.0, 5_000)
    peak = peak_bytes(lambda: solve_all(mech, theta))
    estimate = cost.solve(None, theta.size, triad="sphere")
    assert peak / 3 <= estimate.bytes <= 3 * peak


def test_every_bundled_example_fits_at_the_defaults_and_at_the_servers_largest_samples() -> None:
    from linkwright.io import list_examples
    from linkwright.mechanisms import input_range
    from linkwright.mechanisms.sixbar import NoConstructionPlan

    for name in list_examples():
        mech = load_example(name).mechanism
        try:
            shape = cost.Shape.of_mechanism(mech)
        except NoConstructionPlan:
            continue
        arcs = input_range(mech)
        k = 1 if bool(arcs.full) else max(int(arcs.count), 1)
        for samples, scope in ((360, cost.CLI), (4096, cost.REQUEST)):
            found = cost.trace(shape, samples, circuits=k, modes=4, full=bool(arcs.full))
            assert found.fits(scope), (name, samples, found)


def test_shape_counts_turns_gear_and_configurations() -> None:
    third = geared(1.5)
    shape = cost.Shape.of_mechanism(third)
    assert (shape.turns, shape.gear) == (2, 1.5)  # 3/2 repeats after 2 input turns
    leg = load_example("jansen-leg").mechanism
    # As many as solve --all enumerates.
    assert cost.Shape.of_mechanism(leg).configurations == len(configurations(leg, [0.0], order=0))


def test_a_crank_geared_past_the_budget_is_refused_naming_the_ratio() -> None:
    cost.check_gear(cost.Shape.of_mechanism(geared(64.0)))
    with pytest.raises(cost.CostError, match=r"1,000 times per input turn.*lower the ratio to 64"):
        cost.check_gear(cost.Shape.of_mechanism(geared(1000.0)), "the gear ratio 1000")


def test_combinations_beyond_the_budget_are_refused() -> None:
    twelve = cost.Shape(joints=15, dyads=12, turns=1, gear=1.0, space="plane", analytic=False)
    cost.check_combinations(twelve)
    thirteen = cost.Shape(joints=16, dyads=13, turns=1, gear=1.0, space="plane", analytic=False)
    with pytest.raises(
        cost.CostError, match=r"8,192 configurations; at most 4,096.*leave out --all"
    ):
        cost.check_combinations(thirteen)


@pytest.mark.parametrize(
    ("count", "samples", "shard", "names"),
    [
        (10**9, 64, 65_536, "--count"),
        (1000, 5000, 65_536, "--samples"),
        (10**8, 1000, 65_536, "--count to 6,400,000"),
        (10**7, 64, 10**7, "--shard-size to 93,200"),
        (10**6, 1024, 65_536, "--shard-size to 5,820"),
    ],
)
def test_atlas_builds_beyond_their_budgets_are_refused(count, samples, shard, names) -> None:
    with pytest.raises(cost.CostError) as caught:
        cost.check_atlas(count, samples, shard)
    assert names in str(caught.value) and "\n" not in str(caught.value)


def test_the_default_atlas_builds_fit() -> None:
    cost.check_atlas(100_000, 64, 65_536)  # the built-in atlas
    cost.check_atlas(10**8, 64, 65_536)  # the largest measured


def test_a_refusal_is_one_line_with_the_numbers_and_what_to_lower() -> None:
    shape = cost.Shape.of_mechanism(load_example("crank-rocker").mechanism)

    def build(n: int) -> cost.Estimate:
        return cost.trace(shape, n, spacing="path")

    with pytest.raises(cost.CostError) as caught:
        cost.with_knob(build, cost.CLI, 10**8, 2, "--points").check(cost.CLI)
    text = str(caught.value)
    assert "\n" not in text
    assert "100,000,000 samples" in text and "lower --points to" in text
    suggested = int(text.rsplit("lower --points to ", 1)[1].split()[0].replace(",", ""))
    assert build(suggested).fits(cost.CLI) and not build(10**8).fits(cost.CLI)


@settings(max_examples=60, deadline=None)
@given(
    work=st.floats(1.0, 1e6),
    fixed=st.floats(0.0, 1e9),
    budget=st.floats(1e8, 1e10),
    high=st.integers(2, 10**9),
)
def test_largest_is_the_last_value_that_fits(work, fixed, budget, high) -> None:
    scope = cost.Scope("test", cost.Budget("w", budget, "u", ""), cost.Budget("b", 1e30, "u", ""))

    def estimate(n: int) -> cost.Estimate:
        return cost.Estimate(fixed + work * n, 0.0, "x")

    best = cost.largest(estimate, scope, 1, high)
    if fixed + work > budget:
        assert best is None
        return
    assert best is not None and estimate(best).fits(scope)
    assert best == high or not estimate(best + 1).fits(scope)


def test_the_deadline_stops_a_loop_between_steps() -> None:
    cost.check_time()  # no deadline: nothing to check
    with cost.deadline(0.05, "count or samples"):
        cost.check_time()
        time.sleep(0.06)
        with pytest.raises(cost.OverTime, match=r"longer than the 0.05 s budget.*lower count"):
            cost.check_time()
    cost.check_time()  # gone with its block


def test_an_inner_deadline_never_outlasts_the_outer_one() -> None:
    with cost.deadline(0.05, "outer"), cost.deadline(60.0, "inner"):
        assert cost.remaining() is not None and cost.remaining() <= 0.05
    with cost.deadline(60.0, "outer"), cost.deadline(0.05, "inner"):
        assert cost.remaining() <= 0.05
    assert cost.remaining() is None


def test_errors_carry_the_status_a_server_answers() -> None:
    assert issubclass(cost.CostError, ValueError) and cost.CostError.http_status == 422
    assert not issubclass(cost.OverTime, ValueError) and cost.OverTime.http_status == 503


def test_every_budget_states_its_reason() -> None:
    for name, budget in cost.BUDGETS.items():
        assert budget.name == name and budget.value > 0 and len(budget.why) > 40, name
