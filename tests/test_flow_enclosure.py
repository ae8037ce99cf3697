"""The validated flow enclosure over one sampling interval, against truths of the tests' own integrator."""

from __future__ import annotations

import importlib
import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import linprog

from intervalobs import Bounds, ContinuousNonlinearSystem
from intervalobs.errors import ArgumentError, AssumptionError, BoundsError
from intervalobs.interval import Interval
from intervalobs.systems import flow_enclosure
from intervalobs.systems.field_tape import trace_field
from intervalobs.systems.flow_enclosure import StateZonotope, propagate
from nonlinear_cases import Case, chemostat_bundle, cstr, pendulum, simulate_truth

enclosure_module = importlib.import_module("intervalobs.systems.flow_enclosure")  # the package re-exports the function


def _vertices(lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    return np.array(list(itertools.product(*zip(lower, upper))))


@pytest.mark.parametrize("make", [pendulum, cstr], ids=["pendulum", "cstr"])
def test_encloses_trajectories_from_vertices_with_switching_disturbance(make) -> None:
    case: Case = make()
    b = case.bounds.resolve(case.system)
    h = case.h
    t = np.array([0.0, h])
    u = np.full((2, case.system.m), 0.3)
    box = flow_enclosure(case.system, case.bounds, h, u=u[0])
    points = _vertices(*b.x0)
    params = np.vstack([_vertices(*b.p), b.centre("p")])
    for seed, (x0, p) in enumerate(itertools.product(points, params)):
        end = simulate_truth(case, x0, p, t, u, seed=seed, substeps=40)[-1]
        assert np.all(box.lower <= end) and np.all(end <= box.upper), (x0, p, end, box.lower, box.upper)
        assert np.all(box.a_priori_lower <= end) and np.all(end <= box.a_priori_upper)


def test_tight_for_a_point_and_exact_linear_flow() -> None:
    decay = ContinuousNonlinearSystem(lambda x, u, p: (-p[0] * x[0],), lambda x, u: (x[0],), n=1, n_params=1)
    box = flow_enclosure(decay, Bounds(x0=(1.0, 1.0), p=(1.0, 1.0)), h=1.0, substeps=16)
    assert box.lower[0] <= np.exp(-1.0) <= box.upper[0]
    assert box.upper[0] - box.lower[0] < 2e-3
    wide = flow_enclosure(decay, Bounds(x0=(1.0, 2.0), p=(0.9, 1.1)), h=0.5, substeps=8)
    exact = (np.exp(-0.55), 2.0 * np.exp(-0.45))
    assert wide.lower[0] <= exact[0] and exact[1] <= wide.upper[0]
    assert (wide.upper[0] - wide.lower[0]) < 1.2 * (exact[1] - exact[0])


def test_batched_boxes_match_single_ones() -> None:
    """A batch shares its step length (halved for all when one box needs it), so it agrees to the order of the step."""
    case = pendulum()
    lower = np.array([[0.4, -0.2], [0.5, 0.0]])
    upper = np.array([[0.6, 0.2], [0.55, 0.1]])
    u = np.array([[0.3], [0.3]])
    both = flow_enclosure(case.system, case.bounds, case.h, lower, upper, u=u)
    for i in range(2):
        one = flow_enclosure(case.system, case.bounds, case.h, lower[i], upper[i], u=u[i])
        np.testing.assert_allclose(both.lower[i], one.lower, rtol=1e-5, atol=1e-5)
        np.testing.assert_allclose(both.upper[i], one.upper, rtol=1e-5, atol=1e-5)


def test_blow_up_is_a_named_error() -> None:
    square = ContinuousNonlinearSystem(lambda x, u, p: (x[0] * x[0],), lambda x, u: (x[0],), n=1)
    with pytest.raises(AssumptionError, match="no validated enclosure of the flow"):
        flow_enclosure(square, Bounds(x0=(1.0, 2.0)), h=1.0)


def test_refused_arguments() -> None:
    case = pendulum()
    with pytest.raises(BoundsError, match="h: expected a positive step length"):
        flow_enclosure(case.system, case.bounds, h=0.0, u=[0.0])
    with pytest.raises(BoundsError, match="u: expected the held input"):
        flow_enclosure(case.system, case.bounds, h=0.1)


def test_zonotope_of_a_box_is_the_box() -> None:
    lower, upper = np.array([0.1, -2.0, 3.0]), np.array([0.3, 1.0, 3.0])
    hull = StateZonotope.from_box(lower, upper, order=5).box()
    assert hull.shape == (3,)
    assert np.all(hull.lower <= lower) and np.all(hull.upper >= upper)
    np.testing.assert_allclose(hull.lower, lower, rtol=1e-14)
    np.testing.assert_allclose(hull.upper, upper, rtol=1e-14)


@pytest.mark.parametrize("reduction", ["box", "frame"], ids=str)
@pytest.mark.parametrize("make", [pendulum, cstr], ids=["pendulum", "cstr"])
def test_the_compiled_step_gives_the_numpy_step_bounds(make, reduction: str) -> None:
    """flow_kernel.advance evaluates the NumPy step's formulas: the same sets up to the order of a few sums.

    Random start zonotopes (12 of them, 3 generators beyond the box's) so that the reduction runs too.
    """
    case: Case = make()
    b = case.bounds.resolve(case.system)
    rng = np.random.default_rng(7)
    size = case.system.n + case.system.n_params
    low = np.concatenate([b.x0[0], b.p[0]])
    high = np.concatenate([b.x0[1], b.p[1]])
    centre = low + (high - low) * rng.uniform(0.3, 0.7, (12, size))
    generators = 0.2 * (high - low)[:, None] * rng.uniform(-1.0, 1.0, (12, size, 4 * size))
    start = StateZonotope(centre, generators)
    u = np.full((12, case.system.m), 0.3)
    w = Interval._raw(*b.w)
    sets = [propagate(case.system, u, w, start, case.h, 2, 3 * size, bool(c), reduction=reduction)[0] for c in (0, 1)]
    numpy_box, compiled_box = sets[0].box(), sets[1].box()
    scale = numpy_box.upper - numpy_box.lower
    assert np.all(np.abs(compiled_box.lower - numpy_box.lower) <= 1e-12 * scale)
    assert np.all(np.abs(compiled_box.upper - numpy_box.upper) <= 1e-12 * scale)
    np.testing.assert_allclose(sets[1].generators, sets[0].generators, rtol=1e-12, atol=1e-12 * scale.max())


def _generators(seed: int, size: int, count: int, degenerate: int) -> np.ndarray:
    """Random generators turned by a rotation, norms spread over decades; ``degenerate`` picks a hard case."""
    rng = np.random.default_rng(seed)
    g = rng.normal(size=(size, count)) * np.logspace(0, -rng.uniform(1, 6), count)
    angle = rng.uniform(0, 2 * np.pi)
    turn = np.eye(size)
    turn[:2, :2] = [[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]]
    g = turn @ g
    if degenerate == 1:  # parameter rows untouched by the flow: zero in every small generator
        g[-1, size:] = 0.0
    elif degenerate == 2:  # all generators in one plane (rank 2)
        g[2:] = 0.0
    elif degenerate == 3:  # tiny and huge scales, zero columns
        g[:, -3:] = 0.0
        g[:, size : 2 * size] *= 1e-250
        g[0] *= 1e100
    return g


def _in_zonotope(point: np.ndarray, generators: np.ndarray) -> bool:
    """Whether ``point`` is ``generators @ eta`` for some ``|eta| <= 1`` (an LP: smallest infinity norm of eta)."""
    size, count = generators.shape
    # minimise s subject to G eta = point, -s <= eta <= s
    cost = np.zeros(count + 1)
    cost[-1] = 1.0
    a_eq = np.hstack([generators, np.zeros((size, 1))])
    a_ub = np.vstack(
        [np.hstack([np.eye(count), -np.ones((count, 1))]), np.hstack([-np.eye(count), -np.ones((count, 1))])]
    )
    result = linprog(cost, A_ub=a_ub, b_ub=np.zeros(2 * count), A_eq=a_eq, b_eq=point, bounds=(None, None))
    return bool(result.status == 0 and result.x[-1] <= 1.0 + 1e-7)


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**31),
    size=st.integers(3, 6),
    extra=st.integers(1, 20),
    keep=st.integers(0, 8),
    degenerate=st.integers(0, 3),
)
def test_the_frame_reduction_contains_the_original(
    seed: int, size: int, extra: int, keep: int, degenerate: int
) -> None:
    """Boxing the small generators in a frame keeps every point: by construction (the small generators solved in
    the frame have |x|1 <= d) and by LP membership of the original's vertices-like points in the reduced set."""
    order = size + keep
    g = _generators(seed, size, order + extra, degenerate)
    reduced = enclosure_module._reduce(g, order, "frame")
    assert reduced.shape == (size, order) and np.all(np.isfinite(reduced))
    norms = np.linalg.norm(g, axis=0)
    ranked = np.argsort(-norms, kind="stable")
    np.testing.assert_array_equal(reduced[:, :keep], g[:, ranked[:keep]])
    frame, small = reduced[:, keep:], g[:, ranked[keep:]]
    solved = np.linalg.lstsq(frame, small, rcond=None)[0]
    assert np.allclose(frame @ solved, small, rtol=1e-9, atol=1e-12 * np.abs(small).max(initial=0.0))
    assert np.all(np.abs(solved).sum(-1) <= 1.0 + 1e-9)
    if degenerate == 3:  # the LP's tolerances are absolute: skip the extreme scales
        return
    rng = np.random.default_rng(seed + 1)
    for xi in np.sign(rng.uniform(-1, 1, (6, g.shape[1]))):
        assert _in_zonotope(g @ xi, reduced)


