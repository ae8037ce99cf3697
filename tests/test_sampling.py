"""The sound sampled model (systems/sampling.py): tight for stiff A, sound against an exact-exponential truth."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest
from scipy.linalg import block_diag, expm

from conftest import simulate_truth, unit_bounds
from intervalobs import Bounds, DesignError, IntervalObserver, LTISystem, sampled_model
from intervalobs.design.cooperative import real_modal_basis, unstable_vertex
from intervalobs.design.tube import BlockNorms, tube_horizon, tube_stability
from intervalobs.errors import ArgumentTypeError, AssumptionError, DimensionError
from intervalobs.systems.sampling import _nodes

STEPS = [0.001, 0.01, 0.1, 0.5, 1.0, 10.0]
STIFF_A = np.array([[-1000.0, 0.0], [1.0, -0.01]])
# Entries of dPhi below this fraction of max|Phi| are rounding-level (the Schur residual allowance).
FLOOR = 1e-12


def stiff_system(uncertain: bool) -> LTISystem:
    da = 1e-3 * np.abs(STIFF_A)
    return LTISystem(STIFF_A, [[0.0, 1.0]], E=np.eye(2), dA=(-da, da) if uncertain else None)


def random_stiff(n: int, seed: int, oscillating: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Stable A with eigenvalues spread over 5 decades (-1e-2 … -1e3), a well-conditioned basis.

    Real eigenvalues, or (``oscillating``, n even) the pairs -σ(1 ± i) for σ spread the same way.
    """
    rng = np.random.default_rng(seed)
    basis = np.eye(n) + 0.3 * rng.standard_normal((n, n))
    if oscillating:
        rates = 10.0 ** np.linspace(-2.0, 3.0, n // 2)
        modal = block_diag(*[sigma * np.array([[-1.0, 1.0], [-1.0, -1.0]]) for sigma in rng.permutation(rates)])
    else:
        modal = np.diag(rng.permutation(-(10.0 ** np.linspace(-2.0, 3.0, n))))
    a = basis @ modal @ np.linalg.inv(basis)
    e = rng.standard_normal((n, 2))
    c = rng.standard_normal((1, n))
    return a, e, c


def exact_noise_radius(a: np.ndarray, e: np.ndarray, h: float) -> np.ndarray:
    """∫_0^h |e^{Aτ}E| 1 dτ by a fine trapezoid rule on eigen-evaluated exponentials."""
    lam, vec = np.linalg.eig(a)
    coef = np.linalg.solve(vec, e)
    tau = np.unique(np.concatenate([[0.0], np.geomspace(1e-9, h, 40000), np.linspace(0, h, 20000)]))
    values = np.abs(np.einsum("ip,tp,pk->tik", vec, np.exp(np.outer(tau, lam)), coef).real).sum(axis=2)
    return np.asarray(np.trapezoid(values, tau, axis=0))


def vertex_lower_bound(a: np.ndarray, d: np.ndarray, h: float) -> np.ndarray:
    """max over chosen vertices ΔA of |e^{(A+ΔA)h} - e^{Ah}|: per entry, the vertex of the first-order signs."""
    n = a.shape[0]
    phi = expm(a * h)
    pairs = list(zip(*np.nonzero(d), strict=True))
    sens = np.zeros((len(pairs), n, n))
    for q, (j, l) in enumerate(pairs):  # ∂Φ/∂A_jl = ∫ e^{A(h-s)} e_j e_l^T e^{As} ds (Van Loan block)
        block = np.zeros((2 * n, 2 * n))
        block[:n, :n], block[n:, n:], block[j, n + l] = a, a, 1.0
        sens[q] = expm(block * h)[:n, n:]
    best = np.zeros((n, n))
    for i, k in itertools.product(range(n), range(n)):
        for sign in (1.0, -1.0):
            delta = np.zeros((n, n))
            for q, (j, l) in enumerate(pairs):
                delta[j, l] = sign * d[j, l] * (1.0 if sens[q, i, k] >= 0 else -1.0)
            best = np.maximum(best, np.abs(expm((a + delta) * h) - phi))
    return best


def test_nodes_are_symmetric_and_geometric() -> None:
    for h in (1e-3, 0.1, 7.3):
        nodes = _nodes(h, 1000.0)
        np.testing.assert_array_equal(h - nodes[::-1], nodes)
        assert nodes[1] * 1000.0 <= 1.0 / 16.0 + 1e-15


@pytest.mark.parametrize("h", STEPS, ids=[f"h={h:g}" for h in STEPS])
def test_stiff_noise_radius_within_1_5_of_exact(h: float) -> None:
    model = sampled_model(stiff_system(False), unit_bounds(2, 2, 1), h)
    # Closed form: e^{Aτ} = [[e^{-1000τ}, 0], [(e^{-0.01τ} - e^{-1000τ})/999.99, e^{-0.01τ}]] >= 0.
    fast, slow = (1 - np.exp(-1000 * h)) / 1000, (1 - np.exp(-0.01 * h)) / 0.01
    exact = np.array([fast, (slow - fast) / 999.99 + slow])
    np.testing.assert_allclose(exact_noise_radius(STIFF_A, np.eye(2), h), exact, rtol=1e-4)
    assert np.all(model.noise_radius >= exact * (1 - 1e-9))
    assert np.all(model.noise_radius <= 1.5 * exact)


@pytest.mark.parametrize("h", STEPS, ids=[f"h={h:g}" for h in STEPS])
def test_stiff_dphi_within_3_of_vertex_bound_and_design_bounded(h: float) -> None:
    system = stiff_system(True)
    model = sampled_model(system, unit_bounds(2, 2, 1), h)
    lower = vertex_lower_bound(STIFF_A, 1e-3 * np.abs(STIFF_A), h)
    floor = FLOOR * np.abs(model.Phi).max()
    assert np.all(model.dPhi >= lower * (1 - 1e-9))
    assert np.all(model.dPhi <= 3 * lower + floor)
    observer = IntervalObserver.design(system, unit_bounds(2, 2, 1), h=h)
    assert np.all(np.isfinite(observer.design_result.steady_radius))


RANDOM_CASES = [(3, 0), (6, 1), (10, 2)]
# The ΔA box of the random systems: the largest first-order eigenvalue shift |w_i^H| D |v_i| of any
# vertex is this fraction of |λ_i| (a box that keeps every vertex stable, with margin).
EIGENVALUE_SHIFT = 0.1


def robust_box(a: np.ndarray) -> np.ndarray:
    """D = c|A| with c such that max_i |w_i^H| D |v_i| / |λ_i| = EIGENVALUE_SHIFT."""
    lam, vec = np.linalg.eig(a)
    shift = np.diag(np.abs(np.linalg.inv(vec)) @ np.abs(a) @ np.abs(vec)) / np.abs(lam)
    return np.asarray(EIGENVALUE_SHIFT / shift.max() * np.abs(a))


OSCILLATING_CASES = [(4, 3), (6, 4), (10, 5)]
TIGHT_CASES = [(n, seed, False) for n, seed in RANDOM_CASES] + [(n, seed, True) for n, seed in OSCILLATING_CASES]


def robust_stability_gain(a: np.ndarray, d: np.ndarray) -> float:
    """ρ(|Re Λ|⁻¹ |V⁻¹| D |V|): below 1, every A + ΔA with |ΔA| <= D is Hurwitz.

    V⁻¹(A + ΔA)V = Λ + P with |P| <= |V⁻¹|D|V|, and |e^{(Λ+P)t}| <= e^{(Re Λ + |P|)t} (the Dyson majorant of
    systems/sampling.py, section 2); the Metzler matrix Re Λ + |V⁻¹|D|V| is Hurwitz iff this radius is below 1.
    """
    lam, vec = np.linalg.eig(a)
    gain = np.abs(np.linalg.inv(vec)) @ d @ np.abs(vec) / np.abs(lam.real)[:, None]
    return float(np.max(np.abs(np.linalg.eigvals(gain))))


@pytest.mark.parametrize(
    ("n", "seed", "oscillating"), TIGHT_CASES, ids=[f"n={n}-seed={s}{'-complex' * o}" for n, s, o in TIGHT_CASES]
)
def test_random_boxes_robustly_stable_and_literal_boxes_not(n: int, seed: int, oscillating: bool) -> None:
    """The tests' ΔA box is certified robustly stable; the issue's ±0.1 %|A| on these dense systems is not:
    unstable_vertex finds a matrix of that box with an eigenvalue in the right half-plane."""
    a, _, _ = random_stiff(n, seed, oscillating)
    assert robust_stability_gain(a, robust_box(a)) < 0.5
    assert unstable_vertex(a, -robust_box(a), robust_box(a), continuous=True) is None
    literal = 1e-3 * np.abs(a)
    found = unstable_vertex(a, -literal, literal, continuous=True)
    assert found is not None
    vertex, abscissa = found
    assert np.all(np.abs(vertex - a) <= literal * (1 + 1e-12))
    assert abscissa == pytest.approx(np.max(np.linalg.eigvals(vertex).real)) and abscissa > 0


@pytest.mark.parametrize("n", [6, 10])
def test_design_names_an_unstable_box(n: int) -> None:
    a, e, c = random_stiff(n, dict(RANDOM_CASES)[n])
    literal = 1e-3 * np.abs(a)
    system = LTISystem(a, c, E=e, dA=(-literal, literal))
    for method in ("tube", "framer"):
        with pytest.raises(
            DesignError, match=r"^dA: expected a box of stable matrices, got a vertex .* spectral abscissa"
        ):
            IntervalObserver.design(system, unit_bounds(n, 2, 1), h=0.1, method=method)


def test_unstable_vertex_discrete_time() -> None:
    a = np.array([[0.9, 0.5], [0.0, 0.5]])
    box = np.array([[0.0, 0.0], [0.3, 0.0]])
    vertex, radius = unstable_vertex(a, -box, box, continuous=False)
    assert radius == pytest.approx(np.max(np.abs(np.linalg.eigvals(vertex)))) and radius >= 1
    assert unstable_vertex(a, -0.1 * box, 0.1 * box, continuous=False) is None


@pytest.mark.parametrize(
    ("n", "seed", "oscillating"), TIGHT_CASES, ids=[f"n={n}-seed={s}{'-complex' * o}" for n, s, o in TIGHT_CASES]
)
def test_random_stiff_systems_tight(n: int, seed: int, oscillating: bool) -> None:
    a, e, c = random_stiff(n, seed, oscillating)
    d = robust_box(a)
    system = LTISystem(a, c, E=e, dA=(-d, d))
    point = LTISystem(a, c, E=e)
    bounds = unit_bounds(n, 2, 1)
    for h in STEPS:
        exact = exact_noise_radius(a, e, h)
        radius = sampled_model(point, bounds, h).noise_radius
        assert np.all(radius >= exact * (1 - 1e-6)), h
        assert np.all(radius <= 1.5 * exact), (h, np.max(radius / exact))
        model = sampled_model(system, bounds, h)
        lower = vertex_lower_bound(a, d, h)
        floor = FLOOR * np.abs(model.Phi).max()
        assert np.all(model.dPhi >= lower * (1 - 1e-6)), h
        assert np.all(model.dPhi <= 1.5 * lower + floor), (h, np.max((model.dPhi - floor) / lower))


def test_tube_horizon_of_a_slow_mode() -> None:
    """A mode at 1 - 1e-4 needs ~14 000 steps to contract to 1/4. Diagonal, every horizon is exact (J = 1);
    in a dense basis no affordable horizon makes |M^J| contract (hence the design's modal coordinates)."""
    slow = np.diag([1 - 1e-4, 0.5])
    assert tube_horizon(slow) == 1
    basis = np.array([[1.0, 0.9], [0.2, 1.0]])
    assert tube_horizon(basis @ slow @ np.linalg.inv(basis)) is None
    assert tube_horizon(np.diag([1.0, 0.5])) is None


def basis_vertex_lower_bound(a: np.ndarray, d: np.ndarray, h: float, t: np.ndarray) -> np.ndarray:
    """max over chosen vertices of |T(e^{(A+ΔA)h} - e^{Ah})T⁻¹|: per entry, the vertex of the first-order signs."""
    n = a.shape[0]
    t_inv = np.linalg.inv(t)
    phi = expm(a * h)
    sens = np.zeros((n, n, n, n))
    for j, l in itertools.product(range(n), range(n)):
        block = np.zeros((2 * n, 2 * n))
        block[:n, :n], block[n:, n:], block[j, n + l] = a, a, 1.0
        sens[j, l] = t @ expm(block * h)[:n, n:] @ t_inv
    best = np.zeros((n, n))
    for i, k in itertools.product(range(n), range(n)):
        delta = d * np.where(sens[:, :, i, k] >= 0, 1.0, -1.0)
        best = np.maximum(best, np.abs(t @ (expm((a + delta) * h) - phi) @ t_inv))
    return best


@pytest.mark.parametrize("h", [0.001, 0.01, 1.0])
def test_dphi_in_modal_coordinates_sound_and_tighter(h: float) -> None:
    """|TΔΦT⁻¹| bounded directly: above every first-order-sign vertex, never above |T|δΦ|T⁻¹|, and far below it
    in the modal coordinates of the complex n = 10 system (the cancellations of TK^{jl}T⁻¹ are kept)."""
    a, e, c = random_stiff(10, dict(OSCILLATING_CASES)[10], True)
    d = robust_box(a)
    model = sampled_model(LTISystem(a, c, E=e, dA=(-d, d)), unit_bounds(10, 2, 1), h)
    t = real_modal_basis(a)
    bound = model.dphi_in(t)
    plain = np.abs(t) @ model.dPhi @ np.abs(np.linalg.inv(t))
    lower = basis_vertex_lower_bound(a, d, h, t)
    assert np.all(bound <= plain)
    assert np.all(bound >= lower)
    assert np.median(bound / plain) < 0.5
    assert np.all(dataclasses.replace(model, first_order=None).dphi_in(t) == plain)


def test_modal_tube_of_the_slow_complex_pair_is_bounded() -> None:
    """c=10, h = 0.001: with the design's gain, the modal-coordinate tube is unbounded with |T|δΦ|T⁻¹| (the
    previous design's failure) and bounded with dphi_in; the design prefers the 2x2 block norms there."""
    a, e, c = random_stiff(10, dict(OSCILLATING_CASES)[10], True)
    d = robust_box(a)
    system = LTISystem(a, c, E=e, dA=(-d, d))
    observer = IntervalObserver.design(system, unit_bounds(10, 2, 1), h=0.001)
    assert observer.design_result.candidate.endswith("/modal-blocks")
    t = real_modal_basis(observer.model.Phi - observer.L @ c)
    m_z = t @ (observer.model.Phi - observer.L @ c) @ np.linalg.inv(t)
    horizon = tube_horizon(m_z)
    plain = dataclasses.replace(observer.model, first_order=None)
    assert tube_stability(plain, m_z, np.zeros(10), horizon, t)[0] >= 1
    assert tube_stability(observer.model, m_z, np.zeros(10), horizon, t)[0] < 1


def test_block_norms() -> None:
    """Spectral norms of the blocks, never below the exact ones and within the 16-ulp rounding allowance."""
    rng = np.random.default_rng(3)
    sizes = (1, 2, 2, 1)
    norms = BlockNorms(sizes)
    starts = np.cumsum((0, *sizes[:-1]))
    x = rng.standard_normal((6, 6))
    v = rng.standard_normal(6)
    got, got_v = norms.matrix(x), norms.vector(v)
    for b, c in itertools.product(range(4), range(4)):
        rows, cols = slice(starts[b], starts[b] + sizes[b]), slice(starts[c], starts[c] + sizes[c])
        exact = np.linalg.norm(x[rows, cols], 2)
        assert exact * (1 - 4e-16) <= got[b, c] <= exact * (1 + 1e-14)
    for b in range(4):
        exact = np.linalg.norm(v[starts[b] : starts[b] + sizes[b]])
        assert exact * (1 - 4e-16) <= got_v[b] <= exact * (1 + 1e-14)
    assert np.array_equal(BlockNorms((1,) * 6).matrix(x), np.abs(x))
    with pytest.raises(ValueError, match="sizes"):
        BlockNorms((3,))


def test_rotation_needs_block_norms() -> None:
    """A slow pair that rotates faster than it decays: no box horizon exists, the block norm contracts at rate r."""
    r, theta = 1 - 1e-4, 2e-4
    rotation = r * np.array([[np.cos(theta), np.sin(theta)], [-np.sin(theta), np.cos(theta)]])
    assert tube_horizon(rotation) is None
    horizon = tube_horizon(rotation, BlockNorms((2,)))
    assert horizon is not None
    rate = np.linalg.norm(np.linalg.matrix_power(rotation, horizon), 2) ** (1 / horizon)
    assert rate == pytest.approx(r, rel=1e-12)


def test_blocks_argument_is_checked() -> None:
    system = LTISystem(STIFF_A, [[0.0, 1.0]], E=np.eye(2))
    observer = IntervalObserver.design(system, unit_bounds(2, 2, 1), h=0.1)
    with pytest.raises(DimensionError, match=r"^blocks: expected sizes 1 or 2 summing to n = 2"):
        IntervalObserver(system, unit_bounds(2, 2, 1), observer.L, h=0.1, blocks=(1,))
    with pytest.raises(DimensionError, match=r"^blocks:"):
        IntervalObserver(system, unit_bounds(2, 2, 1), observer.L, h=0.1, method="framer", blocks=(2,))


# "n=K": real spectrum; "c=K": complex pairs. c=10 at h = 0.001 and 0.01 (a slow pair sampled fast) needs the
# ΔA radius in the modal coordinates (SampledModel.dphi_in) and, at h = 0.001, the tube's 2x2 block norms.
SOUND_CASES = (
    [("stiff", h) for h in STEPS]
    + [(f"n={n}", h) for n in (3, 6) for h in STEPS]
    + [("c=6", h) for h in (0.001, 0.1, 10.0)]
    + [("c=10", h) for h in (0.001, 0.01)]
)
SLOW_SOUND_CASES = (
    [("n=10", h) for h in STEPS] + [("c=6", h) for h in (0.01, 0.5, 1.0)] + [("c=10", h) for h in STEPS[2:]]
)


def check_enclosure(name: str, h: float) -> None:
    """The design is bounded (with and without ΔA), and the boxes hold a truth with x0 and ΔA at random box
    vertices and bang-bang noise inside the steps."""
    if name == "stiff":
        a, e, c = STIFF_A, np.eye(2), np.array([[0.0, 1.0]])
        d = 1e-3 * np.abs(a)
    else:
        n = int(name[2:])
        oscillating = name.startswith("c")
        a, e, c = random_stiff(n, dict(OSCILLATING_CASES if oscillating else RANDOM_CASES)[n], oscillating)
        d = robust_box(a)
    n = a.shape[0]
    system = LTISystem(a, c, E=e, dA=(-d, d))
    bounds = unit_bounds(n, e.shape[1], 1)
    point = IntervalObserver.design(LTISystem(a, c, E=e), bounds, h=h)
    observer = IntervalObserver.design(system, bounds, h=h)
    for designed in (point, observer):
        assert np.all(np.isfinite(designed.design_result.steady_radius))
    rng = np.random.default_rng(7)
    steps = 120
    t = h * np.arange(steps)
    for run in range(4):
        delta = d * rng.choice([-1.0, 1.0], d.shape)
        x0 = rng.choice([-1.0, 1.0], n)
        x, y = simulate_truth(a, e, c, delta, x0, h, steps, rng)
        est = observer.run(t, y)
        assert np.all(est.lower <= x) and np.all(x <= est.upper), run
        assert np.all(np.isfinite(est.upper[-1] - est.lower[-1]))


@pytest.mark.parametrize(("name", "h"), SOUND_CASES, ids=[f"{n}-h={h:g}" for n, h in SOUND_CASES])
def test_enclosure_against_exact_exponential_truth(name: str, h: float) -> None:
    check_enclosure(name, h)


@pytest.mark.slow
@pytest.mark.parametrize(("name", "h"), SLOW_SOUND_CASES, ids=[f"{n}-h={h:g}" for n, h in SLOW_SOUND_CASES])
def test_enclosure_against_exact_exponential_truth_slow(name: str, h: float) -> None:
    check_enclosure(name, h)


def test_unstable_long_step_is_a_named_error() -> None:
    system = LTISystem([[800.0]], [[1.0]])
    with pytest.raises(AssumptionError, match="Phi, Gamma"):
        sampled_model(system, unit_bounds(1, 1, 1), 1.0)
    with pytest.raises(ArgumentTypeError, match=r"^h: expected a positive step for a continuous-time system, got None"):
        sampled_model(system, unit_bounds(1, 1, 1), None)


def test_old_examples_never_looser_than_cheap_bound() -> None:
    """A slow, small-norm model: the minimum keeps the cheap bound where it is tighter (never wider)."""
    a = np.array([[0.0, 1.0], [-2.0, -0.3]])
    d = 0.02 * np.abs(a)
    system = LTISystem(a, [[1.0, 0.0]], E=np.eye(2), dA=(-d, d))
    h = 0.05
    model = sampled_model(system, unit_bounds(2, 2, 1), h)
    cheap = np.maximum(expm((np.abs(a) + d) * h) - expm(np.abs(a) * h), 0.0)
    assert np.all(model.dPhi <= cheap * (1 + 1e-9))


def test_discrete_noise_generators_are_exact_and_continuous_ones_the_box() -> None:
    rng = np.random.default_rng(7)
    E = rng.normal(size=(3, 4))
    w = np.array([0.1, 0.2, 0.05, 0.3])
    bounds = Bounds((-np.ones(3), np.ones(3)), w=(-w, w), v=([-0.01], [0.01]))
    A = 0.5 * np.eye(3)
    discrete = sampled_model(LTISystem(A, np.ones((1, 3)), E=E, dt=1.0), bounds)
    np.testing.assert_array_equal(discrete.generators(), E * w)  # E diag(w_r): the noise set itself
    assert np.all(np.abs(discrete.generators()).sum(axis=1) <= discrete.noise_radius)
    continuous = sampled_model(LTISystem(-A, np.ones((1, 3)), E=E), bounds, h=0.1)
    assert continuous.noise_generators is None
    np.testing.assert_array_equal(continuous.generators(), np.diag(continuous.noise_radius))
