"""
Spherical Stephenson III six-bar
================================

Paper 001's spherical Stephenson III (the bundled ``paper001-stephenson3`` example), driven at
AB: a four-bar ABCD whose ternary coupler carries E, and a dyad EFG. Driven at AB it has at
most 2 × 2 = 4 configurations at an input; :func:`~linkwright.mechanisms.configurations`
lists them.
"""

import numpy as np

import linkwright as lw

document = lw.load_example("paper001-stephenson3")
six = document.mechanism
print(document.title)

# %%
# Every real assembly at θ = 40°, each with its assembly signs.
for signs, motion in lw.configurations(six, np.radians([40.0])):
    print("assembly signs", signs, " F =", motion.positions["F"][0].round(4))

# %%
fig = lw.plot_mechanism(six, samples=240, title=document.title)
