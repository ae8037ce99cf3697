"""The curated top-level namespace: what a user calls, and the former names still resolving with a warning."""

from __future__ import annotations

import importlib
import re
import warnings
from pathlib import Path

import pytest

import intervalobs

INIT = Path(intervalobs.__file__)

FORMER_TOP_LEVEL = """
AffineAbstraction ArgumentError ArgumentTypeError AssumptionError Bounds BoundsError CertifiedVertexBounds
ContinuousNonlinearObserver ContinuousNonlinearSystem DataError DeltaLinearisation DesignError DimensionError
Disk DivergenceWarning EnclosureReport Estimate FileError FiniteMemoryObserver FlowEnclosure GSISIO GainDesign
HOSMDifferentiator HighGainIntervalObserver HullEstimator HullLowerBound InconsistentDataError
IntegratedObserver IntersectionObserver Interval IntervalObserver IntervalObserverError JacobianDecomposition
LPVIntervalObserver LPVIntervalUIO LPVSystem LTISystem NonlinearSystem NullSpaceGSISIO Observer ObserverState
ReactionInvariantObserver ReactionSystem RegionPlacement ResolvedBounds RobustFiniteMemoryObserver
RobustHullEstimator SampledModel SampledSystem SchedulerError Simulation ThetaDesign
UnknownInputIntervalObserver VertexDecomposition Zonotope ZonotopicObserver affine_abstraction boundedness_lmi
cabs certify_vertex_extremes check_cooperative ctimes delta_linearisation design_uio_coordinates
difference_derivative_bounds flow_enclosure format_tightness gsisio_design hinf_gain hull_lower_bound
interval_matvec_bounds isolation_outcome jacobian_bounds levant_gains linear_image matvec_bounds neg observe
place_in_disks pos psi_hat robust_hull_lower_bound run_campaign runs_for_sigma sampled_model simulate
simulate_nonlinear simulate_sampled suggest theta_design tightness_reference tightness_report uio_decoupling
verify_boundedness zonotope_size_gain Box
""".split()
"""Every name the top level exported before the namespace was curated (0.1.0), and the deprecated ``Box``."""

REMOVED = sorted(set(FORMER_TOP_LEVEL) - set(intervalobs.__all__))


def _ruff_order(name: str) -> tuple[int, str]:
    """The order ruff's RUF022 keeps ``__all__`` in: CONSTANT_CASE, then CamelCase, then the rest."""
    if name.isupper():
        return 0, name
    if name[0].isupper():
        return 1, name
    return 2, name


def test_the_top_level_is_small_sorted_and_in_one_block() -> None:
    names = intervalobs.__all__
    assert len(names) <= 45
    assert names == sorted(names, key=_ruff_order)
    assert len(set(names)) == len(names)
    source = INIT.read_text(encoding="utf-8")
    assert "__all__ +=" not in source and len(re.findall(r"^__all__\b", source, flags=re.M)) == 1


@pytest.mark.parametrize("name", [n for n in intervalobs.__all__ if n != "__version__"])
def test_every_exported_name_imports_without_a_warning(name: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        obj = getattr(importlib.import_module("intervalobs"), name)
    assert obj.__module__.startswith("intervalobs.")


@pytest.mark.parametrize("name", REMOVED)
def test_a_former_name_warns_and_resolves_to_the_object_at_its_new_home(name: str) -> None:
    home = intervalobs.MOVED[name]
    target = "Interval" if name == "Box" else name
    with pytest.warns(FutureWarning, match=re.escape(f"from {home} import {target}")):
        old = getattr(intervalobs, name)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        new = getattr(importlib.import_module(home), target)
    assert old is new
    assert target in importlib.import_module(home).__all__


def test_every_moved_name_was_exported_before() -> None:
    assert set(intervalobs.MOVED) == set(REMOVED)


def test_an_unknown_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no_such_name"):
        intervalobs.no_such_name  # noqa: B018


@pytest.mark.parametrize(
    ("module", "name", "canonical"),
    [
        ("intervalobs.interval", "Box", "Interval"),
        ("intervalobs.inclusion", "Interval", "Interval"),
        ("intervalobs.inclusion", "SUPPORTED_UFUNCS", "SUPPORTED_UFUNCS"),
    ],
    ids=["interval.Box", "inclusion.Interval", "inclusion.SUPPORTED_UFUNCS"],
)
def test_deprecated_aliases_warn(module: str, name: str, canonical: str) -> None:
    from intervalobs import interval

    with pytest.warns(FutureWarning, match="next release"):
        obj = getattr(importlib.import_module(module), name)
    assert obj is getattr(interval, canonical)
