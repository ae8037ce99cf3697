"""Gain design at scale: the framer search's candidate pruning and the tube gain's gradient refinement."""

import numpy as np
import pytest

from conftest import random_system
from intervalobs import IntervalObserver, simulate
from intervalobs.design import cooperative, tube
from intervalobs.examples.scale_cases import tank_cascade
from intervalobs.systems.sampling import sampled_model

# (seed, n, p, continuous, uncertain): gains of more than 16 entries (the gradient refinement's domain)
LARGE_GAIN_CASES = [(20, 6, 3, False, False), (21, 6, 4, True, True), (22, 8, 3, False, True), (23, 7, 4, True, False)]


def _model(system, bounds, continuous):
    full = bounds.resolve(system)
    return sampled_model(system, full, 0.05 if continuous else None), full.radius("v")


def _random(seed, n, p, continuous, uncertain):
    system, bounds = random_system(seed, n, p, continuous, uncertain)
    return system, bounds, continuous


def _tanks(n):
    case = tank_cascade(n)
    return case.system, case.bounds, False


@pytest.mark.parametrize(
    "make,args",
    [
        (_random, (0, 4, 2, False, False)),
        (_random, (1, 4, 1, False, True)),
        (_random, (21, 6, 4, True, True)),
        pytest.param(_tanks, (12,), marks=pytest.mark.slow),  # the unpruned modal LPs take tens of seconds
    ],
)
def test_skipping_candidates_that_cannot_win_leaves_the_framer_design_unchanged(monkeypatch, make, args):
    system, bounds, continuous = make(*args)
    model, v_radius = _model(system, bounds, continuous)
    pruned = cooperative.design_framer(model, system.C, system.F, v_radius)
    monkeypatch.setattr(cooperative, "_noise_floor", lambda model, T: -np.inf)
    full = cooperative.design_framer(model, system.C, system.F, v_radius)
    np.testing.assert_array_equal(pruned.L, full.L)
    np.testing.assert_array_equal(pruned.T, full.T)
    np.testing.assert_array_equal(pruned.steady_radius, full.steady_radius)
    assert pruned.coordinates == full.coordinates
    skipped = [name for name, score in pruned.tried.items() if score == np.inf and np.isfinite(full.tried[name])]
    if make is _tanks:  # the modal basis of the cascade spreads every tank's noise over all: its LPs are skipped
        assert "modal" in skipped
    elif args[0] < 2:  # candidates whose LPs found gains were skipped
        assert skipped


def test_noise_floor_is_below_every_gains_steady_radius_sum():
    """|T⁻¹||T|r_w bounds the steady x-radius of any gain with a stable width system in coordinates T."""
    rng = np.random.default_rng(0)
    for seed in range(6):
        system, bounds = random_system(seed, 4, 2, False, seed % 2 == 1)
        model, v_radius = _model(system, bounds, False)
        candidates = cooperative.coordinate_candidates(model, system.C, system.F, v_radius)
        design = cooperative.design_framer(model, system.C, system.F, v_radius, candidates)
        for T in candidates.values():
            floor = cooperative._noise_floor(model, T)
            for gain in [design.L] + [design.L + 0.05 * rng.normal(size=design.L.shape) for _ in range(20)]:
                rho, radius = cooperative._steady_radius(model, system.C, system.F, v_radius, gain, T)
                if rho < 1:
                    assert floor <= radius.sum() * (1 + 1e-12)


@pytest.mark.parametrize("smoothing", [0.0, 1e-3])
@pytest.mark.parametrize("seed,n,p,continuous,uncertain", LARGE_GAIN_CASES[:3])
def test_steady_radius_gradient_matches_finite_differences(seed, n, p, continuous, uncertain, smoothing):
    system, bounds = random_system(seed, n, p, continuous, uncertain)
    model, v_radius = _model(system, bounds, continuous)
    design = tube.design_tube_gain(model, system.C, system.F, v_radius)
    assert design is not None
    weights = np.random.default_rng(seed).uniform(0.5, 2.0, n)
    gain = design.L + 1e-3 * np.random.default_rng(seed + 1).normal(size=design.L.shape)  # off any kink
    floors = tube._smoothing_floors(model.Phi - gain @ system.C, gain @ system.F, design.horizon, smoothing)
    found = tube._steady_gradient(model, system.C, system.F, v_radius, gain, design.horizon, floors)
    assert found is not None
    direction = np.random.default_rng(seed + 2).normal(size=gain.shape)
    step = 1e-7 * np.abs(gain).max()
    values = []
    for sign in (1.0, -1.0):
        moved = tube._steady_gradient(
            model, system.C, system.F, v_radius, gain + sign * step * direction, design.horizon, floors
        )
        assert moved is not None
        values.append(weights @ moved[0])
    numeric = (values[0] - values[1]) / (2 * step)
    # central difference: truncation O(step²) and rounding ~ eps·|wᵀs|/step ≈ 1e-9 relative; no sign change
    # of any entry of M^i or LF within ±step at this random point (else the exact one-sided slopes differ)
    assert abs(numeric - np.sum(found[1](weights) * direction)) <= 1e-5 * (abs(numeric) + weights @ found[0])


