"""
Paper 002: the geared five-bar with a rotation constraint
=========================================================

Abhyankar & Gajjal draw a geared five-bar whose cranks turn at equal speeds in opposite
senses, then move its fixed pivot 1 step by step (the cranks and the traced point kept, the
links following) and show how the curve changes. The paper prints no dimensions, so
:mod:`linkwright.papers.p002` regenerates the study for a drawing of its own. Beyond some step
the linkage locks and only oscillates; the study reports where.
"""

from matplotlib.figure import Figure

import linkwright as lw
from linkwright.papers import p002

steps = p002.pivot_study(count=3)
for step in steps:
    link1 = float(step.mechanism.link1)
    print(
        f"step {step.steps}: pivot moved by {step.offset}, link1 = {link1:.4f},"
        f" turns fully: {step.turns_fully}"
    )

# %%
# The drawing itself, as ``linkwright plot`` draws it.
fig = lw.plot_mechanism(steps[0].mechanism, samples=240, title="paper 002: the drawing")

# %%
# The traced point's curve at each step of the study, overlaid.
study = Figure(figsize=(6, 5), layout="constrained")
ax = study.add_subplot()
for step in steps:
    x, y = lw.circuit(step.mechanism, 240).positions["P"].T
    ax.plot(x, y, lw=1.2, label=f"pivot moved {step.offset[0]:+.1f}")
ax.set_aspect("equal")
ax.legend()
ax.set_title("the curve as pivot 1 moves left")
