"""HullEstimator and hull_lower_bound: soundness, exactness, containment in every sound observer."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from scipy.optimize import linprog

from conftest import random_system
from intervalobs import Bounds, Estimate, IntervalObserver, LTISystem, simulate
from intervalobs.errors import AssumptionError, DataError, IntervalObserverError
from intervalobs.observers.hull import HullEstimator
from intervalobs.tightness import HullLowerBound, hull_lower_bound

STEPS = 40


def small_discrete() -> tuple[LTISystem, Bounds]:
    A = np.array([[0.8, 0.1, 0.3], [0.0, 0.8, 0.2], [0.01, 0.0, 0.8]])
    system = LTISystem(A, [[0.0, 0.0, 1.0]], B=[[0.0], [0.0], [1.0]], E=0.08 * np.eye(3), F=[[0.2]], dt=1.0)
    bounds = Bounds((-np.ones(3), np.ones(3)), w=(-np.ones(3), np.ones(3)), v=(-np.ones(1), np.ones(1)))
    return system, bounds


def scale(*arrays: np.ndarray) -> np.ndarray:
    return 1.0 + np.max(np.abs(np.stack(arrays)), axis=0)


# A certified LP bound lies outward of the exact optimum by its dual slack (≲ 1e-8 here); two sound
# boxes that both touch the exact hull can therefore differ by that much in either direction.
SLACK = 1e-7


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_hull_encloses_truth_under_extreme_noise(seed: int) -> None:
    system, bounds = small_discrete()
    t = np.arange(STEPS, dtype=float)
    u = np.sin(t)[:, None]
    sim = simulate(system, bounds, t, u=u, noise="extreme", seed=seed)
    for filtered in (False, True):
        est = HullEstimator.design(system, bounds, horizon=10, filtered=filtered).run(t, sim.y, u)
        report = est.enclosure(sim.x)
        assert report.max_violation == 0.0 and report.fraction == 1.0


def test_hull_continuous_time_sound_with_switching_noise() -> None:
    system, bounds = random_system(5, 2, 1, continuous=True, uncertain=False)
    h = 0.1
    t = np.arange(30) * h
    sim = simulate(system, bounds, t, noise="extreme", seed=5, substeps=10)
    est = HullEstimator.design(system, bounds, horizon=8, h=h).run(t, sim.y, sim.u)
    assert est.enclosure(sim.x).max_violation == 0.0


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_hull_inside_every_sound_observer(seed: int) -> None:
    system, bounds = small_discrete()
    t = np.arange(STEPS, dtype=float)
    sim = simulate(system, bounds, t, noise="extreme", seed=seed)
    hull = HullEstimator.design(system, bounds, horizon=None).run(t, sim.y, sim.u)
    observers = {
        "tube": IntervalObserver.design(system, bounds),
        "framer": IntervalObserver.design(system, bounds, method="framer"),
        "paper gain": IntervalObserver(system, bounds, [[0.3], [0.2], [0.8]], method="framer"),
    }
    for name, obs in observers.items():
        est = obs.run(t, sim.y, sim.u)
        tol = SLACK * scale(est.lower, est.upper)
        assert np.all(est.lower <= hull.lower + tol), name
        assert np.all(est.upper >= hull.upper - tol), name
        assert np.sum(est.width()) > np.sum(hull.width()), name


@pytest.mark.parametrize("window_boxes", [False, True], ids=["prior-only", "window-boxes"])
@pytest.mark.parametrize("horizon", [1, 2, 5])
def test_short_horizon_is_sound_and_contains_the_exact_hull(horizon: int, window_boxes: bool) -> None:
    system, bounds = small_discrete()
    t = np.arange(STEPS, dtype=float)
    sim = simulate(system, bounds, t, noise="extreme", seed=7)
    exact = HullEstimator.design(system, bounds, horizon=None).run(t, sim.y, sim.u)
    windowed = HullEstimator.design(system, bounds, horizon=horizon, window_boxes=window_boxes).run(t, sim.y, sim.u)
    assert windowed.enclosure(sim.x).max_violation == 0.0
    tol = SLACK * scale(exact.lower, exact.upper)
    assert np.all(windowed.lower <= exact.lower + tol)
    assert np.all(windowed.upper >= exact.upper - tol)


def test_full_horizon_is_exact_and_certificate_is_tight() -> None:
    system, bounds = small_discrete()
    t = np.arange(25, dtype=float)
    sim = simulate(system, bounds, t, noise="extreme", seed=3)
    full = HullEstimator.design(system, bounds, horizon=None).run(t, sim.y, sim.u)
    long_window = HullEstimator.design(system, bounds, horizon=30).run(t, sim.y, sim.u)
    np.testing.assert_allclose(full.lower, long_window.lower, atol=1e-7)
    np.testing.assert_allclose(full.upper, long_window.upper, atol=1e-7)
    # The certified bound is outward of the exact optimum by at most the solver's tolerance.
    from scipy.optimize import linprog

    k = 24
    n = 3
    # LP over (x_0..x_k): dynamics box rows, measurements, x0 box; minimise x_k[0].
    nx = (k + 1) * n
    rows, lo, hi = [], [], []
    A, C = system.A, system.C
    for j in range(k):
        block = np.zeros((n, nx))
        block[:, (j + 1) * n : (j + 2) * n] = np.eye(n)
        block[:, j * n : (j + 1) * n] = -A
        rows.append(block)
        lo.append(-0.08 * np.ones(n))
        hi.append(0.08 * np.ones(n))
        meas = np.zeros((1, nx))
        meas[:, j * n : (j + 1) * n] = C
        rows.append(meas)
        lo.append(sim.y[j] - 0.2)
        hi.append(sim.y[j] + 0.2)
    M = np.vstack(rows)
    a_ub = np.vstack([M, -M])
    b_ub = np.concatenate([np.concatenate(hi), -np.concatenate(lo)])
    cost = np.zeros(nx)
    cost[k * n] = 1.0
    res = linprog(cost, A_ub=a_ub, b_ub=b_ub, bounds=[(-1, 1)] * n + [(None, None)] * (nx - n), method="highs")
    assert res.status == 0
    assert full.lower[k, 0] <= res.fun + 1e-9
    assert full.lower[k, 0] >= res.fun - 1e-6


@pytest.mark.parametrize(
    ("horizon", "options"),
    [(4, {}), (4, {"filtered": True}), (4, {"window_boxes": True}), (None, {"filtered": True})],
    ids=["condensed", "condensed-filtered", "window-lp", "full-history"],
)
def test_run_matches_repeated_step(horizon: int | None, options: dict[str, bool]) -> None:
    system, bounds = small_discrete()
    t = np.arange(15, dtype=float)
    u = np.cos(t)[:, None]
    sim = simulate(system, bounds, t, u=u, noise="extreme", seed=2)
    est = HullEstimator.design(system, bounds, horizon=horizon, **options).run(t, sim.y, u)
    stepper = HullEstimator.design(system, bounds, horizon=horizon, **options)
    assert est.meta["rows"] == stepper.rows == ("filtered" if options.get("filtered") else "predicted")
    state = stepper.init()
    rows = [] if stepper.rows == "filtered" else [state]
    for k in range(t.size - len(rows)):
        state = stepper.step(state, sim.y[k], u[k])
        rows.append(state)
    np.testing.assert_allclose(est.lower, [r.lower for r in rows], rtol=0, atol=1e-12)
    np.testing.assert_allclose(est.upper, [r.upper for r in rows], rtol=0, atol=1e-12)


def test_step_keeps_the_last_horizon_samples_only() -> None:
    """Time and memory per step do not grow with k: the state holds ``horizon`` rows at every step."""
    import time

    system, bounds = small_discrete()
    t = np.arange(1001, dtype=float)
    u = np.cos(t)[:, None]
    sim = simulate(system, bounds, t, u=u, noise="extreme", seed=5)
    stepper = HullEstimator.design(system, bounds, horizon=5)
    state, sizes, seconds = stepper.init(), {}, np.zeros(t.size)
    for k in range(t.size):
        clock = time.perf_counter()
        state = stepper.step(state, sim.y[k], u[k])
        seconds[k] = time.perf_counter() - clock
        if k + 1 in (10, 1000):
            sizes[k + 1] = {key: np.shape(value) for key, value in state.internal.items() if key != "x0"}
            assert state.internal["start"] == k + 1 - 5
    assert sizes[10] == sizes[1000] and sizes[10]["y"] == (5, 1) and sizes[10]["box_lo"] == (5, 3)
    # the median over 50 steps: late steps cost what early ones cost (a record rebuilt every step would not)
    assert np.median(seconds[950:1000]) < 3.0 * np.median(seconds[10:60])


def test_general_noise_matrices_use_noise_variables() -> None:
    A = np.array([[0.9, 0.2], [-0.1, 0.7]])
    E = np.array([[1.0], [0.5]])  # one channel drives both states: E·W is a segment, not a box
    F = np.array([[1.0, 0.3]])
    system = LTISystem(A, [[1.0, 0.0]], E=E, F=F, dt=1.0)
    bounds = Bounds((-np.ones(2), np.ones(2)), w=([-0.1], [0.1]), v=([-0.05, -0.05], [0.05, 0.05]))
    t = np.arange(30, dtype=float)
    sim = simulate(system, bounds, t, noise="extreme", seed=4)
    est = HullEstimator.design(system, bounds, horizon=6).run(t, sim.y, sim.u)
    assert est.enclosure(sim.x).max_violation == 0.0
    obs = IntervalObserver.design(system, bounds).run(t, sim.y, sim.u)
    assert np.all(obs.lower <= est.lower + SLACK) and np.all(obs.upper >= est.upper - SLACK)


def test_interval_dA_is_refused() -> None:
    system, bounds = random_system(1, 2, 1, continuous=False, uncertain=True)
    with pytest.raises(AssumptionError, match="hull_lower_bound"):
        HullEstimator.design(system, bounds)


def test_lower_bound_is_inside_sound_observers_and_not_an_estimate() -> None:
    system, bounds = small_discrete()
    d = 0.01 * np.ones((3, 3))
    uncertain = LTISystem(system.A, system.C, B=system.B, E=system.E, F=system.F, dt=1.0, dA=(-d, d))
    t = np.arange(30, dtype=float)
    sim = simulate(uncertain, bounds, t, noise="extreme", seed=1)
    bound = hull_lower_bound(uncertain, bounds, t, sim.y, sim.u, samples=2, horizon=10, truth=(sim.dA, sim.x))
    assert isinstance(bound, HullLowerBound) and not isinstance(bound, Estimate)
    assert "not an estimate" in bound.label
    assert bound.alive[0]  # the true ΔA with its truth anchor stays consistent
    est = IntervalObserver.design(uncertain, bounds).run(t, sim.y, sim.u)
    ok = np.isfinite(bound.lower)
    assert ok.all()
    assert np.all(est.lower[ok] <= bound.lower[ok]) and np.all(est.upper[ok] >= bound.upper[ok])
    # With the true ΔA alone, the inner hull lies inside the (outer, certified) hull of that model.
    alone = hull_lower_bound(uncertain, bounds, t, sim.y, sim.u, samples=0, horizon=10, truth=(sim.dA, sim.x))
    exact_known = HullEstimator.design(
        LTISystem(system.A + sim.dA, system.C, B=system.B, E=system.E, F=system.F, dt=1.0), bounds, horizon=None
    ).run(t, sim.y, sim.u)
    assert np.all(alone.lower >= exact_known.lower - SLACK) and np.all(alone.upper <= exact_known.upper + SLACK)
    assert np.all(alone.width() <= bound.width() + 1e-12)


def test_condensed_window_agrees_with_the_sparse_window() -> None:
    system, bounds = small_discrete()
    t = np.arange(STEPS, dtype=float)
    u = np.sin(t)[:, None]
    sim = simulate(system, bounds, t, u=u, noise="extreme", seed=9)
    condensed = HullEstimator.design(system, bounds, horizon=6)
    assert condensed.meta()["condensed"]
    sparse_form = HullEstimator.design(system, bounds, horizon=6)
    sparse_form._condensed = None  # same LP (prior box only), states kept as variables
    a, b = condensed.run(t, sim.y, u), sparse_form.run(t, sim.y, u)
    assert a.enclosure(sim.x).max_violation == 0.0
    np.testing.assert_allclose(a.lower, b.lower, atol=1e-7)
    np.testing.assert_allclose(a.upper, b.upper, atol=1e-7)


@pytest.mark.parametrize("seed", [1, 4, 8])
def test_condensed_window_agrees_with_the_sparse_window_on_random_systems(seed: int) -> None:
    # Seed 4: a restored (shifted, alien) basis that HiGHS completes into a near-singular one makes
    # run() fail at k = 11; the LP must then be solved from scratch, not left with stale multipliers.
    n, p = 2 + seed % 4, 1 + seed % 2
    plain, bounds = random_system(seed, n, p, continuous=False, uncertain=False)
    system = LTISystem(plain.A, plain.C, B=np.random.default_rng(seed).normal(size=(n, 1)), dt=1.0)
    t = np.arange(60, dtype=float)
    u = np.sin(0.3 * t)[:, None]
    sim = simulate(system, bounds, t, u=u, noise="extreme", seed=seed)
    condensed = HullEstimator.design(system, bounds, horizon=8)
    assert condensed.meta()["condensed"]
    sparse_form = HullEstimator.design(system, bounds, horizon=8)
    sparse_form._condensed = None
    a, b = condensed.run(t, sim.y, u), sparse_form.run(t, sim.y, u)
    assert a.enclosure(sim.x).max_violation == 0.0
    tol = SLACK * scale(b.lower, b.upper)
    assert np.all(np.abs(a.lower - b.lower) <= tol) and np.all(np.abs(a.upper - b.upper) <= tol)


def test_certificates_one_per_condensed_solve_and_refused_otherwise() -> None:
    system, bounds = small_discrete()
    t = np.arange(STEPS, dtype=float)
    u = np.sin(t)[:, None]
    sim = simulate(system, bounds, t, u=u, noise="extreme", seed=4)
    certs = HullEstimator.design(system, bounds, horizon=6).certificates(t, sim.y, u)
    assert set(certs) == {(i, s) for i in range(3) for s in (1.0, -1.0)}
    for duals in certs.values():
        assert duals.shape == (STEPS - 1 - 6, 7, 1)  # steps k = 7 … T-1, rows j = 0 … 6
        assert np.all(duals[:, -1] == 0.0)  # predicted hull: y_k is not a row
    with pytest.raises(AssumptionError, match="condensed"):
        HullEstimator.design(system, bounds, horizon=None).certificates(t, sim.y, u)


def test_certificates_reuse_given_multipliers_instead_of_solving() -> None:
    """reuse: objectives given multipliers are not solved nor logged, and the box they give is still sound (any
    multipliers are: zero multipliers bound x_k by the prior and the noise box alone)."""
    system, bounds = small_discrete()
    t = np.arange(40, dtype=float)
    u = np.sin(t)[:, None]
    sim = simulate(system, bounds, t, u=u, noise="extreme", seed=5)
    calls = []

    def reuse(lp: object, costs: np.ndarray) -> np.ndarray:
        given = np.zeros((costs.shape[0], lp.nrow))  # type: ignore[attr-defined]
        given[:2] = np.nan  # component 0 solved, the others bounded by zero multipliers
        calls.append(costs.shape[0])
        return given

    hull = HullEstimator.design(system, bounds, horizon=6)
    certs = hull.certificates(t, sim.y, u, first_rows=True, reuse=reuse)
    assert len(calls) == t.size - 1 and set(calls) == {2 * system.n}  # every window of the record
    assert all(len(found) == 0 for key, found in certs.items() if key[0] != 0)
    assert len(certs[(0, 1.0)]) == len(certs[(0, -1.0)]) == t.size - 1 - 6  # the full windows, component 0
    plain = hull.run(t, sim.y, u)
    lp = hull._condensed
    assert lp is not None
    lp.reuse = reuse
    try:
        loose = hull.run(t, sim.y, u)
    finally:
        lp.reuse = None
    report = loose.enclosure(sim.x)
    assert report.max_violation == 0.0 and report.fraction == 1.0
    assert np.all(loose.width()[6:, 1:] > plain.width()[6:, 1:])  # the reused components did not use the data
    # component 0 is solved, from the looser priors of the others: never tighter than with every LP solved
    assert np.all(loose.lower[:, 0] <= plain.lower[:, 0] + 1e-9) and np.all(
        loose.upper[:, 0] >= plain.upper[:, 0] - 1e-9
    )


def test_falls_back_to_the_default_threads_when_highs_runs_with_more() -> None:
    # HiGHS keeps one scheduler per process: started by another highspy user with 2 threads, it refuses
    # our one-thread runs; the estimator must then switch to the default and give the same bounds.
    script = """
