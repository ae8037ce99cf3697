"""Model classes, one module per kind of model; every shape and bound is validated on construction."""

from .lpv import LPVSystem, SampledLPVModel, StepEnclosure
from .lti import Bounds, LTISystem
from .sampled import SampledSimulation, SampledSystem, simulate_sampled

__all__ = [
    "Bounds",
    "LPVSystem",
    "LTISystem",
    "SampledLPVModel",
    "SampledSimulation",
    "SampledSystem",
    "StepEnclosure",
    "simulate_sampled",
]
