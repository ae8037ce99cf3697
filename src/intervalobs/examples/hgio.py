r"""The numerical example of the sampled-output high-gain paper (Section 5), as plain data and functions.

.. math::

    \dot x = Ax + \varphi(t, u, x) + d,\quad y(t_k) = x_1(t_k) + V(t_k),\quad
    \varphi = (2u + e^{-|x_1|},\; u + e^{-|x_2|},\; -u + e^{-|x_3|}),

    u(t) = 3\sin t - 2\sin 3t,\quad |V| \le 0.1,\quad d \in 0 \pm (0.1, 1, 1),

with the garbled :math:`A` reconstructed as :math:`[[-1, -3, 5], [0, 1, -3], [0, 2, -2]]` (the printed
:math:`L_1` and :math:`v_1` confirm :math:`A_{13} = +5`), disks :math:`(-0.9; 0.5)` and
:math:`(-0.6 \pm 1.8i; 0.2)`, :math:`\alpha_d = 0.08`, :math:`\alpha_n = 0.03`, initial box
:math:`x^c(0) = (0, 3, 4)`, :math:`x^r(0) = (0.09, 0.2, 0.6)`, step :math:`h = 10^{-3}` s, samples every
:math:`5\cdot10^{-3}` s, :math:`t \in [0, 30]`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..design.regions import Disk
from ..interval import matvec_bounds
from ..systems import Bounds
from ..systems.sampled import SampledSystem

__all__ = [
    "ALPHA_D",
    "ALPHA_N",
    "DISKS",
    "INPUT_RATE",
    "PAPER",
    "PHI_RADIUS",
    "SAMPLE_PERIOD",
    "STEP",
    "T_FINAL",
    "bounds",
    "input_signal",
    "phi",
    "phi_bounds",
    "system",
]

FloatArray = NDArray[np.float64]

A = np.array([[-1.0, -3.0, 5.0], [0.0, 1.0, -3.0], [0.0, 2.0, -2.0]])
C = np.array([[1.0, 0.0, 0.0]])
B_U = np.array([[2.0], [1.0], [-1.0]])
DISKS = (Disk(-0.9, 0.5), Disk(-0.6 + 1.8j, 0.2), Disk(-0.6 - 1.8j, 0.2))
ALPHA_D = 0.08
ALPHA_N = 0.03
STEP = 1e-3
SAMPLE_PERIOD = 5e-3
T_FINAL = 30.0
INPUT_RATE = 9.0
"""Bound of ``|du/dt|`` for u = 3 sin t − 2 sin 3t (3 + 6)."""
PHI_RADIUS = 0.5 + np.abs(B_U[:, 0]) * INPUT_RATE * STEP
"""Radius of the range of φ over any box and one step: ``e^{-|x|} ∈ (0, 1]`` and ``B_u u`` with ``|u̇| ≤ 9``."""

PAPER = {
    "L1": [1.111e-4, 1.25e-4, 1.0e-4],
    "p1": [-1.0003, -0.4999, -0.4999],
    "omega1": [0.0, 1.9365, -1.9365],
    "alpha": 8.7586,
    "theta": 9.7586,
    "v1": [
        [-0.9999, -1.75, 0.2503],
        [complex(-0.0001, 0.0001), complex(1.1154, -0.6992), complex(-0.1596, 1.6045)],
        [complex(-0.0001, -0.0001), complex(1.1154, 0.6992), complex(-0.1596, -1.6045)],
    ],
    "theta_arbitrary": 1000.0,
}
"""The paper's printed numbers (Section 5.2)."""


def phi(t: float, u: FloatArray, x: FloatArray) -> FloatArray:
    """The nonlinear term :math:`B_u u + e^{-|x|}` (vectorised over leading axes).

    Parameters
    ----------
    t : float
        Time (unused).
    u : numpy.ndarray, shape (..., 1)
        Known input.
    x : numpy.ndarray, shape (..., 3)
        State.

    Returns
    -------
    numpy.ndarray, shape (..., 3)
    """
    return np.asarray(np.asarray(u, dtype=float) @ B_U.T + np.exp(-np.abs(x)))


def phi_bounds(
    t0: float, t1: float, u_lower: FloatArray, u_upper: FloatArray, x_lower: FloatArray, x_upper: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Range enclosure of :func:`phi` over boxes: :math:`e^{-|x|} \\in [e^{-\\max|x|}, e^{-\\mathrm{mig}|x|}]`.

    Parameters
    ----------
    t0, t1 : float
        Time interval (``phi`` does not depend on time).
    u_lower, u_upper : numpy.ndarray, shape (..., 1)
        Box of the input.
    x_lower, x_upper : numpy.ndarray, shape (..., 3)
        Box of the state.

    Returns
    -------
    lower, upper : numpy.ndarray, shape (..., 3)
    """
    bu_lo, bu_hi = matvec_bounds(B_U, u_lower, u_upper)
    lo = np.asarray(x_lower, dtype=float)
    hi = np.asarray(x_upper, dtype=float)
    mag = np.maximum(np.abs(lo), np.abs(hi))
    mig = np.where(lo > 0, lo, np.where(hi < 0, -hi, 0.0))
    return bu_lo + np.exp(-mag), bu_hi + np.exp(-mig)


def system() -> SampledSystem:
    """The model of Section 5.1 (samples every 5 ms).

    Returns
    -------
    SampledSystem
    """
    return SampledSystem(A, C, phi=phi, phi_bounds=phi_bounds, m=1, sample_period=SAMPLE_PERIOD)


def bounds() -> Bounds:
    """Initial box (0, 3, 4) ± (0.09, 0.2, 0.6), d ∈ 0 ± (0.1, 1, 1), ``|V| ≤ 0.1``.

    Returns
    -------
    Bounds
    """
    xc = np.array([0.0, 3.0, 4.0])
    xr = np.array([0.09, 0.2, 0.6])
    dr = np.array([0.1, 1.0, 1.0])
    return Bounds(x0=(xc - xr, xc + xr), w=(-dr, dr), v=([-0.1], [0.1]))


def input_signal(t: float | FloatArray) -> FloatArray:
    """The known input :math:`u = 3\\sin t - 2\\sin 3t` of the paper's example.

    Parameters
    ----------
    t : float or numpy.ndarray
        Time(s).

    Returns
    -------
    numpy.ndarray, shape (..., 1)

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`), eq. (53).
    """
    tt = np.asarray(t, dtype=float)
    return np.asarray((3 * np.sin(tt) - 2 * np.sin(3 * tt))[..., None])
