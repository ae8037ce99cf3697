"""The LP layer: every linear programme of the package, solved and certified in one place.

:mod:`~intervalobs.lp.certified` turns any solver's multipliers into bounds by weak duality (the only thing that
decides soundness); :mod:`~intervalobs.lp.dense_simplex` is the simplex of our own that solves a chain of
objectives over one feasible set. No other module of the package imports ``highspy``.
"""
