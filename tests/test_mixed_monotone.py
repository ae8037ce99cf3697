"""Decomposition functions (seed 003, Prop. 3, eq. (2)): enclosure on random boxes, vertices included."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from intervalobs.design.mixed_monotone import (
    JacobianDecomposition,
    VertexDecomposition,
    decomposition_bounds,
    jacobian_bounds,
    jacobian_decomposition_parts,
    paper_lipschitz_constant,
    width_matrix,
)
from intervalobs.errors import AssumptionError
from intervalobs.examples import gsisio
from intervalobs.interval import Interval


def random_map(seed: int, n: int, m: int):
    """q(x) = A x + b * sin(C x + e): a generic mixed-monotone map with its Jacobian."""
    rng = np.random.default_rng(seed)
    A, C = rng.normal(size=(m, n)), rng.normal(size=(m, n))
    b, e = rng.normal(size=m), rng.normal(size=m)

    def q(x):
        return [sum(A[i, j] * x[j] for j in range(n)) + b[i] * np.sin(sum(C[i, j] * x[j] for j in range(n)) + e[i])
                for i in range(m)]  # fmt: skip

    def jac(x):
        rows = []
        for i in range(m):
            c = np.cos(sum(C[i, j] * x[j] for j in range(n)) + e[i])
            rows.append([A[i, j] + b[i] * C[i, j] * c for j in range(n)])
        return rows

    return q, jac


def _points(lo, hi, rng, count=200):
    return np.concatenate([Interval(lo, hi).vertices(), rng.uniform(lo, hi, size=(count, lo.size))])


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10_000), st.integers(1, 3), st.integers(1, 3), st.floats(0.0, 3.0))
def test_jacobian_decomposition_encloses_function_on_random_boxes(seed, n, m, scale):
    q, jac = random_map(seed, n, m)
    rng = np.random.default_rng(seed + 1)
    lo = rng.normal(size=n) * 2
    hi = lo + rng.uniform(0, scale, size=n)
    pts = _points(lo, hi, rng)
    values = np.stack([np.asarray(v) * np.ones(len(pts)) for v in q([pts[:, j] for j in range(n)])], -1)
    for j_lo, j_hi in (jacobian_bounds(jac, lo, hi), jacobian_bounds(jac, np.full(n, -np.inf), np.full(n, np.inf))):
        dlo, dhi = decomposition_bounds(q, lo, hi, j_lo, j_hi)
        assert np.all(dlo <= values) and np.all(values <= dhi)
        # the width bound W (sound replacement of Lemma 2) holds
        assert np.all(dhi - dlo <= width_matrix(j_lo, j_hi) @ (hi - lo) * (1 + 1e-9) + 1e-9)


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10_000))
def test_decomposition_is_mixed_monotone_and_consistent(seed):
    n = m = 2
    q, jac = random_map(seed, n, m)
    dec = JacobianDecomposition.from_jacobian(q, jac, np.full(n, -np.inf), np.full(n, np.inf))
    rng = np.random.default_rng(seed)
    x, y = rng.normal(size=(2, 50, n)) * 3
    step = np.abs(rng.normal(size=(50, n)))
    values = np.stack(q([x[:, j] for j in range(n)]), -1)
    np.testing.assert_allclose(dec(x, x), values, atol=1e-12)
    assert np.all(dec(x + step, y) >= dec(x, y) - 1e-12)  # nondecreasing in the first argument
    assert np.all(dec(x, y + step) <= dec(x, y) + 1e-12)  # nonincreasing in the second
    assert np.all(dec.C >= 0)


def test_case_split_and_C_on_the_paper_example():
    jf = (np.array([[0.38, -0.45], [-0.2, -0.14]]), np.array([[0.82, 0.21], [-0.2, -0.14]]))
    first, C = jacobian_decomposition_parts(*jf)
    np.testing.assert_array_equal(first, [[True, False], [False, False]])
    np.testing.assert_allclose(C, [[0, 0.21], [0, 0]])
    system = gsisio.paper_system()
    inf = np.full(2, np.inf)
    j_lo, j_hi = jacobian_bounds(system.f_jacobian, -inf, inf)
    np.testing.assert_allclose(j_lo, jf[0], atol=1e-12)
    np.testing.assert_allclose(j_hi, jf[1], atol=1e-12)
    g_lo, g_hi = jacobian_bounds(system.g_jacobian, -inf, inf)
    np.testing.assert_allclose(jacobian_decomposition_parts(g_lo, g_hi)[1], [[0.04, 0], [1, 0]], atol=1e-12)


def test_paper_lemma2_constant_is_not_a_bound():
    A = np.array([[1.0, 1.0], [1.0, -1.0]])

    def q(x):
        return [x[0] + x[1], x[0] - x[1]]

    dec = JacobianDecomposition(q, A, A)
    lo, hi = np.zeros(2), np.ones(2)
    dlo, dhi = dec.bounds(lo, hi)
    width = np.linalg.norm(dhi - dlo)
    paper = paper_lipschitz_constant(float(np.linalg.norm(A, 2)), dec.C) * np.linalg.norm(hi - lo)  # L_q = sqrt 2
    assert width > paper + 0.5  # 2.83 > 2.0
    assert width <= dec.lipschitz_width * np.linalg.norm(hi - lo) * (1 + 1e-9)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10_000))
def test_vertex_decomposition_is_exact_for_monotone_functions(seed):
    rng = np.random.default_rng(seed)
    s = rng.choice([-1.0, 1.0], size=(2, 3))
    w = rng.uniform(0.1, 2, size=(2, 3))

    def q(x):
        return [sum(s[i, j] * w[i, j] * np.tanh(x[j] + i) for j in range(3)) + s[i, 0] * x[0] ** 3 for i in range(2)]

    lo = rng.normal(size=3)
    hi = lo + rng.uniform(0, 2, size=3)
    dec = VertexDecomposition(q, s)
    dlo, dhi = dec.bounds(lo, hi)
    verts = Interval(lo, hi).vertices()
    vv = np.stack(q([verts[:, j] for j in range(3)]), -1)
    pts = _points(lo, hi, rng)
    pv = np.stack(q([pts[:, j] for j in range(3)]), -1)
    assert np.all(dlo <= pv) and np.all(pv <= dhi)
    np.testing.assert_allclose(dhi, vv.max(axis=0), rtol=1e-9, atol=1e-9)  # tight: attained at a vertex
    np.testing.assert_allclose(dlo, vv.min(axis=0), rtol=1e-9, atol=1e-9)


def test_vertex_decomposition_rejects_sign_changing_jacobian():
    with pytest.raises(AssumptionError, match="both signs"):
        VertexDecomposition.from_jacobian_bounds(lambda x: [x[0]], [[-1.0]], [[1.0]])


def test_unbounded_jacobian_is_an_assumption_error():
    with pytest.raises(AssumptionError, match="unbounded"):
        jacobian_bounds(lambda x: [[2.0 * x[0]]], [-np.inf], [np.inf])
