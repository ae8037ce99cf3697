"""Model classes, one module per kind of model; every shape and bound is validated on construction."""

from .bounds import Bounds, ResolvedBounds
from .continuous_nonlinear import ContinuousNonlinearSystem
from .flow_enclosure import FlowEnclosure, StateZonotope, flow_enclosure
from .lpv import LPVSystem, SampledLPVModel, StepEnclosure
from .lti import LTISystem
from .nonlinear import NonlinearSystem
from .reaction import ReactionSystem
from .sampled import SampledSystem
from .sampling import DeltaLinearisation, SampledModel, delta_linearisation, sampled_model

__all__ = [
    "Bounds",
    "ContinuousNonlinearSystem",
    "DeltaLinearisation",
    "FlowEnclosure",
    "LPVSystem",
    "LTISystem",
    "NonlinearSystem",
    "ReactionSystem",
    "ResolvedBounds",
    "SampledLPVModel",
    "SampledModel",
    "SampledSystem",
    "StateZonotope",
    "StepEnclosure",
    "delta_linearisation",
    "flow_enclosure",
    "sampled_model",
]
