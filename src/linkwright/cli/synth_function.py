"""``linkwright synth function``: a four-bar generating y = f(x), from precision pairs or from a
function over a range (Chebyshev, even or given spacing; three pairs exactly, more in least
squares), with its structural error along the range."""

from __future__ import annotations

import ast
import math
import sys
from collections.abc import Callable
from typing import Annotated, Any

import numpy as np
import typer
from numpy.typing import NDArray

from linkwright.cli.shared import CliError, JsonOpt, documents_json, dump_json, parse_floats
from linkwright.cli.synth import angle_pairs, design_report, design_text, synth_app

MAX_PAIRS = 1000
"""The most precision pairs a least-squares fit takes (each costs one engine solve a step)."""
ERROR_SAMPLES = 201
"""Where the structural error is measured along the range (its largest value is reported)."""
SHOWN_SAMPLES = 11
"""Rows of the structural-error table printed."""

# What a function may be written with: x, numbers, arithmetic and these names (NumPy's).
_NAMES = "sin cos tan arcsin arccos arctan sinh cosh tanh exp log log10 log2 sqrt abs"
_FUNCTIONS: dict[str, Callable[..., Any]] = {name: getattr(np, name) for name in _NAMES.split()}
_CONSTANTS = {"pi": math.pi, "e": math.e}
_OPERATORS: dict[type, Callable[..., Any]] = {
    ast.Add: np.add,
    ast.Sub: np.subtract,
    ast.Mult: np.multiply,
    ast.Div: np.divide,
    ast.Pow: np.power,
    ast.USub: np.negative,
    ast.UAdd: np.positive,
}


def parse_function(text: str) -> Callable[[NDArray[np.float64]], NDArray[np.float64]]:
    """y = f(x) from text such as ``log10(x)`` or ``x**2 + 1``, or a one-line error.

    Only x, numbers, + − × ÷ **, the constants pi and e and NumPy's elementary functions are
    read; nothing is evaluated by Python itself.

    >>> f = parse_function("log10(x) + x**2")
    >>> float(f(np.array(10.0)))
    101.0
    >>> parse_function("__import__('os')")
    Traceback (most recent call last):
    ...
    linkwright.cli.shared.CliError: --function: unknown name '__import__' (write a function of x \
with + - * / ** and sin, cos, tan, arcsin, arccos, arctan, sinh, cosh, tanh, exp, log, log10, \
log2, sqrt, abs, pi, e)
    """
    allowed = ", ".join([*_FUNCTIONS, *_CONSTANTS])
    hint = f"write a function of x with + - * / ** and {allowed}"
    if len(text) > 200:
        raise CliError(f"--function: at most 200 characters, got {len(text)}")
    try:
        tree = ast.parse(text, mode="eval")
    except SyntaxError:
        raise CliError(f"--function: cannot read {text!r} ({hint})") from None

    def build(node: ast.AST) -> Callable[[NDArray[np.float64]], Any]:
        if isinstance(node, ast.Expression):
            return build(node.body)
        if isinstance(node, ast.Constant) and isinstance(node.value, int | float):
            value = float(node.value)
            return lambda x: np.full_like(x, value)
        if isinstance(node, ast.Name):
            if node.id == "x":
                return lambda x: x
            if node.id in _CONSTANTS:
                value = _CONSTANTS[node.id]
                return lambda x: np.full_like(x, value)
            raise CliError(f"--function: unknown name {node.id!r} ({hint})")
        if isinstance(node, ast.BinOp) and type(node.op) in _OPERATORS:
            op, left, right = _OPERATORS[type(node.op)], build(node.left), build(node.right)
            return lambda x: op(left(x), right(x))
        if isinstance(node, ast.UnaryOp) and type(node.op) in _OPERATORS:
            op1, inner = _OPERATORS[type(node.op)], build(node.operand)
            return lambda x: op1(inner(x))
        if (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name)
            and len(node.args) == 1
            and not node.keywords
        ):
            if node.func.id not in _FUNCTIONS:
                raise CliError(f"--function: unknown name {node.func.id!r} ({hint})")
            fn, arg = _FUNCTIONS[node.func.id], build(node.args[0])
            return lambda x: fn(arg(x))
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
            raise CliError(f"--function: unknown name {node.func.id!r} ({hint})")
        raise CliError(f"--function: cannot read {text!r} ({hint})")

    inner = build(tree)

    def f(x: NDArray[np.float64]) -> NDArray[np.float64]:
        with np.errstate(all="ignore"):
            return np.asarray(inner(np.asarray(x, dtype=float)), dtype=float)

    return f


def _range(text: str, what: str) -> tuple[float, float]:
    lo, hi = parse_floats(text.replace(":", ","), what, 2)
    if lo == hi:
        raise CliError(f"{what}: the range {lo:g}:{hi:g} is empty")
    return lo, hi


