"""Disk pole placement (seed 004, Theorem 4.1, Algorithm 1) and the C-diagonalisation."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment

from intervalobs import DesignError
from intervalobs.design.regions import Disk, canonical_eigenvectors, modal_decomposition, place_in_disks, radius_matrix
from intervalobs.errors import AssumptionError
from intervalobs.examples import hgio as example

A, C = example.A, example.C


def test_paper_disks_already_hold_the_open_loop_eigenvalues() -> None:
    placed = place_in_disks(A, C, example.DISKS)
    np.testing.assert_allclose(placed.L, 0.0, atol=1e-12)
    assert np.all(placed.margins > 0)
    np.testing.assert_allclose(placed.eigenvalues, [-1, -0.5 + 1.9364916731j, -0.5 - 1.9364916731j], atol=1e-9)
    assert placed.radius_abscissa < 0


def test_center_objective_moves_eigenvalues_to_the_centres() -> None:
    placed = place_in_disks(A, C, example.DISKS, objective="center")
    np.testing.assert_allclose(placed.eigenvalues, [d.center for d in example.DISKS], atol=1e-4)
    closed = A - placed.L @ C
    for d, lam in zip(placed.disks, np.linalg.eigvals(closed)[np.argsort(np.linalg.eigvals(closed).imag)[[1, 2, 0]]]):
        assert d.margin(lam) > 0


@pytest.mark.parametrize(
    "disks",
    [
        [(-3.0, 0.5), (-2 + 1j, 0.3), (-2 - 1j, 0.3)],
        [(-5.0, 1.0), (-1 + 3j, 0.5), (-1 - 3j, 0.5)],
    ],
    ids=["moderate", "far"],
)
def test_moves_every_eigenvalue_into_its_disk(disks: list[tuple[complex, float]]) -> None:
    placed = place_in_disks(A, C, disks)
    eig = np.linalg.eigvals(A - placed.L @ C)
    for d in placed.disks:
        assert np.min(np.abs(eig - d.center)) < d.radius  # verified from the matrix itself
    assert np.all(placed.margins > 0)
    assert placed.modal.condition < 1e8


def test_an_inaccurate_solver_status_is_verified_not_warned() -> None:
    """The hgio-sampled tuned disks: Clarabel reports optimal_inaccurate for the complex pair's LMI (15).

    The point passes the residual check (design/lmi.py), so no warning reaches the user, and the placement
    is verified from the eigenvalues of A - LC.
    """
    from intervalobs.reproduce.hgio_sampled import TUNED_DISKS

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        placed = place_in_disks(A, C, TUNED_DISKS)
    assert {step["status"] for step in placed.steps} <= {"optimal", "optimal_inaccurate", "already inside"}
    eig = np.linalg.eigvals(A - placed.L @ C)
    for d in placed.disks:
        assert np.min(np.abs(eig - d.center)) < d.radius


def test_printed_gain_reproduces_the_printed_eigenvalues_and_v1() -> None:
    modal = modal_decomposition(A, C, np.array(example.PAPER["L1"])[:, None], order=[d.center for d in example.DISKS])
    np.testing.assert_allclose(modal.p1, example.PAPER["p1"], atol=1e-4)
    np.testing.assert_allclose(modal.omega1, example.PAPER["omega1"], atol=1e-4)
    # the printed v1 equals ours up to a unit factor per row (LAPACK's arbitrary phase; ours is canonical)
    printed = np.array(example.PAPER["v1"])
    np.testing.assert_allclose(np.abs(modal.v1), np.abs(printed), atol=1e-4)
    rows = np.sum(np.conj(modal.v1) * printed, axis=1) / np.sum(np.abs(modal.v1) ** 2, axis=1)
    np.testing.assert_allclose(np.abs(rows), 1.0, atol=1e-4)
    np.testing.assert_allclose(rows[:, None] * modal.v1, printed, atol=2e-4)
    closed = modal.v1_inv @ np.diag(modal.eigenvalues) @ modal.v1
    np.testing.assert_allclose(closed, A - np.array(example.PAPER["L1"])[:, None] @ C, atol=1e-12)


def test_radius_matrix_is_metzler() -> None:
    modal = modal_decomposition(A, C, np.zeros((3, 1)))
    mat = radius_matrix(modal, np.zeros((3, 1)), C)
    assert np.all(mat - np.diag(np.diag(mat)) >= 0)


@pytest.mark.parametrize(
    "disks, match",
    [
        ([(-1.0, 0.5), (-1.0, 0.5)], "one disk per state"),
        ([(-1.0, 0.5), (-0.6 + 1.8j, 0.2), (-0.6 - 1.7j, 0.2)], "conjugation"),
        ([(0.2, 0.5), (-0.6 + 1.8j, 0.2), (-0.6 - 1.8j, 0.2)], "left half-plane"),
    ],
    ids=["count", "not-conjugate", "unstable-disk"],
)
def test_bad_disks_raise(disks: list[tuple[complex, float]], match: str) -> None:
    with pytest.raises(AssumptionError, match=match):
        place_in_disks(A, C, disks)


def test_disk_validation_and_repeated_eigenvalues() -> None:
    with pytest.raises(ValueError, match="radius"):
        Disk(-1.0, -0.1)
    with pytest.raises(DesignError, match="distinct"):
        modal_decomposition(-np.eye(2), np.array([[1.0, 0.0]]), np.zeros((2, 1)))
    with pytest.raises(DesignError, match="Hurwitz"):
        modal_decomposition(A, C, -np.array([[10.0], [0.0], [0.0]]))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_canonical_eigenvectors_do_not_depend_on_the_phase_lapack_returns(seed: int) -> None:
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(5, 5))
    _, vecs = np.linalg.eig(a)
    phases = np.exp(2j * np.pi * rng.random(5)) * rng.uniform(0.5, 2.0, 5)  # any phase, any scale
    reference = canonical_eigenvectors(vecs)
    np.testing.assert_allclose(canonical_eigenvectors(vecs * phases[None, :]), reference, rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(reference, axis=0), 1.0, rtol=0, atol=1e-12)
    pivot = np.argmax(np.abs(reference) >= (1 - 1e-6) * np.max(np.abs(reference), axis=0), axis=0)
    entry = reference[pivot, np.arange(5)]
    assert np.all(entry.real > 0) and np.all(entry.imag == 0)
    modal = modal_decomposition(a - 10 * np.eye(5), np.eye(1, 5), np.zeros((5, 1)))
    np.testing.assert_allclose(modal.v1_inv, canonical_eigenvectors(modal.v1_inv), rtol=0, atol=1e-12)


def _assert_each_in_its_disk(a: np.ndarray, c: np.ndarray, placed: object) -> None:
    """Every eigenvalue of A - LC, recomputed here, lies in a disk of its own (a one-to-one matching)."""
    eig = np.linalg.eigvals(np.asarray(a, dtype=float) - placed.L @ np.asarray(c, dtype=float))  # type: ignore[attr-defined]
    disks = placed.disks  # type: ignore[attr-defined]
    inside = np.array([[d.radius - abs(lam - d.center) for lam in eig] for d in disks])
    rows, cols = linear_sum_assignment(-np.minimum(inside, 0.0) + (inside <= 0))
    assert np.all(inside[rows, cols] > 0), (eig, disks)


@pytest.mark.parametrize(
    "a, c, disks",
    [
        ([[0, 1], [-2, -3]], [[1, 0]], [(-3, 0.5), (-4, 0.5)]),  # the call: real eigenvalues, real disks
        ([[0, 1], [-2, -3]], [[1, 0]], [(-3 + 1j, 0.5), (-3 - 1j, 0.5)]),  # two real eigenvalues into a pair
        ([[0, 1], [-5, -2]], [[1, 0]], [(-3, 0.5), (-4, 0.5)]),  # a conjugate pair into two real disks
        ([[0, 1], [-5, -2]], [[0, 1]], [(-3, 0.5), (-3, 0.5)]),  # the same disk twice
        ([[0, 1, 0], [0, 0, 1], [1, -2, -3]], [[1, 0, 0]], [(-3, 0.5), (-4, 0.5), (-5, 0.5)]),  # mixed, unstable A
        (A, C, [(-1.0, 0.5), (-2.0, 0.2), (-3.0, 0.2)]),  # the paper's pair moved to the real axis
        ([[-1, 2, 0], [0, -2, 1], [0, 0, -3]], [[1, 0, 0], [0, 0, 1]], [(-6, 1), (-2 + 2j, 0.5), (-2 - 2j, 0.5)]),
    ],
    ids=["real", "real-to-pair", "pair-to-real", "same-disk", "mixed-unstable", "paper-pair-to-real", "two-outputs"],
)
def test_real_and_mixed_targets_land_in_their_disks(a: list[list[float]], c: list[list[float]], disks: list) -> None:
    placed = place_in_disks(a, c, disks)
    _assert_each_in_its_disk(np.asarray(a), np.asarray(c), placed)
    assert np.all(placed.margins > 0)
    assert np.isrealobj(placed.L)
    assert placed.modal.condition < 1e8


def test_a_block_that_cannot_be_moved_is_a_design_error() -> None:
    """A conjugate pair that C does not see (C = 0 on its plane) cannot go to the real axis."""
    a = [[0.0, 1.0, 0.0], [-5.0, -2.0, 0.0], [0.0, 0.0, -1.0]]
    with pytest.raises(DesignError):
        place_in_disks(a, [[0.0, 0.0, 1.0]], [(-1.0, 0.5), (-3.0, 0.5), (-4.0, 0.5)])
