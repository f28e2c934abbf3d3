"""
Paper 004: the double slider's ellipse, and back
================================================

Kiper, Akbalçık and Şen show that the coupler point of a double slider traces an ellipse
(eqs. 1–5), and synthesise a double slider for a given ellipse (section 4).
:mod:`linkwright.papers.p004` checks the analysis on random double sliders; here the
synthesis runs on points traced by one double slider: an ellipse is fitted to them, and
Archimedes' trammel for that ellipse is built and simulated again.
"""

import numpy as np

import linkwright as lw
from linkwright.papers import p004
from linkwright.synthesis import doubleslider_from_ellipse, fit_ellipse

check = p004.forward_check(count=1000, samples=32)
print("1000 random double sliders, largest residual of eq. 3:", check["conic_residual"])

# %%
# Points of the paper's pictured double slider (α = 70°, h = 0.5), fitted and synthesised.
pictured = lw.DoubleSlider(M=[1, 2], alpha=np.radians(70), beta=np.radians(20), p=2, q=1, h=0.5)
points = lw.circuit(pictured, 60).positions["P"]
fit = fit_ellipse(points)
trammel = doubleslider_from_ellipse(fit.coeffs)
print("fit residual (RMS):", fit.rms)

# %%
# The trammel's own curve lies on the fitted ellipse: the conic A·x² + B·xy + C·y² + D·x +
# E·y + F (normalised by eq. 10) vanishes at every point it traces.
x, y = lw.circuit(trammel, 120).positions["P"].T
A_, B_, C_, D_, E_, F_ = fit.coeffs
print(
    "largest conic residual:",
    float(np.max(np.abs(A_ * x**2 + B_ * x * y + C_ * y**2 + D_ * x + E_ * y + F_))),
)
print("semi-axes of the trammel, p and |q|:", float(trammel.p), abs(float(trammel.q)))

# %%
fig = lw.plot_mechanism(trammel, samples=240, title="paper 004: the trammel of the ellipse")
