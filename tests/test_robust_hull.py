"""RobustHullEstimator and robust_hull_lower_bound: soundness under interval ΔA, never wider than the
IntervalObserver it is intersected with, the lower bound inside every sound box, the linearisation bound."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from scipy.linalg import expm

from intervalobs import Bounds, IntervalObserver, LTISystem, simulate
from intervalobs.errors import ArgumentTypeError, AssumptionError, BoundsError, DataError
from intervalobs.observers.robust_hull import RobustHullEstimator
from intervalobs.systems.sampling import delta_linearisation
from intervalobs.tightness import robust_hull_lower_bound

STEPS = 40
H_CONTINUOUS = 0.05


def random_system(seed: int, continuous: bool) -> tuple[LTISystem, Bounds]:
    """A random observable-ish 3-5 state system with ΔA on a random third of the entries."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 6))
    p = int(rng.integers(1, 3))
    A = rng.normal(size=(n, n))
    if continuous:
        A = A / np.max(np.abs(np.linalg.eigvals(A))) - 0.6 * np.eye(n)
    else:
        A = 0.85 * A / np.max(np.abs(np.linalg.eigvals(A)))
    radius = np.where(rng.uniform(size=(n, n)) < 0.35, 0.02 * (1.0 + np.abs(A)), 0.0)
    radius[0, 0] = 0.02  # at least one uncertain entry
    C = rng.normal(size=(p, n))
    B = rng.normal(size=(n, 1))
    system = LTISystem(A, C, B=B, E=np.eye(n), dt=None if continuous else 1.0, dA=(-radius, radius))
    bounds = Bounds(
        (-np.ones(n), np.ones(n)), w=(-0.05 * np.ones(n), 0.05 * np.ones(n)), v=(-0.1 * np.ones(p), 0.1 * np.ones(p))
    )
    return system, bounds


def record(
    system: LTISystem, bounds: Bounds, seed: int, vertex: bool
) -> tuple[np.ndarray, np.ndarray, Any, np.ndarray]:
    """Extreme (bang-bang) noise; ΔA at a box vertex, or at a random point of the box."""
    h = H_CONTINUOUS if system.continuous else 1.0
    t = np.arange(STEPS) * h
    u = np.sin(0.3 * np.arange(STEPS))[:, None]
    assert system.dA is not None
    lo, hi = system.dA
    rng = np.random.default_rng(seed + 100)
    delta = (
        np.where(rng.integers(0, 2, size=lo.shape) == 1, hi, lo)
        if vertex
        else lo + (hi - lo) * rng.uniform(size=lo.shape)
    )
    truth = LTISystem(system.A + delta, system.C, B=system.B, E=system.E, dt=system.dt)
    sim = simulate(truth, bounds, t, u=u, noise="extreme", seed=seed)
    return t, u, sim, delta


CASES = [(seed, continuous, vertex) for seed in range(3) for continuous in (False, True) for vertex in (True, False)]


@pytest.mark.parametrize(
    ("seed", "continuous", "vertex"),
    CASES,
    ids=[f"seed{s}-{'ct' if c else 'dt'}-{'vertex' if v else 'random'}" for s, c, v in CASES],
)
def test_sound_and_never_wider_than_the_interval_observer(seed: int, continuous: bool, vertex: bool) -> None:
    system, bounds = random_system(seed, continuous)
    t, u, sim, _ = record(system, bounds, seed, vertex)
    h = H_CONTINUOUS if continuous else None
    interval = IntervalObserver.design(system, bounds, h=h)
    base = interval.run(t, sim.y, u)
    alone = RobustHullEstimator.design(system, bounds, horizon=10, h=h, fallback=False).run(t, sim.y, u)
    robust = RobustHullEstimator.design(system, bounds, horizon=10, h=h, fallback=interval).run(t, sim.y, u)
    assert alone.enclosure(sim.x).max_violation == 0.0
    assert robust.enclosure(sim.x).max_violation == 0.0
    assert np.all(robust.lower >= base.lower) and np.all(robust.upper <= base.upper)
    # The LP is what makes it narrow: alone it is narrower than the interval observer after the transient.
    assert np.mean(alone.width()[10:]) < np.mean(base.width()[10:])


def test_identification_keeps_the_true_delta_a_and_stays_sound() -> None:
    system, bounds = random_system(1, continuous=False)
    t, u, sim, delta = record(system, bounds, 1, vertex=True)
    estimator = RobustHullEstimator.design(system, bounds, horizon=10, identify=True)
    estimate = estimator.run(t, sim.y, u)
    assert estimate.enclosure(sim.x).max_violation == 0.0
    lo, hi = (np.asarray(b) for b in estimate.meta["delta_box"])
    assert np.all(lo <= delta) and np.all(delta <= hi)


