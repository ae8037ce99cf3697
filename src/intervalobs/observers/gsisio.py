r"""Simultaneous input and state interval observers for nonlinear discrete-time systems (Khajenejad & Yong).

System (Khajenejad & Yong, eq. (3); :class:`~intervalobs.systems.nonlinear.NonlinearSystem`):
:math:`x_{k+1} = f(x_k) + Bu_k + Gd_k + w_k`, :math:`y_k = g(x_k) + Du_k + Hd_k + v_k`.

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
available together with :math:`x_k`; row 0 is :math:`[-\infty, \infty]`).

The sound variant for rank-deficient H is :class:`~intervalobs.observers.null_space_gsisio.NullSpaceGSISIO`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._docstrings import shared_docs
from ..design.abstraction import AffineAbstraction, abstraction_sigma, affine_abstraction
from ..design.composed_range import ComposedRange
from ..design.gsisio import GSISIODesign, gsisio_design
from ..design.mixed_monotone import decomposition_bounds, jacobian_bounds
from ..errors import AssumptionError
from ..interval import inflate, matvec_bounds
from ..systems.bounds import Bounds
from ..systems.nonlinear import NonlinearSystem
from ..validation import as_array, as_box, check_no_kwargs
from .base import Observer, ObserverState, options_after_bounds

__all__ = ["GSISIO"]

FloatArray = NDArray[np.float64]
BoxPair = tuple[FloatArray, FloatArray]


def _input_hull(M: FloatArray, h_lo: FloatArray, h_hi: FloatArray, d_lo: FloatArray, d_hi: FloatArray) -> BoxPair:
    """Exact interval hull of {d : h_lo <= M d <= h_hi} (LP per component), intersected with (d_lo, d_hi).

    The J-based box (Lemma 3) contains the set, so it bounds the LP; the LP optimum is widened by the
    solver's feasibility tolerance scaled back to d and by the rounding margin.
    """
    from scipy.optimize import linprog

    from ..lp.certified import LP_OPTIONS

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
                res = linprog(cost, A_ub=a_ub, b_ub=b_ub, bounds=bounds, method="highs", options=LP_OPTIONS)
                if res.status == 0 and res.x is not None:
                    value = float(res.x[i]) - sign * slack * (1.0 + abs(float(res.x[i])))
                    out[r, i] = pick(out[r, i], value)
    return flat_lo.reshape(lo_out.shape), flat_hi.reshape(hi_out.shape)


class GSISIO(Observer):
    r"""Simultaneous bounds of the state and of an unknown input of a nonlinear discrete-time system.

    The simultaneous input and state interval observer of Khajenejad & Yong, with its gains. Use
    :meth:`design`. The bounds :math:`\underline f, \overline f, \underline g, \overline g` over the
    previous box intersect a decomposition of ``f`` and ``g`` from global Jacobian bounds with an affine
    abstraction over the abstraction domain and, with ``tight=True``, also the local-Jacobian
    decomposition, mean-value form and natural extension; intersecting only shrinks the widths, so the
    paper's width bounds still hold.

    Parameters
    ----------
    system : NonlinearSystem
        The model, with Jacobians.
    design_result : GSISIODesign
        From :func:`gsisio_design` (the constructor does not check that the input can be recovered:
        :meth:`design` does).
    bounds : Bounds
        Boxes of ``x0``, ``w`` and ``v``.
    abstraction_f, abstraction_g : AffineAbstraction, optional
        Affine bounds of ``f`` and ``g`` on the abstraction domain (from a linear program).
    tight : bool
        Also intersect with local-Jacobian ranges.
    splits : int
        Sub-boxes per axis for the local ranges.
    input_hull : bool
        Replace the paper's input box :math:`J^+\overline h - J^-\underline h` by the exact interval
        hull of :math:`\{d : \underline h \le [G; H]d \le \overline h\}` (2q LPs per step with HiGHS;
        the paper's box is "tight" only relative to the J-based box). Default False.

    References
    ----------
    Khajenejad & Yong (:mod:`intervalobs.references`): the observer (4)–(7) with Theorem 1's gains
    (Algorithm 1); the bounds of Corollary 1 (decomposition (2), abstraction LP (1)); the input box of
    Lemma 3; the width bounds of Lemma 5; the existence condition (8).
    """

    summary_fields = ("tight", "input_hull")

    def __init__(
        self,
        system: NonlinearSystem,
        design_result: GSISIODesign,
        bounds: Bounds,
        abstraction_f: AffineAbstraction | None = None,
        abstraction_g: AffineAbstraction | None = None,
        tight: bool = True,
        splits: int = 1,
        input_hull: bool = False,
    ) -> None:
        self.system = system
        self.design_result = design_result
        self.bounds = bounds.resolve(system)
        self.abstraction_f, self.abstraction_g = abstraction_f, abstraction_g
        self.tight = tight
        self.input_hull = input_hull
        self.n, self.p, self.m = system.n, system.p, system.m
        self._range = ComposedRange(system, np.eye(system.n), splits)
        self._phi = np.eye(system.n + system.p)
        d = design_result
        eye = np.eye(self.n)
        self._sum_inv = np.linalg.pinv(eye - d.K1 + d.L1)  # = inverse when (8) holds
        self._diff_inv = np.linalg.pinv(eye - d.K1 - d.L1)

    @classmethod
    @options_after_bounds("jacobian_domain", "abstraction_domain")
    def design(
        cls,
        system: NonlinearSystem,
        bounds: Bounds,
        *,
        jacobian_domain: tuple[ArrayLike, ArrayLike] | None = None,
        abstraction_domain: tuple[ArrayLike, ArrayLike] | None = None,
        **options: Any,
    ) -> GSISIO:
        """Compute the gains, check that the unknown input can be recovered, then bound ``f`` and ``g`` affinely.

        Parameters
        ----------
        system : NonlinearSystem
            The model.
        bounds : Bounds
            Boxes of ``x0``, ``w`` and ``v``.
        jacobian_domain : tuple of array_like, optional
            Domain of the global Jacobian bounds (default: the whole space).
        abstraction_domain : tuple of array_like, optional
            Box on which the affine bounds of ``f`` and ``g`` are computed (default: the initial box);
            used for boxes inside it.
        **options
            ``tight`` (bool, default True), ``splits`` (int, default 1), ``input_hull`` (bool, default
            False: exact LP hull of the input bounds instead of the paper's box).

        Returns
        -------
        GSISIO

        Raises
        ------
        AssumptionError
            The state and unknown input cannot both be recovered from the outputs with these gains
            (the existence condition fails), or :math:`\\rho(K_1 + L_1) \\ge 1` (the widths are not
            guaranteed bounded).

        References
        ----------
        Khajenejad & Yong: Theorem 1 (gains), condition (8) (existence), LP (1) (affine abstraction),
        Lemma 3 (input box), (9) (framers).
        """
        check_no_kwargs("GSISIO.design", options, ("tight", "splits", "input_hull"))
        full = bounds.resolve(system)
        box = full.x0
        d = gsisio_design(system, full, jacobian_domain)
        n = system.n
        if not d.condition_8:
            hidden = ""
            q_h = int(np.linalg.matrix_rank(system.H))
            if q_h < system.q:
                hidden = f"; H has rank {q_h} < {system.q}, so (I - K1 + L1) G V2 = 0 for H V2 = 0"
            raise AssumptionError(
                "the gains cannot bound the state from both sides (rank condition): "
                f"rk(I - K1 - L1) = {d.rank_condition_8[0]}, "
                f"rk(I - K1 + L1) = {d.rank_condition_8[1]}, expected both = n = {n}{hidden}"
            )
        if not d.correctness_radius < 1.0:
            raise AssumptionError(
                "the bounds would not be guaranteed: expected rho(K1 + L1) < 1 (error system an M-matrix), "
                f"got {d.correctness_radius:.4g}"
            )
        dom = box if abstraction_domain is None else as_box("abstraction_domain", abstraction_domain, n)
        f_jac, g_jac = system.jacobians()
        jf = jacobian_bounds(f_jac, dom[0], dom[1], (n, n))
        jg = jacobian_bounds(g_jac, dom[0], dom[1], (system.p, n))
        abs_f = affine_abstraction(system.f, dom[0], dom[1], abstraction_sigma(dom[0], dom[1], *jf), n)
        abs_g = affine_abstraction(system.g, dom[0], dom[1], abstraction_sigma(dom[0], dom[1], *jg), system.p)
        return cls(system, d, full, abs_f, abs_g, tight=bool(options.get("tight", True)),
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
    @shared_docs
    def init(self, x0_lower: ArrayLike | None = None, x0_upper: ArrayLike | None = None) -> ObserverState:
        """State at k = 0: the initial box, no input bound yet (``[-inf, inf]``).

        %(prior_box)s
        """
        lo, hi = self._prior_box(self.bounds.x0, x0_lower, x0_upper)
        unbounded = np.full(self.system.q, np.inf)
        return ObserverState(lo.copy(), hi.copy(), -unbounded, unbounded, {"k": 0})

    def _step(self, state: ObserverState, y: FloatArray, u: FloatArray) -> ObserverState:
        """Consume :math:`y_k, u_k`; return the box of :math:`x_{k+1}` and of :math:`d_k` (eqs. (4)–(7))."""
        lo, hi = np.asarray(state.lower, float), np.asarray(state.upper, float)
        yk, uk = y, u
        d, sysm = self.design_result, self.system
        (f_lo, f_hi), (g_lo, g_hi) = self._fg_bounds(lo, hi)
        bu, du = uk @ sysm.B.T, uk @ sysm.D.T
        wl, wu = self.bounds.w
        vl, vu = self.bounds.v
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

    def meta(self) -> dict[str, Any]:
        """Facts recorded in every :class:`~intervalobs.estimate.Estimate` of :meth:`run`.

        Returns
        -------
        dict
            ``method`` and ``input_delay_steps`` (1: input row ``k`` bounds :math:`d_{k-1}`).
        """
        return {"method": "GSISIO (the gains of Khajenejad & Yong)", "input_delay_steps": 1}

    def current_input_bounds(
        self, x_lower: ArrayLike, x_upper: ArrayLike, y: ArrayLike, u: ArrayLike | None = None
    ) -> tuple[BoxPair, FloatArray]:
        r"""Bounds of the input part :math:`d_{1,k} = V_1^\top d_k` the current output sees, given a box of x_k.

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

        References
        ----------
        Khajenejad & Yong, Lemma 4.
        """
        sysm = self.system
        U, S, Vt = np.linalg.svd(sysm.H)
        r = int(np.sum(S > S.max() * 1e-10))
        U1, V1 = U[:, :r], Vt[:r].T
        lo, hi = np.asarray(x_lower, float), np.asarray(x_upper, float)
        _, (g_lo, g_hi) = self._fg_bounds(lo, hi)
        yk = as_array("y", y)
        du = 0.0 if u is None else as_array("u", u) @ sysm.D.T
        gl, gh = matvec_bounds(U1.T, g_lo, g_hi)
        vl, vh = matvec_bounds(U1.T, *self.bounds.v)
        base = (yk - du) @ U1
        return inflate((base - gh - vh) / S[:r], (base - gl - vl) / S[:r]), V1
