r"""Sound sampled models of continuous-time interval systems.

For :math:`\dot x = (A + \Delta A)x + Bu + Ew` with :math:`u` held over each step of length
:math:`h` (zero-order hold of the known input) and :math:`w(t)` *any* signal in its box, the state at
the sample times obeys

.. math:: x_{k+1} \in (\Phi \pm \delta\Phi)\,x_k + (\Gamma \pm \delta\Gamma)\,u_k + [c - r,\; c + r],

where :math:`\Phi, \Gamma` are the exact sampled matrices of the midpoint system and the elementwise
radii come from two facts, both consequences of the exponential series with nonnegative terms:

* :math:`|e^{(X + \Delta)s} - e^{Xs}| \le e^{(|X| + D)s} - e^{|X|s}` for :math:`|\Delta| \le D`;
* :math:`|e^{A s}E| \le e^{|A|\delta}\,|e^{A s_i}E|` for :math:`s \in [s_i, s_i + \delta]`.

The noise enters through :math:`\int_0^h e^{(A+\Delta)s}E\,w(t_{k+1} - s)\,ds`; with
:math:`w = w_c + \operatorname{diag}(w_r)\epsilon(s)`, :math:`|\epsilon| \le 1`, its centre is
:math:`\Gamma_E w_c` and its radius is bounded by


.. math:: \Big(\int_0^h |e^{As}E|\,ds + \int_0^h (e^{(|A|+D)s} - e^{|A|s})\,ds\,|E|\Big) w_r
          + \delta\Gamma_E|w_c|.

No assumption is made on the noise between samples. A discrete-time system is its own sampled model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import expm

from ..errors import BoundsError
from ..interval import ROUNDING_MARGIN
from ..systems.lti import Bounds, LTISystem

__all__ = ["SampledModel", "sampled_model"]

FloatArray = NDArray[np.float64]

_QUADRATURE_INTERVALS = 16


@dataclass(frozen=True)
class SampledModel:
    r"""A discrete-time interval model.

    .. math:: x^+ \in (\Phi \pm \delta\Phi)x + (\Gamma \pm \delta\Gamma)u + [c \pm r]

    Parameters
    ----------
    Phi, dPhi : numpy.ndarray, shape (n, n)
        Midpoint transition matrix and its elementwise radius (``dPhi >= 0``).
    Gamma, dGamma : numpy.ndarray, shape (n, m)
        Midpoint input matrix and its elementwise radius.
    noise_center, noise_radius : numpy.ndarray, shape (n,)
        Centre and radius of the box that holds the process-noise contribution of one step.
    h : float
        Step length (1.0 for a discrete-time system).
    """

    Phi: FloatArray
    dPhi: FloatArray
    Gamma: FloatArray
    dGamma: FloatArray
    noise_center: FloatArray
    noise_radius: FloatArray
    h: float

    @property
    def uncertain(self) -> bool:
        """True when the transition or input matrix is an interval (not a point) matrix."""
        return bool(np.any(self.dPhi > 0) or np.any(self.dGamma > 0))


def _integral_of_expm(x: FloatArray, h: float) -> FloatArray:
    """:math:`\\int_0^h e^{Xs} ds` from the exponential of the block matrix [[X, I], [0, 0]]."""
    n = x.shape[0]
    block = np.zeros((2 * n, 2 * n))
    block[:n, :n] = x
    block[:n, n:] = np.eye(n)
    return np.asarray(expm(block * h)[:n, n:])


def _integral_of_abs(a: FloatArray, e: FloatArray, h: float) -> FloatArray:
    r"""Upper bound of :math:`\int_0^h |e^{As}E|\,ds` (elementwise), by a left sum with a proven factor."""
    delta = h / _QUADRATURE_INTERVALS
    step = expm(a * delta)
    growth = expm(np.abs(a) * delta)
    total = np.zeros_like(e)
    current = e.copy()
    for _ in range(_QUADRATURE_INTERVALS):
        total += np.abs(current)
        current = step @ current
    return np.asarray(delta * (growth @ total))


def sampled_model(system: LTISystem, bounds: Bounds, h: float | None = None) -> SampledModel:
    """The sound sampled model of ``system`` with step ``h`` (see the module docstring).

    Parameters
    ----------
    system : LTISystem
        Continuous- or discrete-time model.
    bounds : Bounds
        Noise boxes (``w`` is used; ``x0`` and ``v`` are not).
    h : float, optional
        Step length, required for continuous time and ignored for discrete time.

    Returns
    -------
    SampledModel
        All radii rounded upward by the relative margin ``ROUNDING_MARGIN``.
    """
    bounds = bounds.for_system(system)
    assert bounds.w is not None
    w_center = 0.5 * (bounds.w[0] + bounds.w[1])
    w_radius = 0.5 * (bounds.w[1] - bounds.w[0])
    n, m, nw = system.n, system.m, system.nw
    if system.dA is None:
        a_mid, a_rad = system.A, np.zeros((n, n))
    else:
        a_mid = system.A + 0.5 * (system.dA[0] + system.dA[1])
        a_rad = 0.5 * (system.dA[1] - system.dA[0])
    if not system.continuous:
        system.sampling_period(h)  # refuses an h other than dt
        phi, gamma, d_phi, d_gamma = a_mid, system.B, a_rad, np.zeros((n, m))
        center = system.E @ w_center
        radius = np.abs(system.E) @ w_radius
        step = 1.0
    else:
        if h is None or not (np.isfinite(h) and h > 0):
            raise BoundsError(f"h: expected a positive step for a continuous-time system, got {h!r}")
        step = float(h)
        size = n + m + nw
        aug = np.zeros((size, size))
        aug[:n, :n], aug[:n, n : n + m], aug[:n, n + m :] = a_mid, system.B, system.E
        rad = np.zeros((size, size))
        rad[:n, :n] = a_rad
        exact = expm(aug * step)
        spread = np.maximum(expm((np.abs(aug) + rad) * step) - expm(np.abs(aug) * step), 0.0)
        phi, gamma, gamma_e = exact[:n, :n], exact[:n, n : n + m], exact[:n, n + m :]
        d_phi, d_gamma, d_gamma_e = spread[:n, :n], spread[:n, n : n + m], spread[:n, n + m :]
        center = gamma_e @ w_center
        abs_a = np.abs(a_mid)
        spread_integral = np.maximum(_integral_of_expm(abs_a + a_rad, step) - _integral_of_expm(abs_a, step), 0.0)
        radius = (_integral_of_abs(a_mid, system.E, step) + spread_integral @ np.abs(system.E)) @ w_radius
        radius = radius + d_gamma_e @ np.abs(w_center)
    # Round the radii upward; the rounding of the point matrices is absorbed by the observers' output margin.
    d_phi = d_phi * (1 + ROUNDING_MARGIN)
    d_gamma = d_gamma * (1 + ROUNDING_MARGIN)
    radius = radius * (1 + ROUNDING_MARGIN) + ROUNDING_MARGIN * np.abs(center)
    return SampledModel(phi, d_phi, gamma, d_gamma, center, radius, step)
