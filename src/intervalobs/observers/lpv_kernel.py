r"""The compiled recursion of :math:`z` of :class:`~intervalobs.observers.LPVIntervalObserver` over a block of samples.

:meth:`~intervalobs.observers.LPVIntervalObserver.advance_many` evaluates everything that does not depend on the
observer's state for a whole block at once (the model's enclosures, the known terms of :math:`\psi`, the measured
states and :math:`R_{11}x_m`); what is left is the recursion of :math:`\underline z, \overline z`, one sample after
the other. :func:`run_z` runs it in a Numba loop, so that a campaign task no longer pays a few hundred small NumPy
calls a sample (issue 36: that loop was most of a task's fixed cost).

Notes
-----
**The same numbers.** Per sample and run, :func:`run_z` evaluates the expressions of
``LPVIntervalObserver._state_box`` (measured states, :math:`C = (\tilde C\ 0)` square) and ``_next_z`` in the same
order of operations: the box :math:`(\underline z + x_m) - R_{11}x_m` and the isolation signals,
:func:`~intervalobs.interval.inflate` with the same margin, scale and floor, the hull with the step's flow box, the
exact interval product :math:`[\Delta A_R]\,B_k` (per term the least and greatest of the four end products, summed
over the row from the first term), :math:`\psi = ((\text{rate} + \Delta A_R B_k) + \Delta B_R u) + \Delta B_{un,R}
[u_{un}]` and :math:`z_{k+1} = e^{\underline F h} z_k + \Phi \psi` followed by the same inflation. Only the two
products with :math:`e^{Fh}` and :math:`\Phi` may be summed in another order than NumPy's (BLAS may fuse a multiply
and an add); for a diagonal :math:`F` (every campaign's :math:`-\lambda I`) each row has one nonzero term and the
results are the same to the last bit (tests/test_lpv.py).

**Soundness.** The recursion is computed in round-to-nearest, as the NumPy path is, and its outputs are widened by
the same rule, ``pad = ROUNDING_MARGIN * max(|lower|, |upper|) + tiny`` (``interval.py``, policy 2). The rounding
error of an :math:`n`-term dot product is bounded by :math:`\gamma_n \sum_j |a_j x_j|` whatever the order of its
terms (Higham 2002, Section 3.1), so a different order of summation changes the computed ends by no more than the
error the NumPy path's margin is already meant to cover; the kernel therefore contains the exact (real-arithmetic)
recursion exactly when the NumPy path does, and that recursion contains :math:`R(\vartheta)x` for every admissible
realisation (module docstring of :mod:`intervalobs.observers.lpv`).

Importing this module imports Numba; the first call of a fresh install compiles the kernel into Numba's cache
(``cache=True``), later processes load it. Only the campaign imports it: the default reproductions compile nothing.
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import NDArray

__all__ = ["run_z"]

FloatArray = NDArray[np.float64]


@numba.njit(cache=True, nogil=True, inline="always")
def _inflate(lo: float, hi: float, margin: float, tiny: float) -> tuple[float, float]:
    """:func:`~intervalobs.interval.inflate` of one interval with the default scale ``max(|lo|, |hi|)``."""
    pad = margin * max(abs(lo), abs(hi)) + tiny
    return lo - pad, hi + pad


@numba.njit(cache=True, nogil=True, inline="always")
def _psi_end(
    row: int,
    da: FloatArray,
    db: FloatArray,
    b_lo: FloatArray,
    b_hi: FloatArray,
    known: FloatArray,
    lower: bool,
) -> float:
    r"""One end of :math:`\psi_i` (33): the known terms around the exact row sum of :math:`[\Delta A_R] B_k`."""
    acc = 0.0
    for j in range(b_lo.size):
        p1, p2 = da[row, j] * b_lo[j], da[row, j] * b_hi[j]
        p3, p4 = db[row, j] * b_lo[j], db[row, j] * b_hi[j]
        acc += min(min(min(p1, p2), p3), p4) if lower else max(max(max(p1, p2), p3), p4)
    value = known[0, row] + acc + known[1, row]
    if known.shape[0] > 2:
        value = value + known[2, row]
    return value


@numba.njit(cache=True, nogil=True)
def run_z(
    z: FloatArray,
    state: FloatArray,
    flow: FloatArray,
    da: FloatArray,
    known: FloatArray,
    step: FloatArray,
    margin: float,
    tiny: float,
    out: FloatArray,
) -> None:
    r"""The recursion of :math:`\underline z, \overline z` over ``S`` samples of ``M`` runs (module docstring).

    Parameters
    ----------
    z : numpy.ndarray, shape (2, M, n)
        :math:`\underline z, \overline z` at the first sample; overwritten with their values after the last.
    state : numpy.ndarray, shape (2, S, M, n)
        The measured states :math:`x_m = \tilde C^{-1} y` and :math:`v_m = R_{11} x_m` of every sample.
    flow : numpy.ndarray, shape (2, S, M, n)
        Lower and upper ends of the box of the state over each step.
    da : numpy.ndarray, shape (2, S, M, n, n)
        Lower and upper :math:`\Delta A_R` of each step.
    known : numpy.ndarray, shape (2, K, S, M, n)
        For each end, the terms of :math:`\psi` that do not depend on :math:`z`, in the order they are added:
        the rate, :math:`\Delta B_R u` and (``K = 3``) :math:`\Delta B_{un,R}` times the unknown input's box.
    step : numpy.ndarray, shape (4, n, n)
        :math:`e^{\underline F h}, \Phi_{\underline F}, e^{\overline F h}, \Phi_{\overline F}`.
    margin, tiny : float
        Relative margin and floor of :func:`~intervalobs.interval.inflate`.
    out : numpy.ndarray, shape (4, S, M, n)
        Filled with the box of :math:`x(t_k)` and the isolation signals :math:`\underline\varepsilon,
        \overline\varepsilon` at every sample.
    """
    samples, runs, n = state.shape[1], state.shape[2], state.shape[3]
    b_lo, b_hi = np.empty(n), np.empty(n)
    psi_lo, psi_hi = np.empty(n), np.empty(n)
    for k in range(samples):
        for m in range(runs):
            for i in range(n):
                x_m, v_m = state[0, k, m, i], state[1, k, m, i]
                lo, hi = _inflate(z[0, m, i] + x_m - v_m, z[1, m, i] + x_m - v_m, margin, tiny)  # (32)
                out[0, k, m, i], out[1, k, m, i] = lo, hi
                out[2, k, m, i], out[3, k, m, i] = v_m - z[0, m, i], z[1, m, i] - v_m  # (29)-(30)
                b_lo[i], b_hi[i] = min(lo, flow[0, k, m, i]), max(hi, flow[1, k, m, i])
            for i in range(n):
                psi_lo[i] = _psi_end(i, da[0, k, m], da[1, k, m], b_lo, b_hi, known[0, :, k, m], True)
                psi_hi[i] = _psi_end(i, da[0, k, m], da[1, k, m], b_lo, b_hi, known[1, :, k, m], False)
            for i in range(n):
                zl, zu, pl, pu = 0.0, 0.0, 0.0, 0.0
                for j in range(n):
                    zl += step[0, i, j] * z[0, m, j]
                    pl += step[1, i, j] * psi_lo[j]
                    zu += step[2, i, j] * z[1, m, j]
                    pu += step[3, i, j] * psi_hi[j]
                b_lo[i], b_hi[i] = _inflate(zl + pl, zu + pu, margin, tiny)
            z[0, m] = b_lo
            z[1, m] = b_hi
