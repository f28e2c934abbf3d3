"""Mechanisms are values: read-only arrays, equality and hashing, batches that index.

Each property is checked for every bundled example's family (a batch made from the example by
scaling its lengths), and indexing against solving: the motion of ``batch[i]`` is row ``i`` of
the batch's motion.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from linkwright.io import list_examples, load_example
from linkwright.mechanisms import FourBar, Linkage, solve

EXAMPLES = [name for name in list_examples() if load_example(name).mechanism is not None]


def _arrays(m):
    if isinstance(m, Linkage):
        return list(m.params().values())
    return [v for v in vars(m).values() if isinstance(v, np.ndarray)]


@pytest.mark.parametrize("name", EXAMPLES)
def test_every_family_is_a_value(name):
    m = load_example(name).mechanism
    for array in _arrays(m):
        with pytest.raises(ValueError, match="read-only"):
            array[...] = 0.0
    again = load_example(name).mechanism
    assert m == again and hash(m) == hash(again)
    assert len({m, again}) == 1
    with pytest.raises(TypeError, match="one mechanism, not a batch"):
        m[0]


def test_the_callers_array_stays_theirs():
    lengths = np.array([1.0, 1.5])
    m = FourBar(A0=[0, 0], B0=[4, 0], crank=lengths, coupler=5, rocker=3.5)
    lengths[0] = 2.0
    assert m.crank.tolist() == [1.0, 1.5]
    assert lengths.flags.writeable


@settings(max_examples=30)
@given(
    st.lists(st.floats(0.5, 3.0), min_size=2, max_size=6),
    st.floats(3.0, 6.0),
    st.sampled_from([slice(None, None, 2), slice(1, None), -1, 0]),
)
def test_a_batch_indexes_into_mechanisms(cranks, coupler, index):
    batch = FourBar(
        A0=[0, 0],
        B0=[4, 0],
        crank=cranks,
        coupler=coupler,
        rocker=3.5,
        assembly=np.where(np.arange(len(cranks)) % 2, 1.0, -1.0),
    )
    part = batch[index]
    theta = np.linspace(0, 2 * np.pi, 7)
    whole = solve(batch, theta).positions["B"][index]
    np.testing.assert_array_equal(solve(part, theta).positions["B"], whole)
    assert part == batch[index] and hash(part) == hash(batch[index])
    if part.batch_shape and len(part) > 1:
        same = part[0].crank == part[1].crank and part[0].assembly == part[1].assembly
        assert (part[0] == part[1]) == bool(same)


def test_composed_linkages_index_and_compare():
    from linkwright.mechanisms import CrankJoint, DyadJoint, FixedJoint

    joints = (
        FixedJoint("A0", [0, 0]),
        FixedJoint("B0", [4, 0]),
        CrankJoint("A", "A0", [1.0, 1.2, 1.4]),
        DyadJoint("B", "A", 5, "B0", 3.5),
    )
    batch = Linkage(joints=joints)
    assert len(batch) == 3
    second = batch[1]
    single = Linkage(joints=(*joints[:2], CrankJoint("A", "A0", 1.2), joints[3]))
    assert second == single and hash(second) == hash(single)
    np.testing.assert_array_equal(
        solve(second, [0.3]).positions["B"][0], solve(batch, [0.3]).positions["B"][1, 0]
    )
