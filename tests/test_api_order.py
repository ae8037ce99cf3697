"""One order for every estimator's ``design``: ``(system, bounds, *, ...)``, ``h`` named the same everywhere.

Options passed by position after ``bounds`` still work for one release, mapped to their former names
with a ``FutureWarning`` (``observers.base.options_after_bounds``).
"""

from __future__ import annotations

import inspect
import warnings

import numpy as np
import pytest

import intervalobs
from intervalobs import Bounds, IntervalObserver, LTISystem, Observer
from intervalobs.errors import ArgumentTypeError

ESTIMATORS = sorted(
    (
        obj
        for obj in vars(intervalobs).values()
        if isinstance(obj, type) and issubclass(obj, Observer) and obj is not Observer
    ),
    key=lambda cls: cls.__name__,
)
DESIGNS = [(cls, name) for cls in ESTIMATORS for name in ("design", "design_for_width") if name in vars(cls)]


@pytest.fixture(scope="module")
def lti() -> tuple[LTISystem, Bounds]:
    """A stable two-state discrete-time system with one output."""
    system = LTISystem(A=[[0.9, 0.2], [-0.1, 0.8]], C=[[1.0, 0.0]], dt=0.1)
    return system, Bounds(x0=(-1, 1), w=(-0.01, 0.01), v=(-0.05, 0.05))


def test_every_estimator_with_a_design_is_covered() -> None:
    assert len(ESTIMATORS) >= 15
    names = {cls.__name__ for cls, _ in DESIGNS}
    assert {"IntervalObserver", "HullEstimator", "HighGainIntervalObserver", "LPVIntervalUIO"} <= names


@pytest.mark.parametrize(("cls", "name"), DESIGNS, ids=[f"{c.__name__}.{n}" for c, n in DESIGNS])
def test_design_takes_everything_after_bounds_by_keyword(cls: type, name: str) -> None:
    parameters = list(inspect.signature(getattr(cls, name)).parameters.values())
    assert [p.name for p in parameters[:2]] == ["system", "bounds"]
    assert all(p.kind in (p.KEYWORD_ONLY, p.VAR_KEYWORD) for p in parameters[2:]), parameters
    sampling = [p.name for p in parameters if p.name in ("h", "dt", "step", "period", "sampling_period")]
    assert sampling in ([], ["h"]), f"{cls.__name__}.{name}: the sampling period is called h, got {sampling}"


def test_a_positional_option_still_works_for_one_release_with_a_future_warning(
    lti: tuple[LTISystem, Bounds],
) -> None:
    system, bounds = lti
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        by_keyword = IntervalObserver.design(system, bounds, h=0.1)
    with pytest.warns(FutureWarning, match=r"IntervalObserver\.design: pass h=\.\.\. by keyword"):
        by_position = IntervalObserver.design(system, bounds, 0.1)  # type: ignore[misc]
    np.testing.assert_allclose(by_position.gains, by_keyword.gains, rtol=0, atol=0)


def test_too_many_or_doubled_options_are_refused(lti: tuple[LTISystem, Bounds]) -> None:
    system, bounds = lti
    with pytest.raises(ArgumentTypeError, match=r"at most 3 positional arguments \(system, bounds, h\), got 4"):
        IntervalObserver.design(system, bounds, 0.1, "tube")  # type: ignore[misc]
    with pytest.raises(ArgumentTypeError, match=r"\['h'\] both by position and by keyword"):
        IntervalObserver.design(system, bounds, 0.1, h=0.1)  # type: ignore[misc]


def test_the_wrapper_keeps_the_documentation(lti: tuple[LTISystem, Bounds]) -> None:
    assert IntervalObserver.design.__doc__ and "Parameters" in IntervalObserver.design.__doc__
    assert IntervalObserver.design.__name__ == "design"
