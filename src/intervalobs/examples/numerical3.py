r"""The integrated-observer paper, Section 6.1: the 3-state numerical example, (68) (monotone) and (70) (one entry
−0.1).

.. math:: x_{k+1} = (A_0 + \Delta A(\theta))x_k + Bu_k + E_\omega\omega_k,\quad y_k = Cx_k + E_\upsilon\upsilon_k,

:math:`\theta_{ij} \in [-0.01, 0.01]` on every entry of ``A``, :math:`E_\omega = 0.08 I`,
:math:`E_\upsilon = 0.2`, :math:`|\omega|, |\upsilon| \le 1`, ``u = sin t`` on :math:`[0, 3\pi]` with 200
samples. Not printed, chosen here: the samples ``t = linspace(0, 3π, 200)`` (Δt = 3π/199), the initial
box :math:`x_0 \in [-1, 1]^3`, and the true θ (drawn per run by the simulation, a vertex of the box
under extreme noise).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import DataError
from ..systems import Bounds, LTISystem

__all__ = [
    "A68",
    "A70",
    "PRINTED_GAINS",
    "STEPS",
    "THETA",
    "T_FINAL",
    "bounds",
    "input_signal",
    "system",
    "time_grid",
]

A68 = np.array([[0.8, 0.1, 0.3], [0.0, 0.8, 0.2], [0.01, 0.0, 0.8]])
"""Nominal matrix of (68): all entries nonnegative."""

A70 = np.array([[0.8, -0.1, 0.3], [0.0, 0.8, 0.2], [0.01, 0.0, 0.8]])
"""Nominal matrix of (70): entry (1, 2) is −0.1."""

B = np.array([[0.0], [0.0], [1.0]])
C = np.array([[0.0, 0.0, 1.0]])
E_W = 0.08 * np.eye(3)
E_V = np.array([[0.2]])
THETA = 0.01
"""Half-width of every θ_ij."""
STEPS = 200
T_FINAL = 3 * np.pi
X0_RADIUS = 1.0
"""Half-width of the chosen initial box (not printed): x0 ∈ [−1, 1]³."""

PRINTED_GAINS: dict[str, dict[str, list[float]]] = {
    "68": {
        "set_based_thm3.4+3.5": [0.2781, 0.2855, 0.7982],
        "interval_(54)-(55)": [0.3, 0.2, 0.8],
    },
    "70": {
        "set_based_(19)": [-1.1376, -1.9167, -1.2604],
        "interval_(54a)-(55a)": [0.2754, 1.0571, 0.7724],
        "integrated_(19)+(65)": [0.2892, 0.2950, 0.8001],
    },
}
"""The gains printed in Section 6.1 (column vectors, written as lists)."""


def system(variant: str = "68") -> LTISystem:
    """The integrated-observer paper's uncertain three-state system, first or second form (``dt`` = 3π/199).

    Parameters
    ----------
    variant : {"68", "70"}

    Returns
    -------
    LTISystem

    References
    ----------
    The integrated-observer paper: the systems (68) and (70).
    """
    if variant not in ("68", "70"):
        raise DataError(f"variant: expected '68' or '70', got {variant!r}")
    a = A68 if variant == "68" else A70
    d = THETA * np.ones((3, 3))
    return LTISystem(a, C, B=B, E=E_W, F=E_V, dt=T_FINAL / (STEPS - 1), dA=(-d, d))


def bounds() -> Bounds:
    """Initial box ±1 (chosen), ``|ω| ≤ 1``, ``|υ| ≤ 1`` (the paper's noise bounds).

    Returns
    -------
    Bounds

    References
    ----------
    The integrated-observer paper (:mod:`intervalobs.references`), Assumption 3.1.
    """
    return Bounds(
        x0=(-X0_RADIUS * np.ones(3), X0_RADIUS * np.ones(3)),
        w=(-np.ones(3), np.ones(3)),
        v=(-np.ones(1), np.ones(1)),
    )


def time_grid() -> NDArray[np.float64]:
    """The 200 sample times on :math:`[0, 3\\pi]`.

    Returns
    -------
    numpy.ndarray, shape (200,)
    """
    return np.linspace(0.0, T_FINAL, STEPS)


def input_signal(t: NDArray[np.float64]) -> NDArray[np.float64]:
    """``u = sin t``.

    Parameters
    ----------
    t : numpy.ndarray, shape (T,)
        Sample times.

    Returns
    -------
    numpy.ndarray, shape (T, 1)
    """
    return np.sin(np.asarray(t, dtype=float))[:, None]
