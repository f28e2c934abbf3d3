"""A user's typed code type-checks against the package (it ships ``py.typed``).

``make test`` runs mypy over the package itself; this checks the other side, what a user
writing ``FourBar(A0=[0, 0], ...)`` under ``mypy --strict`` sees: the families' constructors
take array-likes by name, and their fields read back as float arrays.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

api = pytest.importorskip("mypy.api", reason="mypy is in the dev extra")

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "linkwright"

USER_CODE = """
import numpy as np
from numpy.typing import NDArray
from linkwright.mechanisms import FourBar, SphericalFourBar, solve

m = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5, u=0.5)
reach: NDArray[np.float64] = m.crank + m.coupler
shifted = m.with_assembly(-1)
motion = solve(m, np.linspace(0.0, 1.0, 5))
s = SphericalFourBar(frame=0.7, crank=0.35, coupler=0.8, rocker=0.6)
arc: NDArray[np.float64] = s.frame - s.crank
reveal_type(m.crank)
"""


def test_py_typed_ships_with_the_package():
    assert (PACKAGE / "py.typed").is_file()


def test_family_constructors_and_fields_are_typed(tmp_path):
    user = tmp_path / "user.py"
    user.write_text(textwrap.dedent(USER_CODE))
    out, err, status = api.run(
        [
            "--strict",
            "--no-incremental",
            "--cache-dir",
            str(tmp_path / "cache"),
            "--follow-imports=silent",
            str(user),
        ]
    )
    assert status == 0, out + err
    assert 'Revealed type is "numpy.ndarray[' in out and "float64" in out, out
