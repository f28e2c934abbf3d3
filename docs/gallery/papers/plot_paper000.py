"""
Paper 000: coupler points of spherical mechanisms
=================================================

Özçelik & Şaka find a coupler point C of a spherical link AB (arc AC, angle μ = BAC) as the
solution of three linear equations (their eqs. 6–13, Cramer's rule). linkwright places the same
point another way: it turns the great circle A→B about OA by μ and walks the arc AC from A.
:mod:`linkwright.papers.p000` implements the paper's own system from the printed formulas;
here the two ways are compared over the whole circuit of Fig. 7's drag link, and the linkage
is drawn. ``linkwright papers 000`` regenerates all three figures.
"""

import numpy as np

import linkwright as lw
from linkwright.papers import p000

drag_link = p000.figure_fourbar(7)
print(lw.classify(drag_link))

# %%
# The paper's eq. 13 against linkwright's coupler point, at every sample of the circuit.
motion = lw.circuit(drag_link, 180)
A, B, P = (motion.positions[k] for k in ("A", "B", "P"))
C = p000.eq13_coupler_point(A, B, drag_link.coupler, drag_link.point_arc, drag_link.point_angle)
print("largest distance between the two:", float(np.nanmax(np.linalg.norm(C - P, axis=-1))))

# %%
# Every figure of the paper, both assembly modes: the largest difference per case.
for check in p000.point_checks(90):
    print(f"{check.case:32} {check.point}: {check.better:.1e}")

# %%
fig = lw.plot_mechanism(drag_link, samples=240, title="paper 000, Fig. 7")
