"""Moved to :mod:`intervalobs.lp.certified`; this name warns and goes in the next release.

.. deprecated:: 0.2.0
   Import from :mod:`intervalobs.lp.certified`.
"""

from __future__ import annotations

import warnings

from ..lp.certified import (
    FEASIBILITY_TOLERANCE,
    INNER_SHRINK,
    DenseLP,
    dual_bounds,
    highs_model,
    new_highs,
    run_highs,
    shrink_inward,
)

__all__ = [
    "FEASIBILITY_TOLERANCE",
    "INNER_SHRINK",
    "DenseLP",
    "dual_bounds",
    "highs_model",
    "new_highs",
    "run_highs",
    "shrink_inward",
]

warnings.warn("intervalobs.design.certified_lp has moved to intervalobs.lp.certified", FutureWarning, stacklevel=2)
