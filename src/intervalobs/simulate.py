"""Truth simulation with admissible noise: the reference every enclosure test is judged against.

Continuous-time systems are simulated *exactly* for piecewise-constant noise: the noise ``w`` is held
over sub-steps of ``h / substeps`` (so it switches inside the observer's sampling intervals), the known
input ``u`` over whole sampling intervals (zero-order hold, as the observers assume), and each
sub-step uses the matrix exponential of the augmented system. Discrete-time systems are iterated.
Measurements are taken at the sample times with their own noise ``v``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import expm

from . import _tables
from .errors import DataError
from .systems.bounds import Bounds
from .systems.lti import LTISystem
from .validation import as_names, as_signal, as_time

__all__ = ["NOISE_KINDS", "Simulation", "noise_signal", "simulate"]

FloatArray = NDArray[np.float64]

NOISE_KINDS = ("uniform", "extreme", "sine", "constant")
"""Built-in noise kinds; ``"extreme"`` jumps between the two bounds at random times (bang-bang)."""

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
        The constant uncertainty drawn for each run.
    state_names, output_names, input_names : sequence of str, optional
        Names of the states, outputs and known inputs (default ``x1 …``, ``y1 …``, ``u1 …``;
        :func:`simulate` gives the model's names).
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

    def __post_init__(self) -> None:
        for kind, signal, prefix in (("state", self.x, "x"), ("output", self.y, "y"), ("input", self.u, "u")):
            name = f"{kind}_names"
            object.__setattr__(self, name, as_names(name, getattr(self, name) or None, np.shape(signal)[-1], prefix))

    def to_pandas(self) -> Any:
        """The record as a pandas ``DataFrame`` (needs the ``data`` extra).

        Indexed by time ``t`` (by ``run`` and ``t`` for several runs), one column per state, output
        and known input, named by the names (the known input, shared by the runs, is repeated in
        each run). The noise, on its own finer grid in continuous time, is not part of the table; ``attrs``
        holds ``dA`` and the names. :meth:`from_pandas` reads it back.

        Returns
        -------
        pandas.DataFrame
        """
        return _tables.to_frame(self.t, self._columns(), self._attrs(), "Simulation.to_pandas")

    def to_xarray(self) -> Any:
        """The record as an xarray ``Dataset`` (needs the ``data`` extra).

        Variables ``x``, ``y``, ``u`` over ``t`` and the dimensions ``state``, ``output``, ``input``
        (``run`` first for several runs), with the names as coordinates; ``attrs`` holds ``dA``.

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
        return _tables.to_dataset(self.t, variables, {"dA": self.dA.tolist()}, "Simulation.to_xarray")

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
            The noise arrays ``w`` and ``v`` are empty (no columns); ``dA`` comes from ``attrs`` (NaN
            when it is not there).
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
        empty = np.zeros((*lead, 0))
        return cls(
            t, x, y, u[0] if u.ndim == 3 else u, empty, empty, d_a, chosen["state"], chosen["output"], chosen["input"]
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
        return {"dA": self.dA.tolist(), **names}

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
        switching with probability 0.1 per step), ``"sine"`` (full-amplitude sinusoid of random period
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


def _draw_box(kind: str, lower: FloatArray, upper: FloatArray, rng: np.random.Generator, runs: int) -> FloatArray:
    """A point per run in the box: a random vertex for extreme noise, uniform otherwise."""
    unit = (
        rng.integers(0, 2, size=(runs, *lower.shape)) if kind == "extreme" else rng.uniform(size=(runs, *lower.shape))
    )
    return np.asarray(lower + (upper - lower) * unit)


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
    """Simulate the true system with admissible noise, initial state and ``ΔA``.

    Parameters
    ----------
    system : LTISystem
        The model.
    bounds : Bounds
        Boxes of ``x0``, ``w``, ``v``; each run draws ``x0`` and a constant ``ΔA`` in their boxes
        (vertices for ``"extreme"`` noise).
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
    """
    times = as_time("t", t)
    full = bounds.resolve(system)
    steps = times.size
    rng = np.random.default_rng(seed)
    count = 1 if runs is None else int(runs)
    us = np.zeros((steps, system.m)) if u is None else as_signal("u", u, steps, system.m)
    if us.ndim != 2:
        raise DataError(f"u: expected shape ({steps}, {system.m}) shared by all runs, got {us.shape}")
    fine = substeps if system.continuous else 1
    if system.continuous and steps > 1:
        h = float(times[1] - times[0])
        if np.max(np.abs(np.diff(times) - h)) > 1e-9 * h:
            raise DataError("t: expected uniformly spaced sample times for a continuous-time system")
    else:
        h = 1.0
    if isinstance(noise, dict):
        w = as_signal("noise['w']", noise["w"], steps * fine, system.nw)
        v = as_signal("noise['v']", noise["v"], steps, system.nv)
        w = np.broadcast_to(w, (count, *w.shape[-2:]))
        v = np.broadcast_to(v, (count, *v.shape[-2:]))
        kind = "uniform"
    else:
        kind = noise
        w = noise_signal(kind, full.w[0], full.w[1], steps * fine, rng, count)
        v = noise_signal(kind, full.v[0], full.v[1], steps, rng, count)
    x0 = _draw_box(kind, *full.x0, rng, count)
    if system.dA is None:
        d_a = np.zeros((count, system.n, system.n))
    else:
        d_a = _draw_box(kind, *system.dA, rng, count)
    n, m, nw = system.n, system.m, system.nw
    a_true = system.A + d_a
    if system.continuous:
        size = n + m + nw
        aug = np.zeros((count, size, size))
        aug[:, :n, :n], aug[:, :n, n : n + m], aug[:, :n, n + m :] = a_true, system.B, system.E
        exact = np.stack([expm(a * (h / fine)) for a in aug])
        phi, gamma_u, gamma_w = exact[:, :n, :n], exact[:, :n, n : n + m], exact[:, :n, n + m :]
    else:
        phi, gamma_u, gamma_w = (
            a_true,
            np.broadcast_to(system.B, (count, n, m)),
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
        return Simulation(times, x[0], y[0], us, w[0], v[0], d_a[0], *names)
    return Simulation(times, x, y, us, np.asarray(w), np.asarray(v), d_a, *names)