@pytest.mark.parametrize("persistent", [0, 2], ids=["all-reduced", "2-persistent"])
@pytest.mark.parametrize("degenerate", [0, 1, 2, 3], ids=["random", "parameter-rows", "rank-2", "scales"])
def test_the_compiled_frame_reduction_is_the_numpy_one(degenerate: int, persistent: int) -> None:
    """flow_kernel._reduce(frame=True) evaluates enclosure_module._reduce_in_frame's formulas (bit for bit here),
    the leading ``persistent`` columns copied and the others reduced to ``order - persistent`` (``with_box``'s)."""
    from intervalobs.systems import flow_kernel

    for seed in range(20):
        size, order = 3 + seed % 4, 8 + seed % 5 + persistent
        g = _generators(seed, size, order + 7, degenerate)
        out = np.empty((size, order))
        flow_kernel._reduce(g, order, True, persistent, out)
        kept, rest = g[:, :persistent], g[:, persistent:]
        scale = np.abs(enclosure_module._reduce(rest, order - persistent, "box")).max()
        expected = np.concatenate([kept, enclosure_module._reduce(rest, order - persistent, "frame")], axis=1)
        np.testing.assert_array_equal(out[:, :persistent], kept)
        np.testing.assert_allclose(out, expected, rtol=1e-12, atol=1e-12 * scale)


