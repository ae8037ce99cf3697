r"""The integrated-observer paper, Section 6.2: the two-tank benchmark (72), Euler-discretised with Ts = 1 s.

.. math::

    A = \begin{bmatrix} 0.9886 + \theta_{11} & \theta_{12} \\ 0.0114 + \theta_{21} & 0.9903 + \theta_{22}
    \end{bmatrix},\quad B = \begin{bmatrix}0.2261\\0\end{bmatrix},\quad C = [0\ 1],

levels :math:`h_1, h_2` in cm, pump voltage ``u`` in V. The coupling follows (72): tank 1 drains into
tank 2, the pump feeds tank 1 and the sensor reads :math:`h_2` ((71) prints it reversed).
:math:`E_\omega = 0.006 I`. Chosen here (not printed or not consistent):

* :math:`E_\upsilon = 0.5` (1×1): the printed :math:`E_\upsilon = [0.5; 0.5]` is 2×1 for one output;
* :math:`\theta_{ij} \in [-0.001, 0.001]`: "±0.3B" is undefined. :math:`A_{11} = 0.9886` cannot be
  changed by any gain (``C`` does not see :math:`h_1`), so every sound framer has
  :math:`\rho(|M| + D) \ge 0.9886 + \theta`, and θ ≥ 0.0114 would stop tank 1 draining; the widths
  grow like ``θ·|x|``, so a small radius is kept;
* the pump signal (Fig. 8 is not given): a staircase in 0.2–0.55 V (levels stay below the 25 cm tubes),
  1200 samples; the initial box :math:`h \in [4, 6]^2` cm.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..systems import Bounds, LTISystem

__all__ = ["A0", "PRINTED_GAINS", "STEPS", "THETA", "bounds", "input_signal", "system", "time_grid"]

A0 = np.array([[0.9886, 0.0], [0.0114, 0.9903]])
B = np.array([[0.2261], [0.0]])
C = np.array([[0.0, 1.0]])
E_W = 0.006 * np.eye(2)
E_V = np.array([[0.5]])
THETA = 0.001
"""Half-width of every θ_ij (chosen; see the module docstring)."""
SAMPLING_PERIOD = 1.0
STEPS = 1200
X0 = (np.array([4.0, 4.0]), np.array([6.0, 6.0]))

PRINTED_GAINS: dict[str, list[float]] = {
    "set_based_(19)": [0.6647, 0.6542],
    "interval_(54a)-(55a)": [0.6542, 0.6493],
    "interval_(54)-(55)": [0.001, 0.9803],
    "set_based_thm3.4+3.5": [0.0100, 0.9903],
    "integrated_(19)+(65)": [0.001, 0.9803],
}
"""The gains printed in Section 6.2."""


def system() -> LTISystem:
    """The uncertain two-tank model (discrete time, Ts = 1 s).

    Returns
    -------
    LTISystem

    References
    ----------
    The integrated-observer paper (:mod:`intervalobs.references`), model (72).
    """
    d = THETA * np.ones((2, 2))
    return LTISystem(A0, C, B=B, E=E_W, F=E_V, dt=SAMPLING_PERIOD, dA=(-d, d))


def bounds() -> Bounds:
    """Initial box [4, 6]² cm (chosen), ``|ω| ≤ 1``, ``|υ| ≤ 1``.

    Returns
    -------
    Bounds
    """
    return Bounds(x0=X0, w=(-np.ones(2), np.ones(2)), v=(-np.ones(1), np.ones(1)))


def time_grid() -> NDArray[np.float64]:
    """Sample times 0, 1, …, 1199 s.

    Returns
    -------
    numpy.ndarray, shape (1200,)
    """
    return np.arange(STEPS, dtype=float) * SAMPLING_PERIOD


def input_signal(t: NDArray[np.float64]) -> NDArray[np.float64]:
    """Pump voltage: a staircase 0.35, 0.55, 0.25, 0.45, 0.2, 0.5 V, 200 s each.

    Parameters
    ----------
    t : numpy.ndarray, shape (T,)
        Sample times in seconds.

    Returns
    -------
    numpy.ndarray, shape (T, 1)
    """
    levels = np.array([0.35, 0.55, 0.25, 0.45, 0.2, 0.5])
    index = np.minimum((np.asarray(t, dtype=float) // 200).astype(int), levels.size - 1)
    return levels[index][:, None]
