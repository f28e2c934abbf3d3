"""The two searches of a path fit: differential evolution, then batched least squares.

:class:`Evolution` is JADE's current-to-pbest/1 with adaptive F and CR (J. Zhang & A. C.
Sanderson, *IEEE Trans. Evol. Comput.* 13, 2009), with Deb's feasibility rules for the
constraints (K. Deb, *Comput. Methods Appl. Mech. Eng.* 186, 2000), evaluating each generation
as one batched mechanism. :class:`LocalSearch` is Levenberg–Marquardt with geodesic
acceleration (M. K. Transtrum & J. P. Sethna, 2012) from many starts at once, the constraints
entering as weighted hinge residuals; :func:`~linkwright.synthesis.path.fit_path` drives both.
"""

from __future__ import annotations

import contextlib
import time

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

from linkwright.synthesis.path_families import rodrigues
from linkwright.synthesis.path_problem import (
    Candidate,
    OutOfTime,
    Problem,
    solve_batched,
    wrap_angle,
)
from linkwright.synthesis.path_spec import (
    BETWEEN,
    COVERAGE,
    GEODESIC_RATIO,
    GEODESIC_STEP,
    GRID,
    STEP,
    WEIGHT,
)

__all__ = [
    "Evolution",
    "LocalSearch",
]

Array = NDArray[np.float64]


# ------------------------------------------------------------------------------------------
# Differential evolution (JADE, current-to-pbest/1/bin)
# ------------------------------------------------------------------------------------------


