"""Model classes, one module per kind of model; every shape and bound is validated on construction."""

from .lti import Bounds, LTISystem

__all__ = ["Bounds", "LTISystem"]
