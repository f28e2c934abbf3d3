"""Source fragments of the compiled plans: one per step kind, keyed by the step's class.

Each fragment is the scalar form of its kind's ``place`` (:mod:`linkwright.engine.plane_steps`,
:mod:`linkwright.engine.sphere_steps`) for one mechanism at one sample: the same factored
discriminants, the same Cramer's-rule solves of the differentiated constraints, the same NaN
where a joint cannot be placed and the same masks, rearranged only where that saves a packed
division (one reciprocal per joint, divisions by dimensions hoisted) or a libm call, so the
numbers are the evaluator's to rounding. A change to a kind's ``place`` must be mirrored here;
tests/test_compile.py compares both, kind by kind and family by family.

A fragment reads its parents' variables (``<joint>x``, ``<joint>vx``, ``<joint>ok``,
``<joint>rg`` ...) and defines its own joint's; :class:`Names` hands out the names and the
expressions of the parameters. A line that starts with :data:`HOIST` depends on parameters
only: the generator places it once per mechanism, outside the sample loop.

What keeps the sample loop vectorisable (LLVM turns it into packed instructions only where no
call to libm remains in it): a crank's cosine and sine come from the generator (NumPy computes
them once per sample row, :meth:`Names.trig`); trigonometry of parameters is hoisted; and the
spherical dyad needs no ``atan2``, ``sin`` or ``cos`` per sample (see :func:`_sphere_dyad`), so
its numbers differ from the evaluator's by rounding (tests/test_compile.py says how much).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from linkwright.engine.plane_steps import Crank, DyadRRP, DyadRRR, Fixed, Rigid, Trammel
from linkwright.engine.sphere_steps import SphereCrank, SphereDyad, SphereRigid
from linkwright.engine.state import ASSEMBLY_TOL, SINGULAR_MARGIN, SINGULAR_SIN, Param

__all__ = ["FRAGMENTS", "Names", "fragment"]

HOIST = "@"
"""Marks a fragment's line that reads parameters only (placed once per mechanism)."""

TOL = repr(ASSEMBLY_TOL)
SS = repr(SINGULAR_SIN)
SM = repr(SINGULAR_MARGIN)


class Names(Protocol):
    """What a fragment asks of the generator."""

    order: int
    dim: int

    def joint(self, name: str) -> str:
        """The prefix of a joint's variables."""
        ...

    def scalar(self, p: Param) -> str:
        """The expression of a scalar parameter (a local of the mechanism, or a literal)."""
        ...

    def point(self, key: str) -> tuple[str, ...]:
        """The expressions of a point parameter's components."""
        ...

    def sign(self, step_name: str, key: str) -> str:
        """The expression of a dyad's branch sign."""
        ...

    def trig(self, step: object) -> tuple[str, str]:
        """(cos, sin) of a crank's angle ``phase + ratio·t`` (a trammel's ``phase + t``) at the
        current sample, computed outside the kernel."""
        ...


Fragment = Callable[[object, Names], list[str]]


def _mask(v: str, comps: str, order: int) -> list[str]:
    """Velocities and accelerations NaN where the joint is not regular (mask_derivatives)."""
    lines = []
    for kind, least in (("v", 1), ("a", 2)):
        if order >= least:
            lines += [f"{v}{kind}{c} = {v}{kind}{c} if {v}rg else nan" for c in comps]
    return lines


def _fixed(step: Fixed, g: Names) -> list[str]:
    comps = "xyz"[: g.dim]
    v = g.joint(step.name)
    lines = [f"{v}{c} = {e}" for c, e in zip(comps, g.point(step.at), strict=True)]
    lines += [f"{v}ok = True", f"{v}rg = True"]
    if g.order >= 1:
        lines += [f"{v}{k}{c} = 0.0" for k in "va" for c in comps]
    return lines


