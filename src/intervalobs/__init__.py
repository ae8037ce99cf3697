"""intervalobs: guaranteed interval estimation for uncertain dynamical systems."""

from .complex_interval import cabs, ctimes, linear_image
from .design.abstraction import AffineAbstraction, affine_abstraction
from .design.differentiator import HOSMDifferentiator, difference_derivative_bounds, levant_gains
from .design.gsisio import gsisio_design
from .design.high_gain import ThetaDesign, theta_design
from .design.hinf import GainDesign, hinf_gain, zonotope_size_gain
from .design.lpv import CertifiedVertexBounds, boundedness_lmi, certify_vertex_extremes, verify_boundedness
from .design.mixed_monotone import JacobianDecomposition, VertexDecomposition, jacobian_bounds
from .design.regions import Disk, RegionPlacement, place_in_disks
from .design.uio import check_cooperative, design_uio_coordinates, uio_decoupling
from .diagnosis import isolation_outcome, psi_hat, run_campaign, runs_for_sigma
from .errors import (
    ArgumentError,
    ArgumentTypeError,
    AssumptionError,
    BoundsError,
    DataError,
    DesignError,
    DimensionError,
    DivergenceWarning,
    FileError,
    InconsistentDataError,
    IntervalObserverError,
    SchedulerError,
)
from .estimate import EnclosureReport, Estimate
from .front_door import observe, suggest
from .interval import Box as Box  # former name of Interval, kept importable (not in __all__)
from .interval import Interval, interval_matvec_bounds, matvec_bounds, neg, pos
from .observers import HighGainIntervalObserver, IntervalObserver, Observer, ObserverState
from .observers.continuous_nonlinear import ContinuousNonlinearObserver
from .observers.fir import FiniteMemoryObserver
from .observers.gsisio import GSISIO
from .observers.hull import HullEstimator
from .observers.intersection import IntersectionObserver
from .observers.lpv import LPVIntervalObserver, LPVIntervalUIO
from .observers.null_space_gsisio import NullSpaceGSISIO
from .observers.reaction_invariant import ReactionInvariantObserver
from .observers.robust_fir import RobustFiniteMemoryObserver
from .observers.robust_hull import RobustHullEstimator
from .observers.unknown_input import UnknownInputIntervalObserver
from .observers.zonotopic import IntegratedObserver, ZonotopicObserver
from .simulate import Simulation, simulate, simulate_nonlinear, simulate_sampled
from .systems import (
    Bounds,
    DeltaLinearisation,
    LTISystem,
    ResolvedBounds,
    SampledModel,
    SampledSystem,
    delta_linearisation,
    sampled_model,
)
from .systems.continuous_nonlinear import ContinuousNonlinearSystem
from .systems.flow_enclosure import FlowEnclosure, flow_enclosure
from .systems.lpv import LPVSystem
from .systems.nonlinear import NonlinearSystem
from .systems.reaction import ReactionSystem
from .tightness import (
    HullLowerBound,
    format_tightness,
    hull_lower_bound,
    robust_hull_lower_bound,
    tightness_reference,
    tightness_report,
)
from .zonotope import Zonotope

__version__ = "0.1.0"

__all__ = [
    "ArgumentError",
    "ArgumentTypeError",
    "AssumptionError",
    "Bounds",
    "BoundsError",
    "DataError",
    "DeltaLinearisation",
    "DesignError",
    "DimensionError",
    "Disk",
    "DivergenceWarning",
    "EnclosureReport",
    "Estimate",
    "FileError",
    "FiniteMemoryObserver",
    "HighGainIntervalObserver",
    "HullEstimator",
    "HullLowerBound",
    "InconsistentDataError",
    "IntersectionObserver",
    "IntervalObserver",
    "IntervalObserverError",
    "LTISystem",
    "Observer",
    "ObserverState",
    "RegionPlacement",
    "ResolvedBounds",
    "RobustFiniteMemoryObserver",
    "RobustHullEstimator",
    "SampledModel",
    "SampledSystem",
    "SchedulerError",
    "Simulation",
    "ThetaDesign",
    "__version__",
    "cabs",
    "ctimes",
    "delta_linearisation",
    "format_tightness",
    "hull_lower_bound",
    "interval_matvec_bounds",
    "linear_image",
    "matvec_bounds",
    "neg",
    "place_in_disks",
    "pos",
    "robust_hull_lower_bound",
    "sampled_model",
    "simulate",
    "simulate_sampled",
    "theta_design",
    "tightness_reference",
    "tightness_report",
]

# seed 002
__all__ += ["GainDesign", "IntegratedObserver", "Zonotope", "ZonotopicObserver", "hinf_gain", "zonotope_size_gain"]

# seed 000
__all__ += [
    "HOSMDifferentiator",
    "UnknownInputIntervalObserver",
    "check_cooperative",
    "design_uio_coordinates",
    "difference_derivative_bounds",
    "levant_gains",
    "uio_decoupling",
]

# seed 001

__all__ += [
    "CertifiedVertexBounds",
    "LPVIntervalObserver",
    "LPVIntervalUIO",
    "LPVSystem",
    "boundedness_lmi",
    "certify_vertex_extremes",
    "isolation_outcome",
    "psi_hat",
    "run_campaign",
    "runs_for_sigma",
    "verify_boundedness",
]

# seed 003

__all__ += [
    "GSISIO",
    "AffineAbstraction",
    "Interval",
    "JacobianDecomposition",
    "NonlinearSystem",
    "NullSpaceGSISIO",
    "VertexDecomposition",
    "affine_abstraction",
    "gsisio_design",
    "jacobian_bounds",
    "simulate_nonlinear",
]

# issue 32: continuous-time nonlinear systems

__all__ += [
    "ContinuousNonlinearObserver",
    "ContinuousNonlinearSystem",
    "FlowEnclosure",
    "flow_enclosure",
]

# the front door

__all__ += ["observe", "suggest"]

# issue 32 (c): reaction systems with unknown kinetics

__all__ += ["ReactionInvariantObserver", "ReactionSystem"]
