r"""Unknown-input interval observer for uncertain continuous-time LTI systems (seed 000).

Model (seed 000, eq. (1), with the noise matrices of :class:`~intervalobs.systems.LTISystem`):

.. math:: \dot x = Ax + Bu + D\xi + E_\omega w, \qquad y = Cx + Fv, \qquad \psi = Cx,

:math:`\xi` unknown and unbounded, :math:`w, v` in boxes, the measurement noise smooth
(:math:`|\dot v| \le \bar{\dot v}`) and :math:`|\ddot\psi| \le L` (the assumption of Levant's
differentiator, seed 000, Theorem 3).

Observer (seed 000, eq. (15)) in the coordinates :math:`z = Tx` of Hypothesis 6, with the diagonal
:math:`J = TNT^{-1} = \Lambda` designed by :func:`~intervalobs.design.uio.design_uio_coordinates`.
Equation (15) contains :math:`-TE\dot y`; we integrate it *exactly* by writing
:math:`w = z + TE\psi = T(x + E\psi)`, for which (using :math:`PD = 0`, :math:`K = L + NE`, eq. (14))

.. math:: \dot w = \Lambda w + TL\,\psi + TPB\,u + TPE_\omega w_{\text{noise}},
          \qquad x = T^{-1}w - E\psi .

No output derivative enters the state bounds, so they hold from :math:`t_0` (no HOSM transient).
Between samples :math:`\psi` is the linear interpolation of its sample boxes plus a remainder
:math:`|r| \le L h^2/8`; because :math:`\Lambda` is diagonal with :math:`e^{\lambda_i h} > 0`, each
component of the bounds obeys an exact scalar recursion

.. math:: \overline w_{i,k+1} = e^{\lambda_i h}\overline w_{i,k} + \overline g_{i,k},

where :math:`\overline g` bounds the exact input integral over the step (every admissible noise
signal inside the step is covered, not only held ones). The whole record is evaluated with
``scipy.signal.lfilter``, one call per component, vectorised over Monte Carlo runs.

State bounds (31): :math:`x \in T^{-1}[w] - E[\psi]` (the exact hull, not through the z-box).
Unknown-input bounds (36)–(37): with :math:`M_0 = (CD)^\dagger`,
:math:`\xi = M_0\dot\psi - M_0CA\,T^{-1}w + M_0CAE\,\psi - M_0CBu - M_0CE_\omega w_{\text{noise}}`,
bounded from the derivative enclosure of :mod:`~intervalobs.design.differentiator` (``"difference"``:
provable, from the first sample on; ``"hosm"``: Levant's differentiator with the paper's bound
:math:`\beta = \bar{\dot\delta} + \mu_1\bar\delta^{1/2}`, claimed only after ``hosm_transient``).

Floating point: every rounding-level departure from the exact model (the float ``T`` only nearly
diagonalises ``N``; ``T⁻¹`` is computed; ``PD`` and ``I - M_0CD`` are ~1e-16 rather than 0, which leaks a
fraction of :math:`\xi` bounded with ``input_magnitude``; the time grid deviates from the nominal step
by at most ``step_tolerance``; the recursion itself rounds) is bounded explicitly and added outward,
through a second ``lfilter`` recursion for the state-dependent parts.

Step semantics (current output): ``init`` returns the prior box; ``step(state, y_k, u_k)`` consumes the
measurement of the *next* sample and returns the box at that sample given ``y_0 … y_k`` (the first call
consumes ``y_0`` and returns the prior box at ``t_0``). Row ``k`` of :meth:`run` equals the box after the
``(k+1)``-th ``step`` call. Known inputs (B) are not supported (see the constructor).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import expm
from scipy.signal import lfilter

from ..design.differentiator import (
    HOSMDifferentiator,
    difference_pair_bounds,
    hosm_error_bound,
)
from ..design.uio import (
    UIOCoordinates,
    UIODecoupling,
    check_cooperative,
    design_uio_coordinates,
    uio_decoupling,
)
from ..errors import BoundsError, DataError, DesignError, DimensionError
from ..estimate import Estimate
from ..interval import ROUNDING_MARGIN, matvec_bounds
from ..systems.lti import Bounds, LTISystem
from ..validation import as_box, as_matrix, as_vector
from .base import SPACING_TOLERANCE, Observer, ObserverState

__all__ = ["UnknownInputIntervalObserver"]

FloatArray = NDArray[np.float64]

_U = np.finfo(float).eps / 2
_RECURSION_ROUNDING = 8 * _U
_STEP_TOLERANCE = SPACING_TOLERANCE  # the deviation run() accepts; the bounds account for it


def _rmul(x: FloatArray, m: FloatArray) -> FloatArray:
    """``x @ m.T`` over leading axes, by einsum: no BLAS call, so no thread oversubscription on (T, n) records."""
    return np.asarray(np.einsum("...j,ij->...i", x, m))


@dataclass(frozen=True)
class _Precomputed:
    """Design-time constants of the recursion (all arrays are read-only by convention)."""

    a: FloatArray  # e^{λ h}
    b: FloatArray  # ∫_0^h e^{λ r} dr
    c_start: FloatArray  # weight of ψ_k
    c_end: FloatArray  # weight of ψ_{k+1}
    TL: FloatArray
    TPB: FloatArray
    TE: FloatArray
    noise_lo: FloatArray  # bounds of T P E_ω w
    noise_hi: FloatArray
    noise_mag: FloatArray
    const_pad: FloatArray  # per step: remainder + ξ leak
    offdiag: FloatArray  # |J_exact - Λ| bound
    dS: float  # entrywise bound of |T⁻¹ - S|
    delta_lo: FloatArray  # bounds of δ = F v
    delta_hi: FloatArray
    Mw: FloatArray
    Mpsi: FloatArray
    Mu: FloatArray
    xi_noise_lo: FloatArray
    xi_noise_hi: FloatArray
    xi_noise_mag: FloatArray
    xi_pad: FloatArray
    M0CA_abs: FloatArray
    TL_mag: FloatArray  # magnitude matrices for the rounding pads (|M| + rounding bound / margin)
    TE_mag: FloatArray
    Mw_mag: FloatArray
    Mpsi_mag: FloatArray


class UnknownInputIntervalObserver(Observer):
    """Interval observer of the state and of the unknown input ξ (seed 000, eqs. (15), (31), (37)).

    Build it with :meth:`design`; see the module docstring for the equations and step semantics.

    Parameters
    ----------
    system : LTISystem
        Continuous-time model with a point matrix ``A``.
    bounds : Bounds
        Prior box of ``x(t_0)`` and noise boxes.
    D : array_like, shape (n, q)
        Unknown-input matrix.
    h : float
        Sampling period.
    decoupling : UIODecoupling
        From :func:`~intervalobs.design.uio.uio_decoupling`.
    coords : UIOCoordinates
        Gain and diagonalising coordinates (Hypothesis 6).
    noise_rate : array_like, shape (nv,)
        Bound of ``|dv/dt|``.
    output_accel : array_like, shape (p,)
        Bound ``L`` of ``|d²ψ/dt²|``.
    derivative : {"difference", "hosm"}
        Derivative enclosure for the unknown-input bounds.
    hosm : HOSMDifferentiator, optional
        Differentiator for ``derivative="hosm"``.
    mu1 : float
        ``µ_1`` of (8).
    hosm_transient : float
        Time after which the HOSM bound is claimed.
    input_magnitude : float
        Bound of ``|ξ|`` for the rounding-level leak through ``PD ≈ 0``.

    Attributes
    ----------
    system : LTISystem
        The continuous-time model (``A``, ``B``, ``C``, ``E`` = noise matrix of ``w``, ``F``).
    D : numpy.ndarray, shape (n, q)
        Unknown-input matrix.
    decoupling : UIODecoupling
        ``E``, ``P`` of (11), (25).
    coords : UIOCoordinates
        ``K``, ``T`` of Hypothesis 6.
    h : float
        Sampling period.
    derivative : str
        ``"difference"`` or ``"hosm"``.
    transient_s : float
        Time after which the input bounds are claimed (state bounds hold from ``t_0``).
    rho_x, rho_xi : numpy.ndarray
        Asymptotic widths of the state and input bounds (eqs. (34), (48) for this observer).
    """

    h: float

    def __init__(
        self,
        system: LTISystem,
        bounds: Bounds,
        D: ArrayLike,
        h: float,
        decoupling: UIODecoupling,
        coords: UIOCoordinates,
        noise_rate: ArrayLike,
        output_accel: ArrayLike,
        derivative: Literal["difference", "hosm"] = "difference",
        hosm: HOSMDifferentiator | None = None,
        mu1: float = 1.1,
        hosm_transient: float = 1.0,
        input_magnitude: float = 1e6,
    ) -> None:
        if not system.continuous:
            raise DimensionError("system: expected a continuous-time LTISystem (dt=None), got a discrete-time one")
        if system.dA is not None:
            raise DimensionError("system: UnknownInputIntervalObserver supports a point matrix A only (dA=None)")
        if system.m > 0:
            raise DimensionError(
                f"system: expected no known input (B with 0 columns), got m = {system.m}. A held input makes "
                "dψ/dt jump at every sample, which breaks the |d²ψ/dt²| ≤ L assumption of the bounds; "
                "the paper's example has none"
            )
        self.system = system
        self.bounds = bounds.for_system(system)
        n, p = system.n, system.p
        self.n, self.p, self.m = n, p, system.m
        self.D = as_matrix("D", D, (n, None))
        self.q = self.D.shape[1]
        if not (np.isfinite(h) and h > 0):
            raise BoundsError(f"h: expected a positive sampling period, got {h!r}")
        self.h = float(h)
        self.step_tolerance = _STEP_TOLERANCE * self.h
        self.decoupling = decoupling
        self.coords = coords
        self.noise_rate = as_vector("noise_rate", noise_rate, system.nv)
        self.output_accel = as_vector("output_accel", output_accel, p)
        if np.any(self.noise_rate < 0) or np.any(self.output_accel < 0):
            raise BoundsError("noise_rate, output_accel: expected nonnegative bounds")
        if derivative not in ("difference", "hosm"):
            raise DimensionError(f"derivative: expected 'difference' or 'hosm', got {derivative!r}")
        if derivative == "hosm" and hosm is None:
            raise DimensionError("hosm: expected a HOSMDifferentiator when derivative='hosm'")
        if not (np.isfinite(input_magnitude) and input_magnitude >= 0):
            raise BoundsError(f"input_magnitude: expected a nonnegative bound of |ξ|, got {input_magnitude!r}")
        self.derivative = derivative
        self.hosm = hosm
        self.mu1 = float(mu1)
        self.input_magnitude = float(input_magnitude)
        self.transient_s = 0.0 if derivative == "difference" else float(hosm_transient)
        poles = coords.poles
        if np.any(poles >= 0):
            raise DesignError(f"coords: expected negative poles, got {poles}")
        self._c = self._precompute()
        self.rate_radius = np.abs(system.F) @ self.noise_rate
        self.beta = hosm_error_bound(
            0.5 * (self._c.delta_hi - self._c.delta_lo) + np.abs(0.5 * (self._c.delta_hi + self._c.delta_lo)),
            self.rate_radius,
            self.mu1,
        )
        self.rho_x, self.rho_xi = self._asymptotic_widths()

    # ------------------------------------------------------------------ design
    @classmethod
    def design(
        cls,
        system: LTISystem,
        bounds: Bounds,
        D: ArrayLike,
        h: float,
        *,
        noise_rate: ArrayLike,
        output_accel: ArrayLike,
        W: ArrayLike | None = None,
        poles: ArrayLike | None = None,
        K: ArrayLike | None = None,
        T: ArrayLike | None = None,
        derivative: Literal["difference", "hosm"] = "difference",
        hosm: HOSMDifferentiator | None = None,
        mu1: float = 1.1,
        hosm_transient: float = 1.0,
        input_magnitude: float = 1e6,
    ) -> UnknownInputIntervalObserver:
        """Check Hypotheses 4–6 and build the observer (seed 000, §4).

        Parameters
        ----------
        system : LTISystem
            Continuous-time model; its ``E`` maps the process noise ``w``, its ``F`` the measurement noise.
        bounds : Bounds
            Prior box of ``x(t_0)`` and the boxes of ``w`` and ``v``.
        D : array_like, shape (n, q)
            Unknown-input matrix.
        h : float
            Sampling period of the measurements (``Te``).
        noise_rate : array_like, shape (nv,)
            Bound of ``|dv/dt|`` (the paper's ``δ̇`` bound); the noise must be smooth.
        output_accel : array_like, shape (p,)
            Bound ``L`` of ``|d²ψ/dt²|`` (Levant's Lipschitz constant; ``λ_1 = 1.1 L``).
        W : array_like, shape (n, p), optional
            Free parameter of (11), default 0.
        poles : array_like, shape (n,), optional
            Real distinct negative poles of ``PA - KC`` (default: searched, see
            :func:`~intervalobs.design.uio.design_uio_coordinates`).
        K, T : array_like, optional
            A given gain (and coordinates), checked against Hypothesis 6; ``T (PA - KC) T⁻¹`` must be
            diagonal to rounding for this implementation.
        derivative : {"difference", "hosm"}
            Derivative enclosure used for the unknown-input bounds.
        hosm : HOSMDifferentiator, optional
            Differentiator for ``derivative="hosm"``.
        mu1 : float
            ``µ_1`` of (8) for ``derivative="hosm"``.
        hosm_transient : float
            Time after which the HOSM bound is claimed.
        input_magnitude : float
            A bound of ``|ξ|`` used only for the rounding-level leak through ``PD ≈ 0``.

        Returns
        -------
        UnknownInputIntervalObserver

        Raises
        ------
        AssumptionError
            Hypothesis 4, 5 or 6 fails.
        DesignError
            No suitable gain/coordinates, or given ``T`` does not diagonalise ``PA - KC``.
        """
        bounds = bounds.for_system(system)
        d = as_matrix("D", D, (system.n, None))
        decoupling = uio_decoupling(system.A, system.C, d, W)
        assert bounds.w is not None and bounds.v is not None
        omega_radius = np.abs(system.E) @ (0.5 * (bounds.w[1] - bounds.w[0]))
        delta_radius = np.abs(system.F) @ (0.5 * (bounds.v[1] - bounds.v[0]))
        if K is not None:
            coords = check_cooperative(system.A, system.C, decoupling, K, T)
            scale = max(1.0, float(np.abs(coords.J).max()))
            if coords.offdiagonal > 1e-9 * scale:
                raise DesignError(
                    "T: this observer needs T (PA - KC) T⁻¹ diagonal (real distinct poles, T = V⁻¹); "
                    f"got off-diagonal entries up to {coords.offdiagonal:.3g}; give T=None"
                )
        else:
            coords = design_uio_coordinates(system.A, system.C, decoupling, omega_radius, delta_radius, poles)
        return cls(
            system,
            bounds,
            d,
            h,
            decoupling,
            coords,
            noise_rate,
            output_accel,
            derivative=derivative,
            hosm=hosm,
            mu1=mu1,
            hosm_transient=hosm_transient,
            input_magnitude=input_magnitude,
        )

    def _precompute(self) -> _Precomputed:
        sys, dec, co = self.system, self.decoupling, self.coords
        h, n = self.h, self.n
        assert self.bounds.w is not None and self.bounds.v is not None
        lam = co.poles
        a = np.empty(n)
        b = np.empty(n)
        c_end = np.empty(n)
        for i, li in enumerate(lam):
            # first row of expm([[λh, 1, 0], [0, 0, 1], [0, 0, 0]]) = (e^{λh}, φ1(λh), φ2(λh))
            blk = np.array([[li * h, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 0.0]])
            row = expm(blk)[0]
            a[i], b[i], c_end[i] = row[0], h * row[1], h * row[2]
        if np.any(a <= 0) or np.any(a >= 1):
            raise DesignError(f"h: expected 0 < exp(λh) < 1, got {a}")
        c_start = b - c_end
        T, S = co.T, co.S
        absT, absS = np.abs(T), np.abs(S)
        # Rounding budget. The exact model is defined by the float matrices T, E, K, C, A, D, (CD)†;
        # every other matrix is computed, and |computed - exact| is bounded entrywise by g·(sum of
        # |products|) (g generously above n·u), propagated below. Terms named d* are such bounds;
        # "*_mag" matrices carry them into the magnitude that the output margin multiplies.
        g_ = 8 * (n + sys.p + self.q) * _U
        absE, absC, absA, absK, absN = np.abs(dec.E), np.abs(sys.C), np.abs(sys.A), np.abs(co.K), np.abs(co.N)
        absP = np.abs(dec.P)
        dP = g_ * (1 + absE @ absC)
        dN = g_ * (absP @ absA + absK @ absC) + dP @ absA
        TL = T @ co.L
        TP = T @ dec.P
        TPB = TP @ sys.B
        TPE = TP @ sys.E
        resid = np.abs(np.eye(n) - S @ T) + g_ * absS @ absT
        r_norm = float(resid.sum(axis=1).max())
        if r_norm >= 0.5:
            raise DesignError(f"T: expected a well-conditioned coordinate change, got ||I - T⁻¹T|| = {r_norm:.3g}")
        dS = r_norm / (1 - r_norm) * float(absS.sum(axis=1).max())  # entrywise bound of |T⁻¹ - S|
        dTL = g_ * (absT @ absK + absT @ absN @ absE) + absT @ dN @ absE
        dTPE = g_ * absT @ absP @ np.abs(sys.E) + absT @ dP @ np.abs(sys.E)
        w_lo, w_hi = self.bounds.w
        v_lo, v_hi = self.bounds.v
        noise_lo, noise_hi = matvec_bounds(TPE, w_lo, w_hi)
        w_mag = np.maximum(np.abs(w_lo), np.abs(w_hi))
        noise_mag = (np.abs(TPE) + dTPE / ROUNDING_MARGIN) @ w_mag
        delta_lo, delta_hi = matvec_bounds(sys.F, v_lo, v_hi)
        # remainder of the linear interpolation of ψ: ∫ e^{λ(h-s)} L s(h-s)/2 ds ≤ L h³/12
        remainder = (np.abs(TL) + dTL) @ self.output_accel * h**3 / 12
        # PD is 0 only to rounding: the leak T P D ξ, with |ξ| ≤ input_magnitude
        pd = np.abs(dec.P @ self.D) + g_ * absP @ np.abs(self.D) + dP @ np.abs(self.D)
        leak = absT @ pd @ np.full(self.q, self.input_magnitude) * b
        const_pad = (remainder + leak) * (1 + 1e-9)
        # J = T N T⁻¹ - Λ (off-diagonal and diagonal departures), exact T⁻¹ = S + ΔS, |ΔS| ≤ dS
        offdiag = (
            np.abs(co.J - np.diag(lam))
            + g_ * absT @ absN @ absS
            + absT @ dN @ absS
            + (absT @ absN).sum(axis=1, keepdims=True) * dS
        )
        m0 = dec.M0
        m0ca = m0 @ sys.C @ sys.A
        d_m0ca = g_ * np.abs(m0) @ absC @ absA
        Mw = -m0ca @ S
        Mpsi = m0ca @ dec.E
        Mu = -m0 @ sys.C @ sys.B
        Mv = -m0 @ sys.C @ sys.E
        Mw_mag = np.abs(Mw) + (d_m0ca @ absS + g_ * np.abs(m0ca) @ absS) / ROUNDING_MARGIN
        Mpsi_mag = np.abs(Mpsi) + (d_m0ca @ absE + g_ * np.abs(m0ca) @ absE) / ROUNDING_MARGIN
        xi_noise_lo, xi_noise_hi = matvec_bounds(Mv, w_lo, w_hi)
        xi_noise_mag = (np.abs(Mv) + g_ * np.abs(m0) @ absC @ np.abs(sys.E) / ROUNDING_MARGIN) @ w_mag
        leak_xi = np.abs(np.eye(self.q) - m0 @ sys.C @ self.D) + g_ * np.abs(m0) @ absC @ np.abs(self.D)
        xi_pad = leak_xi @ np.full(self.q, self.input_magnitude)
        return _Precomputed(
            a=a, b=b, c_start=c_start, c_end=c_end, TL=TL, TPB=TPB, TE=T @ dec.E,
            noise_lo=noise_lo, noise_hi=noise_hi, noise_mag=noise_mag, const_pad=const_pad,
            offdiag=offdiag, dS=dS, delta_lo=delta_lo, delta_hi=delta_hi,
            Mw=Mw, Mpsi=Mpsi, Mu=Mu, xi_noise_lo=xi_noise_lo, xi_noise_hi=xi_noise_hi,
            xi_noise_mag=xi_noise_mag, xi_pad=xi_pad, M0CA_abs=np.abs(m0ca),
            TL_mag=np.abs(TL) + dTL / ROUNDING_MARGIN, TE_mag=absT @ absE, Mw_mag=Mw_mag, Mpsi_mag=Mpsi_mag,
        )  # fmt: skip

    def _asymptotic_widths(self) -> tuple[FloatArray, FloatArray]:
        """Limits of the widths (eqs. (30), (34), (48) for this observer), rounding pads excluded."""
        c = self._c
        dw = self._c.delta_hi - self._c.delta_lo
        g_width = (c.c_start + c.c_end) * (np.abs(c.TL) @ dw) + c.b * (c.noise_hi - c.noise_lo) + 2 * c.const_pad
        rho_w = g_width / (1 - c.a)
        rho_x = np.abs(self.coords.S) @ rho_w + np.abs(self.decoupling.E) @ dw
        deriv = 2 * (self.rate_radius + 0.5 * self.output_accel * (self.h + self.step_tolerance))
        if self.derivative == "hosm":
            deriv = 2 * self.beta
        rho_xi = (
            np.abs(self.decoupling.M0) @ deriv
            + np.abs(c.Mw) @ rho_w
            + np.abs(c.Mpsi) @ dw
            + (c.xi_noise_hi - c.xi_noise_lo)
            + 2 * c.xi_pad
        )
        return np.asarray(rho_x), np.asarray(rho_xi)

    def paper_rho(self, zeta: ArrayLike | None = None) -> tuple[FloatArray, FloatArray]:
        r"""The paper's asymptotic bounds (30), (34), (48) with its ``ẏ``-based forcing (sign-corrected).

        :math:`\rho_z = -\Lambda^{-1}(2|TP|\bar\omega + 2|TK|\bar\delta + |TE|\bar\zeta)`,
        :math:`\rho_x = |T^{-1}|\rho_z`,
        :math:`\rho_\xi = |M_1|\rho_z + 2(|M_3|\bar\omega + (|M_0| + |M_4|)\bar{\dot\delta}
        + |M_0|\mu_1\bar\delta^{1/2})`, with :math:`\bar\zeta = 2(\bar{\dot\delta} + \mu_1\bar\delta^{1/2})`.

        Parameters
        ----------
        zeta : array_like, shape (p,), optional
            Bound of ζ in (29); default ``2 (δ̇ + µ1 δ^½)``.

        Returns
        -------
        rho_x, rho_xi : numpy.ndarray
        """
        c, co, dec = self._c, self.coords, self.decoupling
        omega_r = 0.5 * (c.noise_hi - c.noise_lo)  # already through |TPE|
        delta_r = 0.5 * (c.delta_hi - c.delta_lo)
        z = 2 * self.beta if zeta is None else as_vector("zeta", zeta, self.p)
        forcing = 2 * omega_r + 2 * np.abs(co.T @ co.K) @ delta_r + np.abs(co.T @ dec.E) @ z
        rho_z = forcing / np.abs(co.poles)
        rho_x = np.abs(co.S) @ rho_z
        m0 = dec.M0
        m1 = -m0 @ self.system.C @ self.system.A @ co.S
        m3 = -m0 @ self.system.C @ self.system.E
        assert self.bounds.w is not None
        w_r = 0.5 * (self.bounds.w[1] - self.bounds.w[0])
        rho_xi = np.abs(m1) @ rho_z + 2 * (
            np.abs(m3) @ w_r + 2 * np.abs(m0) @ self.rate_radius + np.abs(m0) @ (self.beta - self.rate_radius)
        )
        return np.asarray(rho_x), np.asarray(rho_xi)

    # ------------------------------------------------------------- building blocks
    def _psi_box(self, y: FloatArray) -> tuple[FloatArray, FloatArray]:
        return y - self._c.delta_hi, y - self._c.delta_lo

    def _tl_bounds(self, y: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Bounds of TLψ and the magnitude |TL||ψ|, for measurements ``y`` (..., p)."""
        plo, phi = self._psi_box(y)
        lo, hi = matvec_bounds(self._c.TL, plo, phi)
        mag = _rmul(np.maximum(np.abs(plo), np.abs(phi)), self._c.TL_mag)
        return lo, hi, mag

    def _forcing(
        self,
        tl0: tuple[FloatArray, FloatArray, FloatArray],
        tl1: tuple[FloatArray, FloatArray, FloatArray],
        u: FloatArray,
    ) -> tuple[FloatArray, FloatArray]:
        """Bounds of the exact input integral over one step (any leading axes)."""
        c = self._c
        tpbu = _rmul(u, c.TPB)
        base_hi = c.c_start * tl0[1] + c.c_end * tl1[1] + c.b * (c.noise_hi + tpbu)
        base_lo = c.c_start * tl0[0] + c.c_end * tl1[0] + c.b * (c.noise_lo + tpbu)
        mag = c.c_start * tl0[2] + c.c_end * tl1[2] + c.b * (c.noise_mag + _rmul(np.abs(u), np.abs(c.TPB)))
        pad = c.const_pad + (ROUNDING_MARGIN + 2 * self.step_tolerance / self.h) * mag
        return base_lo - pad, base_hi + pad

    def _pad_input(
        self, w_lo: FloatArray, w_hi: FloatArray, g_lo: FloatArray, g_hi: FloatArray, w_run: FloatArray
    ) -> FloatArray:
        """Per-step input of the rounding recursion (state-dependent departures from the exact model)."""
        c = self._c
        w_mag = np.maximum(np.abs(w_lo), np.abs(w_hi))
        g_mag = np.maximum(np.abs(g_lo), np.abs(g_hi))
        lam = np.abs(self.coords.poles)
        return (
            _RECURSION_ROUNDING * (w_mag + g_mag)
            + 2 * lam * self.step_tolerance * w_mag
            + c.b * _rmul(2 * w_run, c.offdiag)
        )

    def _initial_w(self, x_lo: FloatArray, x_hi: FloatArray, y0: FloatArray) -> tuple[FloatArray, FloatArray]:
        c = self._c
        plo, phi = self._psi_box(y0)
        a_lo, a_hi = matvec_bounds(self.coords.T, x_lo, x_hi)
        b_lo, b_hi = matvec_bounds(c.TE, plo, phi)
        mag = _rmul(np.maximum(np.abs(x_lo), np.abs(x_hi)), np.abs(self.coords.T))
        mag = mag + _rmul(np.maximum(np.abs(plo), np.abs(phi)), c.TE_mag)
        pad = ROUNDING_MARGIN * mag
        return a_lo + b_lo - pad, a_hi + b_hi + pad

    def _state_box(self, w_lo: FloatArray, w_hi: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
        """x = T⁻¹w - Eψ (eq. (31)), rounded outward."""
        c = self._c
        plo, phi = self._psi_box(y)
        s_lo, s_hi = matvec_bounds(self.coords.S, w_lo, w_hi)
        e_lo, e_hi = matvec_bounds(self.decoupling.E, plo, phi)
        w_mag = np.maximum(np.abs(w_lo), np.abs(w_hi))
        mag = _rmul(w_mag, np.abs(self.coords.S)) + _rmul(
            np.maximum(np.abs(plo), np.abs(phi)), np.abs(self.decoupling.E)
        )
        pad = ROUNDING_MARGIN * mag + c.dS * w_mag.sum(axis=-1, keepdims=True)
        return s_lo - e_hi - pad, s_hi - e_lo + pad

    def _input_box(
        self,
        w_lo: FloatArray,
        w_hi: FloatArray,
        y: FloatArray,
        u: FloatArray,
        d_lo: FloatArray,
        d_hi: FloatArray,
    ) -> tuple[FloatArray, FloatArray]:
        """ξ from (36)–(37) in the w-coordinates, rounded outward; NaN where the derivative box is."""
        c = self._c
        plo, phi = self._psi_box(y)
        a_lo, a_hi = matvec_bounds(self.decoupling.M0, d_lo, d_hi)
        b_lo, b_hi = matvec_bounds(c.Mw, w_lo, w_hi)
        e_lo, e_hi = matvec_bounds(c.Mpsi, plo, phi)
        mu = _rmul(u, c.Mu)
        w_mag = np.maximum(np.abs(w_lo), np.abs(w_hi))
        mag = (
            _rmul(np.maximum(np.abs(d_lo), np.abs(d_hi)), np.abs(self.decoupling.M0))
            + _rmul(w_mag, c.Mw_mag)
            + _rmul(np.maximum(np.abs(plo), np.abs(phi)), c.Mpsi_mag)
            + _rmul(np.abs(u), np.abs(c.Mu))
            + c.xi_noise_mag
        )
        pad = c.xi_pad + ROUNDING_MARGIN * mag + c.dS * (w_mag.sum(axis=-1, keepdims=True) * c.M0CA_abs.sum(axis=-1))
        lo = a_lo + b_lo + e_lo + mu + c.xi_noise_lo - pad
        hi = a_hi + b_hi + e_hi + mu + c.xi_noise_hi + pad
        return lo, hi

    def _derivative_pair(self, y_prev: FloatArray, y_now: FloatArray) -> tuple[FloatArray, FloatArray]:
        return difference_pair_bounds(y_prev, y_now, self.h, self.rate_radius, self.output_accel, self.step_tolerance)

    # ------------------------------------------------------------------ protocol
    def init(self, x0_lower: ArrayLike | None = None, x0_upper: ArrayLike | None = None) -> ObserverState:
        """Prior state at ``t_0`` (no measurement consumed yet).

        Parameters
        ----------
        x0_lower, x0_upper : array_like, shape (n,) or (M, n), optional
            Prior box of ``x(t_0)`` (default: the design bounds).

        Returns
        -------
        ObserverState
        """
        lo, hi = self._prior(x0_lower, x0_upper)
        return ObserverState(lo, hi, None, None, {"started": False})

    def _prior(self, x0_lower: ArrayLike | None, x0_upper: ArrayLike | None) -> tuple[FloatArray, FloatArray]:
        if x0_lower is None and x0_upper is None:
            return self.bounds.x0[0].copy(), self.bounds.x0[1].copy()
        if x0_lower is None or x0_upper is None:
            raise BoundsError("x0_lower, x0_upper: give both or neither")
        lo = np.array(x0_lower, dtype=float)
        hi = np.array(x0_upper, dtype=float)
        if lo.ndim == 1:
            lo, hi = as_box("x0", (lo, hi), self.n)
        elif lo.shape != hi.shape or lo.shape[-1] != self.n or np.any(lo > hi) or not np.all(np.isfinite(lo + hi)):
            raise BoundsError(f"x0: expected finite boxes of shape (..., {self.n}) with lower <= upper")
        return lo, hi

    def step(self, state: ObserverState, y: ArrayLike, u: ArrayLike | None = None) -> ObserverState:
        """Consume the next measurement ``y_k`` (and ``u_k``) and return the box at ``t_k``.

        Parameters
        ----------
        state : ObserverState
            From :meth:`init` or a previous :meth:`step`.
        y : array_like, shape (p,) or (M, p)
            Measurement at the next sample.
        u : array_like, shape (m,) or (M, m), optional
            Known input at that sample (held until the following one).

        Returns
        -------
        ObserverState
        """
        yk = np.asarray(y, dtype=float)
        if yk.shape[-1:] != (self.p,) or not np.all(np.isfinite(yk)):
            raise DataError(f"y: expected finite values of shape (..., {self.p}), got {yk.shape}")
        uk = self._input(u, yk.shape[:-1])
        it = state.internal
        c = self._c
        if not it.get("started", False):
            w_lo, w_hi = self._initial_w(state.lower, state.upper, yk)
            e = np.zeros_like(w_lo)
            w_run = np.maximum(np.abs(w_lo), np.abs(w_hi))
            x_lo, x_hi = (
                np.broadcast_to(state.lower, w_lo.shape).copy(),
                np.broadcast_to(state.upper, w_lo.shape).copy(),
            )
            hosm_q = self.hosm.init(yk) if self.hosm is not None else None
            d_lo = np.full(yk.shape, np.nan)
            d_hi = np.full(yk.shape, np.nan)
            if self.derivative == "hosm" and hosm_q is not None:
                d_lo, d_hi = hosm_q[..., 1] - self.beta, hosm_q[..., 1] + self.beta
            xi_lo, xi_hi = self._input_box(w_lo - e, w_hi + e, yk, uk, d_lo, d_hi)
            internal = {
                "started": True,
                "w_lo": w_lo,
                "w_hi": w_hi,
                "e": e,
                "w_run": w_run,
                "y": yk.copy(),
                "u": np.array(uk),
                "hosm": hosm_q,
            }
            return ObserverState(x_lo, x_hi, xi_lo, xi_hi, internal)
        y_prev, u_prev = it["y"], it["u"]
        g_lo, g_hi = self._forcing(self._tl_bounds(y_prev), self._tl_bounds(yk), u_prev)
        w_lo = c.a * it["w_lo"] + g_lo
        w_hi = c.a * it["w_hi"] + g_hi
        w_run = np.maximum(it["w_run"], np.maximum(np.abs(w_lo), np.abs(w_hi)))
        e = c.a * it["e"] + self._pad_input(it["w_lo"], it["w_hi"], g_lo, g_hi, w_run)
        x_lo, x_hi = self._state_box(w_lo - e, w_hi + e, yk)
        hosm_q = None
        if self.hosm is not None:
            hosm_q = self.hosm.step(it["hosm"], y_prev, self.h)
        if self.derivative == "hosm" and hosm_q is not None:
            d_lo, d_hi = hosm_q[..., 1] - self.beta, hosm_q[..., 1] + self.beta
        else:
            d_lo, d_hi = self._derivative_pair(y_prev, yk)
        xi_lo, xi_hi = self._input_box(w_lo - e, w_hi + e, yk, uk, d_lo, d_hi)
        internal = {
            "started": True,
            "w_lo": w_lo,
            "w_hi": w_hi,
            "e": e,
            "w_run": w_run,
            "y": yk.copy(),
            "u": np.array(uk),
            "hosm": hosm_q,
        }
        return ObserverState(x_lo, x_hi, xi_lo, xi_hi, internal)

    def run(
        self,
        t: ArrayLike,
        y: ArrayLike,
        u: ArrayLike | None = None,
        x0_lower: ArrayLike | None = None,
        x0_upper: ArrayLike | None = None,
        hosm_q1: ArrayLike | None = None,
    ) -> Estimate:
        """Bounds over a whole record (vectorised; equal to repeated :meth:`step` up to rounding).

        Parameters
        ----------
        t : array_like, shape (T,)
            Sample times, uniformly spaced by ``h`` (to ``1e-9 h``).
        y : array_like, shape (T, p) or (M, T, p)
            Measurements.
        u : array_like, shape (T, m) or (M, T, m), optional
            Known input; must be None or empty (m = 0).
        x0_lower, x0_upper : array_like, optional
            Prior box (default: the design bounds).
        hosm_q1 : array_like, shape like ``y``, optional
            With ``derivative="hosm"``: the estimate ``q₁`` already computed by ``self.hosm.run(y, h)``
            (saves the time-stepping loop when several observers share one differentiator run).

        Returns
        -------
        Estimate
            State bounds, unknown-input bounds (NaN where none is available: the first sample with the
            difference enclosure) and ``meta`` with ``transient_s``.
        """
        times, ys, us = self._signals(t, y, u)
        x0_lo, x0_hi = self._prior(x0_lower, x0_upper)
        lead = ys.shape[:-2]
        w0_lo, w0_hi = self._initial_w(x0_lo, x0_hi, ys[..., 0, :])
        w0_lo = np.broadcast_to(w0_lo, (*lead, self.n))
        w0_hi = np.broadcast_to(w0_hi, (*lead, self.n))
        tl = self._tl_bounds(ys)
        g_lo, g_hi = self._forcing(
            tuple(v[..., :-1, :] for v in tl),  # type: ignore[arg-type]
            tuple(v[..., 1:, :] for v in tl),  # type: ignore[arg-type]
            us[..., :-1, :],
        )
        w_lo = self._scalar_recursion(w0_lo, g_lo)
        w_hi = self._scalar_recursion(w0_hi, g_hi)
        w_mag = np.maximum(np.abs(w_lo), np.abs(w_hi))
        w_run = np.maximum.accumulate(w_mag, axis=-2)
        pad_in = self._pad_input(w_lo[..., :-1, :], w_hi[..., :-1, :], g_lo, g_hi, w_run[..., 1:, :])
        e = self._scalar_recursion(np.zeros_like(w0_lo), pad_in)
        w_lo_p, w_hi_p = w_lo - e, w_hi + e
        x_lo, x_hi = self._state_box(w_lo_p, w_hi_p, ys)
        x_lo[..., 0, :] = x0_lo
        x_hi[..., 0, :] = x0_hi
        if self.derivative == "hosm":
            assert self.hosm is not None
            if hosm_q1 is None:
                q1 = self.hosm.run(ys, self.h)[..., 1]
            else:
                q1 = np.asarray(hosm_q1, dtype=float)
                if q1.shape != ys.shape:
                    raise DataError(f"hosm_q1: expected shape {ys.shape}, got {q1.shape}")
            d_lo, d_hi = q1 - self.beta, q1 + self.beta
        else:
            d_lo = np.full(ys.shape, np.nan)
            d_hi = np.full(ys.shape, np.nan)
            d_lo[..., 1:, :], d_hi[..., 1:, :] = self._derivative_pair(ys[..., :-1, :], ys[..., 1:, :])
        xi_lo, xi_hi = self._input_box(w_lo_p, w_hi_p, ys, us, d_lo, d_hi)
        meta = {
            "method": "unknown-input interval observer (seed 000)",
            "derivative": self.derivative,
            "transient_s": float(times[0]) + self.transient_s,
            "poles": self.coords.poles.tolist(),
            "rho_x": self.rho_x.tolist(),
            "rho_xi": self.rho_xi.tolist(),
        }
        return Estimate(times, x_lo, x_hi, xi_lo, xi_hi, meta)

    def _scalar_recursion(self, w0: FloatArray, g: FloatArray) -> FloatArray:
        """``w_{k+1} = a ⊙ w_k + g_k`` for every component, with the initial value as row 0."""
        a = self._c.a
        out = np.empty((*g.shape[:-2], g.shape[-2] + 1, self.n))
        out[..., 0, :] = w0
        for i in range(self.n):
            zi = (a[i] * w0[..., i])[..., None]
            out[..., 1:, i] = lfilter([1.0], [1.0, -a[i]], g[..., i], axis=-1, zi=zi)[0]
        return out