def _crank(step: Crank, g: Names) -> list[str]:
    v, o = g.joint(step.name), g.joint(step.pivot)
    r, k = g.scalar(step.length), g.scalar(step.ratio)
    cos, sin = g.trig(step)
    lines = [
        f"{v}c = {cos}",
        f"{v}s = {sin}",
        f"{v}mx = {r} * {v}c",
        f"{v}my = {r} * {v}s",
        f"{v}x = {o}x + {v}mx",
        f"{v}y = {o}y + {v}my",
        f"{v}ok = {o}ok",
        f"{v}rg = {o}rg",
    ]
    if g.order >= 1:
        lines += [
            f"{v}kr = {k} * {r}",
            f"{v}vx = {o}vx + {v}kr * (-{v}s)",
            f"{v}vy = {o}vy + {v}kr * {v}c",
        ]
    if g.order >= 2:
        lines += [
            f"{v}kk = {k} * {k}",
            f"{v}ax = {o}ax - {v}kk * {v}mx",
            f"{v}ay = {o}ay - {v}kk * {v}my",
        ]
    return lines


def _solve2(
    v: str, r1: tuple[str, str], r2: tuple[str, str], b1: str, b2: str, out: str
) -> list[str]:
    """Cramer's rule as plane.solve_2x2_rows: rows r1, r2, right-hand sides b1, b2. One
    division per joint (``{v}it``, see :func:`_inverse2`), shared by both solves: a packed
    division costs several multiplications."""
    return [
        f"{v}{out}x = ({b1} * {r2[1]} - {b2} * {r1[1]}) * {v}it",
        f"{v}{out}y = ({r1[0]} * {b2} - {r2[0]} * {b1}) * {v}it",
    ]


def _inverse2(v: str, r1: tuple[str, str], r2: tuple[str, str]) -> list[str]:
    """1 / the determinant of rows r1, r2 (inf or NaN where singular: masked by ``rg``)."""
    return [f"{v}it = 1.0 / ({r1[0]} * {r2[1]} - {r1[1]} * {r2[0]})"]


def _dyad_rrr(step: DyadRRR, g: Names) -> list[str]:
    v, p, q = g.joint(step.name), g.joint(step.p1), g.joint(step.p2)
    r1, r2 = g.scalar(step.r1), g.scalar(step.r2)
    sg = g.sign(step.name, step.branch)
    lines = [
        f"{HOIST}{v}sp2 = ({r1} + {r2}) * ({r1} + {r2})",
        f"{HOIST}{v}dm2 = ({r1} - {r2}) * ({r1} - {r2})",
        f"{HOIST}{v}pr = ({r1} - {r2}) * ({r1} + {r2})",
        f"{HOIST}{v}q1 = 0.25 / ({r1} * {r1})",
        f"{HOIST}{v}i12 = 1.0 / ({r1} * {r2})",
        # plane.circle_circle, with one division: a/d = (r1² − r2² + d²)/(2d²) and
        # h/d = √((r1+r2)² − d²)(d² − (r1−r2)²))/(2d²), the product exact near either root.
        f"{v}dx = {q}x - {p}x",
        f"{v}dy = {q}y - {p}y",
        f"{v}d2 = {v}dx * {v}dx + {v}dy * {v}dy",
        f"{v}id = 1.0 / {v}d2",
        f"{v}h2 = 0.5 * {sg}",
        f"{v}k = ({v}sp2 - {v}d2) * ({v}d2 - {v}dm2)",
        f"{v}mg = {v}k * {v}id * {v}q1",
        f"{v}mk = ({v}mg >= -{TOL}) & ({v}d2 > 0.0)",
        f"{v}al = 0.5 * ({v}pr + {v}d2) * {v}id",
        f"{v}ac = {v}h2 * math.sqrt(max({v}k, 0.0)) * {v}id if {v}mk else nan",
        f"{v}ok = {p}ok & {q}ok & {v}mk",
        f"{v}x = {p}x + ({v}al * {v}dx - {v}ac * {v}dy) if {v}ok else nan",
        f"{v}y = {p}y + ({v}al * {v}dy + {v}ac * {v}dx) if {v}ok else nan",
        # DyadRRR.place
        f"{v}ex = {v}x - {p}x",
        f"{v}ey = {v}y - {p}y",
        f"{v}fx = {v}x - {q}x",
        f"{v}fy = {v}y - {q}y",
        f"{v}dr = ({v}ex * {v}fy - {v}ey * {v}fx) * {v}i12",
        f"{v}rg = {v}ok & {p}rg & {q}rg & (abs({v}dr) > {SS}) & ({v}mg > {SM})",
    ]
    rows = ((f"{v}ex", f"{v}ey"), (f"{v}fx", f"{v}fy"))
    if g.order >= 1:
        lines += _inverse2(v, *rows)
        lines += [
            f"{v}b1 = {v}ex * {p}vx + {v}ey * {p}vy",
            f"{v}b2 = {v}fx * {q}vx + {v}fy * {q}vy",
            *_solve2(v, *rows, f"{v}b1", f"{v}b2", "v"),
        ]
    if g.order >= 2:
        lines += [
            f"{v}wx = {v}vx - {p}vx",
            f"{v}wy = {v}vy - {p}vy",
            f"{v}zx = {v}vx - {q}vx",
            f"{v}zy = {v}vy - {q}vy",
            f"{v}c1 = ({v}ex * {p}ax + {v}ey * {p}ay) - ({v}wx * {v}wx + {v}wy * {v}wy)",
            f"{v}c2 = ({v}fx * {q}ax + {v}fy * {q}ay) - ({v}zx * {v}zx + {v}zy * {v}zy)",
            *_solve2(v, *rows, f"{v}c1", f"{v}c2", "a"),
        ]
    return lines + _mask(v, "xy", g.order)


