"""
Double slider
=============

Paper 004's double slider (Kiper, Akbalçık, Şen): two sliders on guides at angles α and β
through M, and a coupler point P at (p, q, h). Its coupler point traces an ellipse (eq. 3 of
the paper), which :func:`linkwright.analysis.doubleslider_conic` gives in closed form.
"""

import numpy as np

import linkwright as lw
from linkwright.analysis import doubleslider_conic

trammel = lw.DoubleSlider(M=[1, 2], alpha=np.radians(70), beta=np.radians(20), p=2, q=1, h=0.5)

# %%
# Every traced point satisfies the conic A·x² + B·xy + C·y² + D·x + E·y + F = 0.
A_, B_, C_, D_, E_, F_ = doubleslider_conic(trammel)
x, y = lw.circuit(trammel, 120).positions["P"].T
residual = A_ * x**2 + B_ * x * y + C_ * y**2 + D_ * x + E_ * y + F_
print("conic coefficients:", np.round(doubleslider_conic(trammel), 4))
print("largest conic residual on the traced curve:", float(np.max(np.abs(residual))))

# %%
fig = lw.plot_mechanism(trammel, samples=240, title="double slider")
