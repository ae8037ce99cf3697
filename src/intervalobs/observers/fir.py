r"""A worst-case-optimal finite-memory (FIR) estimator: LP at design time, a fixed linear filter online.

For a point model :math:`x_{k+1} = \Phi x_k + \Gamma u_k + c + \tilde\eta_k`,
:math:`|\tilde\eta_k| \le r` (the sound sampled model of
:mod:`intervalobs.design.discretization`; for seed 002's (68) :math:`\Phi = A`, :math:`r = |E|\bar w`),
and :math:`y_k = C x_k + F v_k`, write :math:`s = k - N`. Then :math:`x_k` and the window's
measurements :math:`y_{s+j}`, :math:`j = 0 \dots N-1`, are affine in :math:`x_s`, the noises and the
known inputs. The estimate of every component is a fixed linear combination of the :math:`N` last
measurements plus a known input term,

.. math:: \hat x_k = \sum_{j<N} K_j y_{s+j} + \sum_{l<N} M_l u_{s+l} + d,

with error :math:`x_k - \hat x_k = R x_s + \sum_l D_l \tilde\eta_{s+l} - \sum_j K_j F \tilde v_{s+j}`,
:math:`D_l = \Phi^{N-1-l} - \sum_{j>l} K_j C \Phi^{j-1-l}`, :math:`R = \Phi^N - \sum_j K_j C\Phi^j`.
The weights :math:`K` are chosen at design time, one LP per state component, minimising the
worst-case error ``sum |D| r + sum |K F| r_v`` subject to :math:`R = 0` (the estimate is unbiased in
the unknown :math:`x_s`). By Smolyak's theorem a linear algorithm attains the radius of information
of this window, so for large ``N`` the radius approaches the half-width of the exact hull's worst case.

**Soundness.** The LP optimum is never used as a bound. The radius is *evaluated* in NumPy from the
computed weights and rounded upward; the LP's residual :math:`R` (about 1e-10, not exactly zero) is
bounded with the fallback observer's own box of :math:`x_s`; the rounding of the online sums is bounded
by :math:`\gamma\,(\sum|K_j||y| + \sum|M_l||u| + |d|)` with :math:`\gamma = (2N + 8)\,\varepsilon`; the
result is intersected with a sound fallback observer (default: the tube :class:`IntervalObserver`),
which alone gives the first ``N`` boxes. An intersection of sound boxes is sound.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import linprog

from ..design.discretization import sampled_model
from ..errors import AssumptionError, DataError, DesignError
from ..estimate import Estimate
from ..interval import ROUNDING_MARGIN, inflate, matvec_bounds
from ..systems.lti import Bounds, LTISystem
from ..validation import as_box
from .base import Observer, ObserverState
from .interval_observer import IntervalObserver

__all__ = ["FiniteMemoryObserver"]

FloatArray = NDArray[np.float64]
_EPS = float(np.finfo(float).eps)


class FiniteMemoryObserver(Observer):
    r"""Worst-case-optimal linear FIR estimator of window ``N``, intersected with a sound fallback.

    Row ``k`` of :meth:`run` is the box of :math:`x_k` given :math:`y_{k-N} \dots y_{k-1}` (and the
    fallback's box); see the module docstring for the equations. Build it with :meth:`design`.

    Parameters
    ----------
    system : LTISystem
        Point model (no ``dA``); continuous time needs ``h``.
    bounds : Bounds
        Initial-state and noise boxes.
    gains : numpy.ndarray, shape (n, N, p)
        Weights ``K_j`` (row ``i``: component ``i``), oldest measurement first.
    fallback : Observer
        Sound observer run in parallel; its box is intersected with the filter's.
    h : float, optional
        Sampling period of a continuous-time system.
    lp_seconds : float
        Design-time LP cost (recorded in :meth:`meta`).
    """

    def __init__(
        self,
        system: LTISystem,
        bounds: Bounds,
        gains: ArrayLike,
        fallback: Observer,
        h: float | None = None,
        lp_seconds: float = 0.0,
    ) -> None:
        if system.dA is not None:
            raise AssumptionError("FiniteMemoryObserver: point models only (system.dA must be None)")
        self.system = system
        self.bounds = bounds.for_system(system)
        self.n, self.p, self.m = system.n, system.p, system.m
        model = sampled_model(system, self.bounds, h)
        self.h = model.h
        k = np.asarray(gains, dtype=float)
        if k.ndim != 3 or k.shape[0] != self.n or k.shape[2] != self.p or k.shape[1] < 1:
            raise DataError(f"gains: expected shape (n={self.n}, N, p={self.p}), got {k.shape}")
        if not np.all(np.isfinite(k)):
            raise DataError("gains: expected finite values")
        self.window = int(k.shape[1])
        self.K = k
        self.fallback = fallback
        self.lp_seconds = float(lp_seconds)
        self._setup(model.Phi, model.Gamma, model.noise_center, model.noise_radius)

    # -- design ----------------------------------------------------------------------------------
    @classmethod
    def design(
        cls,
        system: LTISystem,
        bounds: Bounds,
        window: int = 40,
        h: float | None = None,
        fallback: Observer | None = None,
    ) -> FiniteMemoryObserver:
        """Weights by one LP per component (minimise the evaluated worst-case error, unbiased in ``x_s``).

        Parameters
        ----------
        system : LTISystem
            Point model (no ``dA``).
        bounds : Bounds
            Initial-state and noise boxes.
        window : int
            Memory ``N`` (number of past measurements); needs ``N`` large enough that
            ``C, CΦ, …, CΦ^{N-1}`` determine ``Φ^N`` (observability suffices for ``N >= n``).
        h : float, optional
            Sampling period of a continuous-time system.
        fallback : Observer, optional
            Sound observer to intersect with; default :meth:`IntervalObserver.design`.

        Returns
        -------
        FiniteMemoryObserver
        """
        if system.dA is not None:
            raise AssumptionError("FiniteMemoryObserver: point models only (system.dA must be None)")
        if isinstance(window, bool) or not isinstance(window, (int, np.integer)) or window < 1:
            raise DataError(f"window: expected a positive integer, got {window!r}")
        full = bounds.for_system(system)
        model = sampled_model(system, full, h)
        assert full.v is not None
        n, p, nv, big_n = system.n, system.p, system.F.shape[1], int(window)
        phi, c_mat, f_mat = model.Phi, system.C, system.F
        r = model.noise_radius
        vr = 0.5 * (full.v[1] - full.v[0])
        powers = [np.eye(n)]
        for _ in range(big_n):
            powers.append(phi @ powers[-1])
        # H maps k (N p, block j = k_j) to the D row (N n, block l): -(sum_{j>l} (C Φ^{j-1-l})^T k_j).
        hmat = np.zeros((big_n * n, big_n * p))
        for l_ in range(big_n):
            for j in range(l_ + 1, big_n):
                hmat[l_ * n : (l_ + 1) * n, j * p : (j + 1) * p] = (c_mat @ powers[j - 1 - l_]).T
        vmat = np.kron(np.eye(big_n), f_mat.T)  # (N nv, N p)
        gmat = np.hstack([(c_mat @ powers[j]).T for j in range(big_n)])  # (n, N p)
        nk, ne, nvv = big_n * p, big_n * n, big_n * nv
        cost = np.concatenate([np.zeros(nk), np.tile(r, big_n), np.tile(vr, big_n)])
        eye_e, eye_v = np.eye(ne), np.eye(nvv)
        # t_e >= |phi_i - H k|,  t_v >= |V k|
        a_ub = np.block(
            [
                [-hmat, -eye_e, np.zeros((ne, nvv))],
                [hmat, -eye_e, np.zeros((ne, nvv))],
                [vmat, np.zeros((nvv, ne)), -eye_v],
                [-vmat, np.zeros((nvv, ne)), -eye_v],
            ]
        )
        a_eq = np.hstack([gmat, np.zeros((n, ne + nvv))])
        var_bounds = [(None, None)] * nk + [(0, None)] * (ne + nvv)
        gains = np.zeros((n, big_n, p))
        start = time.perf_counter()
        for i in range(n):
            phi_row = np.concatenate([powers[big_n - 1 - l_][i] for l_ in range(big_n)])
            b_ub = np.concatenate([-phi_row, phi_row, np.zeros(2 * nvv)])
            res = linprog(
                cost, A_ub=a_ub, b_ub=b_ub, A_eq=a_eq, b_eq=powers[big_n][i], bounds=var_bounds, method="highs"
            )
            if res.status != 0:
                raise DesignError(
                    f"FiniteMemoryObserver.design: LP for component {i} failed ({res.message}); "
                    f"is the pair (Φ, C) observable within window={big_n}?"
                )
            gains[i] = res.x[:nk].reshape(big_n, p)
        elapsed = time.perf_counter() - start
        if fallback is None:
            fallback = IntervalObserver.design(system, full, h=h)
        return cls(system, full, gains, fallback, h=h, lp_seconds=elapsed)

    def _setup(self, phi: FloatArray, gamma: FloatArray, c: FloatArray, r: FloatArray) -> None:
        """Evaluate ``D_l``, ``R``, ``M_l``, ``d`` and the sound radius from the weights."""
        n, big_n, k = self.n, self.window, self.K
        c_mat, f_mat = self.system.C, self.system.F
        assert self.bounds.v is not None
        v_c = 0.5 * (self.bounds.v[0] + self.bounds.v[1])
        v_r = 0.5 * (self.bounds.v[1] - self.bounds.v[0])
        powers = [np.eye(n)]
        for _ in range(big_n):
            powers.append(phi @ powers[-1])
        d_mats = np.empty((big_n, n, n))
        for l_ in range(big_n):
            acc = powers[big_n - 1 - l_].copy()
            for j in range(l_ + 1, big_n):
                acc -= k[:, j, :] @ c_mat @ powers[j - 1 - l_]
            d_mats[l_] = acc
        kf = np.einsum("ijp,pq->ijq", k, f_mat)
        self.residual = powers[big_n] - sum(k[:, j, :] @ c_mat @ powers[j] for j in range(big_n))
        self.M = np.einsum("lij,jm->lim", d_mats, gamma)  # (N, n, m)
        self.offset = np.einsum("lij,j->i", d_mats, c) - np.einsum("ijq,q->i", kf, v_c)
        radius = np.einsum("lij,j->i", np.abs(d_mats), r) + np.einsum("ijq,q->i", np.abs(kf), v_r)
        # Upward rounding of the evaluation itself (sums of N (n + nv) nonnegative terms).
        terms = big_n * (n + f_mat.shape[1])
        self.radius = radius * (1 + (terms + 4) * _EPS) + ROUNDING_MARGIN * radius
        self._gamma = (2 * big_n + 8) * _EPS
        self._abs_k, self._abs_m = np.abs(k), np.abs(self.M)

    # -- online ----------------------------------------------------------------------------------
    def _fir(
        self, ys: FloatArray, us: FloatArray, prior_lo: FloatArray, prior_hi: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """Box of ``x_k`` from windows ``ys`` (..., N, p), ``us`` (..., N, m) and the box of ``x_s``."""
        est = np.einsum("...jp,ijp->...i", ys, self.K) + np.einsum("...lm,lim->...i", us, self.M) + self.offset
        mag = (
            np.einsum("...jp,ijp->...i", np.abs(ys), self._abs_k)
            + np.einsum("...lm,lim->...i", np.abs(us), self._abs_m)
            + np.abs(self.offset)
        )
        res_lo, res_hi = matvec_bounds(self.residual, prior_lo, prior_hi)
        pad = self._gamma * mag + self.radius
        return inflate(est - pad + res_lo, est + pad + res_hi)

    def init(self, x0_lower: ArrayLike | None = None, x0_upper: ArrayLike | None = None) -> ObserverState:
        """State at the first sample: the fallback's initial state and empty buffers.

        Parameters
        ----------
        x0_lower, x0_upper : array_like, shape (n,), optional
            Prior box of ``x(t_0)``; both or neither (default: the design bounds).

        Returns
        -------
        ObserverState
        """
        if (x0_lower is None) != (x0_upper is None):
            raise DataError("x0_lower, x0_upper: give both or neither")
        if x0_lower is not None and x0_upper is not None:
            as_box("x0", (x0_lower, x0_upper), self.n)
        inner = self.fallback.init(x0_lower, x0_upper)
        internal: dict[str, Any] = {
            "fallback": inner,
            "k": 0,
            "ys": [],
            "us": [],
            "priors": [(inner.lower, inner.upper)],
        }
        return ObserverState(inner.lower, inner.upper, internal=internal)

    def step(self, state: ObserverState, y: ArrayLike, u: ArrayLike | None = None) -> ObserverState:
        """Consume ``y_k``, ``u_k``; return the box of ``x_{k+1}`` (fallback ∩ filter once ``k+1 >= N``).

        Parameters
        ----------
        state : ObserverState
            State at ``t_k``.
        y : array_like, shape (p,) or (M, p)
            Measurement at ``t_k``.
        u : array_like, shape (m,) or (M, m), optional
            Known input at ``t_k``.

        Returns
        -------
        ObserverState
        """
        yk, uk = self._sample(y, u)
        if uk.shape[-1:] != (self.m,) or not np.all(np.isfinite(uk)):
            raise DataError(f"u: expected finite values with last dimension {self.m}, got shape {uk.shape}")
        old = state.internal
        inner = self.fallback.step(old["fallback"], yk, uk)
        big_n = self.window
        ys = (old["ys"] + [yk])[-big_n:]
        us = (old["us"] + [uk])[-big_n:]
        priors = (old["priors"] + [(inner.lower, inner.upper)])[-(big_n + 1) :]
        k = old["k"] + 1
        lower, upper = inner.lower, inner.upper
        if k >= big_n:
            y_win = np.stack(ys, axis=-2)
            u_win = np.stack([np.broadcast_to(v, (*y_win.shape[:-2], self.m)) for v in us], axis=-2)
            f_lo, f_hi = self._fir(y_win, u_win, *priors[0])
            lower, upper = np.maximum(lower, f_lo), np.minimum(upper, f_hi)
        internal = {"fallback": inner, "k": k, "ys": ys, "us": us, "priors": priors}
        return ObserverState(lower, upper, internal=internal)

    def run(self, t: ArrayLike, y: ArrayLike, u: ArrayLike | None = None) -> Estimate:
        """Bounds over a whole record, vectorised over time (sliding windows) and Monte Carlo runs.

        Parameters
        ----------
        t : array_like, shape (T,)
            Sample times (spacing ``h`` for a continuous-time system).
        y : array_like, shape (T, p) or (M, T, p)
            Measurements; a leading axis holds Monte Carlo runs.
        u : array_like, shape (T, m) or (M, T, m), optional
            Known inputs.

        Returns
        -------
        Estimate
            Row ``k`` is the box of ``x(t_k)`` given ``y_0 … y_{k-1}``.
        """
        times, ys, us = self._signals(t, y, u)
        if self.system.continuous and times.size > 1:
            spacing = np.diff(times)
            if np.max(np.abs(spacing - self.h)) > 1e-9 * self.h:
                raise DataError(f"t: expected uniform spacing h = {self.h:g} (the design's sampling period)")
        base = self.fallback.run(times, ys, us)
        lower, upper = base.lower.copy(), base.upper.copy()
        big_n, steps = self.window, times.size
        if steps > big_n:
            y_win = np.moveaxis(np.lib.stride_tricks.sliding_window_view(ys[..., :-1, :], big_n, axis=-2), -1, -2)
            u_win = np.moveaxis(np.lib.stride_tricks.sliding_window_view(us[..., :-1, :], big_n, axis=-2), -1, -2)
            f_lo, f_hi = self._fir(
                y_win, u_win, base.lower[..., : steps - big_n, :], base.upper[..., : steps - big_n, :]
            )
            lower[..., big_n:, :] = np.maximum(lower[..., big_n:, :], f_lo)
            upper[..., big_n:, :] = np.minimum(upper[..., big_n:, :], f_hi)
        return Estimate(times, lower, upper, meta=self.meta())

    def meta(self) -> dict[str, Any]:
        """Design facts recorded in every :class:`~intervalobs.estimate.Estimate`.

        Returns
        -------
        dict
            ``method``, ``window``, ``radius`` (evaluated, rounded up), ``residual`` (max ``|R|``),
            ``lp_seconds``, ``fallback`` (its meta).
        """
        fallback_meta = self.fallback.meta() if hasattr(self.fallback, "meta") else {}
        return {
            "method": "FiniteMemoryObserver",
            "window": self.window,
            "radius": self.radius.tolist(),
            "residual": float(np.max(np.abs(self.residual))),
            "lp_seconds": self.lp_seconds,
            "fallback": fallback_meta,
            "transient_s": float(self.window * self.h),
        }
