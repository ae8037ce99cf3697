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

The same recursion holds in coordinates :math:`z = Te` (:math:`M_z = TMT^{-1}`, disturbance radius
:math:`|T|d_k`, :math:`\delta\Phi_z = |T|\,\delta\Phi\,|T^{-1}|`, :math:`|e| \le |T^{-1}|\rho^z`). A slow
error mode of a dense :math:`M` (a stiff model sampled fast: :math:`\rho(M) = 1 - 10^{-4}`) needs
:math:`J \approx \ln(4\,|w|^T|v|)/(1 - \rho(M))` steps before :math:`|M^J|` contracts, far beyond any
affordable horizon; in the real modal basis of :math:`M` (:math:`M_z` block diagonal) every mode is its
own recursion, :math:`|M_z^i| = |M_z|^i` on the 1×1 blocks, so a short :math:`J` cuts nothing. The
design uses these coordinates for a gain whose identity-coordinate tube is not bounded.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import solve_discrete_are

from ..systems.sampling import SampledModel
from .cooperative import real_modal_basis

__all__ = ["TubeDesign", "design_tube_gain", "tube_horizon", "tube_stability"]

FloatArray = NDArray[np.float64]

_KALMAN_REGULARISATION = 1e-12
"""Added to the Kalman-type design covariances so they are positive definite (a design choice, not a
rounding pad: the gain is only a candidate, its tube is computed and verified afterwards)."""

_HORIZON_CONTRACTION = 0.25
_MAX_HORIZON = 4000
_SHORT_HORIZON = 256


@dataclass(frozen=True)
class TubeDesign:
    """A verified error-tube design.

    Attributes
    ----------
    L : numpy.ndarray, shape (n, p)
        Observer gain.
    T : numpy.ndarray, shape (n, n)
        Coordinates ``z = Te`` of the tube (identity, or the real modal basis of ``Φ - LC``).
    horizon : int
        Number ``J`` of exact terms kept in the tube recursion.
    gain_radius : float
        ``ρ(|M^J| + G δΦ)``, verified < 1.
    steady_radius : numpy.ndarray, shape (n,)
        Steady-state error radius of ``x`` from the noise alone (zero state magnitude).
    candidate : str
        Which candidate gain (and coordinates) won.
    """

    L: FloatArray
    T: FloatArray
    horizon: int
    gain_radius: float
    steady_radius: FloatArray
    candidate: str


def tube_horizon(m: FloatArray) -> int | None:
    """The horizon ``J`` of the tube recursion, or None when ``M`` is not Schur stable.

    The smallest ``J`` with ``‖|M^J|‖∞ ≤ 1/4``; when no ``J`` up to 4000 contracts that much (a slow
    error mode), the ``J ≤ 256`` with the smallest per-step rate ``ρ(|M^J|)^(1/J)``, provided it is
    below 1 (for a block-diagonal ``M`` that rate is ``ρ(M)`` already at ``J = 1``).

    Parameters
    ----------
    m : numpy.ndarray, shape (n, n)
        Error matrix ``M = Φ - LC`` (in the tube's coordinates).

    Returns
    -------
    int or None
        The horizon ``J``; None when ``ρ(M) ≥ 1`` or no ``J`` qualifies.
    """
    if np.max(np.abs(np.linalg.eigvals(m))) >= 1:
        return None
    power = np.eye(m.shape[0])
    short = []
    for j in range(1, _MAX_HORIZON + 1):
        power = m @ power
        if np.abs(power).sum(axis=1).max() <= _HORIZON_CONTRACTION:
            return j
        if j <= _SHORT_HORIZON:
            short.append(np.abs(power))
    rates = [float(np.max(np.abs(np.linalg.eigvals(p)))) ** (1.0 / j) for j, p in enumerate(short, start=1)]
    best = int(np.argmin(rates))
    return best + 1 if rates[best] < 1 else None


def abs_powers(m: FloatArray, count: int) -> FloatArray:
    """``|M^i|`` for ``i = 0 … count-1``, shape (count, n, n)."""
    out = np.empty((count, *m.shape))
    power = np.eye(m.shape[0])
    for i in range(count):
        out[i] = np.abs(power)
        power = m @ power
    return out


def tube_stability(
    model: SampledModel, m: FloatArray, disturbance: FloatArray, horizon: int, T: FloatArray | None = None
) -> tuple[float, FloatArray]:
    """Gain ``ρ(|M^J| + GδΦ)`` and the steady radius ``(I - |M^J| - GδΦ)⁻¹ G d`` (inf when unstable).

    Here ``G = Σ_{i<J} |M^i|``; in coordinates ``z = Te`` every quantity is the z one
    (``δΦ_z = |T|δΦ|T⁻¹|``, and ``disturbance`` and the steady radius are z radii).

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
    T : numpy.ndarray, shape (n, n), optional
        Coordinates of ``m`` and ``disturbance`` (default identity).

    Returns
    -------
    rho : float
        Spectral radius of ``|M^J| + GδΦ``.
    steady_radius : numpy.ndarray, shape (n,)
        Steady-state radius bound (``inf`` entries when ``rho ≥ 1``).
    """
    powers = abs_powers(m, horizon + 1)
    g = powers[:horizon].sum(axis=0)
    d_phi = model.dPhi if T is None else np.abs(T) @ model.dPhi @ np.abs(np.linalg.inv(T))
    loop = powers[horizon] + g @ d_phi
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
    measurement covariance scaled by 0.1, 1 and 10, and any ``extra`` gains (e.g. framer gains). Each
    runs in the original coordinates, or, when its tube is not bounded there, in the real modal
    basis of ``Φ - LC`` (see the module docstring).

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
    q = np.diag(np.square(model.noise_radius / scale) + np.square(spread / scale)) + _KALMAN_REGULARISATION * np.eye(n)
    r0 = np.diag((np.abs(F) @ v_radius) ** 2) + _KALMAN_REGULARISATION * np.eye(C.shape[0])
    candidates: dict[str, FloatArray] = {}
    for factor in (0.1, 1.0, 10.0):
        gain = _kalman_gain(model, C, q, r0 * factor / scale / scale)
        if gain is not None:
            candidates[f"kalman-{factor:g}"] = gain
    candidates.update(extra or {})
    best: TubeDesign | None = None
    for name, gain in candidates.items():
        error = model.Phi - gain @ C
        found = _tube_in(model, gain, error, np.eye(n), F, v_radius, name)
        modal = real_modal_basis(error) if found is None else None
        if modal is not None:
            found = _tube_in(model, gain, modal @ error @ np.linalg.inv(modal), modal, F, v_radius, f"{name}/modal")
        if found is not None and (best is None or found.steady_radius.sum() < best.steady_radius.sum()):
            best = found
    return best


def _tube_in(
    model: SampledModel,
    gain: FloatArray,
    m_z: FloatArray,
    T: FloatArray,
    F: FloatArray,
    v_radius: FloatArray,
    name: str,
) -> TubeDesign | None:
    """The tube of ``gain`` in coordinates ``T`` (``m_z = T(Φ - LC)T⁻¹``), or None when it is not bounded."""
    horizon = tube_horizon(m_z)
    if horizon is None:
        return None
    disturbance = np.abs(T) @ (model.noise_radius + np.abs(gain @ F) @ v_radius)
    radius, steady = tube_stability(model, m_z, disturbance, horizon, T)
    if not radius < 1:
        return None
    return TubeDesign(gain, T, horizon, radius, np.abs(np.linalg.inv(T)) @ steady, name)
