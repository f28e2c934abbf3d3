"""
Four-bar
========

The crank-rocker of paper 003, Table 1: crank 1, coupler 5, rocker 6.02, frame 3.5. Grashof
with the crank shortest, so the crank turns fully and the rocker swings. The coupler point
(u, v) = (2.5, 1.5) is measured in the coupler's frame (origin A, x along A→B).
"""

import numpy as np

import linkwright as lw

crank_rocker = lw.FourBar(A0=[0, 0], B0=[3.5, 0], crank=1, coupler=5, rocker=6.02, u=2.5, v=1.5)
print(lw.classify(crank_rocker))

# %%
# Solve it over a whole turn of the crank: positions, and their first and second derivatives
# with respect to the input angle (radians). The coupler keeps its length at every sample.
motion = lw.solve(crank_rocker, np.radians(np.arange(0, 360, 5)))
A, B = motion.positions["A"], motion.positions["B"]
print("valid everywhere:", bool(motion.valid.all()))
print("largest coupler-length error:", float(np.max(np.abs(np.hypot(*(B - A).T) - 5))))

# %%
# The picture: the linkage at 60°, its coupler curves in both assembly modes, the dead centres
# and the transmission-angle extremes.
fig = lw.plot_mechanism(crank_rocker, at=np.radians(60), samples=240, title="crank-rocker")

# %%
# Its motion diagrams: output angle and transmission angle against the input.
angles = lw.plot_diagram(crank_rocker, "angles", samples=240)
