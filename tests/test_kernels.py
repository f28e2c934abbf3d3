"""Compiled four-bar kernels against the construction plan (the reference) and the constraints."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from linkwright.engine import kernels
from linkwright.engine.kernels import (
    KernelInputError,
    fourbar_coupler_points,
    fourbar_positions,
    positions,
    spherical_fourbar_coupler_points,
    spherical_fourbar_positions,
)
from linkwright.mechanisms import FourBar, SphericalFourBar, input_range, solve

numba = pytest.importorskip("numba")
prange = range  # numba.prange where compiled() compiles this module's functions


def _random_fourbars(rng: np.random.Generator, n: int) -> FourBar:
    # Lengths spread over a decade so that crank-rockers, double rockers and linkages that
    # assemble only on part of the turn (NaN samples) all occur.
    return FourBar(
        A0=rng.uniform(-2, 2, (n, 2)),
        B0=rng.uniform(-2, 2, (n, 2)),
        crank=rng.uniform(0.2, 3, n),
        coupler=rng.uniform(0.2, 3, n),
        rocker=rng.uniform(0.2, 3, n),
        u=rng.uniform(-2, 2, n),
        v=rng.uniform(-2, 2, n),
        assembly=rng.choice([-1.0, 1.0], n),
    )


def _random_spherical(rng: np.random.Generator, n: int) -> SphericalFourBar:
    arcs = rng.uniform(0.05, np.pi - 0.05, (4, n))
    return SphericalFourBar(
        *arcs,
        point_arc=rng.uniform(0, np.pi, n),
        point_angle=rng.uniform(-np.pi, np.pi, n),
        assembly=rng.choice([-1.0, 1.0], n),
    )


def _compare(mech, theta, tol_rel):
    ref = solve(mech, theta, order=0)
    got = positions(mech, theta)
    scale = np.asarray(mech.scale)[..., None]
    tol = tol_rel
    if mech.space == "sphere":
        # The data fix B only to eps/(√margin · sin d · sin r1): near a limit position (margin →
        # 0, √eps at the limit itself) or with A nearly antipodal to B0 (d → π, a change point)
        # two correct evaluations differ by that much whatever the code. Calibrated on 1.6M
        # random samples: |error|·conditioning ≤ 1.3e-15; well-conditioned samples (≥ 0.05)
        # agree to 2e-14.
        margin = np.clip(np.nan_to_num(ref.margins["B"]), np.finfo(float).eps, None)
        f = np.asarray(mech.frame)[..., None]
        b0 = np.stack(np.broadcast_arrays(np.cos(f), np.sin(f), 0 * f), axis=-1)
        sin_d = np.linalg.norm(np.cross(ref.positions["A"], b0), axis=-1)
        cond = np.sqrt(margin) * sin_d * np.sin(np.asarray(mech.coupler))[..., None]
        cond = np.where(ref.valid, cond, 1.0)  # no position to compare there, only the mask
        with np.errstate(divide="ignore"):
            tol = np.maximum(tol_rel, 4e-15 / cond)
    for joint in ("A", "B", "P"):
        r, g = ref.positions[joint], got[joint]
        assert g.shape == r.shape
        np.testing.assert_array_equal(np.isnan(g), np.isnan(r))
        np.testing.assert_array_equal(np.isnan(g).any(axis=-1), ~ref.valid)
        err = np.nan_to_num(np.abs(g - r)).max(axis=-1) / scale
        assert np.all(err <= tol), (joint, (err / tol).max())
    if mech.space == "sphere":
        well = ref.valid & (cond >= 0.05)
        for joint in ("B", "P"):
            d = np.abs(got[joint] - ref.positions[joint]).max(axis=-1)
            assert np.all(d[well] <= tol_rel), joint
    return ref


def test_planar_matches_plan_on_random_batch():
    rng = np.random.default_rng(5)
    mech = _random_fourbars(rng, 400)
    theta = rng.uniform(-np.pi, 3 * np.pi, 181)
    ref = _compare(mech, theta, 1e-12)
    # Both signs and both closing and non-closing samples really were exercised.
    assert 0.2 < ref.valid.mean() < 0.9
    assert set(np.unique(mech.assembly)) == {-1.0, 1.0}


def test_spherical_matches_plan_on_random_batch():
    rng = np.random.default_rng(6)
    mech = _random_spherical(rng, 400)
    theta = rng.uniform(-np.pi, 3 * np.pi, 181)
    ref = _compare(mech, theta, 1e-13)
    assert 0.2 < ref.valid.mean() < 0.9


def test_constraint_residuals_vanish():
    # Independent of the plan: the mechanisms' own constraint residuals on the kernel output.
    rng = np.random.default_rng(7)
    theta = np.linspace(0, 2 * np.pi, 73)
    for mech in (_random_fourbars(rng, 100), _random_spherical(rng, 100)):
        ref = solve(mech, theta, order=0)
        got = positions(mech, theta)
        motion = type(ref)(
            input=ref.input,
            positions={**ref.positions, **got},
            velocities=None,
            accelerations=None,
            valid=ref.valid,
            regular=ref.valid,
        )
        for name, res in mech.residuals(motion).items():
            assert np.nanmax(np.abs(res)) < 1e-10, name


def test_branch_sign_is_assembly():
    rng = np.random.default_rng(8)
    theta = np.linspace(0, 2 * np.pi, 91)
    planar = _random_fourbars(rng, 50)
    pos = positions(planar, theta)
    a, b = pos["A"], pos["B"]
    b0 = np.asarray(planar.B0)[:, None, :]
    cross = (b0 - a)[..., 0] * (b - a)[..., 1] - (b0 - a)[..., 1] * (b - a)[..., 0]
    ok = np.abs(cross) > 1e-9
    assert np.all((np.sign(cross) == planar.assembly[:, None])[ok])
    sph = _random_spherical(rng, 50)
    pos = positions(sph, theta)
    f = np.asarray(sph.frame)[:, None]
    b0 = np.stack(np.broadcast_arrays(np.cos(f), np.sin(f), 0 * f), axis=-1)
    triple = np.einsum("...i,...i", np.cross(pos["A"], b0), pos["B"])
    ok = np.abs(triple) > 1e-9
    assert np.all((np.sign(triple) == sph.assembly[:, None])[ok])


@settings(max_examples=40, deadline=None)
@given(
    arcs=st.lists(st.floats(0.05, np.pi - 0.05), min_size=4, max_size=4),
    point=st.tuples(st.floats(0, np.pi), st.floats(-np.pi, np.pi)),
    lengths=st.lists(st.floats(0.1, 5.0), min_size=3, max_size=3),
    pivots=st.lists(st.floats(-3, 3), min_size=4, max_size=4),
    sign=st.sampled_from([-1.0, 1.0]),
)
def test_property_single_mechanisms(arcs, point, lengths, pivots, sign):
    theta = np.linspace(-np.pi, np.pi, 37)
    _compare(SphericalFourBar(*arcs, *point, assembly=sign), theta, 1e-13)
    planar = FourBar(pivots[:2], pivots[2:], *lengths, u=point[0], v=point[1], assembly=sign)
    _compare(planar, theta, 1e-12)


def test_scalar_batch_and_out_arrays():
    theta = np.linspace(0, 2 * np.pi, 10)
    mech = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5, u=1, v=0.5)
    got = positions(mech, theta)
    assert got["P"].shape == (10, 2)
    out = tuple(np.full((1, 10, 2), 7.0) for _ in range(3))
    res = fourbar_positions([0, 0], [4, 0], 1, 5, 3.5, 1, 0.5, 1, theta, out=out)
    assert all(r is o for r, o in zip(res, out, strict=True))
    np.testing.assert_array_equal(out[2][0], got["P"])


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.sampled_from([1, 3, 16, 17, 40]))
def test_coupler_points_are_the_positions_p(seed, n):
    """P alone (the atlas's and the descriptors' path) is bit for bit the P of the full kernels,
    serial (n ≤ 16) and parallel, NaN where the linkage does not assemble, and fills ``out``."""
    rng = np.random.default_rng(seed)
    theta = np.linspace(-np.pi, np.pi, 29)
    planar = _random_fourbars(rng, n)
    p = planar.params()
    args = tuple(p[k] for k in ("A0", "B0", "crank", "coupler", "rocker", "u", "v", "assembly"))
    out = np.full((n, theta.size, 2), 7.0)
    got = fourbar_coupler_points(*args, theta, out=out)
    assert got is out
    np.testing.assert_array_equal(got, fourbar_positions(*args, theta)[2])
    sphere = _random_spherical(rng, n)
    q = sphere.params()
    names = ("frame", "crank", "coupler", "rocker", "point_arc", "point_angle", "assembly")
    sargs = tuple(q[k] for k in names)
    want = spherical_fourbar_positions(*sargs, theta)[2]
    np.testing.assert_array_equal(spherical_fourbar_coupler_points(*sargs, theta), want)


def test_streaming_stores_give_the_same_numbers(monkeypatch):
    """Large outputs go to memory with streaming stores: the same numbers as plain stores, for
    every joint and for P alone, serial and parallel; an output that is not 16-byte aligned (a
    view NumPy did not allocate) is written with plain stores, also correctly."""
    rng = np.random.default_rng(11)
    theta = np.linspace(-np.pi, np.pi, 45)
    for n in (3, 50):
        p = _random_fourbars(rng, n).params()
        args = tuple(p[k] for k in ("A0", "B0", "crank", "coupler", "rocker", "u", "v"))
        args += (p["assembly"],)
        monkeypatch.setattr(kernels, "STREAM_BYTES", 2**62)
        plain = fourbar_positions(*args, theta)
        monkeypatch.setattr(kernels, "STREAM_BYTES", 0)
        assert kernels._streams(*plain)
        streamed = fourbar_positions(*args, theta)
        for a, b in zip(plain, streamed, strict=True):
            np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(fourbar_coupler_points(*args, theta), plain[2])
        buffer = np.empty(n * theta.size * 2 + 1)
        skip = 1 if buffer.ctypes.data % 16 == 0 else 0
        shifted = buffer[skip : skip + plain[2].size].reshape(plain[2].shape)
        assert not kernels._streams(shifted)
        got = fourbar_coupler_points(*args, theta, out=shifted)
        np.testing.assert_array_equal(got, plain[2])
    # Interpreted, the streaming helpers are plain stores (and the module keeps them plain).
    monkeypatch.setattr(kernels, "_numba", lambda: None)
    monkeypatch.setattr(kernels, "_KERNELS", {})
    interpreted = fourbar_positions(*(a[:2] for a in args), theta[:5])
    monkeypatch.undo()
    compiled = fourbar_positions(*(a[:2] for a in args), theta[:5])
    for a, b in zip(interpreted, compiled, strict=True):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-15)


def _thread_of_each(out):
    for i in prange(out.shape[0]):
        out[i] = numba.get_thread_id()


def test_serial_and_parallel_variants_are_cached_apart(monkeypatch, tmp_path):
    """numba's disk cache keys a function by name and bytecode, not by its options: a serial
    variant compiled first used to be loaded for the parallel one too, which then ran on one
    thread (the spherical kernel at half its speed)."""
    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("one thread: a parallel loop cannot show itself")
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(kernels, "_KERNELS", {})
    threads = np.full(256, -1.0)
    kernels.compiled(_thread_of_each, parallel=False)(threads)
    assert set(threads) == {0.0}
    kernels.compiled(_thread_of_each, parallel=True)(threads)
    assert len(set(threads)) > 1
    assert len(list(tmp_path.rglob("*.nbi"))) == 2  # two cache entries, one per variant


def test_bad_input_raises_named_errors():
    theta = [0.0]
    with pytest.raises(KernelInputError, match="theta"):
        fourbar_positions([0, 0], [4, 0], 1, 5, 3.5, 0, 0, 1, [[0.0]])
    with pytest.raises(KernelInputError, match="theta"):
        fourbar_positions([0, 0], [4, 0], 1, 5, 3.5, 0, 0, 1, [np.nan])
    with pytest.raises(KernelInputError, match="coupler"):
        fourbar_positions([0, 0], [4, 0], 1, -5, 3.5, 0, 0, 1, theta)
    with pytest.raises(KernelInputError, match="assembly"):
        fourbar_positions([0, 0], [4, 0], 1, 5, 3.5, 0, 0, 0.5, theta)
    with pytest.raises(KernelInputError, match="disagree"):
        fourbar_positions([0, 0], [4, 0], [1, 2], [5, 5, 5], 3.5, 0, 0, 1, theta)
    with pytest.raises(KernelInputError, match="rocker"):
        spherical_fourbar_positions(1, 1, 1, np.pi, 0, 0, 1, theta)
    with pytest.raises(KernelInputError, match="out"):
        fourbar_positions([0, 0], [4, 0], 1, 5, 3.5, 0, 0, 1, theta, out=(np.empty((1, 2, 2)),) * 3)
    with pytest.raises(KernelInputError, match="out: P"):
        fourbar_coupler_points([0, 0], [4, 0], 1, 5, 3.5, 0, 0, 1, theta, out=np.empty((1, 1, 3)))
    with pytest.raises(KernelInputError, match="out: P"):
        spherical_fourbar_coupler_points(1, 1, 1, 1, 0, 0, 1, theta, out=np.empty((1, 1, 2)))
    with pytest.raises(KernelInputError, match="SliderCrank"):
        from linkwright.mechanisms import SliderCrank

        positions(SliderCrank(A0=[0, 0], crank=1, rod=3), theta)
    with pytest.raises(KernelInputError, match="batch shape"):
        positions(FourBar([0, 0], [4, 0], np.ones((2, 2)), 5, 3.5), theta)


def test_available_and_interpreted_fallback(monkeypatch):
    assert kernels.available()
    rng = np.random.default_rng(9)
    mech = _random_spherical(rng, 3)
    theta = np.linspace(0, 2 * np.pi, 9)
    compiled = positions(mech, theta)
    # Without numba the same loops run interpreted, with the same numbers.
    monkeypatch.setattr(kernels, "_numba", lambda: None)
    monkeypatch.setattr(kernels, "_KERNELS", {})
    assert not kernels.available()
    plain = positions(mech, theta)
    for k in compiled:
        np.testing.assert_allclose(plain[k], compiled[k], rtol=0, atol=1e-15)


def test_prepared_fourbar_repeats_the_batched_kernel():
    """The latency path (checked once, serial, outputs reused) gives the batched kernel's numbers
    on every call, also after the outputs were overwritten in between."""
    from linkwright.engine.kernels import fourbar_positions, prepared_fourbar

    rng = np.random.default_rng(7)
    theta = np.linspace(-np.pi, np.pi, 97, endpoint=False)
    for n in (1, 5):
        args = (
            rng.uniform(-1, 1, (n, 2)),
            rng.uniform(-1, 1, (n, 2)) + 2.0,
            rng.uniform(0.1, 0.3, n),
            rng.uniform(1.5, 2.5, n),
            rng.uniform(1.5, 2.5, n),
            rng.uniform(-1, 1, n),
            rng.uniform(-1, 1, n),
            rng.choice([-1.0, 1.0], n),
        )
        want = fourbar_positions(*args, theta)
        curve = prepared_fourbar(*args, theta)
        first = [a.copy() for a in curve()]
        for a in curve():
            a[...] = 0.0
        again = curve()
        for w, f, g in zip(want, first, again, strict=True):
            np.testing.assert_array_equal(w, f)
            np.testing.assert_array_equal(w, g)


def _motion_of(mech: FourBar, theta: np.ndarray):
    p = mech.params()
    return kernels.fourbar_motion(
        *(p[k] for k in ("A0", "B0", "crank", "coupler", "rocker", "u", "v", "assembly")), theta
    )


def test_motion_kernel_matches_plan_derivatives():
    """Velocities and accelerations against the plan's steps, with the same NaN masks (not
    assembled, and singular at the limit positions)."""
    rng = np.random.default_rng(11)
    mech = _random_fourbars(rng, 300)
    theta = rng.uniform(-np.pi, 3 * np.pi, 121)
    ref = solve(mech, theta, order=2)
    (pos, vel, acc) = _motion_of(mech, theta)
    scale = np.asarray(mech.scale)[:, None]
    # Derivatives blow up like 1/√margin near a limit position, and their rounding with them.
    margin = np.clip(np.nan_to_num(ref.margins["B"]), 1e-16, None)
    for got, want, tol in (
        (pos, ref.positions, 1e-12),
        (vel, ref.velocities, 1e-10),
        (acc, ref.accelerations, 1e-10),
    ):
        for joint, g in zip(("A", "B", "P"), got, strict=True):
            w = want[joint]
            np.testing.assert_array_equal(np.isnan(g), np.isnan(w))
            err = np.nan_to_num(np.abs(g - w)).max(axis=-1) / scale
            allowed = tol / margin**1.5
            assert np.all(err <= allowed), (joint, (err / allowed).max())
    assert 0.2 < ref.valid.mean() < 0.9


@settings(max_examples=40, deadline=None)
@given(
    lengths=st.lists(st.floats(0.3, 3.0), min_size=3, max_size=3),
    pivots=st.lists(st.floats(-2, 2), min_size=4, max_size=4),
    point=st.tuples(st.floats(-2, 2), st.floats(-2, 2)),
    sign=st.sampled_from([-1.0, 1.0]),
    t=st.floats(-np.pi, np.pi),
)
def test_motion_kernel_is_the_derivative_of_the_positions(lengths, pivots, point, sign, t):
    """Independent of the plan: 8th-order central differences of the kernel's own positions."""
    mech = FourBar(pivots[:2], pivots[2:], *lengths, u=point[0], v=point[1], assembly=sign)
    h = 1e-3
    offsets = np.arange(-4, 5) * h
    (pos, vel, acc) = _motion_of(mech, t + offsets)
    P = pos[2][0]
    if np.isnan(P).any() or np.isnan(vel[2][0, 4]).any():
        return
    # Far enough from a limit position for the differences to mean something: the positions
    # go like the square root of the distance to it, so the stencil (±4h) must stay well clear
    # of it (measured in the input, exactly, not through the dyad's margin).
    ref = solve(mech, [t], order=0)
    if ref.margins["B"][0] < 1e-2:
        return
    arcs = input_range(mech)
    ends = np.concatenate([arcs.lo[np.isfinite(arcs.lo)], arcs.hi[np.isfinite(arcs.hi)]])
    if ends.size and np.min(np.abs(np.angle(np.exp(1j * (ends - t))))) < 40 * h:
        return
    # Nor where the crank brings A close to B0 (a near-rhombus folding): B then turns like
    # crank/|A B0| per radian, its k-th derivative like (crank/|A B0|)^k, and a stencil ±4h
    # wide is no longer a Taylor expansion (a fresh run drew |A B0| = 0.0078 with crank 1:
    # the 8th-order stencil missed by 1e-5 through its own truncation).
    a_at_t = np.array(pivots[:2]) + lengths[0] * np.array([np.cos(t), np.sin(t)])
    if np.linalg.norm(a_at_t - np.array(pivots[2:])) < 50 * h * lengths[0]:
        return
    c1 = np.array([1 / 280, -4 / 105, 1 / 5, -4 / 5, 0, 4 / 5, -1 / 5, 4 / 105, -1 / 280])
    c2 = np.array([-1 / 560, 8 / 315, -1 / 5, 8 / 5, -205 / 72, 8 / 5, -1 / 5, 8 / 315, -1 / 560])
    size = float(mech.scale)
    np.testing.assert_allclose(c1 @ P / h, vel[2][0, 4], atol=1e-6 * size / ref.margins["B"][0])
    np.testing.assert_allclose(
        c2 @ P / h**2, acc[2][0, 4], atol=1e-4 * size / ref.margins["B"][0] ** 2
    )


def test_prepared_motion_and_bad_order():
    args = ([0, 0], [4, 0], 1, 5, 3.5, 2.5, 1.0, 1)
    theta = np.linspace(0, 2 * np.pi, 17)
    run = kernels.prepared_fourbar(*args, theta, order=2)
    want = kernels.fourbar_motion(*args, theta)
    for w, g in zip(want, run(), strict=True):
        for a, b in zip(w, g, strict=True):
            np.testing.assert_array_equal(a, b)
    with pytest.raises(KernelInputError, match="order"):
        kernels.prepared_fourbar(*args, theta, order=1)
