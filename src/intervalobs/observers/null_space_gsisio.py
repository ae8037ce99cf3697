r"""The sound simultaneous input and state observer for rank-deficient H (Khajenejad & Yong made sound).

System (Khajenejad & Yong, eq. (3); :class:`~intervalobs.systems.nonlinear.NonlinearSystem`):
:math:`x_{k+1} = f(x_k) + Bu_k + Gd_k + w_k`, :math:`y_k = g(x_k) + Du_k + Hd_k + v_k`.

:class:`NullSpaceGSISIO` is the sound variant of :class:`~intervalobs.observers.gsisio.GSISIO` for
rank-deficient H, with any number
:math:`h = q - \mathrm{rk}H` of hidden input directions. With the SVD :math:`H = U_1\Sigma V_1^\top`,
:math:`U_2^\top H = 0`, :math:`HV_2 = 0` (:math:`V_2` has h columns):

* coordinates :math:`z = (a, t) = Zx`, :math:`Z = [R; S]`, with :math:`RGV_2 = 0` (the hidden
  input components cannot move :math:`a`) and :math:`SGV_2 = I_h` (:math:`GV_2` has rank h because
  :math:`[G; H]` has full column rank);
* prediction of :math:`a`: since :math:`RG = RGH^\dagger H`, for every gain
  :math:`\ell = RGH^\dagger + \lambda U_2^\top`,

  .. math:: a_{k+1} = Rf(x_k) - \ell g(x_k) + RBu_k + \ell(y_k - Du_k) + Rw_k - \ell v_k,

  a bound free of :math:`d` (each :math:`\lambda` is valid; several are intersected: a fixed one, the
  certificate's, and per-step ones cancelling the sensitivity of the right-hand side to :math:`t`);
* correction of :math:`t \in \mathbb R^h` from the *current* d-free output
  :math:`U_2^\top(y_{k+1} - Du_{k+1}) = U_2^\top g(x_{k+1}) + U_2^\top v_{k+1}`, preconditioned by
  matrices P (h rows), by an H-matrix bound and interval Gauss–Seidel in :math:`t`. **Existence
  condition** (checked by :meth:`NullSpaceGSISIO.design`, ``AssumptionError`` naming it):
  :math:`p - \mathrm{rk}H \ge h`, and some P makes the global slope
  :math:`P\,\partial(U_2^\top g)/\partial t` an H-matrix (for h = 1: a d-free output strictly
  monotone along :math:`GV_2`);
* delayed inputs: :math:`V_1^\top d_k = \Sigma^{-1}U_1^\top(y_k - g(x_k) - Du_k - v_k)` and
  :math:`V_2^\top d_k = t_{k+1} - S(f(x_k) + Bu_k + w_k) - (SGH^\dagger + \mu U_2^\top)
  (y_k - g(x_k) - Du_k - v_k)`;
* width guarantee: :meth:`NullSpaceGSISIO.width_certificate` bounds the widths at design time,
  :math:`\Delta z_{k+1} \le \Gamma\Delta z_k + \gamma`, from the decomposition's global interval
  Jacobians (a small-gain condition :math:`\rho(\Gamma) < 1`; the steady bound
  :math:`(I - \Gamma)^{-1}\gamma`), or says why none exists;
* every range (of :math:`f, g` combinations over the current box) is the intersection of the natural
  interval extension, the mean-value form and the Jacobian-based decomposition with *local* Jacobian
  bounds, on a split of the box, and the decomposition with global Jacobian bounds on the whole box.

Rows of :meth:`NullSpaceGSISIO.run`: ``lower[k]``, ``upper[k]`` bound :math:`x_k` given
:math:`y_0 \dots y_k` (the current output is needed: without it :math:`x_k` is unbounded along
:math:`GV_2`); ``step(state, y_k, u_k)`` consumes :math:`y_k` and returns the state *at* k.
``input_lower[k]`` bounds :math:`d_{k-1}` (row 0 :math:`[-\infty, \infty]`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._docstrings import shared_docs
from ..design.composed_range import ComposedRange
from ..design.gsisio import CERTIFICATE_FLOOR, CERTIFICATE_MARGIN
from ..design.mixed_monotone import jacobian_bounds, width_matrix
from ..errors import AssumptionError, DimensionError
from ..inclusion import evaluate_matrix
from ..interval import inflate, matvec_bounds, sandwich_bounds
from ..systems.bounds import Bounds
from ..systems.nonlinear import NonlinearSystem
from ..validation import check_no_kwargs
from .base import Observer, ObserverState

__all__ = ["NullSpaceGSISIO", "WidthCertificate"]

FloatArray = NDArray[np.float64]

_SINGULAR_TOLERANCE = 1e-12
"""Relative size below which an inverse entry counts as negative and a determinant as zero (decides which
preconditioner is tried; the bounds built with the chosen one are sound whatever it is)."""
BoxPair = tuple[FloatArray, FloatArray]


def _round_up(widths: FloatArray) -> FloatArray:
    """Nonnegative certified widths rounded up by the certificate margin (norms, solves and geometric sums)."""
    return inflate(0.0, widths, CERTIFICATE_MARGIN, floor=0.0)[1]


def _divide(num: BoxPair, den: BoxPair) -> BoxPair:
    """Interval division; every denominator interval excludes 0."""
    q = np.stack([num[0] / den[0], num[0] / den[1], num[1] / den[0], num[1] / den[1]])
    return inflate(q.min(axis=0), q.max(axis=0))


def _product(a: BoxPair, b: BoxPair) -> BoxPair:
    """Elementwise interval product, outward rounded."""
    p = np.stack([a[0] * b[0], a[0] * b[1], a[1] * b[0], a[1] * b[1]])
    return inflate(p.min(axis=0), p.max(axis=0))


def _h_matrix_inverse(lo: FloatArray, hi: FloatArray) -> FloatArray | None:
    r"""The inverse of the comparison matrix :math:`\langle A\rangle` of an interval matrix, or None.

    :math:`\langle A\rangle_{ii} = \min|A_{ii}|` (0 if :math:`A_{ii} \ni 0`),
    :math:`\langle A\rangle_{ij} = -\max|A_{ij}|`. A is an H-matrix iff :math:`\langle A\rangle` is a
    nonsingular M-matrix; then every :math:`\tilde A \in A` is nonsingular and
    :math:`|\tilde A^{-1}| \le \langle A\rangle^{-1}` (Ostrowski), so :math:`\tilde A t = r` gives
    :math:`|t| \le \langle A\rangle^{-1}|r|`. Returned rounded up (relative 1e-9), None if not an H-matrix.
    """
    mag = np.maximum(np.abs(lo), np.abs(hi))
    mig = np.where((lo > 0) | (hi < 0), np.minimum(np.abs(lo), np.abs(hi)), 0.0)
    diag = np.diag(mig)
    if np.any(diag <= 0):
        return None
    off = mag - np.diag(np.diag(mag))
    if np.max(np.abs(np.linalg.eigvals(off / diag[:, None]))) >= 1.0 - 1e-9:
        return None
    inverse = np.linalg.inv(np.diag(diag) - off)
    if np.any(inverse < -_SINGULAR_TOLERANCE * np.abs(inverse).max()):
        return None
    return _round_up(np.maximum(inverse, 0.0))


@dataclass(frozen=True)
class WidthCertificate:
    r"""Design-time bound of :class:`NullSpaceGSISIO`'s widths (see :meth:`NullSpaceGSISIO.width_certificate`).

    In the coordinates :math:`z = (a, t)` the widths obey, componentwise,
    :math:`\Delta a_{k+1} \le W_a\Delta z_k + \omega_a` and
    :math:`\Delta t_{k+1} \le 2\langle M\rangle^{-1}(W_{F}\Delta a_{k+1} + \omega_t)`, i.e.
    :math:`\Delta z_{k+1} \le \Gamma\Delta z_k + \gamma` with :math:`\Gamma \ge 0`.

    Attributes
    ----------
    holds : bool
        :math:`\rho(\Gamma) < 1`: the widths stay bounded, with the steady bounds below.
    reason : str
        Why no certificate exists, or ``"rho(Gamma) < 1"``.
    Gamma : numpy.ndarray, shape (n, n)
    gamma : numpy.ndarray, shape (n,)
    spectral_radius : float
        :math:`\rho(\Gamma)`.
    W_a, W_F, M_inverse : numpy.ndarray
        The decomposition's width matrix of the a-prediction (fixed certificate gain), of the
        preconditioned d-free outputs in a, and :math:`\langle M\rangle^{-1}` of their global slope in t.
    gain : numpy.ndarray
        The fixed gain :math:`\ell_c` whose prediction the bound uses (intersected at every step).
    z_width_steady, x_width_steady, d_width_steady : numpy.ndarray
        :math:`(I - \Gamma)^{-1}\gamma`, its image :math:`|Z^{-1}|\Delta z` and the delayed input bound
        (NaN when the certificate does not hold).
    d_matrix, d_offset : numpy.ndarray
        :math:`\Delta d_k \le D_z\Delta z_k + D_t\Delta t_{k+1} + \delta`, stored as ``d_matrix`` =
        :math:`[D_z, D_t]` and ``d_offset`` = :math:`\delta`.
    Zinv : numpy.ndarray, shape (n, n)
        :math:`Z^{-1}`, mapping z widths to x widths (:math:`\Delta x \le |Z^{-1}|\Delta z`).
    """

    holds: bool
    reason: str
    Gamma: FloatArray
    gamma: FloatArray
    spectral_radius: float
    W_a: FloatArray
    W_F: FloatArray
    M_inverse: FloatArray
    gain: FloatArray
    z_width_steady: FloatArray
    x_width_steady: FloatArray
    d_width_steady: FloatArray
    d_matrix: FloatArray
    d_offset: FloatArray
    Zinv: FloatArray

    def width_bounds(self, z0_width: ArrayLike, steps: int) -> tuple[FloatArray, FloatArray]:
        r"""A-priori width bounds for every step: :math:`\Delta z_k \le \Gamma^k\Delta z_0 + \sum_{i<k}\Gamma^i\gamma`.

        Parameters
        ----------
        z0_width : array_like, shape (n,)
            Width of the box at step 0 in z (the hull of :math:`Zx_0`; the t part may be the corrected one).
        steps : int
            Number of steps.

        Returns
        -------
        x_width, d_width : numpy.ndarray, shape (steps, n) and (steps, q)
            Bounds of the state widths (row k: :math:`x_k`) and of the delayed input widths (row k:
            :math:`d_{k-1}`, row 0 NaN). Up to the floating-point margins (relative 1e-12 of the
            bounds' magnitude per step).
        """
        n = self.Gamma.shape[0]
        z = np.empty((steps, n))
        z[0] = np.asarray(z0_width, dtype=float)
        for k in range(1, steps):
            z[k] = self.Gamma @ z[k - 1] + self.gamma
        x = z @ np.abs(self.Zinv).T
        n_t = self.M_inverse.shape[0]
        d = np.full((steps, self.d_offset.size), np.nan)
        if steps > 1:
            stacked = np.concatenate([z[:-1], z[1:, n - n_t :]], axis=-1)
            d[1:] = stacked @ self.d_matrix.T + self.d_offset
        return _round_up(x), _round_up(d)

    def as_dict(self) -> dict[str, Any]:
        """Numbers for ``summary.json``.

        Returns
        -------
        dict
        """
        return {
            "holds": self.holds,
            "reason": self.reason,
            "spectral_radius_Gamma": self.spectral_radius,
            "Gamma": self.Gamma,
            "gamma": self.gamma,
            "W_a": self.W_a,
            "W_F": self.W_F,
            "M_inverse": self.M_inverse,
            "certificate_gain": self.gain,
            "z_width_steady": self.z_width_steady,
            "x_width_steady": self.x_width_steady,
            "d_width_steady": self.d_width_steady,
        }


class NullSpaceGSISIO(Observer):
    r"""GSISIO made sound for rank-deficient H: uses the d-free part :math:`U_2^\top y_k` of the current output.

    See the module docstring for the construction. Use :meth:`design`.

    Parameters
    ----------
    system : NonlinearSystem
        The model (Jacobians automatic or given).
    bounds : Bounds
        Boxes of ``x0``, ``w`` and ``v``.
    direction : str
        ``'orthogonal'`` (default: :math:`S = (GV_2)^\dagger`) or ``'output'`` (:math:`S` from the d-free
        outputs' gradients at the centre of x0).
    gain_factors : tuple of float
        Multiples of the per-step t-cancelling gain; the predictions of all (and of the fixed
        certificate gain) are intersected.
    splits : int
        Sub-boxes per axis for the range bounds.
    newton_steps : int
        Interval Gauss–Seidel iterations for t.

    Attributes
    ----------
    Z : numpy.ndarray, shape (n, n)
        Coordinates :math:`z = (a, t) = Zx`: rows R (:math:`RGV_2 = 0`), then S (:math:`SGV_2 = I_h`).
    R, S : numpy.ndarray
        The two blocks of Z.
    hidden : int
        Number of hidden input directions :math:`h = q - \mathrm{rk}(H)`.
    slope : tuple of numpy.ndarray
        Global bounds of :math:`\partial(U_2^\top g)/\partial t`, shape (p - rk H, h).
    preconditioners : list of numpy.ndarray
        Matrices P (h, p - rk H) for which :math:`P\,\partial(U_2^\top g)/\partial t` is
        generalised diagonally dominant on the whole space (the existence condition).
    """

    summary_fields = ("hidden", "newton_steps")
    rows = "filtered"

    def __init__(
        self,
        system: NonlinearSystem,
        bounds: Bounds,
        direction: str = "orthogonal",
        gain_factors: tuple[float, ...] = (0.0, 1.0),
        splits: int = 2,
        newton_steps: int = 3,
    ) -> None:
        from itertools import combinations

        from scipy.linalg import null_space

        self.system = system
        self.bounds = bounds.resolve(system)
        self.n, self.p, self.m = system.n, system.p, system.m
        self.gain_factors = tuple(float(c) for c in gain_factors)
        self.newton_steps = int(newton_steps)
        n, p, q = system.n, system.p, system.q
        g_jac = system.jacobians()[1]
        U, S, Vt = np.linalg.svd(system.H)
        rank = int(np.sum(S > (S.max() if S.size else 0.0) * 1e-10))
        self.sigma = S[:rank]
        self.U1, self.U2 = U[:, :rank], U[:, rank:]
        self.V1, self.V2 = Vt[:rank].T, Vt[rank:].T
        h = q - rank
        self.hidden = h
        H_pinv = np.linalg.pinv(system.H)
        centre = self.bounds.centre("x0")
        if direction not in ("output", "orthogonal"):
            raise DimensionError(f"direction: expected 'output' or 'orthogonal', got {direction!r}")
        self.g2 = system.G @ self.V2  # (n, h): how the hidden input components move the state
        if h > 0:
            if self.U2.shape[1] < h:
                raise AssumptionError(
                    f"NullSpaceGSISIO: existence condition fails: {self.U2.shape[1]} d-free outputs "
                    f"(p - rk H) for {h} hidden input directions (q - rk H): the hidden input cannot be recovered"
                )
            R = null_space(self.g2.T).T  # rank G V2 = h because [G; H] has full column rank
            S_rows = np.linalg.pinv(self.g2)
            if direction == "output":
                grads = self.U2.T @ evaluate_matrix(g_jac, centre, (p, n))
                wg = grads @ self.g2
                if np.linalg.matrix_rank(wg) == h:
                    S_rows = np.linalg.pinv(wg) @ grads
        else:
            R, S_rows = np.eye(n), np.zeros((0, n))
        self.R, self.S = R, S_rows
        self.Z = np.vstack([R, S_rows])
        self.Zinv = np.linalg.inv(self.Z)
        self.n_a = R.shape[0]
        self.ell0 = R @ system.G @ H_pinv
        self.kappa0 = S_rows @ system.G @ H_pinv  # (h, p)
        self._range = ComposedRange(system, self.Zinv, splits)
        self.E_t = self.Zinv[:, self.n_a :]  # (n, h): the t-columns of Z^{-1}
        self.preconditioners: list[FloatArray] = []
        self._m_inverse: list[FloatArray] = []
        r2 = self.U2.shape[1]
        if h > 0:
            inf = np.full(n, np.inf)
            jg_lo, jg_hi = jacobian_bounds(g_jac, -inf, inf, (p, n), "g_jacobian")
            self.slope = sandwich_bounds(self.U2.T, jg_lo, jg_hi, self.E_t)  # (r2, h)
            mid = 0.5 * (self.slope[0] + self.slope[1])
            candidates: list[FloatArray] = [np.asarray(np.linalg.pinv(mid), dtype=float)]
            for rows in list(combinations(range(r2), h))[:20]:
                block = mid[list(rows)]
                if abs(np.linalg.det(block)) > _SINGULAR_TOLERANCE * max(1.0, np.abs(block).max() ** h):
                    chosen = np.zeros((h, r2))
                    chosen[:, list(rows)] = np.linalg.inv(block)
                    candidates.append(chosen)
            for candidate in candidates:
                m_lo, m_hi = sandwich_bounds(candidate, self.slope[0], self.slope[1], np.eye(h))
                inverse = _h_matrix_inverse(m_lo, m_hi)
                if inverse is not None:
                    self.preconditioners.append(candidate)
                    self._m_inverse.append(inverse)
            if not self.preconditioners:
                raise AssumptionError(
                    "NullSpaceGSISIO: the outputs free of unknown inputs do not determine the hidden state: "
                    f"their slope along the hidden directions G V2 (bounds {np.round(self.slope[0], 4).tolist()} "
                    f"to {np.round(self.slope[1], 4).tolist()}) is not invertible under any preconditioner "
                    "(one hidden direction: those outputs are not strictly monotone along it)"
                )
            # fixed certificate gains: cancel the t-sensitivity at the centre of x0
            lam, mu = self._cancelling(centre)
            self.ell_c = self._certificate_gain(self.ell0 + lam @ self.U2.T)
            self.kappa_c = self.kappa0 + mu @ self.U2.T
        else:
            self.slope = (np.zeros((r2, 0)), np.zeros((r2, 0)))
            self.ell_c, self.kappa_c = self.ell0, self.kappa0
        self._p_stack = np.concatenate(self.preconditioners, axis=0) if self.preconditioners else np.zeros((0, r2))

    @classmethod
    def design(cls, system: NonlinearSystem, bounds: Bounds, **options: Any) -> NullSpaceGSISIO:
        """Build the observer; checks the existence condition.

        The existence condition: at least as many d-free outputs as hidden input directions (:math:`p -
        \\mathrm{rk}H \\ge q - \\mathrm{rk}H`), and a preconditioner P for which the global slope
        :math:`P\\,\\partial(U_2^\\top g)/\\partial t` is generalised diagonally dominant (one hidden direction:
        some d-free output strictly monotone along :math:`GV_2`). Then the current d-free outputs determine t, and
        the interval Gauss–Seidel step cannot divide by an interval containing 0.

        Parameters
        ----------
        system : NonlinearSystem
            Any number of hidden input directions the structure allows.
        bounds : Bounds
            Boxes of ``x0``, ``w`` and ``v``.
        **options
            ``direction`` ('orthogonal' (default) or 'output'), ``gain_factors`` (multiples of the
            per-step t-cancelling gain; default (0, 1)), ``splits`` (per axis, default 2),
            ``newton_steps`` (default 3).

        Returns
        -------
        NullSpaceGSISIO

        Raises
        ------
        AssumptionError
            The existence condition fails (the message names which part).
        """
        check_no_kwargs("NullSpaceGSISIO.design", options, ("direction", "gain_factors", "splits", "newton_steps"))
        return cls(system, bounds, **options)

    # ---- helpers -----------------------------------------------------------------------------------
    def _cancelling(self, xc: FloatArray) -> tuple[FloatArray, FloatArray]:
        """lambda (..., n_a, r2) and mu (..., h, r2) that cancel d/dt of the a- and chi-rows at points xc."""
        f_jac, g_jac = self.system.jacobians()
        jf = evaluate_matrix(f_jac, xc, (self.n, self.n))
        jg = evaluate_matrix(g_jac, xc, (self.p, self.n))
        jf_t, jg_t = jf @ self.E_t, jg @ self.E_t  # (..., n, h), (..., p, h)
        den_pinv = np.linalg.pinv(self.U2.T @ jg_t, rcond=1e-10)  # (..., h, r2)
        num_a = self.R @ jf_t - self.ell0 @ jg_t  # (..., n_a, h)
        num_s = self.S @ jf_t - self.kappa0 @ jg_t  # (..., h, h)
        return num_a @ den_pinv, num_s @ den_pinv

    def _gains(self, zlo: FloatArray, zhi: FloatArray) -> tuple[list[FloatArray], list[FloatArray]]:
        """Per-run gains ell (n_a x p) and kappa (h x p): the fixed certificate gain and the per-step ones."""
        lead = zlo.shape[:-1]
        fixed_ell = np.broadcast_to(self.ell_c, (*lead, *self.ell_c.shape))
        fixed_kap = np.broadcast_to(self.kappa_c, (*lead, *self.kappa_c.shape))
        if self.hidden == 0:
            return [fixed_ell], [fixed_kap]
        lam, mu = self._cancelling((0.5 * (zlo + zhi)) @ self.Zinv.T)
        ells = [fixed_ell] + [self.ell0 + c * lam @ self.U2.T for c in self.gain_factors]
        kaps = [fixed_kap] + [self.kappa0 + c * mu @ self.U2.T for c in self.gain_factors]
        return ells, kaps

    def _target(self, y: FloatArray, u: FloatArray) -> BoxPair:
        """Bounds of the preconditioned d-free outputs P U2' g(x_k), stacked over the preconditioners."""
        base = (y - u @ self.system.D.T) @ self.U2
        vlo, vhi = matvec_bounds(self.U2.T, *self.bounds.v)
        return matvec_bounds(self._p_stack, base - vhi, base - vlo)

    def _correct_t(
        self, a_lo: FloatArray, a_hi: FloatArray, y: FloatArray, u: FloatArray, prior: BoxPair | None, guess: FloatArray
    ) -> BoxPair:
        r"""Bounds of t from :math:`PU_2^\top g(Z^{-1}(a, t)) \in P U_2^\top(y - Du - v)`, for a in its box.

        Three sound steps, intersected: the H-matrix bound around a point :math:`\hat t` solving the
        equation at the centre of the a-box (:math:`|t - \hat t| \le \langle M\rangle^{-1}|r|`, the
        one the width certificate uses), the same around ``guess``, and interval Gauss–Seidel sweeps
        with local slopes.
        """
        lead = a_lo.shape[:-1]
        h, na = self.hidden, self.n_a
        phi = np.concatenate([np.zeros((self._p_stack.shape[0], self.n)), self._p_stack @ self.U2.T], axis=1)
        phi = np.broadcast_to(phi, (*lead, *phi.shape))
        t_lo_m, t_hi_m = self._target(y, u)
        blocks = [slice(i * h, (i + 1) * h) for i in range(len(self.preconditioners))]
        a_c = 0.5 * (a_lo + a_hi)

        def residual(t_point: FloatArray) -> BoxPair:
            zlo = np.concatenate([a_lo, t_point], -1)
            zhi = np.concatenate([a_hi, t_point], -1)
            hlo, hhi = self._range.bounds(phi, zlo, zhi)
            return t_lo_m - hhi, t_hi_m - hlo

        def h_bound(t_point: FloatArray) -> BoxPair:
            rlo, rhi = residual(t_point)
            lo_out = np.full((*lead, h), -np.inf)
            hi_out = np.full((*lead, h), np.inf)
            for blk, inverse in zip(blocks, self._m_inverse):
                r_abs = np.maximum(np.abs(rlo[..., blk]), np.abs(rhi[..., blk]))
                rad = r_abs @ inverse.T
                c_lo, c_hi = inflate(t_point - rad, t_point + rad)
                lo_out, hi_out = np.maximum(lo_out, c_lo), np.minimum(hi_out, c_hi)
            return lo_out, hi_out

        # point solve at the centre of the a-box (chord iterations with the first preconditioner)
        t_hat = np.array(guess, dtype=float)
        target_mid = 0.5 * (t_lo_m + t_hi_m)[..., blocks[0]]
        phi0 = phi[..., blocks[0], :]
        for _ in range(60):
            step = self._range.point(phi0, np.concatenate([a_c, t_hat], -1)) - target_mid
            t_hat = t_hat - step
            if np.all(np.abs(step) <= 1e-13 * (1.0 + np.abs(t_hat))):
                break
        t_lo, t_hi = h_bound(t_hat)
        g_lo, g_hi = h_bound(np.asarray(guess, dtype=float))
        t_lo, t_hi = np.maximum(t_lo, g_lo), np.minimum(t_hi, g_hi)
        if prior is not None:
            t_lo, t_hi = np.maximum(t_lo, prior[0]), np.minimum(t_hi, prior[1])
        m_glob = [sandwich_bounds(P, self.slope[0], self.slope[1], np.eye(h)) for P in self.preconditioners]
        for _ in range(self.newton_steps):
            before = (t_lo.copy(), t_hi.copy())
            c = 0.5 * (t_lo + t_hi)
            rlo, rhi = residual(c)
            jlo, jhi = self._range.jacobian(phi, np.concatenate([a_lo, t_lo], -1), np.concatenate([a_hi, t_hi], -1))
            for blk, (g_mlo, g_mhi) in zip(blocks, m_glob):
                s_lo = np.maximum(jlo[..., blk, na:], g_mlo)
                s_hi = np.minimum(jhi[..., blk, na:], g_mhi)
                for i in range(h):
                    num_lo, num_hi = rlo[..., blk][..., i], rhi[..., blk][..., i]
                    for j in range(h):
                        if j == i:
                            continue
                        p_lo, p_hi = _product(
                            (s_lo[..., i, j], s_hi[..., i, j]), (t_lo[..., j] - c[..., j], t_hi[..., j] - c[..., j])
                        )
                        num_lo, num_hi = num_lo - p_hi, num_hi - p_lo
                    n_lo, n_hi = _divide((num_lo, num_hi), (s_lo[..., i, i], s_hi[..., i, i]))
                    new_lo, new_hi = inflate(c[..., i] + n_lo, c[..., i] + n_hi)
                    t_lo[..., i] = np.maximum(t_lo[..., i], new_lo)
                    t_hi[..., i] = np.minimum(t_hi[..., i], new_hi)
            bad = np.any(t_lo > t_hi, axis=-1, keepdims=True)  # inconsistent data or rounding: keep the last box
            if np.any(bad):
                t_lo, t_hi = np.where(bad, before[0], t_lo), np.where(bad, before[1], t_hi)
        return t_lo, t_hi

    # ---- the width certificate ---------------------------------------------------------------------
    def _small_gain(self, ell: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray] | None:
        """Gamma, gamma, W_a, W_F, <M>^-1 of the certificate for the a-prediction gain ``ell`` (None: unbounded)."""
        n, na, h = self.n, self.n_a, self.hidden
        ja = self._range.global_jacobian(np.concatenate([self.R, -ell], axis=1))
        if ja is None:
            return None
        W_a = width_matrix(*ja)
        dw, dv = self.bounds.w[1] - self.bounds.w[0], self.bounds.v[1] - self.bounds.v[0]
        omega_a = np.abs(self.R) @ dw + np.abs(ell) @ dv
        if h == 0:
            return W_a, omega_a, W_a, np.zeros((0, na)), np.zeros((0, 0))
        P, minv = self.preconditioners[0], self._m_inverse[0]
        jfz = self._range.global_jacobian(np.concatenate([np.zeros((h, n)), P @ self.U2.T], axis=1))
        assert jfz is not None
        W_F = width_matrix(*jfz)[:, :na]
        omega_t = np.abs(P @ self.U2.T) @ dv + CERTIFICATE_FLOOR
        Gamma = np.vstack([W_a, 2.0 * minv @ W_F @ W_a])
        gamma = np.concatenate([omega_a, 2.0 * minv @ (W_F @ omega_a + omega_t)])
        return Gamma, gamma, W_a, W_F, minv

    def _certificate_gain(self, start: FloatArray) -> FloatArray:
        r"""The fixed gain :math:`\ell_c = \ell_0 + \lambda U_2^\top` minimising the certified steady width.

        Nelder–Mead over :math:`\lambda` from the t-cancelling gain and from :math:`\ell_0`; the
        objective is :math:`\sum|Z^{-1}|(I - \Gamma)^{-1}\gamma` where :math:`\rho(\Gamma) < 1`,
        else :math:`10^6 + \rho(\Gamma)`. Any :math:`\lambda` gives a sound prediction, so the
        optimiser's result needs no verification beyond the certificate itself.
        """
        from scipy.optimize import minimize

        r2 = self.U2.shape[1]
        if r2 == 0 or self._range.global_fg is None:
            return start

        def gain(lam: FloatArray) -> FloatArray:
            return np.asarray(self.ell0 + lam.reshape(self.n_a, r2) @ self.U2.T, dtype=float)

        def objective(lam: FloatArray) -> float:
            parts = self._small_gain(gain(lam))
            assert parts is not None
            Gamma, gamma = parts[0], parts[1]
            radius = float(np.max(np.abs(np.linalg.eigvals(Gamma))))
            if not radius < 1.0:
                return 1e6 + radius
            return float(np.sum(np.abs(self.Zinv) @ np.linalg.solve(np.eye(self.n) - Gamma, gamma)))

        starts = [np.asarray((start - self.ell0) @ self.U2, dtype=float).ravel(), np.zeros(self.n_a * r2)]
        options = {"maxiter": 400, "xatol": 1e-6}
        runs = [minimize(objective, x0, method="Nelder-Mead", options=options) for x0 in starts]
        best = min(runs, key=lambda res: float(res.fun))
        return gain(best.x) if float(best.fun) < objective(starts[0]) else start

    def width_certificate(self) -> WidthCertificate:
        r"""A design-time bound of the widths, from the decomposition's global interval Jacobians.

        Every step intersects (i) the a-prediction with the fixed gain :math:`\ell_c` bounded by the
        mixed-monotone decomposition with *global* Jacobian bounds of :math:`\psi = [R, -\ell_c][f; g]\circ Z^{-1}`,
        whose width is at most :math:`W_a\Delta z_k` plus the noise widths
        :math:`\omega_a = |R|\Delta w + |\ell_c|\Delta v`; and (ii) the t-bound
        :math:`\hat t \pm \langle M\rangle^{-1}|r|` around a point :math:`\hat t` solving the
        preconditioned d-free output equation at the centre of the a-box, where
        :math:`r = PU_2^\top(y - Du - v) - F([a], \hat t)` contains 0 (so :math:`|r| \le` its width
        :math:`\le W_F\Delta a + \omega_t`, :math:`\omega_t = |PU_2^\top|\Delta v`). Hence
        :math:`\Delta z_{k+1} \le \Gamma\Delta z_k + \gamma`,

        .. math:: \Gamma = \begin{bmatrix} W_a \\ 2\langle M\rangle^{-1}W_FW_a \end{bmatrix},\qquad
                  \gamma = \begin{bmatrix} \omega_a \\ 2\langle M\rangle^{-1}(W_F\omega_a + \omega_t) \end{bmatrix},

        and if :math:`\rho(\Gamma) < 1` the widths stay below
        :math:`(I - \Gamma)^{-1}\gamma` (in z; :math:`|Z^{-1}|` of it in x) after the transient
        :math:`\Gamma^k\Delta z_0`. Input widths follow from the input bounds with the fixed gains. No
        certificate exists when a Jacobian is unbounded on the whole space or :math:`\rho(\Gamma) \ge 1`
        (the reason is stated). The bound assumes the point solve reached a residual below its tolerance
        (1e-13 relative), which makes :math:`0 \in r` hold up to that residual, added to
        :math:`\omega_t`.

        Returns
        -------
        WidthCertificate

        References
        ----------
        Khajenejad & Yong: decomposition (2), input bounds (5)–(7).
        """
        sysm = self.system
        n, na, h = self.n, self.n_a, self.hidden
        dw, dv = self.bounds.w[1] - self.bounds.w[0], self.bounds.v[1] - self.bounds.v[0]
        nan_n, nan_q = np.full(n, np.nan), np.full(sysm.q, np.nan)
        V = np.concatenate([self.V1, self.V2], axis=1)
        empty = np.zeros((0, 0))

        def fail(reason: str) -> WidthCertificate:
            return WidthCertificate(False, reason, np.full((n, n), np.nan), nan_n, np.nan, empty, empty, empty,
                                    self.ell_c, nan_n, nan_n, nan_q, empty, nan_q, self.Zinv)  # fmt: skip

        parts = self._small_gain(self.ell_c)
        if parts is None:
            return fail("a Jacobian of f or g is unbounded on the whole space: no global decomposition")
        Gamma, gamma, W_a, W_F, minv = parts
        r1 = self.U1.shape[1]
        j1 = self._range.global_jacobian(np.concatenate([np.zeros((r1, n)), self.U1.T], axis=1))
        assert j1 is not None
        d1_rows = np.abs(V[:, :r1]) / self.sigma[None, :]  # |V1| Sigma^-1
        if h > 0:
            jchi = self._range.global_jacobian(np.concatenate([self.S, -self.kappa_c], axis=1))
            assert jchi is not None
            d2_z = width_matrix(*jchi)
            d2_const = np.abs(self.S) @ dw + np.abs(self.kappa_c) @ dv
        else:
            d2_z, d2_const = np.zeros((0, n)), np.zeros(0)
        # delayed inputs: |V1| S^-1 (W_1 dz + |U1'| dv) + |V2| (dt_{k+1} + W_chi dz + const)
        W_1 = width_matrix(*j1)
        D_z = d1_rows @ W_1 + np.abs(self.V2) @ d2_z
        D_t = np.abs(self.V2)
        offset = d1_rows @ (np.abs(self.U1.T) @ dv) + np.abs(self.V2) @ d2_const
        d_matrix = np.concatenate([D_z, D_t], axis=1)
        radius = float(np.max(np.abs(np.linalg.eigvals(Gamma)))) if n else 0.0
        if not radius < 1.0:
            cert = fail(
                f"rho(Gamma) = {radius:.4g} >= 1: the decomposition's global Jacobian bounds give no contraction"
            )
            return WidthCertificate(False, cert.reason, Gamma, gamma, radius, W_a, W_F, minv, self.ell_c,
                                    nan_n, nan_n, nan_q, d_matrix, offset, self.Zinv)  # fmt: skip
        z_steady = _round_up(np.asarray(np.linalg.solve(np.eye(n) - Gamma, gamma), dtype=float))
        x_steady = np.abs(self.Zinv) @ z_steady
        d_steady = D_z @ z_steady + D_t @ z_steady[na:] + offset
        return WidthCertificate(True, "rho(Gamma) < 1", Gamma, gamma, radius, W_a, W_F, minv, self.ell_c,
                                z_steady, x_steady, _round_up(d_steady), d_matrix, offset, self.Zinv)  # fmt: skip

    # ---- protocol ----------------------------------------------------------------------------------
    @shared_docs
    def init(self, x0_lower: ArrayLike | None = None, x0_upper: ArrayLike | None = None) -> ObserverState:
        """State before the first measurement: the prior box of :math:`x_0` (in z: its interval hull).

        %(prior_box)s
        """
        lo, hi = self._prior_box(self.bounds.x0, x0_lower, x0_upper)
        zlo, zhi = inflate(*matvec_bounds(self.Z, lo, hi))
        unbounded = np.full(self.system.q, np.inf)
        internal = {"z_lower": zlo, "z_upper": zhi, "started": False}
        return ObserverState(lo.copy(), hi.copy(), -unbounded, unbounded, internal)

    def _step(self, state: ObserverState, y: FloatArray, u: FloatArray) -> ObserverState:
        """Consume :math:`y_k, u_k` and return the state *at* k: box of :math:`x_k` and of :math:`d_{k-1}`."""
        sysm = self.system
        yk, uk = y, u
        zlo = np.asarray(state.internal["z_lower"], float)
        zhi = np.asarray(state.internal["z_upper"], float)
        lead = yk.shape[:-1]
        zlo, zhi = np.broadcast_to(zlo, (*lead, self.n)), np.broadcast_to(zhi, (*lead, self.n))
        started = bool(state.internal.get("started", False))
        na = self.n_a
        d_lo = np.full((*lead, sysm.q), -np.inf)  # no bound of d_{-1}
        d_hi = np.full_like(d_lo, np.inf)
        if started:
            y_prev = np.asarray(state.internal["y"], float)
            u_prev = np.asarray(state.internal["u"], float)
            a_lo, a_hi, g1, chi_rows = self._predict(zlo, zhi, y_prev, u_prev)
        else:
            a_lo, a_hi = zlo[..., :na], zhi[..., :na]
        if self.hidden > 0:
            prior = None if started else (zlo[..., na:], zhi[..., na:])
            t_lo, t_hi = self._correct_t(a_lo, a_hi, yk, uk, prior, 0.5 * (zlo[..., na:] + zhi[..., na:]))
            new_lo = np.concatenate([a_lo, t_lo], -1)
            new_hi = np.concatenate([a_hi, t_hi], -1)
        elif started:
            new_lo, new_hi = a_lo, a_hi
        else:
            new_lo, new_hi = zlo, zhi
        if started:
            d_lo, d_hi = self._inputs(g1, chi_rows, new_lo, new_hi, y_prev, u_prev)
        x_lo, x_hi = inflate(*matvec_bounds(self.Zinv, new_lo, new_hi))
        internal = {"z_lower": new_lo, "z_upper": new_hi, "started": True, "y": yk, "u": uk}
        return ObserverState(x_lo, x_hi, d_lo, d_hi, internal)

    def _predict(
        self, zlo: FloatArray, zhi: FloatArray, y: FloatArray, u: FloatArray
    ) -> tuple[FloatArray, FloatArray, BoxPair, list[tuple[FloatArray, BoxPair]]]:
        """Bounds of a_{k+1}; also the pieces for the delayed input bounds of d_k."""
        sysm = self.system
        n, na, h = self.n, self.n_a, self.hidden
        ells, kaps = self._gains(zlo, zhi)
        lead = zlo.shape[:-1]
        R_b = np.broadcast_to(self.R, (*lead, *self.R.shape))
        phis = [np.concatenate([R_b, -ell], -1) for ell in ells]
        r1 = self.U1.shape[1]
        u1g = np.broadcast_to(np.concatenate([np.zeros((r1, n)), self.U1.T], 1), (*lead, r1, n + self.p))
        S_b = np.broadcast_to(self.S, (*lead, *self.S.shape))
        chis = [np.concatenate([S_b, -kap], -1) for kap in kaps] if h > 0 else []
        phi_all = np.concatenate([*phis, u1g, *chis], axis=-2)
        lo, hi = self._range.bounds(phi_all, zlo, zhi)
        ydu = y - u @ sysm.D.T
        rbw = matvec_bounds(self.R, *self.bounds.w)
        v_lo = np.broadcast_to(self.bounds.v[0], (*lead, self.p))
        v_hi = np.broadcast_to(self.bounds.v[1], (*lead, self.p))
        a_lo = np.full((*lead, na), -np.inf)
        a_hi = np.full((*lead, na), np.inf)
        for i, ell in enumerate(ells):
            psi_lo, psi_hi = lo[..., i * na : (i + 1) * na], hi[..., i * na : (i + 1) * na]
            known = u @ (self.R @ sysm.B).T + np.einsum("...ij,...j->...i", ell, ydu)
            vlo, vhi = matvec_bounds(-ell, v_lo, v_hi)
            c_lo, c_hi = inflate(psi_lo + known + rbw[0] + vlo, psi_hi + known + rbw[1] + vhi)
            a_lo, a_hi = np.maximum(a_lo, c_lo), np.minimum(a_hi, c_hi)
        off = len(ells) * na
        g1 = (lo[..., off : off + r1], hi[..., off : off + r1])
        chi_rows = []
        for j, kap in enumerate(kaps if h > 0 else []):
            rows = slice(off + r1 + j * h, off + r1 + (j + 1) * h)
            chi_rows.append((kap, (lo[..., rows], hi[..., rows])))
        return a_lo, a_hi, g1, chi_rows

    def _inputs(
        self,
        g1: BoxPair,
        chi_rows: list[tuple[FloatArray, BoxPair]],
        z_next_lo: FloatArray,
        z_next_hi: FloatArray,
        y: FloatArray,
        u: FloatArray,
    ) -> BoxPair:
        """Bounds of d_k from the box of x_k (through g1, chi) and the new t box."""
        sysm = self.system
        ydu = y - u @ sysm.D.T
        base = ydu @ self.U1
        u1v = matvec_bounds(self.U1.T, *self.bounds.v)
        d1_lo = (base - g1[1] - u1v[1]) / self.sigma
        d1_hi = (base - g1[0] - u1v[0]) / self.sigma
        parts_lo, parts_hi = [d1_lo], [d1_hi]
        if self.hidden > 0:
            na = self.n_a
            t_lo, t_hi = z_next_lo[..., na:], z_next_hi[..., na:]
            sbu = u @ (self.S @ sysm.B).T
            sw = matvec_bounds(self.S, *self.bounds.w)
            lead = t_lo.shape[:-1]
            v_lo = np.broadcast_to(self.bounds.v[0], (*lead, self.p))
            v_hi = np.broadcast_to(self.bounds.v[1], (*lead, self.p))
            d2_lo = np.full(t_lo.shape, -np.inf)
            d2_hi = np.full(t_lo.shape, np.inf)
            for kap, (c_lo, c_hi) in chi_rows:
                kv_lo, kv_hi = matvec_bounds(kap, v_lo, v_hi)
                ky = np.einsum("...ij,...j->...i", kap, ydu)
                lo_j = t_lo - sbu - c_hi - ky + kv_lo - sw[1]
                hi_j = t_hi - sbu - c_lo - ky + kv_hi - sw[0]
                d2_lo, d2_hi = np.maximum(d2_lo, lo_j), np.minimum(d2_hi, hi_j)
            parts_lo.append(d2_lo)
            parts_hi.append(d2_hi)
        V = np.concatenate([self.V1, self.V2], axis=1)
        return inflate(*matvec_bounds(V, np.concatenate(parts_lo, -1), np.concatenate(parts_hi, -1)))

    def meta(self) -> dict[str, Any]:
        """Facts recorded in every :class:`~intervalobs.estimate.Estimate` of :meth:`run`.

        Returns
        -------
        dict
            ``method`` and ``input_delay_steps`` (1: input row ``k`` bounds :math:`d_{k-1}`).
        """
        return {
            "method": "NullSpaceGSISIO (Khajenejad & Yong made sound: uses the current output's input-free part)",
            "input_delay_steps": 1,
        }