import json
import numpy as np
from highspy import _core
other = _core._Highs()
other.setOptionValue("output_flag", False)
other.setOptionValue("threads", 2)
other.run()
from intervalobs import Bounds, LTISystem, simulate
from intervalobs.observers.hull import HullEstimator
A = np.array([[0.8, 0.1, 0.3], [0.0, 0.8, 0.2], [0.01, 0.0, 0.8]])
system = LTISystem(A, [[0.0, 0.0, 1.0]], B=[[0.0], [0.0], [1.0]], E=0.08 * np.eye(3), F=[[0.2]], dt=1.0)
bounds = Bounds((-np.ones(3), np.ones(3)), w=(-np.ones(3), np.ones(3)), v=(-np.ones(1), np.ones(1)))
t = np.arange(20, dtype=float)
sim = simulate(system, bounds, t, noise="extreme", seed=1)
est = HullEstimator.design(system, bounds, horizon=6)
out = est.run(t, sim.y, sim.u)
print(json.dumps({"threads": est._condensed.solver.getOptionValue("threads")[1], "lower": out.lower.tolist()}))
"""
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True)
    result = json.loads(done.stdout)
    assert result["threads"] == 0
    system, bounds = small_discrete()
    t = np.arange(20, dtype=float)
    sim = simulate(system, bounds, t, noise="extreme", seed=1)
    here = HullEstimator.design(system, bounds, horizon=6).run(t, sim.y, sim.u)
    np.testing.assert_allclose(np.array(result["lower"]), here.lower, rtol=0, atol=1e-12)


def test_parallel_workers_give_the_same_certified_box() -> None:
    system, bounds = small_discrete()
    t = np.arange(STEPS, dtype=float)
    u = np.sin(t)[:, None]
    sim = simulate(system, bounds, t, u=u, noise="extreme", seed=5)
    one = HullEstimator.design(system, bounds, horizon=8).run(t, sim.y, u)
    two = HullEstimator.design(system, bounds, horizon=8, workers=2)
    both = two.run(t, sim.y, u)
    assert two.meta()["workers"] == 2 and both.enclosure(sim.x).max_violation == 0.0
    np.testing.assert_allclose(both.lower, one.lower, atol=SLACK)
    np.testing.assert_allclose(both.upper, one.upper, atol=SLACK)
    for bad in (0, 1.5, True):
        with pytest.raises(IntervalObserverError, match="workers"):
            HullEstimator.design(system, bounds, horizon=8, workers=bad)  # type: ignore[arg-type]


def test_condensed_window_with_a_shared_noise_channel_is_the_window_lp() -> None:
    A = np.array([[0.8, 0.1, 0.3], [0.0, 0.8, 0.2], [0.01, 0.0, 0.8]])
    E = np.array([[0.08, 0.02], [0.0, 0.05], [0.03, 0.0]])  # each channel drives two states
    B, C = np.array([[0.0], [0.0], [1.0]]), np.array([[0.0, 0.0, 1.0]])
    system = LTISystem(A, C, B=B, E=E, F=[[0.2]], dt=1.0)
    bounds = Bounds((-np.ones(3), np.ones(3)), w=(-np.ones(2), np.ones(2)), v=(-np.ones(1), np.ones(1)))
    t = np.arange(STEPS, dtype=float)
    u = np.sin(t)[:, None]
    sim = simulate(system, bounds, t, u=u, noise="extreme", seed=3)
    hull = HullEstimator.design(system, bounds, horizon=6)
    assert hull.condensed_allowed() and hull.model.G is not None
    est = hull.run(t, sim.y, u)
    assert est.enclosure(sim.x).max_violation == 0.0
    # The sparse form also puts the propagated box of x_k inside the LP: never looser, nearly equal here.
    sparse_form = HullEstimator.design(system, bounds, horizon=6)
    sparse_form._condensed = None
    other = sparse_form.run(t, sim.y, u)
    assert np.all(est.lower <= other.lower + SLACK) and np.all(est.upper >= other.upper - SLACK)
    assert np.mean(est.width()) < 1.01 * np.mean(other.width())
    # At a full window the bound is the LP over (x_s, w_s … w_{k-1}) with the box of x_s as prior.
    k, s = 20, 14
    powers = [np.linalg.matrix_power(A, j) for j in range(7)]

    def state(j: int) -> tuple[np.ndarray, np.ndarray]:  # x_{s+j} = M z + q
        M = np.hstack([powers[j]] + [powers[j - 1 - i] @ E for i in range(j)] + [np.zeros((3, 2 * (6 - j)))])
        return M, sum((powers[j - 1 - i] @ B @ u[s + i] for i in range(j)), np.zeros(3))

    rows = [(C @ state(j)[0])[0] for j in range(6)]
    centres = np.array([sim.y[s + j, 0] - (C @ state(j)[1])[0] for j in range(6)])
    a_ub, b_ub = np.vstack([rows, np.negative(rows)]), np.concatenate([centres + 0.2, 0.2 - centres])
    box = list(zip(est.lower[s], est.upper[s], strict=True)) + [(-1.0, 1.0)] * 12
    M, q = state(6)
    for i in range(3):
        low = linprog(M[i], A_ub=a_ub, b_ub=b_ub, bounds=box, method="highs").fun + q[i]
        high = q[i] - linprog(-M[i], A_ub=a_ub, b_ub=b_ub, bounds=box, method="highs").fun
        # At least as tight as this window LP (tighter only where the propagated box of x_{k-1} cuts).
        assert est.lower[k, i] >= low - 1e-7 and est.upper[k, i] <= high + 1e-7


@pytest.mark.parametrize(
    "options",
    [
        {"horizon": 5, "filtered": True},
        {"horizon": 5, "window_boxes": True},
        {"horizon": 5, "processes": 2},
        {"horizon": None, "filtered": True, "processes": 3},
    ],
    ids=str,
)
def test_monte_carlo_runs_equal_separate_estimators(options: dict) -> None:
    """A run's boxes depend on its data only: ``init`` forgets the warm starts of earlier runs."""
    system, bounds = small_discrete()
    t = np.arange(20, dtype=float)
    u = np.cos(t)[:, None]
    sim = simulate(system, bounds, t, u=u, noise="extreme", seed=2, runs=3)
    together = HullEstimator.design(system, bounds, **options).run(t, sim.y, np.broadcast_to(u, (3, t.size, 1)))
    for i in range(3):
        alone = HullEstimator.design(system, bounds, **options).run(t, sim.y[i], u)
        np.testing.assert_array_equal(together.lower[i], alone.lower)
        np.testing.assert_array_equal(together.upper[i], alone.upper)