def _dyad_rrp(step: DyadRRP, g: Names) -> list[str]:
    v, p, q = g.joint(step.name), g.joint(step.p1), g.joint(step.line_point)
    r, ang = g.scalar(step.r), g.scalar(step.line_angle)
    sg = g.sign(step.name, step.branch)
    lines = [
        f"{HOIST}{v}ir2 = 1.0 / ({r} * {r})",
        f"{HOIST}{v}ir = 1.0 / {r}",
        f"{HOIST}{v}cx = math.cos({ang})",
        f"{HOIST}{v}cy = math.sin({ang})",
        f"{v}nx = -{v}cy",
        f"{v}ny = {v}cx",
        # plane.circle_line
        f"{v}ex = {p}x - {q}x",
        f"{v}ey = {p}y - {q}y",
        f"{v}al = {v}ex * {v}cx + {v}ey * {v}cy",
        f"{v}of = {v}ex * (-{v}cy) + {v}ey * {v}cx",
        f"{v}mg = ({r} - {v}of) * ({r} + {v}of) * {v}ir2",
        f"{v}mk = {v}mg >= -{TOL}",
        f"{v}hf = {r} * math.sqrt(max({v}mg, 0.0)) if {v}mk else nan",
        f"{v}bh = {sg} * {v}hf",
        f"{v}ok = {p}ok & {q}ok & {v}mk",
        f"{v}x = {q}x + {v}al * {v}cx + {v}bh * {v}cx if {v}ok else nan",
        f"{v}y = {q}y + {v}al * {v}cy + {v}bh * {v}cy if {v}ok else nan",
        # DyadRRP.place
        f"{v}fx = {v}x - {p}x",
        f"{v}fy = {v}y - {p}y",
        f"{v}dr = ({v}fx * {v}ny - {v}fy * {v}nx) * {v}ir",
        f"{v}rg = {v}ok & {p}rg & {q}rg & (abs({v}dr) > {SS}) & ({v}mg > {SM})",
    ]
    rows = ((f"{v}fx", f"{v}fy"), (f"{v}nx", f"{v}ny"))
    if g.order >= 1:
        lines += _inverse2(v, *rows)
        lines += [
            f"{v}b1 = {v}fx * {p}vx + {v}fy * {p}vy",
            f"{v}b2 = {v}nx * {q}vx + {v}ny * {q}vy",
            *_solve2(v, *rows, f"{v}b1", f"{v}b2", "v"),
        ]
    if g.order >= 2:
        lines += [
            f"{v}wx = {v}vx - {p}vx",
            f"{v}wy = {v}vy - {p}vy",
            f"{v}c1 = ({v}fx * {p}ax + {v}fy * {p}ay) - ({v}wx * {v}wx + {v}wy * {v}wy)",
            f"{v}c2 = {v}nx * {q}ax + {v}ny * {q}ay",
            *_solve2(v, *rows, f"{v}c1", f"{v}c2", "a"),
        ]
    return lines + _mask(v, "xy", g.order)


