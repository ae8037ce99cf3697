"""Model classes, one module per kind of model; every shape and bound is validated on construction."""

from .lti import Bounds, LTISystem
from .sampled import SampledSimulation, SampledSystem, simulate_sampled

__all__ = ["Bounds", "LTISystem", "SampledSimulation", "SampledSystem", "simulate_sampled"]
