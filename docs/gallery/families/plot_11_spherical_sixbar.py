"""
Spherical six-bar
=================

Paper 000's Fig. 8: a spherical four-bar whose coupler point drives a second dyad (the bundled
``paper000-fig8-sixbar`` example). The same construction plan as in the plane, with spherical
steps: a dyad joint is where two small circles on the sphere meet.
"""

import numpy as np

import linkwright as lw

document = lw.load_example("paper000-fig8-sixbar")
six = document.mechanism
print(document.title)
print(
    "arcs (degrees):",
    {
        k: round(float(np.degrees(getattr(six, k))), 2)
        for k in ("frame", "crank", "coupler", "rocker", "link5", "link6")
    },
)

# %%
motion = lw.circuit(six, 240)
worst = max(float(np.nanmax(np.abs(r))) for r in six.residuals(motion).values())
print("samples:", motion.input.size, " largest constraint residual:", worst)

# %%
fig = lw.plot_mechanism(six, samples=240, title=document.title)