def test_step_and_run_agree() -> None:
    system, bounds = random_system(2, continuous=False)
    t, u, sim, _ = record(system, bounds, 2, vertex=False)
    estimator = RobustHullEstimator.design(system, bounds, horizon=8)
    estimate = estimator.run(t, sim.y, u)
    state = estimator.init()
    for k in range(STEPS - 1):
        state = estimator.step(state, sim.y[k], u[k])
        np.testing.assert_allclose(state.lower, estimate.lower[k + 1], rtol=0, atol=1e-12)
        np.testing.assert_allclose(state.upper, estimate.upper[k + 1], rtol=0, atol=1e-12)
        # the state holds the window only: y, u up to y_k from max(k + 2 - H, 0), boxes up to x_{k+1}
        rows = min(k + 2, 8)
        assert state.internal["start"] == k + 2 - rows
        assert state.internal["y"].shape == (rows - 1, system.p)
        assert state.internal["box_lo"].shape == (rows, system.n)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_linearisation_remainder_bounds_the_sampled_matrix(seed: int) -> None:
    """``e^{(A_c + δ)h} = Φ_c + Σ δ_l M_l + R`` with ``|R| ≤ R_x`` for every δ of the box (vertices and inside)."""
    system, bounds = random_system(seed, continuous=True)
    model = delta_linearisation(system, bounds, H_CONTINUOUS)
    rng = np.random.default_rng(seed)
    rows = np.array([a for a, _ in model.entries])
    cols = np.array([b for _, b in model.entries])
    for trial in range(20):
        step = model.radius[rows, cols] * (
            rng.choice([-1.0, 1.0], size=rows.size) if trial % 2 else rng.uniform(-1, 1, size=rows.size)
        )
        delta = np.zeros_like(system.A)
        delta[rows, cols] = step
        exact = expm((system.A + model.center + delta) * H_CONTINUOUS)
        linear = model.Phi + np.einsum("l,lij->ij", step, model.M)
        assert np.all(np.abs(exact - linear) <= model.R_x)
    # The remainder is second order: much smaller than the first-order term.
    assert np.max(model.R_x) < 0.1 * np.max(np.einsum("l,lij->ij", model.radius[rows, cols], np.abs(model.M)))


@pytest.mark.parametrize("continuous", [False, True], ids=["discrete", "continuous"])
def test_lower_bound_lies_inside_every_sound_box(continuous: bool) -> None:
    system, bounds = random_system(3, continuous)
    t, u, sim, _ = record(system, bounds, 3, vertex=True)
    h = H_CONTINUOUS if continuous else None
    estimator = RobustHullEstimator.design(system, bounds, horizon=10, h=h)
    estimate = estimator.run(t, sim.y, u)
    interval = IntervalObserver.design(system, bounds, h=h).run(t, sim.y, u)
    steps = np.array([10, 25, 39])
    bound = robust_hull_lower_bound(
        system, bounds, t, sim.y, u, h=h, candidates=estimator.extremal_deltas(STEPS), steps=steps, search=1, substeps=2
    )
    width = bound.width()[steps]
    assert np.all(np.isfinite(width)) and np.all(width >= 0)
    for box in (estimate, interval):
        assert np.all(box.lower[steps] <= bound.lower[steps]) and np.all(box.upper[steps] >= bound.upper[steps])
    assert np.all(np.isnan(bound.width()[np.setdiff1d(np.arange(STEPS), steps)]))


def test_errors_name_the_argument() -> None:
    system, bounds = random_system(0, continuous=True)
    with pytest.raises(ArgumentTypeError, match=r"^h: expected a positive sampling period"):
        RobustHullEstimator.design(system, bounds)
    with pytest.raises(DataError, match="horizon"):
        RobustHullEstimator.design(system, bounds, horizon=0, h=0.1)
    point = LTISystem(system.A, system.C, dt=1.0)
    with pytest.raises(AssumptionError, match="dA"):
        RobustHullEstimator.design(point, bounds)
    t = np.arange(5) * 0.1
    assert system.dA is not None
    with pytest.raises(BoundsError, match="candidates"):
        robust_hull_lower_bound(system, bounds, t, np.zeros((5, system.p)), h=0.1, candidates=[2 * system.dA[1] + 1])


FAST = {(0, False, True), (1, True, False)}
"""The McCormick cases of the default suite (its sparse LPs cost 10-100 times the split LP's); the others are slow."""


