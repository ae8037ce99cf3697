"""Seed 003 observers: the paper's GSISIO (where (8) holds) and the sound NullSpaceGSISIO."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs.design.gsisio import gsisio_design
from intervalobs.errors import AssumptionError
from intervalobs.examples import gsisio as ex
from intervalobs.observers.gsisio import GSISIO
from intervalobs.observers.null_space_gsisio import NullSpaceGSISIO
from intervalobs.simulate import simulate_nonlinear
from intervalobs.systems import Bounds, NonlinearSystem


def delayed(d: np.ndarray) -> np.ndarray:
    out = np.full_like(d, np.nan)
    out[..., 1:, :] = d[..., :-1, :]
    return out


@pytest.fixture(scope="module")
def paper():
    return ex.paper_system()


@pytest.fixture(scope="module")
def fullrank():
    return ex.fullrank_system()


def test_paper_gains_recomputed_and_condition_8_fails_structurally(paper):
    d = gsisio_design(paper, ex.paper_bounds())
    np.testing.assert_allclose(d.K, [[0.0884, 0, 0, 0.1572], [0.1768, 1.3988, 0.1100, 0.3143]], atol=6e-5)
    np.testing.assert_allclose(d.L, [[0, 0.2279, 0.0629, 0], [0.4047, 0.4558, 0.1257, 0.2750]], atol=6e-5)
    assert d.rank_condition_8 == (2, 1) and not d.condition_8
    v2 = np.array([3.0, 1.0])
    np.testing.assert_allclose((np.eye(2) - d.K1 + d.L1) @ paper.G @ v2, 0.0, atol=1e-12)
    assert d.correctness_radius > 1.0
    printed = np.array(ex.PRINTED["K"]) - np.array(ex.PRINTED["L"])
    assert np.abs(printed @ np.vstack([paper.G, paper.H]) - paper.G).max() > 0.05  # no left inverse gives them
    with pytest.raises(AssumptionError, match=r"rank condition.*rk\(I - K1 \+ L1\) = 1"):
        GSISIO.design(paper, ex.paper_bounds())


def test_paper_constants_recomputed(paper):
    d = gsisio_design(paper, ex.paper_bounds())
    np.testing.assert_allclose(d.C_f, [[0, 0.21], [0, 0]], atol=1e-12)
    np.testing.assert_allclose(d.C_g, [[0.04, 0], [1, 0]], atol=1e-12)
    assert d.L_f > 0.35 * 2.5 and d.L_g > 1.17  # printed 0.35, 0.74 are impossible
    assert d.script_L > 1.0 and d.stability_condition is None
    assert not d.conditions["(ii)"]["holds"] and not d.conditions["(iii)"]["holds"]


def test_fullrank_design_conditions(fullrank):
    obs = GSISIO.design(fullrank, ex.fullrank_bounds())
    d = obs.design_result
    assert d.condition_8 and d.correctness_radius < 1.0
    assert d.conditions["(i)"]["holds"] and d.script_L < 1.0
    assert d.conditions["(iv)"]["holds"]
    assert not d.conditions["(iii)"]["holds"]  # structurally infeasible LMI


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_paper_construction_encloses_and_stays_below_lemma5(fullrank, seed):
    obs = GSISIO.design(fullrank, ex.fullrank_bounds())
    d_true = ex.fullrank_input(120)
    sim = simulate_nonlinear(fullrank, ex.fullrank_bounds(), d_true, seed=seed, runs=6)
    t = np.arange(120.0)
    est = obs.run(t, sim.y)
    assert est.enclosure(sim.x).max_violation == 0.0
    rep = est.input_enclosure(delayed(sim.d))
    assert rep.max_violation == 0.0 and rep.fraction == 1.0
    width = np.linalg.norm(est.width(), axis=-1)
    delta = obs.design_result.delta_x(float(np.linalg.norm(ex.FULLRANK_X0_BOX[1] - ex.FULLRANK_X0_BOX[0])), 120)
    assert np.all(width <= delta)
    full = ex.fullrank_bounds().resolve(fullrank)
    dd = obs.design_result.delta_d(delta, full.w[1] - full.w[0], full.v[1] - full.v[0])
    wd = np.linalg.norm(est.input_upper - est.input_lower, axis=-1)
    assert np.all(wd[..., 1:] <= dd[1:])


def test_paper_construction_run_equals_step(fullrank):
    obs = GSISIO.design(fullrank, ex.fullrank_bounds())
    sim = simulate_nonlinear(fullrank, ex.fullrank_bounds(), ex.fullrank_input(30), seed=5)
    est = obs.run(np.arange(30.0), sim.y)
    state = obs.init()
    for k in range(29):
        state = obs.step(state, sim.y[k])
        np.testing.assert_allclose(state.lower, est.lower[k + 1], rtol=0, atol=1e-12)
        np.testing.assert_allclose(state.input_upper, est.input_upper[k + 1], rtol=0, atol=1e-12)


def test_exact_input_hull_is_sound_and_no_wider(fullrank):
    plain = GSISIO.design(fullrank, ex.fullrank_bounds())
    hull = GSISIO.design(fullrank, ex.fullrank_bounds(), input_hull=True)
    sim = simulate_nonlinear(fullrank, ex.fullrank_bounds(), ex.fullrank_input(40), seed=3, runs=2)
    t = np.arange(40.0)
    a, b = plain.run(t, sim.y), hull.run(t, sim.y)
    assert b.input_enclosure(delayed(sim.d)).max_violation == 0.0
    wa = (a.input_upper - a.input_lower)[..., 1:, :]
    wb = (b.input_upper - b.input_lower)[..., 1:, :]
    assert np.all(wb <= wa) and np.median(wa / wb) > 1.2
    np.testing.assert_array_equal(a.lower, b.lower)


def test_lemma4_current_input_bounds(paper, fullrank):
    obs = GSISIO.design(fullrank, ex.fullrank_bounds())
    sim = simulate_nonlinear(fullrank, ex.fullrank_bounds(), ex.fullrank_input(40), seed=7)
    est = obs.run(np.arange(40.0), sim.y)
    (lo, hi), v1 = obs.current_input_bounds(est.lower, est.upper, sim.y)
    d1 = sim.d @ v1
    assert np.all(lo <= d1) and np.all(d1 <= hi)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_nullspace_variant_encloses_states_and_delayed_inputs_on_the_paper_example(paper, seed):
    obs = NullSpaceGSISIO.design(paper, ex.paper_bounds())
    steps = 80
    sim = simulate_nonlinear(paper, ex.paper_bounds(), ex.paper_input(steps) * (1 + seed), seed=seed, runs=4)
    est = obs.run(np.arange(float(steps)), sim.y)
    rep = est.enclosure(sim.x)
    assert rep.max_violation == 0.0 and rep.fraction == 1.0
    rep_d = est.input_enclosure(delayed(sim.d))
    assert rep_d.max_violation == 0.0 and rep_d.fraction == 1.0
    assert np.all(est.input_lower[..., 0, :] == -np.inf) and np.all(est.input_upper[..., 0, :] == np.inf)
    assert np.all(np.isfinite(est.input_lower[..., 1:, :])) and est.meta["rows"] == "filtered"
    assert np.linalg.norm(est.width(), axis=-1)[..., 10:].max() < 4.0


@pytest.mark.parametrize(
    ("system", "box", "d"),
    [
        (ex.paper_system(), ex.paper_bounds(), ex.paper_input(15)),
        (ex.two_hidden_system(), ex.two_hidden_bounds(), ex.two_hidden_input(8)),
    ],
    ids=["paper", "two-hidden"],
)
def test_nullspace_variant_run_equals_step(system, box, d):
    obs = NullSpaceGSISIO.design(system, box)
    steps = d.shape[0]
    sim = simulate_nonlinear(system, box, d, seed=11)
    est = obs.run(np.arange(float(steps)), sim.y)
    state = obs.init()
    for k in range(steps):
        state = obs.step(state, sim.y[k])
        np.testing.assert_allclose(state.lower, est.lower[k], rtol=0, atol=1e-12)
        np.testing.assert_allclose(state.upper, est.upper[k], rtol=0, atol=1e-12)
        if k > 0:
            np.testing.assert_allclose(state.input_upper, est.input_upper[k], rtol=0, atol=1e-12)


def test_nullspace_variant_handles_full_rank_h(fullrank):
    obs = NullSpaceGSISIO.design(fullrank, ex.fullrank_bounds())
    assert obs.hidden == 0
    sim = simulate_nonlinear(fullrank, ex.fullrank_bounds(), ex.fullrank_input(60), seed=4, runs=3)
    est = obs.run(np.arange(60.0), sim.y)
    assert est.enclosure(sim.x).max_violation == 0.0
    assert est.input_enclosure(delayed(sim.d)).max_violation == 0.0


def test_nullspace_variant_rejects_a_non_monotone_d_free_output():
    def f(x):
        return (0.5 * x[0], 0.5 * x[1])

    def g(x):
        return (x[0], np.sin(x[1]))

    def jf(x):
        return [[0.5, 0.0], [0.0, 0.5]]

    def jg(x):
        return [[1.0, 0.0], [0.0, np.cos(x[1])]]

    # H hides the second input from the outputs, G moves x2 with it; the d-free output sin(x2) is not monotone
    system = NonlinearSystem(f, g, G=np.eye(2), H=[[1.0, 0.0], [0.0, 0.0]], f_jacobian=jf, g_jacobian=jg)
    with pytest.raises(AssumptionError, match="not strictly monotone"):
        NullSpaceGSISIO.design(system, Bounds(x0=(-1, 1)))


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1])
def test_nullspace_variant_long_horizon_stays_bounded(paper, seed):
    obs = NullSpaceGSISIO.design(paper, ex.paper_bounds())
    steps = 1000
    sim = simulate_nonlinear(paper, ex.paper_bounds(), ex.paper_input(steps), seed=seed, runs=8)
    est = obs.run(np.arange(float(steps)), sim.y)
    assert est.enclosure(sim.x).max_violation == 0.0
    assert est.input_enclosure(delayed(sim.d)).max_violation == 0.0
    assert np.linalg.norm(est.width(), axis=-1)[..., 10:].max() < 4.0


@pytest.fixture(scope="module")
def two_hidden():
    return ex.two_hidden_system()


def test_two_hidden_directions_without_jacobians_are_enclosed_below_the_certified_bound(two_hidden):
    """Five seeds, bang-bang noise, random vertex x0; the truth from the model equations, not the observer."""
    assert two_hidden.jacobian_source == {"f": "automatic", "g": "automatic"}
    obs = NullSpaceGSISIO.design(two_hidden, ex.two_hidden_bounds())
    assert obs.hidden == 2
    cert = obs.width_certificate()
    assert cert.holds and cert.spectral_radius < 1.0 and np.all(cert.Gamma >= 0)
    steps = 100
    sims = [
        simulate_nonlinear(two_hidden, ex.two_hidden_bounds(), ex.two_hidden_input(steps), seed=s) for s in range(5)
    ]
    x = np.stack([s.x for s in sims])
    d = delayed(np.stack([s.d for s in sims]))
    est = obs.run(np.arange(float(steps)), np.stack([s.y for s in sims]))
    rep, rep_d = est.enclosure(x), est.input_enclosure(d)
    assert rep.fraction == 1.0 and rep.max_violation == 0.0
    assert rep_d.fraction == 1.0 and rep_d.max_violation == 0.0
    z0 = obs.init().internal["z_upper"] - obs.init().internal["z_lower"]
    x_bound, d_bound = cert.width_bounds(z0, steps)
    # bounds hold up to the documented rounding margins (relative 1e-12 of |bounds| <= 10 per step)
    assert np.all(est.width() <= x_bound + 1e-9)
    assert np.all((est.input_upper - est.input_lower)[:, 1:] <= d_bound[1:] + 1e-9)
    assert np.all(est.width()[:, 30:] <= cert.x_width_steady)
    assert np.all((est.input_upper - est.input_lower)[:, 30:] <= cert.d_width_steady)


def _hidden_pair(g, p):
    def f(x):
        return (0.5 * x[0], 0.5 * x[1], 0.5 * x[2])

    G = np.array([[1.0, 0.0], [0.0, 0.0], [0.0, 1.0]])
    return NonlinearSystem(f, g, G=G, H=np.zeros((p, 2)))


def test_existence_condition_needs_as_many_d_free_outputs_as_hidden_directions():
    system = _hidden_pair(lambda x: (x[0] + x[2],), 1)
    with pytest.raises(AssumptionError, match=r"1 d-free outputs \(p - rk H\) for 2 hidden input directions"):
        NullSpaceGSISIO.design(system, Bounds(x0=(-1, 1)))


def test_existence_condition_needs_an_h_matrix_slope():
    # d-free outputs sin(x1), sin(x3): their slopes along the hidden directions take both signs
    system = _hidden_pair(lambda x: (np.sin(x[0]), np.sin(x[2])), 2)
    with pytest.raises(AssumptionError, match="is not invertible under any preconditioner"):
        NullSpaceGSISIO.design(system, Bounds(x0=(-1, 1)))
    # the same structure with monotone outputs is accepted
    ok = _hidden_pair(lambda x: (x[0] + 0.3 * np.sin(x[2]), x[2] + 0.3 * np.tanh(x[0])), 2)
    assert NullSpaceGSISIO.design(ok, Bounds(x0=(-1, 1))).hidden == 2


def test_certificate_states_why_none_exists_on_the_paper_example(paper, fullrank):
    cert = NullSpaceGSISIO.design(paper, ex.paper_bounds()).width_certificate()
    assert not cert.holds and cert.spectral_radius >= 1.0 and "rho(Gamma)" in cert.reason
    assert np.all(np.isnan(cert.x_width_steady))
    full = NullSpaceGSISIO.design(fullrank, ex.fullrank_bounds())
    cert = full.width_certificate()
    assert cert.holds
    sim = simulate_nonlinear(fullrank, ex.fullrank_bounds(), ex.fullrank_input(80), seed=2, runs=3)
    est = full.run(np.arange(80.0), sim.y)
    assert np.all(est.width()[:, 20:] <= cert.x_width_steady)
