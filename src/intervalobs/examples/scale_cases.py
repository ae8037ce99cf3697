r"""Test systems at scale and of other shapes: many states and outputs, zonotopic noise, short records.

Our own systems (chosen here, not from a paper), all in discrete time
:math:`x_{k+1} = Ax_k + Bu_k + Ew_k,\ y_k = Cx_k + Fv_k` with :math:`|w|, |v| \le 1` elementwise:

* :func:`tank_cascade` — ``n`` interconnected tanks (``n`` = 3 … 60): tank ``i`` drains into tank
  ``i + 1`` and exchanges water with its neighbours; the last tank drains out. The continuous model is
  sampled exactly (``A = e^{A_c h}``, ``h`` = 1 s), so ``A`` is dense, stable and slow (spectral radius
  about 0.97). ``p = round(0.7 n)`` level sensors (the unmeasured tanks spread evenly, the last one
  unmeasured), ``m = n // 2`` pumps feeding every other tank; for ``n = 30``: ``p = 21``, ``m = 15``.
  Box process noise (one channel per tank).
* :func:`vehicle` — 6 states: lateral offset, lateral speed, heading error, yaw rate, speed error and
  a first-order actuator state of a lane-keeping vehicle under a slow stabilising feedback (sampled
  exactly at 0.05 s); 4 outputs (offset, heading, yaw rate, speed), box noise.
* :func:`pedestrian` — 4 states (planar position and velocity, velocities slightly damped, positions
  leaking slowly to the tracking frame's origin; 0.1 s), 2 position outputs; the process noise is a
  zonotope of 10 generators (accelerations in 8 directions and two position jitters): ``E`` is 4×10.
* :func:`short_record` — a 2-state lightly damped oscillator with one output and a wide prior, for
  records of 20 samples (the first rows of a record matter).

Each returns a :class:`ScaleCase`: the model, its boxes, the sample times and the known input, and
:meth:`ScaleCase.simulate`, an independent truth from :func:`intervalobs.simulate.simulate` (i.i.d.
``"vertex"`` noise: every generator at ±1 at every step, so the process noise visits the zonotope's
vertices; ``"extreme"``: bang-bang switching).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import expm

from ..errors import DataError
from ..simulate import Simulation, simulate
from ..systems import Bounds, LTISystem

__all__ = ["TANK_SIZES", "ScaleCase", "cases", "pedestrian", "short_record", "tank_cascade", "vehicle"]

FloatArray = NDArray[np.float64]

TANK_SIZES = (3, 6, 12, 30, 60)
"""The numbers of tanks of the cost-versus-size table."""


@dataclass(frozen=True)
class ScaleCase:
    """A test system with its boxes, record grid and known input.

    Attributes
    ----------
    name : str
        Short label (``"tanks-30"``, ``"vehicle"``, …).
    system : LTISystem
        The discrete-time model.
    bounds : Bounds
        Boxes of ``x0``, ``w``, ``v``.
    t : numpy.ndarray, shape (T,)
        Sample times.
    u : numpy.ndarray, shape (T, m)
        Known input.
    """

    name: str
    system: LTISystem
    bounds: Bounds
    t: FloatArray
    u: FloatArray

    def simulate(self, seed: int = 0, noise: str = "vertex", runs: int | None = None) -> Simulation:
        """An admissible truth: noise at the generators' bounds, a vertex of the initial box.

        Parameters
        ----------
        seed : int
            Seed of the draw.
        noise : str
            A kind of :func:`intervalobs.simulate.noise_signal` (``"vertex"``: i.i.d. ±1 per generator and
            step; ``"extreme"``: bang-bang switching at random steps).
        runs : int, optional
            Number of Monte Carlo runs (leading axis).

        Returns
        -------
        Simulation
        """
        return simulate(self.system, self.bounds, self.t, u=self.u, noise=noise, seed=seed, runs=runs)


def _sampled(a_c: FloatArray, b_c: FloatArray, h: float) -> tuple[FloatArray, FloatArray]:
    """Exact zero-order-hold sampling ``(e^{A_c h}, ∫_0^h e^{A_c s} ds B_c)``."""
    n, m = b_c.shape
    aug = np.zeros((n + m, n + m))
    aug[:n, :n], aug[:n, n:] = a_c, b_c
    exact = expm(aug * h)
    return exact[:n, :n], exact[:n, n:]


def _unit_noise_case(
    name: str,
    system: LTISystem,
    x0: tuple[FloatArray, FloatArray],
    steps: int,
    known_input: Callable[[FloatArray], FloatArray],
) -> ScaleCase:
    """The case of ``system``: noise boxes ``|w|, |v| <= 1``, ``steps`` samples ``dt`` apart, ``u = known_input(t)``."""
    w, v = np.ones(system.nw), np.ones(system.p)
    t = float(system.dt or 0.0) * np.arange(steps, dtype=float)  # every case is in discrete time
    return ScaleCase(name, system, Bounds(x0=x0, w=(-w, w), v=(-v, v)), t, known_input(t))


def _staircase(t: FloatArray, m: int, period: float, low: float, high: float) -> FloatArray:
    """A known input: each channel a staircase of levels in ``[low, high]``, shifted per channel."""
    index = (np.asarray(t) // period).astype(int)[:, None] + 3 * np.arange(m)[None, :]
    levels = 0.5 + 0.5 * np.sin(1.7 * index + 0.4)
    return low + (high - low) * levels


def tank_cascade(n: int, steps: int = 200) -> ScaleCase:
    """``n`` interconnected tanks with ``round(0.7 n)`` level sensors and ``n // 2`` pumps.

    Parameters
    ----------
    n : int
        Number of tanks (at least 3).
    steps : int
        Record length (samples, 1 s apart).

    Returns
    -------
    ScaleCase
        The cascade under staircase pump rates in [0, 1].
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 3:
        raise DataError(f"n: expected an integer of at least 3 tanks, got {n!r}")
    i = np.arange(n)
    drain = 0.01 + 0.01 * (0.5 + 0.5 * np.sin(1.3 * i))  # 1/s into the next tank (out of the last)
    exchange = 0.1  # 1/s between neighbours, both ways
    a_c = np.diag(-drain - 0.005)  # and a small leak everywhere
    a_c[i[1:], i[:-1]] += drain[:-1]
    a_c[i[:-1], i[:-1]] -= exchange
    a_c[i[1:], i[1:]] -= exchange
    a_c[i[:-1], i[1:]] += exchange
    a_c[i[1:], i[:-1]] += exchange
    m = n // 2
    b_c = np.zeros((n, m))
    b_c[2 * np.arange(m), np.arange(m)] = 0.1
    a, b = _sampled(a_c, b_c, 1.0)
    unmeasured = int(n - round(0.7 * n))
    skip = (i + 1) * unmeasured // n > i * unmeasured // n  # evenly spread, the last tank included
    measured = i[~skip]
    c = np.zeros((measured.size, n))
    c[np.arange(measured.size), measured] = 1.0
    system = LTISystem(
        a,
        c,
        B=b,
        E=0.02 * np.eye(n),
        F=0.05 * np.eye(measured.size),
        dt=1.0,
        state_names=[f"h{j + 1}" for j in i],
        output_names=[f"h{j + 1}_meas" for j in measured],
        input_names=[f"pump{j + 1}" for j in range(m)],
    )
    levels = (np.full(n, 4.0), np.full(n, 6.0))
    return _unit_noise_case(f"tanks-{n}", system, levels, steps, lambda t: _staircase(t, m, 25.0, 0.0, 1.0))


