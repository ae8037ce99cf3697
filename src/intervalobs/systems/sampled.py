r"""Continuous-time systems with a nonlinear term and sampled outputs (seed 004, eq. (8)).

.. math::

    \dot x(t) = Ax(t) + \varphi(t, u(t), x(t)) + d(t), \qquad y(t_k) = Cx(t_k) + V(t_k),

with :math:`d(t)` any measurable signal in a box (Assumption 3.1), :math:`|V| \le \delta`
(Assumption 3.2), :math:`x(0)` in a box (Assumption 3.3) and :math:`u` known (Assumption 3.4).
The boxes are given as :class:`~intervalobs.systems.lti.Bounds` with ``w`` the box of :math:`d`
and ``v`` the box of :math:`V`.

A sound observer needs an *enclosure* of :math:`\varphi` over boxes, not only :math:`\varphi`
itself: ``phi_bounds(t0, t1, u_lower, u_upper, x_lower, x_upper)`` must return bounds of
:math:`\varphi(t, u, x)` valid for every :math:`t \in [t_0, t_1]` and every point of the boxes (e.g.
the range :math:`e^{-|x|} \in [e^{-\max|x|}, e^{-\operatorname{mig}|x|}] \subset (0, 1]` for the
paper's example). The constructor spot-checks it on random points and refuses an enclosure that
misses one.

:func:`simulate_sampled` produces the truth for tests and reproductions: classical Runge–Kutta on a
grid ``substeps`` times finer than the observer's, the disturbance switching on that finer grid
(inside the observer's steps), the known input evaluated in continuous time when given as a
function, and measurements only every ``sample_every`` observer steps (NaN rows in between).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import AssumptionError, BoundsError, DataError, DimensionError
from ..validation import as_matrix, as_signal, as_time
from .bounds import Bounds

__all__ = ["PhiBounds", "PhiFunction", "SampledSimulation", "SampledSystem", "simulate_sampled"]

FloatArray = NDArray[np.float64]
PhiFunction = Callable[[float, FloatArray, FloatArray], FloatArray]
PhiBounds = Callable[[float, float, FloatArray, FloatArray, FloatArray, FloatArray], tuple[FloatArray, FloatArray]]

_SPOT_CHECKS = 256


class SampledSystem:
    """The continuous-discrete model of seed 004, eq. (8).

    Parameters
    ----------
    A : array_like, shape (n, n)
        Linear part.
    C : array_like, shape (p, n)
        Output matrix.
    phi : callable, optional
        ``phi(t, u, x)`` with ``u`` of shape (..., m) and ``x`` of shape (..., n), returning (..., n).
        Default: no nonlinear term.
    phi_bounds : callable, optional
        ``phi_bounds(t0, t1, u_lower, u_upper, x_lower, x_upper) -> (lower, upper)``: an enclosure of
        ``phi`` over ``[t0, t1]`` and the boxes (arrays (..., m) and (..., n)). Required with ``phi``.
    m : int
        Number of known inputs.
    sample_period : float
        Time between two output samples :math:`t_{k+1} - t_k`.

    Attributes
    ----------
    n, m, p, nw, nv : int
        States, known inputs, outputs, disturbance channels (= n) and noise channels (= p).
    """

    def __init__(
        self,
        A: ArrayLike,
        C: ArrayLike,
        phi: PhiFunction | None = None,
        phi_bounds: PhiBounds | None = None,
        m: int = 0,
        sample_period: float = 1.0,
    ) -> None:
        self.A = as_matrix("A", A)
        n = self.A.shape[0]
        if self.A.shape != (n, n):
            raise DimensionError(f"A: expected a square matrix, got shape {self.A.shape}")
        self.C = as_matrix("C", C, (None, n))
        if not (isinstance(m, int | np.integer) and m >= 0):
            raise DimensionError(f"m: expected a nonnegative integer, got {m!r}")
        self._m = int(m)
        if not (np.isfinite(sample_period) and sample_period > 0):
            raise BoundsError(f"sample_period: expected a positive number, got {sample_period!r}")
        self.sample_period = float(sample_period)
        if (phi is None) != (phi_bounds is None):
            raise AssumptionError(
                "phi_bounds: a sound observer needs an enclosure of phi over boxes; give both phi and phi_bounds "
                "or neither"
            )
        self.phi = phi
        self.phi_bounds = phi_bounds
        if phi is not None:
            self._spot_check()

    @property
    def n(self) -> int:
        """Number of states."""
        return int(self.A.shape[0])

    @property
    def m(self) -> int:
        """Number of known inputs."""
        return self._m

    @property
    def p(self) -> int:
        """Number of outputs."""
        return int(self.C.shape[0])

    @property
    def nw(self) -> int:
        """Number of disturbance channels (``d`` enters every state)."""
        return self.n

    @property
    def nv(self) -> int:
        """Number of measurement-noise channels (one per output)."""
        return self.p

    def nonlinearity(self, t: float, u: FloatArray, x: FloatArray) -> FloatArray:
        """``phi(t, u, x)``, zeros when the model has no nonlinear term.

        Parameters
        ----------
        t : float
            Time.
        u : numpy.ndarray, shape (..., m)
            Known input.
        x : numpy.ndarray, shape (..., n)
            State.

        Returns
        -------
        numpy.ndarray, shape (..., n)
        """
        if self.phi is None:
            return np.zeros_like(x)
        return np.asarray(self.phi(t, u, x), dtype=float)

    def nonlinearity_bounds(
        self, t0: float, t1: float, u_lower: FloatArray, u_upper: FloatArray, x_lower: FloatArray, x_upper: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """Enclosure of ``phi`` over ``[t0, t1]`` and the boxes (zeros without a nonlinear term).

        Parameters
        ----------
        t0, t1 : float
            Time interval.
        u_lower, u_upper : numpy.ndarray, shape (..., m)
            Box of the known input.
        x_lower, x_upper : numpy.ndarray, shape (..., n)
            Box of the state.

        Returns
        -------
        lower, upper : numpy.ndarray, shape (..., n)
        """
        if self.phi_bounds is None:
            zero = np.zeros_like(x_lower)
            return zero, zero
        lo, hi = self.phi_bounds(t0, t1, u_lower, u_upper, x_lower, x_upper)
        return np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)

    def _spot_check(self) -> None:
        """Evaluate ``phi`` at random points of random boxes and check ``phi_bounds`` encloses them."""
        assert self.phi is not None and self.phi_bounds is not None
        rng = np.random.default_rng(12345)
        n, m = self.n, self.m
        centre = rng.normal(scale=3.0, size=(_SPOT_CHECKS, n))
        radius = rng.uniform(0.0, 2.0, size=(_SPOT_CHECKS, n))
        u_c = rng.normal(scale=3.0, size=(_SPOT_CHECKS, m))
        u_r = rng.uniform(0.0, 1.0, size=(_SPOT_CHECKS, m))
        lo, hi = self.phi_bounds(0.0, 0.1, u_c - u_r, u_c + u_r, centre - radius, centre + radius)
        lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        if lo.shape != (_SPOT_CHECKS, n) or hi.shape != (_SPOT_CHECKS, n):
            raise DimensionError(
                f"phi_bounds: expected arrays of shape (..., {n}) for boxes of shape (..., {n}), got {lo.shape}"
            )
        for s in (-1.0, 1.0, 0.3):
            x = centre + s * radius * rng.choice([-1.0, 1.0], size=radius.shape)
            u = u_c + s * u_r
            value = np.asarray(self.phi(0.05, u, x), dtype=float)
            if value.shape != x.shape:
                raise DimensionError(f"phi: expected an array of shape (..., {n}), got {value.shape}")
            slack = 1e-9 * (1.0 + np.abs(value))
            if np.any(value < lo - slack) or np.any(value > hi + slack):
                raise AssumptionError("phi_bounds: does not enclose phi at a random point of a random box (spot check)")

    def __repr__(self) -> str:
        return f"SampledSystem(n={self.n}, m={self.m}, p={self.p}, sample_period={self.sample_period:g})"


@dataclass(frozen=True)
class SampledSimulation:
    """A simulated record on the observer's grid (a leading run axis when ``runs`` was given).

    Attributes
    ----------
    t : numpy.ndarray, shape (T,)
        Observer grid.
    x : numpy.ndarray, shape (..., T, n)
        True state on the grid.
    y : numpy.ndarray, shape (..., T, p)
        Measurements at the sample times, NaN at the other grid points.
    u : numpy.ndarray, shape (T, m)
        Known input on the grid.
    d : numpy.ndarray, shape (..., T * substeps, n)
        Disturbance on the fine grid (constant over each fine step).
    v : numpy.ndarray, shape (..., T, p)
        Measurement noise (used at the sample times only).
    sampled : numpy.ndarray of bool, shape (T,)
        Grid points carrying a measurement.
    """

    t: FloatArray
    x: FloatArray
    y: FloatArray
    u: FloatArray
    d: FloatArray
    v: FloatArray
    sampled: NDArray[np.bool_]


def simulate_sampled(
    system: SampledSystem,
    bounds: Bounds,
    t: ArrayLike,
    u: Callable[[float], ArrayLike] | ArrayLike | None = None,
    noise: str = "extreme",
    seed: int = 0,
    runs: int | None = None,
    substeps: int = 4,
) -> SampledSimulation:
    """Simulate eq. (8) with admissible disturbance, noise and initial state.

    Parameters
    ----------
    system : SampledSystem
        The model.
    bounds : Bounds
        Boxes of ``x0``, ``d`` (as ``w``) and ``V`` (as ``v``).
    t : array_like, shape (T,)
        Uniform observer grid; ``system.sample_period`` must be a multiple of its step.
    u : callable or array_like, optional
        ``u(t) -> (m,)`` evaluated in continuous time, or samples (T, m) held over each step.
    noise : str
        A kind of :func:`intervalobs.simulate.noise_signal` (``"extreme"``: bang-bang, switching on
        the fine grid, inside the observer's steps; the initial state at a random vertex).
    seed : int
        Random seed.
    runs : int, optional
        Number of Monte Carlo runs (leading axis).
    substeps : int
        Runge–Kutta steps (and disturbance switching opportunities) per observer step.

    Returns
    -------
    SampledSimulation
    """
    from ..simulate import _draw_box, noise_signal

    times = as_time("t", t)
    steps = times.size
    if steps < 2:
        raise DataError("t: expected at least two samples")
    h = float(times[1] - times[0])
    if np.max(np.abs(np.diff(times) - h)) > 1e-9 * h:
        raise DataError("t: expected a uniformly spaced grid")
    ratio = system.sample_period / h
    every = round(ratio)
    if every < 1 or abs(ratio - every) > 1e-6 * ratio:
        raise DataError(f"t: the sample period {system.sample_period:g} is not a multiple of the grid step {h:g}")
    if not (isinstance(substeps, int) and substeps >= 1):
        raise DimensionError(f"substeps: expected a positive integer, got {substeps!r}")
    full = bounds.resolve(system)
    rng = np.random.default_rng(seed)
    count = 1 if runs is None else int(runs)
    n, m = system.n, system.m
    if callable(u):
        u_of = u

        def u_at(tt: float, k: int) -> FloatArray:
            return np.asarray(u_of(tt), dtype=float).reshape(m)

        u_grid = np.array([u_at(float(tk), k) for k, tk in enumerate(times)]).reshape(steps, m)
    else:
        u_grid = np.zeros((steps, m)) if u is None else as_signal("u", u, steps, m)
        if u_grid.ndim != 2:
            raise DataError(f"u: expected shape ({steps}, {m}) shared by all runs, got {u_grid.shape}")
        held = u_grid

        def u_at(tt: float, k: int) -> FloatArray:
            return held[k]

    d = noise_signal(noise, full.w[0], full.w[1], steps * substeps, rng, count)
    v = noise_signal(noise, full.v[0], full.v[1], steps, rng, count)
    x0 = _draw_box(noise, *full.x0, rng, count)
    dt = h / substeps
    a_t = system.A.T

    def f(tt: float, uu: FloatArray, xx: FloatArray, dd: FloatArray) -> FloatArray:
        return np.asarray(xx @ a_t + system.nonlinearity(tt, uu, xx) + dd)

    x = np.empty((count, steps, n))
    state = np.array(x0, dtype=float)
    for k in range(steps):
        x[:, k] = state
        if k + 1 == steps:
            break
        tk = float(times[k])
        for j in range(substeps):
            t0 = tk + j * dt
            dd = d[:, k * substeps + j]
            u0, um, u1 = u_at(t0, k), u_at(t0 + dt / 2, k), u_at(t0 + dt, k)
            k1 = f(t0, u0, state, dd)
            k2 = f(t0 + dt / 2, um, state + dt / 2 * k1, dd)
            k3 = f(t0 + dt / 2, um, state + dt / 2 * k2, dd)
            k4 = f(t0 + dt, u1, state + dt * k3, dd)
            state = state + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    sampled = (np.arange(steps) % every) == 0
    y = x @ system.C.T + v
    y[:, ~sampled] = np.nan
    if runs is None:
        return SampledSimulation(times, x[0], y[0], u_grid, d[0], v[0], sampled)
    return SampledSimulation(times, x, y, u_grid, np.asarray(d), np.asarray(v), sampled)