@pytest.mark.parametrize("seed,n,p,continuous,uncertain", LARGE_GAIN_CASES)
def test_descended_gain_is_never_looser_than_the_winner_and_encloses_the_truth(
    monkeypatch, seed, n, p, continuous, uncertain
):
    system, bounds = random_system(seed, n, p, continuous, uncertain)
    model, v_radius = _model(system, bounds, continuous)
    descended = tube.design_tube_gain(model, system.C, system.F, v_radius)
    with monkeypatch.context() as patch:
        patch.setattr(tube, "_descended", lambda *args: None)
        plain = tube.design_tube_gain(model, system.C, system.F, v_radius)
    assert descended is not None and plain is not None
    assert np.all(descended.steady_radius <= plain.steady_radius)
    assert descended.candidate in (plain.candidate, f"{plain.candidate}+descended")
    h = 0.05 if continuous else None
    observer = IntervalObserver(system, bounds, descended.L, descended.T, h=h, blocks=descended.blocks)
    t = np.arange(200) * (h or 1.0)
    for noise in ("extreme", "vertex"):  # switching inside the steps (continuous time) / every generator at ±1
        sim = simulate(system, bounds, t, noise=noise, seed=seed, runs=4)
        report = observer.run(t, sim.y).enclosure(sim.x)
        assert report.fraction == 1.0 and report.max_violation == 0.0


def test_descent_narrows_the_six_tank_cascade():
    """Four outputs, 24 gain entries: the framer's LP gain is not the best box bound; the descent finds one."""
    case = tank_cascade(6)
    model, v_radius = _model(case.system, case.bounds, False)
    framer = cooperative.design_framer(model, case.system.C, case.system.F, v_radius).L
    plain = tube.design_tube_gain(model, case.system.C, case.system.F, v_radius, {"framer": framer})
    assert plain is not None and plain.candidate == "framer+descended"
    start = tube._tube_in(
        model,
        framer,
        model.Phi - framer @ case.system.C,
        np.eye(6),
        (1,) * 6,
        case.system.F,
        v_radius,
        "framer",
    )
    assert start is not None
    assert np.all(plain.steady_radius <= start.steady_radius)
    assert plain.steady_radius.sum() <= 0.85 * start.steady_radius.sum()


@pytest.mark.parametrize("sizes", [(1, 1, 1, 1), (2, 1, 1)], ids=["box", "blocks"])
def test_noise_sums_bound_every_vertex_sequence_and_never_exceed_the_box(sizes):
    rng = np.random.default_rng(3)
    m = rng.normal(size=(4, 4))
    m *= 0.9 / np.max(np.abs(np.linalg.eigvals(m)))
    generators = rng.normal(size=(4, 6)) * rng.uniform(0.1, 1.0, 6)
    norms = tube.BlockNorms(sizes)
    box = norms.vector(np.abs(generators).sum(axis=1))
    horizon = 12
    sums = tube.noise_sums(m, generators, box, horizon, norms)
    powers = [np.linalg.matrix_power(m, i) for i in range(horizon)]
    boxed_terms = np.array([norms.matrix(p) @ box for p in powers])
    boxed = np.cumsum(boxed_terms, axis=0)
    columns = np.array([norms.rows(p @ generators).sum(axis=1) for p in powers])
    direct = np.cumsum(np.minimum(columns, boxed_terms), axis=0)  # each term: the smaller bound
    np.testing.assert_array_equal(sums[0], 0.0)
    # upper bounds, rounded up by at most the library's 1e-12 of the box term they are never above
    assert np.all(sums[1:] <= boxed * (1 + 1e-12)) and np.all(sums[1:] >= direct)
    assert np.all(sums[-1] < 0.95 * boxed[-1])  # dense generators: the box forgets their cancellations
    for _ in range(200):  # the error of ℓ steps of vertex noise lies inside c_ℓ, block by block
        xi = rng.choice([-1.0, 1.0], size=(horizon, 6))
        error = np.cumsum([p @ generators @ x for p, x in zip(powers, xi)], axis=0)
        assert np.all(norms.vector(error) <= sums[1:])
    if norms.singleton:  # the bound is attained: ξ_i = sign of the row of M^i G, state by state
        worst = np.cumsum([np.abs(p @ generators).sum(axis=1) for p in powers], axis=0)
        np.testing.assert_allclose(sums[1:], worst, rtol=1e-11)
