"""Shared fixtures: random observable LTI systems of the kinds the foundation promises to handle."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, settings
from scipy.linalg import expm

from intervalobs import Bounds, LTISystem

# Property tests assert properties, not speed: on a loaded machine (CI neighbours, xdist workers) drawing
# inputs or running an example can take seconds, which must not fail a test.
settings.register_profile("intervalobs", deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("intervalobs")


def random_system(seed: int, n: int, p: int, continuous: bool, uncertain: bool) -> tuple[LTISystem, Bounds]:
    """A random observable system; stable when uncertain (so that widths can stay bounded)."""
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(n, n))
    if continuous:
        shift = np.max(np.linalg.eigvals(A).real) + (rng.uniform(0.2, 1.0) if uncertain else rng.uniform(-0.5, 1.0))
        A = A - shift * np.eye(n)
    else:
        A = A / np.max(np.abs(np.linalg.eigvals(A))) * (rng.uniform(0.5, 0.95) if uncertain else rng.uniform(0.5, 1.02))
    C = rng.normal(size=(p, n))
    dA = (-0.02 * np.abs(A), 0.02 * np.abs(A)) if uncertain else None
    system = LTISystem(A, C, dt=None if continuous else 1.0, dA=dA)
    bounds = Bounds(
        (-np.ones(n), np.ones(n)), w=(-0.1 * np.ones(n), 0.1 * np.ones(n)), v=(-0.05 * np.ones(p), 0.05 * np.ones(p))
    )
    return system, bounds


def unit_bounds(n: int, nw: int, p: int) -> Bounds:
    """Unit boxes of x0 and w, measurement noise within ±0.01 (the radius :func:`simulate_truth` uses)."""
    return Bounds(
        x0=(-np.ones(n), np.ones(n)), w=(-np.ones(nw), np.ones(nw)), v=(-0.01 * np.ones(p), 0.01 * np.ones(p))
    )


def simulate_truth(
    a: np.ndarray, e: np.ndarray, c: np.ndarray, delta: np.ndarray, x0: np.ndarray, h: float, steps: int, rng
) -> tuple[np.ndarray, np.ndarray]:
    """Exact exponentials of 4 sub-steps per sample; the noise switches sign (bang-bang) at every sub-step."""
    n, nw, sub = a.shape[0], e.shape[1], 4
    block = np.zeros((n + nw, n + nw))
    block[:n, :n], block[:n, n:] = a + delta, e
    flow = expm(block * (h / sub))
    x = np.empty((steps, n))
    x[0] = x0
    for k in range(steps - 1):
        state = x[k]
        for _ in range(sub):
            w = rng.choice([-1.0, 1.0], nw)
            state = flow[:n, :n] @ state + flow[:n, n:] @ w
        x[k + 1] = state
    y = x @ c.T + 0.01 * rng.choice([-1.0, 1.0], (steps, c.shape[0]))
    return x, y