def test_thin_growing_windows_of_30_tanks_solve_at_the_first_attempt() -> None:
    """The growing windows from ``x_0`` of this record (``k`` = 5 … 9) are so thin that with HiGHS's default
    ``small_matrix_value`` (1e-9, dropping entries of the powers of Φ) HiGHS found no feasible point in them, even
    from scratch: about 80 failed runs a step. With ``SMALL_MATRIX_VALUE``, the widened rows and no primal bound
    perturbation every HiGHS run ends optimal, so no objective goes through the fallbacks; most objectives are
    solved by the dense simplex, a few (where it gives up) by HiGHS from its basis. Read from the route each step
    recorded (``meta["solver_path"]``)."""
    from intervalobs.examples.scale_cases import tank_cascade

    case = tank_cascade(30, steps=30)
    sim = case.simulate(seed=0, noise="vertex")
    estimate = HullEstimator.design(case.system, case.bounds, horizon=10).run(case.t[:12], sim.y[:12], case.u[:12])
    assert estimate.enclosure(sim.x[:12]).max_violation == 0.0
    paths = estimate.meta["solver_path"]
    assert len(paths) == 11  # one per step
    assert all(path["widened"] == 0 and path["failed"] == 0 for path in paths)  # every HiGHS run optimal
    assert all(path["dense"] + path["highs_warm"] >= 2 * 30 for path in paths)  # every objective solved
    assert sum(path["dense"] for path in paths) >= 0.9 * 11 * (2 * 30 - 1)  # almost all by the dense simplex


