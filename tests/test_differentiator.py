"""Output-derivative enclosures: Levant's HOSM (seed 000, §2.2) and the provable difference bound."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs.design.differentiator import (
    HOSMDifferentiator,
    difference_derivative_bounds,
    hosm_error_bound,
    levant_gains,
    settling_time,
)
from intervalobs.errors import BoundsError, DimensionError

H = 1e-4


def _signal(t: np.ndarray, seed: int, kind: str = "sine") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """ψ = 1.1 sin(t + φ) (|ψ̈| ≤ 1.1) and smooth noise |δ| ≤ 1e-2, |δ̇| ≤ 1e-2; shapes (T, 2)."""
    rng = np.random.default_rng(seed)
    phase = rng.uniform(0, 2 * np.pi, 2)
    psi = 1.1 * np.sin(t[:, None] + phase)
    dpsi = 1.1 * np.cos(t[:, None] + phase)
    if kind == "sine":
        delta = 1e-2 * np.sin(t[:, None] + rng.uniform(0, 2 * np.pi, 2))
    else:  # ramp at the largest admissible rate, clipped at the bound
        delta = np.clip(1e-2 * (t[:, None] - rng.uniform(0, 3, 2)) - 1e-2, -1e-2, 1e-2)
    return psi + delta, psi, dpsi


def test_levant_gains() -> None:
    np.testing.assert_allclose(levant_gains(1, 4.0), [1.5 * 2.0, 1.1 * 4.0])
    np.testing.assert_allclose(levant_gains(2, 8.0), [2.0 * 2.0, 1.5 * 8.0**0.5, 1.1 * 8.0])
    with pytest.raises(DimensionError):
        levant_gains(0, 1.0)
    with pytest.raises(BoundsError):
        levant_gains(1, -1.0)


def test_hosm_error_bound_is_eq_8() -> None:
    np.testing.assert_allclose(hosm_error_bound([1e-2] * 4, [1e-2] * 4, 1.1), 0.01 + 0.11)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_difference_bounds_enclose_the_derivative(seed: int) -> None:
    t = np.arange(20001) * H
    for kind in ("sine", "ramp"):
        y, _, dpsi = _signal(t, seed, kind)
        lo, hi = difference_derivative_bounds(y, H, [1e-2] * 2, [1.1] * 2, step_tolerance=1e-9 * H)
        assert np.all(lo[0] == -np.inf) and np.all(hi[0] == np.inf)  # no previous sample: no bound
        assert np.all(lo[1:] <= dpsi[1:]) and np.all(dpsi[1:] <= hi[1:])
        assert np.max(hi[1:] - lo[1:]) < 2 * (1e-2 + 1.1 * H) * 1.001


def test_hosm_levant_gains_converge_and_paper_gains_do_not_meet_mu1() -> None:
    t = np.arange(30001) * H
    y, _, dpsi = _signal(t, 0)
    after = t >= 1.0
    good = HOSMDifferentiator(1, levant_gains(1, 10.0)).run(y, H)[..., 1]
    assert np.abs(good - dpsi)[after].max() < 0.03
    paper = HOSMDifferentiator(1, [100.0, 100.0]).run(y, H)[..., 1]
    err = np.abs(paper - dpsi)[after].max()
    assert err > 1.1 * np.sqrt(1e-2) + 1e-2  # the claimed β = 0.12 does not hold at Te = 1e-4
    assert err == pytest.approx(100.0**2 * H / 4, rel=0.15)  # explicit-Euler chattering λ0² Te / 4
    assert settling_time(t, good - dpsi, np.full(2, 0.03)) < 1.0


def test_hosm_is_vectorised_over_runs() -> None:
    t = np.arange(2001) * H
    runs = np.stack([_signal(t, s)[0] for s in range(3)])
    diff = HOSMDifferentiator(1, levant_gains(1, 10.0))
    together = diff.run(runs, H)
    for s in range(3):
        np.testing.assert_array_equal(together[s], diff.run(runs[s], H))
    assert together.shape == (3, 2001, 2, 2)


def test_hosm_rejects_bad_parameters() -> None:
    with pytest.raises(DimensionError, match="gains"):
        HOSMDifferentiator(2, [1.0, 2.0])
    with pytest.raises(BoundsError, match="positive"):
        HOSMDifferentiator(1, [1.0, -2.0])
