r"""The constants of the unknown-input interval observer's exact step, with their rounding budget (the aircraft UIO
paper).

The observer of :mod:`intervalobs.observers.unknown_input` runs, in the coordinates
:math:`w = T(x + E\psi)`, the exact step

.. math:: w_{k+1} = e^{Mh}w_k + \int_0^h e^{M(h-s)}\big(TL\,\psi(t_k+s) + TPB\,u(t_k+s)
          + TPE_\omega w_{\text{noise}}(t_k+s)\big)\,ds

with :math:`M` Metzler and Hurwitz. :func:`uio_step_constants` computes once, at design time, the
nonnegative integrals of that step (:math:`\Phi = e^{Mh}`, :math:`\Gamma`, :math:`\Gamma_0`,
:math:`\Gamma_1`, :math:`\Gamma_r`: module docstring of the observer), the maps of the state and
input bounds, and an entrywise bound of every rounding-level departure of the computed matrices from
the exact model (the "rounding budget"), which the observer adds outward. See the observer's module
docstring for the argument (the aircraft UIO paper, eqs. (11), (14)–(15), (25), (31), (36)–(37)).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import expm

from ..errors import DesignError
from ..interval import ROUNDING_MARGIN, matvec_bounds
from ..systems.bounds import ResolvedBounds
from ..systems.lti import LTISystem
from .uio import UIOCoordinates, UIODecoupling

__all__ = ["UIOStepConstants", "uio_step_constants"]

FloatArray = NDArray[np.float64]

UNIT_ROUNDOFF = np.finfo(float).eps / 2
"""The unit roundoff u of binary64."""


@dataclass(frozen=True)
class UIOStepConstants:
    r"""Design-time constants of the observer's recursion (all arrays are read-only by convention).

    ``*_mag`` matrices are magnitudes plus rounding bound / ``ROUNDING_MARGIN``, which the observer's
    output margin multiplies; ``d*`` are entrywise bounds of a computed matrix's rounding.

    Parameters
    ----------
    Phi : numpy.ndarray, shape (n, n)
        :math:`e^{Mh}` (nonnegative).
    Gam : numpy.ndarray, shape (n, n)
        :math:`\Gamma = \int_0^h e^{M\sigma}d\sigma`.
    G0, G1 : numpy.ndarray, shape (n, n)
        Weights of :math:`\psi_k` and :math:`\psi_{k+1}` in the step.
    G_mag : numpy.ndarray, shape (n, n)
        Magnitude of the forcing's weights (with the exponential's error).
    dPhi : numpy.ndarray, shape (n, n)
        Entrywise bound of :math:`|\Phi_{computed} - \Phi|`.
    v : numpy.ndarray, shape (n,)
        Majorant direction of the rounding recursion.
    rho : float
        Its rate: :math:`(\Phi + \delta\Phi) v \le \rho v`.
    TL, TPB, TE, CB : numpy.ndarray
        The products :math:`TL`, :math:`TPB`, :math:`TE`, :math:`CB`.
    noise_lo, noise_hi, noise_mag : numpy.ndarray, shape (n,)
        Bounds and magnitude of :math:`TPE_\omega w`.
    const_pad : numpy.ndarray, shape (n,)
        Pad per step: the chord's remainder and the leak of :math:`\xi` through :math:`PD \approx 0`.
    input_remainder : numpy.ndarray, shape (n, m)
        Pad per step and unit input radius: :math:`\Gamma_r|TL|\,4|CB|/h`.
    offdiag : numpy.ndarray, shape (n, n)
        Bound of :math:`|TNT^{-1} - M|`.
    grid : numpy.ndarray, shape (n, n)
        :math:`2|M|\tau`: departure of :math:`e^{Mh_k}` from :math:`\Phi` per unit :math:`|w|`.
    dS : float
        Entrywise bound of :math:`|T^{-1} - S|`.
    delta_lo, delta_hi : numpy.ndarray, shape (p,)
        Bounds of the measurement noise :math:`\delta = Fv`.
    Mw, Mpsi : numpy.ndarray
        Maps of :math:`w` and :math:`\psi` in the unknown-input bound.
    xi_noise_lo, xi_noise_hi, xi_noise_mag : numpy.ndarray, shape (q,)
        Bounds and magnitude of the process noise's term in it.
    xi_pad : numpy.ndarray, shape (q,)
        The leak :math:`(I - M_0CD)\xi` with :math:`|\xi|` bounded by ``input_magnitude``.
    M0CA_abs : numpy.ndarray, shape (q, n)
        :math:`|M_0CA|`.
    TL_mag, TE_mag, Mw_mag, Mpsi_mag, TPB_mag : numpy.ndarray
        Magnitude matrices of the rounding pads.

    References
    ----------
    The aircraft UIO paper: the unknown-input bound (36)–(37).
    """

    Phi: FloatArray
    Gam: FloatArray
    G0: FloatArray
    G1: FloatArray
    G_mag: FloatArray
    dPhi: FloatArray
    v: FloatArray
    rho: float
    TL: FloatArray
    TPB: FloatArray
    TE: FloatArray
    CB: FloatArray
    noise_lo: FloatArray
    noise_hi: FloatArray
    noise_mag: FloatArray
    const_pad: FloatArray
    input_remainder: FloatArray
    offdiag: FloatArray
    grid: FloatArray
    dS: float
    delta_lo: FloatArray
    delta_hi: FloatArray
    Mw: FloatArray
    Mpsi: FloatArray
    xi_noise_lo: FloatArray
    xi_noise_hi: FloatArray
    xi_noise_mag: FloatArray
    xi_pad: FloatArray
    M0CA_abs: FloatArray
    TL_mag: FloatArray
    TE_mag: FloatArray
    Mw_mag: FloatArray
    Mpsi_mag: FloatArray
    TPB_mag: FloatArray


@dataclass(frozen=True)
class _StepIntegrals:
    """The nonnegative integrals of one exact step of :math:`\\dot w = Mw + f` and the expm error allowance."""

    Phi: FloatArray  # e^{Mh}
    Gam: FloatArray  # ∫_0^h e^{Mσ} dσ
    G0: FloatArray  # Γ - Γ_1: weight of the forcing's value at t_k
    G1: FloatArray  # ∫_0^h e^{M(h-s)} s/h ds: weight of its value at t_{k+1}
    remainder: FloatArray  # Γ_r = ∫_0^h e^{M(h-s)} s(h-s)/2 ds: weight of the chord's deviation
    expm_err: float  # relative error allowed for every computed exponential


def _step_integrals(mm: FloatArray, h: float) -> _StepIntegrals:
    """Φ, Γ, Γ_0, Γ_1, Γ_r from one exponential of a block matrix (φ-functions of :math:`Mh`)."""
    n = mm.shape[0]
    # top block row of expm([[Mh, I, 0, 0], [0, 0, I, 0], [0, 0, 0, I], 0]) = (e^{Mh}, φ1, φ2, φ3)(Mh)
    big = np.zeros((4 * n, 4 * n))
    big[:n, :n] = mm * h
    for i in range(3):
        big[i * n : (i + 1) * n, (i + 1) * n : (i + 2) * n] = np.eye(n)
    top = expm(big)[:n]
    phi, phi1, phi2, phi3 = (top[:, i * n : (i + 1) * n] for i in range(4))
    # exact values are nonnegative (M Metzler); clipping a rounding-level negative entry only moves it
    # towards the exact value, whose distance stays bounded by the expm error below
    gam = np.maximum(h * phi1, 0.0)
    g1 = np.maximum(h * phi2, 0.0)
    # expm (scaling and squaring, Padé) of a small well-scaled matrix: error a few ulps of its norm;
    # we allow 64 n u of the largest entry of each matrix
    return _StepIntegrals(
        Phi=np.maximum(phi, 0.0),
        Gam=gam,
        G0=np.maximum(gam - g1, 0.0),
        G1=g1,
        remainder=np.maximum(h**3 * (phi2 - 2 * phi3) / 2, 0.0),
        expm_err=64 * n * UNIT_ROUNDOFF,
    )


def _rounding_majorant(mm: FloatArray, phi: FloatArray, d_phi: FloatArray) -> tuple[FloatArray, float]:
    """Direction v > 0 and rate ρ < 1 with :math:`(\\Phi + \\delta\\Phi) v \\le \\rho v` (v = -M⁻¹1, scaled)."""
    n = mm.shape[0]
    v = np.linalg.solve(-mm, np.ones(n))
    if np.any(v <= 0):
        raise DesignError(f"coords: expected -M⁻¹1 > 0 for a Metzler Hurwitz M, got {v}")
    v = v / v.max()
    rho = float(np.max((phi @ v + d_phi @ v) / v)) * (1 + 4 * (n + 2) * UNIT_ROUNDOFF)
    if not rho < 1:
        raise DesignError(f"h: expected e^(Mh) v <= ρ v with ρ < 1, got ρ = {rho!r}")
    return v, rho


def _inverse_error(t: FloatArray, s: FloatArray, g_: float) -> float:
    """Entrywise bound of :math:`|T^{-1} - S|` for the computed inverse S, from the residual :math:`I - ST`."""
    n = t.shape[0]
    resid = np.abs(np.eye(n) - s @ t) + g_ * np.abs(s) @ np.abs(t)
    r_norm = float(resid.sum(axis=1).max())
    if r_norm >= 0.5:
        raise DesignError(f"T: expected a well-conditioned coordinate change, got ||I - T⁻¹T|| = {r_norm:.3g}")
    return r_norm / (1 - r_norm) * float(np.abs(s).sum(axis=1).max())


def uio_step_constants(
    system: LTISystem,
    bounds: ResolvedBounds,
    D: FloatArray,
    h: float,
    decoupling: UIODecoupling,
    coords: UIOCoordinates,
    output_accel: FloatArray,
    input_magnitude: float,
    step_tolerance: float,
) -> UIOStepConstants:
    """The constants of the observer's exact step and the entrywise bounds of their rounding.

    The exact model is defined by the float matrices ``T, E, K, C, A, D, B`` and :math:`(CD)^\\dagger`;
    every other matrix is computed, and ``|computed - exact|`` is bounded entrywise by ``g`` times the
    sum of the products' magnitudes (``g`` generously above ``n u``), propagated through each product.
    Terms named ``d*`` are such bounds; the ``*_mag`` matrices carry them into the magnitude that the
    observer's output margin multiplies.

    Parameters
    ----------
    system : LTISystem
        The continuous-time model (point ``A``).
    bounds : ResolvedBounds
        Its noise boxes.
    D : numpy.ndarray, shape (n, q)
        Unknown-input matrix.
    h : float
        Sampling period.
    decoupling : UIODecoupling
        ``E``, ``P``, ``M0`` of the decoupling and the unknown-input bound.
    coords : UIOCoordinates
        ``K``, ``L``, ``N``, ``T``, ``S``, ``M``, ``J`` of the cooperative error coordinates.
    output_accel : numpy.ndarray, shape (p,)
        Bound ``L`` of the output acceleration without the known input's direct term.
    input_magnitude : float
        Bound of ``|ξ|`` for the rounding-level leak through ``PD ≈ 0``.
    step_tolerance : float
        Largest deviation of a sampling step from ``h``.

    Returns
    -------
    UIOStepConstants

    Raises
    ------
    DesignError
        If the coordinate change is ill-conditioned or the rounding recursion does not contract.

    References
    ----------
    The aircraft UIO paper: (11), (25), (36); Hypothesis 6.
    """
    n, q = system.n, D.shape[1]
    mm = coords.M
    step = _step_integrals(mm, h)
    Phi, Gam, Grem, expm_err = step.Phi, step.Gam, step.remainder, step.expm_err
    dPhi = np.full((n, n), expm_err * float(Phi.max()))
    G_mag = np.maximum(np.abs(step.G0), np.abs(step.G1)) + expm_err * float(Gam.max()) / ROUNDING_MARGIN
    T, S = coords.T, coords.S
    absT, absS = np.abs(T), np.abs(S)
    g_ = 8 * (n + system.p + q + system.m) * UNIT_ROUNDOFF
    absE, absC, absA, absK, absN = (np.abs(m) for m in (decoupling.E, system.C, system.A, coords.K, coords.N))
    absP = np.abs(decoupling.P)
    dP = g_ * (1 + absE @ absC)
    dN = g_ * (absP @ absA + absK @ absC) + dP @ absA
    TL = T @ coords.L
    TP = T @ decoupling.P
    TPB = TP @ system.B
    TPE = TP @ system.E
    dS = _inverse_error(T, S, g_)
    dTL = g_ * (absT @ absK + absT @ absN @ absE) + absT @ dN @ absE
    dTPE = g_ * absT @ absP @ np.abs(system.E) + absT @ dP @ np.abs(system.E)
    dTPB = g_ * absT @ absP @ np.abs(system.B) + absT @ dP @ np.abs(system.B)
    w_lo, w_hi = bounds.w
    noise_lo, noise_hi = matvec_bounds(TPE, w_lo, w_hi)
    w_mag = np.maximum(np.abs(w_lo), np.abs(w_hi))
    delta_lo, delta_hi = matvec_bounds(system.F, *bounds.v)
    # deviation of ψ from its chord: |r| <= (L + 4|CB| u_r / h) s(h - s)/2 (module docstring)
    TL_abs = np.abs(TL) + dTL
    remainder = Grem @ TL_abs @ output_accel
    CB = system.C @ system.B
    input_remainder = Grem @ TL_abs @ (np.abs(CB) + g_ * absC @ np.abs(system.B)) * (4 / h)
    # PD is 0 only to rounding: the leak T P D ξ, with |ξ| <= input_magnitude
    pd = np.abs(decoupling.P @ D) + g_ * absP @ np.abs(D) + dP @ np.abs(D)
    leak = Gam @ absT @ pd @ np.full(q, input_magnitude)
    const_pad = (remainder + leak) * (1 + 1e-9) + expm_err * float(Grem.max()) * TL_abs.sum(axis=1) * (
        output_accel.max(initial=0.0)
    )
    # J = T N T⁻¹ - M (rounding-level departures), exact T⁻¹ = S + ΔS, |ΔS| <= dS
    offdiag = (
        np.abs(coords.J - mm)
        + g_ * absT @ absN @ absS
        + absT @ dN @ absS
        + (absT @ absN).sum(axis=1, keepdims=True) * dS
    )
    v, rho = _rounding_majorant(mm, Phi, dPhi)
    xi = _input_map(system, D, decoupling, S, g_, w_lo, w_hi, w_mag, input_magnitude)
    return UIOStepConstants(
        Phi=Phi, Gam=Gam, G0=step.G0, G1=step.G1, G_mag=G_mag, dPhi=dPhi, v=v, rho=rho,
        TL=TL, TPB=TPB, TE=T @ decoupling.E, CB=CB,
        noise_lo=noise_lo, noise_hi=noise_hi, noise_mag=(np.abs(TPE) + dTPE / ROUNDING_MARGIN) @ w_mag,
        const_pad=const_pad, input_remainder=input_remainder, offdiag=offdiag,
        grid=2 * np.abs(mm) * step_tolerance, dS=dS, delta_lo=delta_lo, delta_hi=delta_hi,
        TL_mag=np.abs(TL) + dTL / ROUNDING_MARGIN, TE_mag=absT @ absE,
        TPB_mag=np.abs(TPB) + dTPB / ROUNDING_MARGIN, Mw=xi.Mw, Mpsi=xi.Mpsi, Mw_mag=xi.Mw_mag,
        Mpsi_mag=xi.Mpsi_mag, xi_noise_lo=xi.noise_lo, xi_noise_hi=xi.noise_hi, xi_noise_mag=xi.noise_mag,
        xi_pad=xi.pad, M0CA_abs=xi.M0CA_abs,
    )  # fmt: skip


@dataclass(frozen=True)
class _InputMap:
    """ξ = M0 g + Mw w + Mψ ψ + Mv w_noise (36)–(37) with the magnitudes and pads of its rounding."""

    Mw: FloatArray
    Mpsi: FloatArray
    Mw_mag: FloatArray
    Mpsi_mag: FloatArray
    noise_lo: FloatArray
    noise_hi: FloatArray
    noise_mag: FloatArray
    pad: FloatArray  # the leak (I - M0 C D) ξ, with |ξ| <= input_magnitude
    M0CA_abs: FloatArray


def _input_map(
    system: LTISystem,
    D: FloatArray,
    decoupling: UIODecoupling,
    S: FloatArray,
    g_: float,
    w_lo: FloatArray,
    w_hi: FloatArray,
    w_mag: FloatArray,
    input_magnitude: float,
) -> _InputMap:
    """The maps of the unknown-input bound (36)–(37) in the w-coordinates, with their rounding terms."""
    absC, absA, absS, absE = np.abs(system.C), np.abs(system.A), np.abs(S), np.abs(decoupling.E)
    m0 = decoupling.M0
    m0ca = m0 @ system.C @ system.A
    d_m0ca = g_ * np.abs(m0) @ absC @ absA
    Mw = -m0ca @ S
    Mpsi = m0ca @ decoupling.E
    Mv = -m0 @ system.C @ system.E
    xi_noise_lo, xi_noise_hi = matvec_bounds(Mv, w_lo, w_hi)
    leak_xi = np.abs(np.eye(D.shape[1]) - m0 @ system.C @ D) + g_ * np.abs(m0) @ absC @ np.abs(D)
    return _InputMap(
        Mw=Mw,
        Mpsi=Mpsi,
        Mw_mag=np.abs(Mw) + (d_m0ca @ absS + g_ * np.abs(m0ca) @ absS) / ROUNDING_MARGIN,
        Mpsi_mag=np.abs(Mpsi) + (d_m0ca @ absE + g_ * np.abs(m0ca) @ absE) / ROUNDING_MARGIN,
        noise_lo=xi_noise_lo,
        noise_hi=xi_noise_hi,
        noise_mag=(np.abs(Mv) + g_ * np.abs(m0) @ absC @ np.abs(system.E) / ROUNDING_MARGIN) @ w_mag,
        pad=leak_xi @ np.full(D.shape[1], input_magnitude),
        M0CA_abs=np.abs(m0ca),
    )
