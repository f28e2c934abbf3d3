"""
Composed linkage: Jansen's leg
==============================

Any linkage built joint by joint: fixed pivots, a crank, and dyads each placed from two joints
already known. This is Theo Jansen's Strandbeest leg with his "holy numbers" (the bundled
``jansen-leg`` example): one crank, seven dyads, 8 links and 10 pins, one degree of freedom.
"""

import numpy as np

import linkwright as lw

leg = lw.Linkage(
    joints=(
        lw.FixedJoint("O", at=[0, 0]),
        lw.FixedJoint("B", at=[-38, -7.8]),
        lw.CrankJoint("A", pivot="O", length=15),
        lw.DyadJoint("C", p1="A", r1=50, p2="B", r2=41.5, assembly=-1),
        lw.DyadJoint("D", p1="B", r1=40.1, p2="C", r2=55.8),
        lw.DyadJoint("E", p1="A", r1=61.9, p2="B", r2=39.3),
        lw.DyadJoint("F", p1="D", r1=39.4, p2="E", r2=36.7, assembly=-1),
        lw.DyadJoint("G", p1="E", r1=49, p2="F", r2=65.7),
    ),
    traced="G",
)
print(leg == lw.load_example("jansen-leg").mechanism)

# %%
# The foot G over one turn of the crank: its path assembles everywhere, and its flat bottom
# is what makes the leg walk. The lowest 40 % of the turn keeps the foot within a narrow band.
foot = lw.circuit(leg, 360).positions["G"]
low = np.sort(foot[:, 1])[: int(0.4 * len(foot))]
print("foot path height:", float(np.ptp(foot[:, 1])))
print("height band of its lowest 40 %:", float(np.ptp(low)))

# %%
fig = lw.plot_mechanism(leg, at=np.radians(30), samples=240, title="Jansen's leg")
