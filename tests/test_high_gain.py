"""Theorem 4.4 (theta design) read as printed and as sound, and what theta does to an Euler scheme."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs.design.high_gain import euler_radius_factor, theta_design
from intervalobs.design.regions import modal_decomposition
from intervalobs.errors import DimensionError
from intervalobs.examples import hgio as example

L1 = np.array(example.PAPER["L1"])[:, None]


@pytest.fixture(scope="module")
def printed() -> object:
    modal = modal_decomposition(example.A, example.C, L1, order=[d.center for d in example.DISKS])
    return theta_design(
        modal, L1, example.C, [0.1, 1, 1], [0.1], example.ALPHA_D, example.ALPHA_N, paper_v1=example.PAPER["v1"]
    )


def test_paper_alpha_depends_on_the_phase_of_v1() -> None:
    """(43) takes the complex log of v1 d^r: with the canonical phase (v1 = -printed here) it is another α."""
    modal = modal_decomposition(example.A, example.C, L1, order=[d.center for d in example.DISKS])
    canonical = theta_design(modal, L1, example.C, [0.1, 1, 1], [0.1], example.ALPHA_D, example.ALPHA_N)
    assert canonical.alpha_paper == pytest.approx(9.767, abs=1e-3)  # quoted in docs/paper-notes.md
    assert canonical.mat_abscissa_paper == pytest.approx(8.27, abs=5e-3)
    rotated = theta_design(
        modal, L1, example.C, [0.1, 1, 1], [0.1], example.ALPHA_D, example.ALPHA_N, paper_v1=-1j * modal.v1
    )
    assert rotated.theta_sound == canonical.theta_sound  # the sound reading uses moduli only
    with pytest.raises(DimensionError, match="paper_v1"):
        theta_design(modal, L1, example.C, [0.1, 1, 1], [0.1], example.ALPHA_D, example.ALPHA_N, paper_v1=[[1.0]])


def test_paper_alpha_needs_the_modulus_of_a_negative_log(printed: object) -> None:
    design = printed
    assert design.lambda_min_M2 == pytest.approx(-1.0, abs=1e-6)  # type: ignore[attr-defined]
    assert design.alpha_paper == pytest.approx(example.PAPER["alpha"], abs=2e-4)  # type: ignore[attr-defined]
    assert design.theta_paper == pytest.approx(example.PAPER["theta"], abs=2e-4)  # type: ignore[attr-defined]


def test_condition_34_fails_at_t0_and_35_is_not_hurwitz(printed: object) -> None:
    design = printed
    assert np.all(design.condition34_at_0 > example.ALPHA_D)  # type: ignore[attr-defined]
    assert design.condition34_at_0[0] == pytest.approx(1.60, abs=5e-3)  # type: ignore[attr-defined]
    assert design.mat_abscissa_paper == pytest.approx(7.26, abs=0.01)  # type: ignore[attr-defined]
    assert design.theta_sound == pytest.approx(np.log(1.5996 / 0.08), abs=1e-3)  # type: ignore[attr-defined]
    assert design.radius_abscissa < 0  # type: ignore[attr-defined]


def test_euler_radius_factor() -> None:
    assert euler_radius_factor(-0.5, 0.0, 1e-3) == pytest.approx(1.0, rel=1e-9)
    assert euler_radius_factor(-0.5, 9.7586, 1e-3) < 0.92  # Euler bounds too narrow: unsound
    assert euler_radius_factor(-0.5, 1000.0, 1e-3) < 0.01
