r"""Our own demonstration system: two masses coupled by springs, the position of the first measured.

State :math:`x = (q_1, q_2, \dot q_1, \dot q_2)`, unit masses, stiffnesses :math:`k_1 = 2` (wall–mass 1)
and :math:`k_2 = 1` (mass 1–mass 2), damping 0.4 on each mass; the stiffness entries of :math:`A` are
known to ±2 % and a force :math:`u = \sin(0.5t)` drives mass 2. Process noise ±0.05 on both
accelerations, measurement noise ±0.02, initial box ±0.5 around the origin.
"""

from __future__ import annotations

import numpy as np

from ..systems import Bounds, LTISystem

__all__ = ["SAMPLING_PERIOD", "T_FINAL", "bounds", "input_signal", "system"]

SAMPLING_PERIOD = 0.01
T_FINAL = 20.0


def system() -> LTISystem:
    """The uncertain two-mass system (continuous time).

    Returns
    -------
    LTISystem
        ``n = 4`` states, one known input, two process-noise channels, one output, interval ``dA``.
    """
    k1, k2, c = 2.0, 1.0, 0.4
    A = np.array(
        [[0, 0, 1, 0], [0, 0, 0, 1], [-(k1 + k2), k2, -c, 0], [k2, -k2, 0, -c]],
        dtype=float,
    )
    dA = np.zeros((4, 4))
    dA[2:, :2] = 0.02 * np.abs(A[2:, :2])
    B = np.array([[0.0], [0.0], [0.0], [1.0]])
    E = np.array([[0.0, 0.0], [0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    C = np.array([[1.0, 0.0, 0.0, 0.0]])
    return LTISystem(A, C, B=B, E=E, dA=(-dA, dA))


def bounds() -> Bounds:
    """Initial box ±0.5, process noise ±0.05, measurement noise ±0.02.

    Returns
    -------
    Bounds
    """
    return Bounds(
        x0=(-0.5 * np.ones(4), 0.5 * np.ones(4)),
        w=(-0.05 * np.ones(2), 0.05 * np.ones(2)),
        v=([-0.02], [0.02]),
    )


def input_signal(t: np.ndarray) -> np.ndarray:
    """The known force on mass 2, :math:`u = \\sin(0.5t)`.

    Parameters
    ----------
    t : numpy.ndarray, shape (T,)
        Times in seconds.

    Returns
    -------
    numpy.ndarray, shape (T, 1)
    """
    return np.sin(0.5 * t)[:, None]
