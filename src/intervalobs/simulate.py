"""Truth simulation with admissible noise: the reference every enclosure test is judged against.

Every truth simulator of the package lives here, written independently of the observers (no bound,
no sampled model, no inclusion function is used): :func:`simulate` for :class:`LTISystem`,
:func:`simulate_sampled` for the sampled-output :class:`SampledSystem` (the sampled-output high-gain paper) and
:func:`simulate_nonlinear` for the discrete-time :class:`NonlinearSystem` (Khajenejad & Yong). They share the
public helpers that draw admissible unknowns — :func:`noise_signal` (uniform, bang-bang ``"extreme"``
switching at random steps, i.i.d. ``"vertex"``, sinusoidal, constant), :func:`draw_box` (a point or a
random vertex of a box per run) — and :func:`runge_kutta_step`, the classical fourth-order step used
for nonlinear continuous-time truths (also by :mod:`intervalobs.examples.manipulator`).

Continuous-time LTI systems are simulated *exactly* for piecewise-constant noise: the noise ``w`` is held
over sub-steps of ``h / substeps`` (so it switches inside the observer's sampling intervals), the known
input ``u`` over whole sampling intervals (zero-order hold, as the observers assume), and each
sub-step uses the matrix exponential of the augmented system. Discrete-time systems are iterated.
Measurements are taken at the sample times with their own noise ``v``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import expm

from . import _tables
from .errors import DataError
from .systems.bounds import Bounds
from .systems.lti import LTISystem
from .systems.nonlinear import NonlinearSystem
from .systems.sampled import SampledSystem
from .validation import as_matrix, as_names, as_signal, as_time

__all__ = [
    "NOISE_KINDS",
    "NonlinearSimulation",
    "SampledSimulation",
    "Simulation",
    "draw_box",
    "noise_signal",
    "runge_kutta_step",
    "simulate",
    "simulate_nonlinear",
    "simulate_sampled",
]

FloatArray = NDArray[np.float64]
Rate = Callable[[float, FloatArray], FloatArray]

NOISE_KINDS = ("uniform", "extreme", "vertex", "sine", "constant")
"""Built-in noise kinds; ``"extreme"`` jumps between the two bounds at random times (bang-bang),
``"vertex"`` picks a bound independently at every step."""

_SWITCH_PROBABILITY = 0.1


@dataclass(frozen=True)
class Simulation:
    """A simulated record, time-first (a leading axis holds runs when ``runs`` was given).

    Parameters
    ----------
    t : numpy.ndarray, shape (T,)
        Sample times.
    x : numpy.ndarray, shape (..., T, n)
        True state at the sample times.
    y : numpy.ndarray, shape (..., T, p)
        Measurements.
    u : numpy.ndarray, shape (T, m)
        Known input.
    w : numpy.ndarray, shape (..., T * substeps, nw)
        Process noise (on the fine grid in continuous time).
    v : numpy.ndarray, shape (..., T, nv)
        Measurement noise.
    dA : numpy.ndarray, shape (..., n, n)
        The constant uncertainty of ``A`` drawn for each run.
    state_names, output_names, input_names : sequence of str, optional
        Names of the states, outputs and known inputs (default ``x1 …``, ``y1 …``, ``u1 …``;
        :func:`simulate` gives the model's names).
    dB : numpy.ndarray, shape (..., n, m), optional
        The constant uncertainty of ``B`` drawn for each run (zeros for a model without ``dB``; None when
        unknown, e.g. read from a table).
    """

    t: FloatArray
    x: FloatArray
    y: FloatArray
    u: FloatArray
    w: FloatArray
    v: FloatArray
    dA: FloatArray
    state_names: Sequence[str] = ()
    output_names: Sequence[str] = ()
    input_names: Sequence[str] = ()
    dB: FloatArray | None = None

    def __post_init__(self) -> None:
        for kind, signal, prefix in (("state", self.x, "x"), ("output", self.y, "y"), ("input", self.u, "u")):
            name = f"{kind}_names"
            object.__setattr__(self, name, as_names(name, getattr(self, name) or None, np.shape(signal)[-1], prefix))

    def to_pandas(self) -> Any:
        """The record as a pandas ``DataFrame`` (needs the ``data`` extra).

        Indexed by time ``t`` (by ``run`` and ``t`` for several runs), one column per state, output
        and known input, named by the names (the known input, shared by the runs, is repeated in
        each run). The noise, on its own finer grid in continuous time, is not part of the table; ``attrs``
        holds ``dA`` (``dB``) and the names. :meth:`from_pandas` reads it back.

        Returns
        -------
        pandas.DataFrame
        """
        return _tables.to_frame(self.t, self._columns(), self._attrs(), "Simulation.to_pandas")

    def to_xarray(self) -> Any:
        """The record as an xarray ``Dataset`` (needs the ``data`` extra).

        Variables ``x``, ``y``, ``u`` over ``t`` and the dimensions ``state``, ``output``, ``input``
        (``run`` first for several runs), with the names as coordinates; ``attrs`` holds ``dA`` (``dB``).

        Returns
        -------
        xarray.Dataset
        """
        u = np.broadcast_to(self.u, (*self.x.shape[:-1], self.u.shape[-1]))
        variables = {
            "x": (self.x, "state", tuple(self.state_names)),
            "y": (self.y, "output", tuple(self.output_names)),
            "u": (u, "input", tuple(self.input_names)),
        }
        return _tables.to_dataset(self.t, variables, self._uncertainty(), "Simulation.to_xarray")

    @classmethod
    def from_pandas(
        cls,
        frame: Any,
        state_names: Sequence[str] | None = None,
        output_names: Sequence[str] | None = None,
        input_names: Sequence[str] | None = None,
    ) -> Simulation:
        """Read a record from a ``DataFrame`` with one column per state, output and known input.

        Parameters
        ----------
        frame : pandas.DataFrame
            Indexed by time (or by run and time), e.g. as :meth:`to_pandas` writes it.
        state_names, output_names, input_names : sequence of str, optional
            The columns of each kind (default: the names in ``frame.attrs``; no inputs when absent).

        Returns
        -------
        Simulation
            The noise arrays ``w`` and ``v`` are empty (no columns); ``dA`` and ``dB`` come from ``attrs``
            (NaN, and None, when they are not there).
        """
        t, columns, attrs = _tables.from_frame(frame, "Simulation.from_pandas")
        chosen = {}
        for kind, given in (("state", state_names), ("output", output_names), ("input", input_names)):
            names = list(given if given is not None else attrs.get(f"{kind}_names", []))
            missing = [n for n in names if n not in columns]
            if missing or (kind != "input" and not names):
                raise DataError(f"{kind}_names: expected columns of frame, got {names}: missing {missing}")
            chosen[kind] = names
        lead = next(iter(columns.values())).shape
        x, y, u = (
            np.stack([columns[n] for n in chosen[kind]], axis=-1) if chosen[kind] else np.zeros((*lead, 0))
            for kind in ("state", "output", "input")
        )
        n = x.shape[-1]
        d_a = np.asarray(attrs.get("dA", np.full((*lead[:-1], n, n), np.nan)), dtype=float)
        d_b = None if "dB" not in attrs else np.asarray(attrs["dB"], dtype=float)
        empty = np.zeros((*lead, 0))
        return cls(
            t,
            x,
            y,
            u[0] if u.ndim == 3 else u,
            empty,
            empty,
            d_a,
            state_names=chosen["state"],
            output_names=chosen["output"],
            input_names=chosen["input"],
            dB=d_b,
        )

    def _columns(self) -> list[tuple[str, FloatArray]]:
        """Named (T,) or (M, T) columns: states, outputs, then known inputs (broadcast over runs)."""
        u = np.broadcast_to(self.u, (*self.x.shape[:-1], self.u.shape[-1]))
        columns: list[tuple[str, FloatArray]] = []
        for names, values in ((self.state_names, self.x), (self.output_names, self.y), (self.input_names, u)):
            columns += [(name, values[..., i]) for i, name in enumerate(names)]
        return columns

    def _attrs(self) -> dict[str, Any]:
        names = {f"{kind}_names": list(getattr(self, f"{kind}_names")) for kind in ("state", "output", "input")}
        return {**self._uncertainty(), **names}

    def _uncertainty(self) -> dict[str, Any]:
        """The drawn ``dA`` (and ``dB`` when known) as nested lists, for a table's ``attrs``."""
        return {"dA": self.dA.tolist(), **({} if self.dB is None else {"dB": self.dB.tolist()})}

    def __repr__(self) -> str:
        """Runs, samples, time span and the dimensions of x, y and u."""
        runs = f"runs={self.x.shape[0]}, " if self.x.ndim == 3 else ""
        span = f"[{self.t[0]:.4g}, {self.t[-1]:.4g}]" if self.t.size else "[]"
        return (
            f"Simulation({runs}samples={self.t.size}, t={span}, n={self.x.shape[-1]}, p={self.y.shape[-1]}, "
            f"m={self.u.shape[-1]})"
        )


def noise_signal(
    kind: str,
    lower: ArrayLike,
    upper: ArrayLike,
    steps: int,
    rng: np.random.Generator,
    runs: int | None = None,
) -> FloatArray:
    """A noise signal inside ``[lower, upper]``, shape ``(steps, k)`` or ``(runs, steps, k)``.

    Parameters
    ----------
    kind : str
        ``"uniform"`` (independent samples), ``"extreme"`` (each component at one of its bounds,
        switching with probability 0.1 per step), ``"vertex"`` (each component at a bound drawn
        independently at every step), ``"sine"`` (full-amplitude sinusoid of random period
        between 5 and 200 steps and random phase) or ``"constant"`` (a random constant).
    lower, upper : array_like, shape (k,)
        Bounds of each component.
    steps : int
        Number of samples.
    rng : numpy.random.Generator
        Random source.
    runs : int, optional
        Number of independent runs (leading axis).

    Returns
    -------
    numpy.ndarray
    """
    lo = np.asarray(lower, dtype=float)
    hi = np.asarray(upper, dtype=float)
    shape = (1 if runs is None else runs, steps, lo.size)
    if kind == "uniform":
        unit = rng.uniform(size=shape)
    elif kind == "extreme":
        first = rng.integers(0, 2, size=(shape[0], 1, shape[2]))
        flips = rng.uniform(size=(shape[0], steps - 1, shape[2])) < _SWITCH_PROBABILITY
        unit = (first + np.concatenate([np.zeros_like(first), np.cumsum(flips, axis=1)], axis=1)) % 2
    elif kind == "vertex":
        unit = rng.integers(0, 2, size=shape).astype(float)
    elif kind == "sine":
        period = rng.uniform(5, 200, size=(shape[0], 1, shape[2]))
        phase = rng.uniform(0, 2 * np.pi, size=(shape[0], 1, shape[2]))
        unit = 0.5 + 0.5 * np.sin(2 * np.pi * np.arange(steps)[None, :, None] / period + phase)
    elif kind == "constant":
        unit = np.broadcast_to(rng.uniform(size=(shape[0], 1, shape[2])), shape)
    else:
        raise DataError(f"noise: expected one of {NOISE_KINDS} or a dict of arrays, got {kind!r}")
    signal = lo + (hi - lo) * unit
    return signal[0] if runs is None else signal


def draw_box(kind: str, lower: ArrayLike, upper: ArrayLike, rng: np.random.Generator, runs: int) -> FloatArray:
    """One point of the box per run: a random vertex for ``"extreme"`` and ``"vertex"``, uniform otherwise.

    Parameters
    ----------
    kind : str
        The noise kind of the simulation (see :func:`noise_signal`).
    lower, upper : array_like
        Bounds of the box (any shape, e.g. a vector or a matrix).
    rng : numpy.random.Generator
        Random source.
    runs : int
        Number of points (leading axis).

    Returns
    -------
    numpy.ndarray, shape ``(runs,) + lower.shape``
    """
    lo = np.asarray(lower, dtype=float)
    hi = np.asarray(upper, dtype=float)
    size = (runs, *lo.shape)
    unit = rng.integers(0, 2, size=size) if kind in ("extreme", "vertex") else rng.uniform(size=size)
    return np.asarray(lo + (hi - lo) * unit)


def runge_kutta_step(rate: Rate, t: float, x: FloatArray, dt: float) -> FloatArray:
    r"""One classical fourth-order Runge–Kutta step of :math:`\dot x = \text{rate}(t, x)`.

    Parameters
    ----------
    rate : callable
        ``rate(t, x)`` for states ``x`` of shape (..., n) (runs on leading axes); everything it holds
        constant over the step (an input, a disturbance) it closes over.
    t : float
        Start of the step.
    x : numpy.ndarray, shape (..., n)
        State at ``t``.
    dt : float
        Step length.

    Returns
    -------
    numpy.ndarray, shape (..., n)
        State at ``t + dt``.
    """
    k1 = rate(t, x)
    k2 = rate(t + dt / 2, x + dt / 2 * k1)
    k3 = rate(t + dt / 2, x + dt / 2 * k2)
    k4 = rate(t + dt, x + dt * k3)
    return np.asarray(x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4))