def test_thin_windows_under_vertex_noise_end_optimal_and_agree_with_the_sparse_window() -> None:
    """Vertex noise makes windows of the 6-tank cascade thin (inscribed slack about -1e-11): every solve must
    still end optimal (the widened LP of ``ROW_RELAX`` when the exact one does not), so no box keeps the loose
    multipliers of a failed solve."""
    from intervalobs.examples.scale_cases import tank_cascade

    case = tank_cascade(6, steps=40)
    sim = case.simulate(seed=0, noise="vertex")
    a = HullEstimator.design(case.system, case.bounds, horizon=10).run(case.t, sim.y, case.u)
    paths = a.meta["solver_path"]
    assert all(path["failed"] == 0 and path["dense"] + path["highs_warm"] + path["widened"] >= 12 for path in paths)
    assert a.enclosure(sim.x).max_violation == 0.0
    sparse_form = HullEstimator.design(case.system, case.bounds, horizon=10)
    sparse_form._condensed = None
    b = sparse_form.run(case.t, sim.y, case.u)
    assert all(path["dense"] == 0 for path in b.meta["solver_path"])  # the sparse LP: HiGHS only
    # Both certified; on these ill-conditioned windows (multipliers up to ~1e4) the two formulations' optima
    # agree to the solver tolerance 1e-9 times the multipliers' size, 1e-5 of (1 + |x|) (seen: 3.5e-6).
    tol = 1e-5 * scale(b.lower, b.upper)
    assert np.all(np.abs(a.lower - b.lower) <= tol) and np.all(np.abs(a.upper - b.upper) <= tol)
    # Not systematically looser: on average a bound within the feasibility tolerance 1e-9 times multipliers
    # of size 10 (1e4 only on the thinnest windows). Seen: 5.3e-6 in 38.4 (1.4e-7 relative) with and
    # without HiGHS's scaling, a fifth of this.
    assert np.sum(a.upper - a.lower) <= np.sum(b.upper - b.lower) + 1e-8 * np.sum(2.0 * scale(b.lower, b.upper))


