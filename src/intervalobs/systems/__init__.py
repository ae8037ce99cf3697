"""Model classes, one module per kind of model; every shape and bound is validated on construction."""

from .bounds import Bounds, ResolvedBounds
from .lpv import LPVSystem, SampledLPVModel, StepEnclosure
from .lti import LTISystem
from .nonlinear import NonlinearSystem
from .sampled import SampledSystem
from .sampling import DeltaLinearisation, SampledModel, delta_linearisation, sampled_model

__all__ = [
    "Bounds",
    "DeltaLinearisation",
    "LPVSystem",
    "LTISystem",
    "NonlinearSystem",
    "ResolvedBounds",
    "SampledLPVModel",
    "SampledModel",
    "SampledSystem",
    "StepEnclosure",
    "delta_linearisation",
    "sampled_model",
]