def _count(name: str, value: object) -> int:
    """A positive integer argument, refused in one line otherwise."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise DataError(f"{name}: expected a positive integer, got {value!r}")
    return int(value)


def _seed(seed: object) -> np.random.Generator:
    """The generator of a simulation, from a nonnegative integer seed."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise DataError(f"seed: expected a nonnegative integer, got {seed!r}")
    return np.random.default_rng(seed)


def _noise_kind(noise: object) -> str:
    if not isinstance(noise, str) or noise not in NOISE_KINDS:
        raise DataError(f"noise: expected one of {NOISE_KINDS}, got {noise!r}")
    return noise


def simulate(
    system: LTISystem,
    bounds: Bounds,
    t: ArrayLike,
    u: ArrayLike | None = None,
    noise: str | dict[str, ArrayLike] = "extreme",
    seed: int = 0,
    runs: int | None = None,
    substeps: int = 10,
) -> Simulation:
    """Simulate the true system with admissible noise, initial state, ``ΔA`` and ``ΔB``.

    Parameters
    ----------
    system : LTISystem
        The model.
    bounds : Bounds
        Boxes of ``x0``, ``w``, ``v``; each run draws ``x0`` and a constant ``ΔA`` and ``ΔB`` in their
        boxes (vertices for ``"extreme"`` noise).
    t : array_like, shape (T,)
        Sample times; uniformly spaced for continuous time. For discrete time only the length counts.
    u : array_like, shape (T, m), optional
        Known input (held between samples in continuous time).
    noise : str or dict
        A kind from ``NOISE_KINDS``, or ``{"w": array, "v": array}`` with user signals of shape
        ``(T * substeps, nw)`` (continuous) or ``(T, nw)`` (discrete), and ``(T, nv)``.
    seed : int
        Seed of the random generator; results are deterministic.
    runs : int, optional
        Number of Monte Carlo runs (adds a leading axis to every signal).
    substeps : int
        Noise switches per sampling interval in continuous time.

    Returns
    -------
    Simulation

    Raises
    ------
    DataError
        ``runs``, ``substeps`` or ``seed`` is not a positive (nonnegative) integer, ``noise`` is not a
        kind or a dict with ``"w"`` and ``"v"``, or a signal has the wrong shape.
    """
    times = as_time("t", t)
    full = bounds.resolve(system)
    steps = times.size
    count = 1 if runs is None else _count("runs", runs)
    fine = _count("substeps", substeps) if system.continuous else 1
    rng = _seed(seed)
    us = np.zeros((steps, system.m)) if u is None else as_signal("u", u, steps, system.m)
    if us.ndim != 2:
        raise DataError(f"u: expected shape ({steps}, {system.m}) shared by all runs, got {us.shape}")
    if system.continuous and steps > 1:
        h = float(times[1] - times[0])
        if np.max(np.abs(np.diff(times) - h)) > 1e-9 * h:
            raise DataError("t: expected uniformly spaced sample times for a continuous-time system")
    else:
        h = 1.0
    if isinstance(noise, dict):
        if set(noise) != {"w", "v"}:
            raise DataError(f"noise: expected a dict with the keys 'w' and 'v', got keys {sorted(noise)}")
        w = as_signal("noise['w']", noise["w"], steps * fine, system.nw)
        v = as_signal("noise['v']", noise["v"], steps, system.nv)
        w = np.broadcast_to(w, (count, *w.shape[-2:]))
        v = np.broadcast_to(v, (count, *v.shape[-2:]))
        kind = "uniform"
    else:
        kind = _noise_kind(noise)
        w = noise_signal(kind, full.w[0], full.w[1], steps * fine, rng, count)
        v = noise_signal(kind, full.v[0], full.v[1], steps, rng, count)
    x0 = draw_box(kind, *full.x0, rng, count)
    if system.dA is None:
        d_a = np.zeros((count, system.n, system.n))
    else:
        d_a = draw_box(kind, *system.dA, rng, count)
    d_b = np.zeros((count, system.n, system.m)) if system.dB is None else draw_box(kind, *system.dB, rng, count)
    n, m, nw = system.n, system.m, system.nw
    a_true, b_true = system.A + d_a, system.B + d_b
    if system.continuous:
        size = n + m + nw
        aug = np.zeros((count, size, size))
        aug[:, :n, :n], aug[:, :n, n : n + m], aug[:, :n, n + m :] = a_true, b_true, system.E
        exact = np.stack([expm(a * (h / fine)) for a in aug])
        phi, gamma_u, gamma_w = exact[:, :n, :n], exact[:, :n, n : n + m], exact[:, :n, n + m :]
    else:
        phi, gamma_u, gamma_w = (
            a_true,
            b_true,
            np.broadcast_to(system.E, (count, n, nw)),
        )
    x = np.empty((count, steps, n))
    state = x0
    for k in range(steps):
        x[:, k] = state
        if k + 1 == steps:
            break
        for j in range(fine):
            state = (
                np.einsum("rij,rj->ri", phi, state)
                + gamma_u @ us[k]
                + np.einsum("rij,rj->ri", gamma_w, w[:, k * fine + j])
            )
    y = x @ system.C.T + v @ system.F.T
    names = (system.state_names, system.output_names, system.input_names)
    if runs is None:
        return Simulation(times, x[0], y[0], us, w[0], v[0], d_a[0], *names, dB=d_b[0])
    return Simulation(times, x, y, us, np.asarray(w), np.asarray(v), d_a, *names, dB=d_b)


