r"""Simultaneous input and state interval observers for nonlinear discrete-time systems (seed 003).

System (seed 003, eq. (3); :class:`~intervalobs.systems.nonlinear.NonlinearSystem`):
:math:`x_{k+1} = f(x_k) + Bu_k + Gd_k + w_k`, :math:`y_k = g(x_k) + Du_k + Hd_k + v_k`.

Two observers:

:class:`GSISIO` — the paper's construction (4)–(7) with the gains of Theorem 1,
:math:`J = [G; H]^\dagger`, :math:`K = G^+J^+ + G^-J^-`, :math:`L = G^+J^- + G^-J^+`. Substituting the
input bounds (5)–(7) of Lemma 3 into the state bounds gives the implicit linear system (9),

.. math:: (I - K_1)\overline{x}_k + L_1\underline{x}_k = \overline r_k,\qquad
          (I - K_1)\underline{x}_k + L_1\overline{x}_k = \underline r_k,

solved through its sum and difference:
:math:`(I - K_1 + L_1)(\overline x + \underline x) = \overline r + \underline r`,
:math:`(I - K_1 - L_1)(\overline x - \underline x) = \overline r - \underline r`. Hence condition (8),
read as :math:`\mathrm{rk}(I - K_1 - L_1) = \mathrm{rk}(I - K_1 + L_1) = n`. Two corrections:

* (8) fails structurally when H is rank-deficient: :math:`J[G; H] = I` gives
  :math:`(K_1 - L_1)G + (K_2 - L_2)H = G`, so for :math:`HV_2 = 0`,
  :math:`(I - K_1 + L_1)GV_2 = 0` with :math:`GV_2 \ne 0`. :meth:`GSISIO.design` raises
  :class:`~intervalobs.errors.AssumptionError` naming it.
* (8) is not sufficient for *correct* framers. The errors :math:`\overline e = \overline x - x`,
  :math:`\underline e = x - \underline x` obey
  :math:`M[\overline e; \underline e] = \rho \ge 0` with :math:`M = [[I - K_1, -L_1], [-L_1, I - K_1]]`
  (ρ collects nonnegative bound gaps), so the solution is a framer for every admissible ρ iff that
  Z-matrix is a nonsingular M-matrix, i.e. :math:`\rho(K_1 + L_1) < 1` (note
  :math:`K_1 + L_1 = |G||J_{:,1:n}|`). :meth:`GSISIO.design` checks it too.

Rows of :meth:`GSISIO.run`: ``lower[k]``, ``upper[k]`` bound :math:`x_k` given :math:`y_0 \dots y_{k-1}`
(the base protocol); ``input_lower[k]``, ``input_upper[k]`` bound :math:`d_{k-1}` (one step delayed,
available together with :math:`x_k`; row 0 is NaN).

:class:`NullSpaceGSISIO` — the sound variant for rank-deficient H (one hidden input direction). With
the SVD :math:`H = U_1\Sigma V_1^\top`, :math:`U_2^\top H = 0`, :math:`HV_2 = 0`:

* coordinates :math:`z = (a, t) = Zx`, :math:`Z = [R; s^\top]`, with :math:`RGV_2 = 0` (the hidden
  input component cannot move :math:`a`) and :math:`s^\top GV_2 = 1`;
* prediction of :math:`a`: since :math:`RG = RGH^\dagger H`, for every gain
  :math:`\ell = RGH^\dagger + \lambda U_2^\top`,

  .. math:: a_{k+1} = Rf(x_k) - \ell g(x_k) + RBu_k + \ell(y_k - Du_k) + Rw_k - \ell v_k,

  a bound free of :math:`d` (each :math:`\lambda` is valid; several are intersected, one chosen at
  every step to cancel the sensitivity of the right-hand side to :math:`t`);
* correction of :math:`t` from the *current* d-free output
  :math:`U_2^\top(y_{k+1} - Du_{k+1}) = U_2^\top g(x_{k+1}) + U_2^\top v_{k+1}` by interval Newton in
  :math:`t` (requires :math:`U_2^\top g` strictly monotone along :math:`GV_2`, checked globally);
* delayed inputs: :math:`V_1^\top d_k = \Sigma^{-1}U_1^\top(y_k - g(x_k) - Du_k - v_k)` and
  :math:`V_2^\top d_k = t_{k+1} - s^\top(f(x_k) + Bu_k + w_k) - (s^\top GH^\dagger + \mu U_2^\top)
  (y_k - g(x_k) - Du_k - v_k)`;
* every range (of :math:`f, g` combinations over the current box) is the intersection of the natural
  interval extension, the mean-value form and the Jacobian-based decomposition with *local* Jacobian
  bounds, on a split of the box.

Rows of :meth:`NullSpaceGSISIO.run`: ``lower[k]``, ``upper[k]`` bound :math:`x_k` given
:math:`y_0 \dots y_k` (the current output is needed: without it :math:`x_k` is unbounded along
:math:`GV_2`); ``step(state, y_k, u_k)`` consumes :math:`y_k` and returns the state *at* k.
``input_lower[k]`` bounds :math:`d_{k-1}` (row 0 NaN).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..design.abstraction import AffineAbstraction, abstraction_sigma, affine_abstraction
from ..design.mixed_monotone import (
    JacobianDecomposition,
    decomposition_bounds,
    jacobian_bounds,
    jacobian_decomposition_parts,
    lipschitz_bound,
    paper_lipschitz_constant,
)
from ..errors import AssumptionError, DimensionError
from ..estimate import Estimate
from ..inclusion import evaluate_matrix
from ..interval import inflate, interval_matvec_bounds, matvec_bounds, neg, pos
from ..systems.nonlinear import NonlinearSystem
from ..validation import as_box, as_vector, check_no_kwargs
from .base import Observer, ObserverState

__all__ = ["GSISIO", "GSISIODesign", "NullSpaceGSISIO", "gsisio_design"]

FloatArray = NDArray[np.float64]
BoxPair = tuple[FloatArray, FloatArray]


# --------------------------------------------------------------------------------------------------
# Ranges of linear combinations of [f; g] composed with a linear change of coordinates
# --------------------------------------------------------------------------------------------------


def _mat_bounds(P: FloatArray, lo: FloatArray, hi: FloatArray) -> BoxPair:
    """Bounds of ``P @ x`` for x in [lo, hi]; ``P`` may carry leading axes (..., r, c)."""
    pp, pn = pos(P), neg(P)
    return (
        np.einsum("...ij,...j->...i", pp, lo) - np.einsum("...ij,...j->...i", pn, hi),
        np.einsum("...ij,...j->...i", pp, hi) - np.einsum("...ij,...j->...i", pn, lo),
    )


class _ComposedRange:
    r"""Ranges of :math:`\psi(z) = \Phi\,[f(x); g(x)]` with :math:`x = Z^{-1}z` over boxes in z.

    ``bounds`` intersects the natural interval extension, the mean-value form and the
    Yang–Mickelin–Ozay decomposition built from *local* Jacobian bounds of :math:`\psi`, on a
    ``splits``-per-axis partition of the box (the hull of the pieces is returned).
    """

    def __init__(self, system: NonlinearSystem, Zinv: FloatArray, splits: int) -> None:
        self.system = system
        self.Zinv = Zinv
        self.splits = splits
        self.f_jac, self.g_jac = system.jacobians()
        self.n, self.p = system.n, system.p

    def point(self, Phi: FloatArray, z: FloatArray) -> FloatArray:
        x = z @ self.Zinv.T
        fg = np.concatenate([self.system.evaluate_f(x), self.system.evaluate_g(x)], axis=-1)
        return np.einsum("...ij,...j->...i", Phi, fg)

    def _fg_jacobian(self, xlo: FloatArray, xhi: FloatArray) -> BoxPair:
        jf = jacobian_bounds(self.f_jac, xlo, xhi, (self.n, self.n), "f_jacobian")
        jg = jacobian_bounds(self.g_jac, xlo, xhi, (self.p, self.n), "g_jacobian")
        return np.concatenate([jf[0], jg[0]], axis=-2), np.concatenate([jf[1], jg[1]], axis=-2)

    def jacobian(self, Phi: FloatArray, zlo: FloatArray, zhi: FloatArray) -> BoxPair:
        """Bounds of the Jacobian of psi with respect to z over the box."""
        xlo, xhi = matvec_bounds(self.Zinv, zlo, zhi)
        jlo, jhi = self._fg_jacobian(xlo, xhi)
        pp, pn = pos(Phi), neg(Phi)
        alo = np.einsum("...ij,...jk->...ik", pp, jlo) - np.einsum("...ij,...jk->...ik", pn, jhi)
        ahi = np.einsum("...ij,...jk->...ik", pp, jhi) - np.einsum("...ij,...jk->...ik", pn, jlo)
        zp, zn = pos(self.Zinv), neg(self.Zinv)
        return alo @ zp - ahi @ zn, ahi @ zp - alo @ zn

    def _single(self, Phi: FloatArray, zlo: FloatArray, zhi: FloatArray) -> BoxPair:
        xlo, xhi = matvec_bounds(self.Zinv, zlo, zhi)
        flo, fhi = self.system.f_range(xlo, xhi)
        glo, ghi = self.system.g_range(xlo, xhi)
        low, high = _mat_bounds(Phi, np.concatenate([flo, glo], -1), np.concatenate([fhi, ghi], -1))
        low, high = inflate(low, high)
        jlo, jhi = self.jacobian(Phi, zlo, zhi)
        if not (np.all(np.isfinite(jlo)) and np.all(np.isfinite(jhi))):
            return low, high
        # mean-value form
        c = 0.5 * (zlo + zhi)
        centre = self.point(Phi, c)
        mlo, mhi = interval_matvec_bounds(jlo, jhi, zlo - c, zhi - c)
        mlo, mhi = inflate(centre + mlo, centre + mhi)
        low, high = np.maximum(low, mlo), np.minimum(high, mhi)
        # decomposition with local Jacobian bounds
        first, cmat = jacobian_decomposition_parts(jlo, jhi)
        zeta_hi = np.where(first, zhi[..., None, :], zlo[..., None, :])
        zeta_lo = np.where(first, zlo[..., None, :], zhi[..., None, :])
        spread = np.einsum("...ij,...j->...i", cmat, zhi - zlo)
        dhi = self._rows(Phi, zeta_hi) + spread
        dlo = self._rows(Phi, zeta_lo) - spread
        dlo, dhi = inflate(dlo, dhi)
        return np.maximum(low, dlo), np.minimum(high, dhi)

    def _rows(self, Phi: FloatArray, points: FloatArray) -> FloatArray:
        x = points @ self.Zinv.T
        fg = np.concatenate([self.system.evaluate_f(x), self.system.evaluate_g(x)], axis=-1)
        return np.einsum("...ij,...ij->...i", Phi, fg)

    def bounds(self, Phi: FloatArray, zlo: FloatArray, zhi: FloatArray, splits: int | None = None) -> BoxPair:
        """Range bounds of psi over the boxes (leading axes of Phi and the boxes broadcast)."""
        s = self.splits if splits is None else splits
        if s <= 1:
            lo, hi = self._single(Phi, zlo, zhi)
        else:
            nz = zlo.shape[-1]
            frac = np.linspace(0.0, 1.0, s + 1)
            grids = np.stack(np.meshgrid(*([np.arange(s)] * nz), indexing="ij"), -1).reshape(-1, nz)
            width = (zhi - zlo)[..., None, :]
            sub_lo = zlo[..., None, :] + width * frac[grids]
            sub_hi = zlo[..., None, :] + width * frac[grids + 1]
            sub_hi = np.where(grids + 1 == s, zhi[..., None, :], sub_hi)
            lo, hi = self._single(Phi[..., None, :, :], sub_lo, sub_hi)
            lo, hi = lo.min(axis=-2), hi.max(axis=-2)
        return lo, hi


def _input_hull(M: FloatArray, h_lo: FloatArray, h_hi: FloatArray, d_lo: FloatArray, d_hi: FloatArray) -> BoxPair:
    """Exact interval hull of {d : h_lo <= M d <= h_hi} (LP per component), intersected with (d_lo, d_hi).

    The J-based box (Lemma 3) contains the set, so it bounds the LP; the LP optimum is widened by the
    solver's feasibility tolerance scaled back to d and by the rounding margin.
    """
    from scipy.optimize import linprog

    q = M.shape[1]
    lo_out, hi_out = np.array(d_lo, dtype=float), np.array(d_hi, dtype=float)
    flat_hl, flat_hh = h_lo.reshape(-1, M.shape[0]), h_hi.reshape(-1, M.shape[0])
    flat_lo, flat_hi = lo_out.reshape(-1, q), hi_out.reshape(-1, q)
    a_ub = np.vstack([M, -M])
    slack = 1e-7 * (1.0 + np.abs(np.linalg.pinv(M)).sum())
    for r in range(flat_hl.shape[0]):
        b_ub = np.concatenate([flat_hh[r], -flat_hl[r]])
        bounds = list(zip(flat_lo[r], flat_hi[r]))
        for i in range(q):
            for sign, out, pick in ((1.0, flat_lo, np.maximum), (-1.0, flat_hi, np.minimum)):
                cost = np.zeros(q)
                cost[i] = sign
                res = linprog(cost, A_ub=a_ub, b_ub=b_ub, bounds=bounds, method="highs")
                if res.status == 0 and res.x is not None:
                    value = float(res.x[i]) - sign * slack * (1.0 + abs(float(res.x[i])))
                    out[r, i] = pick(out[r, i], value)
    return flat_lo.reshape(lo_out.shape), flat_hi.reshape(hi_out.shape)


def _divide(num: BoxPair, den: BoxPair) -> BoxPair:
    """Interval division; every denominator interval excludes 0."""
    q = np.stack([num[0] / den[0], num[0] / den[1], num[1] / den[0], num[1] / den[1]])
    return inflate(q.min(axis=0), q.max(axis=0))


# --------------------------------------------------------------------------------------------------
# The paper's design (Theorem 1, Theorem 2, Lemma 5)
# --------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class GSISIODesign:
    r"""Everything Theorems 1–2 and Lemmas 2–5 of seed 003 compute, recomputed (no check raises here).

    Attributes
    ----------
    J, K, L : numpy.ndarray
        :math:`J = [G; H]^\dagger` and the gains of Theorem 1.
    K1, K2, L1, L2 : numpy.ndarray
        Column blocks (first n columns: state part).
    rank_condition_8 : tuple of int
        :math:`(\mathrm{rk}(I - K_1 - L_1), \mathrm{rk}(I - K_1 + L_1))`; (8) needs both equal to n.
    correctness_radius : float
        :math:`\rho(K_1 + L_1)`; the framers of (9) are correct iff it is < 1 (our addition).
    jacobian_f, jacobian_g : tuple of numpy.ndarray
        Jacobian bounds on the Jacobian domain (interval evaluation).
    C_f, C_g, W_f, W_g : numpy.ndarray
        Matrices of the decomposition (2) and the width matrices.
    L_f, L_g : float
        Lipschitz bounds :math:`\sup\|Df\|`, :math:`\sup\|Dg\|` on the domain.
    L_fd, L_gd : float
        Sound Lemma-2 constants :math:`\|W_f\|`, :math:`\|W_g\|`.
    L_fd_paper, L_gd_paper : float
        The seed's formula :math:`L_q + 2\|C_q\|` (not a valid bound in general).
    T_f, T_g : numpy.ndarray
        :math:`(I - K_1 - L_1)^\dagger(I + K_1 + L_1)` and :math:`(I - K_1 - L_1)^\dagger(K_2 + L_2)`.
    script_L, script_L_paper : float
        :math:`\mathcal L = L_{f_d}\|T_f\| + L_{g_d}\|T_g\|` with the sound and the paper's constants.
    componentwise_radius : float
        :math:`\rho(T_fW_f + T_gW_g)`: the width recursion is a contraction in a weighted norm iff < 1
        (our condition (iv), valid when :math:`T_f, T_g \ge 0`).
    delta_z : float
        :math:`\|T_f\Delta w + T_g\Delta v\|`.
    conditions : dict
        Which of (i), (ii), (iii), (iv) hold, with the numbers behind them.
    """

    J: FloatArray
    K: FloatArray
    L: FloatArray
    K1: FloatArray
    K2: FloatArray
    L1: FloatArray
    L2: FloatArray
    rank_condition_8: tuple[int, int]
    correctness_radius: float
    jacobian_f: BoxPair
    jacobian_g: BoxPair
    C_f: FloatArray
    C_g: FloatArray
    W_f: FloatArray
    W_g: FloatArray
    L_f: float
    L_g: float
    L_fd: float
    L_gd: float
    L_fd_paper: float
    L_gd_paper: float
    T_f: FloatArray
    T_g: FloatArray
    script_L: float
    script_L_paper: float
    componentwise_radius: float
    delta_z: float
    conditions: dict[str, Any] = field(default_factory=dict)

    @property
    def condition_8(self) -> bool:
        """Whether the existence condition (8) holds."""
        n = self.K1.shape[0]
        return self.rank_condition_8 == (n, n)

    @property
    def stability_condition(self) -> str | None:
        """The first stability condition that holds ('(i)', '(ii)', '(iii)', '(iv)') or None."""
        for name in ("(i)", "(ii)", "(iii)", "(iv)"):
            if self.conditions.get(name, {}).get("holds"):
                return name
        return None

    def delta_x(self, delta0: float, steps: int) -> FloatArray:
        r"""Lemma 5: :math:`\delta^x_k = \mathcal L^k\delta_0 + \|\Delta z\|(1 - \mathcal L^k)/(1 - \mathcal L)`.

        Uses the sound :math:`\mathcal L`; NaN everywhere unless :math:`\mathcal L < 1` (condition (i)).
        The steady state is :math:`\|\Delta z\|/(1 - \mathcal L)` (the seed prints
        :math:`\|\Delta z\|\mathcal L/(1 - \mathcal L)`, which its own recursion does not give).

        Parameters
        ----------
        delta0 : float
            :math:`\delta^x_0 = \|\overline x_0 - \underline x_0\|`.
        steps : int
            Number of samples.

        Returns
        -------
        numpy.ndarray, shape (steps,)
        """
        ell = self.script_L
        if not ell < 1.0:
            return np.full(steps, np.nan)
        k = np.arange(steps, dtype=float)
        return (ell**k * delta0 + self.delta_z * (1.0 - ell**k) / (1.0 - ell)) * (1.0 + 1e-9) + 1e-12

    def delta_d(self, delta_x: FloatArray, dw: FloatArray, dv: FloatArray) -> FloatArray:
        r"""Lemma 5's input-width bound, corrected to use :math:`\delta^x_k` and :math:`\delta^x_{k-1}`.

        :math:`\|\Delta^d_{k-1}\| \le \|\hat J_1\|\delta^x_k + (L_{f_d}\|\hat J_1\| + L_{g_d}\|\hat J_2\|)\delta^x_{k-1}
        + \|\hat J_1\Delta w + \hat J_2\Delta v\|`, :math:`\hat J = |J|`. Row k bounds the width of
        :math:`d_{k-1}` (NaN at k = 0).

        Parameters
        ----------
        delta_x : numpy.ndarray, shape (T,)
            The state sequence of :meth:`delta_x`.
        dw, dv : numpy.ndarray
            Noise widths :math:`\overline w - \underline w`, :math:`\overline v - \underline v`.

        Returns
        -------
        numpy.ndarray, shape (T,)
        """
        n = self.K1.shape[0]
        jh = np.abs(self.J)
        j1, j2 = np.linalg.norm(jh[:, :n], 2), np.linalg.norm(jh[:, n:], 2)
        const = float(np.linalg.norm(jh[:, :n] @ dw + jh[:, n:] @ dv))
        out = np.full_like(delta_x, np.nan)
        out[1:] = j1 * delta_x[1:] + (self.L_fd * j1 + self.L_gd * j2) * delta_x[:-1] + const
        return out * (1.0 + 1e-9)

    def as_dict(self) -> dict[str, Any]:
        """The design numbers for ``summary.json``.

        Returns
        -------
        dict
        """
        return {
            "J": self.J,
            "K": self.K,
            "L": self.L,
            "rank_condition_8": list(self.rank_condition_8),
            "condition_8_holds": self.condition_8,
            "correctness_radius_rho_K1_plus_L1": self.correctness_radius,
            "jacobian_f_lower": self.jacobian_f[0],
            "jacobian_f_upper": self.jacobian_f[1],
            "jacobian_g_lower": self.jacobian_g[0],
            "jacobian_g_upper": self.jacobian_g[1],
            "C_f": self.C_f,
            "C_g": self.C_g,
            "W_f": self.W_f,
            "W_g": self.W_g,
            "L_f": self.L_f,
            "L_g": self.L_g,
            "L_fd": self.L_fd,
            "L_gd": self.L_gd,
            "L_fd_paper_formula": self.L_fd_paper,
            "L_gd_paper_formula": self.L_gd_paper,
            "T_f": self.T_f,
            "T_g": self.T_g,
            "script_L": self.script_L,
            "script_L_paper_formula": self.script_L_paper,
            "componentwise_radius": self.componentwise_radius,
            "delta_z": self.delta_z,
            "conditions": self.conditions,
            "stability_condition": self.stability_condition or "none holds",
        }


def _condition_ii(T_f: FloatArray, T_g: FloatArray, L_fd: float, L_gd: float) -> dict[str, Any]:
    n = T_f.shape[0]
    Q = np.linalg.eigvalsh(T_f.T @ T_f).max() * L_fd**2 + np.linalg.eigvalsh(T_g.T @ T_g).max() * L_gd**2 - 1
    Z, gg, gf, ff, fg = np.zeros((n, n)), T_g.T @ T_g, T_g.T @ T_f, T_f.T @ T_f, T_f.T @ T_g
    upper = [
        [Q * np.eye(n), Z, Z, Z, Z],
        [Z, gg, gf, gf, gg],
        [Z, gf.T, ff, ff, fg],
        [Z, gf.T, ff.T, Z, fg],
        [Z, gg.T, fg.T, fg.T, Z],
    ]
    M = np.block(upper)
    M = 0.5 * (M + M.T)
    top = float(np.linalg.eigvalsh(M).max())
    return {
        "holds": bool(top <= 0.0),
        "max_eigenvalue": top,
        "note": "blocks (4,4), (5,5) are 0 with nonzero off-diagonal blocks T_f'T_f, T_f'T_g: never NSD",
    }


def _condition_iii(script_l: float, n: int) -> dict[str, Any]:
    try:
        import cvxpy as cp
    except ImportError:  # pragma: no cover - cvxpy is a dependency
        return {"holds": False, "status": "cvxpy unavailable"}
    P = cp.Variable((n, n), symmetric=True)
    Gam = cp.Variable((n, n), symmetric=True)
    eye, Z = np.eye(n), np.zeros((n, n))
    big = cp.bmat([[P + Gam - eye, Z, P], [Z, script_l**2 * eye - P, Z], [P, Z, P]])
    eps = 1e-6
    problem = cp.Problem(cp.Minimize(0), [P >> eps * eye, Gam >> 0, 0.5 * (big + big.T) << 0])
    try:
        problem.solve(solver=cp.CLARABEL)
        status = str(problem.status)
    except cp.error.SolverError as exc:  # pragma: no cover - solver failure is reported, not raised
        status = f"solver error: {exc}"
    holds = status == "optimal"
    if holds and P.value is not None and Gam.value is not None:
        Pv = P.value
        check = np.block([[Pv + Gam.value - eye, Z, Pv], [Z, script_l**2 * eye - Pv, Z], [Pv, Z, Pv]])
        holds = bool(np.linalg.eigvalsh(0.5 * (check + check.T)).max() <= 1e-9 and np.linalg.eigvalsh(Pv).min() > 0)
    return {
        "holds": holds,
        "status": status,
        "note": "block (3,3) of the LMI is P, which must be NSD and positive definite at once: infeasible",
    }


def gsisio_design(system: NonlinearSystem, jacobian_domain: tuple[ArrayLike, ArrayLike] | None = None) -> GSISIODesign:
    r"""Recompute every design quantity of seed 003's Theorems 1–2 and Lemmas 2, 5 for a system.

    Parameters
    ----------
    system : NonlinearSystem
        With both Jacobians.
    jacobian_domain : tuple of array_like, optional
        Box on which the Jacobian bounds (and so :math:`C_f, C_g`, the Lipschitz constants) hold;
        default the whole space (the bounds must then be finite, as for the paper's example).

    Returns
    -------
    GSISIODesign
    """
    n, p = system.n, system.p
    f_jac, g_jac = system.jacobians()
    if jacobian_domain is None:
        dom_lo, dom_hi = np.full(n, -np.inf), np.full(n, np.inf)
    else:
        dom_lo, dom_hi = as_box("jacobian_domain", jacobian_domain, n)
    J = np.linalg.pinv(np.vstack([system.G, system.H]))
    Gp, Gn, Jp, Jn = pos(system.G), neg(system.G), pos(J), neg(J)
    K = Gn @ Jn + Gp @ Jp
    L = Gn @ Jp + Gp @ Jn
    K1, K2, L1, L2 = K[:, :n], K[:, n:], L[:, :n], L[:, n:]
    eye = np.eye(n)
    ranks = (int(np.linalg.matrix_rank(eye - K1 - L1)), int(np.linalg.matrix_rank(eye - K1 + L1)))
    radius = float(np.max(np.abs(np.linalg.eigvals(K1 + L1))))
    jf = jacobian_bounds(f_jac, dom_lo, dom_hi, (n, n), "f_jacobian")
    jg = jacobian_bounds(g_jac, dom_lo, dom_hi, (p, n), "g_jacobian")
    dec_f = JacobianDecomposition(system.f, *jf)
    dec_g = JacobianDecomposition(system.g, *jg)
    L_f, L_g = float(lipschitz_bound(*jf)), float(lipschitz_bound(*jg))
    L_fd, L_gd = dec_f.lipschitz_width, dec_g.lipschitz_width
    L_fd_paper, L_gd_paper = paper_lipschitz_constant(L_f, dec_f.C), paper_lipschitz_constant(L_g, dec_g.C)
    inv = np.linalg.pinv(eye - K1 - L1)
    T_f, T_g = inv @ (eye + K1 + L1), inv @ (K2 + L2)
    nf, ng = np.linalg.norm(T_f, 2), np.linalg.norm(T_g, 2)
    script_l = float(L_fd * nf + L_gd * ng)
    script_l_paper = float(L_fd_paper * nf + L_gd_paper * ng)
    dw = system.w[1] - system.w[0]
    dv = system.v[1] - system.v[0]
    delta_z = float(np.linalg.norm(T_f @ dw + T_g @ dv))
    comp = float(np.max(np.abs(np.linalg.eigvals(T_f @ dec_f.W + T_g @ dec_g.W))))
    nonneg = bool(np.all(T_f >= -1e-12) and np.all(T_g >= -1e-12))
    conditions: dict[str, Any] = {
        "(i)": {"holds": bool(script_l <= 1.0), "script_L": script_l, "script_L_paper_formula": script_l_paper},
        "(ii)": _condition_ii(T_f, T_g, L_fd, L_gd),
        "(iii)": _condition_iii(script_l, n),
        "(iv)": {
            "holds": bool(comp < 1.0 and nonneg and radius < 1.0),
            "spectral_radius_TfWf_plus_TgWg": comp,
            "T_nonnegative": nonneg,
        },
    }
    return GSISIODesign(
        J, K, L, K1, K2, L1, L2, ranks, radius, jf, jg, dec_f.C, dec_g.C, dec_f.W, dec_g.W,
        L_f, L_g, L_fd, L_gd, L_fd_paper, L_gd_paper, T_f, T_g, script_l, script_l_paper, comp, delta_z,
        conditions,
    )  # fmt: skip


# --------------------------------------------------------------------------------------------------
# The paper's observer
# --------------------------------------------------------------------------------------------------


class GSISIO(Observer):
    r"""The paper's GSISIO, eqs. (4)–(7) with Theorem 1's gains (seed 003, Algorithm 1).

    Use :meth:`design`. The bounds :math:`\underline f, \overline f, \underline g, \overline g` over the
    previous box are Corollary 1's (global-Jacobian decomposition (2) ∩ affine abstraction (1)) and,
    with ``tight=True``, also intersected with the local-Jacobian decomposition, mean-value form and
    natural extension; intersecting only shrinks the widths, so Lemma 5's bounds still hold.

    Parameters
    ----------
    system : NonlinearSystem
        The model, with Jacobians.
    design_result : GSISIODesign
        From :func:`gsisio_design` (the constructor does not check (8): :meth:`design` does).
    x0 : tuple of numpy.ndarray
        Initial box.
    abstraction_f, abstraction_g : AffineAbstraction, optional
        LP (1) solutions on the abstraction domain.
    tight : bool
        Also intersect with local-Jacobian ranges.
    splits : int
        Sub-boxes per axis for the local ranges.
    input_hull : bool
        Replace Lemma 3's box :math:`J^+\overline h - J^-\underline h` by the exact interval hull of
        :math:`\{d : \underline h \le [G; H]d \le \overline h\}` (2q LPs per step with HiGHS; Lemma 3's
        "tight" holds only relative to the J-based box). Default False.
    """

    def __init__(
        self,
        system: NonlinearSystem,
        design_result: GSISIODesign,
        x0: BoxPair,
        abstraction_f: AffineAbstraction | None = None,
        abstraction_g: AffineAbstraction | None = None,
        tight: bool = True,
        splits: int = 1,
        input_hull: bool = False,
    ) -> None:
        self.system = system
        self.design_result = design_result
        self.x0 = x0
        self.abstraction_f, self.abstraction_g = abstraction_f, abstraction_g
        self.tight = tight
        self.input_hull = input_hull
        self.n, self.p, self.m = system.n, system.p, system.m
        self._range = _ComposedRange(system, np.eye(system.n), splits)
        self._phi = np.eye(system.n + system.p)
        d = design_result
        eye = np.eye(self.n)
        self._sum_inv = np.linalg.pinv(eye - d.K1 + d.L1)  # = inverse when (8) holds
        self._diff_inv = np.linalg.pinv(eye - d.K1 - d.L1)

    @classmethod
    def design(
        cls,
        system: NonlinearSystem,
        x0: tuple[ArrayLike, ArrayLike],
        jacobian_domain: tuple[ArrayLike, ArrayLike] | None = None,
        abstraction_domain: tuple[ArrayLike, ArrayLike] | None = None,
        **options: Any,
    ) -> GSISIO:
        """Compute Theorem 1's gains, check (8) and correctness, solve LP (1).

        Parameters
        ----------
        system : NonlinearSystem
        x0 : tuple of array_like
            Initial box ``(lower, upper)``.
        jacobian_domain : tuple of array_like, optional
            Domain of the global Jacobian bounds (default: the whole space).
        abstraction_domain : tuple of array_like, optional
            Box on which LP (1) is solved (default: the initial box); used for boxes inside it.
        **options
            ``tight`` (bool, default True), ``splits`` (int, default 1), ``input_hull`` (bool, default
            False: exact LP hull of the input bounds instead of Lemma 3's box).

        Returns
        -------
        GSISIO

        Raises
        ------
        AssumptionError
            Condition (8) fails, or :math:`\\rho(K_1 + L_1) \\ge 1` (framers of (9) not guaranteed).
        """
        check_no_kwargs("GSISIO.design", options, ("tight", "splits", "input_hull"))
        box = as_box("x0", x0, system.n)
        d = gsisio_design(system, jacobian_domain)
        n = system.n
        if not d.condition_8:
            hidden = ""
            q_h = int(np.linalg.matrix_rank(system.H))
            if q_h < system.q:
                hidden = f"; H has rank {q_h} < {system.q}, so (I - K1 + L1) G V2 = 0 for H V2 = 0"
            raise AssumptionError(
                f"condition (8) of Theorem 1 fails: rk(I - K1 - L1) = {d.rank_condition_8[0]}, "
                f"rk(I - K1 + L1) = {d.rank_condition_8[1]}, expected both = n = {n}{hidden}"
            )
        if not d.correctness_radius < 1.0:
            raise AssumptionError(
                "correctness of (9): expected rho(K1 + L1) < 1 (error system an M-matrix), "
                f"got {d.correctness_radius:.4g}"
            )
        dom = box if abstraction_domain is None else as_box("abstraction_domain", abstraction_domain, n)
        f_jac, g_jac = system.jacobians()
        jf = jacobian_bounds(f_jac, dom[0], dom[1], (n, n))
        jg = jacobian_bounds(g_jac, dom[0], dom[1], (system.p, n))
        abs_f = affine_abstraction(system.f, dom[0], dom[1], abstraction_sigma(dom[0], dom[1], *jf), n)
        abs_g = affine_abstraction(system.g, dom[0], dom[1], abstraction_sigma(dom[0], dom[1], *jg), system.p)
        return cls(system, d, box, abs_f, abs_g, tight=bool(options.get("tight", True)),
                   splits=int(options.get("splits", 1)), input_hull=bool(options.get("input_hull", False)))  # fmt: skip

    # ---- Corollary 1 -------------------------------------------------------------------------------
    def _fg_bounds(self, lo: FloatArray, hi: FloatArray) -> tuple[BoxPair, BoxPair]:
        d, sysm = self.design_result, self.system
        f_b = decomposition_bounds(sysm.f, lo, hi, *d.jacobian_f)
        g_b = decomposition_bounds(sysm.g, lo, hi, *d.jacobian_g)
        if self.abstraction_f is not None and self.abstraction_g is not None:
            af, ag = self.abstraction_f.range_bounds(lo, hi), self.abstraction_g.range_bounds(lo, hi)
            f_b = (np.maximum(f_b[0], af[0]), np.minimum(f_b[1], af[1]))
            g_b = (np.maximum(g_b[0], ag[0]), np.minimum(g_b[1], ag[1]))
        if self.tight:
            tlo, thi = self._range.bounds(self._phi, lo, hi)
            n = self.n
            f_b = (np.maximum(f_b[0], tlo[..., :n]), np.minimum(f_b[1], thi[..., :n]))
            g_b = (np.maximum(g_b[0], tlo[..., n:]), np.minimum(g_b[1], thi[..., n:]))
        return f_b, g_b

    # ---- protocol ----------------------------------------------------------------------------------
    def init(self, x0_lower: ArrayLike | None = None, x0_upper: ArrayLike | None = None) -> ObserverState:
        """State at k = 0: the initial box, no input bound yet.

        Parameters
        ----------
        x0_lower, x0_upper : array_like, shape (n,), optional
            Initial box (default: the design's).

        Returns
        -------
        ObserverState
        """
        lo = self.x0[0] if x0_lower is None else as_vector("x0_lower", x0_lower, self.n)
        hi = self.x0[1] if x0_upper is None else as_vector("x0_upper", x0_upper, self.n)
        lo, hi = as_box("x0", (lo, hi), self.n)
        nan = np.full(self.system.q, np.nan)
        return ObserverState(lo.copy(), hi.copy(), nan, nan.copy(), {"k": 0})

    def step(self, state: ObserverState, y: ArrayLike, u: ArrayLike | None = None) -> ObserverState:
        """Consume :math:`y_k, u_k`; return the box of :math:`x_{k+1}` and of :math:`d_k` (eqs. (4)–(7)).

        Parameters
        ----------
        state : ObserverState
            The current state.
        y : array_like, shape (p,) or (M, p)
            Measurement :math:`y_k`.
        u : array_like, shape (m,) or (M, m), optional
            Known input :math:`u_k`.

        Returns
        -------
        ObserverState
        """
        lo, hi = np.asarray(state.lower, float), np.asarray(state.upper, float)
        yk = np.asarray(y, dtype=float)
        if yk.shape[-1] != self.p:
            raise DimensionError(f"y: expected {self.p} components, got shape {yk.shape}")
        uk = self._input(u, yk.shape[:-1])
        d, sysm = self.design_result, self.system
        (f_lo, f_hi), (g_lo, g_hi) = self._fg_bounds(lo, hi)
        bu, du = uk @ sysm.B.T, uk @ sysm.D.T
        wl, wu = sysm.w
        vl, vu = sysm.v
        fu_lo, fu_hi = f_lo + bu + wl, f_hi + bu + wu  # f + Bu + w bounds
        gy_hi = yk - g_lo - du - vl  # upper bound of y - g - Du - v
        gy_lo = yk - g_hi - du - vu
        r_up = fu_hi - fu_lo @ d.K1.T + fu_hi @ d.L1.T + gy_hi @ d.K2.T - gy_lo @ d.L2.T
        r_low = fu_lo - fu_hi @ d.K1.T + fu_lo @ d.L1.T + gy_lo @ d.K2.T - gy_hi @ d.L2.T
        total = (r_up + r_low) @ self._sum_inv.T
        diff = (r_up - r_low) @ self._diff_inv.T
        x_lo, x_hi = inflate(0.5 * (total - diff), 0.5 * (total + diff))
        h_lo = np.concatenate([x_lo - fu_hi, gy_lo], axis=-1)
        h_hi = np.concatenate([x_hi - fu_lo, gy_hi], axis=-1)
        d_lo, d_hi = inflate(*matvec_bounds(d.J, h_lo, h_hi))
        if self.input_hull:
            d_lo, d_hi = _input_hull(np.vstack([sysm.G, sysm.H]), h_lo, h_hi, d_lo, d_hi)
        return ObserverState(x_lo, x_hi, d_lo, d_hi, {"k": int(state.internal.get("k", 0)) + 1})

    def run(self, t: ArrayLike, y: ArrayLike, u: ArrayLike | None = None) -> Estimate:
        """Bounds over a record: row k bounds :math:`x_k` (from :math:`y_{0..k-1}`) and :math:`d_{k-1}`.

        Parameters
        ----------
        t : array_like, shape (T,)
            Sample times.
        y : array_like, shape (T, p) or (M, T, p)
            Measurements.
        u : array_like, shape (T, m) or (M, T, m), optional
            Known inputs.

        Returns
        -------
        Estimate
        """
        times, ys, us = self._signals(t, y, u)
        lead = ys.shape[:-2]
        T = times.size
        lower = np.empty((*lead, T, self.n))
        upper = np.empty_like(lower)
        dl = np.full((*lead, T, self.system.q), np.nan)
        du = np.full_like(dl, np.nan)
        state = self.init()
        state = ObserverState(
            np.broadcast_to(state.lower, (*lead, self.n)).copy(), np.broadcast_to(state.upper, (*lead, self.n)).copy()
        )
        lower[..., 0, :], upper[..., 0, :] = state.lower, state.upper
        for k in range(T - 1):
            state = self.step(state, ys[..., k, :], us[..., k, :])
            lower[..., k + 1, :], upper[..., k + 1, :] = state.lower, state.upper
            assert state.input_lower is not None and state.input_upper is not None
            dl[..., k + 1, :], du[..., k + 1, :] = state.input_lower, state.input_upper
        meta = {"method": "GSISIO (seed 003, Theorem 1)", "transient_s": float(times[0]), "input_delay_steps": 1}
        return Estimate(times, lower, upper, dl, du, meta)

    def current_input_bounds(
        self, x_lower: ArrayLike, x_upper: ArrayLike, y: ArrayLike, u: ArrayLike | None = None
    ) -> tuple[BoxPair, FloatArray]:
        r"""Lemma 4: bounds of :math:`d_{1,k} = V_1^\top d_k` from the current output and the box of :math:`x_k`.

        Parameters
        ----------
        x_lower, x_upper : array_like, shape (..., n)
            Box of :math:`x_k`.
        y : array_like, shape (..., p)
            Current output :math:`y_k`.
        u : array_like, shape (..., m), optional
            Current known input.

        Returns
        -------
        (lower, upper), V1
            Bounds of :math:`V_1^\top d_k` and the matrix :math:`V_1` (:math:`d_k = V_1d_{1,k} + V_2d_{2,k}`).
        """
        sysm = self.system
        U, S, Vt = np.linalg.svd(sysm.H)
        r = int(np.sum(S > S.max() * 1e-10))
        U1, V1 = U[:, :r], Vt[:r].T
        lo, hi = np.asarray(x_lower, float), np.asarray(x_upper, float)
        _, (g_lo, g_hi) = self._fg_bounds(lo, hi)
        yk = np.asarray(y, dtype=float)
        du = 0.0 if u is None else np.asarray(u, dtype=float) @ sysm.D.T
        gl, gh = matvec_bounds(U1.T, g_lo, g_hi)
        vl, vh = matvec_bounds(U1.T, *sysm.v)
        base = (yk - du) @ U1
        return inflate((base - gh - vh) / S[:r], (base - gl - vl) / S[:r]), V1


# --------------------------------------------------------------------------------------------------
# The sound variant for rank-deficient H
# --------------------------------------------------------------------------------------------------


class NullSpaceGSISIO(Observer):
    r"""GSISIO made sound for rank-deficient H: uses the d-free part :math:`U_2^\top y_k` of the current output.

    See the module docstring for the construction. Use :meth:`design`.

    Parameters
    ----------
    system : NonlinearSystem
        With Jacobians; at most one hidden input direction.
    x0 : tuple of numpy.ndarray
        Initial box.
    direction : str
        ``'orthogonal'`` (default: :math:`s \parallel GV_2`) or ``'output'`` (:math:`s` along the d-free
        output's gradient at the centre of x0; badly conditioned on the paper's example).
    gain_factors : tuple of float
        Multiples of the per-step t-cancelling gain; the predictions of all are intersected.
    splits : int
        Sub-boxes per axis for the range bounds.
    newton_steps : int
        Interval Newton iterations for t.

    Attributes
    ----------
    Z : numpy.ndarray, shape (n, n)
        Coordinates :math:`z = (a, t) = Zx` (last row :math:`s^\top`, absent when H has full column rank).
    R : numpy.ndarray
        Rows of Z that the hidden input cannot move (:math:`RGV_2 = 0`).
    hidden : int
        Number of hidden input directions :math:`q - \mathrm{rk}(H)` (0 or 1).
    slope : tuple of numpy.ndarray
        Global bounds of :math:`\partial(U_2^\top g)/\partial t`.
    """

    def __init__(
        self,
        system: NonlinearSystem,
        x0: BoxPair,
        direction: str = "orthogonal",
        gain_factors: tuple[float, ...] = (0.0, 1.0),
        splits: int = 2,
        newton_steps: int = 3,
    ) -> None:
        self.system = system
        self.x0 = x0
        self.n, self.p, self.m = system.n, system.p, system.m
        self.gain_factors = tuple(float(c) for c in gain_factors)
        self.newton_steps = int(newton_steps)
        n, p, q = system.n, system.p, system.q
        _, g_jac = system.jacobians()
        U, S, Vt = np.linalg.svd(system.H)
        rank = int(np.sum(S > (S.max() if S.size else 0.0) * 1e-10))
        self.sigma = S[:rank]
        self.U1, self.U2 = U[:, :rank], U[:, rank:]
        self.V1, self.V2 = Vt[:rank].T, Vt[rank:].T
        self.hidden = q - rank
        if self.hidden > 1:
            raise AssumptionError(
                f"NullSpaceGSISIO: implemented for at most one hidden input direction, got q - rk(H) = {self.hidden}"
            )
        H_pinv = np.linalg.pinv(system.H)
        centre = 0.5 * (x0[0] + x0[1])
        if self.hidden == 1:
            g2 = system.G @ self.V2[:, 0]
            basis = np.linalg.svd(g2[None, :])[2]  # rows: g2 direction, then its orthogonal complement
            R = basis[1:]
            if self.U2.shape[1] == 0:
                raise AssumptionError(
                    "NullSpaceGSISIO: no d-free output (U2 empty): the hidden input cannot be recovered"
                )
            jg = evaluate_matrix(g_jac, centre, (p, n))
            grads = self.U2.T @ jg  # (p - rank, n)
            score = np.abs(grads @ g2) / (np.linalg.norm(grads, axis=1) + 1e-300)
            best = int(np.argmax(score))
            if direction == "output" and abs(grads[best] @ g2) > 1e-12:
                s = grads[best] / (grads[best] @ g2)
            elif direction in ("output", "orthogonal"):
                s = g2 / (g2 @ g2)
            else:
                raise DimensionError(f"direction: expected 'output' or 'orthogonal', got {direction!r}")
            self.Z = np.vstack([R, s])
            self.g2 = g2
        else:
            R = np.eye(n)
            self.Z = np.eye(n)
            self.g2 = np.zeros(n)
        self.R = R
        self.Zinv = np.linalg.inv(self.Z)
        self.n_a = R.shape[0]
        self.ell0 = R @ system.G @ H_pinv
        self._range = _ComposedRange(system, self.Zinv, splits)
        if self.hidden == 1:
            self.kappa0 = self.Z[-1] @ system.G @ H_pinv
            # global slope of the d-free outputs along t
            inf = np.full(n, np.inf)
            jg_lo, jg_hi = jacobian_bounds(g_jac, -inf, inf, (p, n), "g_jacobian")
            e_t = self.Zinv[:, -1]
            # d/dt U2^T g(Z^{-1} z) = U2^T Jg e_t : interval matrix times point vector
            ujg_lo = pos(self.U2.T) @ jg_lo - neg(self.U2.T) @ jg_hi
            ujg_hi = pos(self.U2.T) @ jg_hi - neg(self.U2.T) @ jg_lo
            sl_lo, sl_hi = ujg_lo @ pos(e_t) - ujg_hi @ neg(e_t), ujg_hi @ pos(e_t) - ujg_lo @ neg(e_t)
            usable = (sl_lo > 0) | (sl_hi < 0)
            if not np.any(usable):
                raise AssumptionError(
                    "NullSpaceGSISIO: the d-free output U2'g is not strictly monotone along G V2 "
                    f"(global slope bounds {np.round(sl_lo, 4).tolist()} to {np.round(sl_hi, 4).tolist()}): "
                    "the hidden state direction cannot be recovered"
                )
            self.slope = (sl_lo, sl_hi)
            self.usable = np.flatnonzero(usable)
        else:
            self.kappa0 = np.zeros(p)
            self.slope = (np.zeros(0), np.zeros(0))
            self.usable = np.zeros(0, dtype=int)

    @classmethod
    def design(cls, system: NonlinearSystem, x0: tuple[ArrayLike, ArrayLike], **options: Any) -> NullSpaceGSISIO:
        """Build the observer.

        Parameters
        ----------
        system : NonlinearSystem
            With Jacobians; at most one hidden input direction (q - rk H ≤ 1).
        x0 : tuple of array_like
            Initial box.
        **options
            ``direction`` ('output' (default): t aligned with the d-free output's gradient at the
            centre of x0, or 'orthogonal'), ``gain_factors`` (multiples of the per-step
            t-cancelling gain; default (0, 1)), ``splits`` (per axis, default 2), ``newton_steps``
            (default 3).

        Returns
        -------
        NullSpaceGSISIO
        """
        check_no_kwargs("NullSpaceGSISIO.design", options, ("direction", "gain_factors", "splits", "newton_steps"))
        box = as_box("x0", x0, system.n)
        return cls(system, box, **options)

    # ---- helpers -----------------------------------------------------------------------------------
    def _gains(self, zlo: FloatArray, zhi: FloatArray) -> tuple[list[FloatArray], list[FloatArray]]:
        """Per-run gains ell (n_a x p) and kappa (1 x p), cancelling d/dt at the box centre."""
        sysm = self.system
        lead = zlo.shape[:-1]
        if self.hidden == 0 or self.U2.shape[1] == 0:
            ell = np.broadcast_to(self.ell0, (*lead, *self.ell0.shape))
            kap = np.broadcast_to(self.kappa0[None, :], (*lead, 1, self.p))
            return [ell], [kap]
        f_jac, g_jac = sysm.jacobians()
        xc = (0.5 * (zlo + zhi)) @ self.Zinv.T
        jf = evaluate_matrix(f_jac, xc, (self.n, self.n))
        jg = evaluate_matrix(g_jac, xc, (self.p, self.n))
        e_t = self.Zinv[:, -1]
        jf_t, jg_t = jf @ e_t, jg @ e_t  # (..., n), (..., p)
        den = jg_t @ self.U2  # (..., p - rank)
        den2 = np.sum(den * den, axis=-1, keepdims=True)
        safe = den2 > 1e-24
        unit = np.where(safe, den / np.where(safe, den2, 1.0), 0.0)  # pseudo-inverse of a row vector
        num_a = jf_t @ self.R.T - jg_t @ self.ell0.T  # (..., n_a)
        num_s = jf_t @ self.Z[-1] - jg_t @ self.kappa0  # (...)
        lam = num_a[..., :, None] * unit[..., None, :]  # (..., n_a, p - rank)
        mu = num_s[..., None, None] * unit[..., None, :]  # (..., 1, p - rank)
        ells = [self.ell0 + c * lam @ self.U2.T for c in self.gain_factors]
        kaps = [self.kappa0[None, :] + c * mu @ self.U2.T for c in self.gain_factors]
        return ells, kaps

    def _correct_t(
        self,
        a_lo: FloatArray,
        a_hi: FloatArray,
        y: FloatArray,
        u: FloatArray,
        prior: BoxPair | None,
        guess: FloatArray,
    ) -> BoxPair:
        """Interval Newton for t in U2'g(Z^{-1}(a, t)) = U2'(y - Du) - U2'v over a in [a_lo, a_hi]."""
        sysm = self.system
        lead = a_lo.shape[:-1]
        rows = self.usable
        u2 = self.U2[:, rows].T  # (r, p)
        phi = np.concatenate([np.zeros((rows.size, self.n)), u2], axis=1)
        phi = np.broadcast_to(phi, (*lead, *phi.shape))
        base = (y - u @ sysm.D.T) @ u2.T
        vlo, vhi = matvec_bounds(u2, *sysm.v)
        target = (base - vhi, base - vlo)  # bounds of U2' g(x)
        if prior is None:
            c = guess
            zc_lo = np.concatenate([a_lo, c[..., None]], -1)
            zc_hi = np.concatenate([a_hi, c[..., None]], -1)
            hlo, hhi = self._range.bounds(phi, zc_lo, zc_hi)
            t_lo, t_hi = _divide((target[0] - hhi, target[1] - hlo), (self.slope[0][rows], self.slope[1][rows]))
            t_lo, t_hi = c[..., None] + t_lo, c[..., None] + t_hi
            t_lo, t_hi = inflate(t_lo.max(axis=-1), t_hi.min(axis=-1))
        else:
            t_lo, t_hi = prior
        for _ in range(self.newton_steps):
            c = 0.5 * (t_lo + t_hi)
            zc_lo = np.concatenate([a_lo, c[..., None]], -1)
            zc_hi = np.concatenate([a_hi, c[..., None]], -1)
            hlo, hhi = self._range.bounds(phi, zc_lo, zc_hi)
            jlo, jhi = self._range.jacobian(
                phi, np.concatenate([a_lo, t_lo[..., None]], -1), np.concatenate([a_hi, t_hi[..., None]], -1)
            )
            s_lo = np.maximum(jlo[..., -1], self.slope[0][rows])
            s_hi = np.minimum(jhi[..., -1], self.slope[1][rows])
            n_lo, n_hi = _divide((target[0] - hhi, target[1] - hlo), (s_lo, s_hi))
            new_lo = np.max(c[..., None] + n_lo, axis=-1)
            new_hi = np.min(c[..., None] + n_hi, axis=-1)
            new_lo, new_hi = inflate(new_lo, new_hi)
            t_lo, t_hi = np.maximum(t_lo, new_lo), np.minimum(t_hi, new_hi)
            bad = t_lo > t_hi  # inconsistent data (or rounding): keep the last sound hull
            if np.any(bad):
                mid = 0.5 * (t_lo + t_hi)
                t_lo, t_hi = np.where(bad, np.minimum(mid, new_lo), t_lo), np.where(bad, np.maximum(mid, new_hi), t_hi)
        return t_lo, t_hi

    # ---- protocol ----------------------------------------------------------------------------------
    def init(self, x0_lower: ArrayLike | None = None, x0_upper: ArrayLike | None = None) -> ObserverState:
        """State before the first measurement: the prior box of :math:`x_0` (in z: its interval hull).

        Parameters
        ----------
        x0_lower, x0_upper : array_like, shape (n,), optional
            Initial box (default: the design's).

        Returns
        -------
        ObserverState
        """
        lo = self.x0[0] if x0_lower is None else as_vector("x0_lower", x0_lower, self.n)
        hi = self.x0[1] if x0_upper is None else as_vector("x0_upper", x0_upper, self.n)
        lo, hi = as_box("x0", (lo, hi), self.n)
        zlo, zhi = inflate(*matvec_bounds(self.Z, lo, hi))
        nan = np.full(self.system.q, np.nan)
        return ObserverState(lo.copy(), hi.copy(), nan, nan.copy(), {"z_lower": zlo, "z_upper": zhi, "started": False})

    def step(self, state: ObserverState, y: ArrayLike, u: ArrayLike | None = None) -> ObserverState:
        """Consume :math:`y_k, u_k` and return the state *at* k: box of :math:`x_k` and of :math:`d_{k-1}`.

        Parameters
        ----------
        state : ObserverState
            The current state.
        y : array_like, shape (p,) or (M, p)
            Measurement :math:`y_k`.
        u : array_like, shape (m,) or (M, m), optional
            Known input :math:`u_k`.

        Returns
        -------
        ObserverState
        """
        sysm = self.system
        yk = np.asarray(y, dtype=float)
        if yk.shape[-1] != self.p:
            raise DimensionError(f"y: expected {self.p} components, got shape {yk.shape}")
        uk = self._input(u, yk.shape[:-1])
        zlo = np.asarray(state.internal["z_lower"], float)
        zhi = np.asarray(state.internal["z_upper"], float)
        lead = yk.shape[:-1]
        zlo, zhi = np.broadcast_to(zlo, (*lead, self.n)), np.broadcast_to(zhi, (*lead, self.n))
        started = bool(state.internal.get("started", False))
        d_lo = np.full((*lead, sysm.q), np.nan)
        d_hi = np.full_like(d_lo, np.nan)
        if started:
            y_prev = np.asarray(state.internal["y"], float)
            u_prev = np.asarray(state.internal["u"], float)
            a_lo, a_hi, d1, chi_rows = self._predict(zlo, zhi, y_prev, u_prev)
        else:
            a_lo, a_hi = zlo[..., : self.n_a], zhi[..., : self.n_a]
        if self.hidden == 1:
            prior = None if started else (zlo[..., -1], zhi[..., -1])
            t_lo, t_hi = self._correct_t(a_lo, a_hi, yk, uk, prior, 0.5 * (zlo[..., -1] + zhi[..., -1]))
            new_lo = np.concatenate([a_lo, t_lo[..., None]], -1)
            new_hi = np.concatenate([a_hi, t_hi[..., None]], -1)
        else:
            new_lo, new_hi = a_lo, a_hi
            if not started:
                new_lo, new_hi = zlo, zhi
        if started:
            d_lo, d_hi = self._inputs(d1, chi_rows, new_lo, new_hi, y_prev, u_prev)
        x_lo, x_hi = inflate(*matvec_bounds(self.Zinv, new_lo, new_hi))
        internal = {"z_lower": new_lo, "z_upper": new_hi, "started": True, "y": yk, "u": uk}
        return ObserverState(x_lo, x_hi, d_lo, d_hi, internal)

    def _predict(
        self, zlo: FloatArray, zhi: FloatArray, y: FloatArray, u: FloatArray
    ) -> tuple[FloatArray, FloatArray, BoxPair, list[tuple[FloatArray, BoxPair]]]:
        """Bounds of a_{k+1}; also the pieces for the delayed input bounds of d_k."""
        sysm = self.system
        n, na = self.n, self.n_a
        ells, kaps = self._gains(zlo, zhi)
        lead = zlo.shape[:-1]
        R_b = np.broadcast_to(self.R, (*lead, *self.R.shape))
        phis = [np.concatenate([R_b, -ell], -1) for ell in ells]
        u1g = np.broadcast_to(
            np.concatenate([np.zeros((self.U1.shape[1], n)), self.U1.T], 1), (*lead, self.U1.shape[1], n + self.p)
        )
        chis = []
        if self.hidden == 1:
            s_b = np.broadcast_to(self.Z[-1][None, :], (*lead, 1, n))
            chis = [np.concatenate([s_b, -kap], -1) for kap in kaps]
        phi_all = np.concatenate([*phis, u1g, *chis], axis=-2)
        lo, hi = self._range.bounds(phi_all, zlo, zhi)
        ydu = y - u @ sysm.D.T
        rbw = matvec_bounds(self.R, *sysm.w)
        a_lo = np.full((*lead, na), -np.inf)
        a_hi = np.full((*lead, na), np.inf)
        for i, ell in enumerate(ells):
            psi_lo, psi_hi = lo[..., i * na : (i + 1) * na], hi[..., i * na : (i + 1) * na]
            known = u @ (self.R @ sysm.B).T + np.einsum("...ij,...j->...i", ell, ydu)
            vlo, vhi = _mat_bounds(
                -ell, np.broadcast_to(sysm.v[0], (*lead, self.p)), np.broadcast_to(sysm.v[1], (*lead, self.p))
            )
            c_lo, c_hi = inflate(psi_lo + known + rbw[0] + vlo, psi_hi + known + rbw[1] + vhi)
            a_lo, a_hi = np.maximum(a_lo, c_lo), np.minimum(a_hi, c_hi)
        off = len(ells) * na
        r1 = self.U1.shape[1]
        g1 = (lo[..., off : off + r1], hi[..., off : off + r1])
        chi_rows = []
        for j, kap in enumerate(kaps if self.hidden == 1 else []):
            k = off + r1 + j
            chi_rows.append((kap[..., 0, :], (lo[..., k], hi[..., k])))
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
        u1v = matvec_bounds(self.U1.T, *sysm.v)
        d1_lo = (base - g1[1] - u1v[1]) / self.sigma
        d1_hi = (base - g1[0] - u1v[0]) / self.sigma
        parts_lo, parts_hi = [d1_lo], [d1_hi]
        if self.hidden == 1:
            s = self.Z[-1]
            t_lo, t_hi = z_next_lo[..., -1], z_next_hi[..., -1]
            sbu = u @ (sysm.B.T @ s)
            sw = matvec_bounds(s[None, :], *sysm.w)
            d2_lo = np.full(t_lo.shape, -np.inf)
            d2_hi = np.full(t_lo.shape, np.inf)
            lead = t_lo.shape
            for kap, (c_lo, c_hi) in chi_rows:
                kv_lo, kv_hi = _mat_bounds(kap[..., None, :], np.broadcast_to(sysm.v[0], (*lead, self.p)),
                                           np.broadcast_to(sysm.v[1], (*lead, self.p)))  # fmt: skip
                ky = np.einsum("...j,...j->...", kap, ydu)
                lo_j = t_lo - sbu - c_hi - ky + kv_lo[..., 0] - sw[1][0]
                hi_j = t_hi - sbu - c_lo - ky + kv_hi[..., 0] - sw[0][0]
                d2_lo, d2_hi = np.maximum(d2_lo, lo_j), np.minimum(d2_hi, hi_j)
            scale = s @ self.g2  # = 1 by construction
            parts_lo.append((d2_lo / scale)[..., None])
            parts_hi.append((d2_hi / scale)[..., None])
        V = np.concatenate([self.V1, self.V2[:, : self.hidden]], axis=1)
        return inflate(*matvec_bounds(V, np.concatenate(parts_lo, -1), np.concatenate(parts_hi, -1)))

    def run(self, t: ArrayLike, y: ArrayLike, u: ArrayLike | None = None) -> Estimate:
        """Bounds over a record: row k bounds :math:`x_k` given :math:`y_{0..k}`, and :math:`d_{k-1}`.

        Parameters
        ----------
        t : array_like, shape (T,)
            Sample times.
        y : array_like, shape (T, p) or (M, T, p)
            Measurements.
        u : array_like, shape (T, m) or (M, T, m), optional
            Known inputs.

        Returns
        -------
        Estimate
        """
        times, ys, us = self._signals(t, y, u)
        lead = ys.shape[:-2]
        T = times.size
        lower = np.empty((*lead, T, self.n))
        upper = np.empty_like(lower)
        dl = np.full((*lead, T, self.system.q), np.nan)
        du = np.full_like(dl, np.nan)
        state = self.init()
        for k in range(T):
            state = self.step(state, ys[..., k, :], us[..., k, :])
            lower[..., k, :], upper[..., k, :] = state.lower, state.upper
            assert state.input_lower is not None and state.input_upper is not None
            dl[..., k, :], du[..., k, :] = state.input_lower, state.input_upper
        meta = {
            "method": "NullSpaceGSISIO (seed 003 made sound: current d-free output)",
            "transient_s": float(times[0]),
            "input_delay_steps": 1,
            "rows": "x_k given y_0..y_k; d_{k-1}",
        }
        return Estimate(times, lower, upper, dl, du, meta)
