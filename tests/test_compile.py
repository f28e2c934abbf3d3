"""Compiled plans (linkwright.engine.compile) against the plan evaluator, the reference.

For every registered family (one bundled example each, tests/family_examples.py), random
batches around the example (every length, arc, point and sign drawn per mechanism) are placed
by the generated kernel and by :func:`place_all`: positions, velocities, accelerations, valid
and regular masks and dyad margins must agree to 1e-12 relative. The batches include inputs
bisected onto limit positions (margins of ~1e-16), where the derivatives are ill-conditioned.

Where the two may differ, and why: a kernel performs the evaluator's planar operations in the
same order, so planar plans agree to the last bit (a crank whose phase is drawn per mechanism
aside: the kernel turns a shared cosine by it, a rounding apart). On the sphere the kernel's
dyad calls no atan2, sin or cos per sample (compile_steps._sphere_dyad), so a spherical dyad's
joint differs by rounding, amplified in its derivatives by the conditioning of their 3×3
solve; :func:`test_the_spherical_dyad_is_as_accurate_as_the_evaluator` checks both against
extended precision. The derivative tolerance therefore carries the factor 1/margin (the dyad's
sin² of its angle at P1, which vanishes at a limit position), and masks and values are
compared only away from the assembly tolerance (every margin outside ±1e-10), where a 1-ulp
difference of the margin can flip the decision.
"""

from __future__ import annotations

import os
import platform
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from family_examples import FAMILY_EXAMPLES, INPUT_EXAMPLES
from hypothesis import given, settings
from hypothesis import strategies as st

from linkwright.engine import compile as lwc
from linkwright.engine.continuation import every_configuration
from linkwright.engine.evaluate import evaluate, place_all
from linkwright.engine.plan import Crank, DyadRRR, Fixed, Plan
from linkwright.io import load_example
from linkwright.mechanisms import FAMILIES, solve

numba_only = pytest.mark.skipif(not lwc.available(), reason="numba (the fast extra) is missing")

BAND = 1e-10
"""Margins within ±BAND of 0: the assembly and singularity decisions may differ by rounding."""


@pytest.fixture(scope="session", autouse=True)
def kernel_cache(tmp_path_factory: pytest.TempPathFactory):
    """One cache directory for the session: each plan shape compiles once, whatever the test."""
    path = tmp_path_factory.mktemp("kernels")
    old = os.environ.get("LINKWRIGHT_CACHE")
    os.environ["LINKWRIGHT_CACHE"] = str(path)
    yield path
    if old is None:
        os.environ.pop("LINKWRIGHT_CACHE", None)
    else:
        os.environ["LINKWRIGHT_CACHE"] = old


def mechanism_of(key: str):
    rows = {**FAMILY_EXAMPLES, **INPUT_EXAMPLES}
    doc = load_example(rows[key])
    return getattr(doc, "mechanism", doc)


def perturbed(mechanism, n: int, rng: np.random.Generator, eps: float) -> dict[str, np.ndarray]:
    """The example's plan parameters, each drawn per mechanism within ±eps (relative) of the
    example's, branch signs at random; spherical points stay unit vectors."""
    plan = mechanism.plan
    signs = {s.branch for s in plan.dyads}
    out = {}
    for key, value in mechanism.params().items():
        value = np.asarray(value, dtype=float)
        if key in signs:
            out[key] = rng.choice([-1.0, 1.0], n)
        elif key in mechanism.points:
            size = max(1.0, float(np.abs(value).max()))
            moved = value + eps * size * rng.uniform(-1.0, 1.0, (n, *value.shape))
            if plan.space == "sphere":
                moved = moved / np.linalg.norm(moved, axis=-1, keepdims=True)
            out[key] = moved
        else:
            out[key] = value * (1.0 + eps * rng.uniform(-1.0, 1.0, n))
    return out


