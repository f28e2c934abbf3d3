"""Circuits through singular geometry on random mechanisms drawn at and around their singularities.

NumPy batches and single mechanisms from Hypothesis (tests/singular_helpers.py), traced with
``spacing="input"`` and ``spacing="path"`` and held to the checks of tests/singular_checks.py:
constraints, limits as samples, no branch jump, the path spacing's step bound.
"""

from __future__ import annotations

from dataclasses import fields

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from singular_checks import check_circuit, circuit_of
from singular_helpers import (
    FAMILIES,
    build_fourbars,
    build_sphericals,
    random_recipes,
    recipes,
    through_pivot,
)

from linkwright.engine import trace
from linkwright.mechanisms import (
    GearedFiveBar,
    input_range,
)

# ----------------------------------------------------------------------------------------------
# Tests
# ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("spacing", ["path", "input"])
@pytest.mark.parametrize("family", sorted(FAMILIES))
def test_near_singular_batch(family, spacing):
    rng = np.random.default_rng(20261010)
    m = FAMILIES[family](random_recipes(rng, 300))
    ratio = check_circuit(m, 120, spacing)
    if ratio is not None:  # trace's docstring: measured c ≤ 1.19 where rounding is negligible
        assert np.nanmax(ratio) <= 1.25


@settings(max_examples=60, deadline=None)
@given(
    recipe=recipes(),
    family=st.sampled_from(sorted(FAMILIES)),
    n=st.integers(16, 240),
    spacing=st.sampled_from(["path", "input"]),
)
def test_near_singular_single(recipe, family, n, spacing):
    m = FAMILIES[family](recipe)
    # Within 1e-12 of A passing through B0 the positions' rounding is of the order of the miss:
    # left out (exactly through it is a crossing, tested on its own below).
    assume(not np.any(through_pivot(m)))
    check_circuit(m, n, spacing)


def test_path_batch_equals_one_by_one():
    rng = np.random.default_rng(20261011)
    for build in (build_fourbars, build_sphericals):
        m = build(random_recipes(rng, 12))
        whole = circuit_of(m, 40, "path")
        for i in range(12):
            one = circuit_of(take(m, i), 40, "path")
            np.testing.assert_array_equal(one.input[0], whole.input[i])
            for j, pos in one.positions.items():
                np.testing.assert_array_equal(pos[0], whole.positions[j][i])


def take(m, i):
    """The ``i``-th mechanism of a batch, as a batch of one."""
    out = {}
    for f in fields(m):
        if f.name == "start":  # where it runs, one value for a batch
            continue
        tail = (2,) if f.name in m.points else ()
        value = np.broadcast_to(np.asarray(getattr(m, f.name), float), m.batch_shape + tail)
        out[f.name] = value[i : i + 1]
    return type(m)(**out)


@pytest.mark.parametrize("spacing", ["path", "input"])
def test_cranks_that_always_coincide_never_assemble(spacing):
    """Two equal cranks on one pivot, geared 1:1 in phase: the dyad's pivots coincide at every
    input, so it is undefined everywhere: no input assembles it (not a full turn of NaN)."""
    m = GearedFiveBar(A0=[0, 0], B0=[0, 0], crank1=1, crank2=1, link1=1, link2=1, ratio=1)
    arcs = input_range(m)
    assert bool(arcs.never) and not bool(arcs.full)
    motion = trace(m.plan, m.params(), 8, points=m.points, order=0, spacing=spacing)
    assert not motion.valid.any()


def test_curve_command_spacing_path_keeps_steps_short(tmp_path, capsys):
    """`linkwright curve --spacing path` on the near-deltoid: even input steps draw a chord of
    over a third of the curve; along the path no step reaches a tenth of it."""
    import json

    from linkwright.cli import main

    doc = tmp_path / "near-deltoid.json"
    mechanism = {"family": "fourbar", "A0": [0, 0], "B0": [1, 0], "crank": 1 + 1e-9,
                 "coupler": 2, "rocker": 2, "point": {"u": 1, "v": 0.5}}  # fmt: skip
    doc.write_text(json.dumps({"format": "linkwright/1", "mechanism": mechanism}))
    largest = {}
    for spacing in ("input", "path"):
        assert main(["curve", str(doc), "-n", "72", "--spacing", spacing, "--json"]) == 0
        points = np.array(json.loads(capsys.readouterr().out)["points"])
        size = np.linalg.norm(points.max(axis=0) - points.min(axis=0))
        largest[spacing] = np.linalg.norm(np.roll(points, -1, 0) - points, axis=1).max() / size
    assert largest["input"] > 0.3 and largest["path"] < 0.1, largest
