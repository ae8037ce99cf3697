r"""Output-derivative estimation for the unknown-input bounds of the aircraft UIO paper (Section 2.2, eqs. (2)–(9)).

Two estimators of :math:`\dot\psi` (the derivative of the noise-free output :math:`\psi = Cx`) from the
samples :math:`y_k = \psi(t_k) + \delta(t_k)`:

* :class:`HOSMDifferentiator` — Levant's arbitrary-order sliding-mode differentiator as printed in the
  aircraft UIO paper, §2.2, integrated by explicit Euler (optionally with sub-steps), vectorised over outputs and Monte
  Carlo runs. Its error bound (4)/(8), :math:`\beta = \bar{\dot\delta} + \mu_1\bar\delta^{1/2}`, holds only
  after a convergence time and only if :math:`\mu_1` is right for the gains *and the integration step*:
  explicit Euler with the paper's :math:`\lambda = 100` at :math:`T_e = 10^{-4}` has a steady error
  :math:`\approx \lambda_0^2 T_e/4 = 0.25`, not :math:`\mu_1\sqrt{\bar\delta} = 0.11`. The bound is
  therefore *demonstrated* (measured), never proved; see :func:`settling_time`.
* :func:`difference_derivative_bounds` — a *provable* enclosure. If :math:`|\ddot\psi| \le L` (the
  assumption under which Levant's differentiator is designed, :math:`\lambda_s = 1.1L`) and the noise is
  smooth with :math:`|\dot\delta| \le \bar{\dot\delta}` (the aircraft UIO paper, §1), the mean-value theorem gives

  .. math:: \dot\psi(t_k) \in \frac{y_k - y_{k-1}}{t_k - t_{k-1}} \pm \Big(\bar{\dot\delta}
            + \tfrac{L}{2}(t_k - t_{k-1})\Big),

  for every admissible noise realisation, with no transient beyond one sample.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import BoundsError, DataError, DimensionError
from ..interval import inflate
from ..validation import as_time, as_vector

__all__ = [
    "LEVANT_COEFFICIENTS",
    "HOSMDifferentiator",
    "difference_derivative_bounds",
    "difference_pair_bounds",
    "hosm_error_bound",
    "levant_gains",
    "settling_time",
]

FloatArray = NDArray[np.float64]

LEVANT_COEFFICIENTS = (1.1, 1.5, 2.0, 3.0, 5.0, 8.0)
"""Levant (2003) coefficients λ̃_0 … λ̃_5 of the recursive differentiator, valid up to order 5."""

_UNIT_ROUNDOFF = np.finfo(float).eps / 2


def levant_gains(order: int, lipschitz: float) -> FloatArray:
    r"""Levant's recommended gains for the recursion of the aircraft UIO paper, §2.2.

    The equation of :math:`q_j` uses :math:`\lambda_j = \tilde\lambda_{s-j} L^{1/(s-j+1)}`, with
    :math:`\tilde\lambda = (1.1, 1.5, 2, 3, 5, 8)` and :math:`L` a bound of :math:`|\psi^{(s+1)}|`.
    For ``order = 1``: :math:`\lambda_0 = 1.5\sqrt{L}`, :math:`\lambda_1 = 1.1L`.

    Parameters
    ----------
    order : int
        Differentiator order ``s`` (1 … 5).
    lipschitz : float
        Bound ``L`` of the ``(s+1)``-th derivative of the noise-free signal.

    Returns
    -------
    numpy.ndarray, shape (s + 1,)
    """
    if not 1 <= order <= len(LEVANT_COEFFICIENTS) - 1:
        raise DimensionError(f"order: expected 1 … {len(LEVANT_COEFFICIENTS) - 1}, got {order}")
    if not (np.isfinite(lipschitz) and lipschitz > 0):
        raise BoundsError(f"lipschitz: expected a positive bound, got {lipschitz!r}")
    return np.array([LEVANT_COEFFICIENTS[order - j] * lipschitz ** (1.0 / (order - j + 1)) for j in range(order + 1)])


def hosm_error_bound(delta_bar: ArrayLike, delta_dot_bar: ArrayLike, mu1: float) -> FloatArray:
    r"""The differentiator's derivative-error bound :math:`\beta = \bar{\dot\delta} + \mu_1\bar\delta^{1/2}`.

    Parameters
    ----------
    delta_bar, delta_dot_bar : array_like, shape (p,)
        Bounds of the measurement noise and of its derivative.
    mu1 : float
        Gain of the differentiator's error bound for the first derivative.

    Returns
    -------
    numpy.ndarray, shape (p,)

    References
    ----------
    The aircraft UIO paper (:mod:`intervalobs.references`): β of eq. (8); ``mu1`` of Theorem 3, eq. (4), for ``j =
    1``, ``s = 1``.
    """
    d = as_vector("delta_bar", delta_bar)
    dd = as_vector("delta_dot_bar", delta_dot_bar, d.size)
    if np.any(d < 0) or np.any(dd < 0) or not mu1 >= 0:
        raise BoundsError("hosm_error_bound: expected nonnegative delta_bar, delta_dot_bar and mu1")
    return np.asarray(dd + mu1 * np.sqrt(d))


class HOSMDifferentiator:
    r"""Levant's ``s``-th order sliding-mode differentiator (the aircraft UIO paper, §2.2), explicit Euler.

    .. math::

        \dot q_0 = \nu_0,\quad \nu_0 = -\lambda_0|q_0 - y|^{s/(s+1)}\operatorname{sign}(q_0 - y) + q_1,\\
        \dot q_i = \nu_i,\quad \nu_i = -\lambda_i|q_i - \nu_{i-1}|^{(s-i)/(s-i+1)}
                   \operatorname{sign}(q_i - \nu_{i-1}) + q_{i+1},\\
        \dot q_s = -\lambda_s \operatorname{sign}(q_s - \nu_{s-1}).

    One explicit Euler step per sample interval. Row ``k`` of :meth:`run` is the state at ``t_k``,
    computed from ``y_0 … y_{k-1}`` (the state starts at ``q_0 = y_0``, higher derivatives 0). With
    :math:`\lambda_0 = 100` at :math:`T_e = 10^{-4}` the steady derivative error is
    :math:`\approx\lambda_0^2 T_e/4 = 0.25` (sampling chatter; sub-stepping the Euler scheme on the held
    sample does not reduce it — measured), so the paper's :math:`\mu_1 = 1.1` does not hold there;
    Levant's gains (:func:`levant_gains`) give ≈ 0.026 on the aircraft outputs.

    Parameters
    ----------
    order : int
        ``s`` ≥ 1.
    gains : array_like, shape (s + 1,) or (p, s + 1)
        ``λ_0 … λ_s`` (per output if 2-D). The paper's example uses 100 for all.
    """

    def __init__(self, order: int, gains: ArrayLike) -> None:
        if order < 1:
            raise DimensionError(f"order: expected ≥ 1, got {order}")
        g = np.array(gains, dtype=float)
        if g.shape[-1] != order + 1 or g.ndim not in (1, 2):
            raise DimensionError(f"gains: expected shape ({order + 1},) or (p, {order + 1}), got {g.shape}")
        if not np.all(np.isfinite(g)) or np.any(g <= 0):
            raise BoundsError("gains: expected positive finite λ")
        self.order = order
        self.gains = g
        self._columns = [np.ascontiguousarray(g[..., j]) for j in range(order + 1)]
        self._powers = [(order - i) / (order - i + 1) for i in range(order)]

    def init(self, y0: ArrayLike) -> FloatArray:
        """Initial state, shape ``(..., p, s + 1)``: ``q_0 = y_0``, ``q_j = 0`` for ``j ≥ 1``.

        Parameters
        ----------
        y0 : array_like, shape (..., p)
            First measurement.

        Returns
        -------
        numpy.ndarray
        """
        y = np.asarray(y0, dtype=float)
        q = np.zeros((*y.shape, self.order + 1))
        q[..., 0] = y
        return q

    def step(self, q: FloatArray, y: ArrayLike, h: float) -> FloatArray:
        """Advance the state over one sample interval of length ``h`` with the measurement ``y`` held.

        Parameters
        ----------
        q : numpy.ndarray, shape (..., p, s + 1)
            State at ``t_k``.
        y : array_like, shape (..., p)
            Measurement ``y_k``.
        h : float
            Sample interval.

        Returns
        -------
        numpy.ndarray
            State at ``t_{k+1}``.
        """
        s = self.order
        lam = self._columns
        nu_prev = np.asarray(y, dtype=float)
        rates = np.empty_like(q)
        for i in range(s):
            e = q[..., i] - nu_prev
            nu = q[..., i + 1] - lam[i] * np.abs(e) ** self._powers[i] * np.sign(e)
            rates[..., i] = nu
            nu_prev = nu
        rates[..., s] = -lam[s] * np.sign(q[..., s] - nu_prev)
        return np.asarray(q + h * rates)

    def run(self, y: ArrayLike, h: float) -> FloatArray:
        """States at every sample, shape ``(..., T, p, s + 1)`` (time axis before the output axis).

        Parameters
        ----------
        y : array_like, shape (..., T, p)
            Measurements (leading axes: runs).
        h : float
            Sample interval.

        Returns
        -------
        numpy.ndarray
        """
        ys = np.asarray(y, dtype=float)
        if ys.ndim < 2:
            raise DimensionError(f"y: expected shape (..., T, p), got {ys.shape}")
        out = np.empty((*ys.shape, self.order + 1))
        q = self.init(ys[..., 0, :])
        for k in range(ys.shape[-2]):
            out[..., k, :, :] = q
            q = self.step(q, ys[..., k, :], h)
        return out


def difference_derivative_bounds(
    y: ArrayLike,
    h: float,
    rate_radius: ArrayLike,
    accel_bound: ArrayLike,
    step_tolerance: float = 0.0,
) -> tuple[FloatArray, FloatArray]:
    r"""Provable bounds of :math:`\dot\psi(t_k)` from two consecutive samples (module docstring).

    The true sample interval :math:`h_k` may differ from the nominal ``h`` by ``step_tolerance``
    (floating-point time grids). With :math:`|\dot\delta| \le` ``rate_radius`` and
    :math:`|\ddot\psi| \le` ``accel_bound`` (= L):

    .. math:: \dot\psi(t_k) \in \frac{y_k - y_{k-1}}{h} \pm \Big(\bar{\dot\delta} + \frac{L(h + \tau)}{2}
              + \Big|\frac{y_k - y_{k-1}}{h}\Big|\frac{\tau}{h - \tau}\Big),

    widened outward for the rounding of the quotient. Row 0 is ``[-inf, inf]`` (no previous sample: no bound).

    Parameters
    ----------
    y : array_like, shape (..., T, p)
        Measurements.
    h : float
        Nominal sample interval.
    rate_radius : array_like, shape (p,)
        Bound of ``|dδ/dt|`` for each output.
    accel_bound : array_like, shape (p,)
        Bound ``L`` of ``|d²ψ/dt²|`` for each output.
    step_tolerance : float
        Bound ``τ`` of ``|h_k - h|``.

    Returns
    -------
    lower, upper : numpy.ndarray, shape (..., T, p)
    """
    ys = np.asarray(y, dtype=float)
    if ys.ndim < 2:
        raise DataError(f"y: expected shape (..., T, p), got {ys.shape}")
    if not (np.isfinite(h) and h > 0) or not (0 <= step_tolerance < h):
        raise BoundsError(
            f"h: expected a positive step larger than step_tolerance, got h={h!r}, tol={step_tolerance!r}"
        )
    p = ys.shape[-1]
    rate = as_vector("rate_radius", rate_radius, p)
    accel = as_vector("accel_bound", accel_bound, p)
    if np.any(rate < 0) or np.any(accel < 0):
        raise BoundsError("difference_derivative_bounds: expected nonnegative rate_radius and accel_bound")
    lower = np.full(ys.shape, -np.inf)
    upper = np.full(ys.shape, np.inf)
    lo, hi = difference_pair_bounds(ys[..., :-1, :], ys[..., 1:, :], h, rate, accel, step_tolerance)
    lower[..., 1:, :] = lo
    upper[..., 1:, :] = hi
    return lower, upper


def difference_pair_bounds(
    y_prev: FloatArray,
    y_now: FloatArray,
    h: float,
    rate: FloatArray,
    accel: FloatArray,
    step_tolerance: float,
) -> tuple[FloatArray, FloatArray]:
    """The bounds of :func:`difference_derivative_bounds` for one pair of samples (no validation).

    Parameters
    ----------
    y_prev, y_now : numpy.ndarray, shape (..., p)
        Consecutive measurements ``y_{k-1}``, ``y_k``.
    h : float
        Nominal sample interval.
    rate : numpy.ndarray, shape (p,)
        Bound of ``|dδ/dt|``.
    accel : numpy.ndarray, shape (p,)
        Bound ``L`` of ``|d²ψ/dt²|``.
    step_tolerance : float
        Bound of ``|h_k - h|``.

    Returns
    -------
    lower, upper : numpy.ndarray, shape (..., p)
    """
    centre = (y_now - y_prev) / h
    # the radius is a few rounded operations on nonnegative terms: rounded up like every design constant
    _, radius = inflate(0.0, rate + 0.5 * accel * (h + step_tolerance), floor=0.0)
    _, radius = inflate(0.0, radius + np.abs(centre) * (step_tolerance / (h - step_tolerance)), floor=0.0)
    # the centre's own rounding: a difference and a quotient, relative to the measurements' size
    fuzz_scale = np.abs(centre) + (np.abs(y_now) + np.abs(y_prev)) / h
    return inflate(centre - radius, centre + radius, margin=8 * _UNIT_ROUNDOFF, scale=fuzz_scale, floor=0.0)


def settling_time(t: ArrayLike, error: ArrayLike, bound: ArrayLike) -> float:
    """First time after which ``|error| <= bound`` holds at every later sample (all components, runs).

    Parameters
    ----------
    t : array_like, shape (T,)
        Times.
    error : array_like, shape (..., T, p)
        Estimation error (e.g. ``q1 - dψ/dt`` from a simulation).
    bound : array_like, shape (p,)
        Claimed bound.

    Returns
    -------
    float
        ``inf`` when the bound is violated at the last sample.
    """
    times = as_time("t", t)
    err = np.abs(np.asarray(error, dtype=float))
    bad = err > np.asarray(bound, dtype=float)
    bad_t = np.any(bad, axis=tuple(i for i in range(bad.ndim) if i != bad.ndim - 2))
    if not bad_t.any():
        return float(times[0])
    last = int(np.flatnonzero(bad_t)[-1])
    return float(times[last + 1]) if last + 1 < times.size else float("inf")
