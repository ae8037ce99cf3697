r"""The aircraft UIO paper, §5: 5th-order lateral-axis model of a fixed-wing aircraft with two unknown inputs.

Data as printed (A, D, C, x0, noise bounds 1e-2, ξ = (cos t, sin t), HOSM s = 1, λ = 100, µ1 = 1.1,
initial box ±1, Te = 1e-4 s) and the paper's printed design (E, P, K — printed transposed — and T),
kept for comparison; several printed entries are wrong (docs/paper-notes.md).

The truth is computed *exactly* (closed form): every input is a sum of sinusoids (or constants), so
:math:`x(t) = e^{At}(x_0 - x_p(0)) + x_p(t)` with the particular solution
:math:`x_p(t) = \operatorname{Re}\sum_j (i\nu_j I - A)^{-1} b_j e^{i\nu_j t}` — as fine as it gets.

Admissible noise must be *smooth* (the paper assumes :math:`|\dot\delta| \le \bar{\dot\delta}` and a
differentiable output). Worst-case admissible kinds (documented choices, bounds as in the paper):

* measurement noise δ: ``"sine"`` — full amplitude 1e-2 at the largest admissible frequency
  :math:`\bar{\dot\delta}/\bar\delta = 1` rad/s, random phases; ``"plateau"`` — sits at ±1e-2 for random
  dwell times and moves between the bounds at the largest admissible rate 1e-2/s (bang-bang with the
  rate limit the assumption imposes);
* process noise ω (enters the dynamics): ``"sine"`` — full amplitude 1e-2, 1 rad/s, random phases;
  ``"vertex"`` — a constant vertex of the box (random signs).

Known control inputs (not in the paper, whose inputs are all unknown): the paper's ``D`` is the
control matrix of Edwards & Spurgeon's model, column 1 the rudder, column 2 the aileron (our reading of
its rows: yaw rate and roll rate). With ``control=...`` the surfaces get known commands
:func:`control_input` through ``B_CONTROL = D`` on top of the unknown inputs ξ (actuator faults or
disturbances in the same channels): ``ẋ = Ax + Bu + Dξ + ω``. ``"held"``: the command sampled and held
between samples (exact zero-order-hold response); ``"continuous"``: the command itself, with its steps
*inside* sampling steps (exact closed form), for which the observer is given per-step boxes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.signal import lfilter

from ..errors import DimensionError
from ..systems.bounds import Bounds
from ..systems.lti import LTISystem

__all__ = [
    "B_CONTROL",
    "DELTA_BAR",
    "DELTA_DOT_BAR",
    "HOSM_LAMBDA",
    "MU1",
    "OMEGA_BAR",
    "OUTPUT_ACCEL",
    "PAPER",
    "TE",
    "X0",
    "A",
    "AircraftRecord",
    "C",
    "D",
    "aircraft_bounds",
    "aircraft_system",
    "control_box",
    "control_input",
    "simulate_aircraft",
    "unknown_input",
]

FloatArray = NDArray[np.float64]

A = np.array(
    [
        [0.0, 0.0, 1.0, 0.0, 0.0],
        [0.0, -0.154, -0.0042, 1.54, 0.0],
        [0.0, 0.249, -1.0, -5.2, 0.0],
        [0.0386, -0.996, -0.0003, -0.117, 0.0],
        [0.0, 0.5, 0.0, 0.0, -0.5],
    ]
)
D = np.array([[0.0, 0.0], [-0.744, -0.032], [0.337, -1.12], [0.02, 0.0], [0.0, 0.0]])
C = np.array([[0.0, 1, 0, 0, -1], [0, 0, 1, 0, 0], [0, 0, 0, 1, 0], [1, 0, 0, 0, 0]])
X0 = np.array([0.342, 0.32, 0.0178, -0.287, -0.9497])
DELTA_BAR = 1e-2
DELTA_DOT_BAR = 1e-2
OMEGA_BAR = 1e-2
OMEGA_DOT_BAR = 1e-2
TE = 1e-4
HOSM_LAMBDA = 100.0
MU1 = 1.1
OUTPUT_ACCEL = HOSM_LAMBDA / 1.1
"""Bound L of ``|d²ψ/dt²|`` implied by the paper's HOSM gain (Levant's rule λ_s = 1.1 L); checked on the truth."""

PAPER = {
    "E": [
        [0, 0, 0, 0],
        [9.993e-1, -2.011e-2, 2.652e-2, 0],
        [-2.011e-5, -1, -7.577e-4, 0],
        [2.652e-2, -7.577e-4, -7.044e-4, 0],
        [0, 0, 0, 0],
    ],
    "P": [
        [1, 0, 0, 0, 0],
        [0, 7.038e-4, 2.011e-5, 2.652e-2, 9.993e-1],
        [0, -2.011e-5, 5.745e-7, 7.577e-4, 2.011e-5],
        [0, 2.652e-2, -7.577e-4, 9.993e-1, -2.652e-2],
        [0, 0, 0, 0, 1],
    ],
    # printed as a 4×5 array: K is its transpose
    "K_printed": [
        [-6.30e-1, 3.23, -6.42e-4, -8.46e-1, -6.86e-1],
        [1, 6.37e-3, 6, 2.08e-4, 6.29e-3],
        [-1.70e-1, -8.40, -8.41e-5, 6.11, -8.29],
        [3.88, 2.66, 6.33e-4, -8.35e-1, 1.40],
    ],
    "T": [
        [4.02e-1, 1.35, 4.18e-3, -5.51, -1.42],
        [-7.90e-1, 5.07e-1, 8.13e-5, -1.07e-1, -5.38e-1],
        [-1.97e-1, -1.24, -8.24e-4, 1.09, 1.45],
        [1.18, 2.06, -3.56e-3, 4.70, -8.73e-1],
        [0, 0, 1, 7.58e-4, 0],
    ],
    "poles": [-5, -6, -4, -3, -2, -1],
    "mu1": MU1,
    "hosm_lambda": HOSM_LAMBDA,
    "Te": TE,
    "claimed_derivative_error": MU1 * np.sqrt(DELTA_BAR),
}
"""The paper's printed design numbers (§5.1)."""


