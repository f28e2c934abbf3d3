"""The pylinkage peer of the benchmark (bench/peers.py) computes the same four-bars as linkwright.

Skipped where pylinkage is not installed (it is a benchmark-only dependency).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

pytest.importorskip("pylinkage")

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))
from peers import (
    PeerInputError,
    build_ensemble,
    build_single,
    peer_versions,
    pylinkage_ensemble,
    pylinkage_single,
)
from run import crank_rockers

from linkwright.mechanisms import FourBar, solve

THETA = np.linspace(-np.pi, np.pi, 360, endpoint=False)


def one_of(batch: FourBar, i: int) -> FourBar:
    return FourBar(**{k: np.asarray(v)[i] for k, v in batch.params().items()})


def cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def check_against_constraints(m: FourBar, A, B, P, theta) -> None:
    """Every pose closes every loop and lies on linkwright's assembly, input by input."""
    p = {k: np.asarray(v, dtype=float) for k, v in m.params().items()}
    A0, B0 = p["A0"][..., None, :], p["B0"][..., None, :]
    crank_dir = np.stack((np.cos(theta), np.sin(theta)), -1)
    np.testing.assert_allclose(A, A0 + p["crank"][..., None, None] * crank_dir, atol=1e-12)
    np.testing.assert_allclose(
        np.linalg.norm(B - A, axis=-1), np.broadcast_to(p["coupler"][..., None], A.shape[:-1])
    )
    np.testing.assert_allclose(
        np.linalg.norm(B - B0, axis=-1), np.broadcast_to(p["rocker"][..., None], A.shape[:-1])
    )
    assert np.all(np.sign(cross(B0 - A, B - A)) == p["assembly"][..., None])
    e = (B - A) / p["coupler"][..., None, None]
    left = np.stack((-e[..., 1], e[..., 0]), -1)
    np.testing.assert_allclose(
        P, A + p["u"][..., None, None] * e + p["v"][..., None, None] * left, atol=1e-12
    )


def test_ensemble_matches_linkwright_on_benchmark_linkages():
    m = crank_rockers(40, seed=3)
    A, B, P = pylinkage_ensemble(m, THETA)
    assert A.shape == B.shape == P.shape == (40, 360, 2)
    motion = solve(m, THETA, order=0)
    for name, got in zip("ABP", (A, B, P), strict=True):
        np.testing.assert_allclose(got, motion.positions[name], rtol=0, atol=1e-9)
    check_against_constraints(m, A, B, P, THETA)


def test_single_matches_linkwright_and_repeats():
    m = one_of(crank_rockers(5, seed=4), 2)
    peer = build_single(m, THETA)
    motion = solve(m, THETA, order=0)
    # twice: step_fast leaves the linkage at its last pose, the peer must start over each call
    for _ in range(2):
        for name, got in zip("ABP", pylinkage_single(peer, THETA), strict=True):
            np.testing.assert_allclose(got, motion.positions[name], rtol=0, atol=1e-9)


def test_prepared_ensemble_is_the_same_as_building_on_the_spot():
    m = crank_rockers(6, seed=5)
    peer = build_ensemble(m, THETA)
    for a, b in zip(pylinkage_ensemble(peer, THETA), pylinkage_ensemble(m, THETA), strict=True):
        np.testing.assert_array_equal(a, b)


@settings(max_examples=10, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    samples=st.integers(24, 200),
    start=st.floats(-np.pi, np.pi),
)
def test_random_crank_rockers_any_uniform_grid(seed, samples, start):
    m = crank_rockers(5, seed=seed)
    theta = start + np.arange(samples) * (2 * np.pi / samples)
    A, B, P = pylinkage_ensemble(m, theta)
    check_against_constraints(m, A, B, P, theta)


def test_bad_inputs_raise_clear_errors():
    m = crank_rockers(3)
    with pytest.raises(PeerInputError, match="uniformly spaced"):
        pylinkage_ensemble(m, [0.0, 0.1, 0.3])
    with pytest.raises(PeerInputError, match="at least 2"):
        pylinkage_ensemble(m, [0.0])
    with pytest.raises(PeerInputError, match="one four-bar"):
        pylinkage_single(m, THETA)
    with pytest.raises(PeerInputError, match="differs"):
        pylinkage_ensemble(build_ensemble(m, THETA), THETA[:-1])
    with pytest.raises(PeerInputError, match="FourBar only"):
        pylinkage_ensemble(object(), THETA)  # type: ignore[arg-type]


def test_versions():
    v = peer_versions()
    assert set(v) == {"pylinkage", "numba"} and all(v.values())
