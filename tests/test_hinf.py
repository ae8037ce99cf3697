"""H∞ / zonotope-size LMI gains of seed 002: the paper's constants where they are right, errors otherwise."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs.design.hinf import gain_properties, hinf_gain, hinf_norm, monotone_gain_exists, zonotope_size_gain
from intervalobs.errors import AssumptionError, DesignError
from intervalobs.examples import numerical3, two_tank


def args(system):  # type: ignore[no-untyped-def]
    return system.A, system.C, system.E, system.F


def test_monotone_design_reproduces_printed_interval_gain_of_68() -> None:
    design = hinf_gain(*args(numerical3.system("68")), monotone=True)
    np.testing.assert_allclose(design.gain.ravel(), [0.3, 0.2, 0.8], atol=1e-4)
    assert design.gamma == pytest.approx(6.44, abs=0.01)
    assert design.monotone and design.min_entry >= 0.0
    assert design.hinf_norm <= design.gamma * (1 + 1e-4)
    assert design.spectral_radius < 1


def test_monotone_design_of_70_is_impossible() -> None:
    system = numerical3.system("70")
    ok, reason = monotone_gain_exists(system.A, system.C)
    assert not ok and "column 1" in reason
    with pytest.raises(AssumptionError, match=r"A\[0,1\] = -0.1"):
        hinf_gain(*args(system), monotone=True)


def test_printed_full_p_form_does_not_imply_monotonicity() -> None:
    design = hinf_gain(*args(numerical3.system("70")), monotone=True, p_structure="full")
    np.testing.assert_allclose(design.gain.ravel(), [0.173, 0.046, 0.663], atol=2e-3)
    assert not design.monotone
    assert design.min_entry == pytest.approx(-0.1)


def test_hinf_gain_is_verified() -> None:
    design = hinf_gain(*args(numerical3.system("68")))
    assert design.gamma is not None and design.hinf_norm <= design.gamma * (1 + 1e-4)
    assert design.extra["lmi_max_eig"] < 0
    assert design.spectral_radius < 1


def test_zonotope_size_gain_contracts_as_rho_says() -> None:
    for rho in (0.9, 0.99):
        design = zonotope_size_gain(*args(numerical3.system("68")), rho=rho)
        assert design.spectral_radius < np.sqrt(rho)
        assert design.extra["lmi_min_eig"] > -1e-6
    with pytest.raises(DesignError, match="rho"):
        zonotope_size_gain(*args(numerical3.system("68")), rho=1.5)


def test_printed_tank_gains() -> None:
    system = two_tank.system()
    radius = 0.5 * (system.dA[1] - system.dA[0])  # type: ignore[index]
    printed = {k: np.reshape(v, (2, 1)) for k, v in two_tank.PRINTED_GAINS.items()}
    hinf = gain_properties(system.A, system.C, printed["set_based_(19)"], radius)
    assert hinf["abs_spectral_radius"] == pytest.approx(1.000014, abs=2e-6)
    monotone = gain_properties(system.A, system.C, printed["interval_(54)-(55)"])
    assert not monotone["monotone"] and monotone["min_entry"] == pytest.approx(-0.001)
    ours = hinf_gain(*args(system), monotone=True)
    assert ours.monotone and ours.gain[0, 0] == 0.0
    # the (70) set-based gain of Fig. 3 is unstable; flipping L3 makes it stable
    a70 = numerical3.system("70")
    bad = gain_properties(a70.A, a70.C, np.array([[-1.1376], [-1.9167], [-1.2604]]))
    assert bad["spectral_radius"] == pytest.approx(2.07, abs=0.01)
    flipped = gain_properties(a70.A, a70.C, np.array([[-1.1376], [-1.9167], [1.2604]]))
    assert flipped["spectral_radius"] == pytest.approx(0.807, abs=0.001)


def test_infeasible_and_bad_arguments() -> None:
    a = np.diag([1.5, 0.5])  # unstable mode that C does not see: no stabilising gain
    c = np.array([[0.0, 1.0]])
    # Which check fails first (no solution, P or the Lyapunov block not definite) depends on the solver's last iterate.
    with pytest.raises(DesignError, match=r"\(19\)"):
        hinf_gain(a, c, np.eye(2), np.eye(1))
    with pytest.raises(DesignError, match="p_structure"):
        hinf_gain(np.eye(2) * 0.5, c, np.eye(2), np.eye(1), p_structure="block")  # type: ignore[arg-type]
    assert hinf_norm(a, np.eye(2)) == float("inf")
