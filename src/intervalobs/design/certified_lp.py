"""Moved to :mod:`intervalobs.lp.certified`; a name read from here warns, and this module goes in the next release.

.. deprecated:: 0.2.0
   Import from :mod:`intervalobs.lp.certified`.
"""

from __future__ import annotations

import warnings
from typing import Any

from ..lp import certified as _moved

__all__ = list(_moved.__all__)


def __getattr__(name: str) -> Any:
    """The object of :mod:`intervalobs.lp.certified`, with a ``FutureWarning``."""
    if name not in __all__:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    warnings.warn("intervalobs.design.certified_lp has moved to intervalobs.lp.certified", FutureWarning, stacklevel=2)
    return getattr(_moved, name)
