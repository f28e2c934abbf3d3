"""Analyses return typed results in radians; :mod:`linkwright.io.report` alone turns them into
the degrees, JSON and words that ``linkwright analyze`` prints (issue 23, item 3)."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from linkwright.analysis import (
    FourBarAnalysis,
    GeneralAnalysis,
    analyze,
    dyad_transmission_angles,
)
from linkwright.cli import main
from linkwright.io import load_example
from linkwright.io.report import analysis_report, jsonable, table_lines
from linkwright.io.results import NotAssembled, curve_document, unassembled_reason
from linkwright.mechanisms import FourBar, GearedFiveBar, SphericalFourBar, circuit


def rocker_extremes(d: float, a: float, b: float, c: float) -> list[float]:
    """A crank-rocker's output angle from the frame line at its two toggle positions (crank and
    coupler stretched out, |A0 B| = b + a, or folded, |A0 B| = b − a), by the cosine rule in the
    triangle A0 B0 B, with B above the frame line."""
    return sorted(
        math.pi - math.acos((d * d + c * c - r * r) / (2 * d * c)) for r in (b + a, b - a)
    )


@pytest.mark.parametrize(("d", "a", "b", "c"), [(4, 1, 3.5, 3), (5, 1.5, 4, 3.5), (3, 0.5, 3, 2)])
def test_fourbar_analysis_is_radians_against_the_cosine_rule(d, a, b, c):
    found = analyze(FourBar(A0=[0, 0], B0=[d, 0], crank=a, coupler=b, rocker=c))
    assert isinstance(found, FourBarAnalysis) and found.kind == "crank-rocker"
    assert found.input_full and found.input_arcs == ()
    assert found.output_range == pytest.approx(rocker_extremes(d, a, b, c), abs=1e-9)
    report = analysis_report(found)
    assert report["swing_deg"] == pytest.approx(
        math.degrees(found.output_range[1] - found.output_range[0]), abs=1e-9
    )


def test_transmission_extremes_match_the_sampled_angle():
    mech = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=3.5, rocker=3)
    found = analyze(mech)
    sampled = dyad_transmission_angles(mech, circuit(mech, 20_000, order=0))["B"]
    assert found.transmission.min == pytest.approx(np.nanmin(sampled), abs=1e-6)
    assert found.transmission.max == pytest.approx(np.nanmax(sampled), abs=1e-6)
    # The report's pressure angle is 90° − γ, in degrees.
    pressure = analysis_report(found)["pressure_angle_deg"]
    assert pressure["max"] == pytest.approx(90 - math.degrees(found.transmission.min), abs=1e-9)


def _numbers(value):
    if dataclasses.is_dataclass(value):
        for f in dataclasses.fields(value):
            yield from _numbers(getattr(value, f.name))
    elif isinstance(value, dict):
        for v in value.values():
            yield from _numbers(v)
    elif isinstance(value, tuple | list):
        for v in value:
            yield from _numbers(v)
    elif isinstance(value, float):
        yield value


@pytest.mark.parametrize(
    "mech",
    [
        FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3),  # never assembles
        FourBar(A0=[0, 0], B0=[1, 0], crank=1, coupler=1, rocker=1),  # change point
        SphericalFourBar(*np.radians([10, 20, 30, 90])),  # never assembles
        GearedFiveBar(A0=[0, 0], B0=[1, 0], crank1=4, crank2=4, link1=3, link2=5, ratio=1),
    ],
)
def test_results_hold_no_nan(mech):
    found = analyze(mech)
    assert all(math.isfinite(x) for x in _numbers(found))
    json.dumps(jsonable(analysis_report(found)), allow_nan=False)


def test_a_linkage_that_never_assembles_says_why_and_has_no_numbers():
    found = analyze(FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3))
    assert (found.kind, found.assembles, found.transmission, found.output_range) == (
        None, False, None, None,
    )  # fmt: skip
    assert "the frame (10) is longer than the other three links together (6)" in found.reason


def test_general_analysis_is_typed_and_in_radians():
    doc = load_example("geared-fivebar")
    found = analyze(doc.mechanism)
    assert isinstance(found, GeneralAnalysis) and found.locking is not None
    report = analysis_report(found)
    for limit, shown in zip(found.limit_positions, report["limit_positions"], strict=True):
        assert shown["input_deg"] == pytest.approx(math.degrees(limit.input), abs=1e-9)
    assert report["locking"]["locking_positions_deg"] == [
        p["input_deg"] for p in report["limit_positions"]
    ]


@pytest.mark.parametrize(
    "name",
    ["crank-rocker", "offset-slider-crank", "paper000-fig6-crank-rocker", "geared-fivebar",
     "elliptic-trammel", "jansen-leg", "stephenson3-output"],
)  # fmt: skip
def test_the_cli_prints_the_report_modules_rendering(name, capsys):
    doc = load_example(name)
    expected = jsonable(analysis_report(analyze(doc.mechanism)))
    assert main(["analyze", name, "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == expected
    assert main(["analyze", name]) == 0
    assert capsys.readouterr().out.splitlines()[1:] == table_lines(expected)


def test_curve_document_raises_a_library_error_not_the_clis():
    far = FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3)
    doc = dataclasses.replace(load_example("crank-rocker"), mechanism=far)
    with pytest.raises(NotAssembled, match="cannot be assembled at any input"):
        curve_document(doc, 36)
    assert unassembled_reason(far, 0.0).startswith("cannot be assembled at this input: ")