def _rigid(step: Rigid, g: Names) -> list[str]:
    v, o, t = g.joint(step.name), g.joint(step.origin), g.joint(step.toward)
    u, w = g.scalar(step.u), g.scalar(step.v)

    def local(k: str) -> list[str]:
        """jo + local(jt − jo) for positions (k = ""), velocities ("v"), accelerations ("a")."""
        dx, dy = f"{v}{k}dx", f"{v}{k}dy"
        return [
            f"{dx} = {t}{k}x - {o}{k}x",
            f"{dy} = {t}{k}y - {o}{k}y",
            f"{v}{k}x = {o}{k}x + ({v}cu * {dx} + {v}cv * (-{dy}))",
            f"{v}{k}y = {o}{k}y + ({v}cu * {dy} + {v}cv * {dx})",
        ]

    lines = [
        # √(dx² + dy²) where the evaluator has np.hypot (at most 1 ulp apart): a call to libm's
        # hypot would keep the sample loop from being vectorised.
        f"{v}hx = {t}x - {o}x",
        f"{v}hy = {t}y - {o}y",
        f"{v}il = 1.0 / math.sqrt({v}hx * {v}hx + {v}hy * {v}hy)",
        f"{v}cu = {u} * {v}il",
        f"{v}cv = {w} * {v}il",
        f"{v}ok = {o}ok & {t}ok & math.isfinite({v}il)",
        *local(""),
        f"{v}x = {v}x if {v}ok else nan",
        f"{v}y = {v}y if {v}ok else nan",
        f"{v}rg = {o}rg & {t}rg & {v}ok",
    ]
    if g.order >= 1:
        lines += local("v")
    if g.order >= 2:
        lines += local("a")
    return lines + _mask(v, "xy", g.order)


def _trammel(step: Trammel, g: Names) -> list[str]:
    v, p, q = g.joint(step.name), g.joint(step.guide1), g.joint(step.guide2)
    a1, a2, arm = g.scalar(step.angle1), g.scalar(step.angle2), g.scalar(step.arm)
    cos, sin = g.trig(step)

    def along(k: str, wx: str, wy: str) -> list[str]:
        dot = f"(({q}{k}x - {p}{k}x) - {wx}) * {v}nx + (({q}{k}y - {p}{k}y) - {wy}) * {v}ny"
        return [
            f"{v}{k}l = ({dot}) * {v}iv",
            f"{v}{k}x = {p}{k}x + {v}{k}l * {v}ex",
            f"{v}{k}y = {p}{k}y + {v}{k}l * {v}ey",
        ]

    lines = [
        f"{HOIST}{v}ex = math.cos({a1})",
        f"{HOIST}{v}ey = math.sin({a1})",
        f"{HOIST}{v}nx = -math.sin({a2})",
        f"{HOIST}{v}ny = math.cos({a2})",
        f"{v}wx = {arm} * {cos}",
        f"{v}wy = {arm} * {sin}",
        f"{v}dn = {v}ex * {v}nx + {v}ey * {v}ny",
        f"{v}pa = abs({v}dn) <= {SS}",
        f"{v}iv = nan if {v}pa else 1.0 / {v}dn",
        f"{v}ok = {p}ok & {q}ok & (not {v}pa)",
        *along("", f"{v}wx", f"{v}wy"),
        f"{v}x = {v}x if {v}ok else nan",
        f"{v}y = {v}y if {v}ok else nan",
        f"{v}rg = {p}rg & {q}rg & {v}ok",
    ]
    if g.order >= 1:
        lines += along("v", f"(-{v}wy)", f"{v}wx")
    if g.order >= 2:
        lines += along("a", f"(-{v}wx)", f"(-{v}wy)")
    return lines + _mask(v, "xy", g.order)


