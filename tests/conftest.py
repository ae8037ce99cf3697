"""Shared fixtures: random observable LTI systems of the kinds the foundation promises to handle."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, settings

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