@pytest.mark.parametrize(
    ("seed", "continuous", "vertex"),
    [pytest.param(*case, marks=() if case in FAST else pytest.mark.slow) for case in CASES],
    ids=[f"seed{s}-{'ct' if c else 'dt'}-{'vertex' if v else 'random'}" for s, c, v in CASES],
)
def test_mccormick_sound_and_inside_the_split_window(seed: int, continuous: bool, vertex: bool) -> None:
    """The McCormick LP's set lies inside the split LP's: its boxes are sound and never wider."""
    system, bounds = random_system(seed, continuous)
    t, u, sim, _ = record(system, bounds, seed, vertex)
    steps = 40 if (seed, continuous, vertex) not in FAST else 12
    t, u, y, x = t[:steps], u[:steps], sim.y[:steps], sim.x[:steps]
    h = H_CONTINUOUS if continuous else None
    horizon = 4 if steps != 40 else 6 if continuous else 10  # continuous: n_δ n products per step
    interval = IntervalObserver.design(system, bounds, h=h)
    base = interval.run(t, y, u)
    split = RobustHullEstimator.design(system, bounds, horizon=horizon, h=h, fallback=False).run(t, y, u)
    alone = RobustHullEstimator.design(system, bounds, horizon=horizon, h=h, mccormick=True, fallback=False).run(
        t, y, u
    )
    robust = RobustHullEstimator.design(system, bounds, horizon=horizon, h=h, mccormick=True, fallback=interval)
    both = robust.run(t, y, u)
    assert alone.meta["mccormick"] is True
    assert alone.enclosure(x).max_violation == 0.0
    for estimate in (split, alone):  # the route of every step: HiGHS only, every objective solved
        paths = estimate.meta["solver_path"]
        assert len(paths) == steps - 1 and all(path["dense"] == 0 and path["failed"] == 0 for path in paths)
        assert all(path["highs_warm"] + path["scratch"] >= 2 * system.n for path in paths)
    assert both.enclosure(x).max_violation == 0.0
    assert np.all(both.lower >= base.lower) and np.all(both.upper <= base.upper)
    # Certified bounds sit within HiGHS's tolerances (1e-9, times column magnitudes ≤ 1e3) of the LP optimum.
    assert np.all(alone.lower >= split.lower - 1e-6) and np.all(alone.upper <= split.upper + 1e-6)
    assert np.mean(alone.width()[horizon:]) < np.mean(split.width()[horizon:])


