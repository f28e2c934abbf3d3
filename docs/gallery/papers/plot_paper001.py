"""
Paper 001: configurations of the spherical Stephenson III
=========================================================

Zong, Lu, An and Zhang eliminate the position equations of the spherical Stephenson III down
to a degree-8 polynomial and conclude that it has "at most 8" configurations for input AB.
Driven at AB one rigid coupler has at most 2 × 2 = 4: the paper's 8 counts the mirror-image
coupler too. Eight genuine configurations occur when it is driven at FG, where the coupler is
a spherical triad. :mod:`linkwright.papers.p001` finds them all, and this example counts them
over the input for both drives. ``linkwright papers 001`` writes the tables and figures.
"""

from matplotlib.figure import Figure

from linkwright.papers import p001

# %%
# The eight configurations of the paper's example mechanism driven at FG, at θ6 = 280°, each
# satisfying the constraints to rounding.
for row in p001.configuration_table():
    print(f"θ1 = {row['theta1']:9.3f}°  θ4 = {row['theta4']:9.3f}°  residual {row['residual']:.1e}")

# %%
# How many real configurations there are at each input, driven at AB and at FG.
sweep = p001.count_sweep(180)
fig = Figure(figsize=(7, 3.2), layout="constrained")
ax = fig.add_subplot()
ax.step(sweep["input"], sweep["fg"], where="mid", label="driven at FG (a triad)")
ax.step(sweep["input"], sweep["ab"], where="mid", label="driven at AB")
ax.set(xlabel="input angle (degrees)", ylabel="real configurations", yticks=range(0, 9, 2))
ax.legend(loc="lower right")
ax.grid(True, lw=0.4, alpha=0.5)
print("most at AB:", int(sweep["ab"].max()), " most at FG:", int(sweep["fg"].max()))
