import dataclasses

import numpy as np
import pytest

from intervalobs import Bounds, LTISystem, SampledSystem
from intervalobs.errors import BoundsError, DimensionError
from intervalobs.systems import ResolvedBounds


@pytest.fixture
def system() -> LTISystem:
    return LTISystem(-np.eye(3), np.ones((2, 3)), E=np.ones((3, 1)))


def test_resolve_broadcasts_scalars_and_zeros_absent_noise(system):
    full = Bounds(x0=(-1.0, [1.0, 2.0, 3.0]), w=(-0.5, 0.25)).resolve(system)
    assert isinstance(full, ResolvedBounds)
    np.testing.assert_array_equal(full.x0[0], [-1.0, -1.0, -1.0])
    np.testing.assert_array_equal(full.x0[1], [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(full.w[0], [-0.5])
    np.testing.assert_array_equal(full.v[0], [0.0, 0.0])
    np.testing.assert_array_equal(full.v[1], [0.0, 0.0])
    np.testing.assert_array_equal(full.centre("x0"), [0.0, 0.5, 1.0])
    np.testing.assert_array_equal(full.radius("x0"), [1.0, 1.5, 2.0])
    np.testing.assert_array_equal(full.centre("w"), [-0.125])
    np.testing.assert_array_equal(full.radius("w"), [0.375])


def test_a_pair_of_numbers_is_the_same_interval_for_every_component(system):
    full = Bounds(x0=[1, 2]).resolve(system)
    np.testing.assert_array_equal(full.x0[0], [1.0, 1.0, 1.0])
    np.testing.assert_array_equal(full.x0[1], [2.0, 2.0, 2.0])


def test_a_nonzero_box_for_an_absent_channel_is_refused():
    no_noise = LTISystem(-np.eye(2), np.ones((1, 2)), E=np.zeros((2, 0)))
    assert Bounds(x0=(-1, 1), w=(0.0, 0.0)).resolve(no_noise).w[0].shape == (0,)
    with pytest.raises(
        DimensionError, match=r"^bounds\.w: expected no box or zeros \(the model's nw is 0\), got \(-0\.1, 0\.1\)$"
    ):
        Bounds(x0=(-1, 1), w=(-0.1, 0.1)).resolve(no_noise)


def test_resolving_twice_checks_sizes_and_returns_the_same_object(system):
    full = Bounds(x0=(-1.0, 1.0)).resolve(system)
    assert full.resolve(system) is full
    with pytest.raises(DimensionError, match=r"bounds\.x0: expected length 2 \(the model's n\), got 3"):
        full.resolve(LTISystem(-np.eye(2), np.ones((1, 2))))


def test_resolve_reads_the_sizes_of_a_sampled_system():
    sampled = SampledSystem(-np.eye(2), [[1.0, 0.0]], sample_period=0.1)
    full = Bounds(x0=(-1.0, 1.0), w=(-0.1, 0.1), v=(-0.01, 0.01)).resolve(sampled)
    assert (full.x0[0].size, full.w[0].size, full.v[0].size) == (2, 2, 1)


def test_bounds_are_read_only(system):
    full = Bounds(x0=(-1.0, 1.0)).resolve(system)
    with pytest.raises(dataclasses.FrozenInstanceError):
        full.w = (np.zeros(1), np.zeros(1))  # type: ignore[misc]


@pytest.mark.parametrize(
    ("kwargs", "error", "message"),
    [
        ({"x0": ([0, 2], [1, 1])}, BoundsError, r"^x0: expected lower <= upper, got lower\[1\]=2 > upper\[1\]=1$"),
        ({"x0": (0, 1), "w": (1, -1)}, BoundsError, r"^w: expected lower <= upper, got lower=1 > upper=-1$"),
        ({"x0": np.array([0.0, 1.0])}, BoundsError, r"^x0: expected a \(lower, upper\) pair, got ndarray$"),
        ({"x0": (0, 1, 2)}, BoundsError, r"^x0: expected a \(lower, upper\) pair, got \(0, 1, 2\)$"),
        ({"x0": (0, 1), "v": ([0, np.nan], 1)}, BoundsError, r"^v lower: expected finite entries, got \[0\.0, nan\]$"),
        ({"x0": ([0, 0], [1, 1, 1])}, DimensionError, r"^x0: expected lower and upper of equal length, got 2 and 3$"),
        ({"x0": (np.zeros((2, 2)), 1)}, DimensionError, r"^x0 lower: expected a number or a vector, got shape \(2, 2"),
        ({"x0": ("a", 1)}, DimensionError, r"^x0 lower: expected a number or a vector, got 'a'$"),
    ],
    ids=["x0-crossed", "w-crossed-scalars", "not-a-pair", "three-parts", "nan", "lengths", "matrix", "text"],
)
def test_construction_errors_name_the_argument_and_the_values(kwargs, error, message):
    with pytest.raises(error, match=message):
        Bounds(**kwargs)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"x0": ([0, 0], [1, 1])}, r"^bounds\.x0: expected length 3 \(the model's n\), got 2$"),
        ({"x0": (0, 1), "w": ([0, 0], [1, 1])}, r"^bounds\.w: expected length 1 \(the model's nw\), got 2$"),
        ({"x0": (0, 1), "v": ([0], [1])}, r"^bounds\.v: expected length 2 \(the model's nv\), got 1$"),
    ],
    ids=["x0", "w", "v"],
)
def test_sizes_are_checked_against_the_model(system, kwargs, message):
    with pytest.raises(DimensionError, match=message):
        Bounds(**kwargs).resolve(system)
