r"""Khajenejad & Yong, Section V: the nonlinear example of the GSISIO paper, and our own full-rank demonstration.

Paper's system (n = 2 states, p = 2 outputs, q = 2 unknown inputs; the paper's n = l = p = 2):

.. math::

    f_1(x) = 0.6x_1 - 0.12x_2 + 1.1\sin(0.3x_2 - 0.2x_1),\quad f_2(x) = -0.2x_1 - 0.14x_2,

    g_1(x) = 0.2x_1 + 0.65x_2 + 0.8\sin(0.3x_1 + 0.2x_2),\quad g_2(x) = \sin(x_1),

:math:`G = [[0, -0.1], [0.2, -0.2]]`, :math:`H = [[-0.1, 0.3], [0.25, -0.75]]` (rank 1),
:math:`B = D = 0`, :math:`|w|, |v| \le 0.2`, :math:`x_0 \in [[-1.1, -2], [2, 1.1]]`.

Not given by the paper, chosen here: the unknown input (Fig. 1 only; we use
:func:`paper_input`, two signals of amplitude up to ≈ 3 with a step and a ramp — the observer is not
told their bounds), the true :math:`x_0` (a vertex of the box under extreme noise), the horizon (300
steps) and the noise (bang-bang between the bounds).

Our own system (:func:`fullrank_system`) has a full-column-rank H (q = 1 unknown input, p = 2 outputs),
so that the paper's existence condition (8) holds and the paper's construction can be demonstrated.

Our own system with two hidden input directions (:func:`two_hidden_system`): three states, three
unknown inputs of which two never reach the outputs (rk H = 1), written as f, g and boxes only — its
Jacobian bounds come from :mod:`intervalobs.interval_dual`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._docstrings import shared_docs
from ..systems.bounds import Bounds
from ..systems.nonlinear import NonlinearSystem

__all__ = [
    "PRINTED",
    "STEPS",
    "X0_BOX",
    "G",
    "H",
    "fullrank_bounds",
    "fullrank_input",
    "fullrank_system",
    "paper_bounds",
    "paper_input",
    "paper_system",
    "two_hidden_bounds",
    "two_hidden_input",
    "two_hidden_system",
]

FloatArray = NDArray[np.float64]

G = np.array([[0.0, -0.1], [0.2, -0.2]])
H = np.array([[-0.1, 0.3], [0.25, -0.75]])
NOISE = 0.2
X0_BOX = (np.array([-1.1, -2.0]), np.array([2.0, 1.1]))
STEPS = 300

PRINTED: dict[str, Any] = {
    "jacobian_f_lower": [[0.38, -0.52], [-0.2, -0.14]],
    "jacobian_f_upper": [[0.82, 0.21], [-0.2, -0.14]],
    "jacobian_g_lower": [[-0.04, 0.49], [-1.0, 0.0]],
    "jacobian_g_upper": [[0.44, 0.81], [1.0, 0.0]],
    "L_f": 0.35,
    "L_g": 0.74,
    "K": [[0.0267, 0.0, 0.0666, 0.1061], [0.4177, 2.1203, 1.0817, 2.0209]],
    "L": [[0.0, 0.1017, 0.0, 0.0], [0.5194, 1.1814, 1.2787, 1.9302]],
    "rank_condition_8": [2, 2],
    "C_f": [[0.251, 0.0], [0.0029, 0.201]],
    "C_g": [[0.0, 0.225], [-0.374, -0.045]],
    "L_fd": 0.852,
    "L_gd": 1.19,
    "script_L": 0.643,
    "stability_condition": "(i)",
}
"""Every number the paper prints for its example (Section V)."""


def _f(x: Sequence[Any]) -> tuple[Any, Any]:
    return 0.6 * x[0] - 0.12 * x[1] + 1.1 * np.sin(0.3 * x[1] - 0.2 * x[0]), -0.2 * x[0] - 0.14 * x[1]


def _f_jacobian(x: Sequence[Any]) -> list[list[Any]]:
    c = np.cos(0.3 * x[1] - 0.2 * x[0])
    return [[0.6 - 0.22 * c, -0.12 + 0.33 * c], [-0.2, -0.14]]


def _g(x: Sequence[Any]) -> tuple[Any, Any]:
    return 0.2 * x[0] + 0.65 * x[1] + 0.8 * np.sin(0.3 * x[0] + 0.2 * x[1]), np.sin(x[0])


def _g_jacobian(x: Sequence[Any]) -> list[list[Any]]:
    c = np.cos(0.3 * x[0] + 0.2 * x[1])
    return [[0.2 + 0.24 * c, 0.65 + 0.16 * c], [np.cos(x[0]), 0.0]]


def paper_system() -> NonlinearSystem:
    """The example of Khajenejad & Yong, Section V (its boxes: :func:`paper_bounds`).

    Returns
    -------
    NonlinearSystem
    """
    return NonlinearSystem(_f, _g, G, H, f_jacobian=_f_jacobian, g_jacobian=_g_jacobian)


def paper_bounds() -> Bounds:
    """The paper's initial box :data:`X0_BOX` and noise bounds :math:`|w|, |v| \\le 0.2` (Section V).

    Returns
    -------
    Bounds
    """
    return Bounds(x0=X0_BOX, w=(-NOISE, NOISE), v=(-NOISE, NOISE))


@shared_docs
def paper_input(steps: int = STEPS) -> FloatArray:
    """Our unknown input for the paper's system, shape (steps, 2): a sinusoid with a step, and a ramp-sine.

    The paper shows its inputs only in Fig. 1; these are of similar size and shape. The observer is not
    told any bound on them.

    %(samples)s

    Returns
    -------
    numpy.ndarray, shape (steps, 2)
        One row per sample.
    """
    k = np.arange(steps, dtype=float)
    d1 = 1.5 * np.sin(0.05 * k) + np.where(k >= steps // 2, 1.0, 0.0)
    d2 = 2.0 * np.cos(0.03 * k) + 0.004 * k * np.sin(0.11 * k)
    return np.stack([d1, d2], axis=1)


# --- our own system with a full-column-rank H ---------------------------------------------------------

FULLRANK_G = np.array([[0.2], [-0.1]])
FULLRANK_H = np.array([[1.0], [0.5]])
FULLRANK_X0_BOX = (np.array([-1.0, -1.0]), np.array([1.0, 1.0]))
FULLRANK_NOISE = (0.05, 0.05)


def _f_own(x: Sequence[Any]) -> tuple[Any, Any]:
    return 0.3 * x[0] + 0.1 * np.sin(x[1]), 0.25 * x[1] - 0.1 * np.tanh(x[0])


def _f_own_jacobian(x: Sequence[Any]) -> list[list[Any]]:
    t = np.tanh(x[0])
    return [[0.3, 0.1 * np.cos(x[1])], [-0.1 * (1.0 - t * t), 0.25]]


def _g_own(x: Sequence[Any]) -> tuple[Any, Any]:
    return x[0] + 0.1 * np.sin(x[1]), 0.2 * x[1] + 0.05 * x[0]


def _g_own_jacobian(x: Sequence[Any]) -> list[list[Any]]:
    return [[1.0, 0.1 * np.cos(x[1])], [0.05, 0.2]]


def fullrank_system() -> NonlinearSystem:
    """Our own two-state system with one unknown input and a full-column-rank H: state and input recoverable.

    Returns
    -------
    NonlinearSystem

    References
    ----------
    Khajenejad & Yong (:mod:`intervalobs.references`): existence condition (8).
    """
    return NonlinearSystem(
        _f_own, _g_own, FULLRANK_G, FULLRANK_H, f_jacobian=_f_own_jacobian, g_jacobian=_g_own_jacobian
    )


def fullrank_bounds() -> Bounds:
    """Initial box and noise bounds of :func:`fullrank_system`.

    Returns
    -------
    Bounds
    """
    w, v = FULLRANK_NOISE
    return Bounds(x0=FULLRANK_X0_BOX, w=(-w, w), v=(-v, v))


@shared_docs
def fullrank_input(steps: int = 200) -> FloatArray:
    """Unknown input for :func:`fullrank_system`.

    %(samples)s

    Returns
    -------
    numpy.ndarray, shape (steps, 1)
        The input, sample by sample.
    """
    k = np.arange(steps, dtype=float)
    return (2.0 * np.sin(0.07 * k) + np.where((k > 60) & (k < 120), 1.5, 0.0))[:, None]


# --- our own system with two hidden input directions (no Jacobians written) ---------------------------

TWO_HIDDEN_G = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 0.2], [0.0, 1.0, 0.0]])
TWO_HIDDEN_H = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
TWO_HIDDEN_X0_BOX = (-np.ones(3), np.ones(3))
TWO_HIDDEN_NOISE = 0.02


def _f_two_hidden(x: Sequence[Any]) -> tuple[Any, Any, Any]:
    return (
        0.5 * x[0] + 0.2 * np.tanh(x[1]),
        0.4 * x[1] - 0.15 * np.sin(x[0]) + 0.1 * x[2],
        0.3 * x[2] + 0.2 * np.tanh(x[0] - x[1]),
    )


def _g_two_hidden(x: Sequence[Any]) -> tuple[Any, Any, Any]:
    return x[0] + 0.2 * np.tanh(x[1]), x[2] + 0.1 * np.sin(x[0]), x[1] + 0.1 * x[2]


def two_hidden_system() -> NonlinearSystem:
    r"""Our own three-state system with three unknown inputs, two of them hidden from the outputs.

    :math:`f = (0.5x_1 + 0.2\tanh x_2,\ 0.4x_2 - 0.15\sin x_1 + 0.1x_3,\ 0.3x_3 + 0.2\tanh(x_1 - x_2))`,
    :math:`g = (x_1 + 0.2\tanh x_2,\ x_3 + 0.1\sin x_1,\ x_2 + 0.1x_3)`; :math:`d_1, d_2` push
    :math:`x_1, x_3` and appear in no output, :math:`d_3` pushes :math:`x_2` and enters :math:`y_3`
    (``H`` has rank 1, so q - rk H = 2 hidden directions); :math:`|w|, |v| \le 0.02`. No Jacobian is
    given: the observers use the automatic ones.

    Returns
    -------
    NonlinearSystem
    """
    return NonlinearSystem(_f_two_hidden, _g_two_hidden, TWO_HIDDEN_G, TWO_HIDDEN_H)


def two_hidden_bounds() -> Bounds:
    """Initial box and noise bounds (:math:`|w|, |v| \\le 0.02`) of :func:`two_hidden_system`.

    Returns
    -------
    Bounds
    """
    return Bounds(
        x0=TWO_HIDDEN_X0_BOX, w=(-TWO_HIDDEN_NOISE, TWO_HIDDEN_NOISE), v=(-TWO_HIDDEN_NOISE, TWO_HIDDEN_NOISE)
    )


@shared_docs
def two_hidden_input(steps: int = 150) -> FloatArray:
    """Unknown inputs for :func:`two_hidden_system`: a sinusoid, a step and a slow cosine (unbounded for the observer).

    %(samples)s

    Returns
    -------
    numpy.ndarray, shape (steps, 3)
        The sinusoid, the step and the cosine, one column each.
    """
    k = np.arange(steps, dtype=float)
    return np.stack([1.5 * np.sin(0.1 * k), np.where(k > 60, 1.0, -0.5), 0.8 * np.cos(0.05 * k)], axis=1)
