r"""Fast evaluation of the linear recursion :math:`z_{k+1} = M z_k + g_k` over a whole record.

A Python loop over time costs microseconds per step whatever the size. :class:`LinearRecursion`
precomputes, once per matrix, one of two exact rewritings:

* **modal** (when :math:`M = V\Lambda V^{-1}` with a well-conditioned :math:`V`): the modes
  :math:`\tilde z = V^{-1}z` obey scalar recursions :math:`\tilde z_{k+1} = \lambda\tilde z_k + \tilde g_k`,
  each run by SciPy's compiled ``lfilter``; the cost per step is two small matrix products;
* **blocked** (otherwise): blocks of ``K`` steps are one matrix product for all blocks and runs,
  :math:`z_{k_0+i} = M^i z_{k_0} + \sum_{j<i} M^{i-1-j} g_{k_0+j}`, and only the block starts are
  propagated sequentially.

Both agree with the step-by-step loop up to rounding; :attr:`LinearRecursion.error_factor` bounds how
much the rewriting can amplify it (``cond(V)``), so callers can size their outward margin.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.signal import lfilter

__all__ = ["LinearRecursion"]

FloatArray = NDArray[np.float64]

_MAX_MODAL_CONDITION = 1e4


class LinearRecursion:
    """All states of :math:`z_{k+1} = M z_k + g_k`, evaluated without a Python loop over time.

    Parameters
    ----------
    m : numpy.ndarray, shape (n, n)
        Transition matrix.
    block : int
        Block length of the blocked evaluation (used when ``M`` is not well diagonalisable).
    """

    def __init__(self, m: FloatArray, block: int = 16) -> None:
        self.m = np.asarray(m, dtype=float)
        n = self.m.shape[0]
        vals, vecs = np.linalg.eig(self.m)
        condition = float(np.linalg.cond(vecs))
        self.modal = condition < _MAX_MODAL_CONDITION
        self.error_factor = condition if self.modal else 1.0
        if self.modal:
            self._eigenvalues = vals
            self._vecs = vecs
            self._vecs_inv = np.linalg.inv(vecs)
            self._real = bool(np.all(vals.imag == 0))
            return
        self.block = block
        powers = np.empty((block + 1, n, n))
        powers[0] = np.eye(n)
        for i in range(1, block + 1):
            powers[i] = self.m @ powers[i - 1]
        toeplitz = np.zeros((block, n, block, n))
        for i in range(block):
            for j in range(i + 1):
                toeplitz[i, :, j, :] = powers[i - j]
        self._powers = powers
        self._toeplitz_t = toeplitz.reshape(block * n, block * n).T.copy()

    def __call__(self, z0: FloatArray, g: FloatArray) -> FloatArray:
        """States ``z_0 … z_{T-1}`` from ``z0`` (..., n) and inputs ``g`` (..., T-1, n).

        Parameters
        ----------
        z0 : numpy.ndarray, shape (..., n)
            Initial state; leading axes broadcast with those of ``g``.
        g : numpy.ndarray, shape (..., T - 1, n)
            Input of each step.

        Returns
        -------
        numpy.ndarray, shape (..., T, n)
        """
        n = self.m.shape[0]
        steps = g.shape[-2]
        lead = np.broadcast_shapes(np.shape(z0)[:-1], g.shape[:-2])
        z0 = np.broadcast_to(z0, (*lead, n))
        g = np.broadcast_to(g, (*lead, steps, n))
        out = np.empty((*lead, steps + 1, n))
        out[..., 0, :] = z0
        if steps == 0:
            return out
        if self.modal:
            out[..., 1:, :] = self._modal(z0, g)
        else:
            out[..., 1:, :] = self._blocked(z0, g, lead, steps)
        return out

    def _modal(self, z0: FloatArray, g: FloatArray) -> FloatArray:
        # Real matrix products only (NumPy's mixed real/complex products do not use BLAS).
        vinv, vecs = self._vecs_inv, self._vecs
        if self._real:
            modes_g: NDArray[np.generic] = g @ vinv.real.T
            modes_0: NDArray[np.generic] = z0 @ vinv.real.T
        else:
            modes_g = g @ vinv.real.T + 1j * (g @ vinv.imag.T)
            modes_0 = z0 @ vinv.real.T + 1j * (z0 @ vinv.imag.T)
        modes = np.empty(modes_g.shape, dtype=modes_g.dtype)
        for i, lam in enumerate(self._eigenvalues):
            lam_i = lam.real if self._real else lam
            zi = (lam_i * modes_0[..., i])[..., None]
            modes[..., i], _ = lfilter([1.0], [1.0, -lam_i], modes_g[..., i], axis=-1, zi=zi)
        if self._real:
            return np.asarray(modes.real @ vecs.real.T)
        return np.asarray(modes.real @ vecs.real.T - modes.imag @ vecs.imag.T)

    def _blocked(self, z0: FloatArray, g: FloatArray, lead: tuple[int, ...], steps: int) -> FloatArray:
        n, k = self.m.shape[0], self.block
        blocks = -(-steps // k)
        padded = np.zeros((*lead, blocks * k, n))
        padded[..., :steps, :] = g
        local = (padded.reshape(*lead, blocks, k * n) @ self._toeplitz_t).reshape(*lead, blocks, k, n)
        starts = np.empty((*lead, blocks, n))
        current = z0
        last = self._powers[k].T
        for b in range(blocks):
            starts[..., b, :] = current
            current = current @ last + local[..., b, k - 1, :]
        states = local + np.einsum("kij,...bj->...bki", self._powers[1:], starts)
        return np.asarray(states.reshape(*lead, blocks * k, n)[..., :steps, :])