def limit_inputs(plan: Plan, params, points, theta: np.ndarray, per: int = 4) -> np.ndarray:
    """Per mechanism, up to ``per`` inputs bisected onto the edges of its assembled range (a
    limit position of some dyad, margin ~1e-16), padded with plain samples: ``(n, per)``."""

    def assembled(t: np.ndarray) -> np.ndarray:
        _, states = place_all(plan, params, t, points=points, order=0)
        valid = np.ones(t.shape, dtype=bool)
        for s in states.values():
            valid = valid & s.valid
        return valid

    valid = assembled(theta)
    n = valid.shape[0]
    lo = np.tile(theta[:per], (n, 1))
    hi = lo.copy()
    for i in range(n):
        edges = np.flatnonzero(valid[i, 1:] != valid[i, :-1])[:per]
        lo[i, : len(edges)], hi[i, : len(edges)] = theta[edges], theta[edges + 1]
    side = assembled(lo)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        same = assembled(mid) == side
        lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
    return lo  # the side of each edge the first plain sample was on


def outside_band(states) -> np.ndarray:
    """Samples where no dyad's margin is within ±BAND of 0 (NaN margins count as outside)."""
    keep = None
    for s in states.values():
        if s.margin is None:
            continue
        near = np.abs(s.margin) <= BAND
        keep = ~near if keep is None else keep & ~near
    return keep


def assert_same(got, ref, rtol: float = 1e-12) -> None:
    """Compiled states ``got`` equal the evaluator's ``ref`` (see the module doc)."""
    assert got.keys() == ref.keys()
    keep = outside_band(ref)
    some = next(iter(ref.values()))
    if keep is None:
        keep = np.ones(some.valid.shape, dtype=bool)
    # Every margin on the sample's chain: the conditioning of its derivatives.
    cond = np.ones(keep.shape)
    for s in ref.values():
        if s.margin is not None:
            cond = np.minimum(cond, np.where(np.isfinite(s.margin), np.abs(s.margin), 1.0))
    cond = np.maximum(cond, 1e-300)
    size = np.ones(keep.shape[:-1] + (1,))
    for s in ref.values():
        mag = np.nanmax(np.abs(s.pos), axis=(-1, -2), initial=0.0)
        size = np.maximum(size, mag[..., None] if mag.ndim == keep.ndim - 1 else 1.0)
    for name in ref:
        a, b = got[name], ref[name]
        for mask in ("valid", "regular"):
            x, y = getattr(a, mask), getattr(b, mask)
            assert np.array_equal(x[keep], y[keep]), (name, mask)
        for attr, factor in (("pos", 1.0), ("vel", 1.0 / cond), ("acc", 1.0 / cond**2)):
            x, y = getattr(a, attr), getattr(b, attr)
            if y is None:
                assert x is None, (name, attr)
                continue
            x, y = x[keep], y[keep]
            assert np.array_equal(np.isnan(x), np.isnan(y)), (name, attr, "NaN pattern")
            f = np.broadcast_to(factor, keep.shape)[keep][..., None]
            s = np.broadcast_to(size, keep.shape)[keep][..., None]
            tol = rtol * np.maximum(np.abs(y), s) * f
            ok = np.isnan(y) | (np.abs(x - y) <= tol)
            assert ok.all(), (name, attr, float(np.nanmax(np.abs(x - y) / tol)))
        if b.margin is not None:
            x, y = a.margin[keep], b.margin[keep]
            assert np.allclose(x, y, rtol=rtol, atol=rtol, equal_nan=True), (name, "margin")
            assert np.array_equal(np.broadcast_to(a.branch, b.branch.shape), b.branch)


COMPILED_FAMILIES = sorted(FAMILY_EXAMPLES)


def test_every_registered_family_has_an_example_row() -> None:
    """The rows below cover the registry (the composed linkage in both spaces)."""
    from family_examples import family_of

    assert {family_of(k) for k in FAMILY_EXAMPLES} == set(FAMILIES)


