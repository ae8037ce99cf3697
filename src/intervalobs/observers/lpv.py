r"""LPV interval observer (seed 001, (31)–(34)) and LPV interval UIO with isolation signals ((69)–(72)).

Continuous-time theory (Theorem 3.1, Lemma 4.1): with :math:`T C = I - R` (36), :math:`S` from
(37)–(42) and Metzler :math:`\underline F, \overline F`, the lower observer state :math:`\underline z`
is a lower bound of :math:`v = R(\vartheta)x` and :math:`\underline x = \underline z + T y` (32). The
estimation errors obey :math:`\dot{\underline e} = \underline F\,\underline e + w + H u_{un}` (46),
(80) with :math:`w \ge 0`, and the isolation signals :math:`\underline\varepsilon = C^\dagger(y - C
\underline x)`, :math:`\overline\varepsilon = C^\dagger(C\overline x - y)` (29)–(30) stay nonnegative
along every column :math:`H^{(j)}` whose unknown input is zero (27).

**Sound sampling** (DESIGN.md). Measurements arrive every :math:`h`; nothing is assumed about
:math:`x, \vartheta` between samples except the model. Over :math:`[t_k, t_k + h]`, with
:math:`\psi = \tfrac{d}{dt}v - \underline F v` and :math:`\underline F` constant Metzler,

.. math:: v(t_{k+1}) = e^{\underline F h} v(t_k) + \int_0^h e^{\underline F (h-s)}\psi(t_k + s)\,ds
          \;\ge\; e^{\underline F h}\,\underline z_k + \Phi\,\underline\psi_k,
          \qquad \Phi = \int_0^h e^{\underline F s}\,ds \ge 0,

where :math:`\underline\psi_k` bounds :math:`\psi` from below over the whole step, computed from a
box :math:`X_k` that contains :math:`x(t)` on the step (the model's
:meth:`~intervalobs.systems.lpv.SampledLPVModel.step_enclosure`):

.. math:: \underline\psi_k = \underline{[(\dot R + RA)x + RBu + Rc]}_{X_k}
          + \underline{[-\underline F Rx]}_{X_k} + \underline{[\Delta A_R]\cdot B_k}
          + \underline{[\Delta B_R]\,u_k} + \underline{[\Delta B_{un,R}]\,[\underline u_{un},
          \overline u_{un}]}\ (\text{UIO only}),

the last three being the terms of (31)/(69) with exact interval products
(:func:`~intervalobs.interval.interval_matvec_bounds`, never looser than the paper's
:math:`\underline{\Delta A_R}^+\underline x^+ - \dots`). The state box in the :math:`\Delta A_R` term is
:math:`B_k = \operatorname{hull}([\underline x_k, \overline x_k], X_k)`: for a measured component this is
exactly the paper's switching rule of (69)/(71) — when :math:`\underline\varepsilon^{(i)} < 0`,
:math:`\underline x^{(i)}` is replaced by :math:`\tilde x^{(i)} = (C^\dagger y)^{(i)}` (73) — extended
from the sample instant to the whole step. All outputs are widened by ``ROUNDING_MARGIN``.

Step semantics: the box of :math:`x(t_k)` needs the current output (32), so
``step(state_k, y_k, u_k)`` returns a state whose ``lower``/``upper`` are the box of :math:`x(t_k)` and
whose ``internal`` holds :math:`\underline z_{k+1}, \overline z_{k+1}` and the isolation signals at
:math:`t_k`; ``run`` row ``k`` is the same box, so ``run`` equals repeated ``step`` exactly.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import expm

from ..errors import AssumptionError, DataError, DesignError, DimensionError
from ..estimate import Estimate
from ..interval import inflate, interval_matvec_bounds, matvec_bounds
from ..systems.lpv import SampledLPVModel
from ..validation import as_box, as_matrix
from .base import Observer, ObserverState

__all__ = ["IsolationRecord", "LPVIntervalObserver", "LPVIntervalUIO"]

FloatArray = NDArray[np.float64]


def _check_metzler_hurwitz(name: str, f: FloatArray) -> None:
    off = f - np.diag(np.diag(f))
    if np.any(off < 0):
        i, j = np.argwhere(off < 0)[0]
        raise AssumptionError(f"{name}: expected a Metzler matrix, got {name}[{i},{j}] = {f[i, j]:g} < 0")
    if np.max(np.linalg.eigvals(f).real) >= 0:
        raise DesignError(
            f"{name}: expected a Hurwitz matrix, got spectral abscissa {np.max(np.linalg.eigvals(f).real):g}"
        )


def _sampled(f: FloatArray, h: float) -> tuple[FloatArray, FloatArray]:
    """``expm(F h)`` and ``∫_0^h expm(F s) ds`` (both ≥ 0 for Metzler F; rounding noise clipped)."""
    n = f.shape[0]
    block = np.zeros((2 * n, 2 * n))
    block[:n, :n] = f
    block[:n, n:] = np.eye(n)
    ex = expm(block * h)
    e, phi = ex[:n, :n], ex[:n, n:]
    for name, m in (("expm(F h)", e), ("integral of expm(F s)", phi)):
        if np.any(m < -1e-14 * max(1.0, float(np.abs(m).max()))):
            raise DesignError(f"{name}: expected a nonnegative matrix for Metzler F, got min {m.min():g}")
    return np.maximum(e, 0.0), np.maximum(phi, 0.0)


@dataclass(frozen=True)
class IsolationRecord:
    r"""Isolation signals of a run of the interval UIO.

    Attributes
    ----------
    t : numpy.ndarray, shape (T,)
    eps_lower, eps_upper : numpy.ndarray, shape (..., T, n)
        :math:`\underline\varepsilon, \overline\varepsilon` (29)–(30).
    signal_lower, signal_upper : numpy.ndarray, shape (..., T, q)
        Their coordinates along the columns of H, :math:`H_j^T\varepsilon/\|H_j\|^2` (the scalar of
        the projection :math:`\Pi(H^{(j)})\varepsilon` of (27)–(28)).
    """

    t: FloatArray
    eps_lower: FloatArray
    eps_upper: FloatArray
    signal_lower: FloatArray
    signal_upper: FloatArray


class LPVIntervalObserver(Observer):
    r"""LPV interval observer (31)–(34), sampled soundly (module docstring).

    Parameters
    ----------
    model : SampledLPVModel
        The model with its sampled-data enclosures and :math:`R(\vartheta)`.
    h : float
        Sampling interval (s).
    f_lower, f_upper : array_like, shape (n, n)
        Constant Metzler Hurwitz :math:`\underline F, \overline F` (Section 5: :math:`-\lambda I`).
    x0 : tuple of array_like
        Default prior box of :math:`x(t_0)` (20).

    Raises
    ------
    AssumptionError
        If F is not Metzler, C is not square invertible (the partitions (16)–(18) with unmeasured
        states are not implemented), or the model has a disturbance d (not covered by the sampled
        enclosure).
    DesignError
        If F is not Hurwitz.
    """

    h: float

    method = "lpv-interval-observer"

    def __init__(
        self,
        model: SampledLPVModel,
        h: float,
        f_lower: ArrayLike,
        f_upper: ArrayLike | None = None,
        x0: tuple[ArrayLike, ArrayLike] | None = None,
    ) -> None:
        if not isinstance(model, SampledLPVModel):
            raise DimensionError(f"model: expected a SampledLPVModel, got {type(model).__name__}")
        system = model.system
        self.model = model
        self.system = system
        self.n, self.p, self.m = system.n, system.p, system.m
        if self.p != self.n:
            raise AssumptionError(
                f"C: expected n_y = n_x (the partitions (16)–(18) for unmeasured states are not "
                f"implemented), got n_y = {self.p}, n_x = {self.n}"
            )
        if system.d is not None:
            raise AssumptionError("d: the sampled observer covers c but not a bounded disturbance d; got d")
        if not (np.isfinite(h) and h > 0):
            raise DataError(f"h: expected a positive sampling interval, got {h!r}")
        self.h = float(h)
        self.f_lower = as_matrix("f_lower", f_lower, (self.n, self.n))
        self.f_upper = self.f_lower.copy() if f_upper is None else as_matrix("f_upper", f_upper, (self.n, self.n))
        _check_metzler_hurwitz("f_lower", self.f_lower)
        _check_metzler_hurwitz("f_upper", self.f_upper)
        self.e_lower, self.phi_lower = _sampled(self.f_lower, self.h)
        self.e_upper, self.phi_upper = _sampled(self.f_upper, self.h)
        self.c_inv = np.linalg.inv(system.C)
        self.x0 = None if x0 is None else as_box("x0", x0, self.n)

    # --- the recursion ----------------------------------------------------------------------------
    def _unknown_input_term(self, bul: FloatArray, buh: FloatArray) -> tuple[FloatArray, FloatArray] | None:
        return None

    def advance(
        self, z_lower: FloatArray, z_upper: FloatArray, y: FloatArray, u: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        r"""One sample: box of :math:`x(t_k)`, isolation signals at :math:`t_k`, and :math:`z_{k+1}`.

        Parameters
        ----------
        z_lower, z_upper : numpy.ndarray, shape (M, n)
            Observer states at :math:`t_k`.
        y, u : numpy.ndarray, shape (M, p) and (M, m)
            Output and known input at :math:`t_k` (u held over the step).

        Returns
        -------
        x_lower, x_upper, eps_lower, eps_upper, z_lower_next, z_upper_next : numpy.ndarray
        """
        model = self.model
        r = model.r_matrix(y)
        x_tilde = y @ self.c_inv.T  # (73)
        ty = x_tilde - np.einsum("mij,mj->mi", r, x_tilde)  # T y = (I - R) C^{-1} y, (36)
        x_lo, x_hi = inflate(z_lower + ty, z_upper + ty)  # (32), (34)
        eps_lo = x_tilde - x_lo  # (29) with C invertible
        eps_hi = x_hi - x_tilde  # (30)
        enc = model.step_enclosure(x_lo, x_hi, y, u, self.h)
        b_lo, b_hi = np.minimum(x_lo, enc.flow_lower), np.maximum(x_hi, enc.flow_upper)
        fl_lo = matvec_bounds(-self.f_lower, enc.rx_lower, enc.rx_upper)[0]
        fu_hi = matvec_bounds(-self.f_upper, enc.rx_lower, enc.rx_upper)[1]
        a_lo, a_hi = interval_matvec_bounds(enc.da_lower, enc.da_upper, b_lo, b_hi)
        ub_lo, ub_hi = interval_matvec_bounds(enc.db_lower, enc.db_upper, u, u)
        psi_lo = enc.rate_lower + fl_lo + a_lo + ub_lo
        psi_hi = enc.rate_upper + fu_hi + a_hi + ub_hi
        extra = self._unknown_input_term(enc.dbun_lower, enc.dbun_upper)
        if extra is not None:
            psi_lo = psi_lo + extra[0]
            psi_hi = psi_hi + extra[1]
        zl = z_lower @ self.e_lower.T + psi_lo @ self.phi_lower.T
        zu = z_upper @ self.e_upper.T + psi_hi @ self.phi_upper.T
        zl, zu = inflate(zl, zu)
        return x_lo, x_hi, eps_lo, eps_hi, zl, zu

    # --- protocol ---------------------------------------------------------------------------------
    def init(self, x0_lower: ArrayLike | None = None, x0_upper: ArrayLike | None = None) -> ObserverState:
        """State at :math:`t_0` from the prior box: :math:`\\underline z_0, \\overline z_0` bound
        :math:`R(\\vartheta_0)x_0` over the box (the paper's :math:`\\underline\\xi_0`).

        Parameters
        ----------
        x0_lower, x0_upper : array_like, shape (n,) or (M, n), optional
            Prior box (default: ``x0`` of the constructor).

        Returns
        -------
        ObserverState
        """
        if x0_lower is None or x0_upper is None:
            if self.x0 is None:
                raise DataError("x0: expected a prior box (constructor or init), got None")
            lo, hi = self.x0
        else:
            lo = np.asarray(x0_lower, dtype=float)
            hi = np.asarray(x0_upper, dtype=float)
            if lo.shape != hi.shape or lo.shape[-1] != self.n or np.any(lo > hi) or not np.all(np.isfinite(lo + hi)):
                raise DataError(
                    f"x0: expected finite lower <= upper of shape (..., {self.n}), got {lo.shape}, {hi.shape}"
                )
        lo2, hi2 = np.atleast_2d(lo), np.atleast_2d(hi)
        zl, zu = inflate(*self.model.rx_bounds(lo2, hi2))
        if lo.ndim == 1:
            zl, zu = zl[0], zu[0]
        return ObserverState(
            lower=np.array(lo, dtype=float), upper=np.array(hi, dtype=float), internal={"z_lower": zl, "z_upper": zu}
        )

    def step(self, state: ObserverState, y: ArrayLike, u: ArrayLike | None = None) -> ObserverState:
        """Consume ``y_k, u_k``; return the box of :math:`x(t_k)` and :math:`z_{k+1}` (module docstring).

        Parameters
        ----------
        state : ObserverState
            From :meth:`init` or a previous :meth:`step`.
        y : array_like, shape (p,) or (M, p)
            Output at :math:`t_k`.
        u : array_like, shape (m,) or (M, m), optional
            Known input at :math:`t_k` (default 0).

        Returns
        -------
        ObserverState
            ``internal`` holds ``z_lower``, ``z_upper`` (at :math:`t_{k+1}`), ``eps_lower``,
            ``eps_upper`` (at :math:`t_k`).
        """
        ys = np.asarray(y, dtype=float)
        single = ys.ndim == 1
        y2 = np.atleast_2d(ys)
        if y2.shape[-1] != self.p or not np.all(np.isfinite(y2)):
            raise DataError(f"y: expected finite values of shape (..., {self.p}), got {ys.shape}")
        u2 = self._input(u, y2.shape[:-1])
        zl = np.atleast_2d(state.internal["z_lower"])
        zu = np.atleast_2d(state.internal["z_upper"])
        x_lo, x_hi, e_lo, e_hi, zl, zu = self.advance(zl, zu, y2, np.asarray(u2, dtype=float))
        if single:
            x_lo, x_hi, e_lo, e_hi, zl, zu = (a[0] for a in (x_lo, x_hi, e_lo, e_hi, zl, zu))
        return ObserverState(
            lower=x_lo,
            upper=x_hi,
            internal={"z_lower": zl, "z_upper": zu, "eps_lower": e_lo, "eps_upper": e_hi},
        )

    def run_with_signals(
        self,
        t: ArrayLike,
        y: ArrayLike,
        u: ArrayLike | None = None,
        x0_lower: ArrayLike | None = None,
        x0_upper: ArrayLike | None = None,
    ) -> tuple[Estimate, FloatArray, FloatArray]:
        """Like :meth:`run`, also returning :math:`\\underline\\varepsilon, \\overline\\varepsilon` (29)–(30).

        Parameters
        ----------
        t : array_like, shape (T,)
            Uniform sample times, spacing ``h``.
        y : array_like, shape (T, p) or (M, T, p)
            Outputs.
        u : array_like, shape (T, m) or (M, T, m), optional
            Known inputs.
        x0_lower, x0_upper : array_like, optional
            Prior box (default: the constructor's ``x0``).

        Returns
        -------
        estimate : Estimate
        eps_lower, eps_upper : numpy.ndarray, shape like ``estimate.lower``
        """
        times, ys, us = self._signals(t, y, u)
        squeeze = ys.ndim == 2
        y3 = ys[None] if squeeze else ys
        u3 = np.broadcast_to(us[None] if us.ndim == 2 else us, (*y3.shape[:-1], self.m))
        state = self.init(x0_lower, x0_upper)
        zl = np.broadcast_to(np.atleast_2d(state.internal["z_lower"]), (y3.shape[0], self.n)).copy()
        zu = np.broadcast_to(np.atleast_2d(state.internal["z_upper"]), (y3.shape[0], self.n)).copy()
        shape = (y3.shape[0], times.size, self.n)
        lo, hi, el, eh = (np.empty(shape) for _ in range(4))
        for k in range(times.size):
            lo[:, k], hi[:, k], el[:, k], eh[:, k], zl, zu = self.advance(zl, zu, y3[:, k], u3[:, k])
        if squeeze:
            lo, hi, el, eh = lo[0], hi[0], el[0], eh[0]
        meta: dict[str, Any] = {"method": self.method, "h": self.h, "transient_s": float(times[0])}
        return Estimate(times, lo, hi, meta=meta), el, eh

    def run(self, t: ArrayLike, y: ArrayLike, u: ArrayLike | None = None) -> Estimate:
        """Bounds over a whole record; ``y`` is (T, p) or (M, T, p); row k is the box of :math:`x(t_k)`.

        Parameters
        ----------
        t : array_like, shape (T,)
            Uniform sample times, spacing ``h``.
        y : array_like, shape (T, p) or (M, T, p)
            Outputs.
        u : array_like, shape (T, m) or (M, T, m), optional
            Known inputs (held over each step).

        Returns
        -------
        Estimate
        """
        return self.run_with_signals(t, y, u)[0]


class LPVIntervalUIO(LPVIntervalObserver):
    r"""LPV interval unknown-input observer (69)–(72) with isolation signals (29)–(30).

    On top of :class:`LPVIntervalObserver`: the bounded term of :math:`R\Delta B_{un}u_{un}` enters
    both bounds ((69), (71), :math:`\underline w^4, \overline w^4 \ge 0` of (83), (85)); the switching
    rule is built into the sampled step (module docstring); :math:`H = R B_{un}` must be constant
    (26) and its columns eigenvectors of both F ((103)–(104), Theorem 4.1) — checked here.

    Parameters
    ----------
    model : SampledLPVModel
        As for :class:`LPVIntervalObserver`.
    h : float
        Sampling interval (s).
    f_lower, f_upper : array_like, shape (n, n)
        Metzler Hurwitz observer matrices.
    x0 : tuple of array_like
        Default prior box.
    unknown_input : tuple of array_like
        ``(lower, upper)`` of :math:`u_{un}` with lower ≤ 0 ≤ upper (Assumption 2.2).

    Raises
    ------
    AssumptionError
        If :math:`RB_{un}` is not constant, the bounds do not contain 0, or H's columns are not
        eigenvectors of F.
    """

    method = "lpv-interval-uio"

    def __init__(
        self,
        model: SampledLPVModel,
        h: float,
        f_lower: ArrayLike,
        f_upper: ArrayLike | None = None,
        x0: tuple[ArrayLike, ArrayLike] | None = None,
        unknown_input: tuple[ArrayLike, ArrayLike] = ((), ()),
    ) -> None:
        super().__init__(model, h, f_lower, f_upper, x0)
        system = model.system
        if system.B_un is None:
            raise AssumptionError("B_un: the interval UIO needs unknown-input directions, got None")
        self.q = system.q
        self.u_un = as_box("unknown_input", unknown_input, self.q)
        if np.any(self.u_un[0] > 0) or np.any(self.u_un[1] < 0):
            raise AssumptionError("unknown_input: expected lower <= 0 <= upper (Assumption 2.2)")
        points = system.test_points()
        rb = np.einsum("kij,kjl->kil", model.r_matrix(points @ system.C.T), np.asarray(system.B_un(points)))
        self.H = rb[0]
        if not np.allclose(rb, self.H, atol=1e-9 * max(1.0, float(np.abs(self.H).max()))):
            raise AssumptionError("R, B_un: expected R(θ) B_un(θ) = H constant on theta_box (26)")
        for name, f in (("f_lower", self.f_lower), ("f_upper", self.f_upper)):
            gam = np.linalg.pinv(self.H) @ f @ self.H
            if not np.allclose(f @ self.H, self.H @ np.diag(np.diag(gam)), atol=1e-9):
                raise AssumptionError(f"{name}: expected F H = H Γ with Γ diagonal ((103)–(104))")
        col_norm2 = np.sum(self.H**2, axis=0)
        self._projector = (self.H / col_norm2).T  # rows: H_j^T / |H_j|^2

    def _unknown_input_term(self, bul: FloatArray, buh: FloatArray) -> tuple[FloatArray, FloatArray] | None:
        return interval_matvec_bounds(bul, buh, self.u_un[0], self.u_un[1])

    def fault_signals(self, eps: ArrayLike) -> FloatArray:
        """Coordinates :math:`H_j^T\\varepsilon / \\|H_j\\|^2` of isolation signals along H's columns.

        Parameters
        ----------
        eps : array_like, shape (..., n)

        Returns
        -------
        numpy.ndarray, shape (..., q)
        """
        return np.asarray(np.asarray(eps, dtype=float) @ self._projector.T)

    def isolate(self, t: ArrayLike, y: ArrayLike, u: ArrayLike | None = None) -> tuple[Estimate, IsolationRecord]:
        """Run on a record and return the state bounds and the isolation signals.

        Parameters
        ----------
        t : array_like, shape (T,)
            Uniform sample times.
        y : array_like, shape (T, p) or (M, T, p)
            Outputs.
        u : array_like, shape (T, m) or (M, T, m), optional
            Known inputs.

        Returns
        -------
        estimate : Estimate
        record : IsolationRecord
        """
        est, el, eh = self.run_with_signals(t, y, u)
        return est, IsolationRecord(est.t, el, eh, self.fault_signals(el), self.fault_signals(eh))