def _cross(out: str, a: str, b: str, ak: str = "", bk: str = "") -> list[str]:
    """out = a × b (sphere.cross), a and b joint prefixes with their kinds (pos, v, a)."""
    return [
        f"{out}x = {a}{ak}y * {b}{bk}z - {a}{ak}z * {b}{bk}y",
        f"{out}y = {a}{ak}z * {b}{bk}x - {a}{ak}x * {b}{bk}z",
        f"{out}z = {a}{ak}x * {b}{bk}y - {a}{ak}y * {b}{bk}x",
    ]


def _dot(a: str, b: str, ak: str = "", bk: str = "") -> str:
    return f"({a}{ak}x * {b}{bk}x + {a}{ak}y * {b}{bk}y + {a}{ak}z * {b}{bk}z)"


def _sphere_crank(step: SphereCrank, g: Names) -> list[str]:
    v, o = g.joint(step.name), g.joint(step.pivot)
    rx, ry, rz = g.point(step.ref)
    k, length = g.scalar(step.ratio), g.scalar(step.length)
    cos, sin = g.trig(step)
    lines = [
        # sphere.tangent(o, ref) and e2 = o × e1
        f"{v}rd = {rx} * {o}x + {ry} * {o}y + {rz} * {o}z",
        f"{v}tx = {rx} - {v}rd * {o}x",
        f"{v}ty = {ry} - {v}rd * {o}y",
        f"{v}tz = {rz} - {v}rd * {o}z",
        f"{v}tn = math.sqrt({v}tx * {v}tx + {v}ty * {v}ty + {v}tz * {v}tz)",
        f"{v}ex = {v}tx / {v}tn",
        f"{v}ey = {v}ty / {v}tn",
        f"{v}ez = {v}tz / {v}tn",
        *_cross(f"{v}f", o, f"{v}e"),
    ]
    lines += [f"{v}c = {cos}", f"{v}s = {sin}"]
    lines += [f"{HOIST}{v}cl = math.cos({length})", f"{HOIST}{v}sl = math.sin({length})"]
    lines += [f"{v}{c} = {v}cl * {o}{c} + {v}sl * ({v}c * {v}e{c} + {v}s * {v}f{c})" for c in "xyz"]
    lines += [
        f"{v}ok = {o}ok & math.isfinite({v}x) & math.isfinite({v}y) & math.isfinite({v}z)",
        *[f"{v}{c} = {v}{c} if {v}ok else nan" for c in "xyz"],
    ]
    if g.order >= 1:
        lines += _cross(f"{v}q", o, v)
        lines += [f"{v}v{c} = {k} * {v}q{c}" for c in "xyz"]
    if g.order >= 2:
        lines += _cross(f"{v}q", o, v, "", "v")
        lines += [f"{v}a{c} = {k} * {v}q{c}" for c in "xyz"]
    lines.append(f"{v}rg = {v}ok & {o}rg")
    return lines + _mask(v, "xyz", g.order)


def _solve3(v: str, p: str, q: str, b: tuple[str, str, str], out: str) -> list[str]:
    """sphere.solve_3x3_rows with rows P1, P2, X: the Cramer columns are computed once per
    joint (``{v}k``, ``{v}l``, ``{v}m``) by the caller."""
    return [
        f"{v}{out}{c} = ({b[0]} * {v}k{c} + {b[1]} * {v}l{c} + {b[2]} * {v}m{c}) * {v}it"
        for c in "xyz"
    ]


