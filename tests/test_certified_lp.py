"""Certified LP bounds (lp/certified.py): weak duality with the rounding subtracted."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from scipy import sparse

from intervalobs.lp.certified import DenseLP, dual_bounds, shrink_inward


def test_dense_lp_bounds_hold_for_any_multipliers_and_meet_the_optimum() -> None:
    """min ±(z0 + 2 z1) on z0 + z1 ∈ [0, 1], z ∈ [-1, 1]²: optima -1 and -2, at (1, -1) and (0, 1)."""
    lp = DenseLP()
    lp.load(np.array([[1.0, 1.0]]), -np.ones(2), np.ones(2), np.zeros(1), np.ones(1))
    bounds, points = lp.minima(np.array([[1.0, 2.0], [-1.0, -2.0]]))
    np.testing.assert_allclose(bounds, [-1.0, -2.0], atol=1e-9)
    assert np.all(bounds <= [-1.0, -2.0])  # certified: never above the true minimum
    np.testing.assert_allclose(points, [[1.0, -1.0], [0.0, 1.0]], atol=1e-9)
    # any multipliers give a valid (weaker) bound
    for dual in (-3.0, 0.0, 0.5, 7.0):
        weak = dual_bounds(lp, np.array([[1.0, 2.0]]), np.array([[dual]]))[0]
        assert weak <= -1.0


def test_shrink_inward_moves_inner_bounds_in_and_never_crosses() -> None:
    lower, upper = shrink_inward(np.array([1.0, 0.0, np.nan]), np.array([3.0, 1e-7, np.nan]))
    np.testing.assert_allclose(lower[:1], 1.0 + 4e-6, rtol=1e-12)
    np.testing.assert_allclose(upper[:1], 3.0 - 4e-6, rtol=1e-12)
    assert lower[1] == upper[1] == pytest.approx(5e-8)  # crossed: both at the midpoint
    assert np.isnan(lower[2]) and np.isnan(upper[2])


def test_duality_bound_refuses_free_columns_it_cannot_bound() -> None:
    def lp(col_hi: float) -> SimpleNamespace:
        matrix_t = sparse.csr_matrix(np.array([[1.0], [0.1]]))  # one row: x0 + 0.1 x1 ∈ [0, 0]
        return SimpleNamespace(
            row_lo=np.zeros(1),
            row_hi=np.zeros(1),
            matrix_t=matrix_t,
            abs_matrix_t=abs(matrix_t),
            col_lo=np.array([-1.0, -col_hi]),
            col_hi=np.array([1.0, col_hi]),
            col_nnz=1,
        )

    costs, duals = np.array([[1.0, 0.1]]), np.array([[1.0]])  # reduced costs exactly zero
    bounded = dual_bounds(lp(5.0), costs, duals)[0]
    assert -1e-12 < bounded <= 0.0  # min of x0 + 0.1 x1 on the row is exactly 0
    # With x1 free, a rounding error of its reduced cost times an infinite bound is not a number.
    assert dual_bounds(lp(np.inf), costs, duals)[0] == -np.inf


@pytest.mark.parametrize("old", ["certified_lp", "dense_simplex"])
def test_the_old_design_paths_are_gone(old: str) -> None:
    """The LP layer's modules have one home, ``intervalobs.lp``; the former ``design`` paths were removed."""
    import importlib

    with pytest.raises(ModuleNotFoundError):
        importlib.import_module(f"intervalobs.design.{old}")


def test_the_time_limit_holds_for_each_run_not_for_the_instance_s_life(monkeypatch: pytest.MonkeyPatch) -> None:
    """HiGHS reads ``time_limit`` against the run time an instance has accumulated: a limit set once would end
    every run "time limit reached" once the runs together took that long (the window LPs keep one instance for a
    whole record). ``run_highs`` gives each run its own limit."""
    from highspy import _core

    from intervalobs.lp import certified

    monkeypatch.setattr(certified, "LP_TIME_LIMIT", 0.4)
    rng = np.random.default_rng(5)
    matrix = rng.standard_normal((20, 30))
    solver = certified.new_highs()
    inf = float(solver.getInfinity())
    solver.passModel(certified.highs_model(matrix, -np.ones(30), np.ones(30), -np.full(20, 5.0), np.full(20, 5.0), inf))
    statuses = []
    while solver.getRunTime() < 1.0:  # runs of 2.5 limits in all, each far below one (a few milliseconds)
        solver.changeColsCost(30, np.arange(30, dtype=np.int32), rng.standard_normal(30))
        solver.clearSolver()
        certified.run_highs(solver)
        statuses.append(solver.getModelStatus())
    assert len(statuses) > 5 and all(status == _core.HighsModelStatus.kOptimal for status in statuses)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_compensated_products_enclose_the_exact_product(seed: int) -> None:
    """Rows that cancel to 1e-9 of their terms: the exact value (rational arithmetic) is within the bound."""
    from fractions import Fraction

    from intervalobs.lp.compensated import RowProducts

    rng = np.random.default_rng(seed)
    a = sparse.random(30, 12, density=0.4, random_state=seed, format="csr") * 10.0 ** rng.uniform(-3, 3)
    z = 3e6 + rng.normal(size=12)
    value, error = RowProducts(a.T.tocsr()).enclose(z)
    dense = a.toarray()
    for i in range(30):
        exact = sum((Fraction(float(x)) * Fraction(float(v)) for x, v in zip(dense[i], z)), Fraction(0))
        assert abs(Fraction(float(value[i])) - exact) <= Fraction(float(error[i]))
        assert error[i] <= 4e-16 * abs(value[i]) + 1e-300  # about one rounding of the result, not of its terms


def test_centred_lp_keeps_the_digits_of_a_far_optimum() -> None:
    """min x1 on x1 - 0.7 x0 ∈ [0.3 c, 0.3 c + 1e-9], x0 ∈ c + [-1e-9, 1e-9], c = 3e6: optimum 0.3c + 0.7(c - 1e-9)."""
    from intervalobs.lp.certified import centred_bounds
    from intervalobs.lp.compensated import RowProducts

    c = 3e6 + 0.1234567
    matrix_t = sparse.csr_matrix(np.array([[-0.7], [1.0]]))
    given = (
        np.array([c - 1e-9, c - 1.0]),
        np.array([c + 1e-9, c + 1.0]),
        np.array([0.3 * c]),
        np.array([0.3 * c + 1e-9]),
    )

    def lp(bounds: tuple[np.ndarray, ...]) -> SimpleNamespace:
        col_lo, col_hi, row_lo, row_hi = bounds
        return SimpleNamespace(
            row_lo=row_lo, row_hi=row_hi, col_lo=col_lo, col_hi=col_hi,
            matrix_t=matrix_t, abs_matrix_t=abs(matrix_t), col_nnz=1,
        )  # fmt: skip

    costs, duals = np.array([[0.0, 1.0]]), np.array([[1.0]])
    centre = np.array([c, c])
    plain = dual_bounds(lp(given), costs, duals)[0]
    shifted = centred_bounds(given, RowProducts(matrix_t), centre)
    assert np.all(shifted[0] <= given[0] - centre) and np.all(shifted[1] >= given[1] - centre)
    centred = np.nextafter(c + dual_bounds(lp(shifted), costs, duals)[0], -np.inf)
    optimum = 0.3 * c + 0.7 * (c - 1e-9)
    assert centred <= optimum + 2e-9  # valid: the exact optimum is within one rounding of `optimum`
    assert 4 * (optimum - centred) < optimum - plain  # the plain evaluation loses more of its last digits