def test_highs_alone_gives_the_boxes_of_the_dense_simplex_to_the_certificates_tolerance() -> None:
    """``solver="highs"`` bypasses the dense simplex (the recorded route says so); both answers are certified
    bounds of the same LPs, so they agree to the solver's tolerance times the multipliers (as the sparse and
    condensed forms above), and both contain the truth."""
    from intervalobs.examples.scale_cases import tank_cascade

    case = tank_cascade(6, steps=30)
    sim = case.simulate(seed=1, noise="vertex")
    dense = HullEstimator.design(case.system, case.bounds, horizon=8).run(case.t, sim.y, case.u)
    highs = HullEstimator.design(case.system, case.bounds, horizon=8, solver="highs").run(case.t, sim.y, case.u)
    assert highs.meta["solver"] == "highs" and dense.meta["solver"] == "auto"
    assert sum(path["dense"] for path in highs.meta["solver_path"]) == 0
    assert sum(path["dense"] for path in dense.meta["solver_path"]) > 0
    tol = 1e-6 * scale(dense.lower, dense.upper)
    assert np.all(np.abs(dense.lower - highs.lower) <= tol) and np.all(np.abs(dense.upper - highs.upper) <= tol)
    assert dense.enclosure(sim.x).max_violation == 0.0 and highs.enclosure(sim.x).max_violation == 0.0


