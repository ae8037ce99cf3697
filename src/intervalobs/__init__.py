"""intervalobs: guaranteed interval estimation for uncertain dynamical systems."""

from .design.differentiator import HOSMDifferentiator, difference_derivative_bounds, levant_gains
from .design.hinf import GainDesign, hinf_gain, zonotope_size_gain
from .design.uio import check_cooperative, design_uio_coordinates, uio_decoupling
from .errors import (
    AssumptionError,
    BoundsError,
    DataError,
    DesignError,
    DimensionError,
    IntervalObserverError,
)
from .estimate import EnclosureReport, Estimate
from .interval import Box, interval_matvec_bounds, matvec_bounds, neg, pos
from .observers import IntervalObserver, Observer, ObserverState
from .observers.unknown_input import UnknownInputIntervalObserver
from .observers.zonotopic import IntegratedObserver, ZonotopicObserver
from .simulate import Simulation, simulate
from .systems import Bounds, LTISystem
from .zonotope import Zonotope

__version__ = "0.1.0"

__all__ = [
    "AssumptionError",
    "Bounds",
    "BoundsError",
    "Box",
    "DataError",
    "DesignError",
    "DimensionError",
    "EnclosureReport",
    "Estimate",
    "IntervalObserver",
    "IntervalObserverError",
    "LTISystem",
    "Observer",
    "ObserverState",
    "Simulation",
    "__version__",
    "interval_matvec_bounds",
    "matvec_bounds",
    "neg",
    "pos",
    "simulate",
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
