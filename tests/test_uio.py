"""Unknown-input decoupling and cooperative coordinates (seed 000, eqs. (10)–(14), (21)–(25))."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs.design.uio import (
    check_cooperative,
    design_uio_coordinates,
    metzler_block_form,
    uio_constraint_matrices,
    uio_decoupling,
)
from intervalobs.errors import AssumptionError, DesignError
from intervalobs.examples import aircraft as ac

MISPRINTS = {("E", 1, 0), ("E", 1, 1), ("P", 1, 2), ("P", 2, 3)}


@pytest.fixture(scope="module")
def decoupling():
    return uio_decoupling(ac.A, ac.C, ac.D)


def test_aircraft_E_P_agree_with_paper_except_four_misprints(decoupling) -> None:
    assert decoupling.rank_CD == decoupling.rank_D == 2
    assert decoupling.decoupling_residual < 1e-15
    assert decoupling.observability_margin == pytest.approx(0.643, abs=1e-3)
    for name, ours in (("E", decoupling.E), ("P", decoupling.P)):
        printed = np.array(ac.PAPER[name], dtype=float)
        for i, j in np.ndindex(printed.shape):
            close = abs(printed[i, j] - ours[i, j]) <= 5e-6
            assert close != ((name, i, j) in MISPRINTS), f"{name}({i + 1},{j + 1})"
    assert decoupling.E[1, 0] == pytest.approx(-0.9993, abs=1e-4)
    assert decoupling.E[1, 1] == pytest.approx(-2.011e-5, rel=1e-3)
    assert decoupling.P[1, 2] == pytest.approx(-2.011e-5, rel=1e-3)
    assert decoupling.P[2, 3] == pytest.approx(-7.577e-4, rel=1e-3)


def test_parametrisation_solves_the_constraints(decoupling) -> None:
    sigma, theta, sigma_pinv = uio_constraint_matrices(ac.A, ac.C, ac.D)
    np.testing.assert_allclose(sigma_pinv @ sigma, np.eye(7), atol=1e-12)
    coords = design_uio_coordinates(ac.A, ac.C, decoupling, np.full(5, 0.01), np.full(4, 0.01))
    nke = np.hstack([coords.N, coords.K, decoupling.E])
    np.testing.assert_allclose(nke @ sigma, theta, atol=1e-12)  # eq. (23)
    np.testing.assert_allclose(coords.K, coords.L + coords.N @ decoupling.E, atol=1e-12)  # eq. (14)


def test_designed_coordinates_are_metzler_hurwitz(decoupling) -> None:
    coords = design_uio_coordinates(ac.A, ac.C, decoupling, np.full(5, 0.01), np.full(4, 0.01))
    # T N T⁻¹ has the spectrum of N, so it can meet the target M only as closely as the pole placement met M's
    # spectrum: |J - M| <= cond(T)·max|λ(N) - λ(M)| (first order), plus the rounding of the eigenvector solve,
    # 8·n·u·cond(T)·‖N‖·(1 + ‖N‖/gap) with gap the smallest distance between two poles.
    eig_n = np.sort_complex(np.linalg.eigvals(coords.N))
    mismatch = float(np.abs(eig_n - np.sort_complex(coords.poles)).max())
    gap = min(abs(a - b) for i, a in enumerate(coords.poles) for b in coords.poles[i + 1 :])
    norm_n = np.linalg.norm(coords.N, 2)
    rounding = 8 * 5 * np.finfo(float).eps * coords.cond_T * norm_n * (1 + norm_n / gap)
    assert coords.form_residual <= 2 * coords.cond_T * mismatch + rounding
    assert coords.metzler_check > -1e-12
    assert np.all(coords.poles.real < 0)
    assert coords.cond_T < 10
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(coords.N)), np.sort_complex(coords.poles), atol=1e-7)
    assert any(name.startswith("complex pair") and np.isfinite(v) for name, v in coords.tried.items())


def test_given_poles_are_placed(decoupling) -> None:
    poles = -np.arange(1.0, 6.0)
    coords = design_uio_coordinates(ac.A, ac.C, decoupling, np.full(5, 0.01), np.full(4, 0.01), poles=poles)
    np.testing.assert_allclose(np.sort(coords.poles.real), np.sort(poles), atol=1e-7)
    assert coords.cond_T == pytest.approx(4.08, abs=0.05)
    with pytest.raises(DesignError, match="negative real parts"):
        design_uio_coordinates(ac.A, ac.C, decoupling, np.full(5, 0.01), np.full(4, 0.01), poles=[1, -1, -2, -3, -4])


@pytest.mark.parametrize(
    "poles",
    [[-1, -1, -2, -3, -4], [-1, -2 + 0.5j, -2 - 0.5j, -3, -4], [-0.5, -1.5 + 0.4j, -1.5 - 0.4j, -3 + 1j, -3 - 1j]],
    ids=["repeated", "complex", "two-pairs"],
)
def test_repeated_and_complex_poles_get_metzler_coordinates(decoupling, poles) -> None:
    if np.iscomplexobj(poles) and len([p for p in poles if np.imag(p) > 0]) == 2:
        # two pairs but one free real pole: no 3×3 Metzler block for the second pair
        with pytest.raises(DesignError, match="needs a real pole"):
            design_uio_coordinates(ac.A, ac.C, decoupling, np.full(5, 0.01), np.full(4, 0.01), poles=poles)
        return
    coords = design_uio_coordinates(ac.A, ac.C, decoupling, np.full(5, 0.01), np.full(4, 0.01), poles=poles)
    np.testing.assert_allclose(
        np.sort_complex(coords.poles), np.sort_complex(np.array(poles, dtype=complex)), atol=1e-7
    )
    off = coords.M[~np.eye(5, dtype=bool)]
    assert off.min() >= 0.0 and coords.metzler_check > -1e-9 and coords.form_residual < 1e-8
    # T N T⁻¹ recomputed here equals the Metzler form
    np.testing.assert_allclose(coords.T @ coords.N @ np.linalg.inv(coords.T), coords.M, atol=1e-8)


@pytest.mark.parametrize(("r", "sigma", "omega"), [(-1.0, -2.0, 0.5), (-1.0, -3.0, 2 / np.sqrt(3)), (-0.2, -5.0, 0.1)])
def test_metzler_block_form_spectrum_and_sector(r, sigma, omega) -> None:
    m = metzler_block_form([sigma + 1j * omega, r, sigma - 1j * omega])
    assert m[~np.eye(3, dtype=bool)].min() >= 0
    np.testing.assert_allclose(
        np.sort_complex(np.linalg.eigvals(m)),
        np.sort_complex(np.array([r, sigma + 1j * omega, sigma - 1j * omega])),
        atol=1e-12,
    )
    # outside the 60° sector no 3×3 Metzler matrix has this spectrum
    with pytest.raises(DesignError, match="needs a real pole"):
        metzler_block_form(
            [sigma + 1j * (omega + (r - sigma) / np.sqrt(3)), r, sigma - 1j * (omega + (r - sigma) / np.sqrt(3))]
        )
    with pytest.raises(DesignError, match="conjugation"):
        metzler_block_form([sigma + 1j * omega, r, sigma])


def test_printed_K_and_T_are_not_metzler(decoupling) -> None:
    k = np.array(ac.PAPER["K_printed"]).T
    with pytest.raises(AssumptionError, match=r"Metzler.*-2\.61"):
        check_cooperative(ac.A, ac.C, decoupling, k, np.array(ac.PAPER["T"]))


@pytest.mark.parametrize(
    ("A", "C", "D", "match"),
    [
        (np.zeros((3, 3)), np.array([[1.0, 0, 0]]), np.eye(3)[:, :2], "q ≤ p"),
        (np.zeros((3, 3)), np.eye(3)[:2], np.array([[1.0, 1], [0, 0], [0, 0]]), r"rank\(D\)"),
        (
            np.zeros((3, 3)),
            np.array([[1.0, 0, 0], [0, 1, 0]]),
            np.array([[0.0, 0], [0, 0], [1, 1e-3]]) @ np.diag([1, 1]),
            r"rank\(D\)",
        ),
        (
            np.zeros((3, 3)),
            np.array([[1.0, 0, 0], [0, 1, 0]]),
            np.array([[1.0, 0], [0, 0], [0, 1]]),
            r"rank\(CD\) = 1",
        ),
    ],
    ids=["q>p", "rank-D", "rank-D-small", "rank-CD"],
)
def test_hypothesis4_violations(A, C, D, match) -> None:
    with pytest.raises(AssumptionError, match=match):
        uio_decoupling(A, C, D)


def test_hypothesis5_violations() -> None:
    A = np.array([[0.0, 1.0], [0.0, 1.0]])
    C = np.array([[1.0, 0.0]])
    D = np.array([[1.0], [0.0]])
    with pytest.raises(AssumptionError, match="detectable"):
        uio_decoupling(A, C, D)
    with pytest.raises(AssumptionError, match="I_p"):
        uio_decoupling(-np.eye(2), C, D, W=np.array([[-1.0], [0.0]]))
