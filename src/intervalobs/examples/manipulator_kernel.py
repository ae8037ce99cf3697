r"""The manipulator's closed-loop truth compiled: the campaign's time loop without a NumPy call a sample.

:func:`closed_loop_block` advances ``M`` runs of the true manipulator over a block of samples exactly as the
manipulator campaign's loop did with :func:`~intervalobs.examples.manipulator.controller` and
:func:`~intervalobs.examples.manipulator.rk4_step`: the same expressions in the same order (so the same numbers
wherever ``math.sin``/``math.cos`` round as NumPy's ``sin``/``cos`` do; tests/test_lpv.py compares them to the
last bit). The truth is a simulation, not a bound: nothing here enters an estimator's soundness argument, and a
last-bit difference would only move a true trajectory by a rounding error of the integrator.

Importing this module imports Numba; only the campaign does (issue 36: the 13 000-sample loop of the truth was
the fixed cost of a campaign task once the observer's recursion was compiled).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

__all__ = ["closed_loop_block"]

FloatArray = NDArray[np.float64]


@numba.njit(cache=True, nogil=True, inline="always")
def _torque(x: FloatArray, t: float, nominal: FloatArray, gains: FloatArray, out: FloatArray) -> None:
    """:func:`~intervalobs.examples.manipulator.controller` for one run (reference, computed torque)."""
    a, b, c = nominal[0], nominal[1], nominal[2]
    kp, kd = gains[0], gains[1]
    q0, q1 = np.pi / 12 + 0.5 * math.sin(0.5 * t), -np.pi / 12 + 0.5 * math.sin(0.7 * t)
    qd0, qd1 = 0.25 * math.cos(0.5 * t), 0.35 * math.cos(0.7 * t)
    qdd0, qdd1 = -0.125 * math.sin(0.5 * t), -0.245 * math.sin(0.7 * t)
    phi = x[1] - x[0]
    kap, sig = math.cos(phi), math.sin(phi)
    acc0 = qdd0 + kd * (qd0 - x[2]) + kp * (q0 - x[0])
    acc1 = qdd1 + kd * (qd1 - x[3]) + kp * (q1 - x[1])
    out[0] = a * acc0 + b * kap * acc1 - b * sig * x[3] ** 2
    out[1] = b * kap * acc0 + c * acc1 + b * sig * x[2] ** 2


@numba.njit(cache=True, nogil=True, inline="always")
def _rate(x: FloatArray, tau: FloatArray, par: FloatArray, out: FloatArray) -> None:
    """The true manipulator's rate (``manipulator._true_rate``) for one run."""
    at, bt, ct = par[0], par[1], par[2]
    phi = x[1] - x[0]
    kap, sig = math.cos(phi), math.sin(phi)
    bk = bt * kap
    inv = 1.0 / (at * ct - bk * bk)
    bs = bt * sig
    r1 = tau[0] + bs * x[3] ** 2
    r2 = tau[1] - bs * x[2] ** 2
    out[0], out[1] = x[2], x[3]
    out[2] = (ct * r1 - bk * r2) * inv
    out[3] = (at * r2 - bk * r1) * inv


@numba.njit(cache=True, nogil=True, inline="always")
def _rk4(x: FloatArray, tau: FloatArray, par: FloatArray, h: float, work: FloatArray) -> None:
    """One classical RK4 step (``simulate.runge_kutta_step``) of one run, in place, torque held."""
    k1, k2, k3, k4, arg = work[0], work[1], work[2], work[3], work[4]
    _rate(x, tau, par, k1)
    for i in range(4):
        arg[i] = x[i] + h / 2 * k1[i]
    _rate(arg, tau, par, k2)
    for i in range(4):
        arg[i] = x[i] + h / 2 * k2[i]
    _rate(arg, tau, par, k3)
    for i in range(4):
        arg[i] = x[i] + h * k3[i]
    _rate(arg, tau, par, k4)
    for i in range(4):
        x[i] = x[i] + h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i])


@numba.njit(cache=True, nogil=True)
def closed_loop_block(
    x: FloatArray,
    t: FloatArray,
    faults: FloatArray,
    onset: float,
    params: FloatArray,
    nominal: FloatArray,
    gains: FloatArray,
    h: float,
    substeps: int,
    xs: FloatArray,
    us: FloatArray,
) -> None:
    """Record and advance ``M`` runs over the samples ``t``: state and known input at each, then the next state.

    Parameters
    ----------
    x : numpy.ndarray, shape (M, 4)
        True states at ``t[0]``; overwritten with the states one sample after ``t[-1]``.
    t : numpy.ndarray, shape (S,)
        Sample times (s).
    faults : numpy.ndarray, shape (M, 2)
        Fault torque of each run, added to the known input at samples ``t >= onset`` (N·m).
    onset : float
        Fault onset (s).
    params : numpy.ndarray, shape (M, 3)
        True a, b, c of each run.
    nominal, gains : numpy.ndarray, shape (3,) and (2,)
        The controller's nominal a, b, c and its gains ``K_p, K_d``.
    h : float
        RK4 step (s); ``substeps`` of them make a sample interval.
    substeps : int
        RK4 steps per sample.
    xs, us : numpy.ndarray, shape (S, M, 4) and (S, M, 2)
        Filled with the states and the known inputs (the controller's torque) at the samples.
    """
    work = np.empty((5, 4))
    tau = np.empty(2)
    for k in range(t.size):
        for m in range(x.shape[0]):
            xs[k, m] = x[m]
            _torque(x[m], t[k], nominal, gains, us[k, m])
            tau[0], tau[1] = us[k, m, 0], us[k, m, 1]
            if t[k] >= onset:
                tau[0], tau[1] = tau[0] + faults[m, 0], tau[1] + faults[m, 1]
            for _ in range(substeps):
                _rk4(x[m], tau, params[m], h, work)
