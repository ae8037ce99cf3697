r"""Unknown-input interval observer for uncertain continuous-time LTI systems (the aircraft UIO paper).

Model (the aircraft UIO paper, eq. (1), with the noise matrices of :class:`~intervalobs.systems.LTISystem`):

.. math:: \dot x = Ax + Bu + D\xi + E_\omega w, \qquad y = Cx + Fv, \qquad \psi = Cx,

:math:`\xi` unknown and unbounded, :math:`w, v` in boxes, the measurement noise smooth
(:math:`|\dot v| \le \bar{\dot v}`) and :math:`|\ddot\psi| \le L` (the assumption of Levant's
differentiator, the aircraft UIO paper, Theorem 3).

Observer (the aircraft UIO paper, eq. (15)) in the coordinates :math:`z = Tx` of Hypothesis 6, in which
:math:`TNT^{-1} = M` is Metzler and Hurwitz (diagonal for real poles, 3×3 cyclic blocks for complex
pairs: :func:`~intervalobs.design.uio.metzler_block_form`). Equation (15) contains :math:`-TE\dot y`; we
integrate it *exactly* by writing :math:`w = z + TE\psi = T(x + E\psi)`, for which (using :math:`PD = 0`,
:math:`K = L + NE`, eq. (14))

.. math:: \dot w = M w + TL\,\psi + TPB\,u + TPE_\omega w_{\text{noise}},
          \qquad x = T^{-1}w - E\psi .

No output derivative enters the state bounds, so they hold from :math:`t_0` (no HOSM transient).

**Known inputs.** ``u`` is either point-known and held on :math:`[t_k, t_{k+1})` (zero-order hold, a
digital controller), or interval-known: on :math:`[t_k, t_{k+1})` it is *any* signal in the box
:math:`[\underline u_k, \overline u_k]` (``u=(lower, upper)``; e.g. a continuous command, or a switch
inside the step). The assumption on the output is placed on the part of :math:`\dot\psi` the known
input does not enter directly,

.. math:: g = \dot\psi - CBu = C(Ax + D\xi + E_\omega w_{\text{noise}}), \qquad |\dot g| \le L
          \ (\texttt{output\_accel}),

which is Lipschitz even when :math:`u` jumps (for :math:`B = 0` it is :math:`|\ddot\psi| \le L`).

*Soundness of the state bounds.* On a step, :math:`\psi(t_k + s) = \psi_k + G(s) + CB\,U(s)` with
:math:`G = \int_0^s g`, :math:`U = \int_0^s u`. Its deviation from the chord through
:math:`\psi_k, \psi_{k+1}` is :math:`r_G(s) + CB\,r_U(s)`, where :math:`|r_G(s)| \le L s(h-s)/2`
(:math:`|G''| \le L`) and, writing :math:`u = u_c + \tilde u` with the box centre :math:`u_c` (which the
chord reproduces exactly) and :math:`|\tilde u| \le u_r`,
:math:`r_U(s) = \int_0^h \tilde u(\sigma)(\mathbb 1_{\sigma < s} - s/h)\,d\sigma`, so
:math:`|r_U(s)| \le u_r\,2s(h-s)/h`. Because :math:`e^{M\tau} \ge 0` (M Metzler), the exact step

.. math:: w_{k+1} = e^{Mh}w_k + \int_0^h e^{M(h-s)}\big(TL\,\psi(t_k+s) + TPB\,u(t_k+s)
          + TPE_\omega w_{\text{noise}}(t_k+s)\big)\,ds

is bounded componentwise by :math:`\overline w_{k+1} = \Phi\overline w_k + \Gamma_0\overline{TL\psi_k}
+ \Gamma_1\overline{TL\psi_{k+1}} + \Gamma(\overline{TPBu}_k + \overline{TPE_\omega w}) + \Gamma_r|TL|
(L + 4|CB|u_r/h)` with the nonnegative matrices :math:`\Phi = e^{Mh}`,
:math:`\Gamma = \int_0^h e^{M\sigma}d\sigma`, :math:`\Gamma_1 = \int_0^h e^{M(h-s)}\tfrac sh ds`,
:math:`\Gamma_0 = \Gamma - \Gamma_1`, :math:`\Gamma_r = \int_0^h e^{M(h-s)}\tfrac{s(h-s)}2 ds`
(every noise and input signal inside the step is covered, not only held ones); the lower bound
likewise. For a held point input :math:`u_r = 0` and the widths do not depend on ``u`` at all.

*Soundness of the input bounds.* The known input is removed before differentiating:
:math:`(\psi_k - \psi_{k-1})/h_k = \tfrac1{h_k}\int g + CB\bar u_{k-1}` with the step mean
:math:`\bar u_{k-1} \in [\underline u_{k-1}, \overline u_{k-1}]`, and
:math:`|g(t_k) - \tfrac1{h_k}\int g| \le Lh_k/2`, so

.. math:: g(t_k) \in \frac{y_k - y_{k-1}}{h_k} - CB[\underline u_{k-1}, \overline u_{k-1}]
          \pm \big(\bar{\dot\delta} + L h_k/2\big),

and, by (36), :math:`\xi(t_k) = M_0\big(g(t_k) - CAx(t_k) - CE_\omega w_{\text{noise}}(t_k)\big)` with
:math:`M_0 = (CD)^\dagger` — no value of ``u`` at :math:`t_k` is needed, so a jump of ``u`` at a sample
(or inside a step) never enters the derivative. With ``derivative="hosm"`` Levant's differentiator runs
on :math:`y - CB\int u`, whose derivative is :math:`g + \dot\delta` (point-known inputs only); its bound
is the paper's :math:`\beta = \bar{\dot\delta} + \mu_1\bar\delta^{1/2}` (eq. (8)), claimed only after
``hosm_transient``.

Floating point: every rounding-level departure from the exact model (the float ``T`` only nearly maps
``N`` onto ``M``; ``T⁻¹``, ``e^{Mh}`` and the Γ's are computed; ``PD`` and ``I - M_0CD`` are ~1e-16 rather
than 0, which leaks a fraction of :math:`\xi` bounded with ``input_magnitude``; the time grid deviates from
the nominal step by at most ``step_tolerance``) is bounded and added outward. The recursion
:math:`\overline w_{k+1} = \Phi\overline w_k + \overline g_k` is evaluated over the whole record by
:class:`~intervalobs.recursion.LinearRecursion` (modal ``lfilter``, vectorised over Monte Carlo runs);
its computed value is then checked *a posteriori*: the residual :math:`\rho_k = \hat w_{k+1} - \Phi\hat w_k
- \overline g_k` (plus the rounding of computing it) drives the exact error recursion
:math:`\epsilon_{k+1} = \Phi\epsilon_k + |\rho_k|`, which we majorise by :math:`\epsilon_k \le s_k v`
with :math:`v = -M^{-1}\mathbf 1 > 0`, :math:`\Phi v \le \varrho v` (:math:`\varrho < 1`) and the scalar,
nonnegative recursion :math:`s_{k+1} = \varrho s_k + \max_i(\cdot)_i/v_i`, whose own rounding is a
relative :math:`\le 2ku`. The other rounding pads enter the same scalar recursion.

Step semantics (current output): ``init`` returns the prior box; ``step(state, y_k, u_k)`` consumes the
measurement of the *next* sample and the input held from it on, and returns the box at that sample given
``y_0 … y_k`` (the first call consumes ``y_0`` and returns the prior box at ``t_0``). Row ``k`` of
:meth:`run` equals the box after the ``(k+1)``-th ``step`` call.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
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
from ..design.uio_step import UNIT_ROUNDOFF, uio_step_constants
from ..errors import BoundsError, DataError, DesignError, DimensionError
from ..estimate import Estimate
from ..interval import ROUNDING_MARGIN, matvec_bounds
from ..recursion import LinearRecursion
from ..systems.bounds import Bounds
from ..systems.lti import LTISystem, refuse_uncertain_input
from ..validation import as_array, as_matrix, as_positive, as_signal, as_vector
from .base import SPACING_TOLERANCE, Observer, ObserverState, options_after_bounds

__all__ = ["UnknownInputIntervalObserver"]

FloatArray = NDArray[np.float64]
KnownInput = ArrayLike | tuple[ArrayLike, ArrayLike] | None
"""A point-known input (held between samples) or a pair ``(lower, upper)`` of an interval-known one."""

_U = UNIT_ROUNDOFF
_STEP_TOLERANCE = SPACING_TOLERANCE  # the deviation run() accepts; the bounds account for it


def _rmul(x: FloatArray, m: FloatArray) -> FloatArray:
    """``x @ m.T`` over leading axes, by einsum: no BLAS call, so no thread oversubscription on (T, n) records."""
    return np.asarray(np.einsum("...j,ij->...i", x, m))


class UnknownInputIntervalObserver(Observer):
    """Interval observer of the state and of the unknown input ξ of a continuous-time LTI system.

    The state and unknown-input bounds of the aircraft UIO paper: the unknown input is removed from the
    error by a decoupling that needs it to be visible in the outputs, then bounded from the output's
    derivative.

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
        Gain and coordinates in which the error is cooperative (off-diagonal entries ≥ 0) and stable.
    noise_rate : array_like, shape (nv,)
        Bound of ``|dv/dt|``.
    output_accel : array_like, shape (p,)
        Bound ``L`` of ``|d/dt (dψ/dt - CBu)|`` (``|d²ψ/dt²|`` when ``B = 0``).
    derivative : {"difference", "hosm"}
        Derivative enclosure for the unknown-input bounds.
    hosm : HOSMDifferentiator, optional
        Differentiator for ``derivative="hosm"``.
    mu1 : float
        ``µ_1``, the gain of the differentiator's error bound ``µ_1 δ^½``.
    hosm_transient : float
        Time after which the HOSM bound is claimed.
    input_magnitude : float
        Bound of ``|ξ|`` for the rounding-level leak through ``PD ≈ 0``.

    Attributes
    ----------
    system : LTISystem
        The continuous-time model (``A``, ``B`` of the known input, ``C``, ``E`` = noise matrix of ``w``, ``F``).
    D : numpy.ndarray, shape (n, q)
        Unknown-input matrix.
    decoupling : UIODecoupling
        ``E``, ``P`` that remove the unknown input from the error (``PD = 0``).
    coords : UIOCoordinates
        Gain ``K`` and coordinates ``T`` of the cooperative, stable error.
    h : float
        Sampling period.
    derivative : str
        ``"difference"`` or ``"hosm"``.
    transient_s : float
        Time after which the input bounds are claimed (state bounds hold from ``t_0``).
    rho_x, rho_xi : numpy.ndarray
        Asymptotic widths of the state and input bounds of this observer.

    References
    ----------
    The aircraft UIO paper (:mod:`intervalobs.references`): bounds (15), (31), (37); ``µ_1`` of (8);
    ``E``, ``P`` of (11), (25); ``K``, ``T`` of Hypothesis 6; widths as in (34), (48).
    """

    summary_fields = ("q", "derivative")
    rows = "filtered"

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
        refuse_uncertain_input(system, "UnknownInputIntervalObserver")
        self.system = system
        self.bounds = bounds.resolve(system)
        n, p = system.n, system.p
        self.n, self.p, self.m = n, p, system.m
        self.D = as_matrix("D", D, (n, None))
        self.q = self.D.shape[1]
        self.h = as_positive("h", h, "a positive sampling period")
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
        if np.any(coords.poles.real >= 0):
            raise DesignError(f"coords: expected poles with negative real parts, got {coords.poles}")
        off = coords.M[~np.eye(n, dtype=bool)]
        if off.size and off.min() < 0:
            raise DesignError(f"coords: expected a Metzler M, got an off-diagonal entry {off.min():.3g}")
        self._c = uio_step_constants(
            system,
            self.bounds,
            self.D,
            self.h,
            decoupling,
            coords,
            self.output_accel,
            self.input_magnitude,
            self.step_tolerance,
        )
        self.rate_radius = np.abs(system.F) @ self.noise_rate
        self.beta = hosm_error_bound(
            0.5 * (self._c.delta_hi - self._c.delta_lo) + np.abs(0.5 * (self._c.delta_hi + self._c.delta_lo)),
            self.rate_radius,
            self.mu1,
        )
        self.rho_x, self.rho_xi = self._asymptotic_widths()

    # ------------------------------------------------------------------ design
    @classmethod
    @options_after_bounds("D", "h")
    def design(
        cls,
        system: LTISystem,
        bounds: Bounds,
        *,
        D: ArrayLike,
        h: float,
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
        """Check that the unknown input can be removed and the error made cooperative, then build the observer.

        Three conditions on the model: the unknown input acts through directions the outputs see
        (``rank(CD) = rank(D) = q ≤ p``); after removing it, the state is still detectable from the
        outputs; and a gain and coordinates exist in which the error is cooperative and stable.

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
            Bound ``L`` of ``|d/dt (dψ/dt - CBu)|``, the output acceleration without the known input's
            direct term (``|d²ψ/dt²|`` when ``B = 0``; Levant's Lipschitz constant, ``λ_1 = 1.1 L``).
        W : array_like, shape (n, p), optional
            Free parameter of the decoupling ``E = -D(CD)† + W(I - CD(CD)†)``, default 0.
        poles : array_like, shape (n,), optional
            Poles of ``PA - KC``: real (repeated up to ``p`` times) or complex pairs with a real partner
            (default: searched, see :func:`~intervalobs.design.uio.design_uio_coordinates`).
        K, T : array_like, optional
            A given gain (and coordinates), checked: ``T (PA - KC) T⁻¹`` Metzler and
            Hurwitz (default ``T``: onto :func:`~intervalobs.design.uio.metzler_block_form`).
        derivative : {"difference", "hosm"}
            Derivative enclosure used for the unknown-input bounds.
        hosm : HOSMDifferentiator, optional
            Differentiator for ``derivative="hosm"``.
        mu1 : float
            ``µ_1`` (the differentiator's error gain) for ``derivative="hosm"``.
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
            The unknown input is not visible in the outputs, the decoupled model is not detectable, or
            the given gain does not make the error cooperative and stable.
        DesignError
            No suitable gain/coordinates.

        References
        ----------
        The aircraft UIO paper, §4: Hypotheses 4–6 (the three conditions above), ``W`` of (11), ``µ_1``
        of (8).
        """
        refuse_uncertain_input(system, "UnknownInputIntervalObserver")
        full = bounds.resolve(system)
        d = as_matrix("D", D, (system.n, None))
        decoupling = uio_decoupling(system.A, system.C, d, W)
        omega_radius = np.abs(system.E) @ full.radius("w")
        delta_radius = np.abs(system.F) @ full.radius("v")
        if K is not None:
            coords = check_cooperative(system.A, system.C, decoupling, K, T)
        else:
            coords = design_uio_coordinates(system.A, system.C, decoupling, omega_radius, delta_radius, poles)
        return cls(
            system,
            full,
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

    def _asymptotic_widths(self) -> tuple[FloatArray, FloatArray]:
        """Limits of the widths (eqs. (30), (34), (48) for this observer) for held point inputs, pads excluded."""
        c = self._c
        dw = self._c.delta_hi - self._c.delta_lo
        g_width = (c.G0 + c.G1) @ (np.abs(c.TL) @ dw) + c.Gam @ (c.noise_hi - c.noise_lo) + 2 * c.const_pad
        rho_w = np.linalg.solve(np.eye(self.n) - c.Phi, g_width)
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
        r"""The aircraft UIO paper's asymptotic widths, with its ``ẏ``-based forcing (sign-corrected).

        :math:`\rho_z = -M^{-1}(2|TP|\bar\omega + 2|TK|\bar\delta + |TE|\bar\zeta)`,
        :math:`\rho_x = |T^{-1}|\rho_z`,
        :math:`\rho_\xi = |M_1|\rho_z + 2(|M_3|\bar\omega + (|M_0| + |M_4|)\bar{\dot\delta}
        + |M_0|\mu_1\bar\delta^{1/2})`, with :math:`\bar\zeta = 2(\bar{\dot\delta} + \mu_1\bar\delta^{1/2})`.

        Parameters
        ----------
        zeta : array_like, shape (p,), optional
            Bound of ζ, the error of the output derivative; default ``2 (δ̇ + µ1 δ^½)``.

        Returns
        -------
        rho_x, rho_xi : numpy.ndarray

        References
        ----------
        The aircraft UIO paper: widths (30), (34), (48); ζ of (29).
        """
        c, co, dec = self._c, self.coords, self.decoupling
        omega_r = 0.5 * (c.noise_hi - c.noise_lo)  # already through |TPE|
        delta_r = 0.5 * (c.delta_hi - c.delta_lo)
        z = 2 * self.beta if zeta is None else as_vector("zeta", zeta, self.p)
        forcing = 2 * omega_r + 2 * np.abs(co.T @ co.K) @ delta_r + np.abs(co.T @ dec.E) @ z
        rho_z = np.linalg.solve(-co.M, forcing)
        rho_x = np.abs(co.S) @ rho_z
        m0 = dec.M0
        m1 = -m0 @ self.system.C @ self.system.A @ co.S
        m3 = -m0 @ self.system.C @ self.system.E
        w_r = self.bounds.radius("w")
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
        u_lo: FloatArray,
        u_hi: FloatArray,
    ) -> tuple[FloatArray, FloatArray]:
        """Bounds of the exact input integral over one step (any leading axes; module docstring)."""
        c = self._c
        bu_lo, bu_hi = matvec_bounds(c.TPB, u_lo, u_hi)
        u_mag = np.maximum(np.abs(u_lo), np.abs(u_hi))
        base_hi = _rmul(tl0[1], c.G0) + _rmul(tl1[1], c.G1) + _rmul(c.noise_hi + bu_hi, c.Gam)
        base_lo = _rmul(tl0[0], c.G0) + _rmul(tl1[0], c.G1) + _rmul(c.noise_lo + bu_lo, c.Gam)
        mag = _rmul(tl0[2] + tl1[2] + c.noise_mag + _rmul(u_mag, c.TPB_mag), c.G_mag)
        pad = c.const_pad + _rmul(0.5 * (u_hi - u_lo), c.input_remainder)
        pad = pad + (ROUNDING_MARGIN + 2 * self.step_tolerance / self.h) * mag
        return base_lo - pad, base_hi + pad

    def _step_residual(self, w_now: FloatArray, w_next: FloatArray, g: FloatArray) -> FloatArray:
        """Bound of ``|w_next - (Φ w_now + g)|`` in exact arithmetic, for computed ``w_next`` (module docstring)."""
        c = self._c
        phi_w = _rmul(w_now, c.Phi)
        resid = np.abs(w_next - phi_w - g)
        scale = np.abs(w_next) + _rmul(np.abs(w_now), c.Phi) + np.abs(g)
        return np.asarray(resid + 2 * (self.n + 3) * _U * scale / (1 - (self.n + 3) * _U))

    def _pad_input(
        self,
        w_lo: FloatArray,
        w_hi: FloatArray,
        w_next: tuple[FloatArray, FloatArray],
        g: tuple[FloatArray, FloatArray],
        w_run: FloatArray,
    ) -> FloatArray:
        """Input of the rounding recursion: departures of the computed step from the exact model."""
        c = self._c
        w_mag = np.maximum(np.abs(w_lo), np.abs(w_hi))
        residual = np.maximum(self._step_residual(w_lo, w_next[0], g[0]), self._step_residual(w_hi, w_next[1], g[1]))
        return np.asarray(residual + _rmul(w_mag, c.dPhi + c.grid) + _rmul(_rmul(2 * w_run, c.offdiag), c.Gam))

    def _majorant_step(self, s: FloatArray, pad: FloatArray) -> FloatArray:
        """``s_{k+1} = ρ s_k + max_i pad_i / v_i``, rounded up."""
        c = self._c
        return np.asarray((c.rho * s + np.max(pad / c.v, axis=-1)) * (1 + 4 * _U))

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
        d_lo: FloatArray,
        d_hi: FloatArray,
    ) -> tuple[FloatArray, FloatArray]:
        """ξ from (36)–(37) in the w-coordinates, from a box of ``g = dψ/dt - CBu``, rounded outward."""
        c = self._c
        plo, phi = self._psi_box(y)
        a_lo, a_hi = matvec_bounds(self.decoupling.M0, d_lo, d_hi)
        b_lo, b_hi = matvec_bounds(c.Mw, w_lo, w_hi)
        e_lo, e_hi = matvec_bounds(c.Mpsi, plo, phi)
        w_mag = np.maximum(np.abs(w_lo), np.abs(w_hi))
        mag = (
            _rmul(np.maximum(np.abs(d_lo), np.abs(d_hi)), np.abs(self.decoupling.M0))
            + _rmul(w_mag, c.Mw_mag)
            + _rmul(np.maximum(np.abs(plo), np.abs(phi)), c.Mpsi_mag)
            + c.xi_noise_mag
        )
        pad = c.xi_pad + ROUNDING_MARGIN * mag + c.dS * (w_mag.sum(axis=-1, keepdims=True) * c.M0CA_abs.sum(axis=-1))
        lo = a_lo + b_lo + e_lo + c.xi_noise_lo - pad
        hi = a_hi + b_hi + e_hi + c.xi_noise_hi + pad
        return lo, hi

    def _derivative_pair(
        self, y_prev: FloatArray, y_now: FloatArray, u_lo: FloatArray, u_hi: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """Box of ``g(t_k) = dψ/dt - CBu`` from ``y_{k-1}, y_k`` and the input box of the step between."""
        d_lo, d_hi = difference_pair_bounds(
            y_prev, y_now, self.h, self.rate_radius, self.output_accel, self.step_tolerance
        )
        cb_lo, cb_hi = matvec_bounds(self._c.CB, u_lo, u_hi)
        pad = 4 * (self.m + 1) * _U * _rmul(np.maximum(np.abs(u_lo), np.abs(u_hi)), np.abs(self._c.CB))
        return d_lo - cb_hi - pad, d_hi - cb_lo + pad

    def _hosm_signal(self, y: FloatArray, u: FloatArray) -> FloatArray:
        """``y - CB ∫u`` on the sample grid (exact for a held point input): its derivative is ``g + dδ/dt``."""
        integral = np.zeros_like(u)
        integral[..., 1:, :] = np.cumsum(u[..., :-1, :], axis=-2) * self.h
        return np.asarray(y - _rmul(integral, self._c.CB))

    def _input_signal(self, u: KnownInput, shape: tuple[int, ...], steps: int | None) -> tuple[FloatArray, FloatArray]:
        """The known input as a box ``(lower, upper)`` broadcast to ``shape`` (point input: lower = upper)."""
        if u is None:
            if self.m > 0:
                raise DataError(f"u: expected the known input (m = {self.m}), got None")
            zero = np.zeros((*shape, self.m))
            return zero, zero
        if isinstance(u, tuple):
            if len(u) != 2:
                raise DataError(f"u: expected an array or a pair (lower, upper), got a tuple of {len(u)}")
            lo, hi = self._input_array("u lower", u[0], steps), self._input_array("u upper", u[1], steps)
            if lo.shape != hi.shape or np.any(lo > hi):
                raise DataError("u: expected lower <= upper of one shape")
        else:
            lo = hi = self._input_array("u", u, steps)
        return np.broadcast_to(lo, (*shape, self.m)), np.broadcast_to(hi, (*shape, self.m))

    def _input_array(self, name: str, value: ArrayLike, steps: int | None) -> FloatArray:
        if steps is not None:
            return as_signal(name, value, steps, self.m)
        arr = np.asarray(value, dtype=float)
        if arr.shape[-1:] != (self.m,) or not np.all(np.isfinite(arr)):
            raise DataError(f"{name}: expected finite values of shape (..., {self.m}), got {arr.shape}")
        return arr

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
        lo, hi = self._prior_boxes(self.bounds.x0, x0_lower, x0_upper)
        return ObserverState(lo, hi, None, None, {"started": False})

    def step(self, state: ObserverState, y: ArrayLike, u: KnownInput = None) -> ObserverState:
        """Consume the next measurement ``y_k`` (and ``u_k``) and return the box at ``t_k``.

        Parameters
        ----------
        state : ObserverState
            From :meth:`init` or a previous :meth:`step`.
        y : array_like, shape (p,) or (M, p)
            Measurement at the next sample.
        u : array_like or (array_like, array_like), shape (m,) or (M, m), optional
            Known input from that sample to the following one: a held value, or a pair ``(lower, upper)``
            bounding it over the step. Required when ``m > 0``.

        Returns
        -------
        ObserverState
        """
        yk = as_array("y", y)
        if yk.shape[-1:] != (self.p,) or not np.all(np.isfinite(yk)):
            raise DataError(f"y: expected finite values of shape (..., {self.p}), got {yk.shape}")
        u_lo, u_hi = self._input_signal(u, yk.shape[:-1], None)
        if self.derivative == "hosm" and np.any(u_lo != u_hi):
            raise DataError("u: derivative='hosm' needs a point-known input (lower == upper)")
        it = state.internal
        c = self._c
        if not it.get("started", False):
            w_lo, w_hi = self._initial_w(state.lower, state.upper, yk)
            s = np.zeros(w_lo.shape[:-1])
            w_run = np.maximum(np.abs(w_lo), np.abs(w_hi))
            x_lo, x_hi = (
                np.broadcast_to(state.lower, w_lo.shape).copy(),
                np.broadcast_to(state.upper, w_lo.shape).copy(),
            )
            hosm_q = self.hosm.init(yk) if self.hosm is not None else None
            if self.derivative == "hosm" and hosm_q is not None:
                d_lo, d_hi = hosm_q[..., 1] - self.beta, hosm_q[..., 1] + self.beta
                xi_lo, xi_hi = self._input_box(w_lo, w_hi, yk, d_lo, d_hi)
            else:  # no derivative bound before a second sample: no input bound yet
                xi_lo = np.full((*w_lo.shape[:-1], self.decoupling.M0.shape[0]), -np.inf)
                xi_hi = -xi_lo
            cb_integral = np.zeros_like(yk)
        else:
            y_prev = it["y"]
            g_lo, g_hi = self._forcing(self._tl_bounds(y_prev), self._tl_bounds(yk), it["u_lo"], it["u_hi"])
            w_lo = _rmul(it["w_lo"], c.Phi) + g_lo
            w_hi = _rmul(it["w_hi"], c.Phi) + g_hi
            w_run = np.maximum(it["w_run"], np.maximum(np.abs(w_lo), np.abs(w_hi)))
            s = self._majorant_step(it["s"], self._pad_input(it["w_lo"], it["w_hi"], (w_lo, w_hi), (g_lo, g_hi), w_run))
            e = s[..., None] * c.v
            x_lo, x_hi = self._state_box(w_lo - e, w_hi + e, yk)
            cb_integral = it["cb_integral"] + _rmul(it["u_lo"], c.CB) * self.h
            hosm_q = None
            if self.hosm is not None:
                hosm_q = self.hosm.step(it["hosm"], y_prev - it["cb_integral"], self.h)
            if self.derivative == "hosm" and hosm_q is not None:
                d_lo, d_hi = hosm_q[..., 1] - self.beta, hosm_q[..., 1] + self.beta
            else:
                d_lo, d_hi = self._derivative_pair(y_prev, yk, it["u_lo"], it["u_hi"])
            xi_lo, xi_hi = self._input_box(w_lo - e, w_hi + e, yk, d_lo, d_hi)
        internal = {
            "started": True,
            "w_lo": w_lo,
            "w_hi": w_hi,
            "s": s,
            "w_run": w_run,
            "y": yk.copy(),
            "u_lo": np.array(u_lo),
            "u_hi": np.array(u_hi),
            "cb_integral": cb_integral,
            "hosm": hosm_q,
        }
        return ObserverState(x_lo, x_hi, xi_lo, xi_hi, internal)

    def run(
        self,
        t: ArrayLike,
        y: ArrayLike,
        u: KnownInput = None,
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
        u : array_like or (array_like, array_like), shape (T, m) or (M, T, m), optional
            Known input, required when ``m > 0``: row ``k`` is held on ``[t_k, t_{k+1})``, or a pair
            ``(lower, upper)`` whose row ``k`` bounds the input over that step (any signal inside).
        x0_lower, x0_upper : array_like, optional
            Prior box (default: the design bounds).
        hosm_q1 : array_like, shape like ``y``, optional
            With ``derivative="hosm"``: the estimate ``q₁`` already computed by ``self.hosm.run`` on
            ``y - CB ∫u`` (``y`` itself when ``m = 0``; saves the loop when observers share one run).

        Returns
        -------
        Estimate
            State bounds, unknown-input bounds (``[-inf, inf]`` where none is available: the first
            sample with the difference enclosure) and ``meta`` with ``transient_s``.
        """
        times, ys, _ = self._signals(t, y, u[0] if isinstance(u, tuple) else u)
        u_lo, u_hi = self._input_signal(u, ys.shape[:-1], times.size)
        if self.derivative == "hosm" and np.any(u_lo != u_hi):
            raise DataError("u: derivative='hosm' needs a point-known input (lower == upper)")
        x0_lo, x0_hi = self._prior_boxes(self.bounds.x0, x0_lower, x0_upper)
        lead = np.broadcast_shapes(ys.shape[:-2], u_lo.shape[:-2])
        ys = np.broadcast_to(ys, (*lead, *ys.shape[-2:]))
        u_lo = np.broadcast_to(u_lo, (*lead, *u_lo.shape[-2:]))
        u_hi = np.broadcast_to(u_hi, (*lead, *u_hi.shape[-2:]))
        w0_lo, w0_hi = self._initial_w(x0_lo, x0_hi, ys[..., 0, :])
        w0_lo = np.broadcast_to(w0_lo, (*lead, self.n))
        w0_hi = np.broadcast_to(w0_hi, (*lead, self.n))
        tl = self._tl_bounds(ys)
        g_lo, g_hi = self._forcing(
            tuple(v[..., :-1, :] for v in tl),  # type: ignore[arg-type]
            tuple(v[..., 1:, :] for v in tl),  # type: ignore[arg-type]
            u_lo[..., :-1, :],
            u_hi[..., :-1, :],
        )
        recursion = LinearRecursion(self._c.Phi)
        w_lo = recursion(w0_lo, g_lo)
        w_hi = recursion(w0_hi, g_hi)
        w_mag = np.maximum(np.abs(w_lo), np.abs(w_hi))
        w_run = np.maximum.accumulate(w_mag, axis=-2)
        pad_in = self._pad_input(
            w_lo[..., :-1, :],
            w_hi[..., :-1, :],
            (w_lo[..., 1:, :], w_hi[..., 1:, :]),
            (g_lo, g_hi),
            w_run[..., 1:, :],
        )
        e = self._majorant(pad_in)
        w_lo_p, w_hi_p = w_lo - e, w_hi + e
        x_lo, x_hi = self._state_box(w_lo_p, w_hi_p, ys)
        x_lo[..., 0, :] = x0_lo
        x_hi[..., 0, :] = x0_hi
        if self.derivative == "hosm":
            assert self.hosm is not None
            if hosm_q1 is None:
                q1 = self.hosm.run(self._hosm_signal(ys, u_lo), self.h)[..., 1]
            else:
                q1 = np.asarray(hosm_q1, dtype=float)
                if q1.shape != ys.shape:
                    raise DataError(f"hosm_q1: expected shape {ys.shape}, got {q1.shape}")
            d_lo, d_hi = q1 - self.beta, q1 + self.beta
            xi_lo, xi_hi = self._input_box(w_lo_p, w_hi_p, ys, d_lo, d_hi)
        else:  # the difference enclosure needs a previous sample: row 0 has no input bound
            d_lo, d_hi = self._derivative_pair(ys[..., :-1, :], ys[..., 1:, :], u_lo[..., :-1, :], u_hi[..., :-1, :])
            later = self._input_box(w_lo_p[..., 1:, :], w_hi_p[..., 1:, :], ys[..., 1:, :], d_lo, d_hi)
            xi_lo = np.concatenate([np.full_like(later[0][..., :1, :], -np.inf), later[0]], axis=-2)
            xi_hi = np.concatenate([np.full_like(later[1][..., :1, :], np.inf), later[1]], axis=-2)
        meta = {
            "method": "unknown-input interval observer (the aircraft UIO paper)",
            "derivative": self.derivative,
            "transient_s": float(times[0]) + self.transient_s,
            "poles": [complex(v) if v.imag else float(v.real) for v in self.coords.poles],
            "rho_x": self.rho_x.tolist(),
            "rho_xi": self.rho_xi.tolist(),
            "known_input": "none" if self.m == 0 else ("interval" if np.any(u_lo != u_hi) else "held point"),
            "rows": self.rows,
        }
        return Estimate.from_boxes(times, x_lo, x_hi, xi_lo, xi_hi, meta)

    def _majorant(self, pad: FloatArray) -> FloatArray:
        """``e_k = s_k v`` from the scalar recursion of :meth:`_majorant_step` over a record, row 0 zero."""
        c = self._c
        steps = pad.shape[-2]
        drive = np.max(pad / c.v, axis=-1) * (1 + 4 * _U)
        s = np.zeros((*pad.shape[:-2], steps + 1))
        # nonnegative recursion: lfilter's relative rounding is at most (1 + u)^(2k) - 1 <= 3ku
        s[..., 1:] = lfilter([1.0], [1.0, -c.rho], drive, axis=-1) * (1 + 3 * (steps + 1) * _U)
        return np.asarray(s[..., None] * c.v)