@numba_only
@pytest.mark.parametrize("key", COMPILED_FAMILIES)
@settings(max_examples=6, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(1, 5),
    eps=st.sampled_from([0.02, 0.1, 0.3]),
)
def test_family_matches_the_evaluator(key: str, seed: int, n: int, eps: float) -> None:
    """Positions, derivatives, masks and margins of random batches, near-singular inputs
    included (bisected onto limit positions), equal the evaluator's."""
    mech = mechanism_of(key)
    rng = np.random.default_rng(seed)
    params = perturbed(mech, n, rng, eps)
    theta = np.sort(rng.uniform(-np.pi, np.pi, 181))
    theta = np.concatenate(
        [limit_inputs(mech.plan, params, mech.points, theta), np.tile(theta, (n, 1))], axis=1
    )
    compiled = lwc.compiled_plan(mech.plan)
    assert compiled.compiled, compiled.reason
    _, got = compiled.place(params, theta, points=mech.points, order=2)
    _, ref = place_all(mech.plan, params, theta, points=mech.points, order=2)
    assert_same(got, ref)


@numba_only
@pytest.mark.parametrize("key", ["watt1", "spherical-sixbar", "linkage-plane"])
def test_every_assembly_mode_in_one_pass(key: str) -> None:
    """configurations() equals every_configuration(): the same combinations in the same
    order, each mode's positions, derivatives and masks the evaluator's (32 modes for
    Jansen's leg)."""
    mech = mechanism_of(key)
    rng = np.random.default_rng(7)
    params = perturbed(mech, 3, rng, 0.05)
    theta = np.linspace(-np.pi, np.pi, 97)
    combos, got = lwc.compiled_plan(mech.plan).configurations(
        params, theta, points=mech.points, order=2
    )
    ref_combos, ref = every_configuration(mech.plan, params, theta, points=mech.points, order=2)
    assert combos == ref_combos
    assert np.array_equal(got.valid, ref.valid)
    assert np.array_equal(got.regular, ref.regular)
    # The conditioning of each sample's derivatives (see the module doc): its least margin.
    margins = [np.abs(m) for m in ref.margins.values()]
    cond = np.maximum(np.fmin.reduce(margins), 1e-300)[..., None] if margins else 1.0
    for name in ref.positions:
        for a, b, factor in (
            (got.positions, ref.positions, 1.0),
            (got.velocities, ref.velocities, 1.0 / cond),
            (got.accelerations, ref.accelerations, 1.0 / cond**2),
        ):
            x, y = a[name], b[name]
            assert np.array_equal(np.isnan(x), np.isnan(y)), name
            ok = ~np.isnan(y)
            scale = np.abs(y[ok]).max()
            tol = 1e-12 * np.maximum(np.abs(y), scale) * factor
            assert np.all(np.abs(x - y)[ok] <= tol[ok]), name
    for name in ref.labels:
        assert np.array_equal(got.labels[name], np.broadcast_to(ref.labels[name], got.valid.shape))


@numba_only
@pytest.mark.parametrize("order", [0, 1])
def test_lower_orders_and_shared_parameters(order: int) -> None:
    """One four-bar (every parameter one value for the batch, so the crank's cosines are
    shared), at order 0 and 1, and a batch with inputs of its own per mechanism: the
    evaluator's numbers, and no derivative arrays beyond the order."""
    mech = mechanism_of("fourbar")
    theta = np.linspace(0.0, 2 * np.pi, 50)
    compiled = lwc.compiled_plan(mech.plan)
    _, got = compiled.place(mech.params(), theta, points=mech.points, order=order)
    _, ref = place_all(mech.plan, mech.params(), theta, points=mech.points, order=order)
    assert_same(got, ref)
    assert all((s.acc is None) == (order < 2) for n, s in got.items() if n not in mech.plan.ground)
    params = perturbed(mech, 4, np.random.default_rng(1), 0.1)
    per = np.random.default_rng(2).uniform(-4, 4, (4, 9))
    _, got = compiled.place(params, per, points=mech.points, order=order)
    _, ref = place_all(mech.plan, params, per, points=mech.points, order=order)
    assert_same(got, ref)


