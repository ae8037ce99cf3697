"""Moved to :mod:`intervalobs.lp.dense_simplex`; this name warns and goes in the next release.

.. deprecated:: 0.2.0
   Import from :mod:`intervalobs.lp.dense_simplex`.
"""

from __future__ import annotations

import warnings

from ..lp.dense_simplex import DenseSimplex, load_kernels

__all__ = ["DenseSimplex", "load_kernels"]

warnings.warn("intervalobs.design.dense_simplex has moved to intervalobs.lp.dense_simplex", FutureWarning, stacklevel=2)
