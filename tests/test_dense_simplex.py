"""The dense primal simplex of the window hull's chain (lp/dense_simplex.py), against HiGHS from scratch."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from intervalobs.lp.certified import (
    FEASIBILITY_TOLERANCE,
    basic_variables,
    dual_bounds,
    highs_model,
    new_highs,
    run_highs,
)
from intervalobs.lp.dense_simplex import DenseSimplex, load_kernels

TOL = FEASIBILITY_TOLERANCE


def _random_lp(seed: int, rows: int, cols: int, one_sided: bool = True) -> SimpleNamespace:
    """A feasible LP: rows ranged around the activity of a point inside the box, some one-sided (unless not
    ``one_sided``) or free."""
    rng = np.random.default_rng(seed)
    matrix = rng.standard_normal((rows, cols))
    col_lo, col_hi = -rng.uniform(0.5, 2.0, cols), rng.uniform(0.5, 2.0, cols)
    inside = rng.uniform(col_lo, col_hi) * 0.5
    activity = matrix @ inside
    row_lo = activity - rng.uniform(0.0, 1.0, rows)
    row_hi = activity + rng.uniform(0.0, 1.0, rows)
    if one_sided:
        row_lo[rng.random(rows) < 0.2] = -np.inf
        row_hi[rng.random(rows) < 0.2] = np.inf
    else:
        row_lo[[5, 6]], row_hi[[5, 6]] = -np.inf, np.inf
    row_hi[:2] = row_lo[:2] = activity[:2]  # two equality rows: a degenerate face
    return SimpleNamespace(
        matrix=matrix,
        matrix_t=np.ascontiguousarray(matrix.T),
        abs_matrix_t=np.abs(matrix.T),
        col_nnz=rows,
        col_lo=col_lo,
        col_hi=col_hi,
        row_lo=row_lo,
        row_hi=row_hi,
    )


def _highs(lp: SimpleNamespace, cost: np.ndarray) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
    """HiGHS from scratch: optimal value, basic variables, values (columns, rows), row duals."""
    solver = new_highs()
    inf = float(solver.getInfinity())
    solver.passModel(highs_model(lp.matrix, lp.col_lo, lp.col_hi, lp.row_lo, lp.row_hi, inf))
    solver.changeColsCost(len(cost), np.arange(len(cost), dtype=np.int32), cost)
    run_highs(solver)
    solution = solver.getSolution()
    values = np.concatenate([solution.col_value, solution.row_value])
    basic = basic_variables(solver)
    return float(cost @ values[: len(cost)]), basic, values, np.asarray(solution.row_dual)


def _slack(lp: SimpleNamespace, duals: np.ndarray) -> float:
    """How far an optimal value can be from the optimum of an LP solved to the tolerances ``TOL``: the rows and
    bounds violated by ``TOL`` (times the multipliers) and the reduced costs off by ``TOL`` (times the ranges)."""
    return TOL * (np.sum(np.abs(duals)) + np.sum(lp.col_hi - lp.col_lo) + 1.0)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_a_chain_of_objectives_meets_the_optima_of_highs_and_certifies_them(seed: int) -> None:
    lp = _random_lp(seed, rows=30, cols=45)
    rng = np.random.default_rng(100 + seed)
    costs = rng.standard_normal((8, 45))
    _, basic, values, _ = _highs(lp, costs[0])
    dense = DenseSimplex(lp.matrix, TOL, TOL, pivot_limit=10_000)
    assert dense.start(lp.col_lo, lp.col_hi, lp.row_lo, lp.row_hi, basic, values)
    for cost in costs[1:]:
        optimal, pivots = dense.solve(cost)
        assert optimal and pivots >= 0
        reference, _, _, reference_duals = _highs(lp, cost)
        duals = dense.row_duals()
        value = cost @ dense.values()[:45]
        certified = dual_bounds(lp, cost[None], duals[None])[0]
        slack = _slack(lp, duals) + _slack(lp, reference_duals)
        assert abs(value - reference) <= slack
        assert reference - slack <= certified <= reference + slack  # the multipliers certify the optimum
        # the values are a basic solution within the bounds
        x = dense.values()
        assert np.all(x >= np.concatenate([lp.col_lo, lp.row_lo]) - TOL)
        assert np.all(x <= np.concatenate([lp.col_hi, lp.row_hi]) + TOL)
        np.testing.assert_allclose(lp.matrix @ x[:45], x[45:], atol=1e-9 * (1 + np.abs(x[45:]).max()))
        statuses = dense.statuses()
        assert np.count_nonzero(statuses == 1) == 30
        np.testing.assert_array_equal(np.sort(dense.basic_variables()), np.sort(basic_to_highs(statuses, 45)))


def basic_to_highs(statuses: np.ndarray, cols: int) -> np.ndarray:
    """The basic variables of ``statuses`` in HiGHS's convention."""
    index = np.flatnonzero(statuses == 1)
    return np.where(index < cols, index, cols - 1 - index)