@numba_only
def test_the_solve_hook_gives_the_motion_of_solve() -> None:
    """compile.solve(mechanism, inputs) is mechanisms.solve's Motion (masked alike)."""
    mech = mechanism_of("stephenson3")
    theta = np.linspace(-np.pi, np.pi, 73)
    got, ref = lwc.solve(mech, theta), solve(mech, theta)
    assert np.array_equal(got.valid, ref.valid) and np.array_equal(got.regular, ref.regular)
    for name in ref.positions:
        np.testing.assert_allclose(got.positions[name], ref.positions[name], rtol=1e-12)
        np.testing.assert_allclose(got.accelerations[name], ref.accelerations[name], rtol=1e-12)


@pytest.mark.parametrize("key", sorted(INPUT_EXAMPLES))
def test_plans_with_triads_fall_back_to_the_evaluator(key: str) -> None:
    """A pose step (a triad, a driven hinge) has no compiled form: the plan says why and
    places through place_all."""
    mech = mechanism_of(key)
    compiled = lwc.compiled_plan(mech.plan)
    assert not compiled.compiled and "no compiled form" in compiled.reason
    theta = np.linspace(-1.0, 1.0, 7)
    _, got = compiled.place(mech.params(), theta, points=mech.points, order=1)
    _, ref = place_all(mech.plan, mech.params(), theta, points=mech.points, order=1)
    for name in ref:
        np.testing.assert_array_equal(got[name].pos, ref[name].pos)


def test_without_numba_everything_goes_through_the_evaluator(monkeypatch) -> None:
    """Without the fast extra a compiled plan is the evaluator, and says so."""
    monkeypatch.setattr(lwc, "available", lambda: False)
    mech = mechanism_of("fourbar")
    compiled = lwc.CompiledPlan(mech.plan)
    assert not compiled.compiled and "numba" in compiled.reason
    theta = np.linspace(0.0, 6.0, 5)
    _, got = compiled.place(mech.params(), theta, points=mech.points)
    _, ref = place_all(mech.plan, mech.params(), theta, points=mech.points)
    np.testing.assert_array_equal(got["P"].pos, ref["P"].pos)


def test_bad_orders_and_unbounded_work_are_refused_before_any_work(monkeypatch) -> None:
    """A one-line ValueError for an order other than 0-2, for more modes than MAX_MODES and for
    a result larger than the bound, each before any kernel is generated."""
    mech = mechanism_of("fourbar")
    compiled = lwc.compiled_plan(mech.plan)
    with pytest.raises(ValueError, match="order: must be 0, 1 or 2"):
        compiled.place(mech.params(), [0.0], points=mech.points, order=3)
    if not compiled.compiled:
        return
    monkeypatch.setattr(lwc, "load_kernel", lambda source: pytest.fail("compiled anyway"))
    monkeypatch.setattr(lwc, "MAX_OUTPUT_BYTES", 10_000)
    with pytest.raises(ValueError, match="GiB") as err:
        compiled.place(mech.params(), np.zeros(1000), points=mech.points)
    assert "\n" not in str(err.value)
    chain = [Fixed("O", "O"), Fixed("Q", "Q"), Crank("J0", "O", 1.0)]
    chain += [DyadRRR(f"J{k + 1}", f"J{k}", 1.0, "Q", 1.0, f"s{k}") for k in range(13)]
    plan = Plan(tuple(chain), traced=("J13",))
    params = {"O": [0.0, 0.0], "Q": [1.0, 0.0], **{f"s{k}": 1.0 for k in range(13)}}
    with pytest.raises(ValueError, match="8192 assembly modes"):
        lwc.compiled_plan(plan).configurations(params, [0.0], points=frozenset("OQ"))


