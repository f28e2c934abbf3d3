"""The curve atlas: sampling, shards, determinism across Dask workers, resume after a kill,
the index against exact search, and matching curves that are not in the atlas."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from linkwright.atlas import (
    FAMILIES,
    AtlasBuildError,
    AtlasError,
    AtlasQueryError,
    build,
    default_atlas,
    open_atlas,
    query,
    sample,
)
from linkwright.atlas.families import curves
from linkwright.atlas.index import Index, exact_search, merge_variants, recall_at
from linkwright.atlas.store import finished_shards
from linkwright.cli import main
from linkwright.mechanisms import FourBar, solve
from linkwright.synthesis.path_families import MODELS


@pytest.fixture(scope="module")
def fourbars(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("atlas") / "fourbar"
    build("fourbar", 30_000, out, shard_size=10_000, workers=0)
    return out


def _shards(path: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(path.glob("shard-*"))}


def _polyline_rms(points: np.ndarray, curve: np.ndarray) -> float:
    """RMS distance from points to a closed polyline, by dense subdivision of its segments (an
    independent check of the query's own figure)."""
    a, b = curve, np.roll(curve, -1, axis=0)
    t = np.linspace(0.0, 1.0, 50, endpoint=False)
    dense = (a[:, None, :] + t[None, :, None] * (b - a)[:, None, :]).reshape(-1, curve.shape[1])
    d2 = np.min(np.sum((points[:, None, :] - dense[None]) ** 2, axis=-1), axis=1)
    return float(np.sqrt(np.mean(d2)))


# ------------------------------------------------------------------------------------------
# Sampling
# ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("family", FAMILIES)
def test_every_kept_design_turns_fully_by_the_plan(family):
    designs = sample(family, np.random.default_rng(3), 300)
    model = MODELS[family]
    mech = model.local(designs, designs["assembly"])
    motion = solve(mech, np.linspace(0.0, 2.0 * np.pi, 720, endpoint=False), order=0)
    assert motion.valid.all()
    # The kernel path (where there is one) traces the same curves as the plan.
    P = curves(family, designs, 720)
    np.testing.assert_allclose(P, motion.positions["P"], atol=1e-9)


def test_sampling_depends_on_the_stream_alone():
    a = sample("geared-fivebar", np.random.default_rng(11), 500)
    b = sample("geared-fivebar", np.random.default_rng(11), 500)
    assert all(np.array_equal(a[k], b[k]) for k in a)
    assert set(np.unique(a["ratio"])) <= {-2.0, -1.0, 1.0, 2.0}


# ------------------------------------------------------------------------------------------
# Building: determinism, resume, refusal
# ------------------------------------------------------------------------------------------


def test_two_dask_workers_write_the_same_bytes_as_one_process(tmp_path):
    pytest.importorskip("dask.distributed")
    one = build("fourbar", 9_000, tmp_path / "one", seed=7, shard_size=3_000, workers=0)
    two = build("fourbar", 9_000, tmp_path / "two", seed=7, shard_size=3_000, workers=2)
    assert two["build"]["workers"] == 2 and one["build"]["workers"] == 0
    assert _shards(tmp_path / "one") == _shards(tmp_path / "two")
    assert [s["sha256"] for s in one["shards"]] == [s["sha256"] for s in two["shards"]]
    other = build("fourbar", 3_000, tmp_path / "other", seed=8, shard_size=3_000, workers=0)
    assert other["shards"][0]["sha256"] != one["shards"][0]["sha256"]


def test_a_killed_build_resumes_without_redoing_finished_shards(tmp_path):
    out = tmp_path / "killed"
    args = ["atlas", "build", "--family", "fourbar", "--count", "150000", "--shard-size",
            "7500", "--workers", "0", "--out", str(out), "--quiet"]  # fmt: skip
    proc = subprocess.Popen([sys.executable, "-m", "linkwright", *args])
    deadline = time.monotonic() + 120
    while len(list(out.glob("shard-*.sha256"))) < 2:
        assert proc.poll() is None, "the build finished before it could be killed"
        assert time.monotonic() < deadline
        time.sleep(0.02)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert not (out / "atlas.json").exists()
    with pytest.raises(AtlasError, match="unfinished"):
        open_atlas(out)
    sizes = [7_500] * 20
    done = finished_shards(out, sizes)
    assert len(done) >= 2
    before = {i: os.stat(out / f"shard-{i:05d}.npy").st_mtime_ns for i in done}
    assert main(args) == 0
    manifest = json.loads((out / "atlas.json").read_text())
    assert manifest["build"]["shards_resumed"] >= len(done)
    assert {i: os.stat(out / f"shard-{i:05d}.npy").st_mtime_ns for i in done} == before
    assert not list(out.glob(".tmp-*"))
    clean = build("fourbar", 150_000, tmp_path / "clean", shard_size=7_500, workers=0)
    assert [s["sha256"] for s in clean["shards"]] == [s["sha256"] for s in manifest["shards"]]


def test_a_directory_holding_another_atlas_is_refused(fourbars, tmp_path):
    with pytest.raises(AtlasBuildError, match="holds a different atlas"):
        build("fourbar", 30_000, fourbars, shard_size=10_000, seed=1, workers=0)
    with pytest.raises(AtlasBuildError, match="family"):
        build("sixbar", 10, tmp_path / "x")
    with pytest.raises(AtlasBuildError, match="count"):
        build("fourbar", 0, tmp_path / "y")
    with pytest.raises(AtlasError, match="no such atlas"):
        open_atlas(tmp_path / "missing")


# ------------------------------------------------------------------------------------------
# The index
# ------------------------------------------------------------------------------------------


def test_exact_search_is_brute_force():
    rng = np.random.default_rng(0)
    v = rng.normal(size=(3000, 8)).astype(np.float32)
    q = rng.normal(size=(5, 8)).astype(np.float32)
    d, i = exact_search(v, q, 7)
    brute = np.sum((q[:, None, :].astype(float) - v[None]) ** 2, axis=-1)
    np.testing.assert_array_equal(i, np.argsort(brute, axis=1, kind="stable")[:, :7])
    np.testing.assert_allclose(d, np.sort(brute, axis=1)[:, :7], rtol=1e-4)


def test_variants_merge_to_the_least_distance_per_entry():
    dist = np.array([[0.5, 0.9, 1.0], [0.2, 0.6, 0.7]])  # one query, two variants
    ids = np.array([[4, 8, 2], [8, 3, 4]])
    d, i = merge_variants(dist.reshape(2, 3), ids.reshape(2, 3), 2, 3)
    assert i.tolist() == [[8, 4, 3]] and d.tolist() == [[0.2, 0.5, 0.6]]


def test_the_ivf_index_is_tuned_to_its_recall(fourbars):
    pytest.importorskip("faiss")
    atlas = open_atlas(fourbars)
    vectors = atlas.descriptors()
    index = Index.build(vectors, kind="ivf")
    queries = vectors[::97][:100] + np.float32(0.01)
    recall = index.tune(vectors, queries, 1)
    assert recall >= 0.97
    truth = exact_search(vectors, queries, 10)[1]
    assert recall_at(index.search(queries, 1, 10)[1], truth) == pytest.approx(recall)


# ------------------------------------------------------------------------------------------
# Matching
# ------------------------------------------------------------------------------------------


def _random_fourbar_curve(rng: np.random.Generator, samples: int = 80):
    """A crank-driven four-bar's curve, placed anywhere: not an atlas entry."""
    while True:
        m = FourBar(
            A0=rng.normal(size=2) * 5,
            B0=rng.normal(size=2) * 5,
            crank=rng.uniform(0.5, 2.0),
            coupler=rng.uniform(2.0, 8.0),
            rocker=rng.uniform(2.0, 8.0),
            u=rng.uniform(-3.0, 4.0),
            v=rng.uniform(-3.0, 3.0),
            assembly=rng.choice([-1.0, 1.0]),
        )
        P = solve(m, np.linspace(0.0, 2.0 * np.pi, samples, endpoint=False), order=0)
        if P.valid.all():
            return m, P.positions["P"]


def test_query_refine_matches_a_random_fourbar_within_one_percent(fourbars, tmp_path):
    from linkwright.io import parse_document

    rng = np.random.default_rng(2026)
    for trial in range(3):
        _, P = _random_fourbar_curve(rng)
        path = tmp_path / f"curve{trial}.csv"
        np.savetxt(path, P, delimiter=",", header="x,y", comments="")
        out = tmp_path / f"match{trial}.json"
        with open(out, "w") as f:
            proc = subprocess.run(
                [sys.executable, "-m", "linkwright", "atlas", "query", str(fourbars),
                 "--points", str(path), "--top", "3", "--refine", "--json", "--quiet"],
                stdout=f, stderr=subprocess.PIPE, text=True,
            )  # fmt: skip
        assert proc.returncode == 0, proc.stderr
        best = json.loads(out.read_text())["matches"][0]
        size = np.sqrt(np.mean(np.sum((P - P.mean(0)) ** 2, axis=1)))
        assert best["error"] < 0.01
        # Independently: the document, read back and traced by the plan, passes within 1 % of
        # the curve's size of every query point, where the user drew it.
        mech = parse_document(best["mechanism"]).mechanism
        traced = solve(mech, np.linspace(0.0, 2.0 * np.pi, 2048, endpoint=False), order=0)
        assert traced.valid.all()
        assert _polyline_rms(P, traced.positions["P"]) < 0.01 * size


finite = dict(allow_nan=False, allow_infinity=False)


@settings(
    max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    entry=st.integers(0, 29_999),
    scale=st.floats(0.01, 100.0, **finite),
    angle=st.floats(-np.pi, np.pi, **finite),
    shift=st.floats(-50.0, 50.0, **finite),
    start=st.integers(0, 199),
    backwards=st.booleans(),
)
def test_an_entry_moved_anywhere_is_found_with_its_transform(
    fourbars, entry, scale, angle, shift, start, backwards
):
    atlas = open_atlas(fourbars)
    design = atlas.designs([entry])
    local = curves("fourbar", design, 200)[0]
    c, s = np.cos(angle), np.sin(angle)
    moved = scale * local @ np.array([[c, s], [-s, c]]) + np.array([shift, -shift / 2])
    moved = np.roll(moved[::-1] if backwards else moved, start, axis=0)
    best = query(atlas, moved, top=3)[0]
    size = scale * np.sqrt(np.mean(np.sum((local - local.mean(0)) ** 2, axis=1)))
    assert best.error < 2e-3
    assert best.distance < 2e-3 * size
    if best.atlas_id == entry:  # (a cognate or a near twin may rank first instead)
        assert best.scale == pytest.approx(scale, rel=1e-3)
        assert np.cos(best.rotation - angle) == pytest.approx(1.0, abs=1e-5)
        np.testing.assert_allclose(best.translation, [shift, -shift / 2], atol=2e-3 * size)
    # The placed linkage traces the query where it lies, by the plan.
    traced = solve(best.mechanism, np.linspace(0, 2 * np.pi, 1024, endpoint=False), order=0)
    assert _polyline_rms(moved, traced.positions["P"]) < 2e-3 * size


def test_bad_queries_name_the_problem(fourbars, tmp_path):
    atlas = open_atlas(fourbars)
    with pytest.raises(AtlasQueryError, match="shape"):
        query(atlas, np.zeros((10, 3)))
    with pytest.raises(AtlasQueryError, match="at least 3"):
        query(atlas, [[0, 0], [1, 1]])
    with pytest.raises(AtlasQueryError, match="same point"):
        query(atlas, np.ones((10, 2)))
    with pytest.raises(AtlasQueryError, match="finite"):
        query(atlas, [[0, 0], [1, 0], [np.nan, 1]])
    with pytest.raises(AtlasQueryError, match="top"):
        query(atlas, [[0, 0], [1, 0], [0, 1]], top=0)
    empty = tmp_path / "empty.csv"
    empty.write_text("x,y\n")
    assert main(["atlas", "query", str(fourbars), "--points", str(empty)]) == 2
    assert main(["atlas", "query", str(tmp_path), "--points", str(empty)]) == 2


def test_the_built_in_atlas_builds_on_first_use(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("LINKWRIGHT_DATA", str(tmp_path))
    atlas = default_atlas("fourbar")
    assert atlas.count == 100_000 and atlas.path.is_relative_to(tmp_path)
    assert default_atlas("fourbar").manifest == atlas.manifest  # opened, not rebuilt
    _, P = _random_fourbar_curve(np.random.default_rng(5))
    points = tmp_path / "curve.csv"
    np.savetxt(points, P, delimiter=",")
    assert main(["atlas", "query", "--points", str(points), "--top", "2"]) == 0
    text = capsys.readouterr().out
    assert "2 matches from 100000 fourbar curves" in text and "[mechanism]" in text
    assert main(["atlas", "info", str(atlas.path)]) == 0
    assert "recall@10" in capsys.readouterr().out


def test_a_spherical_curve_turned_anywhere_is_matched_and_refined(tmp_path):
    from linkwright.mechanisms import SphericalFourBar
    from linkwright.synthesis.path_families import sphere_rotation

    build("spherical-fourbar", 20_000, tmp_path / "sphere", workers=0)
    atlas = open_atlas(tmp_path / "sphere")
    rng = np.random.default_rng(9)
    while True:
        a = np.radians(rng.uniform(20.0, 160.0, 4))
        m = SphericalFourBar(frame=a[0], crank=a[1], coupler=a[2], rocker=a[3],
                             point_arc=0.6, point_angle=1.0, assembly=1)  # fmt: skip
        motion = solve(m, np.linspace(0.0, 2.0 * np.pi, 80, endpoint=False), order=0)
        if motion.valid.all():
            break
    R = sphere_rotation(np.array(2.0), np.array(0.3), np.array(-1.0))
    P = motion.positions["P"] @ R.T
    best = query(atlas, P, top=2, refine=True, budget=3.0)[0]
    centre = P.mean(axis=0) / np.linalg.norm(P.mean(axis=0))
    size = np.sqrt(np.mean(np.sum((P - centre) ** 2, axis=1)))
    traced = solve(best.mechanism, np.linspace(0, 2 * np.pi, 2048, endpoint=False), order=0)
    assert traced.valid.all()
    assert _polyline_rms(P, traced.positions["P"]) < 0.01 * size
    assert best.error < 0.01 and best.translation is None and best.scale == 1.0


def test_a_geared_fivebar_entry_moved_anywhere_is_found(tmp_path):
    build("geared-fivebar", 5_000, tmp_path / "five", workers=0)
    atlas = open_atlas(tmp_path / "five")
    design = atlas.designs([1234])
    local = curves("geared-fivebar", design, 300)[0]
    moved = 3.0 * local[:, ::-1] * [1, -1] + [10.0, 2.0]  # turned by −90°, scaled, moved
    best = query(atlas, moved, top=1)[0]
    size = 3.0 * np.sqrt(np.mean(np.sum((local - local.mean(0)) ** 2, axis=1)))
    assert best.error < 1e-3
    traced = solve(best.mechanism, np.linspace(0, 2 * np.pi, 2048, endpoint=False), order=0)
    assert _polyline_rms(moved, traced.positions["P"]) < 1e-3 * size