def _sphere_dyad(step: SphereDyad, g: Names) -> list[str]:
    """sphere.small_circles without a transcendental call per sample: the evaluator's
    ``gram(atan2(sin d, cos d), r1, r2)``, the product 4 sin s sin(s−d) sin(s−r1) sin(s−r2) with
    s = (d + r1 + r2)/2, is expanded in the sine and cosine of d/2 and of the hoisted half-sum
    and half-difference of the arcs (each factor stays exact at its root, as the product form
    is meant to); and (cos φ, sin φ) of ``φ = atan2(y, x)`` are (x, y)/√(x² + y²). Both differ
    from the evaluator's by rounding only."""
    v, p, q = g.joint(step.name), g.joint(step.p1), g.joint(step.p2)
    r1, r2 = g.scalar(step.r1), g.scalar(step.r2)
    sg = g.sign(step.name, step.branch)
    lines = [
        f"{HOIST}{v}s1 = math.sin({r1})",
        f"{HOIST}{v}c1 = math.cos({r1})",
        f"{HOIST}{v}c2 = math.cos({r2})",
        f"{HOIST}{v}i12 = 1.0 / ({v}s1 * math.sin({r2}))",
        f"{HOIST}{v}is = 1.0 / ({v}s1 * {v}s1)",
        f"{HOIST}{v}hp = 0.5 * ({r1} + {r2})",
        f"{HOIST}{v}hq = 0.5 * ({r1} - {r2})",
        f"{HOIST}{v}ca = math.cos({v}hp)",
        f"{HOIST}{v}sa = math.sin({v}hp)",
        f"{HOIST}{v}cb = math.cos({v}hq)",
        f"{HOIST}{v}sb = math.sin({v}hq)",
        *_cross(f"{v}w", p, q),
        f"{v}w2 = {_dot(v + 'w', v + 'w')}",
        f"{v}sd = math.sqrt({v}w2)",
        f"{v}cd = {_dot(p, q)}",
        # cos and sin of d/2 (d in [0, π]) from whichever half-angle formula does not cancel
        # (p1 and p2 are unit vectors: sin² d + cos² d = 1 to rounding).
        f"{v}hb = math.sqrt(0.5 * (1.0 + abs({v}cd)))",
        f"{v}hs = {v}sd / (2.0 * {v}hb)",
        f"{v}ch = {v}hb if {v}cd >= 0.0 else {v}hs",
        f"{v}sh = {v}hs if {v}cd >= 0.0 else {v}hb",
        f"{v}g = 4.0 * ({v}sh * {v}ca + {v}ch * {v}sa) * ({v}sa * {v}ch - {v}ca * {v}sh)"
        f" * ({v}sh * {v}cb - {v}ch * {v}sb) * ({v}sh * {v}cb + {v}ch * {v}sb)",
        f"{v}mg = {v}g / {v}w2 * {v}is",
        f"{v}mk = ({v}mg >= -{TOL}) & ({v}sd > 0.0)",
        *_cross(f"{v}u", f"{v}w", p),
        f"{v}un = 1.0 / math.sqrt({_dot(v + 'u', v + 'u')})",
        *[f"{v}t{c} = {v}u{c} * {v}un" for c in "xyz"],
        f"{v}rt = math.sqrt(max({v}g, 0.0)) if {v}mk else nan",
        f"{v}py = {sg} * {v}rt",
        f"{v}px = {v}c2 - {v}c1 * {v}cd",
        # atan2(±0, ±0) is 0 or π: cos φ = ±1 there (the sign of x), sin φ = 0.
        f"{v}pn = math.sqrt({v}px * {v}px + {v}py * {v}py)",
        f"{v}pi = 1.0 / {v}pn if {v}pn > 0.0 else 0.0",
        f"{v}cp = {v}px * {v}pi if {v}pn > 0.0 else math.copysign(1.0, {v}px)",
        f"{v}sp = {v}py * {v}pi",
        *_cross(f"{v}n", p, f"{v}t"),
        f"{v}ok = {p}ok & {q}ok & {v}mk",
        *[
            f"{v}{c} = {v}c1 * {p}{c} + {v}s1 * ({v}cp * {v}t{c} + {v}sp * {v}n{c})"
            f" if {v}ok else nan"
            for c in "xyz"
        ],
        # SphereDyad.place
        f"{v}dr = {_dot(v, v + 'w')} * {v}i12",
        f"{v}rg = {v}ok & {p}rg & {q}rg & (abs({v}dr) > {SS}) & ({v}mg > {SM})",
    ]
    if g.order >= 1:
        lines += [
            *_cross(f"{v}k", q, v),
            *_cross(f"{v}l", v, p),
            *_cross(f"{v}m", p, q),
            f"{v}it = 1.0 / {_dot(p, v + 'k')}",
            f"{v}b1 = -{_dot(v, p, '', 'v')}",
            f"{v}b2 = -{_dot(v, q, '', 'v')}",
            *_solve3(v, p, q, (f"{v}b1", f"{v}b2", "0.0"), "v"),
        ]
    if g.order >= 2:
        lines += [
            f"{v}e1 = -2.0 * {_dot(v, p, 'v', 'v')} - {_dot(v, p, '', 'a')}",
            f"{v}e2 = -2.0 * {_dot(v, q, 'v', 'v')} - {_dot(v, q, '', 'a')}",
            f"{v}e3 = -{_dot(v, v, 'v', 'v')}",
            *_solve3(v, p, q, (f"{v}e1", f"{v}e2", f"{v}e3"), "a"),
        ]
    return lines + _mask(v, "xyz", g.order)