@numba_only
def test_a_second_process_loads_the_kernel_from_the_disk_cache(kernel_cache: Path) -> None:
    """The generated source lies in $LINKWRIGHT_CACHE/kernels, and a new process finds numba's
    machine code for it there (a cache hit, no compile)."""
    mech = mechanism_of("fourbar")
    lwc.compiled_plan(mech.plan).place(mech.params(), [0.0, 1.0], points=mech.points, order=1)
    sources = list((kernel_cache / "kernels").glob("lw_*.py"))
    assert sources and all(
        "generated by linkwright.engine.compile" in p.read_text() for p in sources
    )
    script = (
        "import sys; sys.path.insert(0, 'tests')\n"
        "from test_compile import mechanism_of\n"
        "from linkwright.engine import compile as lwc\n"
        "from linkwright.engine import compile_cache\n"
        "m = mechanism_of('fourbar')\n"
        "lwc.compiled_plan(m.plan).place(m.params(), [0.0, 1.0], points=m.points, order=1)\n"
        "(kernel,) = compile_cache._LOADED.values()\n"
        "print(sum(kernel.stats.cache_hits.values()), sum(kernel.stats.cache_misses.values()))\n"
    )
    env = dict(os.environ, LINKWRIGHT_CACHE=str(kernel_cache))
    root = Path(__file__).resolve().parents[1]
    done = subprocess.run(
        [sys.executable, "-c", script], cwd=root, env=env, capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    hits, misses = map(int, done.stdout.split())
    assert (hits, misses) == (1, 0)


def test_every_step_kind_but_the_triads_has_a_fragment() -> None:
    """The plan modules' step kinds, triads aside, each own a compiled fragment."""
    from linkwright.engine import plan as plan_module
    from linkwright.engine.compile_steps import FRAGMENTS

    kinds = set(plan_module.PLANE_STEPS) | set(plan_module.SPHERE_STEPS) | {Fixed}
    assert kinds == set(FRAGMENTS)


def _sample_loop(source: str) -> list[str]:
    """The lines of a generated kernel's sample loop (the first ``for jj`` loop's body)."""
    lines = source.splitlines()
    start = next(k for k, line in enumerate(lines) if line.strip() == "for jj in range(nb):")
    indent = len(lines[start]) - len(lines[start].lstrip())
    body = []
    for line in lines[start + 1 :]:
        if len(line) - len(line.lstrip()) <= indent:
            break
        body.append(line)
    return body


def _source(key: str, order: int, joints: tuple[str, ...] | None = None) -> str:
    mech = mechanism_of(key)
    params = perturbed(mech, 3, np.random.default_rng(0), 0.05)
    compiled = lwc.compiled_plan(mech.plan)
    shape, *_ = compiled._prepare(params, np.linspace(0.0, 1.0, 5), mech.points)
    return lwc.generate(mech.plan, shape, order, False, joints)


@pytest.mark.parametrize("key", COMPILED_FAMILIES)
def test_the_sample_loop_calls_no_libm_function(key: str) -> None:
    """No cos, sin, atan2 ... per sample (a call keeps LLVM from vectorising the loop): cranks'
    cosines come from NumPy, trigonometry of parameters is hoisted, the spherical dyad needs
    none. Checked on the source, for every family, every parameter drawn per mechanism."""
    for order, joints in ((0, None), (2, None), (0, mechanism_of(key).plan.traced)):
        body = _sample_loop(_source(key, order, joints))
        called = set(re.findall(r"math\.(\w+)", "\n".join(body)))
        # sqrt, isfinite and copysign are LLVM intrinsics or compares, with packed forms.
        assert body and called <= {"sqrt", "isfinite", "copysign"}, called


@numba_only
@pytest.mark.skipif(platform.machine() not in ("x86_64", "AMD64"), reason="x86 assembly")
@pytest.mark.parametrize("key", ["stephenson3", "spherical-sixbar"])
def test_the_sample_loop_is_vectorised(key: str, tmp_path: Path) -> None:
    """The kernel's machine code holds packed square roots (``sqrtpd``, on SSE2 or AVX
    registers): LLVM vectorised the sample loop. The source is compiled afresh here, without
    the disk cache, whose loaded code numba cannot show."""
    import importlib.util

    source = _source(key, 0, mechanism_of(key).plan.traced).replace("cache=True", "cache=False")
    path = tmp_path / "fresh_kernel.py"
    path.write_text(source)
    spec = importlib.util.spec_from_file_location("fresh_kernel", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    mech = mechanism_of(key)
    compiled = lwc.compiled_plan(mech.plan)
    params = perturbed(mech, 3, np.random.default_rng(0), 0.05)
    _, S, U, trig, n, _ = compiled._prepare(params, np.linspace(0.0, 1.0, 5), mech.points)
    outs = [np.empty((n, 5, compiled.dim)) for _ in mech.plan.traced]
    module.kernel(0, n, 5, S, U, *trig, *outs)
    (signature,) = module.kernel.signatures
    asm = module.kernel.inspect_asm(signature)
    assert re.search(r"\bv?sqrtpd\b", asm), "no packed square root: the loop stayed scalar"


@numba_only
@pytest.mark.parametrize("key", COMPILED_FAMILIES)
def test_positions_only_are_the_motions_masked_positions(key: str) -> None:
    """positions() writes the named joints alone, NaN wherever any joint of the mechanism is
    not placed: evaluate()'s Motion positions, to 1e-12 relative (away from the assembly
    tolerance, as above)."""
    mech = mechanism_of(key)
    rng = np.random.default_rng(11)
    params = perturbed(mech, 4, rng, 0.1)
    theta = np.sort(rng.uniform(-np.pi, np.pi, 150))
    compiled = lwc.compiled_plan(mech.plan)
    got = compiled.positions(params, theta, tuple(compiled.moving), points=mech.points)
    ref = evaluate(mech.plan, params, theta, points=mech.points, order=0)
    _, states = place_all(mech.plan, params, theta, points=mech.points, order=0)
    keep = outside_band(states)
    keep = np.ones(ref.valid.shape, dtype=bool) if keep is None else keep
    size = max(1.0, float(np.nanmax(np.abs(np.stack([ref.positions[j] for j in got])))))
    for name, x in got.items():
        y = ref.positions[name]
        assert x.shape == y.shape
        x, y = x[keep], y[keep]
        assert np.array_equal(np.isnan(x), np.isnan(y)), name
        ok = ~np.isnan(y)
        assert np.all(np.abs(x[ok] - y[ok]) <= 1e-12 * size), name
    traced = compiled.positions(params, theta, points=mech.points)
    assert list(traced) == list(mech.plan.traced)


def test_positions_of_a_joint_not_placed_are_refused() -> None:
    """A ground pivot or an unknown name: a one-line ValueError naming the moving joints."""
    mech = mechanism_of("fourbar")
    compiled = lwc.compiled_plan(mech.plan)
    for name in (mech.plan.joints[0], "nowhere"):
        with pytest.raises(ValueError, match="not a moving joint") as err:
            compiled.positions(mech.params(), [0.0], (name,), points=mech.points)
        assert "\n" not in str(err.value)


EXTENDED = np.finfo(np.longdouble).eps < 1e-17


def _dyad_extended(p1, p2, r1, r2, sign):
    """sphere.small_circles' point in extended precision (the evaluator's formulas, np.longdouble
    throughout): an independent reference ~1000 times finer than either method."""
    p1, p2, r1, r2, sign = (np.asarray(a, dtype=np.longdouble) for a in (p1, p2, r1, r2, sign))
    w = np.cross(p1, p2)
    sin_d, cos_d = np.sqrt((w * w).sum(-1)), (p1 * p2).sum(-1)
    d = np.arctan2(sin_d, cos_d)
    s = (d + r1 + r2) / 2
    g = 4 * np.sin(s) * np.sin(s - d) * np.sin(s - r1) * np.sin(s - r2)
    u = np.cross(w, p1)
    t = u / np.sqrt((u * u).sum(-1))[..., None]
    phi = np.arctan2(sign * np.sqrt(np.clip(g, 0, None)), np.cos(r2) - np.cos(r1) * cos_d)
    n = np.cross(p1, t)
    across = np.cos(phi)[..., None] * t + np.sin(phi)[..., None] * n
    point = np.cos(r1)[..., None] * p1 + np.sin(r1)[..., None] * across
    return point, g / (sin_d * np.sin(r1)) ** 2


@numba_only
@pytest.mark.skipif(not EXTENDED, reason="np.longdouble is no wider than double here")
@settings(max_examples=5, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), eps=st.sampled_from([0.05, 0.2]))
def test_the_spherical_dyad_is_as_accurate_as_the_evaluator(seed: int, eps: float) -> None:
    """The kernel's spherical dyad (no atan2, sin or cos per sample) against the evaluator's
    formulas in extended precision: its error, scaled by √margin (the conditioning of the
    point near a limit position), is at most 1e-14 (a few tens of ulp: seen up to 2.5e-15 on
    fresh seeds), and no worse than four times the evaluator's own plus a few ulp."""
    mech = mechanism_of("spherical-sixbar")
    rng = np.random.default_rng(seed)
    params = perturbed(mech, 20, rng, eps)
    theta = np.linspace(-np.pi, np.pi, 361)
    _, got = lwc.compiled_plan(mech.plan).place(params, theta, points=mech.points, order=0)
    _, ref = place_all(mech.plan, params, theta, points=mech.points, order=0)
    step = mech.plan.step("B")  # its inputs (the crank's A, the pivot B0) are the same bits
    ones = np.ones(theta.shape)
    r1, r2, sign = (np.asarray(params[k])[:, None] * ones for k in (step.r1, step.r2, step.branch))
    exact, margin = _dyad_extended(ref[step.p1].pos, ref[step.p2].pos, r1, r2, sign)
    ok = ref["B"].valid & (np.abs(ref["B"].margin) > BAND)
    if not ok.any():
        return
    root = np.sqrt(np.abs(margin[ok]).astype(float))
    kernel = np.abs(got["B"].pos - exact).max(-1)[ok].astype(float) * root
    plan = np.abs(ref["B"].pos - exact).max(-1)[ok].astype(float) * root
    assert kernel.max() <= 1e-14
    assert kernel.max() <= 4.0 * plan.max() + 1e-15


@numba_only
def test_positions_into_given_arrays() -> None:
    """positions(out=...) writes the caller's arrays (no new ones) with the numbers of a fresh
    call, and refuses, in one line, an array of another shape, dtype or layout."""
    mech = mechanism_of("stephenson3")
    params = perturbed(mech, 3, np.random.default_rng(5), 0.05)
    theta = np.linspace(0.0, 2 * np.pi, 40)
    compiled = lwc.compiled_plan(mech.plan)
    fresh = compiled.positions(params, theta, ("P", "D"), points=mech.points)
    out = {"P": np.full((3, 40, 2), 7.0), "D": np.full((3, 40, 2), 7.0)}
    got = compiled.positions(params, theta, ("P", "D"), points=mech.points, out=out)
    for name in ("P", "D"):
        assert np.shares_memory(got[name], out[name])
        np.testing.assert_array_equal(out[name], fresh[name])
    for bad in (
        np.zeros((3, 41, 2)),
        np.zeros((3, 40, 2), dtype=np.float32),
        np.zeros((3, 40, 4))[..., ::2],
    ):
        with pytest.raises(ValueError, match="out") as err:
            compiled.positions(params, theta, ("P",), points=mech.points, out={"P": bad})
        assert "\n" not in str(err.value)


@numba_only
@pytest.mark.parametrize("family", ["geared-fivebar", "stephenson3"])
def test_atlas_curves_come_from_the_compiled_plan(family: str, monkeypatch) -> None:
    """The atlas samples a geared five-bar's or a six-bar's curves through the compiled plan
    (positions of the traced point only), and they are the plan evaluator's."""
    from linkwright.atlas import families

    designs = families.sample(family, np.random.default_rng(3), 40)
    calls = []
    original = lwc.CompiledPlan.positions

    def spy(self, *args, **kwargs):
        calls.append(self.plan)
        return original(self, *args, **kwargs)

    monkeypatch.setattr(lwc.CompiledPlan, "positions", spy)
    got = families.curves(family, designs, 48)
    assert calls, "the atlas did not use the compiled plan"
    monkeypatch.setattr(lwc, "available", lambda: False)
    ref = families.curves(family, designs, 48)
    assert got.shape == ref.shape
    assert np.array_equal(np.isnan(got), np.isnan(ref))
    ok = ~np.isnan(ref)
    assert np.all(np.abs(got[ok] - ref[ok]) <= 1e-12 * max(1.0, float(np.abs(ref[ok]).max())))
