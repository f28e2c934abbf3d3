"""Function generation over many pairs and over a range (issue 28, item 4).

Checked against what is computed here, not by the fit: pairs traced from a known four-bar come
back as that four-bar; a least-squares fit is no worse at its pairs than the three-point
Chebyshev design nor than its own neighbours (a local minimum, measured by the engine); and the
structural error `synth function` prints is recomputed from its document by a circle-circle
intersection written here.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from synth_helpers import run_cli

from linkwright.mechanisms import solve
from linkwright.synthesis.precision import (
    PrecisionError,
    freudenstein,
    freudenstein_fit,
    function_pairs,
)


def _output_angle(a, b, c, d, theta, assembly):
    """ψ of B − B0 for crank a at θ (A0 at the origin, B0 at (d, 0)): circle(A, b) ∩ circle(B0,
    c), the intersection on the side sign((B0 − A) × (B − A)) = assembly."""
    A = np.stack((a * np.cos(theta), a * np.sin(theta)), axis=-1)
    B0 = np.array([d, 0.0])
    gap = B0 - A
    dist = np.linalg.norm(gap, axis=-1)
    along = (b * b - c * c + dist * dist) / (2 * dist)
    across = np.sqrt(np.maximum(b * b - along * along, 0.0))
    unit = gap / dist[..., None]
    normal = np.stack((-unit[..., 1], unit[..., 0]), axis=-1)
    out = []
    for side in (1.0, -1.0):
        B = A + along[..., None] * unit + side * across[..., None] * normal
        cross = gap[..., 0] * (B - A)[..., 1] - gap[..., 1] * (B - A)[..., 0]
        out.append((np.sign(cross), B))
    B = np.where((out[0][0] == assembly)[..., None], out[0][1], out[1][1])
    return np.arctan2(B[..., 1], B[..., 0] - d)


@settings(max_examples=25, deadline=None)
@given(
    st.floats(0.3, 0.9),  # crank
    st.floats(2.0, 3.0),  # coupler
    st.floats(2.0, 3.0),  # rocker
    st.sampled_from([1.0, -1.0]),
    st.integers(4, 12),
    st.floats(-math.pi, math.pi),
)
def test_pairs_of_a_known_four_bar_give_it_back(a, b, c, assembly, n, first):
    d = 2.5  # a crank-rocker: the crank is the shortest and s + l < p + q
    phi = first + np.linspace(0.0, 1.5 * math.pi, n)
    psi = _output_angle(a, b, c, d, phi, assembly)
    fit = freudenstein_fit(phi, psi, frame=d)
    got = np.array([float(fit.mechanism.crank), float(fit.mechanism.coupler),
                    float(fit.mechanism.rocker)])  # fmt: skip
    np.testing.assert_allclose(got, [a, b, c], rtol=1e-8)
    assert float(fit.error.max()) < 1e-8


def _sum_of_squares(a, b, c, d, assembly, inputs, outputs):
    found = _output_angle(a, b, c, d, inputs, assembly)
    return float(np.sum(np.angle(np.exp(1j * (found - outputs))) ** 2))


def test_least_squares_beats_the_chebyshev_design_and_its_own_neighbours():
    x = np.linspace(1.0, 2.0, 11)
    phi = np.radians(30 + 90 * (x - 1))
    psi = np.radians(60 + 90 * np.log10(x) / np.log10(2))
    fit = freudenstein_fit(phi, psi)
    m = fit.mechanism
    a, b, c, asm = (float(v) for v in (m.crank, m.coupler, m.rocker, m.assembly))
    inputs, outputs = fit.inputs, fit.outputs
    own = _sum_of_squares(a, b, c, 1.0, asm, inputs, outputs)
    assert own == pytest.approx(float(np.sum(fit.error**2)), rel=1e-9)
    rng = ((1, 2), np.radians([30, 120]), np.radians([60, 150]))
    three = freudenstein(*function_pairs(np.log10, *rng)[1:]).mechanism
    assert own < _sum_of_squares(
        float(three.crank), float(three.coupler), float(three.rocker), 1.0,
        float(three.assembly), inputs, outputs,
    )  # fmt: skip
    steps = np.random.default_rng(3).normal(size=(40, 3)) * 1e-4
    for s in steps:
        assert own <= _sum_of_squares(a * (1 + s[0]), b * (1 + s[1]), c * (1 + s[2]), 1.0,
                                      asm, inputs, outputs) * (1 + 1e-9)  # fmt: skip


def test_too_few_pairs_are_refused():
    with pytest.raises(PrecisionError, match="n ≥ 3"):
        freudenstein_fit([0.1, 0.2], [0.3, 0.4])


@pytest.mark.parametrize(
    ("points", "spacing"), [(3, "chebyshev"), (9, "even"), (5, "1,1.2,1.5,1.8,2")]
)
def test_synth_function_over_a_range_prints_its_structural_error(points, spacing):
    code, out, err = run_cli(
        "synth", "function", "--function", "log10(x)", "--x-range", "1:2", "--phi-range",
        "30:120", "--psi-range", "60:150", "--points", str(points), "--spacing", spacing,
        "--json",
    )  # fmt: skip
    assert code == 0, err
    report = json.loads(out)
    body = report["mechanism"]["mechanism"]
    a, b, c = body["crank"], body["coupler"], body["rocker"]
    d = body["B0"][0]
    x = np.array(report["structural_error"]["x"])
    # The linear maps of the range: x → φ, y → ψ; the document's crank and rocker pins sit at
    # φ and ψ, or opposite them (offsets of 0 or π, read from the first pair).
    first = report["precision_x"][0]
    phi_first = math.radians(30 + 90 * (first - 1))
    psi_first = math.radians(60 + 90 * math.log10(first) / math.log10(2))
    crank_offset = math.radians(report["inputs_deg"][0]) - phi_first
    rocker_offset = math.radians(report["outputs_deg"][0]) - psi_first
    psi_out = _output_angle(a, b, c, d, np.radians(30 + 90 * (x - 1)) + crank_offset,
                            body["assembly"])  # fmt: skip
    psi = np.angle(np.exp(1j * (psi_out - rocker_offset - math.radians(60)))) + math.radians(60)
    generated = (psi - math.radians(60)) / math.radians(90) * math.log10(2)
    expected = generated - np.log10(x)
    np.testing.assert_allclose(report["structural_error"]["error"], expected, atol=1e-9)
    assert report["structural_error"]["largest"] == pytest.approx(np.max(np.abs(expected)))
    assert report["method"] == ("exact" if points == 3 else "least squares")
    # The printed document traces the design: the engine agrees at the first pair.
    from linkwright.io import parse_document

    mech = parse_document(report["mechanism"]).mechanism
    assert solve(mech, np.radians(report["inputs_deg"][:1]), order=0).valid.all()


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--function", "x**2"], "give --pairs, or --function with"),
        (["--pairs", "10,20;30,40"], "give 3 to 1000 pairs"),
        (
            [
                "--function",
                "exp(y)",
                "--x-range",
                "0:1",
                "--phi-range",
                "0:90",
                "--psi-range",
                "0:90",
            ],
            "unknown name 'y'",
        ),
        (
            ["--function", "x", "--x-range", "1:1", "--phi-range", "0:90", "--psi-range", "0:90"],
            "the range 1:1 is empty",
        ),
        (
            [
                "--function",
                "x",
                "--x-range",
                "0:1",
                "--phi-range",
                "0:90",
                "--psi-range",
                "0:90",
                "--spacing",
                "0,0.5,2",
            ],
            "every x must lie in the range",
        ),
    ],
)
def test_bad_function_requests_are_one_line(args, words):
    code, out, err = run_cli("synth", "function", *args)
    assert code != 0 and out == ""
    assert err.count("\n") == 1 and words in err, err
