r"""Data-dependent boxes under an interval :math:`\Delta A`: the window LP with :math:`\Delta A` a shared unknown.

With an unknown constant :math:`\Delta A \in [\underline{\Delta A}, \overline{\Delta A}]` the set of states
consistent with the data is not convex (the dynamics contain the products :math:`\Delta A\,x_j`), so
its hull is not an LP (:class:`~intervalobs.observers.hull.HullEstimator` refuses it). The fixed-gain
observers bound :math:`\Delta A\,x_j` by the interval product :math:`|\Delta A|\,|x_j|`, a fresh
disturbance at every step of the size of the *state*; that term dominates their width on the two-tank
and spring-mass examples. Here :math:`\Delta A` is one unknown shared by every step of a window, and the
product is split around a known reference :math:`\hat x_j` (the midpoint of the estimator's own box of
:math:`x_j`):

.. math::

    \Delta A\,x_j = \Delta A\,\hat x_j + \Delta A\,(x_j - \hat x_j),

whose first term is **linear in the unknown** :math:`\delta = \Delta A - \Delta A_c` (an LP variable,
the same at every step, which the data identify) and whose second term is bounded by
:math:`|\delta|_{\max}\,|x_j - \hat x_j|`, of the size of the *box width*, not of the state. The window
LP over steps :math:`s = k - H, \dots, k` (states eliminated, as the hull's condensed LP):

.. math::

    x_{j+1} = \Phi_c x_j + \Gamma_c u_j + W_j\,\delta + e_j,\qquad
    e_j \in [c - r - \rho_j,\; c + r + \rho_j],\qquad y_j - C x_j \in \mathcal V,\qquad
    x_s \in [\underline x_s, \overline x_s],\quad \delta \in [\underline\delta, \overline\delta],

with :math:`W_j = [M_{ab}\hat x_j + N_{ab}u_j]_{ab}` (one column per uncertain entry :math:`(a, b)`),
:math:`[c \pm r]` the noise box of the sound sampled model (valid for every :math:`\Delta A` of the box)
and the remainder radius :math:`\rho_j = K\,|x_j - \hat x_j|_{\max} + R_x|x_j|_{\max} + R_u|u_j|`.

* **Discrete time**: :math:`\Phi_c = A + \Delta A_c`, :math:`M_{ab} = e_a e_b^\top`, :math:`N = 0`,
  :math:`R = 0`, :math:`K = |\delta|_{\max}`.
* **Continuous time** (sampling period ``h``, input held): with the augmented matrix
  :math:`\mathcal A = [[A_c, B], [0, 0]]` and the direction :math:`\mathcal D = [[\delta, 0], [0, 0]]`,
  :math:`e^{(\mathcal A + \mathcal D)h} = e^{\mathcal A h} + L(\mathcal A h, \mathcal D h) + R`, with
  :math:`L` the Fréchet derivative of the exponential (linear in :math:`\delta`: it gives
  :math:`M_{ab}, N_{ab}`) and :math:`|R| \le e^{(|\mathcal A| + D)h} - e^{|\mathcal A|h} -
  L(|\mathcal A|h, Dh)` (the terms of the exponential series with at least two factors of
  :math:`\mathcal D`, bounded termwise; all terms nonnegative). :math:`K = \sum_{ab} D_{ab}|M_{ab}|`.

  Both cases are :func:`~intervalobs.systems.sampling.delta_linearisation`.

Every state of the true system, with the true :math:`\Delta A`, noise and remainder, is feasible (the
boxes of :math:`x_j` are the estimator's own, sound by induction), so every bound of the LP is a sound
bound. Bounds are **certified by weak duality** with the rounding of their evaluation subtracted
(:func:`~intervalobs.lp.certified.dual_bounds`, as the hull); the condensed matrix and the drive are
padded for their own rounding like the hull's condensed LP.

**McCormick window** (``mccormick=True``). The split bounds :math:`\delta\,(x_j - \hat x_j)` by
:math:`|\delta|_{\max}|x_j - \hat x_j|_{\max}` whatever :math:`\delta` the LP picks; but the extremal
:math:`\delta` sits near a vertex of its box, where the product is known exactly. Keeping every product
:math:`q = \delta_l\,x_{j,b}` as an LP column, bounded by its four McCormick envelopes over
:math:`\delta_l \in [\underline\delta_l, \overline\delta_l]` and :math:`x_{j,b}` in its box (exact at
the vertices; McCormick 1976), gives a set inside the split LP's. The states stay LP columns (a sparse
LP: the envelopes of step ``j`` read :math:`x_j` only) and every state of the window is bounded by its
box. On the integrated-observer paper's (68) it removes most of the remainder's width (docs/tightness.md: 1.35× → 1.21×
the certified lower bound on the worst run, H = 20), at about 3 times the CPU time per step of the split
LP (H = 40). The LP is one HiGHS model built once, with a slot per time of the window used cyclically;
each step changes its bounds and the few coefficients of the newest slot, and every bound restarts from
its basis of the previous step (:class:`EnvelopeLP`).

**Identification.** The same LP bounds each entry of :math:`\delta`; since :math:`\Delta A` is constant,
every certified bound holds at every later step, so the estimator keeps the running intersection (the
box of :math:`\Delta A` consistent with all data seen so far). It shrinks the remainder radii and the
interval prediction too.

The box of :math:`x_k` is finally intersected with the interval prediction of the previous box and
with an optional fallback observer's box (so it is never wider than that observer).
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._docstrings import shared_docs
from ..errors import ArgumentTypeError, AssumptionError, DataError, DesignError, DimensionError, InconsistentDataError
from ..interval import inflate
from ..lp.certified import DenseLP
from ..lp.chain import Solver, SolverPath, as_solver
from ..lp.envelope import EnvelopeLP
from ..lp.window import window_state_maps
from ..systems.bounds import Bounds
from ..systems.lti import LTISystem
from ..systems.sampling import delta_linearisation, sampled_model
from ..validation import as_positive
from .base import Observer, ObserverState, options_after_bounds
from .interval_observer import IntervalObserver

__all__ = ["RobustHullEstimator"]

FloatArray = NDArray[np.float64]

_EPS = float(np.finfo(float).eps)


@shared_docs
class RobustHullEstimator(Observer):
    r"""Sound, data-dependent boxes for an LTI system with interval ``ΔA``: window LP with ``ΔA`` shared.

    Build it with :meth:`design` (the constructor takes the same arguments).

    Parameters
    ----------
    %(uncertain_system_bounds)s
    horizon : int
        Window length ``H`` in steps (the prior is the estimator's own box ``H`` steps back).
    h : float, optional
        Sampling period of a continuous-time system (required there).
    identify : bool
        Also bound every uncertain entry of ``ΔA`` by the window LP at each step and keep the running
        intersection (``2 n_δ`` more LPs per step; tighter remainders and predictions).
    fallback : Observer, optional
        A sound observer run on the same data; the box is intersected with its box (never wider).
    mccormick : bool
        Keep the products ``δ_l x_{j,b}`` as LP columns bounded by their McCormick envelopes (module
        docstring): never wider than the split LP, a sparse LP with ``4 n_q`` more rows per step
        (``n_q`` = nonzero columns of the ``M_l``: ``n_δ`` in discrete time).
    solver : {"auto", "highs"}
        As for :class:`~intervalobs.observers.hull.HullEstimator`; both mean HiGHS here (these LPs have no
        chain for the dense simplex), and the option exists so that one setting serves both estimators.

    Notes
    -----
    See the module docstring for the LP. Each step solves ``2n`` LPs (``2(n + n_δ)`` with ``identify``)
    with HiGHS; row ``k`` of :meth:`run` is the box of ``x_k`` given ``y_0 … y_{k-1}`` (prediction form).
    ``meta()["delta_box"]`` holds the identified box of ``ΔA`` at the end of the last run, and
    ``meta()["solver_path"]`` the route of every step's solves (:class:`~intervalobs.lp.chain.SolverPath`).
    """

    summary_fields = ("horizon", "identify", "mccormick")
    batched = False  # one LP per bound and run: a Monte Carlo axis is run after run

    def __init__(
        self,
        system: LTISystem,
        bounds: Bounds,
        horizon: int = 40,
        h: float | None = None,
        identify: bool = True,
        fallback: Observer | None = None,
        mccormick: bool = False,
        solver: Solver = "auto",
    ) -> None:
        if not isinstance(system, LTISystem):
            raise ArgumentTypeError(f"system: expected an LTISystem, got {type(system).__name__}")
        if not isinstance(bounds, Bounds):
            raise ArgumentTypeError(f"bounds: expected a Bounds, got {type(bounds).__name__}")
        if system.dA is None:
            raise AssumptionError("system.dA: expected an interval ΔA (without it, use HullEstimator: exact)")
        if isinstance(horizon, bool) or int(horizon) != horizon or horizon < 1:
            raise DataError(f"horizon: expected a positive integer, got {horizon!r}")
        if system.continuous:
            as_positive("h", h, "a positive sampling period for a continuous-time system")
        self.system, self.bounds = system, bounds.resolve(system)
        self.n, self.p, self.m = system.n, system.p, system.m
        self.horizon = int(horizon)
        self.h = float(h) if system.continuous and h is not None else float(system.dt or 1.0)
        self.identify = bool(identify)
        self.fallback = fallback
        self.model = delta_linearisation(system, self.bounds, h if system.continuous else None)
        self.sampled = sampled_model(system, self.bounds, h if system.continuous else None)
        self.nd = len(self.model.entries)
        self._rows = np.array([a for a, _ in self.model.entries], dtype=int)
        self._cols = np.array([b for _, b in self.model.entries], dtype=int)
        self.mccormick = bool(mccormick)
        self.solver = as_solver(solver)
        self._paths: list[dict[str, int]] = []
        """The route of every step's LP solves since :meth:`init` (``meta["solver_path"]``)."""
        pairs = np.argwhere(np.any(self.model.M != 0, axis=1))  # (l, b): column b of M_l is nonzero
        self._pairs = (pairs[:, 0], pairs[:, 1])
        self._extremal: dict[int, FloatArray] = {}
        self._lp = DenseLP()
        self._envelope = EnvelopeLP(self.model, self._pairs, self.horizon) if self.mccormick else None
        self.delta_box: tuple[FloatArray, FloatArray] = (-self.model.radius.copy(), self.model.radius.copy())

    @classmethod
    @options_after_bounds("h")
    @shared_docs
    def design(
        cls,
        system: LTISystem,
        bounds: Bounds,
        *,
        h: float | None = None,
        horizon: int = 40,
        identify: bool = True,
        fallback: Observer | Literal[False] | None = None,
        mccormick: bool = False,
        solver: Solver = "auto",
    ) -> RobustHullEstimator:
        """Build the estimator (there is no gain: the window LP of each step is the estimator).

        Parameters
        ----------
        %(uncertain_system_bounds)s
        h : float, optional
            Sampling period of a continuous-time system (required there).
        horizon : int
            Window length ``H`` in steps.
        identify : bool
            Also bound the uncertain entries of ``ΔA`` at each step (class docstring).
        fallback : Observer or False, optional
            A sound observer whose box the estimate is intersected with; default
            :meth:`IntervalObserver.design` of ``system`` (where a gain exists), so that the estimator never
            returns a box wider than the default observer's on the same data (the window LP's linearisation
            in ``ΔA`` can be the looser one for ``‖A‖h`` of a few units); ``False``: the window LP alone.
        mccormick : bool
            Bound the products ``δ_l x_{j,b}`` by their McCormick envelopes (class docstring).
        solver : {"auto", "highs"}
            Which solvers the LPs use (class docstring).

        Returns
        -------
        RobustHullEstimator

        Raises
        ------
        AssumptionError
            If the system has no interval ``dA`` (use :class:`~intervalobs.observers.hull.HullEstimator`).
        """
        given = fallback if isinstance(fallback, Observer) else None
        estimator = cls(system, bounds, horizon, h, identify, given, mccormick, solver)
        if fallback is None:
            try:
                estimator.fallback = IntervalObserver.design(system, bounds, h=h)
            except DesignError:  # no bounded observer for this model: the window LP alone
                pass
        return estimator

    # -- the window LP ---------------------------------------------------------------------------
    def _window(
        self, k: int, ys: FloatArray, us: FloatArray, box_lo: FloatArray, box_hi: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Load the LP of the window ``s = max(k - H, 0) … k`` (rows: ``y_s … y_{k-1}``).

        Row ``i`` of ``ys``, ``us`` and ``box_*`` is time ``s + i`` (``box_*`` bound ``x_τ`` for
        ``s ≤ τ < k``). Returns the affine maps of the window's states (L + 1, n, ncol), their drives
        (L + 1, n) and rounding pads (L + 1, n).
        """
        mod, n, nd = self.model, self.n, self.nd
        L = min(k, self.horizon)
        d_lo, d_hi = self.delta_box
        d_max = np.maximum(np.abs(d_lo), np.abs(d_hi))[self._rows, self._cols]
        K = np.einsum("l,lij->ij", d_max, np.abs(mod.M))
        lo, hi = box_lo[:L], box_hi[:L]
        mid, half, big = 0.5 * (lo + hi), 0.5 * (hi - lo), np.maximum(np.abs(lo), np.abs(hi))
        u_win = us[:L]
        rho = half @ K.T + big @ mod.R_x.T + np.abs(u_win) @ mod.R_u.T
        e_lo, e_hi = mod.noise_lo - rho, mod.noise_hi + rho
        sens = np.einsum("lab,jb->jal", mod.M, mid) + np.einsum("lab,jb->jal", mod.N, u_win)
        states, drives = window_state_maps(mod.Phi, mod.Gamma, np.eye(n), sens, u_win)
        # Magnitude bound of every term of x_j (rounding of the maps, the drive and the products W_j).
        growth = (
            np.maximum(np.abs(e_lo), np.abs(e_hi))
            + np.einsum("lab,jb,l->ja", np.abs(mod.M), np.abs(mid), d_max)
            + np.einsum("lab,jb,l->ja", np.abs(mod.N), np.abs(u_win), d_max)
            + np.abs(u_win) @ np.abs(mod.Gamma).T
            + np.abs(drives[1:])
        )
        mag = np.zeros((L + 1, n))
        mag[0] = np.maximum(np.abs(box_lo[0]), np.abs(box_hi[0]))
        abs_phi = np.abs(mod.Phi)
        for j in range(L):
            mag[j + 1] = abs_phi @ mag[j] + growth[j]
        rounding = (n + nd + self.m + 2) * _EPS * mag
        pads = 4.0 * (L + 1) * rounding + rounding
        row_pad = pads[:L] @ np.abs(mod.C).T
        matrix = np.einsum("pn,jnc->jpc", mod.C, states[:L]).reshape(L * self.p, -1)
        centre = drives[:L] @ mod.C.T
        row_lo = (ys[:L] - mod.v_hi - centre - row_pad).ravel()
        row_hi = (ys[:L] - mod.v_lo - centre + row_pad).ravel()
        col_lo = np.concatenate([box_lo[0], e_lo.ravel(), d_lo[self._rows, self._cols]])
        col_hi = np.concatenate([box_hi[0], e_hi.ravel(), d_hi[self._rows, self._cols]])
        self._lp.load(matrix, col_lo, col_hi, row_lo, row_hi)
        return states, drives, pads

    def _box(
        self,
        k: int,
        start: int,
        ys: FloatArray,
        us: FloatArray,
        box_lo: FloatArray,
        box_hi: FloatArray,
        predicted: tuple[FloatArray, FloatArray],
    ) -> tuple[FloatArray, FloatArray]:
        """Certified box of ``x_k`` from ``y_0 … y_{k-1}``; with ``identify`` the ``δ`` box is updated too.

        Row ``i`` of ``ys``, ``us`` and ``box_*`` is time ``start + i``; ``predicted`` is a sound box of
        ``x_k`` (the McCormick LP bounds its newest state by it).
        """
        n, nd = self.n, self.nd
        first = max(k - self.horizon, 0) - start
        lp: DenseLP | EnvelopeLP = self._lp
        if self._envelope is not None:
            d_box = (self.delta_box[0][self._rows, self._cols], self.delta_box[1][self._rows, self._cols])
            window = (ys[first:], us[first:], box_lo[first:], box_hi[first:])
            objective = self._envelope.set_window(k, *window, predicted, d_box, self.m)
            drive = pad = np.zeros(n)
            lp = self._envelope
        else:
            states, drives, pads = self._window(k, ys[first:], us[first:], box_lo[first:], box_hi[first:])
            objective, drive, pad = states[-1], drives[-1], pads[-1]
        costs = np.concatenate([objective, -objective])
        identify = self.identify and nd > 0 and k > 0
        if identify:
            pick = np.zeros((nd, lp.ncol))
            pick[:, lp.ncol - nd :] = np.eye(nd)
            costs = np.concatenate([costs, pick, -pick])
        values, points = lp.minima(costs)
        self._extremal[k] = points[: 2 * n, lp.ncol - nd :]
        lower = values[:n] + drive - pad
        upper = -values[n : 2 * n] + drive + pad
        if identify:
            d_lo, d_hi = self.delta_box[0].copy(), self.delta_box[1].copy()
            rows, cols = self._rows, self._cols
            d_lo[rows, cols] = np.maximum(d_lo[rows, cols], values[2 * n : 2 * n + nd])
            d_hi[rows, cols] = np.minimum(d_hi[rows, cols], -values[2 * n + nd :])
            if np.any(d_lo > d_hi):
                raise InconsistentDataError(
                    f"y: the measurements are inconsistent with the model and its ΔA box at step {k}"
                )
            self.delta_box = (d_lo, d_hi)
        return lower, upper

    def _predict(self, lo: FloatArray, hi: FloatArray, u: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Interval image of the box through one step of the sampled model (discrete time: identified ``ΔA`` box)."""
        transition = None
        if not self.system.continuous:
            base = self.system.A + self.model.center
            transition = (base + self.delta_box[0], base + self.delta_box[1])
        return self.sampled.image(lo, hi, u, transition)

    # -- protocol ------------------------------------------------------------------------------
    @shared_docs
    def init(self, x0_lower: ArrayLike | None = None, x0_upper: ArrayLike | None = None) -> ObserverState:
        """State at the first sample: the prior box, an empty record and the full ``ΔA`` box.

        %(prior_box)s
        """
        lo, hi = self._prior_box(self.bounds.x0, x0_lower, x0_upper)
        self.delta_box = (-self.model.radius.copy(), self.model.radius.copy())
        self._extremal = {}
        if self._envelope is not None:
            self._envelope.forget_bases()  # every run starts from scratch (reproducible)
        self._take_path()
        self._paths = []
        internal: dict[str, Any] = {
            "k": 0,
            "start": 0,
            "y": np.zeros((0, self.p)),
            "u": np.zeros((0, self.m)),
            "box_lo": lo[None].copy(),
            "box_hi": hi[None].copy(),
            "fallback": None if self.fallback is None else self.fallback.init(lo, hi),
            "delta_box": self.delta_box,
        }
        return ObserverState(lo.copy(), hi.copy(), internal=internal)

    def step(self, state: ObserverState, y: ArrayLike, u: ArrayLike | None = None) -> ObserverState:
        """Consume ``y_k``, ``u_k`` and return the box of ``x_{k+1}`` given ``y_0 … y_k``.

        The state keeps the last ``horizon`` samples only, so a step costs the same at every ``k``.

        Parameters
        ----------
        state : ObserverState
            State at ``t_k`` (from :meth:`init` or a previous step).
        y : array_like, shape (p,)
            Measurement at ``t_k`` (one run: LPs do not batch).
        u : array_like, shape (m,), optional
            Known input over ``[t_k, t_{k+1})``.

        Returns
        -------
        ObserverState
            ``internal["delta_box"]`` is the identified box of ``ΔA - ΔA_c`` (``ΔA_c`` the box centre).
        """
        return super().step(state, y, u)

    def _step(self, state: ObserverState, y: FloatArray, u: FloatArray) -> ObserverState:
        if y.ndim != 1:
            raise DimensionError(f"y: expected one sample of shape ({self.p},) (LPs do not batch), got {y.shape}")
        old = state.internal
        k, start = int(old["k"]), int(old["start"])
        self.delta_box = old["delta_box"]
        ys, us = np.concatenate([old["y"], y[None]]), np.concatenate([old["u"], u[None]])
        lo, hi = self._predict(old["box_lo"][-1], old["box_hi"][-1], u)
        low, high = self._box(k + 1, start, ys, us, old["box_lo"], old["box_hi"], (lo, hi))
        lo, hi = inflate(np.maximum(lo, low), np.minimum(hi, high))
        self._paths.append(self._take_path().as_dict())
        inner = None
        if self.fallback is not None:  # the fallback's box is sound as it is: intersect after the inflation
            inner = self.fallback.step(old["fallback"], y, u)
            lo, hi = np.maximum(lo, inner.lower), np.minimum(hi, inner.upper)
        if np.any(lo > hi):
            raise InconsistentDataError(
                f"y: the measurements are inconsistent with the model and its bounds at step {k + 1}"
            )
        drop = max(k + 2 - self.horizon, 0) - start  # the next window starts at max(k + 2 - H, 0)
        internal = {
            "k": k + 1,
            "start": start + drop,
            "y": ys[drop:],
            "u": us[drop:],
            "box_lo": np.concatenate([old["box_lo"], lo[None]])[drop:],
            "box_hi": np.concatenate([old["box_hi"], hi[None]])[drop:],
            "fallback": inner,
            "delta_box": self.delta_box,
        }
        return ObserverState(lo, hi, internal=internal)

    def _take_path(self) -> SolverPath:
        """The routes of the LP solves since the last call (a fresh count starts)."""
        path = self._lp.take_path()
        if self._envelope is not None:
            path.add(self._envelope.take_path())
        return path

    def extremal_deltas(self, steps: int) -> FloatArray:
        """The ``ΔA`` of the LP optimum of each bound of the last run: candidates for a lower bound.

        Parameters
        ----------
        steps : int
            Length of the record.

        Returns
        -------
        numpy.ndarray, shape (steps, 2n, n, n)
            Row ``k``, ``r``: the ``ΔA`` at which the window LP attained the bound ``r`` of ``x_k``
            (``r < n``: lower bound of component ``r``, else upper bound of ``r - n``); NaN where none.
        """
        out = np.full((steps, 2 * self.n, self.n, self.n), np.nan)
        for k, found in self._extremal.items():
            if k < steps:
                ok = np.all(np.isfinite(found), axis=1)
                full = np.broadcast_to(self.model.center, (2 * self.n, self.n, self.n)).copy()
                full[:, self._rows, self._cols] += found
                out[k, ok] = full[ok]
        assert self.system.dA is not None
        return np.clip(out, self.system.dA[0], self.system.dA[1])  # the solver's point is accurate to 1e-9

    def meta(self) -> dict[str, Any]:
        """Facts recorded in every :class:`~intervalobs.estimate.Estimate`.

        Returns
        -------
        dict
        """
        return {
            "method": "RobustHullEstimator",
            "horizon": self.horizon,
            "identify": self.identify,
            "mccormick": self.mccormick,
            "solver": self.solver,
            "solver_path": [dict(path) for path in self._paths],
            "h": self.h,
            "uncertain_entries": len(self.model.entries),
            "delta_box": [(self.model.center + b).tolist() for b in self.delta_box],
            "fallback": None if self.fallback is None else type(self.fallback).__name__,
            "transient_s": 0.0,
            "certificate": "weak duality (Neumaier-Shcherbina), rounding subtracted",
        }
