"""
Paper 003: kinematic coefficients of four-bars
==============================================

Dzhavakhyan, Makhsudyan and Arakelyan rate four-bars by the coefficients Kω, Kε and Kp = Kω·Kε
of their output's speed and acceleration, and δ, the spread of the velocity ratio. Their
Table 4 lists double cranks with frame L4 = 1; here each row is recomputed exactly with
:func:`linkwright.analysis.coefficients` beside the printed values. ``linkwright papers 003``
compares every cell of Tables 1–4, planar and spherical, judging each printed value at its own
precision and at the precision of its printed inputs (L3 is printed to two decimals).
"""

import numpy as np

import linkwright as lw
from linkwright.analysis import coefficients
from linkwright.papers.p003 import TABLE4

print("  L2   L1    L3  |  Kω printed/ours  |  Kε printed/ours  |  δ printed/ours")
for L2, L1, L3, k_omega, k_eps, _k_p, delta, _nu in TABLE4[:6]:
    exact_L3 = np.sqrt(1 + L1**2 - L2**2)  # the table's L3, before rounding
    linkage = lw.FourBar(A0=[0, 0], B0=[1, 0], crank=L1, coupler=L2, rocker=exact_L3)
    k = coefficients(linkage)
    print(
        f"{L2:4} {L1:4} {L3:>5} | {k_omega:>5} {float(k['K_omega']):.4f} |"
        f" {k_eps:>5} {float(k['K_epsilon']):.4f} | {delta:>5} {float(k['delta']):.4f}"
    )

# %%
# The first row's coefficients over the cycle, with their exact maxima marked.
first = lw.FourBar(A0=[0, 0], B0=[1, 0], crank=4, coupler=2, rocker=np.sqrt(13))
fig = lw.plot_diagram(first, "coefficients", samples=240, title="paper 003, Table 4, first row")
