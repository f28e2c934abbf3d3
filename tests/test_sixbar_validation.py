"""Six-bars that cannot assemble, batches against one-by-one solves, validation messages, and
the output-driven Stephenson III.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from sixbar_helpers import (
    EXAMPLE_NAMES,
    SIXBARS,
    assert_closes,
    example_fields,
    random_sixbars,
    take,
)

from linkwright.engine import Plan
from linkwright.mechanisms import (
    InvalidMechanism,
    circuit,
    circuits,
    configurations,
    solve,
)
from linkwright.mechanisms.sixbar import (
    Stephenson1,
    Stephenson3,
    Watt1,
    Watt2,
)


@pytest.mark.parametrize("cls", SIXBARS, ids=lambda c: c.family)
def test_circuit_of_a_linkage_that_never_assembles(cls):
    """No circuit, every joint NaN, for one six-bar or a batch (the second dyad far too short)."""
    fields = {**_example_fields(cls), "link1": 0.01, "link2": 0.01}
    for m in (cls(**fields), cls(**{**fields, "link1": [0.01, 0.02]})):
        motion = circuit(m, 16)
        assert not motion.valid.any() and not motion.regular.any()
        for pos in motion.positions.values():
            assert np.isnan(pos).all()


# ----------------------------------------------------------------------------------------------
# 5. Batched equals one by one; validation; the output-driven Stephenson III
# ----------------------------------------------------------------------------------------------


def test_batch_equals_one_by_one():
    rng = np.random.default_rng(20250601)
    theta = rng.uniform(-np.pi, np.pi, 16)
    for cls in SIXBARS:
        m = random_sixbars(cls, rng, 20)
        batch = solve(m, theta)
        for i in range(20):
            one = solve(take(m, i), theta)
            for field in ("valid", "regular"):
                np.testing.assert_array_equal(getattr(one, field), getattr(batch, field)[i])
            for field in ("positions", "velocities", "accelerations", "margins", "branches"):
                whole, part = getattr(one, field), getattr(batch, field)
                assert whole.keys() == part.keys()
                for k in whole:
                    np.testing.assert_array_equal(whole[k], part[k][i], err_msg=(field, k))


def _example_fields(cls):
    return {k: v for k, v in example_fields(EXAMPLE_NAMES[SIXBARS.index(cls)]).items()}


@pytest.mark.parametrize("cls", SIXBARS, ids=lambda c: c.family)
def test_validation_names_the_field(cls):
    fields = _example_fields(cls)
    for name, bad, match in (
        ("assembly2", 0.5, "assembly2: must be 1 or -1"),
        ("assembly2", [1.0, 0.0], "assembly2: must be 1 or -1"),
        ("link1", -1.0, "link1: must be a positive length"),
        ("link2", 0.0, "link2: must be a positive length"),
        ("u1", math.nan, "u1: must be finite"),
    ):
        with pytest.raises(InvalidMechanism, match=match):
            cls(**{**fields, name: bad})
    with pytest.raises(TypeError, match="u1"):  # attachments are required: no default
        cls(**{k: v for k, v in fields.items() if k != "u1"})
    assert cls.plan.joints == cls.reported_joints
    assert cls.plan.traced == ("P",)


@pytest.mark.parametrize(
    ("cls", "zeros", "match"),
    [
        (Watt1, {"u1": "crank", "v1": 0.0, "u2": 0.0, "v2": 0.0}, r"^u2, v2: E at \(0, 0\)"),
        (Watt2, {"u1": 0.0, "v1": 0.0}, r"^u1, v1: C at \(0, 0\) is the rocker pivot B0"),
        (Stephenson1, {"u1": 0.0, "v1": 0.0, "u2": 0.0, "v2": 0.0}, r"^u1, v1, u2, v2: C = A0"),
    ],
)
def test_degenerate_attachments_are_rejected(cls, zeros, match):
    """Attachments that leave the second dyad undefined or immobile, and nearby ones that don't."""
    fields = _example_fields(cls)
    at = {k: (fields["crank"] if v == "crank" else v) for k, v in zeros.items()}
    with pytest.raises(InvalidMechanism, match=match):
        cls(**{**fields, **at})
    # In a batch, one bad member is enough; one coordinate off makes a good linkage.
    batch = {k: [fields[k], v] for k, v in at.items()}
    with pytest.raises(InvalidMechanism, match=match):
        cls(**{**fields, **batch})
    first = next(iter(at))
    cls(**{**fields, **at, first: at[first] + 0.5})


def test_stephenson3_input_field():
    fields = _example_fields(Stephenson3)
    for bad in ("Crank", "E", 1.0, None):
        with pytest.raises(
            InvalidMechanism, match=r"^input: must be one of crank, output, rocker, A, B, C, D "
        ):
            Stephenson3(**{**fields, "input": bad})
    m = Stephenson3(**fields)
    assert m.input == "crank" and isinstance(m.input, str)
    out = Stephenson3(**{**fields, "input": "output"})
    assert out.input == "output" and out.input_link == ("D0", "D")
    assert out.with_assembly(-1.0).input == "output"  # rebuilt from params(), input kept
    assert isinstance(Stephenson3.plan, Plan)  # the class shows the crank-driven structure
    assert not m.plan.triads
    # Driven at the output, the coupler is a triad step of the plan, and every verb works.
    assert [type(t).__name__ for t in out.plan.triads] == ["Triad"]
    assert solve(out, [0.0]).positions["P"].shape == (1, 2)
    assert len(configurations(out, [0.0])) == 6
    arcs, found = circuits(out, 16)
    assert len(found) == int(arcs.count) and all(mo.valid.all() for mo in found)
    assert circuit(out, 16).input.shape == (16,) or not found


def test_stephenson3_output_residuals():
    """Driven at the output, the same positions satisfy the same constraints, the input now
    being the angle of D − D0: the residuals see that, and only that, difference."""
    rng = np.random.default_rng(20250701)
    m = random_sixbars(Stephenson3, rng, 1000)
    motion = solve(m, rng.uniform(-np.pi, np.pi, (1000, 8)), order=0)
    out = Stephenson3(**{**m.params(), "input": "output"})
    D = motion.positions["D"] - motion.positions["D0"]
    driven = type(motion)(
        input=np.arctan2(D[..., 1], D[..., 0]),
        positions=motion.positions,
        velocities=None,
        accelerations=None,
        valid=motion.valid,
        regular=motion.valid,
    )
    assert motion.valid.mean() > 0.1
    assert_closes(out, driven)
    crank_driven = m.residuals(driven)["input"][motion.valid]
    assert np.median(crank_driven) > 1e-3  # the crank's angle is not the output's