@synth_app.command("function")
def synth_function(
    pairs: Annotated[
        str | None,
        typer.Option(
            "--pairs",
            metavar="PHI,PSI;…",
            help="Input/output angle pairs (deg, from the frame line): 3 are met exactly, "
            "more fitted in least squares.",
        ),
    ] = None,
    function: Annotated[
        str | None,
        typer.Option("--function", metavar="F(x)", help="The function y = f(x), e.g. 'log10(x)'."),
    ] = None,
    x_range: Annotated[
        str | None, typer.Option("--x-range", metavar="X0:X1", help="The range of x.")
    ] = None,
    phi_range: Annotated[
        str | None,
        typer.Option("--phi-range", metavar="DEG:DEG", help="The crank's angles at x0 and x1."),
    ] = None,
    psi_range: Annotated[
        str | None,
        typer.Option("--psi-range", metavar="DEG:DEG", help="The rocker's angles at x0 and x1."),
    ] = None,
    points: Annotated[
        int,
        typer.Option(
            "--points", metavar="N", min=3, max=MAX_PAIRS, help="Precision points on the range."
        ),
    ] = 3,
    spacing: Annotated[
        str,
        typer.Option(
            "--spacing",
            metavar="chebyshev|even|X,…",
            help="Where the precision points lie: Chebyshev's nodes, even steps, or these x.",
        ),
    ] = "chebyshev",
    frame: Annotated[float, typer.Option("--frame", metavar="D", help="Frame length.")] = 1.0,
    as_json: JsonOpt = False,
) -> None:
    """Function generation: the four-bar whose rocker angle ψ follows the crank angle φ, from
    precision pairs, or from y = f(x) over a range (the crank and rocker turning linearly with
    x and y); three pairs by Freudenstein's equation, more in least squares. With a function,
    the structural error along the range is printed."""
    from linkwright.synthesis.precision import (
        PrecisionError,
        chebyshev_spacing,
        freudenstein_fit,
        function_error,
    )

    if not (math.isfinite(frame) and frame > 0):
        raise CliError("--frame: must be a positive length")
    ranged = (x_range, phi_range, psi_range)
    if pairs is not None and (function is not None or any(r is not None for r in ranged)):
        raise CliError("give --pairs, or --function with its ranges, not both")
    f = None
    if pairs is not None:
        rows = angle_pairs(pairs, "--pairs")
        if not 3 <= len(rows) <= MAX_PAIRS:
            raise CliError(f"--pairs: give 3 to {MAX_PAIRS} pairs, got {len(rows)}")
        phi, psi = np.radians(np.array(rows).T)
    else:
        if function is None or any(r is None for r in ranged):
            raise CliError("give --pairs, or --function with --x-range, --phi-range, --psi-range")
        f = parse_function(function)
        x0, x1 = _range(str(x_range), "--x-range")
        ranges = (np.radians(_range(str(phi_range), "--phi-range")),
                  np.radians(_range(str(psi_range), "--psi-range")))  # fmt: skip
        x = _spaced(spacing, x0, x1, points, chebyshev_spacing)
        y, y0, y1 = f(x), f(np.array(x0)), f(np.array(x1))
        if not (np.all(np.isfinite(y)) and np.isfinite(y0) and np.isfinite(y1) and y0 != y1):
            raise CliError(
                f"--function: f must be finite at the points and differ at the range's ends "
                f"(f(x0) = {float(y0):g}, f(x1) = {float(y1):g})"
            )
        phi = ranges[0][0] + (x - x0) / (x1 - x0) * (ranges[0][1] - ranges[0][0])
        psi = ranges[1][0] + (y - y0) / (y1 - y0) * (ranges[1][1] - ranges[1][0])
    try:
        design = freudenstein_fit(phi, psi, frame)
    except PrecisionError as exc:
        raise CliError(str(exc)) from None
    report = documents_json(design_report(design))
    report["method"] = "exact" if len(phi) == 3 else "least squares"
    if f is not None:
        xs, err = function_error(design, f, (x0, x1), ranges[0], ranges[1], ERROR_SAMPLES)
        report["precision_x"] = x.tolist()
        report["structural_error"] = {
            "x": xs.tolist(),
            "error": [None if not np.isfinite(e) else float(e) for e in err],
            "largest": float(np.nanmax(np.abs(err))) if np.isfinite(err).any() else None,
            "reached": bool(np.isfinite(err).all()),
        }
    if as_json:
        sys.stdout.write(dump_json(report))
        return
    k = report["coefficients"]
    head = (
        f"Freudenstein K1 = {k[0]:.9g}, K2 = {k[1]:.9g}, K3 = {k[2]:.9g} "
        f"({report['method']}, {len(phi)} pairs)\n"
    )
    sys.stdout.write(head + design_text(report) + "\n")
    if f is not None:
        sys.stdout.write(_error_table(report["structural_error"], f) + "\n")


def _spaced(
    spacing: str, x0: float, x1: float, n: int, chebyshev: Callable[..., Any]
) -> NDArray[np.float64]:
    if spacing == "chebyshev":
        return np.asarray(chebyshev(x0, x1, n), dtype=float)
    if spacing == "even":
        return np.linspace(x0, x1, n)
    x = np.array(parse_floats(spacing, "--spacing"))
    lo, hi = min(x0, x1), max(x0, x1)
    if not 3 <= len(x) <= MAX_PAIRS:
        raise CliError(f"--spacing: give 3 to {MAX_PAIRS} values of x, got {len(x)}")
    if np.any((x < lo) | (x > hi)):
        raise CliError(f"--spacing: every x must lie in the range {x0:g}:{x1:g}")
    return x


def _error_table(error: dict[str, Any], f: Callable[..., Any]) -> str:
    xs = np.array(error["x"])
    err = np.array([np.nan if e is None else e for e in error["error"]])
    pick = np.linspace(0, len(xs) - 1, SHOWN_SAMPLES).round().astype(int)
    lines = [f"structural error along the range (generated y − f(x); {len(xs)} samples):",
             f"{'x':>12} {'f(x)':>14} {'error':>12}"]  # fmt: skip
    for i in pick:
        shown = "unreached" if not np.isfinite(err[i]) else f"{err[i]:12.4e}"
        lines.append(f"{xs[i]:12.6g} {float(f(np.array(xs[i]))):14.8g} {shown:>12}")
    largest = error["largest"]
    lines.append(
        "largest |error|: "
        + ("none reached" if largest is None else f"{largest:.4e}")
        + ("" if error["reached"] else " (the linkage cannot reach part of the range)")
    )
    return "\n".join(lines)
