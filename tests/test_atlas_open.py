"""Matching an open curve, a piece of a coupler curve, against the atlas (issue 28, item 5).

A piece of an entry's own curve, moved anywhere by a similarity and run either way, must be
found: the best match's placed linkage, solved by the engine, passes the piece's points (RMS
distance to its densely subdivided curve, measured here). The screen's correlations are
checked against a direct computation of the same residual.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st
from synth_helpers import run_cli

from linkwright.atlas import AtlasQueryError, build, open_atlas, query
from linkwright.atlas.families import curves
from linkwright.atlas.partial import (
    _nuclear_traces,
    fit_sphere_pieces,
    kabsch,
    resampled,
    screen_pieces,
    screen_sphere_pieces,
)
from linkwright.engine import cost
from linkwright.mechanisms import solve

finite = {"allow_nan": False, "allow_infinity": False}
# A query screens the whole atlas: two pieces a run, the same two every run.
PIECES = settings(
    max_examples=2,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
    phases=[Phase.explicit, Phase.generate],
)


@pytest.fixture(scope="module")
def fourbars(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("atlas") / "fourbar"
    build("fourbar", 10_000, out, shard_size=10_000, workers=0)
    return out


def _polyline_rms(points: np.ndarray, curve: np.ndarray) -> float:
    """RMS distance from points to a closed polyline, by dense subdivision of its segments."""
    a, b = curve, np.roll(curve, -1, axis=0)
    t = np.linspace(0.0, 1.0, 50, endpoint=False)
    dense = (a[:, None, :] + t[None, :, None] * (b - a)[:, None, :]).reshape(-1, 2)
    d2 = np.min(np.sum((points[:, None, :] - dense[None]) ** 2, axis=-1), axis=1)
    return float(np.sqrt(np.mean(d2)))


def _piece(atlas, entry, scale, angle, shift, start, share, backwards):
    local = curves("fourbar", atlas.designs([entry]), 400)[0]
    c, s = np.cos(angle), np.sin(angle)
    moved = scale * local @ np.array([[c, s], [-s, c]]) + np.array([shift, -shift / 2])
    piece = np.roll(moved, -start, axis=0)[: int(share * 400)]
    piece = piece[::-1] if backwards else piece
    return piece, float(np.sqrt(np.mean(np.sum((piece - piece.mean(0)) ** 2, axis=1))))


@PIECES
@given(
    entry=st.integers(0, 9_999),
    scale=st.floats(0.01, 100.0, **finite),
    angle=st.floats(-np.pi, np.pi, **finite),
    shift=st.floats(-50.0, 50.0, **finite),
    start=st.integers(0, 399),
    share=st.floats(0.2, 0.8),
    backwards=st.booleans(),
)
def test_a_piece_of_an_entry_moved_anywhere_is_matched_truthfully(fourbars, **case):
    # A short piece is ambiguous (many curves pass near a third of one), so the entry itself
    # need not come first; measured on 20 random pieces, 17 matches passed within 0.1 % of the
    # piece's size and the worst within 3.7 %. What must always hold: the distance reported is
    # the distance from the piece to the placed linkage's curve, traced by the engine.
    atlas = open_atlas(fourbars)
    piece, size = _piece(atlas, **case)
    _assert_truthful(query(atlas, piece, top=3, open_curve=True)[0], piece, size, _polyline_rms)


def _assert_truthful(best, piece, size, polyline_rms) -> None:
    """The distance a match reports is the one from the piece to the placed linkage's curve,
    traced by the engine, and it is a close match."""
    traced = solve(best.mechanism, np.linspace(0, 2 * np.pi, 4096, endpoint=False), order=0)
    measured = polyline_rms(piece, traced.positions["P"])
    assert best.distance == pytest.approx(measured, abs=1e-3 * size)
    assert measured < 0.05 * size
    assert best.error == pytest.approx(best.distance / size)


def test_a_piece_of_an_entry_finds_it(fourbars):
    atlas = open_atlas(fourbars)
    piece, size = _piece(atlas, 9127, 60.7, 1.1, -12.0, 57, 0.69, True)
    best = query(atlas, piece, top=3, open_curve=True)[0]
    traced = solve(best.mechanism, np.linspace(0, 2 * np.pi, 4096, endpoint=False), order=0)
    assert _polyline_rms(piece, traced.positions["P"]) < 1e-4 * size


def test_the_screen_is_the_similarity_residual_at_every_start():
    rng = np.random.default_rng(2)
    curve = rng.normal(size=(1, 64, 2)).cumsum(axis=1)
    query_points = rng.normal(size=(32, 2))
    score = screen_pieces(curve, query_points)[0]
    # Directly: every arc share, start and direction, the least-squares similarity residual.
    c = curve[0, :, 0] + 1j * curve[0, :, 1]
    best = np.inf
    for b in (query_points, query_points[::-1]):
        z = b[:, 0] + 1j * b[:, 1]
        zc = z - z.mean()
        for share in (0.125, 0.1875, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875, 1.0):
            length = max(round(share * 64), 8, 2)
            index = np.round(np.linspace(0.0, length - (share == 1.0), 32)).astype(int)
            for s0 in range(64):
                a = c[(s0 + index) % 64]
                ac = a - a.mean()
                rel = 1 - abs(np.vdot(ac, zc)) ** 2 / (np.vdot(zc, zc).real * np.vdot(ac, ac).real)
                best = min(best, rel)
    assert score[0] == pytest.approx(best, abs=1e-9)


def test_open_queries_are_bounded(fourbars, monkeypatch):
    atlas = open_atlas(fourbars)
    piece = resampled(curves("fourbar", atlas.designs([3]), 200)[0][:80], 40)
    monkeypatch.setattr(cost, "OPEN_SCREEN", replace(cost.OPEN_SCREEN, value=5_000))
    with pytest.raises(AtlasQueryError, match="screened against every entry"):
        query(atlas, piece, open_curve=True)


def test_atlas_query_open_on_the_command_line(fourbars, tmp_path):
    atlas = open_atlas(fourbars)
    piece = curves("fourbar", atlas.designs([17]), 300)[0][20:140]
    table = tmp_path / "piece.csv"
    np.savetxt(table, piece, delimiter=",")
    code, out, err = run_cli("atlas", "query", str(fourbars), "--points", str(table), "--open",
                          "--top", "2", "--json", "--quiet")  # fmt: skip
    assert code == 0, err
    result = json.loads(out)
    assert len(result["matches"]) == 2
    size = float(np.sqrt(np.mean(np.sum((piece - piece.mean(0)) ** 2, axis=1))))
    assert result["matches"][0]["distance"] < 2e-3 * size


# -- on the sphere ---------------------------------------------------------------------------


@pytest.fixture(scope="module")
def spherical(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("atlas") / "spherical"
    build("spherical-fourbar", 1_000, out, shard_size=1_000, workers=0)
    return out


def _rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    k = axis / np.linalg.norm(axis)
    cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * cross + (1 - np.cos(angle)) * cross @ cross


def _sphere_polyline_rms(points: np.ndarray, curve: np.ndarray) -> float:
    """RMS chord distance from points to a closed polyline of unit vectors, by dense
    subdivision of its segments (then back onto the sphere)."""
    a, b = curve, np.roll(curve, -1, axis=0)
    t = np.linspace(0.0, 1.0, 50, endpoint=False)
    dense = (a[:, None, :] + t[None, :, None] * (b - a)[:, None, :]).reshape(-1, 3)
    dense /= np.linalg.norm(dense, axis=1, keepdims=True)
    d2 = np.min(np.sum((points[:, None, :] - dense[None]) ** 2, axis=-1), axis=1)
    return float(np.sqrt(np.mean(d2)))


@PIECES
@given(
    entry=st.integers(0, 999),
    axis=st.tuples(*[st.floats(-1.0, 1.0, **finite)] * 3).filter(lambda v: np.linalg.norm(v) > 0.1),
    angle=st.floats(-np.pi, np.pi, **finite),
    start=st.integers(0, 399),
    share=st.floats(0.3, 0.8),
    backwards=st.booleans(),
)
def test_a_piece_of_a_spherical_entry_turned_anywhere_is_matched_truthfully(
    spherical, entry, axis, angle, start, share, backwards
):
    atlas = open_atlas(spherical)
    piece, size = _sphere_piece(atlas, entry, np.array(axis), angle, start, share, backwards)
    best = query(atlas, piece, top=3, open_curve=True, refine=False)[0]
    _assert_truthful(best, piece, size, _sphere_polyline_rms)


def _sphere_piece(atlas, entry, axis, angle, start, share, backwards):
    """A piece of an entry's curve turned about the centre, and its size (RMS chord from its
    mean direction)."""
    local = curves("spherical-fourbar", atlas.designs([entry]), 400)[0]
    piece = np.roll(local @ _rotation(axis, angle).T, -start, axis=0)[: int(share * 400)]
    piece = piece[::-1] if backwards else piece
    centre = piece.mean(0) / np.linalg.norm(piece.mean(0))
    return piece, float(np.sqrt(np.mean(np.sum((piece - centre) ** 2, axis=1))))


def test_a_piece_of_a_spherical_entry_finds_it(spherical):
    atlas = open_atlas(spherical)
    piece, size = _sphere_piece(atlas, 419, np.array([0.3, -0.8, 0.5]), 2.1, 40, 0.55, False)
    best = query(atlas, piece, top=3, open_curve=True, refine=False)[0]
    assert best.atlas_id == 419
    traced = solve(best.mechanism, np.linspace(0, 2 * np.pi, 4096, endpoint=False), order=0)
    assert _sphere_polyline_rms(piece, traced.positions["P"]) < 1e-2 * size


@given(st.integers(0, 2**32 - 1))
@settings(max_examples=20, deadline=None)
def test_the_closed_form_singular_values_and_kabsch(seed):
    rng = np.random.default_rng(seed)
    # Near-singular matrices too: rank 1 and 2, where the cubic's roots meet.
    h = rng.normal(size=(3, 3, 3))
    h[1] = np.outer(rng.normal(size=3), rng.normal(size=3))
    h[2][2] = h[2][0] + h[2][1]
    s = np.linalg.svd(h, compute_uv=False)
    expected = s[:, 0] + s[:, 1] + np.sign(np.linalg.det(h)) * s[:, 2]
    np.testing.assert_allclose(_nuclear_traces(h), expected, atol=1e-6 * np.max(s))
    # Kabsch lays a turned point set back exactly, with a proper rotation.
    p = rng.normal(size=(7, 3))
    turn = _rotation(rng.normal(size=3), rng.uniform(-np.pi, np.pi))
    found = kabsch(p, p @ turn.T)
    np.testing.assert_allclose(found, turn, atol=1e-10)
    assert np.linalg.det(found) == pytest.approx(1.0)


def test_the_sphere_screen_is_the_rotation_residual_at_every_start():
    rng = np.random.default_rng(5)
    curve = rng.normal(size=(1, 64, 3))
    curve /= np.linalg.norm(curve, axis=-1, keepdims=True)
    query_points = rng.normal(size=(16, 3))
    query_points /= np.linalg.norm(query_points, axis=-1, keepdims=True)
    score, turn = screen_sphere_pieces(curve, query_points)
    # Directly: every arc share, start and direction, the best rotation's mean squared chord.
    best = np.inf
    for b in (query_points, query_points[::-1]):
        for share in (0.125, 0.1875, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875, 1.0):
            length = max(round(share * 64), 4, 2)
            index = np.round(np.linspace(0.0, length - (share == 1.0), 16)).astype(int)
            for s0 in range(64):
                a = curve[0, (s0 + index) % 64]
                r = kabsch(a, b)
                best = min(best, float(np.mean(np.sum((a @ r.T - b) ** 2, axis=1))))
    assert score[0] == pytest.approx(best, abs=1e-9)
    # The fit from the screen's rotation only improves on it.
    _, rms = fit_sphere_pieces(curve, query_points, turn)
    assert rms[0] ** 2 <= score[0] + 1e-12