def _sphere_rigid(step: SphereRigid, g: Names) -> list[str]:
    v, o, t = g.joint(step.name), g.joint(step.origin), g.joint(step.toward)
    length, angle = g.scalar(step.length), g.scalar(step.angle)
    lines = [
        *_cross(f"{v}w", o, t),
        f"{v}co = {_dot(o, t)}",
        f"{v}so = math.sqrt({_dot(v + 'w', v + 'w')})",
        f"{HOIST}{v}sl = math.sin({length})",
        f"{HOIST}{v}lb = {v}sl * math.cos({angle})",
        f"{HOIST}{v}lc = {v}sl * math.sin({angle})",
        f"{HOIST}{v}cl = math.cos({length})",
        f"{v}io = 1.0 / {v}so",
        f"{v}b = {v}lb * {v}io",
        f"{v}c = {v}lc * {v}io",
        f"{v}a = {v}cl - {v}b * {v}co",
        f"{v}ok = {o}ok & {t}ok & ({v}so > 0.0)",
        *[
            f"{v}{c} = {v}a * {o}{c} + {v}b * {t}{c} + {v}c * {v}w{c} if {v}ok else nan"
            for c in "xyz"
        ],
        f"{v}rg = {o}rg & {t}rg & {v}ok",
    ]
    if g.order >= 1:
        lines += [*_cross(f"{v}p", o, t, "v"), *_cross(f"{v}q", o, t, "", "v")]
        lines += [
            f"{v}v{c} = {v}a * {o}v{c} + {v}b * {t}v{c} + {v}c * ({v}p{c} + {v}q{c})" for c in "xyz"
        ]
    if g.order >= 2:
        lines += [
            *_cross(f"{v}p", o, t, "a"),
            *_cross(f"{v}r", o, t, "v", "v"),
            *_cross(f"{v}q", o, t, "", "a"),
        ]
        lines += [
            f"{v}a{c} = {v}a * {o}a{c} + {v}b * {t}a{c}"
            f" + {v}c * ({v}p{c} + 2.0 * {v}r{c} + {v}q{c})"
            for c in "xyz"
        ]
    return lines + _mask(v, "xyz", g.order)


FRAGMENTS: dict[type, Fragment] = {
    Fixed: _fixed,  # type: ignore[dict-item]
    Crank: _crank,  # type: ignore[dict-item]
    DyadRRR: _dyad_rrr,  # type: ignore[dict-item]
    DyadRRP: _dyad_rrp,  # type: ignore[dict-item]
    Rigid: _rigid,  # type: ignore[dict-item]
    Trammel: _trammel,  # type: ignore[dict-item]
    SphereCrank: _sphere_crank,  # type: ignore[dict-item]
    SphereDyad: _sphere_dyad,  # type: ignore[dict-item]
    SphereRigid: _sphere_rigid,  # type: ignore[dict-item]
}
"""Step kind → its fragment. A kind missing here (a triad) makes its plan fall back to the
plan evaluator."""


def fragment(step: object) -> Fragment | None:
    """The fragment of a step's kind (exactly that class: a subclass may place differently)."""
    return FRAGMENTS.get(type(step))
