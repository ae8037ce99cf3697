"""Observers, one module per family, all on the protocol of :mod:`intervalobs.observers.base`."""

from .angles_only import AnglesOnlyObserver
from .base import Observer, ObserverState
from .continuous_nonlinear import ContinuousNonlinearObserver
from .fir import FiniteMemoryObserver
from .gsisio import GSISIO
from .hgio import HighGainIntervalObserver
from .hull import HullEstimator
from .intersection import IntersectionObserver, output_contraction
from .interval_observer import IntervalObserver
from .lpv import LPVIntervalObserver, LPVIntervalUIO
from .null_space_gsisio import NullSpaceGSISIO
from .reaction_invariant import ReactionInvariantObserver
from .robust_fir import RobustFiniteMemoryObserver
from .robust_hull import RobustHullEstimator
from .set_inversion import SetInversionSmoother
from .unknown_input import UnknownInputIntervalObserver
from .window_inversion import ContinuousWindowObserver
from .zonotopic import IntegratedObserver, ZonotopicObserver

__all__ = [
    "GSISIO",
    "AnglesOnlyObserver",
    "ContinuousNonlinearObserver",
    "ContinuousWindowObserver",
    "FiniteMemoryObserver",
    "HighGainIntervalObserver",
    "HullEstimator",
    "IntegratedObserver",
    "IntersectionObserver",
    "IntervalObserver",
    "LPVIntervalObserver",
    "LPVIntervalUIO",
    "NullSpaceGSISIO",
    "Observer",
    "ObserverState",
    "ReactionInvariantObserver",
    "RobustFiniteMemoryObserver",
    "RobustHullEstimator",
    "SetInversionSmoother",
    "UnknownInputIntervalObserver",
    "ZonotopicObserver",
    "output_contraction",
]
