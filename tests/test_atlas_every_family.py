"""`atlas build` for every registered family (issue 21, item 5): a tiny atlas of each, checked
independently of the sampler.

Each stored design is rebuilt as a mechanism and traced by :func:`linkwright.mechanisms.circuits`
(the plan-based circuit tracer: exact limit positions for dyads, continuation through a triad's
poses), not by the atlas's own sampling code: the design's input must turn fully (for dyads:
no limit position among the exact roots, and the atlas's curve is the circuit's, sample for
sample, to 1e-9 of its size; with a triad: one of its circuits turns fully and carries the
atlas's curve, to 1e-5 of its size, the chord error of 4,000 samples). A curve traced by
`linkwright curve` from an entry's document is then matched back to that entry by `atlas query`.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from synth_helpers import polyline_distance, run_cli

from linkwright.atlas import open_atlas
from linkwright.atlas.families import CODE, atlas_model, curves
from linkwright.io.documents import load_example, mechanism_to_dict, save_document
from linkwright.mechanisms import circuit, circuits, input_range

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "linkwright" / "examples"

# (family, template example or None, count): a composed linkage needs its template; a
# Stephenson III driven at its output and paper 001 at FG take theirs (a triad: fewer, dearer).
CASES = [
    ("slidercrank", None, 24),
    ("doubleslider", None, 24),
    ("watt1", None, 24),
    ("watt2", None, 24),
    ("stephenson1", None, 24),
    ("stephenson3", None, 24),
    ("stephenson3", "stephenson3-output", 2),
    ("linkage", "jansen-leg", 24),
    ("linkage", "paper000-fig6-linkage", 24),
    ("spherical-sixbar", None, 24),
    ("spherical-stephenson3", None, 24),
    ("spherical-stephenson3", "paper001-fg", 2),
]


@pytest.mark.parametrize(("family", "example", "count"), CASES)
def test_a_tiny_atlas_of_every_family(tmp_path, family, example, count):
    out = tmp_path / "atlas"
    args = ["atlas", "build", "--family", family, "--count", str(count), "--out", str(out),
            "--workers", "0", "--samples", "32", "--shard-size", str(count // 2), "--quiet",
            "--json"]  # fmt: skip
    template = None
    if example is not None:
        args += ["--template", str(EXAMPLES / f"{example}.toml")]
        template = load_example(example).mechanism
    code, text, err = run_cli(*args)
    assert code == 0, err
    manifest = json.loads(text)
    assert manifest["spec"]["family"] == family and len(manifest["shards"]) == 2
    assert manifest["params"][-1] == CODE
    assert run_cli("atlas", "info", str(out), "--quick")[0] == 0

    atlas = open_atlas(out)
    designs = atlas.designs(np.arange(count))
    model = atlas_model(family, atlas.spec.mechanism)
    traced = curves(family, designs, 32, atlas.spec.mechanism)
    shape = {k: v for k, v in designs.items() if k != CODE}
    for i in range(count):
        mech = model.local({k: v[i] for k, v in shape.items()}, designs[CODE][i])
        points = traced[i]
        size = float(np.max(np.linalg.norm(points - points.mean(axis=0), axis=-1)))
        if not mech.plan.triads:
            # No limit position at all (exact roots), and the curve is the circuit's, sample
            # for sample: a full turn is traced from the input 0 in even steps.
            assert bool(input_range(mech).full)
            whole = circuit(mech, 32 * 64, order=0).positions[mech.traced_joint]
            np.testing.assert_allclose(whole[::64], points, atol=1e-9 * size)
            continue
        # A triad's configuration: one of its circuits (continuation) turns fully and carries
        # the curve (to the chord error of 4,000 samples).
        gaps = []
        for motion in circuits(mech, 4000, order=0)[1]:
            inputs = motion.input
            if np.all(np.diff(inputs) > 0) and inputs[-1] - inputs[0] > 2 * np.pi * 0.99:
                curve = motion.positions[mech.traced_joint]
                gaps.append(float(np.max(polyline_distance(points, curve))))
        assert gaps and min(gaps) <= 1e-5 * size, (i, gaps)
    if template is not None and template.family == "linkage":
        # Its structure is the template's: same joints, same traced joint.
        assert [j.name for j in mech.joints] == [j.name for j in template.joints]
        assert mech.traced == template.traced

    # An entry's own curve, traced by `linkwright curve` from its document, comes back first.
    if not mech.plan.triads:
        entry = 5
        doc = tmp_path / "entry.toml"
        one = model.local({k: v[entry] for k, v in shape.items()}, designs[CODE][entry])
        save_document(mechanism_to_dict(one), doc)
        code, text, err = run_cli("curve", str(doc), "--csv", "-n", "200")
        assert code == 0, err
        rows = [line.split(",")[1:-1] for line in text.splitlines()[1:]]
        csv = tmp_path / "curve.csv"
        csv.write_text("\n".join(",".join(r) for r in rows) + "\n")
        code, text, err = run_cli("atlas", "query", str(out), "--points", str(csv), "--top", "1",
                               "--json")  # fmt: skip
        assert code == 0, err
        best = json.loads(text)["matches"][0]
        assert best["atlas_id"] == entry or best["error"] < 1e-3


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--family", "linkage"], "give --template FILE"),
        (["--family", "watt3"], "--family: must be one of"),
        (["--family", "fourbar", "--template", str(EXAMPLES / "crank-rocker.toml")],
         "has its own design distribution"),
        (["--family", "watt1", "--template", str(EXAMPLES / "watt2-example.toml")],
         "template: a watt2 mechanism, not a watt1"),
        ([], "give a family, or a --template"),
    ],
)  # fmt: skip
def test_bad_builds_are_one_line(tmp_path, args, words):
    code, out, err = run_cli(
        "atlas", "build", "--count", "10", "--out", str(tmp_path / "a"), "--quiet", *args
    )
    assert code == 2 and out == ""
    assert words in err and err.count("\n") == 1, err


def test_a_family_that_rarely_turns_fully_is_refused_in_bounded_time(tmp_path):
    """A composed linkage about a template that never turns fully yields no design: the build
    stops after its rounds and says so, rather than drawing for ever."""
    far = tmp_path / "far.toml"
    doc = load_example("jansen-leg").raw
    doc = json.loads(json.dumps(doc))
    doc["mechanism"]["joints"][2]["length"] = 400.0  # a crank many times the links it drives
    far.write_text(json.dumps(doc))
    far = far.rename(far.with_suffix(".json"))
    code, _, err = run_cli(
        "atlas", "build", "--family", "linkage", "--template", str(far), "--count", "5",
        "--out", str(tmp_path / "a"), "--workers", "0", "--quiet",
    )  # fmt: skip
    assert code == 2 and "turn fully" in err and err.count("\n") == 1, err
