"""`linkwright plot`, `animate` and `export`: files written where asked, paths printed, clear
errors for bad requests; one reference picture per family compared tolerantly.

The pictures themselves are tested in test_plot_view.py, test_plot_diagrams.py, test_animate.py
and test_export.py; here the commands are driven as a user drives them.
"""

from __future__ import annotations

import os
from pathlib import Path

import ezdxf
import numpy as np
import pytest
from family_examples import FAMILY_EXAMPLES
from matplotlib.testing.compare import compare_images
from PIL import Image

from linkwright.cli import main
from linkwright.io import load_example
from linkwright.mechanisms import solve
from linkwright.plot import save_figure
from linkwright.plot.view import plot_mechanism

GALLERY = Path(__file__).resolve().parents[1] / "docs" / "img" / "gallery"
GALLERY_DPI = 60
GALLERY_SAMPLES = 360
# RMS difference (0-255 grey levels) tolerated: fonts and anti-aliasing vary a little between
# FreeType builds; a moved curve, a missing marker or a changed layout does not pass.
GALLERY_TOLERANCE = 6.0


def run(capsys, *args: str) -> tuple[int, str, str]:
    status = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return status, out, err


def render_gallery_picture(family: str, path: Path) -> Path:
    doc = load_example(FAMILY_EXAMPLES[family])
    figure = plot_mechanism(doc.mechanism, samples=GALLERY_SAMPLES, title=doc.title)
    figure.set_dpi(GALLERY_DPI)
    return save_figure(figure, path, dpi=GALLERY_DPI)


@pytest.mark.parametrize("family", list(FAMILY_EXAMPLES))
def test_each_family_matches_its_reference_picture(family, tmp_path):
    reference = GALLERY / f"{family}.png"
    if os.environ.get("LINKWRIGHT_UPDATE_GALLERY"):
        GALLERY.mkdir(parents=True, exist_ok=True)
        render_gallery_picture(family, reference)
    actual = render_gallery_picture(family, tmp_path / f"{family}.png")
    assert reference.exists(), f"no reference picture {reference}"
    failed = compare_images(str(reference), str(actual), tol=GALLERY_TOLERANCE, in_decorator=True)
    assert failed is None, failed


def test_plot_writes_the_default_name_and_prints_it(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    status, out, err = run(capsys, "plot", "crank-rocker", "--samples", "120")
    assert status == 0, err
    assert out == "wrote crank-rocker.png\n"
    with Image.open(tmp_path / "crank-rocker.png") as image:
        assert image.format == "PNG" and min(image.size) > 300
    status, out, err = run(capsys, "plot", "crank-rocker", "--kind", "coefficients")
    assert status == 0, err
    assert out == "wrote crank-rocker-coefficients.png\n"


@pytest.mark.parametrize("kind", ["angles", "velocity", "acceleration", "coefficients"])
def test_plot_diagram_kinds_write_svg(capsys, tmp_path, kind):
    out = tmp_path / f"{kind}.svg"
    status, _, err = run(capsys, "plot", "paper000-fig6-crank-rocker", "--kind", kind,
                         "--samples", "90", "--out", out)  # fmt: skip
    assert status == 0, err
    assert out.read_text().lstrip().startswith("<?xml")


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--kind", "speed"], "--kind: expected one of"),
        (["--out", "x.jpg"], "--out: pictures are written as .png, .svg, .pdf"),
        (["--kind", "angles", "--at", "10"], "--at: only the linkage picture"),
        (["--at", "nan"], "--at: must be a finite angle"),
    ],
)
def test_plot_refuses_bad_requests_in_one_line(capsys, tmp_path, args, message):
    status, out, err = run(capsys, "plot", "crank-rocker", *args)
    assert status == 2 and out == ""
    assert message in err and "Traceback" not in err and err.count("\n") == 1


def test_plot_at_an_input_the_linkage_cannot_reach_names_the_range(capsys, tmp_path):
    status, _, err = run(capsys, "plot", "rocker-input", "--at", "180", "--out",
                         tmp_path / "x.png")  # fmt: skip
    assert status == 2 and "rocker-input" in err and "°" in err
    assert not (tmp_path / "x.png").exists()


def test_animate_writes_a_looping_gif_and_prints_its_path(capsys, tmp_path):
    out = tmp_path / "cycle.gif"
    status, printed, err = run(capsys, "animate", "crank-rocker", "--out", out, "--frames", "6",
                               "--dpi", "40", "--quiet")  # fmt: skip
    assert status == 0, err
    assert printed == f"wrote {out}\n" and err == ""
    with Image.open(out) as gif:
        assert gif.n_frames == 6 and gif.info.get("loop") == 0


def test_animate_refuses_other_formats(capsys, tmp_path):
    status, _, err = run(capsys, "animate", "crank-rocker", "--out", tmp_path / "x.avi")
    assert status == 2 and "--out: animations are written as .gif, .mp4" in err


def test_export_writes_csv_svg_and_an_audited_dxf(capsys, tmp_path):
    for suffix in ("csv", "svg", "dxf"):
        out = tmp_path / f"crank-rocker.{suffix}"
        status, printed, err = run(capsys, "export", "crank-rocker", "--out", out, "--at", "30")
        assert status == 0, err
        assert printed == f"wrote {out}\n"
    table = np.loadtxt(tmp_path / "crank-rocker.csv", delimiter=",", skiprows=1)
    header = (tmp_path / "crank-rocker.csv").read_text().splitlines()[0].split(",")
    doc = load_example("crank-rocker")
    theta = np.radians(table[:, header.index(next(h for h in header if "deg" in h))])
    again = solve(doc.mechanism, theta, order=0).positions["P"]
    px, py = header.index("P_x"), header.index("P_y")
    np.testing.assert_allclose(table[:, [px, py]], again, atol=1e-12)
    drawing = ezdxf.readfile(tmp_path / "crank-rocker.dxf")
    auditor = drawing.audit()
    assert not auditor.has_errors and not auditor.has_fixes


def test_export_refuses_other_formats(capsys, tmp_path):
    status, _, err = run(capsys, "export", "crank-rocker", "--out", tmp_path / "x.step")
    assert status == 2 and "--out: exports are written as .csv, .svg, .dxf" in err
