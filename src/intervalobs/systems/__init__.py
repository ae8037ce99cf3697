"""Model classes, one module per kind of model; every shape and bound is validated on construction."""

from .bounds import Bounds, ResolvedBounds
from .lpv import LPVSystem, SampledLPVModel, StepEnclosure
from .lti import LTISystem
from .nonlinear import NonlinearSimulation, NonlinearSystem, simulate_nonlinear
from .sampled import SampledSimulation, SampledSystem, simulate_sampled
from .sampling import SampledModel, sampled_model

__all__ = [
    "Bounds",
    "LPVSystem",
    "LTISystem",
    "NonlinearSimulation",
    "NonlinearSystem",
    "ResolvedBounds",
    "SampledLPVModel",
    "SampledModel",
    "SampledSimulation",
    "SampledSystem",
    "StepEnclosure",
    "sampled_model",
    "simulate_nonlinear",
    "simulate_sampled",
]