def test_a_solve_past_its_pivot_limit_says_so_and_refuses_until_restarted() -> None:
    lp = _random_lp(7, rows=30, cols=45)
    costs = np.random.default_rng(70).standard_normal((2, 45))
    _, basic, values, _ = _highs(lp, costs[0])
    dense = DenseSimplex(lp.matrix, TOL, TOL, pivot_limit=1)
    assert dense.start(lp.col_lo, lp.col_hi, lp.row_lo, lp.row_hi, basic, values)
    optimal, pivots = dense.solve(-costs[0])  # the opposite objective: many pivots away
    assert not optimal and pivots <= 1 and not dense.ready
    assert dense.solve(costs[1]) == (False, 0)
    assert dense.start(lp.col_lo, lp.col_hi, lp.row_lo, lp.row_hi, basic, values)


def test_a_singular_basis_is_repaired_to_a_nonsingular_one() -> None:
    """Columns 0 and 1 of ``A`` are parallel: as a basis they are singular. One is kept, the other goes to a bound
    and a row's activity becomes basic; the solve then finds the optimum."""
    matrix = np.array([[1.0, 1.0], [2.0, 2.0]])
    dense = DenseSimplex(matrix, TOL, TOL, pivot_limit=100)
    ok = dense.start(-np.ones(2), np.ones(2), -np.ones(2), np.ones(2), np.array([0, 1]), np.zeros(4))
    assert ok and dense.ready
    statuses = dense.statuses()
    assert np.count_nonzero(statuses[:2] == 1) == 1 and np.count_nonzero(statuses[2:] == 1) == 1
    optimal, _ = dense.solve(np.array([1.0, 2.0]))  # min z0 + 2 z1 with |z0 + z1| ≤ 1/2: z1 = -1, z0 = 1/2
    assert optimal
    np.testing.assert_allclose(dense.values()[:2], [0.5, -1.0], atol=1e-12)


def test_degenerate_vertex_many_rows_through_one_point() -> None:
    """Twenty rows, all tight at the optimum of the first objective (z = 0 in a box around it): the next objectives
    move along degenerate pivots; each ends optimal at the optimum HiGHS finds, or says it did not."""
    rng = np.random.default_rng(3)
    matrix = rng.standard_normal((20, 6))
    matrix[:, 0] = np.abs(matrix[:, 0]) + 0.1
    lp = SimpleNamespace(
        matrix=matrix,
        matrix_t=np.ascontiguousarray(matrix.T),
        abs_matrix_t=np.abs(matrix.T),
        col_nnz=20,
        col_lo=-np.ones(6),
        col_hi=np.ones(6),
        row_lo=np.zeros(20),  # A z ≥ 0: a cone with apex at 0, cut by the box
        row_hi=np.full(20, np.inf),
    )
    first = np.zeros(6)
    first[0] = 1.0  # min z0 over the cone: 0, at the apex
    _, basic, values, _ = _highs(lp, first)
    dense = DenseSimplex(lp.matrix, TOL, TOL, pivot_limit=1000)
    assert dense.start(lp.col_lo, lp.col_hi, lp.row_lo, lp.row_hi, basic, values)
    for cost in np.vstack([rng.standard_normal((6, 6)), first]):
        optimal, _ = dense.solve(cost)
        reference, _, _, reference_duals = _highs(lp, cost)
        if not optimal:
            assert not dense.ready
            _, basic, values, _ = _highs(lp, cost)
            assert dense.start(lp.col_lo, lp.col_hi, lp.row_lo, lp.row_hi, basic, values)
            continue
        duals = dense.row_duals()
        slack = _slack(lp, duals) + _slack(lp, reference_duals)
        assert abs(cost @ dense.values()[:6] - reference) <= slack
        assert dual_bounds(lp, cost[None], duals[None])[0] >= reference - slack


