"""
Stephenson III six-bar
======================

The bundled example ``stephenson3-example``, loaded as a document (the same file
``linkwright plot`` reads). A six-bar is a four-bar with a second dyad; both dyads keep their
link lengths at every sample of the circuit.
"""

import numpy as np

import linkwright as lw

document = lw.load_example("stephenson3-example")
six = document.mechanism
print(document.title)
print(six)

# %%
# The circuit of the traced point, and how well every sample satisfies the link lengths
# (each family knows its own constraints: ``residuals``).
motion = lw.circuit(six, 240)
worst = max(float(np.nanmax(np.abs(r))) for r in six.residuals(motion).values())
print("samples:", motion.input.size, " largest constraint residual:", worst)

# %%
fig = lw.plot_mechanism(six, samples=240, title=document.title)
