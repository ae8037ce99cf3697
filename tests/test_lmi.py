"""The one solve-and-verify path of every LMI (design/lmi.py)."""

from __future__ import annotations

import warnings
from typing import Any

import cvxpy as cp
import numpy as np
import pytest

from intervalobs.design.lmi import RTOL, constraint_residual, solve_lmi, verify_definite
from intervalobs.errors import DesignError


def _lyapunov(a: np.ndarray) -> tuple[cp.Problem, cp.Variable]:
    n = a.shape[0]
    p = cp.Variable((n, n), symmetric=True)
    lmi = a.T @ p + p @ a
    problem = cp.Problem(cp.Minimize(cp.trace(p)), [p >> np.eye(n), 0.5 * (lmi + lmi.T) << -1e-6 * np.eye(n)])
    return problem, p


def test_a_feasible_lmi_is_solved_and_every_constraint_rechecked() -> None:
    problem, p = _lyapunov(np.array([[-1.0, 2.0], [0.0, -3.0]]))
    solution = solve_lmi(problem, "(L)", "nothing to relax")
    assert solution.solver == "CLARABEL" and solution.status == "optimal"
    assert solution.label == "CLARABEL: optimal"
    assert 0.0 <= solution.residual <= RTOL
    # the recovered P satisfies the Lyapunov inequality by its own eigenvalues
    pv = np.asarray(p.value)
    a = np.array([[-1.0, 2.0], [0.0, -3.0]])
    assert verify_definite("(L)", a.T @ pv + pv @ a, -1, "-") < 0
    assert verify_definite("P", pv, 1, "-") >= 1.0 - 1e-7


def test_a_certified_infeasible_lmi_raises_naming_the_condition_and_what_to_relax() -> None:
    problem, _ = _lyapunov(np.array([[1.0, 0.0], [0.0, -1.0]]))  # unstable: no Lyapunov matrix
    with pytest.raises(DesignError, match=r"LMI \(L\): no verified solution \(CLARABEL: infeasible\); move the pole"):
        solve_lmi(problem, "(L)", "move the pole")


class _Scripted:
    """A stand-in for a cvxpy.Problem whose solvers return given points with an inaccurate status."""

    def __init__(self, points: dict[str, float]) -> None:
        self.x = cp.Variable()
        self.constraints = [self.x >= 1.0, cp.reshape(self.x, (1, 1), order="F") >> 2.0 * np.eye(1)]
        self.points = points
        self.tried: list[str] = []
        self.status = "not solved"
        self.value = 0.0

    def solve(self, solver: str) -> None:
        self.tried.append(solver)
        self.x.value = np.array(self.points[solver])
        self.status, self.value = cp.OPTIMAL_INACCURATE, float(self.points[solver])
        warnings.warn("Solution may be inaccurate. Try another solver.", UserWarning, stacklevel=2)


def test_an_inaccurate_status_that_verifies_is_accepted_without_a_warning() -> None:
    scripted = _Scripted({"CLARABEL": 2.0 - 1e-9, "SCS": 5.0})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        solution = solve_lmi(scripted, "(S)", "-")  # type: ignore[arg-type]
    assert scripted.tried == ["CLARABEL"] and solution.status == "optimal_inaccurate"
    assert solution.residual == pytest.approx(1e-9, rel=1e-6)  # x - 2 = -1e-9 over 1 + 1e-9


def test_an_inaccurate_point_that_fails_the_check_falls_back_then_raises() -> None:
    scripted = _Scripted({"CLARABEL": 1.5, "SCS": 2.5})
    solution = solve_lmi(scripted, "(S)", "-")  # type: ignore[arg-type]
    assert scripted.tried == ["CLARABEL", "SCS"] and solution.solver == "SCS" and solution.residual == 0.0
    worse = _Scripted({"CLARABEL": 1.5, "SCS": 0.5})
    with pytest.raises(DesignError, match=r"SCS: optimal_inaccurate but constraint 1 has residual 6\.00e-01 > 1e-06"):
        solve_lmi(worse, "(S)", "-")  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("make", "value", "expected"),
    [
        (lambda x: x >> np.diag([1.0, -2.0]), np.zeros((2, 2)), 1.0 / 3.0),  # λ_min(diag(-1, 2)) = -1, size 2
        (lambda x: x <= 1.0, np.array([[3.0, 0.0], [0.0, 0.0]]), 2.0 / 3.0),
        (lambda x: x >= 1.0, np.array([[3.0, 0.0], [0.0, 0.0]]), 1.0 / 3.0),
        (lambda x: x == 1.0, np.array([[3.0, 1.0], [1.0, 1.0]]), 2.0 / 3.0),
    ],
    ids=["psd", "upper", "lower", "equal"],
)
def test_constraint_residual_is_the_violation_over_the_size(make: Any, value: np.ndarray, expected: float) -> None:
    x = cp.Variable((2, 2), symmetric=True)
    x.value = value
    assert constraint_residual(make(x)) == pytest.approx(expected, rel=1e-12)


def test_verify_definite_names_the_condition_and_the_eigenvalue() -> None:
    with pytest.raises(DesignError, match=r"\(X\): expected a negative definite matrix .* got 1\.000e\+00; shrink it"):
        verify_definite("(X)", np.diag([-1.0, 1.0]), -1, "shrink it")
    assert verify_definite("(X)", np.diag([-1.0, 1e-9]), -1, "-", tol=1e-8) == pytest.approx(1e-9)
    with pytest.raises(DesignError, match="positive definite"):
        verify_definite("(X)", np.diag([1.0, 0.0]), 1, "-")