@pytest.mark.parametrize("change", ["same", "too many basic", "too few basic", "other bounds"])
def test_a_kept_basis_is_completed_and_solved_from_by_the_dual_simplex(change: str) -> None:
    """A basis kept from another LP (as the hull keeps each objective's basis from the previous window): made
    square and nonsingular, then solved to the optimum HiGHS finds from scratch, by the dual simplex where its
    values violate bounds. Its rows are boxed or free, like the hull's: the dual simplex needs every nonbasic
    variable boxed (a one-sided one priced the wrong way cannot be flipped, and the solve says so)."""
    lp = _random_lp(11, rows=30, cols=45, one_sided=False)
    rng = np.random.default_rng(12)
    costs = rng.standard_normal((2, 45))
    _, basic, values, _ = _highs(lp, costs[0])
    dense = DenseSimplex(lp.matrix, TOL, TOL, pivot_limit=10_000)
    assert dense.start(lp.col_lo, lp.col_hi, lp.row_lo, lp.row_hi, basic, values)
    statuses = dense.statuses()
    if change == "too many basic":
        statuses[np.flatnonzero(statuses[:45] != 1)[:3]] = 1
    elif change == "too few basic":
        statuses[np.flatnonzero(statuses[:45] == 1)[:3]] = 0
    elif change == "other bounds":  # the next window's data: every row moved
        shift = rng.uniform(-0.3, 0.3, 30)
        lp.row_lo, lp.row_hi = lp.row_lo + shift, lp.row_hi + shift
    assert dense.start_from_statuses(lp.col_lo, lp.col_hi, lp.row_lo, lp.row_hi, statuses)
    assert np.count_nonzero(dense.statuses() == 1) == 30
    for cost in costs:
        optimal, _ = dense.solve(cost)
        assert optimal
        reference, _, _, reference_duals = _highs(lp, cost)
        duals = dense.row_duals()
        slack = _slack(lp, duals) + _slack(lp, reference_duals)
        assert abs(cost @ dense.values()[:45] - reference) <= slack
        assert dual_bounds(lp, cost[None], duals[None])[0] >= reference - slack


def test_load_kernels_runs_the_compiled_code_once() -> None:
    load_kernels()  # a 1 x 1 LP: start and solve, nothing to assert but that it runs


def _one_by_one(entry: float, col: tuple[float, float], row: tuple[float, float]) -> DenseSimplex:
    """The LP ``row_lo ≤ entry · z ≤ row_hi``, ``col_lo ≤ z ≤ col_hi``, started with the row's activity basic."""
    dense = DenseSimplex(np.array([[entry]]), TOL, TOL, pivot_limit=100)
    dense.start(
        np.array([col[0]]), np.array([col[1]]), np.array([row[0]]), np.array([row[1]]), np.array([-1]), np.zeros(2)
    )
    return dense


def test_every_exit_of_a_solve_is_reached_and_named() -> None:
    """Each way a solve ends, on an LP built to end there: the estimator reads the name (lp/chain.py)."""
    optimal = _one_by_one(2.0, (-1.0, 1.0), (-1.0, 1.0))
    assert optimal.exit == "started"
    assert optimal.solve(np.array([1.0]))[0] and optimal.exit == "optimal"
    np.testing.assert_allclose(optimal.values(), [-0.5, -1.0])  # the row 2z ≥ -1 is the binding one
    # z ≤ 1 and z ≥ 2: the dual simplex finds no variable that can repair the violated row
    infeasible = _one_by_one(1.0, (-1.0, 1.0), (2.0, 3.0))
    assert infeasible.solve(np.array([1.0])) == (False, 1) and infeasible.exit == "infeasible"
    assert not infeasible.ready
    # a free z and a free row: min z has no bound
    unbounded = _one_by_one(1.0, (-np.inf, np.inf), (-np.inf, np.inf))
    assert not unbounded.solve(np.array([1.0]))[0] and unbounded.exit == "unbounded"
    limited = _one_by_one(2.0, (-1.0, 1.0), (-1.0, 1.0))
    limited.pivot_limit = 0
    assert limited.solve(np.array([1.0])) == (False, 0) and limited.exit == "pivot limit"
    assert limited.solve(np.array([1.0])) == (False, 0) and limited.exit == "no basis"


def test_a_basis_whose_inverse_overflows_is_singular_and_refused() -> None:
    """A basic column of 1e-310 (subnormal): its inverse is infinite, so the start fails and every solve says so."""
    dense = DenseSimplex(np.array([[1e-310]]), TOL, TOL, pivot_limit=100)
    one = np.ones(1)
    assert not dense.start(-one, one, -one, one, np.array([0]), np.zeros(2))
    assert dense.exit == "singular basis" and not dense.ready
    assert dense.solve(one) == (False, 0) and dense.exit == "singular basis"
