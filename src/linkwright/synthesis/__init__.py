"""Synthesis: from what a designer wants (an ellipse, a path, target coefficients, precision
points) to the dimensions of a linkage.

Each route lives in its own module and returns mechanisms (immutable values of
:mod:`linkwright.mechanisms`) with the error it reached; turning them into documents and
printing them is the job of the layers above (``io`` and the command line). Long searches take
an optional ``progress`` callable, called with the fraction done in [0, 1].
"""