class Evolution:
    def __init__(self, problem: Problem, size: int, rng: np.random.Generator) -> None:
        p = problem
        self.p = p
        self.rng = rng
        self.lo = np.r_[p.lo[p.free], -1.0]
        self.hi = np.r_[p.hi[p.free], 1.0]
        self.wrap = np.r_[p.periodic[p.free], False]
        # The first generation is the best of SCREEN times as many random members: one
        # batched evaluation that starts the evolution among the better basins.
        X = rng.uniform(self.lo, self.hi, (p.screen * size, len(self.lo)))
        if p.seeds is not None:
            # Starts from the template the user gave (its own linkage, laid over the targets)
            # take the first places; they are screened like the rest.
            X[: len(p.seeds)] = np.clip(p.seeds[: len(X)], self.lo, self.hi)
            p.seeds = None
        err, viol = p.fitness(X)
        keep = np.lexsort((err, viol))[:size]
        self.X, self.err, self.viol = X[keep], err[keep], viol[keep]
        self.first = (self.X.copy(), self.err.copy(), self.viol.copy())
        self.mu_f, self.mu_cr = 0.5, 0.5

    def order(self) -> NDArray[np.int64]:
        return np.lexsort((self.err, self.viol))

    def step(self) -> None:
        X, rng = self.X, self.rng
        n, d = int(X.shape[0]), int(X.shape[1])
        F = self.mu_f + 0.1 * rng.standard_cauchy(n)
        while np.any(F <= 0):
            bad = F <= 0
            F[bad] = self.mu_f + 0.1 * rng.standard_cauchy(int(bad.sum()))
        F = np.minimum(F, 1.0)
        CR = np.clip(rng.normal(self.mu_cr, 0.1, n), 0.0, 1.0)
        top = self.order()[: max(2, n // 10)]
        pbest = X[rng.choice(top, n)]
        r1 = (np.arange(n) + rng.integers(1, n, n)) % n
        r2 = (r1 + rng.integers(1, n - 1, n)) % n
        r2 = np.where(r2 == np.arange(n), (r2 + 1) % n, r2)
        V = X + F[:, None] * (pbest - X) + F[:, None] * (X[r1] - X[r2])
        cross = rng.random((n, d)) < CR[:, None]
        cross[np.arange(n), rng.integers(0, d, n)] = True
        U = np.where(cross, V, X)
        span = self.hi - self.lo
        wrapped = self.lo + np.mod(U - self.lo, np.where(span > 0, span, 1.0))
        below = np.where(self.lo > U, (self.lo + X) / 2, U)
        inside = np.where(below > self.hi, (self.hi + X) / 2, below)
        U = np.where(self.wrap, wrapped, inside)
        err, viol = self.p.fitness(U)
        better = (viol < self.viol) | ((viol == self.viol) & (err <= self.err))
        if better.any():
            sf, scr = F[better], CR[better]
            self.mu_f = 0.9 * self.mu_f + 0.1 * float(np.sum(sf**2) / np.sum(sf))
            self.mu_cr = 0.9 * self.mu_cr + 0.1 * float(np.mean(scr))
        self.X = np.where(better[:, None], U, X)
        self.err = np.where(better, err, self.err)
        self.viol = np.where(better, viol, self.viol)

    def best(self) -> tuple[float, float]:
        i = self.order()[0]
        return float(self.err[i]), float(self.viol[i])


# ------------------------------------------------------------------------------------------
# Local least squares
# ------------------------------------------------------------------------------------------


class LocalSearch:
    """Least squares from several members at once: dimensions, placement and inputs together.

    Each start has its own assembly, free-timing sense and (sphere) base rotation R0; the
    placement is then R0 times the rotation of a rotation vector, so that no chart of the
    sphere's rotations has a pole in the way. :meth:`levenberg_marquardt` advances every start
    in lock step, evaluating all their finite-difference Jacobians as one batched mechanism;
    :meth:`polish` finishes one start with :func:`scipy.optimize.least_squares`.
    """

    def __init__(
        self,
        problem: Problem,
        starts: list[Candidate],
        senses: list[float],
        deadline: float,
        goal: float = 0.0,
    ) -> None:
        p = self.p = problem
        m = p.model
        self.deadline = deadline
        # An error the caller counts as an exact fit: once a start reaches it, the others'
        # iterations would only be spent (a close template would otherwise run to the budget).
        self.goal = goal
        self.assembly = np.array([c.assembly for c in starts])
        self.sense = np.array(senses, float)
        self.sphere = m.space == "sphere"
        self.R0 = np.array([c.pose for c in starts]) if self.sphere else None
        self.shape_free = [k for i, k in enumerate(m.shape_names) if p.free[3 + i]]
        self.pose_free = [] if self.sphere else [i for i in range(3) if p.free[i]]
        lo: list[float] = []
        hi: list[float] = []
        typ: list[float] = []
        columns: list[Array] = []
        if self.sphere:
            columns += [np.zeros(len(starts))] * 3
            lo += [-np.inf] * 3
            hi += [np.inf] * 3
            typ += [1.0] * 3
        else:
            for i in self.pose_free:
                columns.append(np.array([c.pose[i] for c in starts]))
                lo.append(-np.inf if p.periodic[i] else p.lo[i])
                hi.append(np.inf if p.periodic[i] else p.hi[i])
                typ.append(1.0 if i == 2 else p.size)
        linear = m.linear
        for k in self.shape_free:
            i = 3 + m.shape_names.index(k)
            columns.append(np.array([c.shape[k] for c in starts]))
            lo.append(-np.inf if p.periodic[i] else p.lo[i])
            hi.append(np.inf if p.periodic[i] else p.hi[i])
            typ.append(p.size if k in linear else 1.0)
        first = starts[0]
        self.fixed_shape = {k: first.shape[k] for k in m.shape_names if k not in self.shape_free}
        self.fixed_pose = None if self.sphere else np.asarray(first.pose, float).copy()
        if p.timing == "free":
            sticks = []
            for c, sense in zip(starts, senses, strict=True):
                # Stick-breaking: each increment takes a fraction of what is left of the period.
                left, t = p.period, []
                for step in sense * np.diff(c.rel):
                    t.append(min(max(step / left, 0.0), 1.0) if left > 0 else 0.0)
                    left = max(left - step, 0.0)
                sticks.append([c.rel[0], *t])
            columns += list(np.array(sticks).T)
            lo += [-np.inf] + [0.0] * (p.n - 1)
            hi += [np.inf] + [1.0] * (p.n - 1)
            typ += [1.0] * p.n
        elif p.free_start:
            assert p.angles is not None  # a prescribed timing comes with its angles
            columns.append(np.array([c.rel[0] - p.angles[0] for c in starts]))
            lo.append(-np.inf)
            hi.append(np.inf)
            typ.append(1.0)
        elif p.timing == "none":
            columns += list(np.array([c.rel for c in starts]).T)
            lo += [-np.inf] * p.n
            hi += [np.inf] * p.n
            typ += [1.0] * p.n
        self.lo, self.hi = np.array(lo, float), np.array(hi, float)
        self.typ = np.array(typ, float)
        self.x0 = np.clip(np.stack(columns, axis=1), self.lo, self.hi)
        count = len(starts)
        self.best_err = np.full(count, np.inf)
        self.best_obj = np.full(count, np.inf)
        self.best_z = self.x0.copy()

    def decode(self, Z: Array, owner: NDArray[np.int64]) -> tuple[Array, dict[str, Array], Array]:
        p = self.p
        B = len(Z)
        j = 0
        pose: Array
        if self.sphere:
            assert self.R0 is not None  # every spherical start has its base rotation
            pose = np.einsum("bij,bjk->bik", self.R0[owner], rodrigues(Z[:, :3]))
            j = 3
        else:
            assert self.fixed_pose is not None  # a planar search fixes its pose's rest
            pose = np.broadcast_to(self.fixed_pose, (B, 3)).copy()
            for i in self.pose_free:
                pose[:, i] = Z[:, j]
                j += 1
        shape = {k: np.full(B, v) for k, v in self.fixed_shape.items()}
        for k in self.shape_free:
            shape[k] = Z[:, j]
            j += 1
        if p.timing == "prescribed":
            assert p.angles is not None  # a prescribed timing comes with its angles
            rel = np.broadcast_to(p.angles, (B, p.n))
            if p.free_start:
                rel = rel + Z[:, j : j + 1]
        elif p.timing == "free":
            t = Z[:, j + 1 :]
            left = np.full(B, p.period)
            steps = np.empty_like(t)
            for i in range(t.shape[1]):
                steps[:, i] = left * t[:, i]
                left = left - steps[:, i]
            inc = np.concatenate([np.zeros((B, 1)), np.cumsum(steps, axis=1)], axis=1)
            rel = Z[:, j : j + 1] + self.sense[owner][:, None] * inc
        else:
            rel = Z[:, j:]
        return pose, shape, np.asarray(rel, float)

    def residuals(
        self, Z: Array, owner: NDArray[np.int64]
    ) -> tuple[Array, NDArray[np.bool_], Array, NDArray[np.bool_]]:
        """Residual vectors (B, m), the validity pattern, the errors Σ d², feasibility."""
        p = self.p
        pose, shape, rel = self.decode(Z, owner)
        B = len(Z)
        path = np.sort(rel, axis=1) if p.timing == "none" else rel
        f = np.arange(1, BETWEEN + 1) / (BETWEEN + 1)
        mids = (path[:, :-1, None] + np.diff(path, axis=1)[:, :, None] * f).reshape(B, -1)
        parts = [rel, mids]
        cover = p.timing == "none" and p.closed
        if cover:
            parts.append(np.broadcast_to(p.cover_grid, (B, COVERAGE)))
        if p.sampled:
            parts.append(np.broadcast_to(p.grid, (B, GRID)))
        inputs = np.concatenate(parts, axis=1)
        P, valid, motion = p.trace(pose, shape, self.assembly[owner], inputs)
        n, nm = p.n, mids.shape[1]
        diff = P[:, :n] - p.targets
        ok_t = valid[:, :n]
        res = [np.where(ok_t[..., None], diff, p.penalty).reshape(B, -1)]
        err = np.sum(np.where(ok_t[..., None], diff, 0.0) ** 2, axis=(1, 2))
        res.append(np.where(valid[:, n : n + nm], 0.0, p.penalty))
        at = n + nm
        if cover:
            c = P[:, at : at + COVERAGE]
            d = np.sqrt(np.min(np.sum((c[:, :, None] - p.targets) ** 2, axis=-1), axis=-1))
            ex = np.sqrt(p.n / COVERAGE) * np.maximum(d - p.coverage_h, 0.0)
            res.append(np.where(valid[:, at : at + COVERAGE], ex, p.penalty))
            at += COVERAGE
        sl = slice(at, at + GRID) if p.sampled else slice(None)
        feasible = np.asarray(valid[:, : n + nm].all(axis=1))
        hull = (rel.min(axis=1), rel.max(axis=1))
        for g, margin in p.gaps(shape, motion, sl, hull, self.assembly[owner]):
            res.append((WEIGHT * p.size * np.maximum(g + margin, 0.0))[:, None])
            feasible &= g <= 0.0
        return np.concatenate(res, axis=1), valid, err, feasible

    def _note(
        self, Z: Array, owner: NDArray[np.int64], R: Array, err: Array, ok: NDArray[np.bool_]
    ) -> Array:
        """Keep each start's best feasible point; return the objectives Σ r²."""
        obj: Array = np.sum(R * R, axis=1)
        # Penalties vanish at a feasible point, so Σ r² is the objective there.
        better = ok & (obj < self.best_obj[owner])
        for b in np.flatnonzero(better):
            o = owner[b]
            if obj[b] < self.best_obj[o]:
                self.best_obj[o], self.best_err[o], self.best_z[o] = obj[b], err[b], Z[b]
        return obj

    def _jacobians(
        self, Z: Array, owner: NDArray[np.int64], R0: Array, V0: NDArray[np.bool_]
    ) -> Array:
        """Finite-difference Jacobians (K, m, n) at the rows Z, one batched evaluation.

        A difference across a change of validity (a sample that stops assembling) measures the
        penalty's jump, not a slope: such a side is dropped (central → one-sided → 0).
        """
        K, n = Z.shape
        h = STEP * np.maximum(self.typ, np.abs(Z))
        up = np.minimum(Z + h, self.hi)
        dn = np.maximum(Z - h, self.lo)
        eye = np.eye(n, dtype=bool)
        Zp = np.where(eye, up[:, None, :], Z[:, None, :])
        Zm = np.where(eye, dn[:, None, :], Z[:, None, :])
        rows = np.concatenate([Zp.reshape(-1, n), Zm.reshape(-1, n)])
        own = np.concatenate([np.repeat(owner, n), np.repeat(owner, n)])
        R, V, _, _ = self.residuals(rows, own)
        m = R.shape[1]
        Rp, Rm = R[: K * n].reshape(K, n, m), R[K * n :].reshape(K, n, m)
        Vp, Vm = V[: K * n].reshape(K, n, -1), V[K * n :].reshape(K, n, -1)
        sp = np.all(Vp == V0[:, None], axis=2)
        sm = np.all(Vm == V0[:, None], axis=2)
        zi, ui, di = Z, up, dn
        central = sp & sm & (ui > di)
        fwd = sp & ~central & (ui > zi)
        bwd = sm & ~central & ~fwd & (di < zi)

        def safe(x: Array) -> Array:
            nonzero: Array = np.where(x != 0, x, 1.0)
            return nonzero

        J = np.where(
            central[..., None],
            (Rp - Rm) / safe(ui - di)[..., None],
            np.where(
                fwd[..., None],
                (Rp - R0[:, None]) / safe(ui - zi)[..., None],
                np.where(bwd[..., None], (R0[:, None] - Rm) / safe(zi - di)[..., None], 0.0),
            ),
        )
        jacobians: Array = np.swapaxes(J, 1, 2)
        return jacobians

    def levenberg_marquardt(self, iterations: int) -> None:
        """Advance every start by Levenberg–Marquardt steps with geodesic acceleration,
        projected onto the bounds, evaluating all starts together.

        The optima of path synthesis often lie at the end of long curved valleys (near a
        change point, a cusp, a straight stretch of the curve), where plain Gauss–Newton steps
        are cut short by the curvature. The second-order correction along the step (M. K.
        Transtrum & J. P. Sethna, "Improvements to the Levenberg–Marquardt algorithm for
        nonlinear least-squares minimization", arXiv:1201.5885, 2012) follows the valley at
        the price of one more batched evaluation per iteration. Damping is Marquardt's
        diagonal scaling, raised ×4 on a rejected step and lowered ÷3 on an accepted one.
        """
        Z = self.x0.copy()
        K, n = Z.shape
        owner = np.arange(K)
        R, V, err, ok = self.residuals(Z, owner)
        cost = self._note(Z, owner, R, err, ok)
        lam = np.full(K, 1e-3)
        J = self._jacobians(Z, owner, R, V)
        live = np.ones(K, bool)
        eye = np.eye(n)
        for _ in range(iterations):
            if time.perf_counter() > self.deadline or not live.any() or self.reached():
                break
            rows = np.flatnonzero(live)
            Jr, Rr, Zr = J[rows], R[rows], Z[rows]
            A = np.einsum("kmi,kmj->kij", Jr, Jr)
            g = np.einsum("kmi,km->ki", Jr, Rr)
            d = np.diagonal(A, axis1=1, axis2=2)
            d = np.maximum(d, 1e-12 * np.max(d, axis=1, keepdims=True) + 1e-300)
            M = A + (lam[rows][:, None] * d)[:, :, None] * eye
            v = -solve_batched(M, g)
            # Second directional derivative of the residuals along v, by one more evaluation.
            h = GEODESIC_STEP
            Rh = self.residuals(np.clip(Zr + h * v, self.lo, self.hi), rows)[0]
            rvv = (2.0 / h) * ((Rh - Rr) / h - np.einsum("kmi,ki->km", Jr, v))
            acc = -solve_batched(M, np.einsum("kmi,km->ki", Jr, rvv))
            size_v = np.sqrt(np.sum(d * v * v, axis=1))
            size_a = np.sqrt(np.sum(d * acc * acc, axis=1))
            # Where the correction is large against the step the valley bends too sharply for
            # it: take the plain step.
            bend = np.isfinite(size_a) & (2.0 * size_a <= GEODESIC_RATIO * size_v)
            step = np.where(bend[:, None], v + 0.5 * acc, v)
            trial = np.clip(Zr + step, self.lo, self.hi)
            Rt, Vt, et, okt = self.residuals(trial, rows)
            ct = self._note(trial, rows, Rt, et, okt)
            accept = np.isfinite(ct) & (ct < cost[rows])
            small = np.abs(cost[rows] - ct) <= 1e-15 * cost[rows] + 1e-300
            acc_rows = rows[accept]
            Z[acc_rows], R[acc_rows], V[acc_rows], cost[acc_rows] = (
                trial[accept],
                Rt[accept],
                Vt[accept],
                ct[accept],
            )
            lam[acc_rows] = np.maximum(lam[acc_rows] / 3.0, 1e-12)
            lam[rows[~accept]] *= 4.0
            live[rows[(lam[rows] > 1e10) | (accept & small)]] = False
            if acc_rows.size:
                J[acc_rows] = self._jacobians(Z[acc_rows], acc_rows, R[acc_rows], V[acc_rows])

    def reached(self) -> bool:
        """Whether some start's best feasible point already fits to the goal."""
        return bool(np.any(self.best_err <= self.goal))

    def polish(self, k: int, max_nfev: int = 200) -> None:
        """Finish start k with :func:`scipy.optimize.least_squares` (trust region, bounds)."""
        owner = np.array([k])
        cache: dict[bytes, tuple[Array, NDArray[np.bool_]]] = {}

        def evaluate(z: Array) -> tuple[Array, NDArray[np.bool_]]:
            key = z.tobytes()
            if key not in cache:
                if time.perf_counter() > self.deadline:
                    raise OutOfTime
                R, V, err, ok = self.residuals(z[None], owner)
                self._note(z[None], owner, R, err, ok)
                cache.clear()
                cache[key] = (R[0], V[0])
            return cache[key]

        def jac(z: Array) -> Array:
            r, v = evaluate(z)
            jacobian: Array = self._jacobians(z[None], owner, r[None], v[None])[0]
            return jacobian

        with contextlib.suppress(OutOfTime):
            least_squares(
                lambda z: evaluate(z)[0],
                self.best_z[k] if np.isfinite(self.best_obj[k]) else self.x0[k],
                jac=jac,
                bounds=(self.lo, self.hi),
                x_scale="jac",
                ftol=1e-15,
                xtol=1e-15,
                gtol=1e-15,
                max_nfev=max_nfev,
            )

    def candidate(self, k: int) -> Candidate | None:
        if not np.isfinite(self.best_obj[k]):
            return None
        pose, shape, rel = self.decode(self.best_z[k][None], np.array([k]))
        pose = pose[0].copy()
        if not self.sphere:
            pose[2] = wrap_angle(pose[2])
        periodic = self.p.model.periodic
        rel = rel[0]
        if self.p.timing != "prescribed" or self.p.free_start:
            # Where the inputs start is found, not given: report it in the first period (the
            # refinement lets it wander by whole turns, which change nothing).
            rel = rel - self.p.period * np.floor(rel[0] / self.p.period)
        return Candidate(
            float(self.best_err[k]),
            float(self.best_obj[k]),
            pose,
            {n: float(wrap_angle(v[0]) if n in periodic else v[0]) for n, v in shape.items()},
            float(self.assembly[k]),
            rel,
        )