B_CONTROL = D.copy()
"""Known control inputs (rudder, aileron): the control matrix of Edwards & Spurgeon's model (= the paper's D)."""
RUDDER_STEPS = ((2.00005, 0.1), (6.00003, -0.15))
"""(time [s], size [rad]) of the rudder steps: both fall inside a sampling step of 1e-4 s."""
AILERON_AMPLITUDE, AILERON_FREQUENCY = 0.2, 0.8


def aircraft_system(known_inputs: bool = False) -> LTISystem:
    """The model of the aircraft UIO paper, §5.1: ``ẋ = Ax + Bu + Dξ + ω``, ``y = Cx + δ`` (D is separate).

    Parameters
    ----------
    known_inputs : bool
        ``B = B_CONTROL`` (rudder, aileron) when True; the paper's ``B = 0`` otherwise.

    Returns
    -------
    LTISystem
    """
    return LTISystem(A, C, B=B_CONTROL) if known_inputs else LTISystem(A, C)


def control_input(t: ArrayLike) -> FloatArray:
    """The commands: rudder steps :data:`RUDDER_STEPS`, aileron ``0.2 sin(0.8 t)`` [rad], shape (T, 2).

    Parameters
    ----------
    t : array_like, shape (T,)

    Returns
    -------
    numpy.ndarray
    """
    tt = np.asarray(t, dtype=float)
    rudder = sum((size * (tt >= when) for when, size in RUDDER_STEPS), np.zeros_like(tt))
    return np.stack([rudder, AILERON_AMPLITUDE * np.sin(AILERON_FREQUENCY * tt)], axis=-1)


