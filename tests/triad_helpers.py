"""Comparing linkages with triads configuration by configuration.

A triad's pose index names a pose by its slot in an order (the body's rotation, or J2's angle on
its circle) that depends on how the triad is written: the same mechanism written from another
joint of its ternary link numbers its poses differently. So two constructions are compared as
sets: at every input, the same number of real configurations, and each configuration of one
within a tolerance of a configuration of the other (matched one to one).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from linkwright.mechanisms import Mechanism, configurations


def configuration_sets(
    mech: Mechanism, inputs: ArrayLike, joints: Sequence[str]
) -> list[np.ndarray]:
    """At each input, every real configuration as one row of ``joints``' coordinates."""
    found = configurations(mech, inputs, order=0)
    theta = np.atleast_1d(np.asarray(inputs, dtype=float))
    out = []
    for i in range(theta.size):
        rows = [
            np.concatenate([motion.positions[j][i] for j in joints])
            for _, motion in found
            if motion.valid[i]
        ]
        width = sum(found[0][1].positions[j].shape[-1] for j in joints) if found else 0
        out.append(np.array(rows).reshape(len(rows), width))
    return out


def assert_same_configurations(
    ours: Mechanism,
    theirs: Mechanism,
    inputs: ArrayLike,
    joints: Sequence[str],
    tol: float,
    *,
    shift: float = 0.0,
) -> int:
    """Every input has as many real configurations in both, matched one to one within ``tol``
    (largest coordinate difference); ``theirs`` is solved at ``inputs + shift``. Returns how
    many configurations were compared."""
    theta = np.atleast_1d(np.asarray(inputs, dtype=float))
    a = configuration_sets(ours, theta, joints)
    b = configuration_sets(theirs, theta + shift, joints)
    compared = 0
    for i, (x, y) in enumerate(zip(a, b, strict=True)):
        assert len(x) == len(y), (float(theta[i]), len(x), len(y))
        left = list(range(len(y)))
        for row in x:
            gaps = [float(np.max(np.abs(row - y[k]))) for k in left]
            best = int(np.argmin(gaps))
            assert gaps[best] <= tol, (float(theta[i]), gaps[best])
            left.pop(best)
            compared += 1
    return compared