def test_filtered_rows_solve_as_many_lps_as_predicted_ones_and_keep_their_boxes() -> None:
    """A filtered step solves the ``2n`` LPs of its own window only (issue 36): the predicted window's hull,
    which the certificates still solve, adds nothing beyond the certificates' tolerance, and the truth stays
    inside."""
    from intervalobs.examples.scale_cases import tank_cascade

    case = tank_cascade(6, steps=30)
    sim = case.simulate(seed=2, noise="vertex")

    def solves(estimate: Estimate) -> int:
        keys = ("dense", "highs_warm", "scratch", "failed")
        return sum(path[key] for path in estimate.meta["solver_path"] for key in keys)

    predicted = HullEstimator.design(case.system, case.bounds, horizon=8).run(case.t, sim.y, case.u)
    filtered = HullEstimator.design(case.system, case.bounds, horizon=8, filtered=True)
    fast = filtered.run(case.t, sim.y, case.u)
    filtered._certifying = lambda: True  # type: ignore[method-assign]  # both windows, as before issue 36
    both = filtered.run(case.t, sim.y, case.u)
    lps = 2 * case.system.n  # a box's LPs; predicted rows: one box per step after the prior
    assert solves(predicted) == lps * (case.t.size - 1) and solves(fast) == lps * case.t.size
    assert solves(both) == solves(fast) + lps * (case.t.size - 1)
    tol = 1e-6 * scale(both.lower, both.upper)
    assert np.all(np.abs(fast.lower - both.lower) <= tol) and np.all(np.abs(fast.upper - both.upper) <= tol)
    assert fast.enclosure(sim.x).max_violation == 0.0


def test_an_unknown_solver_is_refused_by_name() -> None:
    system, bounds = small_discrete()
    with pytest.raises(DataError, match="solver: expected one of 'auto', 'highs', got 'glpk'"):
        HullEstimator.design(system, bounds, solver="glpk")  # type: ignore[arg-type]


@pytest.mark.parametrize("processes", [0, 1.5, True])
def test_processes_must_be_a_positive_integer(processes: object) -> None:
    system, bounds = small_discrete()
    with pytest.raises(DataError, match="processes: expected a positive integer"):
        HullEstimator.design(system, bounds, processes=processes)  # type: ignore[arg-type]