def test_the_kernel_uses_the_frame_constants() -> None:
    from intervalobs.systems import flow_kernel

    for name in ("_FRAME_BITS", "_FRAME_ACCEPT", "_FRAME_RESIDUAL", "_FRAME_FLOOR", "_FRAME_TINY"):
        assert getattr(flow_kernel, name) == getattr(enclosure_module, name), name


def test_the_frame_box_turns_with_a_rotated_box() -> None:
    """A box turned by 30 degrees, split into many small generators: the frame of the largest boxes them with no
    wrapping; the axis box, turned back, is (sqrt(3)/2 + 1/2)^2 = 1.87 times the small generators' part."""
    angle = np.pi / 6
    turn = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    pieces = np.concatenate([np.repeat(turn[:, :1], 4, axis=1) * 0.25, np.repeat(turn[:, 1:], 4, axis=1) * 0.25], 1)
    g = np.concatenate([turn * [1.0, 0.9], pieces], axis=1)
    framed = enclosure_module._reduce(g, 4, "frame")
    boxed = enclosure_module._reduce(g, 4, "box")
    back = turn.T  # the hull in the turned coordinates: [2, 1.9] for the original and the frame's box
    assert np.abs(back @ framed).sum(-1) == pytest.approx(np.abs(back @ g).sum(-1), rel=1e-7)
    assert np.abs(back @ boxed).sum(-1) == pytest.approx(np.array([1.0, 0.9]) + (0.5 + 0.75**0.5) ** 2, rel=1e-7)


def test_a_refused_frame_falls_back_to_the_axis_box(monkeypatch: pytest.MonkeyPatch) -> None:
    """Where the frame's verified residual is above the limit, the small generators get Combastel's axis box."""
    g = _generators(3, 4, 20, 0)
    monkeypatch.setattr(enclosure_module, "_FRAME_RESIDUAL", -1.0)
    np.testing.assert_array_equal(enclosure_module._reduce(g, 8, "frame"), enclosure_module._reduce(g, 8, "box"))