def window_lp_reference(estimator: RobustHullEstimator, call: tuple[Any, ...], delta: tuple[Any, Any]) -> np.ndarray:
    """The McCormick window LP built from its definition (time-ordered, dense, no pads) and solved by scipy.

    ``call`` holds the arguments of one ``_box`` call, ``delta`` the box of ``ΔA - ΔA_c`` then. Returns
    the minima and maxima of ``x_k`` (2, n). Every product ``δ_l x_{j,b}`` is a variable (also those no
    dynamics row uses: their envelopes do not change the set of states).
    """
    from scipy.optimize import linprog

    k, start, ys, us, box_lo, box_hi, predicted = call
    mod, n, p, m = estimator.model, estimator.n, estimator.p, estimator.m
    nd = len(mod.entries)
    rows_a = [a for a, _ in mod.entries]
    cols_b = [b for _, b in mod.entries]
    d_lo, d_hi = delta[0][rows_a, cols_b], delta[1][rows_a, cols_b]
    L = min(k, estimator.horizon)
    first = k - L - start
    ys, us, lo, hi = ys[first : first + L], us[first : first + L], box_lo[first : first + L], box_hi[first : first + L]
    nx, ne, nq = (L + 1) * n, L * n, L * nd * n
    ncol = nx + ne + nq + nd

    def x(j: int, i: int) -> int:
        return j * n + i

    def q(j: int, l: int, b: int) -> int:
        return nx + ne + (j * nd + l) * n + b

    eq, eq_rhs, ub, ub_rhs = [], [], [], []
    for j in range(L):
        for i in range(n):  # x_{j+1} - Φ x_j - Σ M_l q_l - Σ (N_l u_j) δ_l - e_j = Γ u_j
            row = np.zeros(ncol)
            row[x(j + 1, i)] += 1.0
            row[[x(j, b) for b in range(n)]] -= mod.Phi[i]
            row[nx + j * n + i] -= 1.0
            for l in range(nd):
                for b in range(n):
                    row[q(j, l, b)] -= mod.M[l, i, b]
                row[nx + ne + nq + l] -= mod.N[l, i] @ us[j] if m else 0.0
            eq.append(row)
            eq_rhs.append(mod.Gamma[i] @ us[j] if m else 0.0)
        for r in range(p):  # y_j - v_hi <= C x_j <= y_j - v_lo
            row = np.zeros(ncol)
            row[[x(j, b) for b in range(n)]] = mod.C[r]
            ub += [row, -row]
            ub_rhs += [ys[j, r] - mod.v_lo[r], -(ys[j, r] - mod.v_hi[r])]
        for l in range(nd):
            for b in range(n):  # the four McCormick envelopes of q = δ_l x_{j,b}
                for sign, a, c in (
                    (-1, d_lo[l], lo[j, b]),
                    (-1, d_hi[l], hi[j, b]),
                    (1, d_lo[l], hi[j, b]),
                    (1, d_hi[l], lo[j, b]),
                ):
                    row = np.zeros(ncol)  # sign (q - a x - c δ + a c) <= 0
                    row[q(j, l, b)], row[x(j, b)], row[nx + ne + nq + l] = sign, -sign * a, -sign * c
                    ub.append(row)
                    ub_rhs.append(-sign * a * c)
    big = np.maximum(np.abs(lo), np.abs(hi))
    rho = big @ mod.R_x.T + np.abs(us) @ mod.R_u.T
    bounds = [(lo[j, i], hi[j, i]) for j in range(L) for i in range(n)]
    bounds += [(predicted[0][i], predicted[1][i]) for i in range(n)]
    bounds += [(mod.noise_lo[i] - rho[j, i], mod.noise_hi[i] + rho[j, i]) for j in range(L) for i in range(n)]
    bounds += [(None, None)] * nq + list(zip(d_lo, d_hi, strict=True))
    out = np.zeros((2, n))
    for i in range(n):
        for side, sign in enumerate((1.0, -1.0)):
            cost = np.zeros(ncol)
            cost[x(L, i)] = sign
            res = linprog(
                cost,
                A_ub=np.array(ub) if ub else None,
                b_ub=ub_rhs or None,
                A_eq=np.array(eq) if eq else None,
                b_eq=eq_rhs or None,
                bounds=bounds,
                method="highs",
                options={"primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10},
            )
            assert res.status == 0
            out[side, i] = sign * res.fun
    return out


@pytest.mark.parametrize(
    ("seed", "continuous", "identify"),
    [(0, False, False), (1, False, True), (1, True, False)],
    ids=["dt", "dt-identify", "ct"],
)
def test_mccormick_fixed_model_gives_the_lp_optimum(seed: int, continuous: bool, identify: bool) -> None:
    """The McCormick LP kept as one HiGHS model (cyclic slots, coefficients updated, warm-started) certifies
    the optimum of the same LP built from its definition at every step, through the window's wrap-around.

    Tolerance: both solvers meet feasibility tolerances of 1e-9 / 1e-10, so the optima differ by at most
    about 1e-9 times the sum of the columns' magnitudes (≤ ncol (1 + max |bound|) ≲ 300 · 3); the
    certificate's rounding pads are ~1e-13 here.
    """
    system, bounds = random_system(seed, continuous)
    t, u, sim, _ = record(system, bounds, seed, vertex=True)
    steps, horizon = 14, 4
    h = H_CONTINUOUS if continuous else None
    estimator = RobustHullEstimator.design(system, bounds, horizon=horizon, h=h, identify=identify, mccormick=True)
    calls: list[tuple[tuple[Any, ...], tuple[Any, Any], Any]] = []
    box = estimator._box

    def recorded(*args: Any) -> Any:
        delta = (estimator.delta_box[0].copy(), estimator.delta_box[1].copy())
        out = box(*args)
        calls.append((args, delta, out))
        return out

    estimator._box = recorded  # type: ignore[method-assign]
    for run in range(2):  # a second run starts from scratch: the same boxes
        est = estimator.run(t[:steps], sim.y[:steps], u[:steps])
        if run == 0:
            first = est
    np.testing.assert_array_equal(est.lower, first.lower)
    assert est.enclosure(sim.x[:steps]).max_violation == 0.0
    assert len(calls) == 2 * (steps - 1)
    for args, delta, (lower, upper) in calls[: steps - 1]:
        ref = window_lp_reference(estimator, args, delta)
        scale = 1e-9 * 300 * (1.0 + np.max(np.abs(np.concatenate([args[4], args[5]]))))

        assert np.all(np.abs(lower - ref[0]) <= scale), (args[0], lower, ref[0])
        assert np.all(np.abs(upper - ref[1]) <= scale), (args[0], upper, ref[1])