def control_box(t: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Boxes of the continuous commands over each step ``[t_k, t_{k+1}]`` (last row: the last sample).

    The rudder is exact (the step's values at both ends and any step inside); the aileron sine is
    bounded by its values at the ends widened by ``|u̇| h / 2`` (``|u̇| <= 0.2·0.8``), a sound bound of
    a function with that Lipschitz constant between two samples.

    Parameters
    ----------
    t : array_like, shape (T,)

    Returns
    -------
    lower, upper : numpy.ndarray, shape (T, 2)
    """
    tt = np.asarray(t, dtype=float)
    u = control_input(tt)
    nxt = np.vstack([u[1:], u[-1:]])
    lo, hi = np.minimum(u, nxt), np.maximum(u, nxt)
    step = np.append(np.diff(tt), 0.0)
    slack = AILERON_AMPLITUDE * AILERON_FREQUENCY * step / 2
    lo[:, 1] -= slack
    hi[:, 1] += slack
    return lo, hi


def aircraft_bounds() -> Bounds:
    """Initial box ±1 and the noise boxes ±1e-2 of the aircraft UIO paper, §5.1.

    Returns
    -------
    Bounds
    """
    return Bounds(
        x0=(-np.ones(5), np.ones(5)),
        w=(-OMEGA_BAR * np.ones(5), OMEGA_BAR * np.ones(5)),
        v=(-DELTA_BAR * np.ones(4), DELTA_BAR * np.ones(4)),
    )


def unknown_input(t: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """ξ(t) = (cos t, sin t) and its derivative, shape (T, 2) each.

    Parameters
    ----------
    t : array_like, shape (T,)

    Returns
    -------
    xi, xi_dot : numpy.ndarray
    """
    tt = np.asarray(t, dtype=float)
    return np.stack([np.cos(tt), np.sin(tt)], axis=-1), np.stack([-np.sin(tt), np.cos(tt)], axis=-1)


@dataclass(frozen=True)
class AircraftRecord:
    """A simulated record (leading run axis when ``runs`` is given).

    Attributes
    ----------
    t : (T,)
    x : (..., T, 5) true state
    y : (..., T, 4) measurements
    xi : (T, 2) unknown input
    psi, psi_dot : (..., T, 4) noise-free output and its derivative (right limit)
    psi_ddot : (..., T, 4) ``d/dt (dψ/dt - CBu)`` (``d²ψ/dt²`` without inputs), larger of both limits
    delta : (..., T, 4) measurement noise
    u : (T, 2) known input at the samples (zeros without ``control``)
    """

    t: FloatArray
    x: FloatArray
    y: FloatArray
    xi: FloatArray
    psi: FloatArray
    psi_dot: FloatArray
    psi_ddot: FloatArray
    delta: FloatArray
    u: FloatArray


def _rmul(x: FloatArray, m: FloatArray) -> FloatArray:
    """``x @ m.T`` by einsum (no BLAS threads on long records)."""
    return np.asarray(np.einsum("...j,ij->...i", x, m))


def _plateau(t: FloatArray, amplitude: float, rate: float, rng: np.random.Generator, k: int) -> FloatArray:
    """Rate-limited bang-bang: dwell at ±amplitude, ramps at the largest admissible rate."""
    out = np.empty((t.size, k))
    ramp = 2 * amplitude / rate
    for j in range(k):
        level = rng.choice([-1.0, 1.0])
        knots_t = [float(t[0]) - rng.uniform(0, ramp)]
        knots_v = [level * amplitude]
        while knots_t[-1] < t[-1]:
            dwell = rng.exponential(1.0)
            knots_t.append(knots_t[-1] + dwell)
            knots_v.append(level * amplitude)
            level = -level
            knots_t.append(knots_t[-1] + ramp)
            knots_v.append(level * amplitude)
        out[:, j] = np.interp(t, knots_t, knots_v)
    return out


def simulate_aircraft(
    t: ArrayLike,
    seed: int = 0,
    runs: int | None = None,
    delta_kind: str = "sine",
    omega_kind: str = "sine",
    x0: ArrayLike | None = None,
    control: str | None = None,
) -> AircraftRecord:
    """Exact truth of the aircraft model with smooth worst-case admissible noise (module docstring).

    Parameters
    ----------
    t : array_like, shape (T,)
        Sample times.
    seed : int
        Seed of the noise phases/levels.
    runs : int, optional
        Number of Monte Carlo runs (adds a leading axis).
    delta_kind : {"sine", "plateau"}
        Measurement-noise kind.
    omega_kind : {"sine", "vertex"}
        Process-noise kind.
    x0 : array_like, shape (5,), optional
        Initial state (default: the paper's).
    control : {None, "held", "continuous"}
        Known commands :func:`control_input` through ``B_CONTROL`` (module docstring); None: no input.

    Returns
    -------
    AircraftRecord
    """
    tt = np.asarray(t, dtype=float)
    if delta_kind not in ("sine", "plateau"):
        raise DimensionError(f"delta_kind: expected 'sine' or 'plateau', got {delta_kind!r}")
    if omega_kind not in ("sine", "vertex"):
        raise DimensionError(f"omega_kind: expected 'sine' or 'vertex', got {omega_kind!r}")
    if control not in (None, "held", "continuous"):
        raise DimensionError(f"control: expected None, 'held' or 'continuous', got {control!r}")
    rng = np.random.default_rng(seed)
    m = 1 if runs is None else int(runs)
    n, p = 5, 4
    start = X0 if x0 is None else np.asarray(x0, dtype=float)
    nu_delta = DELTA_DOT_BAR / DELTA_BAR
    nu_omega = OMEGA_DOT_BAR / OMEGA_BAR
    # complex amplitudes per frequency: input Re(b e^{i ν t})
    xi_amp = D @ np.array([1.0, -1j])  # D (cos t, sin t)
    xs, ys, psis, dpsis, ddpsis, deltas = [], [], [], [], [], []
    vals, vecs = np.linalg.eig(A)
    vinv = np.linalg.inv(vecs)
    x_u, u_right, u_left, u_terms = _control_response(tt, control, vals, vecs, vinv)
    u_direct = u_right.copy()  # the part of u whose response x_u is not in the closed form below
    if control == "continuous":
        u_direct[:, 1] = 0.0
    for _ in range(m):
        omega_terms: list[tuple[float, NDArray[np.complex128]]] = []
        if omega_kind == "sine":
            omega_terms.append((nu_omega, OMEGA_BAR * np.exp(1j * rng.uniform(0, 2 * np.pi, n))))
        else:
            omega_terms.append((0.0, (OMEGA_BAR * rng.choice([-1.0, 1.0], n)).astype(np.complex128)))
        terms = [(1.0, xi_amp.astype(complex)), *omega_terms, *u_terms]
        xp = np.zeros((tt.size, n))
        xp_dot = np.zeros((tt.size, n))
        xp0 = np.zeros(n)
        for nu, b in terms:
            amp = np.linalg.solve(1j * nu * np.eye(n) - A, b)
            rot = np.exp(1j * nu * tt)[:, None]
            xp += np.real(amp * rot)
            xp_dot += np.real(1j * nu * amp * rot)
            xp0 += np.real(amp * np.exp(1j * nu * tt[0]))
        omega_dot = np.zeros((tt.size, n))
        for nu, b in omega_terms:
            omega_dot += np.real(1j * nu * b * np.exp(1j * nu * tt)[:, None])
        coef = vinv @ (start - xp0)
        modes = np.exp(np.outer(tt - tt[0], vals))
        x = np.real(np.einsum("tj,ij->ti", modes * coef, vecs)) + xp + x_u
        x[0] = start  # exact at t_0 (the closed form reproduces it only to rounding)
        x_dot = np.real(np.einsum("tj,ij->ti", modes * (vals * coef), vecs)) + xp_dot
        x_dot = x_dot + _rmul(x_u, A) + _rmul(u_direct, B_CONTROL)
        _, xi_dot = unknown_input(tt)
        # d/dt (dψ/dt - CBu) = C(A ẋ + D ξ̇ + ω̇), at both one-sided limits of ẋ
        accel = _rmul(x_dot, A) + _rmul(xi_dot, D) + omega_dot
        accel_left = accel + _rmul(_rmul(u_left - u_right, B_CONTROL), A)
        g_dot, g_dot_left = _rmul(accel, C), _rmul(accel_left, C)
        g_dot = np.where(np.abs(g_dot_left) > np.abs(g_dot), g_dot_left, g_dot)
        psi = _rmul(x, C)
        if delta_kind == "sine":
            delta = DELTA_BAR * np.sin(nu_delta * tt[:, None] + rng.uniform(0, 2 * np.pi, p))
        else:
            delta = _plateau(tt, DELTA_BAR, DELTA_DOT_BAR, rng, p)
        xs.append(x)
        psis.append(psi)
        dpsis.append(_rmul(x_dot, C))
        ddpsis.append(g_dot)
        deltas.append(delta)
        ys.append(psi + delta)
    stack = (lambda v: np.stack(v)) if runs is not None else (lambda v: v[0])
    xi, _ = unknown_input(tt)
    return AircraftRecord(
        tt, stack(xs), stack(ys), xi, stack(psis), stack(dpsis), stack(ddpsis), stack(deltas), u_right
    )


def _control_response(
    t: FloatArray, control: str | None, vals: NDArray[np.complex128], vecs: NDArray[np.complex128], vinv: NDArray
) -> tuple[FloatArray, FloatArray, FloatArray, list[tuple[float, NDArray[np.complex128]]]]:
    """Zero-state response to the commands, the input at the samples (right and left limits), sine terms.

    ``"held"``: exact zero-order-hold recursion of the modes, ``z_{k+1} = e^{λh} z_k + (e^{λh} - 1)/λ ·
    V⁻¹B u_k``. ``"continuous"``: the steps in closed form, ``A⁻¹(e^{A(t-τ)} - I) b`` for ``t >= τ``; the
    aileron sine is returned as a term for the caller's closed form.
    """
    n = A.shape[0]
    zero = np.zeros((t.size, n))
    if control is None:
        u0 = np.zeros((t.size, 2))
        return zero, u0, u0, []
    if control == "held":
        h = float(t[1] - t[0])
        if np.max(np.abs(np.diff(t) - h)) > 1e-9 * h:
            raise DimensionError("t: control='held' expects a uniform time grid")
        u = control_input(t)
        drive = _rmul(u, B_CONTROL) @ vinv.T
        decay = np.exp(vals * h)
        gain = (decay - 1) / vals
        modes = np.zeros((t.size, n), dtype=complex)
        for i in range(n):
            modes[1:, i] = lfilter([gain[i]], [1.0, -decay[i]], drive[:-1, i])
        u_left = np.vstack([u[:1], u[:-1]])
        return np.real(modes @ vecs.T), u, u_left, []
    x_u = zero.copy()
    for when, size in RUDDER_STEPS:
        after = t >= when
        modes = np.exp(np.outer(t[after] - when, vals))
        b = vinv @ (B_CONTROL[:, 0] * size)
        x_u[after] += np.real(((modes - 1) / vals * b) @ vecs.T)
    sine = (AILERON_FREQUENCY, -1j * AILERON_AMPLITUDE * B_CONTROL[:, 1].astype(complex))
    u = control_input(t)
    return x_u, u, u, [sine]