@dataclass(frozen=True)
class SampledSimulation:
    """A simulated record of a :class:`SampledSystem` on the observer's grid (leading run axis if ``runs``).

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
    """Simulate a partially linear model with sampled outputs: admissible disturbance, noise and initial state.

    Classical Runge–Kutta (:func:`runge_kutta_step`) on a grid ``substeps`` times finer than the
    observer's, the disturbance switching on that finer grid (inside the observer's steps), the known
    input evaluated in continuous time when given as a function, and measurements only every
    ``system.sample_period`` (NaN rows in between).

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
        A kind of :func:`noise_signal` (``"extreme"``: bang-bang, switching on the fine grid, inside
        the observer's steps; the initial state at a random vertex).
    seed : int
        Random seed.
    runs : int, optional
        Number of Monte Carlo runs (leading axis).
    substeps : int
        Runge–Kutta steps (and disturbance switching opportunities) per observer step.

    Returns
    -------
    SampledSimulation

    Raises
    ------
    DataError
        A bad grid, or ``runs``, ``substeps``, ``seed`` or ``noise`` out of its range.

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`), model (8).
    """
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
    fine = _count("substeps", substeps)
    count = 1 if runs is None else _count("runs", runs)
    kind = _noise_kind(noise)
    rng = _seed(seed)
    full = bounds.resolve(system)
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

    d = noise_signal(kind, full.w[0], full.w[1], steps * fine, rng, count)
    v = noise_signal(kind, full.v[0], full.v[1], steps, rng, count)
    x0 = draw_box(kind, *full.x0, rng, count)
    dt = h / fine
    a_t = system.A.T
    x = np.empty((count, steps, n))
    state = np.array(x0, dtype=float)
    for k in range(steps):
        x[:, k] = state
        if k + 1 == steps:
            break
        tk = float(times[k])
        for j in range(fine):
            dd = d[:, k * fine + j]

            def rate(tt: float, xx: FloatArray, k: int = k, dd: FloatArray = dd) -> FloatArray:
                return np.asarray(xx @ a_t + system.nonlinearity(tt, u_at(tt, k), xx) + dd)

            state = runge_kutta_step(rate, tk + j * dt, state, dt)
    sampled = (np.arange(steps) % every) == 0
    y = x @ system.C.T + v
    y[:, ~sampled] = np.nan
    if runs is None:
        return SampledSimulation(times, x[0], y[0], u_grid, d[0], v[0], sampled)
    return SampledSimulation(times, x, y, u_grid, np.asarray(d), np.asarray(v), sampled)


@dataclass(frozen=True)
class NonlinearSimulation:
    """A simulated record of a :class:`NonlinearSystem`, time-first (leading run axis if ``runs``).

    Attributes
    ----------
    x : numpy.ndarray, shape (..., T, n)
    y : numpy.ndarray, shape (..., T, p)
    u : numpy.ndarray, shape (T, m)
    d : numpy.ndarray, shape (..., T, q)
    w : numpy.ndarray, shape (..., T, n)
    v : numpy.ndarray, shape (..., T, p)
    """

    x: FloatArray
    y: FloatArray
    u: FloatArray
    d: FloatArray
    w: FloatArray
    v: FloatArray


def simulate_nonlinear(
    system: NonlinearSystem,
    bounds: Bounds,
    d: ArrayLike,
    u: ArrayLike | None = None,
    noise: str = "extreme",
    seed: int = 0,
    runs: int | None = None,
) -> NonlinearSimulation:
    """Iterate a nonlinear discrete-time system with unknown inputs, with admissible noise.

    Parameters
    ----------
    system : NonlinearSystem
        The model.
    bounds : Bounds
        Boxes of ``x0`` (each run draws a point, :func:`draw_box`: a random vertex for ``"extreme"``
        noise, uniform otherwise; a point when lower = upper), ``w`` and ``v``.
    d : array_like, shape (T, q) or (runs, T, q)
        Unknown input; its length fixes the horizon T.
    u : array_like, shape (T, m), optional
        Known input (default zero).
    noise : str
        Kind of :func:`noise_signal` ("extreme" is bang-bang between the bounds).
    seed : int
        Random seed.
    runs : int, optional
        Number of Monte Carlo runs (leading axis).

    Returns
    -------
    NonlinearSimulation

    Raises
    ------
    DataError
        ``d`` of the wrong shape or not finite, or ``runs``, ``seed`` or ``noise`` out of its range.

    References
    ----------
    Khajenejad & Yong (:mod:`intervalobs.references`), model (3).
    """
    dd = np.asarray(d, dtype=float)
    if dd.ndim not in (2, 3) or dd.shape[-1] != system.q:
        raise DataError(f"d: expected shape (T, {system.q}) or (runs, T, {system.q}), got {dd.shape}")
    if not np.all(np.isfinite(dd)):
        raise DataError("d: expected finite values, got NaN or inf")
    steps = dd.shape[-2]
    uu = np.zeros((steps, system.m)) if u is None else as_matrix("u", u, (steps, system.m))
    count = 1 if runs is None else _count("runs", runs)
    kind = _noise_kind(noise)
    rng = _seed(seed)
    full = bounds.resolve(system)
    x_init = draw_box(kind, *full.x0, rng, count)
    w = noise_signal(kind, full.w[0], full.w[1], steps, rng, runs=count)
    v = noise_signal(kind, full.v[0], full.v[1], steps, rng, runs=count)
    dr = np.broadcast_to(dd, (count, steps, system.q))
    x = np.empty((count, steps, system.n))
    x[:, 0] = x_init
    for k in range(steps - 1):
        x[:, k + 1] = system.evaluate_f(x[:, k]) + uu[k] @ system.B.T + dr[:, k] @ system.G.T + w[:, k]
    y = system.evaluate_g(x) + uu @ system.D.T + dr @ system.H.T + v
    if runs is None:
        return NonlinearSimulation(x[0], y[0], uu, dr[0].copy(), w[0], v[0])
    return NonlinearSimulation(x, y, uu, np.array(dr), w, v)
