r"""One path from a linear matrix inequality to a verified solution.

Every LMI of the package (the integrated-observer paper's (19), (26), (54)–(55); the sampled-output high-gain paper's
(15) and (32); the boundedness LMIs (43)/(63)/(74)/(109) of the LPV observers) is posed as a :class:`cvxpy.Problem`
and solved by :func:`solve_lmi`:

1. the requested solver (Clarabel by default), then SCS if the first one errs, returns no solution,
   or returns one that fails step 2; a certified infeasible or unbounded status ends the search (an
   interior-point certificate of infeasibility is not overturned by a first-order solver);
2. the returned point is re-checked with NumPy: every constraint is evaluated at the solution and its
   residual (for ``A ⪰ B``: the most negative eigenvalue of the symmetric part of ``A - B``; for
   elementwise constraints: the largest violation) must not exceed ``rtol`` times the constraint's
   own magnitude.

A solver status of ``optimal_inaccurate`` is therefore accepted silently when the check of step 2
passes (CVXPY's "Solution may be inaccurate" warning is replaced by that check, recorded in
:attr:`LMISolution.residual`), and leads to the next solver, then to a :class:`DesignError` naming
the condition and what to relax, when it fails. The properties a design needs from the solution
(a strict inequality, a spectral radius, an eigenvalue inside its region) are then checked by the
caller on the recovered quantities, with :func:`verify_definite` for matrix inequalities.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any, Literal

import cvxpy as cp
import numpy as np
from numpy.typing import ArrayLike

from ..errors import ArgumentTypeError, DesignError

__all__ = ["RTOL", "LMISolution", "constraint_residual", "solve_lmi", "verify_definite"]

RTOL = 1e-6
"""Largest accepted residual of a constraint at the solver's point, relative to the constraint's size."""

_FALLBACK = "SCS"
_ACCEPTED = (cp.OPTIMAL, cp.OPTIMAL_INACCURATE)
_CERTIFIED = (cp.INFEASIBLE, cp.UNBOUNDED)


@dataclass(frozen=True)
class LMISolution:
    """How :func:`solve_lmi` obtained and checked a solution (the values stay in the problem's variables).

    Attributes
    ----------
    condition : str
        The LMI's name, e.g. ``"(19)"``.
    solver : str
        The solver whose point was accepted.
    status : str
        Its CVXPY status (``"optimal"`` or ``"optimal_inaccurate"``).
    residual : float
        Largest relative constraint residual at that point (at most ``rtol``).
    value : float
        Objective value.
    """

    condition: str
    solver: str
    status: str
    residual: float
    value: float

    @property
    def label(self) -> str:
        """``"SOLVER: status"``, as reported by the designs.

        Returns
        -------
        str
        """
        return f"{self.solver}: {self.status}"


def constraint_residual(constraint: cp.constraints.constraint.Constraint) -> float:
    """Residual of a CVXPY constraint at the current values of its variables, relative to its size.

    Parameters
    ----------
    constraint : cvxpy.constraints.constraint.Constraint
        A ``>>``/``<<`` (PSD), ``<=``/``>=`` or ``==`` constraint of a solved problem.

    Returns
    -------
    float
        ``violation / (1 + max |entry|)``: for a PSD constraint ``E ⪰ 0`` the violation is
        ``max(0, -λ_min((E + Eᵀ)/2))``, for ``E ≤ 0`` it is ``max(0, max E)``, for ``E = 0`` it is
        ``max |E|``; ``inf`` when the variables have no value.

    Raises
    ------
    TypeError
        For another kind of constraint (second-order cones and the like are not checked here).
    """
    expr = constraint.expr if not isinstance(constraint, cp.constraints.PSD) else constraint.args[0]
    value = expr.value
    if value is None:
        return float("inf")
    mat = np.atleast_1d(np.asarray(value, dtype=float))
    if not np.all(np.isfinite(mat)):
        return float("inf")
    scale = 1.0 + float(np.abs(mat).max())
    if isinstance(constraint, cp.constraints.PSD):
        sym = 0.5 * (mat + mat.T)
        violation = max(0.0, -float(np.linalg.eigvalsh(sym)[0]))
    elif isinstance(constraint, (cp.constraints.Inequality, cp.constraints.NonPos)):
        violation = max(0.0, float(mat.max()))
    elif isinstance(constraint, cp.constraints.NonNeg):
        violation = max(0.0, -float(mat.min()))
    elif isinstance(constraint, (cp.constraints.Equality, cp.constraints.Zero)):
        violation = float(np.abs(mat).max())
    else:
        raise ArgumentTypeError(
            f"constraint: expected a PSD, inequality or equality constraint, got {type(constraint).__name__}"
        )
    return violation / scale


def solve_lmi(
    problem: cp.Problem, condition: str, relax: str, *, solver: str = "CLARABEL", rtol: float = RTOL
) -> LMISolution:
    """Solve an LMI problem and re-check every constraint at the returned point (module docstring).

    Parameters
    ----------
    problem : cvxpy.Problem
        The problem; its variables hold the accepted solution on return.
    condition : str
        Name of the LMI in error messages (e.g. ``"(19)"``).
    relax : str
        What the user can relax when no verified solution exists (ends the error message).
    solver : str
        First solver; SCS is the fallback.
    rtol : float
        Largest accepted relative constraint residual (:func:`constraint_residual`).

    Returns
    -------
    LMISolution

    Raises
    ------
    DesignError
        No solver returned a point that passes the check: names the condition, each solver's outcome
        (status, or the worst constraint residual) and ``relax``.
    """
    outcomes = []
    for name in dict.fromkeys((solver, _FALLBACK)):
        try:
            with warnings.catch_warnings():
                # an inaccurate status is judged by the residual check below, not by a warning
                warnings.filterwarnings("ignore", message="Solution may be inaccurate", category=UserWarning)
                problem.solve(solver=name)
        except cp.error.SolverError:
            outcomes.append(f"{name}: solver error")
            continue
        status = str(problem.status)
        if status not in _ACCEPTED:
            outcomes.append(f"{name}: {status}")
            if status in _CERTIFIED:
                break
            continue
        residuals = [constraint_residual(c) for c in problem.constraints]
        worst = int(np.argmax(residuals)) if residuals else 0
        residual = residuals[worst] if residuals else 0.0
        if residual <= rtol:
            return LMISolution(condition, name, status, residual, float(np.asarray(problem.value)))
        outcomes.append(f"{name}: {status} but constraint {worst} has residual {residual:.2e} > {rtol:.0e}")
    raise DesignError(f"LMI {condition}: no verified solution ({'; '.join(outcomes)}); {relax}")


def verify_definite(condition: str, matrix: ArrayLike, sign: Literal[-1, 1], relax: str, *, tol: float = 0.0) -> float:
    """Check a matrix inequality from the eigenvalues of the symmetric part of a numeric matrix.

    Parameters
    ----------
    condition : str
        Name of the inequality in the error message.
    matrix : array_like, shape (k, k)
        The matrix, evaluated with NumPy from the recovered design quantities.
    sign : {-1, 1}
        ``-1``: negative definite (every eigenvalue ``< tol``); ``1``: positive definite (every
        eigenvalue ``> -tol``).
    relax : str
        What to relax when the check fails (ends the error message).
    tol : float
        Allowance on the wrong side of zero (0: strict).

    Returns
    -------
    float
        The eigenvalue nearest the wrong side: the largest for ``sign=-1``, the smallest for ``sign=1``.

    Raises
    ------
    DesignError
        If the check fails.
    """
    mat: Any = np.asarray(matrix, dtype=float)
    eig = np.linalg.eigvalsh(0.5 * (mat + mat.T))
    extreme = float(eig[-1] if sign < 0 else eig[0])
    if not (sign * extreme > -tol):
        kind = "negative" if sign < 0 else "positive"
        bound = f"< {tol:.1e}" if sign < 0 else f"> {-tol:.1e}"
        raise DesignError(
            f"{condition}: expected a {kind} definite matrix (eigenvalues {bound}), got {extreme:.3e}; {relax}"
        )
    return extreme
