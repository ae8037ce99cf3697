import numpy as np
import pytest

from intervalobs.recursion import LinearRecursion


@pytest.mark.parametrize("kind", ["modal-complex", "modal-real", "blocked"])
def test_fast_recursion_matches_the_loop(kind):
    rng = np.random.default_rng(3)
    m = rng.normal(size=(4, 4))
    if kind == "modal-real":
        m = m @ m.T
    if kind == "blocked":  # a Jordan block is not diagonalisable
        m = np.eye(4) + np.diag(np.ones(3), 1)
    m *= 0.9 / np.max(np.abs(np.linalg.eigvals(m)))
    recursion = LinearRecursion(m)
    assert recursion.modal == (kind != "blocked")
    z0 = rng.normal(size=(3, 4))
    g = rng.normal(size=(3, 100, 4))
    fast = recursion(z0, g)
    z = z0.copy()
    for k in range(100):
        np.testing.assert_allclose(fast[:, k], z, rtol=1e-12, atol=1e-12)
        z = z @ m.T + g[:, k]
    np.testing.assert_allclose(fast[:, 100], z, rtol=1e-12, atol=1e-12)