def vehicle(steps: int = 200) -> ScaleCase:
    """Lane keeping: 6 states, 4 outputs, box noise, sampled at 0.05 s.

    Parameters
    ----------
    steps : int
        Record length (samples 0.05 s apart; 200 make 10 s).

    Returns
    -------
    ScaleCase
        The vehicle under staircase steering and throttle commands of ±0.05.
    """
    # states: lateral offset (m), lateral speed (m/s), heading error (rad), yaw rate (rad/s),
    # speed error (m/s), steering actuator (rad); inputs: steering command, throttle.
    a_c = np.array(
        [
            [0.0, 1.0, 0.0, 0.0, 0.0, 0.0],
            [-0.4, -3.0, 15.0, -0.6, 0.0, 4.0],
            [0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
            [-0.05, 0.2, -2.0, -3.5, 0.0, 6.0],
            [0.0, 0.0, 0.0, 0.0, -0.15, 0.0],
            [-0.02, -0.05, -0.3, -0.2, 0.0, -5.0],
        ]
    )
    b_c = np.array([[0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [0.0, 1.0], [5.0, 0.0]])
    a, b = _sampled(a_c, b_c, 0.05)
    c = np.zeros((4, 6))
    c[[0, 1, 2, 3], [0, 2, 3, 4]] = 1.0
    system = LTISystem(
        a,
        c,
        B=b,
        E=np.diag([0.002, 0.02, 0.001, 0.01, 0.02, 0.002]),
        F=np.diag([0.05, 0.005, 0.01, 0.05]),
        dt=0.05,
        state_names=["offset", "lateral_speed", "heading", "yaw_rate", "speed_error", "steering"],
        output_names=["offset_meas", "heading_meas", "yaw_rate_meas", "speed_meas"],
        input_names=["steering_cmd", "throttle"],
    )
    x0 = np.array([0.5, 0.3, 0.05, 0.05, 1.0, 0.02])
    return _unit_noise_case("vehicle", system, (-x0, x0), steps, lambda t: _staircase(t, 2, 1.0, -0.05, 0.05))


def pedestrian(steps: int = 200) -> ScaleCase:
    """Planar walker: 4 states, 2 outputs, process noise a zonotope of 10 generators (``E`` is 4×10).

    Parameters
    ----------
    steps : int
        Record length (samples 0.1 s apart; 200 make 20 s).

    Returns
    -------
    ScaleCase
        The walker, without known input (``m = 0``).
    """
    h = 0.1
    a = np.array(
        [[0.999, 0.0, h, 0.0], [0.0, 0.999, 0.0, h], [0.0, 0.0, 0.98, 0.0], [0.0, 0.0, 0.0, 0.98]]
    )  # positions (m) leak slowly to the tracking frame's origin; velocities (m/s) are damped
    angles = 2 * np.pi * np.arange(8) / 8 + 0.2
    accel = 0.3 * np.vstack(
        [h * h / 2 * np.cos(angles), h * h / 2 * np.sin(angles), h * np.cos(angles), h * np.sin(angles)]
    )
    jitter = 0.01 * np.array([[1.0, 0.6], [0.3, -1.0], [0.0, 0.0], [0.0, 0.0]])
    system = LTISystem(
        a,
        np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]]),
        E=np.hstack([accel, jitter]),
        F=0.05 * np.eye(2),
        dt=h,
        state_names=["px", "py", "vx", "vy"],
        output_names=["px_meas", "py_meas"],
    )
    x0 = np.array([1.0, 1.0, 1.5, 1.5])
    return _unit_noise_case("pedestrian", system, (-x0, x0), steps, lambda t: np.zeros((t.size, 0)))


def short_record(steps: int = 20) -> ScaleCase:
    """A lightly damped oscillator (2 states, 1 output) with a wide prior, for 20-sample records.

    Parameters
    ----------
    steps : int
        Record length (samples 1 s apart); the case is about the first 20.

    Returns
    -------
    ScaleCase
        The oscillator driven by the known input ``sin(t/2)``.
    """
    angle = 0.3
    a = 0.97 * np.array([[np.cos(angle), np.sin(angle)], [-np.sin(angle), np.cos(angle)]])
    system = LTISystem(a, np.array([[1.0, 0.0]]), B=np.array([[0.0], [0.1]]), E=0.05 * np.eye(2), F=[[0.1]], dt=1.0)
    prior = 5.0 * np.ones(2)
    return _unit_noise_case("short-record", system, (-prior, prior), steps, lambda t: np.sin(0.5 * t)[:, None])


def cases() -> dict[str, ScaleCase]:
    """Every case: the tank cascades of :data:`TANK_SIZES`, the vehicle, the pedestrian, the short record.

    Returns
    -------
    dict of str to ScaleCase
    """
    every = [tank_cascade(n) for n in TANK_SIZES] + [vehicle(), pedestrian(), short_record()]
    return {case.name: case for case in every}
