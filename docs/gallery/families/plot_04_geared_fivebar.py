"""
Geared five-bar
===============

Paper 002's geared five-bar: two cranks coupled by gears (here equal speeds in opposite
senses, ``ratio=-1``) and a dyad A–C–B between them. This one locks: its input oscillates
between two locking positions, which :func:`~linkwright.mechanisms.input_range` finds as
exact roots, and the circuit runs up one branch and back on the other.
"""

import numpy as np

import linkwright as lw

five = lw.GearedFiveBar(
    A0=[0, 0],
    B0=[3, 0],
    crank1=1,
    crank2=1.5,
    link1=2,
    link2=2.5,
    ratio=-1,
    phase2=np.pi,
    u=4,
    v=0.5,
)
arcs = lw.input_range(five)
# One arc here; the arrays have room for as many as a linkage has (unused ones are NaN).
lo, hi = arcs.lo[np.isfinite(arcs.lo)], arcs.hi[np.isfinite(arcs.hi)]
print("input range (degrees):", np.degrees(lo).round(3), "to", np.degrees(hi).round(3))

# %%
# At a locking position the dyad is stretched straight: |A − B| = link1 + link2 (or folded).
path = lw.circuit(five, 360)
A, B = path.positions["A"], path.positions["B"]
print("largest |A − B| on the circuit:", float(np.max(np.hypot(*(A - B).T))), "≤", 2 + 2.5)

# %%
fig = lw.plot_mechanism(five, samples=240, title="geared five-bar that locks")
