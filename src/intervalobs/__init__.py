"""intervalobs: guaranteed interval estimation for uncertain dynamical systems.

The top level holds what a user calls: the model classes and :class:`Bounds`, the estimators, the
front door (:func:`observe`, :func:`suggest`), the result :class:`Estimate`, the truth simulators,
:func:`sampled_model` and the base errors. Everything else lives in its module and is imported from
there: design tools from :mod:`intervalobs.design` (e.g. ``intervalobs.design.high_gain.theta_design``),
lower bounds and tightness reports from :mod:`intervalobs.tightness`, fault isolation from
:mod:`intervalobs.diagnosis`, interval helpers from :mod:`intervalobs.interval`, every named error from
:mod:`intervalobs.errors`.

.. deprecated:: 0.2.0
   The names that left the top level (listed in ``MOVED``) still resolve here with a ``FutureWarning``
   naming their new home; they go in the next release.
"""

import importlib
import warnings
from typing import Any

from .errors import DesignError, DivergenceWarning, InconsistentDataError, IntervalObserverError
from .estimate import Estimate
from .front_door import observe, suggest
from .interval import Interval
from .observers import (
    GSISIO,
    ContinuousNonlinearObserver,
    ContinuousWindowObserver,
    FiniteMemoryObserver,
    HighGainIntervalObserver,
    HullEstimator,
    IntegratedObserver,
    IntersectionObserver,
    IntervalObserver,
    LPVIntervalObserver,
    LPVIntervalUIO,
    NullSpaceGSISIO,
    Observer,
    ReactionInvariantObserver,
    RobustFiniteMemoryObserver,
    RobustHullEstimator,
    SetInversionSmoother,
    UnknownInputIntervalObserver,
    ZonotopicObserver,
)
from .simulate import Simulation, simulate, simulate_nonlinear, simulate_sampled
from .systems import (
    Bounds,
    ContinuousNonlinearSystem,
    LPVSystem,
    LTISystem,
    NonlinearSystem,
    ReactionSystem,
    SampledSystem,
    sampled_model,
)

__version__ = "0.1.0"

__all__ = [
    "GSISIO",
    "Bounds",
    "ContinuousNonlinearObserver",
    "ContinuousNonlinearSystem",
    "ContinuousWindowObserver",
    "DesignError",
    "DivergenceWarning",
    "Estimate",
    "FiniteMemoryObserver",
    "HighGainIntervalObserver",
    "HullEstimator",
    "InconsistentDataError",
    "IntegratedObserver",
    "IntersectionObserver",
    "Interval",
    "IntervalObserver",
    "IntervalObserverError",
    "LPVIntervalObserver",
    "LPVIntervalUIO",
    "LPVSystem",
    "LTISystem",
    "NonlinearSystem",
    "NullSpaceGSISIO",
    "Observer",
    "ReactionInvariantObserver",
    "ReactionSystem",
    "RobustFiniteMemoryObserver",
    "RobustHullEstimator",
    "SampledSystem",
    "SetInversionSmoother",
    "Simulation",
    "UnknownInputIntervalObserver",
    "ZonotopicObserver",
    "__version__",
    "observe",
    "sampled_model",
    "simulate",
    "simulate_nonlinear",
    "simulate_sampled",
    "suggest",
]

MOVED: dict[str, str] = {
    "AffineAbstraction": "intervalobs.design.abstraction",
    "ArgumentError": "intervalobs.errors",
    "ArgumentTypeError": "intervalobs.errors",
    "AssumptionError": "intervalobs.errors",
    "BoundsError": "intervalobs.errors",
    "CertifiedVertexBounds": "intervalobs.design.lpv",
    "DataError": "intervalobs.errors",
    "DeltaLinearisation": "intervalobs.systems",
    "DimensionError": "intervalobs.errors",
    "Disk": "intervalobs.design.regions",
    "EnclosureReport": "intervalobs.estimate",
    "FileError": "intervalobs.errors",
    "FlowEnclosure": "intervalobs.systems",
    "GainDesign": "intervalobs.design.hinf",
    "HOSMDifferentiator": "intervalobs.design.differentiator",
    "HullLowerBound": "intervalobs.tightness",
    "JacobianDecomposition": "intervalobs.design.mixed_monotone",
    "ObserverState": "intervalobs.observers",
    "RegionPlacement": "intervalobs.design.regions",
    "ResolvedBounds": "intervalobs.systems",
    "SampledModel": "intervalobs.systems",
    "SchedulerError": "intervalobs.errors",
    "ThetaDesign": "intervalobs.design.high_gain",
    "VertexDecomposition": "intervalobs.design.mixed_monotone",
    "Zonotope": "intervalobs.zonotope",
    "affine_abstraction": "intervalobs.design.abstraction",
    "boundedness_lmi": "intervalobs.design.lpv",
    "cabs": "intervalobs.complex_interval",
    "certify_vertex_extremes": "intervalobs.design.lpv",
    "check_cooperative": "intervalobs.design.uio",
    "ctimes": "intervalobs.complex_interval",
    "delta_linearisation": "intervalobs.systems",
    "design_uio_coordinates": "intervalobs.design.uio",
    "difference_derivative_bounds": "intervalobs.design.differentiator",
    "flow_enclosure": "intervalobs.systems",
    "format_tightness": "intervalobs.tightness",
    "gsisio_design": "intervalobs.design.gsisio",
    "hinf_gain": "intervalobs.design.hinf",
    "hull_lower_bound": "intervalobs.tightness",
    "interval_matvec_bounds": "intervalobs.interval",
    "isolation_outcome": "intervalobs.diagnosis",
    "jacobian_bounds": "intervalobs.design.mixed_monotone",
    "levant_gains": "intervalobs.design.differentiator",
    "linear_image": "intervalobs.complex_interval",
    "matvec_bounds": "intervalobs.interval",
    "neg": "intervalobs.interval",
    "place_in_disks": "intervalobs.design.regions",
    "pos": "intervalobs.interval",
    "psi_hat": "intervalobs.diagnosis",
    "robust_hull_lower_bound": "intervalobs.tightness",
    "run_campaign": "intervalobs.diagnosis",
    "runs_for_sigma": "intervalobs.diagnosis",
    "theta_design": "intervalobs.design.high_gain",
    "tightness_reference": "intervalobs.tightness",
    "tightness_report": "intervalobs.tightness",
    "uio_decoupling": "intervalobs.design.uio",
    "verify_boundedness": "intervalobs.design.lpv",
    "zonotope_size_gain": "intervalobs.design.hinf",
    "Box": "intervalobs.interval",
}
"""Names that left the top level, each with the module to import it from (read here, they warn)."""


def __getattr__(name: str) -> Any:
    """A name that left the top level: its object, with a ``FutureWarning`` naming the module it moved to."""
    home = MOVED.get(name)
    if home is None:
        raise AttributeError(f"module 'intervalobs' has no attribute {name!r}")
    new = "Interval" if name == "Box" else name
    warnings.warn(
        f"intervalobs.{name} is deprecated and goes in the next release: use 'from {home} import {new}'",
        FutureWarning,
        stacklevel=2,
    )
    return getattr(importlib.import_module(home), new)
