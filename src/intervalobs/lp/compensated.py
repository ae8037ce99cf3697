r"""Matrix-vector products accurate to about one rounding, with a rigorous error bound.

A weak-duality certificate evaluated at a point far from the origin loses every digit of a small
optimum in the cancellation of its large terms (a tank level of :math:`3\cdot 10^6` with noise
:math:`10^{-9}`). :func:`~intervalobs.lp.certified.dual_bounds` therefore centres the certificate on a
point :math:`\bar z` near the optimum, which needs the residuals :math:`\underline b - A\bar z` of the
rows: there :math:`A\bar z` nearly cancels the bound, and a plain product would leave an error of
:math:`\gamma_n |A||\bar z|` in them, as large as what centring removes.

:class:`RowProducts` evaluates :math:`A\bar z` with the compensated dot product ``Dot2`` of Ogita, Rump
and Oishi: every product is split exactly (``TwoProduct`` by Veltkamp splitting, no FMA needed) and
the sum is accumulated with the exact rounding errors of ``TwoSum``. For :math:`n` terms its result
:math:`s` satisfies

.. math:: |s - a^\top z| \le u\,|a^\top z| + \gamma_n^2\, |a|^\top |z|,
          \qquad \gamma_n = \frac{n u}{1 - n u},\; u = 2^{-53},

(their Proposition 5.5), i.e. the accuracy of a product computed in twice the working precision and
then rounded. :meth:`RowProducts.enclose` returns :math:`s` and twice that bound (with
:math:`|a^\top z| \le |s| + \text{bound}`, and a term for underflow in the splitting).

**Reference.** T. Ogita, S. M. Rump and S. Oishi, "Accurate sum and dot product", SIAM J. Sci. Comput. 26(6),
1955–1988, 2005. https://doi.org/10.1137/030601818
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy import sparse

__all__ = ["RowProducts"]

FloatArray = NDArray[np.float64]

_U = 2.0**-53
_SPLITTER = 2.0**27 + 1.0
_TINY = float(np.finfo(float).tiny)


def _split(a: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Veltkamp's split ``a = high + low``, each half with at most 26 significant bits (exact)."""
    c = _SPLITTER * a
    high = c - (c - a)
    return high, a - high


def _two_product(a: FloatArray, b: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``a·b = p + e`` exactly (barring underflow), with ``p = fl(a·b)``."""
    p = a * b
    a_hi, a_lo = _split(a)
    b_hi, b_lo = _split(b)
    return p, a_lo * b_lo - (((p - a_hi * b_hi) - a_lo * b_hi) - a_hi * b_lo)


def _two_sum(a: FloatArray, b: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``a + b = s + e`` exactly, with ``s = fl(a + b)``."""
    s = a + b
    b_virtual = s - a
    return s, (a - (s - b_virtual)) + (b - b_virtual)


class RowProducts:
    """The products ``A z`` of one matrix with many vectors, each row as a compensated dot product.

    Parameters
    ----------
    matrix_t : numpy.ndarray or scipy.sparse matrix, shape (cols, rows)
        ``Aᵀ``, as the LPs of :mod:`intervalobs.lp` keep it.
    """

    def __init__(self, matrix_t: Any) -> None:
        a = sparse.csr_matrix(matrix_t.T if sparse.issparse(matrix_t) else np.asarray(matrix_t).T)
        a.sum_duplicates()
        counts = np.diff(a.indptr)
        rows = a.shape[0]
        self.width = max(int(counts.max(initial=0)), 1)
        owner = np.repeat(np.arange(rows), counts)
        slot = np.arange(a.nnz) - a.indptr[owner]
        self.values = np.zeros((rows, self.width))
        self.columns = np.zeros((rows, self.width), dtype=np.intp)
        self.values[owner, slot] = a.data
        self.columns[owner, slot] = a.indices
        gamma = self.width * _U / (1.0 - self.width * _U)
        self.gamma_sq = gamma * gamma

    def enclose(self, z: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``A z`` and a bound on its error: ``|value - (A z)_i| ≤ error_i`` for every row.

        Parameters
        ----------
        z : numpy.ndarray, shape (cols,)
            Finite.

        Returns
        -------
        value, error : numpy.ndarray, shape (rows,)
        """
        factors = z[self.columns]
        products, errors = _two_product(self.values, factors)
        total, carry = products[:, 0], errors[:, 0]
        for i in range(1, self.width):
            total, rounding = _two_sum(total, products[:, i])
            carry = carry + (errors[:, i] + rounding)
        value = total + carry
        magnitude = (np.abs(self.values) * np.abs(factors)).sum(axis=1) * (1.0 + 2.0 * self.width * _U)
        bound = _U * np.abs(value) + self.gamma_sq * magnitude + 8.0 * self.width * _TINY
        return value, 2.0 * bound
