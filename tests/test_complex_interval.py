"""Centred complex intervals (seed 004, Section 2): Theorem 2.1 and Proposition 2.2."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs.complex_interval import cabs, ctimes, delta_operator, linear_image, real_part_bounds
from intervalobs.errors import BoundsError, DimensionError


def _random(seed: int, k: int = 3, n: int = 4) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    m = rng.normal(size=(k, n)) + 1j * rng.normal(size=(k, n))
    c = rng.normal(size=n) + 1j * rng.normal(size=n)
    r = rng.uniform(0, 1, size=n) + 1j * rng.uniform(0, 1, size=n)
    return m, c, r


def test_cabs_and_ctimes_formula() -> None:
    assert cabs(np.array([-1 + 2j, 3 - 4j])) == pytest.approx(np.array([1 + 2j, 3 + 4j]))
    m, _, r = _random(0)
    expected = cabs(m) @ cabs(r) + 2 * np.abs(m.imag) @ np.abs(r.imag)
    np.testing.assert_allclose(ctimes(m, r), expected, rtol=1e-14)


@pytest.mark.parametrize("seed", range(5))
def test_linear_image_encloses_vertices_and_random_points_and_is_tight(seed: int) -> None:
    m, c, r = _random(seed)
    centre, radius = linear_image(m, c, r)
    rng = np.random.default_rng(seed + 100)
    signs_re = rng.choice([-1.0, 1.0], size=(512, c.size))
    signs_im = rng.choice([-1.0, 1.0], size=(512, c.size))
    inner = rng.uniform(-1, 1, size=(2, 512, c.size))
    for a, b in ((signs_re, signs_im), (inner[0], inner[1])):
        z = c + a * r.real + 1j * b * r.imag
        image = z @ m.T
        assert np.all(np.abs(image.real - centre.real) <= radius.real + 1e-12)
        assert np.all(np.abs(image.imag - centre.imag) <= radius.imag + 1e-12)
    # the real-part bound is attained at a vertex (exact hull)
    best = c + np.sign(m[0].real) * r.real - 1j * np.sign(m[0].imag) * r.imag
    assert (m[0] @ best).real == pytest.approx(centre[0].real + radius[0].real, rel=1e-12)


def test_real_part_bounds_and_leading_axes() -> None:
    m, c, r = _random(3)
    lo, hi = real_part_bounds(m, np.stack([c, c]), np.stack([r, r]))
    assert lo.shape == (2, 3)
    assert np.all(lo <= hi)


def test_delta_operator_reconstructs_points() -> None:
    _, c, r = _random(4)
    d = delta_operator(r)
    assert d.shape == (4, 8)
    sigma = np.random.default_rng(1).uniform(-1, 1, size=8)
    z = c + d @ sigma
    assert np.all(np.abs((z - c).real) <= r.real + 1e-15)
    assert np.all(np.abs((z - c).imag) <= r.imag + 1e-15)


def test_invalid_radius_and_shapes_raise() -> None:
    m, _, r = _random(5)
    with pytest.raises(BoundsError, match="nonnegative"):
        ctimes(m, -r)
    with pytest.raises(DimensionError, match="ctimes"):
        ctimes(m, r[:2])
