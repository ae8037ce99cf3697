r"""Error tubes: the exact elementwise bound of a Luenberger estimate's error under box disturbances.

For :math:`\hat x_{k+1} = \Phi\hat x_k + \Gamma u_k + L(y_k - C\hat x_k) + \dots` the error
:math:`e = x - \hat x` obeys :math:`e_{k+1} = Me_k + \eta_k` with :math:`M = \Phi - LC` and
:math:`\eta_k` in a box of radius :math:`d_k` (process noise, :math:`LFv`, and
:math:`\delta\Phi x_k + \delta\Gamma u_k` for interval models). Hence, exactly for independent boxes,

.. math:: |e_k| \le |M^k|\,\rho_0 + \sum_{i<k} |M^i|\, d_{k-1-i},

which is never wider than the framer bound :math:`\sum_i |M|^i d` (since :math:`|M^i| \le |M|^i`) and
needs only :math:`\rho(M) < 1`, not a stable :math:`|M|`. For data-dependent :math:`d_k` the sum is cut
after :math:`J` terms without loss of soundness,
:math:`\rho_k = |M^J|\rho_{k-J} + \sum_{i<J}|M^i| d_{k-1-i}`, where :math:`J` is chosen so that
:math:`|M^J|` is a strong contraction. With :math:`d_k = d^0 + \delta\Phi(|\hat x_k| + \rho_k)`, the
tube is bounded iff :math:`\rho(|M^J| + G\,\delta\Phi) < 1` with :math:`G = \sum_{i<J}|M^i|` (a positive
system with delays).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import solve_discrete_are

from ..systems.sampling import SampledModel

__all__ = ["TubeDesign", "design_tube_gain", "tube_horizon", "tube_stability"]

FloatArray = NDArray[np.float64]

_HORIZON_CONTRACTION = 0.25
_MAX_HORIZON = 4000


@dataclass(frozen=True)
class TubeDesign:
    """A verified error-tube design.

    Attributes
    ----------
    L : numpy.ndarray, shape (n, p)
        Observer gain.
    horizon : int
        Number ``J`` of exact terms kept in the tube recursion.
    gain_radius : float
        ``ρ(|M^J| + G δΦ)``, verified < 1.
    steady_radius : numpy.ndarray, shape (n,)
        Steady-state error radius from the noise alone (zero state magnitude).
    candidate : str
        Which candidate gain won.
    """

    L: FloatArray
    horizon: int
    gain_radius: float
    steady_radius: FloatArray
    candidate: str


def tube_horizon(m: FloatArray) -> int | None:
    """Smallest ``J`` with ``‖|M^J|‖∞ ≤ 1/4``, or None when ``M`` does not contract within the cap.

    Parameters
    ----------
    m : numpy.ndarray, shape (n, n)
        Error matrix ``M = Φ - LC``.

    Returns
    -------
    int or None
        The horizon ``J``; None when ``ρ(M) ≥ 1`` or no ``J`` up to the cap contracts enough.
    """
    if np.max(np.abs(np.linalg.eigvals(m))) >= 1:
        return None
    power = np.eye(m.shape[0])
    for j in range(1, _MAX_HORIZON + 1):
        power = m @ power
        if np.abs(power).sum(axis=1).max() <= _HORIZON_CONTRACTION:
            return j
    return None


def abs_powers(m: FloatArray, count: int) -> FloatArray:
    """``|M^i|`` for ``i = 0 … count-1``, shape (count, n, n)."""
    out = np.empty((count, *m.shape))
    power = np.eye(m.shape[0])
    for i in range(count):
        out[i] = np.abs(power)
        power = m @ power
    return out


def tube_stability(
    model: SampledModel, m: FloatArray, disturbance: FloatArray, horizon: int
) -> tuple[float, FloatArray]:
    """Gain ``ρ(|M^J| + GδΦ)`` and the steady radius ``(I - |M^J| - GδΦ)⁻¹ G d`` (inf when unstable).

    Here ``G = Σ_{i<J} |M^i|``.

    Parameters
    ----------
    model : SampledModel
        Sampled interval model (its ``δΦ``).
    m : numpy.ndarray, shape (n, n)
        Error matrix ``M = Φ - LC``.
    disturbance : numpy.ndarray, shape (n,)
        Per-step radius ``d⁰`` of the box disturbance entering the error (without the ``δΦ`` term).
    horizon : int
        Tube horizon ``J``.

    Returns
    -------
    rho : float
        Spectral radius of ``|M^J| + GδΦ``.
    steady_radius : numpy.ndarray, shape (n,)
        Steady-state radius bound (``inf`` entries when ``rho ≥ 1``).
    """
    powers = abs_powers(m, horizon + 1)
    g = powers[:horizon].sum(axis=0)
    loop = powers[horizon] + g @ model.dPhi
    radius = float(np.max(np.abs(np.linalg.eigvals(loop))))
    if radius >= 1:
        return radius, np.full(m.shape[0], np.inf)
    return radius, np.linalg.solve(np.eye(m.shape[0]) - loop, g @ disturbance)


def _kalman_gain(model: SampledModel, C: FloatArray, q: FloatArray, r: FloatArray) -> FloatArray | None:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            p = solve_discrete_are(model.Phi.T, C.T, q, r)
    except (ValueError, np.linalg.LinAlgError):
        return None
    return np.asarray(model.Phi @ p @ C.T @ np.linalg.inv(C @ p @ C.T + r))


def design_tube_gain(
    model: SampledModel,
    C: FloatArray,
    F: FloatArray,
    v_radius: FloatArray,
    extra: dict[str, FloatArray] | None = None,
) -> TubeDesign | None:
    """Pick the gain with the smallest steady error tube among Kalman-type and given candidates.

    Candidates are steady-state Kalman gains of the sampled model whose covariances are the squared
    box radii (process noise, plus the ``δΦ`` spread scaled by unit state magnitude), with the
    measurement covariance scaled by 0.1, 1 and 10, and any ``extra`` gains (e.g. framer gains).

    Parameters
    ----------
    model : SampledModel
        Sampled interval model.
    C, F : numpy.ndarray
        Output and measurement-noise matrices.
    v_radius : numpy.ndarray
        Measurement-noise radius.
    extra : dict of str to numpy.ndarray, optional
        More gains to compare.

    Returns
    -------
    TubeDesign or None
        None when no candidate gives a bounded tube.
    """
    n = model.Phi.shape[0]
    spread = model.dPhi.sum(axis=1)
    if not (np.all(np.isfinite(model.noise_radius)) and np.all(np.isfinite(spread))):
        return None
    scale = max(1.0, float(np.max(model.noise_radius)))
    q = np.diag(np.square(model.noise_radius / scale) + np.square(spread / scale)) + 1e-12 * np.eye(n)
    r0 = np.diag((np.abs(F) @ v_radius) ** 2) + 1e-12 * np.eye(C.shape[0])
    candidates: dict[str, FloatArray] = {}
    for factor in (0.1, 1.0, 10.0):
        gain = _kalman_gain(model, C, q, r0 * factor / scale / scale)
        if gain is not None:
            candidates[f"kalman-{factor:g}"] = gain
    candidates.update(extra or {})
    best: TubeDesign | None = None
    for name, gain in candidates.items():
        m = model.Phi - gain @ C
        horizon = tube_horizon(m)
        if horizon is None:
            continue
        disturbance = model.noise_radius + np.abs(gain @ F) @ v_radius
        radius, steady = tube_stability(model, m, disturbance, horizon)
        if radius < 1 and (best is None or steady.sum() < best.steady_radius.sum()):
            best = TubeDesign(gain, horizon, radius, steady, name)
    return best
