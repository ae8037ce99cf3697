"""Continuous-time nonlinear test systems and a truth simulator of the tests' own (fixed-step RK4).

The truth never comes from the library: :func:`simulate_truth` integrates the point vector field with
classical RK4 on steps ``substeps`` times finer than the sampling period, with a disturbance that
switches sign inside every sampling interval (bang-bang at the box's ends) and the input held.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from intervalobs import Bounds, ContinuousNonlinearSystem


@dataclass(frozen=True)
class Case:
    """A model, its boxes, its point vector field ``rates(x, u, p, w)``, output rows and sampling period."""

    name: str
    system: ContinuousNonlinearSystem
    bounds: Bounds
    rates: Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]
    outputs: list[int]
    h: float
    observer_options: dict[str, Any]


def simulate_truth(
    case: Case, x0: np.ndarray, p: np.ndarray, t: np.ndarray, u: np.ndarray, seed: int, substeps: int = 20
) -> np.ndarray:
    """RK4 from ``x0`` with parameters ``p``; ``w`` at an end of its box, flipping every few substeps."""
    rng = np.random.default_rng(seed)
    b = case.bounds.resolve(case.system)
    w_lo, w_hi = b.w
    x = np.array(x0, dtype=float)
    out = [x.copy()]
    dt = (t[1] - t[0]) / substeps
    for k in range(t.size - 1):
        period = int(rng.integers(2, substeps // 2))
        for j in range(substeps):
            w = w_hi if (j // period + k) % 2 == 0 else w_lo

            def rates(z: np.ndarray, w: np.ndarray = w, held: np.ndarray = u[k]) -> np.ndarray:
                return case.rates(z, held, p, w)

            k1 = rates(x)
            k2 = rates(x + 0.5 * dt * k1)
            k3 = rates(x + 0.5 * dt * k2)
            k4 = rates(x + dt * k3)
            x = x + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        out.append(x.copy())
    return np.array(out)


def truths(case: Case, count: int, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """Starts and parameters at vertices of their boxes and inside them."""
    rng = np.random.default_rng(seed)
    b = case.bounds.resolve(case.system)
    corners = list(itertools.product(*zip(*b.x0)))
    picks = []
    for j in range(count):
        if j % 2 == 0:
            x0 = np.array(corners[rng.integers(len(corners))])
            p = np.where(rng.random(case.system.n_params) < 0.5, b.p[0], b.p[1])
        else:
            x0 = rng.uniform(*b.x0)
            p = rng.uniform(*b.p)
        picks.append((x0, p))
    return picks


def measure(case: Case, x: np.ndarray, seed: int) -> np.ndarray:
    """Outputs with noise at the ends of its box (random signs)."""
    rng = np.random.default_rng(seed + 1000)
    b = case.bounds.resolve(case.system)
    noise = np.where(rng.random((x.shape[0], len(case.outputs))) < 0.5, b.v[0], b.v[1])
    return x[:, case.outputs] + noise


def _with_w(field: Callable[..., Any], n: int, channels: list[int]) -> Callable[..., np.ndarray]:
    def rates(x: np.ndarray, u: np.ndarray, p: np.ndarray, w: np.ndarray) -> np.ndarray:
        out = np.array(field(list(x), list(u), list(p)), dtype=float)
        out[channels] += w
        return out

    return rates


def chemostat(x0: tuple[list[float], list[float]] = ([1.0, 0.3], [3.0, 0.8])) -> Case:
    """Monod chemostat: biomass X, substrate S (measured ±0.02 every 0.1 h); μmax, Ks ±5 %."""
    dilution, inlet, yield_ = 0.2, 5.0, 0.5

    def f(x: Any, u: Any, p: Any) -> tuple[Any, Any]:
        growth = p[0] * x[1] / (p[1] + x[1])
        return (growth - dilution) * x[0], dilution * (inlet - x[1]) - growth * x[0] / yield_

    system = ContinuousNonlinearSystem(f, lambda x, u: (x[1],), n=2, n_params=2, domain=(0.0, np.inf))
    bounds = Bounds(x0=x0, v=(-0.02, 0.02), p=([0.475, 0.285], [0.525, 0.315]))
    return Case("chemostat", system, bounds, _with_w(f, 2, []), [1], 0.1, {"splits": (8, 1)})


def chemostat_bundle() -> Case:
    """The chemostat in reaction-invariant coordinates (Z = X/Y + S, S), run as a bundle of up to 16 parts."""
    dilution, inlet, yield_ = 0.2, 5.0, 0.5

    def f(z: Any, u: Any, p: Any) -> tuple[Any, Any]:
        return dilution * (inlet - z[0]), dilution * (inlet - z[1]) - p[0] * z[1] / (p[1] + z[1]) * (z[0] - z[1])

    system = ContinuousNonlinearSystem(f, lambda z, u: (z[1],), n=2, n_params=2, domain=(0.0, np.inf))
    prior = ([1.0 / yield_ + 0.3, 0.3], [3.0 / yield_ + 0.8, 0.8])
    bounds = Bounds(x0=prior, v=(-0.02, 0.02), p=([0.475, 0.285], [0.525, 0.315]))
    return Case("chemostat-bundle", system, bounds, _with_w(f, 2, []), [1], 0.1, {"refine": 16})


def pendulum() -> Case:
    """Damped pendulum, angle measured ±0.01 rad every 0.05 s; friction ±10 %, torque disturbance ±0.05."""

    def f(x: Any, u: Any, p: Any) -> tuple[Any, Any]:
        return x[1], -9.81 * np.sin(x[0]) - p[0] * x[1] + u[0]

    system = ContinuousNonlinearSystem(f, lambda x, u: (x[0],), n=2, m=1, n_params=1, E=[[0.0], [1.0]])
    bounds = Bounds(x0=([0.4, -0.2], [0.6, 0.2]), p=(0.45, 0.55), w=(-0.05, 0.05), v=(-0.01, 0.01))
    return Case("pendulum", system, bounds, _with_w(f, 2, [1]), [0], 0.05, {})


def cstr() -> Case:
    """Exothermic CSTR (dimensionless, Arrhenius), temperature measured; Damköhler number ±5 %."""
    gamma, heat, cooling = 20.0, 8.0, 0.3

    def f(x: Any, u: Any, p: Any) -> tuple[Any, Any]:
        rate = p[0] * (1.0 - x[0]) * np.exp(x[1] / (1.0 + x[1] / gamma))
        return -x[0] + rate, -x[1] + heat * rate - cooling * x[1]

    system = ContinuousNonlinearSystem(
        f, lambda x, u: (x[1],), n=2, n_params=1, E=[[0.0], [1.0]], domain=([0.0, -1.0], [1.0, np.inf])
    )
    bounds = Bounds(x0=([0.1, 0.4], [0.2, 0.6]), p=(0.0684, 0.0756), w=(-0.01, 0.01), v=(-0.01, 0.01))
    return Case("cstr", system, bounds, _with_w(f, 2, [1]), [1], 0.1, {})


def compartments() -> Case:
    """Six compartments in a chain with Michaelis–Menten elimination; first and last measured."""
    k = (0.8, 0.6, 0.5, 0.4, 0.7)

    def f(x: Any, u: Any, p: Any) -> tuple[Any, ...]:
        elimination = p[0] * x[5] / (0.5 + x[5])
        flows = [k[i] * x[i] for i in range(5)]
        return (u[0] - flows[0], *(flows[i - 1] - flows[i] for i in range(1, 5)), flows[4] - elimination)

    system = ContinuousNonlinearSystem(
        f, lambda x, u: (x[0], x[5]), n=6, m=1, n_params=1, E=np.eye(6)[:, :1], domain=(0.0, np.inf)
    )
    bounds = Bounds(x0=(0.0, 0.5), p=(0.95, 1.05), w=(-0.02, 0.02), v=(-0.02, 0.02))
    return Case("compartments", system, bounds, _with_w(f, 6, [0]), [0, 5], 0.1, {})


def rotation() -> Case:
    """A linear system whose x2-x3 block rotates (eigenvalues -0.5 ± 1.94i at the nominal frequency), x1 measured.

    The wrapping case of the zonotopes' reduction (the sampled-output high-gain paper's example has the same block);
    the rotation frequency is a parameter (±3 %), the disturbance enters x2 and x3.
    """

    def f(x: Any, u: Any, p: Any) -> tuple[Any, Any, Any]:
        return -x[0] + x[1], -0.5 * x[1] + p[0] * x[2] + u[0], -p[0] * x[1] - 0.5 * x[2]

    e = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]
    system = ContinuousNonlinearSystem(f, lambda x, u: (x[0],), n=3, m=1, n_params=1, E=e)
    bounds = Bounds(x0=([-0.5, -1.0, -1.0], [0.5, 1.0, 1.0]), p=(1.88, 2.0), w=(-0.2, 0.2), v=(-0.05, 0.05))
    return Case("rotation", system, bounds, _with_w(f, 3, [1, 2]), [0], 0.05, {"order": 12})