@pytest.mark.parametrize("path", ["numpy", "compiled", "taped"])
@pytest.mark.parametrize("make", [pendulum, cstr, chemostat_bundle], ids=["pendulum", "cstr", "chemostat"])
def test_persistent_symbols_keep_their_meaning_over_many_steps(make, path: str) -> None:
    """With ``persistent=N`` the start's symbols stay the same: ``z(t_k) ∈ c_k + G_k ξ ± r_k`` for the start's ``ξ``.

    Starts at the vertices and inside the box (each with its ``ξ``), ``w`` switching inside the intervals; the
    residual ``z(t_k) - c_k - G_k ξ`` must lie in the hull of the other generators at every sample. On the NumPy
    step, the compiled one (field in Python) and the compiled one with the field's tape.
    """
    case: Case = make()
    b = case.bounds.resolve(case.system)
    size = case.system.n + case.system.n_params
    low, high = np.concatenate([b.x0[0], b.p[0]]), np.concatenate([b.x0[1], b.p[1]])
    if case.name == "chemostat-bundle":  # one small part, as the bundle's (the whole box loses the enclosure)
        low, high = low + (high - low) * [0.45, 0.45, 0.5, 0.5], low + (high - low) * [0.5, 0.5, 0.75, 0.75]
    centre, radius = 0.5 * (low + high), 0.5 * (high - low)
    zset = StateZonotope(centre, np.concatenate([np.diag(radius), np.zeros((size, 8))], axis=1))
    tape = trace_field(case.system, low, high)[0] if path == "taped" else None
    t = np.arange(0.0, 6 * case.h + 1e-12, case.h)
    u = np.full((t.size, case.system.m), 0.3)
    rng = np.random.default_rng(3)
    symbols = np.vstack([_vertices(-np.ones(size), np.ones(size)), rng.uniform(-1.0, 1.0, (6, size))])
    truths = [
        simulate_truth(case, (centre + radius * xi)[: case.system.n], (centre + radius * xi)[case.system.n :], t, u, s)
        for s, xi in enumerate(symbols)
    ]
    w = Interval._raw(*b.w)
    for k in range(1, t.size):
        zset = propagate(
            case.system, u[k - 1], w, zset, case.h, 4, size + 8, path != "numpy", tape=tape, persistent=size
        )[0]
        persistent, rest = zset.generators[:, :size], zset.generators[:, size:]
        reach = np.abs(rest).sum(axis=1) * (1 + 1e-12)
        assert np.all(reach[: case.system.n] < 0.5 * np.abs(persistent[: case.system.n]).sum(axis=1))  # not all rest
        for xi, truth in zip(symbols, truths):
            residual = truth[k] - zset.centre[: case.system.n] - persistent[: case.system.n] @ xi
            assert np.all(np.abs(residual) <= reach[: case.system.n] + 1e-12), (k, xi, residual, reach)


@pytest.mark.parametrize("reduction", ["box", "frame"], ids=str)
@pytest.mark.parametrize("make", [pendulum, cstr, chemostat_bundle], ids=["pendulum", "cstr", "chemostat"])
def test_persistent_generators_on_the_compiled_paths_give_the_numpy_sets(make, reduction: str) -> None:
    """With ``persistent=N`` both compiled paths (the field in Python, and by its tape) keep the leading columns and
    reduce the others as ``StateZonotope.with_box``: the same sets up to the order of a few sums (12 random starts
    with 3 generators beyond the box's, 4 steps, so that the reduction runs at each)."""
    case: Case = make()
    b = case.bounds.resolve(case.system)
    rng = np.random.default_rng(11)
    size = case.system.n + case.system.n_params
    low = np.concatenate([b.x0[0], b.p[0]])
    high = np.concatenate([b.x0[1], b.p[1]])
    centre = low + (high - low) * rng.uniform(0.3, 0.7, (12, size))
    generators = 0.01 * (high - low)[:, None] * rng.uniform(-1.0, 1.0, (12, size, 4 * size))
    start = StateZonotope(centre, generators)
    u, w = np.full((12, case.system.m), 0.3), Interval._raw(*b.w)
    tape = trace_field(case.system, low, high)[0]
    numpy_set, *compiled_sets = (
        propagate(case.system, u, w, start, case.h, 4, 3 * size, c, tape=t, reduction=reduction, persistent=size)[0]
        for c, t in ((False, None), (True, None), (True, tape))
    )
    numpy_box = numpy_set.box()
    scale = numpy_box.upper - numpy_box.lower
    for compiled_set in compiled_sets:
        compiled_box = compiled_set.box()
        assert np.all(np.abs(compiled_box.lower - numpy_box.lower) <= 1e-12 * scale)
        assert np.all(np.abs(compiled_box.upper - numpy_box.upper) <= 1e-12 * scale)
        np.testing.assert_allclose(compiled_set.generators, numpy_set.generators, rtol=1e-12, atol=1e-12 * scale.max())


def test_persistent_columns_are_checked() -> None:
    """More persistent columns than ``order - N`` (or than the start has) would leave the reduction no room."""
    case = pendulum()
    b = case.bounds.resolve(case.system)
    zset = StateZonotope.from_box(np.concatenate([b.x0[0], b.p[0]]), np.concatenate([b.x0[1], b.p[1]]))
    for persistent, order in ((-1, None), (4, None), (2, 4)):
        with pytest.raises(ArgumentError, match="persistent"):
            propagate(case.system, [0.3], Interval._raw(*b.w), zset, case.h, order=order, persistent=persistent)
