"""
Spherical four-bar
==================

On the sphere every joint is the unit vector of its axis and every link an arc (radians inside
the library, degrees in documents). This is paper 000's Fig. 6 crank-rocker: frame, crank,
coupler and rocker arcs 40°, 20°, 45°, 35°, and a coupler point at arc AC = 50°, angle
μ = 130° from AB.
"""

import numpy as np

import linkwright as lw

fig6 = lw.SphericalFourBar(*np.radians([40, 20, 45, 35, 50, 130]))
print(lw.classify(fig6))

# %%
# Every traced point is a unit vector, and the coupler keeps its arc.
motion = lw.circuit(fig6, 240)
A, B, P = (motion.positions[k] for k in ("A", "B", "P"))
print("largest | |P| − 1 |:", float(np.max(np.abs(np.linalg.norm(P, axis=1) - 1))))
arc_AB = np.degrees(np.arccos(np.clip(np.sum(A * B, axis=1), -1, 1)))
print("coupler arc (degrees), min and max:", float(arc_AB.min()), float(arc_AB.max()))

# %%
# The sphere and a Lambert equal-area map of the curves.
fig = lw.plot_mechanism(fig6, samples=240, title="paper 000, Fig. 6")

# %%
# The angles against the input: output, transmission angle and paper 003's normal and
# tangential pressure angles.
angles = lw.plot_diagram(fig6, "angles", samples=240)
