"""The one public namespace (issue 23 items 1, 5): ``import linkwright as lw``, ``ax=`` on the plot
verbs, and the pictures mechanisms and motions show in Jupyter."""

from __future__ import annotations

import inspect
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import linkwright as lw
from linkwright.mechanisms import registry
from linkwright.plot import AxesError, new_figure

CRANK_ROCKER = dict(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5, u=2, v=1)
NEVER = dict(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3)


def test_every_name_in_all_resolves_and_all_is_the_lazy_table() -> None:
    for name in lw.__all__:
        assert getattr(lw, name) is not None, name
    assert set(lw.__all__) == {"__version__", "atlas", *lw._WHERE}
    assert len(lw.__all__) == len(set(lw.__all__))
    assert set(lw.__all__) <= set(dir(lw))
    with pytest.raises(AttributeError, match="no attribute 'nonsense'"):
        lw.nonsense  # noqa: B018


def test_every_registered_family_is_in_the_namespace_under_its_class_name() -> None:
    for fam in registry.families():
        assert getattr(lw, fam.cls.__name__) is fam.cls, fam.name


def test_one_name_for_one_idea() -> None:
    # The near-synonyms of issue 23: one public name each; the old ones stay out of lw.
    for old in ("input_arcs", "input_limits", "Trammel", "solve_all", "plot_curves"):
        assert old not in lw.__all__
    assert lw.input_range is lw.mechanisms.input_range
    # The ellipse's trammel has one public name; the engine's Trammel is a plan step.
    assert "EllipseTrammel" in lw.synthesis.__all__ and "Trammel" not in lw.synthesis.__all__


def test_import_linkwright_loads_nothing_heavy() -> None:
    code = (
        "import sys, linkwright; "
        "print(sorted(m for m in ('numpy', 'scipy', 'matplotlib', 'fastapi', 'faiss') "
        "if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def _public_callables() -> list[tuple[str, object]]:
    found = []
    for name in lw.__all__:
        value = getattr(lw, name)
        if not callable(value) or inspect.ismodule(value):
            continue
        if inspect.isclass(value) and issubclass(value, BaseException):
            continue  # an error's docstring says when it is raised; it is not a verb
        found.append((name, value))
    return found


# Ids from the names alone: an object's repr holds its address, which differs between the
# xdist workers, and they must collect the same tests.
@pytest.mark.parametrize(
    "name, value", _public_callables(), ids=[name for name, _ in _public_callables()]
)
def test_every_public_callable_has_a_numpydoc_docstring_with_examples(
    name: str, value: object
) -> None:
    doc = inspect.getdoc(value) or ""
    assert ">>>" in doc and "Examples\n--------" in doc, f"{name}: no Examples section"
    if inspect.isfunction(value):
        for section in ("Parameters\n----------", "Returns\n-------"):
            assert section in doc, f"{name}: no {section.splitlines()[0]} section"


def test_plot_mechanism_draws_into_the_given_axes() -> None:
    fig = new_figure((9, 4))
    left, right = fig.subplots(1, 2)
    mech = lw.FourBar(**CRANK_ROCKER)
    assert lw.plot_mechanism(mech, samples=90, ax=right) is fig
    assert len(fig.axes) == 2 and not left.lines
    # The path of A drawn there lies on the crank's circle (closed form: |A − A0| = crank).
    path = next(ln for ln in right.lines if ln.get_label().startswith("paths of A"))
    assert np.allclose(np.hypot(*path.get_xydata().T), 1.0, atol=1e-12)


def test_plot_diagram_draws_into_one_axes_per_panel() -> None:
    mech = lw.FourBar(**CRANK_ROCKER)
    fig = new_figure((6, 8))
    axes = fig.subplots(3, 1)
    assert lw.plot_diagram(mech, "coefficients", samples=90, ax=axes) is fig
    assert [a.get_lines()[0].get_label() for a in axes] == ["Kω", "Kε", "Kp"]
    with pytest.raises(AxesError, match="has 3 panels, so it needs 3 axes, got 2"):
        lw.plot_diagram(mech, "coefficients", samples=90, ax=axes[:2])


def test_a_sphere_is_drawn_on_flat_axes_and_a_3d_axes_is_refused_in_one_line() -> None:
    fb = lw.SphericalFourBar(*np.radians([40, 20, 45, 35, 50, 130]))
    fig = new_figure((5, 5))
    assert lw.plot_mechanism(fb, samples=60, ax=fig.add_subplot()) is fig
    assert len(fig.axes) == 1  # the sphere's view alone; the map needs a second axes
    with pytest.raises(AxesError) as err:
        lw.plot_mechanism(fb, samples=60, ax=new_figure((4, 4)).add_subplot(projection="3d"))
    assert "\n" not in str(err.value) and "3-D Axes" in str(err.value)
    with pytest.raises(AxesError, match="expected a matplotlib Axes, got 'left'"):
        lw.plot_mechanism(lw.FourBar(**CRANK_ROCKER), ax="left")


def _svg_root(text: str) -> ET.Element:
    return ET.fromstring(text.encode())


def test_mechanisms_and_motions_show_themselves_as_svg() -> None:
    mech = lw.FourBar(**CRANK_ROCKER)
    picture = mech._repr_svg_()
    assert _svg_root(picture).tag.endswith("svg")
    motion = lw.circuit(mech, 90)
    assert _svg_root(motion._repr_svg_()).tag.endswith("svg")
    # Cannot assemble: a short text, not a failure.
    never = lw.FourBar(**NEVER)._repr_svg_()
    assert len(never) < 400 and "cannot be assembled" in never
    assert _svg_root(never).tag.endswith("svg")
    batch = lw.FourBar(A0=[0, 0], B0=[4, 0], crank=[1, 1.1], coupler=5, rocker=3.5)
    assert "index one linkage" in batch._repr_svg_()
    assert "index one" in lw.solve(batch, [0.0])._repr_svg_()
    text = lw.solve(lw.FourBar(**NEVER), [0.0, 1.0])._repr_svg_()
    assert "assembled at none" in text
