"""
Slider-crank
============

An offset slider-crank: the crank A0A turns, the rod AB drives the slider B along a line
through ``line_point`` at ``line_angle``; a point on the rod traces the coupler curve.
"""

import numpy as np

import linkwright as lw

slider = lw.SliderCrank(
    A0=[0, 0], crank=1, rod=3.5, line_point=[0, -0.5], line_angle=0.0, u=1.5, v=0.6
)
print(lw.classify(slider))

# %%
# The slider stays on its line and the rod keeps its length over the whole turn.
motion = lw.circuit(slider, 180)
A, B = motion.positions["A"], motion.positions["B"]
print("rod length error:", float(np.max(np.abs(np.hypot(*(B - A).T) - 3.5))))
print("slider off its line:", float(np.max(np.abs(B[:, 1] + 0.5))))
print("stroke:", float(np.ptp(B[:, 0])))

# %%
fig = lw.plot_mechanism(slider, at=np.radians(45), samples=240, title="offset slider-crank")
