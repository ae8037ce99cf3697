"""Every public function that accepts ``**kwargs`` rejects an unknown keyword with a clear error.

A misspelt option (``candidate=`` for ``candidates=``) must fail loudly, not be ignored. The public
API is walked automatically (:mod:`public_api`); each callable with a ``**kwargs`` parameter needs an
entry in :data:`CASES` that calls it with valid arguments plus the given keywords. A new ``**kwargs``
function without an entry fails :func:`test_every_kwargs_function_has_a_case` (as in
python-control's ``test_kwargs.py``): add a case, and make the function call
:func:`intervalobs.validation.check_no_kwargs` before doing any work.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from intervalobs import Bounds, IntervalObserver, LTISystem
from public_api import public_callables, signature_of

UNKNOWN = "no_such_option_xyz"


def _system() -> tuple[LTISystem, Bounds]:
    system = LTISystem([[0.5, 0.1], [0.0, 0.6]], [[1.0, 0.0]], dt=1.0)
    bounds = Bounds(([-1.0, -1.0], [1.0, 1.0]), w=([-0.1, -0.1], [0.1, 0.1]), v=([-0.01], [0.01]))
    return system, bounds


def _design(**kwargs: Any) -> Any:
    system, bounds = _system()
    return IntervalObserver.design(system, bounds, **kwargs)


def _from_control(**kwargs: Any) -> Any:
    control = pytest.importorskip("control")
    return LTISystem.from_control(control.ss([[0.5, 0.1], [0.0, 0.6]], [[0.0], [1.0]], [[1.0, 0.0]], 0, 1.0), **kwargs)


def _integrated_design(**kwargs: Any) -> Any:
    from intervalobs.examples import numerical3
    from intervalobs.observers.zonotopic import IntegratedObserver

    return IntegratedObserver.design(numerical3.system("68"), numerical3.bounds(), **kwargs)


def _zonotopic_design(**kwargs: Any) -> Any:
    from intervalobs.examples import numerical3
    from intervalobs.observers.zonotopic import ZonotopicObserver

    return ZonotopicObserver.design(numerical3.system("68"), numerical3.bounds(), **kwargs)


def _gsisio_design(**kwargs: Any) -> Any:
    from intervalobs.examples import gsisio
    from intervalobs.observers.gsisio import GSISIO

    return GSISIO.design(gsisio.fullrank_system(), gsisio.fullrank_bounds(), **kwargs)


def _nullspace_gsisio_design(**kwargs: Any) -> Any:
    from intervalobs.examples import gsisio
    from intervalobs.observers.null_space_gsisio import NullSpaceGSISIO

    return NullSpaceGSISIO.design(gsisio.paper_system(), gsisio.paper_bounds(), **kwargs)


def _lpv_system() -> Any:
    from intervalobs import LPVSystem

    return LPVSystem(
        A=lambda th: [[-1.0, 0.5], [0.0, -1.0 - 0.1 * th[0]]],
        B=lambda th: [[1.0], [0.0]],
        C=[[1.0, 0.0]],
        theta_box=([-1.0], [1.0]),
        B_un=lambda th: [[1.0], [0.0]],
    )


def _lpv_design(**kwargs: Any) -> Any:
    from intervalobs import LPVIntervalObserver

    return LPVIntervalObserver.design(_lpv_system(), Bounds(x0=(-1, 1)), h=0.01, theta_rate=1.0, **kwargs)


def _lpv_uio_design(**kwargs: Any) -> Any:
    from intervalobs import LPVIntervalUIO

    box = (-np.ones(1), np.ones(1))
    return LPVIntervalUIO.design(_lpv_system(), Bounds(x0=(-1, 1)), h=0.01, theta_rate=1.0, unknown_input=box, **kwargs)


# qualified name -> (call with extra keywords, keywords the function documents and must accept)
CASES: dict[str, tuple[Callable[..., Any], dict[str, Any]]] = {
    "intervalobs.observers.interval_observer.IntervalObserver.design": (
        _design,
        {"candidates": {"identity": np.eye(2)}},
    ),
    "intervalobs.observers.gsisio.GSISIO.design": (_gsisio_design, {"tight": False, "splits": 2}),
    "intervalobs.observers.null_space_gsisio.NullSpaceGSISIO.design": (
        _nullspace_gsisio_design,
        {"direction": "output", "gain_factors": (1.0,), "splits": 3, "newton_steps": 2},
    ),
    "intervalobs.observers.zonotopic.IntegratedObserver.design": (_integrated_design, {"fallback": "hinf"}),
    "intervalobs.observers.zonotopic.ZonotopicObserver.design": (_zonotopic_design, {"order": 12}),
    "intervalobs.observers.lpv.LPVIntervalObserver.design": (_lpv_design, {"grid": 3, "fine_grid": 5}),
    "intervalobs.observers.lpv.LPVIntervalUIO.design": (_lpv_uio_design, {"grid": 3, "fine_grid": 5}),
    "intervalobs.systems.lti.LTISystem.from_control": (_from_control, {"E": np.eye(2)}),
}


def _kwargs_functions() -> list[str]:
    found = []
    for name, obj in public_callables().items():
        try:
            params = signature_of(obj).parameters.values()
        except (TypeError, ValueError):  # pragma: no cover - builtins without a signature
            continue
        if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params):
            found.append(name)
    return sorted(found)


def test_every_kwargs_function_has_a_case():
    missing = sorted(set(_kwargs_functions()) - set(CASES))
    assert not missing, f"public functions with **kwargs but no case in tests/test_kwargs.py CASES: {missing}"
    stale = sorted(set(CASES) - set(_kwargs_functions()))
    assert not stale, f"CASES entries that no longer take **kwargs (remove them): {stale}"


@pytest.mark.parametrize("name", sorted(CASES), ids=str)
def test_unknown_keyword_is_rejected(name):
    call, _ = CASES[name]
    with pytest.raises(TypeError, match=rf"unexpected keyword argument '{UNKNOWN}'"):
        call(**{UNKNOWN: 1})


@pytest.mark.parametrize("name", sorted(CASES), ids=str)
def test_documented_keywords_are_accepted(name):
    call, good = CASES[name]
    call(**good)  # the check must not reject what the function documents
