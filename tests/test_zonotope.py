"""Zonotope operations: every enclosure is tested on sampled points (vertices of the generator cube)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from intervalobs.errors import BoundsError, DimensionError
from intervalobs.zonotope import Zonotope, hull_radius, interval_matrix_image, reduce_order


def random_zonotope(rng: np.random.Generator, n: int, m: int) -> Zonotope:
    return Zonotope(rng.normal(size=n), rng.normal(size=(n, m)))


def sample_points(z: Zonotope, rng: np.random.Generator, count: int = 12) -> np.ndarray:
    """Vertices (random sign vectors) and interior points of a zonotope."""
    s = rng.choice([-1.0, 1.0], size=(count, z.order))
    s[: count // 3] = rng.uniform(-1, 1, size=(count // 3, z.order))
    return z.center + s @ z.generators.T


dims = st.tuples(st.integers(1, 3), st.integers(0, 6), st.integers(0, 2**31 - 1))


@settings(max_examples=25, deadline=None)
@given(dims)
def test_affine_map_and_minkowski_sum_contain_images(arg: tuple[int, int, int]) -> None:
    n, m, seed = arg
    rng = np.random.default_rng(seed)
    z1, z2 = random_zonotope(rng, n, m), random_zonotope(rng, n, max(m - 1, 0))
    mat, off = rng.normal(size=(2, n)), rng.normal(size=2)
    points = sample_points(z1, rng)
    assert np.all(z1.affine_map(mat, off).contains_points(points @ mat.T + off))
    pairs = points + sample_points(z2, rng)
    assert np.all((z1 + z2).contains_points(pairs))


@settings(max_examples=25, deadline=None)
@given(dims)
def test_interval_matrix_map_contains_every_product(arg: tuple[int, int, int]) -> None:
    n, m, seed = arg
    rng = np.random.default_rng(seed)
    z = random_zonotope(rng, n, m)
    mid, rad = rng.normal(size=(n, n)), np.abs(rng.normal(scale=0.3, size=(n, n)))
    image = z.interval_matrix_map(mid - rad, mid + rad)
    points = sample_points(z, rng)
    for _ in range(4):  # vertex matrices and random matrices of the interval matrix
        a_vertex = mid + rad * rng.choice([-1.0, 1.0], size=(n, n))
        a_random = mid + rad * rng.uniform(-1, 1, size=(n, n))
        assert np.all(image.contains_points(points @ a_vertex.T))
        assert np.all(image.contains_points(points @ a_random.T))


def test_interval_matrix_map_needs_the_box_for_the_centre() -> None:
    """The printed single generator diam(A)/2·c misses ΔA c for some ΔA; the sound box does not."""
    c = np.array([1.0, 1.0])
    rad = np.array([[0.1, 0.1], [0.1, 0.1]])
    delta = np.array([[0.1, 0.1], [-0.1, -0.1]])  # ΔA c = (0.2, -0.2), not on the segment t·(rad c)
    printed = Zonotope(np.zeros(2), (rad @ c)[:, None])
    assert not printed.contains_points((delta @ c)[None])[0]
    sound_c, sound_g = interval_matrix_image(-rad, rad, c, np.zeros((2, 0)))
    assert Zonotope(sound_c, sound_g).contains_points((delta @ c)[None])[0]


@settings(max_examples=25, deadline=None)
@given(st.tuples(st.integers(1, 3), st.integers(4, 12), st.integers(0, 2**31 - 1)))
def test_reduction_contains_original_and_keeps_hull(arg: tuple[int, int, int]) -> None:
    n, m, seed = arg
    rng = np.random.default_rng(seed)
    z = random_zonotope(rng, n, m)
    q = n + int(rng.integers(0, 3))
    reduced = z.reduce(q)
    assert reduced.order <= q
    assert np.all(reduced.contains_points(sample_points(z, rng)))
    np.testing.assert_allclose(reduced.interval_hull()[1], z.interval_hull()[1], rtol=1e-12)


def test_reduce_order_is_vectorised_over_leading_axes() -> None:
    rng = np.random.default_rng(3)
    g = rng.normal(size=(4, 3, 9))
    batch = reduce_order(g, 5)
    for i in range(4):
        np.testing.assert_array_equal(batch[i], reduce_order(g[i], 5))
    assert reduce_order(g, 12) is not None and reduce_order(g, 12).shape == g.shape


def test_interval_hull_is_tight() -> None:
    rng = np.random.default_rng(1)
    z = random_zonotope(rng, 3, 5)
    lo, hi = z.interval_hull()
    corner = z.center + z.generators @ np.sign(z.generators[0])
    assert corner[0] == pytest.approx(hi[0], rel=1e-12)
    assert np.all(z.contains_points(np.vstack([lo, hi])) == [False, False])
    np.testing.assert_allclose(hull_radius(z.generators), np.abs(z.generators).sum(axis=1))


def test_radii() -> None:
    z = Zonotope([0.0, 0.0], [[1.0, 1.0], [0.0, 2.0]])
    assert z.frobenius_radius() == pytest.approx(np.sqrt(6.0))
    # vertices s = (±1, ±1): Rs = (2, 2) or (0, -2) (and negatives): max squared norm 8
    assert z.w_radius() == pytest.approx(8.0)
    w = np.diag([2.0, 1.0])
    assert z.w_radius(w) == pytest.approx(12.0)
    assert Zonotope([0.0], np.zeros((1, 0))).w_radius() == 0.0


def test_from_box_and_validation() -> None:
    z = Zonotope.from_box([0.0, -1.0], [2.0, 1.0])
    lo, hi = z.interval_hull()
    np.testing.assert_allclose(lo, [0.0, -1.0])
    np.testing.assert_allclose(hi, [2.0, 1.0])
    with pytest.raises(BoundsError, match="lower <= upper"):
        Zonotope.from_box([1.0], [0.0])
    with pytest.raises(DimensionError, match="order"):
        z.reduce(1)
    with pytest.raises(DimensionError, match="generators"):
        Zonotope([0.0, 0.0], np.ones((3, 2)))
    with pytest.raises(BoundsError, match="positive definite"):
        z.w_radius(-np.eye(2))
    with pytest.raises(BoundsError, match="a_lower <= a_upper"):
        z.interval_matrix_map(np.ones((2, 2)), np.zeros((2, 2)))
    with pytest.raises(DimensionError, match="reduce first"):
        Zonotope(np.zeros(2), np.ones((2, 21))).w_radius()
