"""Packaging (issue 23 item 6): the core works with every extra's modules missing, each missing
extra says in one line what to install, and the built wheel installs in a clean environment."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import textwrap
import venv
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

# Imports of the extras' modules fail, as in an install without them.
BLOCKER = textwrap.dedent(
    """
    import importlib.abc, sys
    BLOCKED = {"fastapi", "uvicorn", "starlette", "multipart", "python_multipart", "orjson",
               "faiss", "dask", "distributed", "numba"}
    class Blocker(importlib.abc.MetaPathFinder):
        def find_spec(self, name, path=None, target=None):
            if name.split(".")[0] in BLOCKED:
                raise ModuleNotFoundError(f"No module named {name!r}", name=name)
            return None
    sys.meta_path.insert(0, Blocker())
    """
)


def _run_blocked(code: str, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", BLOCKER + textwrap.dedent(code)],
        capture_output=True,
        text=True,
        timeout=timeout,
        cwd=ROOT,
    )


def test_the_core_works_with_every_extra_hidden() -> None:
    out = _run_blocked(
        """
        import numpy as np
        import linkwright as lw
        from linkwright import _extras
        from linkwright.engine import kernels
        for name in lw.__all__:
            getattr(lw, name)
        fb = lw.FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5, u=2, v=1)
        assert lw.analyze(fb).kind == "crank-rocker"
        assert lw.plot_mechanism(fb, samples=60).axes
        assert "<svg" in fb._repr_svg_()
        assert not kernels.available()
        print(sorted(e for e in _extras.EXTRAS if not _extras.has(e)))
        try:
            import linkwright.server
        except ImportError as exc:
            print(type(exc).__name__, exc)
        """
    )
    assert out.returncode == 0, out.stderr
    lines = out.stdout.strip().splitlines()
    assert lines == [
        "['atlas', 'fast', 'server']",
        "MissingExtra the workbench needs the server extra: pip install 'linkwright[server]'",
    ]


def test_the_command_line_runs_without_the_extras_and_serve_says_what_to_install() -> None:
    out = _run_blocked(
        """
        import sys
        from linkwright.cli import main
        sys.argv = ["linkwright", "--help"]
        try:
            main()
        except SystemExit as exc:
            assert exc.code in (0, None), exc.code
        """
    )
    assert out.returncode == 0, out.stderr
    assert "serve" in out.stdout
    out = _run_blocked(
        """
        import sys
        from linkwright.cli import main
        sys.argv = ["linkwright", "serve"]
        raise SystemExit(main())
        """
    )
    assert out.returncode != 0
    assert "Traceback" not in out.stderr + out.stdout
    assert "pip install 'linkwright[server]'" in out.stderr + out.stdout


def _index_reachable(tmp: Path) -> bool:
    probe = subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "download",
            "--quiet",
            "--no-deps",
            "--dest",
            str(tmp),
            "setuptools>=77",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    return probe.returncode == 0


def test_the_wheel_installs_in_a_clean_environment_and_runs(tmp_path: Path) -> None:
    pytest.importorskip("build", reason="the dev extra installs build")
    if not _index_reachable(tmp_path / "probe"):
        pytest.skip("the package index is unreachable: the clean install needs its dependencies")
    dist = tmp_path / "dist"
    # Built from a copy: setuptools writes a build/ folder beside the sources, and the tree
    # must stay as the other tests (running at the same time) see it.
    source = tmp_path / "source"
    shutil.copytree(
        ROOT / "src", source / "src", ignore=shutil.ignore_patterns("__pycache__", "*.egg-info")
    )
    for name in ("pyproject.toml", "README.md", "CITATION.cff"):
        shutil.copy2(ROOT / name, source / name)
    # Bounded: the build, the install from the index (numpy, scipy, matplotlib, typer, ezdxf;
    # about a minute with pip's cache) and the runs each have a time limit.
    subprocess.run(
        [sys.executable, "-m", "build", "--wheel", "--outdir", str(dist), str(source)],
        check=True,
        capture_output=True,
        timeout=300,
    )
    wheel = next(dist.glob("linkwright-*.whl"))
    env_dir = tmp_path / "clean"
    venv.create(env_dir, with_pip=True, system_site_packages=False)
    bin_dir = env_dir / "bin"
    subprocess.run(
        [str(bin_dir / "python"), "-m", "pip", "install", "--quiet", str(wheel)],
        check=True,
        capture_output=True,
        timeout=600,
    )
    clean = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    helped = subprocess.run(
        [str(bin_dir / "linkwright"), "--help"],
        capture_output=True,
        text=True,
        timeout=120,
        env=clean,
        cwd=tmp_path,
    )
    assert helped.returncode == 0, helped.stderr
    assert "Usage" in helped.stdout
    # The tutorial's first steps, from the installed wheel (not this source tree).
    example = """
        import numpy as np, linkwright as lw
        assert "site-packages" in lw.__file__, lw.__file__
        fb = lw.FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5, u=2, v=1)
        m = lw.solve(fb, np.radians([0, 90]))
        # Closed form: A is on the crank's circle at the input angle.
        assert np.allclose(m.positions["A"], [[1, 0], [0, 1]], atol=1e-12)
        print(lw.classify(fb), lw.classify(lw.FourBar(A0=[0, 0], B0=[10, 0], crank=1,
              coupler=2, rocker=3)), "<svg" in fb._repr_svg_())
        print(sorted(lw.list_examples())[0])
    """
    ran = subprocess.run(
        [str(bin_dir / "python"), "-c", textwrap.dedent(example)],
        capture_output=True,
        text=True,
        timeout=300,
        env=clean,
        cwd=tmp_path,
    )
    assert ran.returncode == 0, ran.stderr
    assert ran.stdout.splitlines()[0] == "crank-rocker None True"
