r"""The exact interval hull of the consistent set: the tightest box any sound estimator can report.

For a linear model with box-bounded unknowns, the states :math:`x_k` consistent with the model, the
prior box of :math:`x_0`, the noise boxes and the measurements form a polytope :math:`S_k`; its interval
hull :math:`\square S_k` is the smallest box that contains every admissible state, so every sound
estimator's box contains it (the integrated-observer paper, Section 3: the zonotopic and interval observers are outer
approximations of :math:`S_k`). Each bound of :math:`\square S_k` is a linear programme:

.. math::

    \min / \max \; e_i^\top x_k \quad \text{s.t.} \quad
    x_{j+1} - \Phi x_j - \Gamma u_j \in \mathcal W,\qquad y_j - C x_j \in \mathcal V,\qquad
    x_{k-H} \in [\underline{x}_{k-H}, \overline{x}_{k-H}],

over a window of :math:`H` steps (:math:`\mathcal W`, :math:`\mathcal V`: the noise sets — a box, or
:math:`E\,[\underline w, \overline w]` with noise variables when one noise channel drives several
states). With :math:`H \ge k` (full history) the prior is the box of :math:`x_0` and the hull is exact;
with a shorter window the prior is the estimator's own box :math:`H` steps back (sound by induction),
and every state of the window is also bounded by its earlier box (redundant for the full history,
so exactness is kept, and a useful tightening otherwise).

**Soundness of an LP bound.** A simplex optimum is only accurate to the solver's tolerances, which
is not a guarantee: every bound is taken from weak duality with the solver's duals as multipliers and
the rounding of its own evaluation subtracted (:mod:`intervalobs.lp.certified`), so it is valid
whatever their accuracy. The box is finally intersected with the interval propagation of the previous
box (sound without any LP) and inflated by ``ROUNDING_MARGIN`` like every observer's output.

**Continuous time** uses the sound sampled model of :mod:`intervalobs.systems.sampling`: the hull
is exact for that model (whose per-step noise set is a box around the true, non-box set), so it is
sound for the continuous system and slightly wider than its true hull.
:func:`~intervalobs.tightness.hull_lower_bound` gives the matching inner value.

**Interval** :math:`\Delta B` (an uncertain input matrix, ``dB``), constant in time (``constant_dB``, the
default): with :math:`\Delta B = \Delta B_c + \beta`, the sampled model's :math:`\Gamma` holds
:math:`\Delta B_c` and step :math:`j` adds :math:`\Psi\beta u_j`, :math:`\Psi = \int_0^h e^{As}ds` (the
identity in discrete time; :mod:`intervalobs.systems.sampling`, section 7). With :math:`u` known this is linear
in the entries of :math:`\beta`, which are LP unknowns in their box shared by all steps of the window (the
true :math:`\Delta B` is constant over the record, hence over the window); their coefficients move with
:math:`u` and are set at every step in both window LPs (:class:`~intervalobs.lp.window.SharedDeltaB`). The
hull of the window is then exact for a constant :math:`\Delta B` (the process noise is taken as a box of the
states, :math:`E[\underline w, \overline w]` in discrete time; in continuous time the rounding of
:math:`\Psi` widens each step's noise box by a relative 1e-12 of :math:`|\Psi||\beta||u_j|`). With
``constant_dB=False``, :math:`\Delta\Gamma u_j` is a term of step :math:`j` alone in the box
:math:`\pm\delta\Gamma|u_j|`, which widens that step's noise box: the exact hull for :math:`\Delta B` free
at every step, wider (``tests/test_uncertain_input.py`` and ``benchmarks/hull_dB_cost.py`` measure both).

**Interval** :math:`\Delta A` makes :math:`S_k` non-convex. :class:`HullEstimator` refuses it;
:func:`~intervalobs.tightness.hull_lower_bound` computes, for a few fixed samples of :math:`\Delta A`,
inner hulls of the consistent sets and reports the hull of their union: a **lower bound on the box of any
sound estimator**, never an estimate (it is not an :class:`~intervalobs.estimate.Estimate`).
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import expm

from .._docstrings import shared_docs
from ..errors import ArgumentTypeError, AssumptionError, DataError, DimensionError, InconsistentDataError
from ..estimate import Estimate
from ..interval import inflate, matvec_bounds
from ..lp.chain import RecordsPath, Solver, SolverPath, as_solver
from ..lp.condensed import CondensedWindowLP
from ..lp.window import SharedDeltaB, SparseWindow, WindowModel
from ..systems.balancing import balanced, state_scales
from ..systems.bounds import Bounds, ResolvedBounds
from ..systems.lti import LTISystem
from ..systems.sampling import SampledModel, sampled_model
from ..validation import as_positive
from .base import Observer, ObserverState, _one_blas_thread, options_after_bounds

__all__ = ["HullEstimator"]

FloatArray = NDArray[np.float64]


def _single_support(matrix: FloatArray) -> bool:
    """True when each column has at most one nonzero: then ``matrix @ box`` is itself a box."""
    return bool(np.all(np.count_nonzero(matrix, axis=0) <= 1))


def _outer_model(system: LTISystem, full: ResolvedBounds, h: float | None, constant_dB: bool) -> WindowModel:
    """The exact (discrete) or sound sampled (continuous) model of a system without ``ΔA``; with an interval
    ``ΔB`` one error shared by the window (``constant_dB``) or ``ΔΓ u_j`` widening each step's noise box (the
    noise is then a box of the states either way)."""
    model = sampled_model(system, full, h)
    d_gamma = model.dGamma if system.uncertain_input else None
    shared = _shared_dB(model, system.continuous) if d_gamma is not None and constant_dB else None
    if system.continuous or _single_support(system.E) or d_gamma is not None:
        G, w_lo, w_hi = None, model.noise_center - model.noise_radius, model.noise_center + model.noise_radius
    else:
        G, w_lo, w_hi = system.E, full.w[0], full.w[1]
    F, v_lo, v_hi = _measurement_noise(system, full)
    return WindowModel(model.Phi, model.Gamma, G, w_lo, w_hi, system.C, F, v_lo, v_hi, d_gamma, shared)


def _shared_dB(model: SampledModel, continuous: bool) -> SharedDeltaB:
    """``β = ΔB - ΔB_c`` as one unknown of the window: ``Ψ`` the midpoint of ``∫e^{As}ds`` (the identity in
    discrete time); its radius times ``|β|`` and, in continuous time, a relative rounding margin of ``|Ψ||β|``
    (the product ``Ψβu`` with a computed ``Ψ``) are left to each step's noise box."""
    psi, d_psi, radius = model.input_integral, model.d_input_integral, model.dB_radius
    assert psi is not None and d_psi is not None and radius is not None
    spread = d_psi @ radius
    scale = np.abs(psi) @ radius + spread if continuous else spread  # Ψ = I is exact in discrete time
    return SharedDeltaB(psi, radius, inflate(-spread, spread, scale=scale, floor=0.0)[1])


def inner_model(
    system: LTISystem, full: ResolvedBounds, h: float | None, delta_a: FloatArray, substeps: int = 1
) -> WindowModel:
    """A model whose consistent set lies *inside* the true one: ``A + ΔA`` fixed, noise held per sub-step.

    In continuous time a process noise held constant over each of ``substeps`` equal parts of a sampling
    interval is admissible, so the exact sampled matrices with one noise vector per sub-step give a
    subset of the true consistent set (the simulator's noise is of that form, so its truth lies in it).
    """
    a = system.A + delta_a
    if system.continuous:
        h = as_positive("h", h, "a positive sampling period for a continuous-time system")
        n, m, nw = system.n, system.m, system.nw
        aug = np.zeros((n + m + nw, n + m + nw))
        aug[:n, :n], aug[:n, n : n + m], aug[:n, n + m :] = a, system.B, system.E
        exact = expm(aug * h)
        phi, gamma = exact[:n, :n], exact[:n, n : n + m]
        part = expm(aug * (h / substeps))
        phi_part, g_part = part[:n, :n], part[:n, n + m :]
        columns, carry = [], np.eye(n)
        for _ in range(substeps):  # noise of the last sub-step first: e^{A(h - iδ)} Γ_δ E
            columns.append(carry @ g_part)
            carry = carry @ phi_part
        g = np.hstack(columns[::-1])
        w_box = (np.tile(full.w[0], substeps), np.tile(full.w[1], substeps))
    else:
        phi, gamma, g = a, system.B, system.E
        w_box = (full.w[0], full.w[1])
    if _single_support(g):
        w_lo, w_hi = matvec_bounds(g, w_box[0], w_box[1])
        G: FloatArray | None = None
    else:
        G, w_lo, w_hi = g, w_box[0], w_box[1]
    F, v_lo, v_hi = _measurement_noise(system, full)
    return WindowModel(phi, gamma, G, w_lo, w_hi, system.C, F, v_lo, v_hi)


def _measurement_noise(system: LTISystem, full: ResolvedBounds) -> tuple[FloatArray | None, FloatArray, FloatArray]:
    if _single_support(system.F):
        lo, hi = matvec_bounds(system.F, full.v[0], full.v[1])
        return None, lo, hi
    return system.F, full.v[0], full.v[1]


class HullEstimator(Observer):
    r"""The interval hull of the consistent set of an LTI system, by linear programming at each step.

    Build it with :meth:`design` (the constructor takes the same arguments).

    Parameters
    ----------
    system : LTISystem
        Discrete- or continuous-time model without ``dA`` (for interval ``ΔA`` see
        :func:`~intervalobs.tightness.hull_lower_bound`); an interval ``dB`` is one unknown of each window
        (``constant_dB``).
    bounds : Bounds
        Boxes of ``x0``, ``w``, ``v``.
    horizon : int or None
        Window length ``H`` (steps); ``None`` for the full history (exact, cost growing with time).
    h : float, optional
        Sampling period of a continuous-time system (the sound sampled model is used).
    filtered : bool
        If False (default), row ``k`` of :meth:`run` is the hull of ``x_k`` given ``y_0 … y_{k-1}``
        (:attr:`rows` ``"predicted"``), comparable with every other observer. If True it also uses
        ``y_k`` (the "filtered" hull, :attr:`rows` ``"filtered"``): :meth:`step` with ``y_k`` then
        returns the box of ``x_k`` given ``y_0 … y_k``.
    window_boxes : bool
        Also bound every state inside the window by its earlier box (not only the first one, the
        prior). Slightly tighter for short windows (0.4 % at H = 10 on the integrated-observer paper's
        three-state example, nothing at H = 40) but about 1.5× more simplex pivots; redundant for the full history.
    workers : int
        HiGHS instances solving the ``2n`` LPs of a step in parallel threads (condensed LP only; HiGHS
        releases the GIL while it solves). The bounds do not depend on it; use at most the number of
        free cores.
    processes : int
        Worker processes for the Monte Carlo runs of :meth:`run` (a leading axis of ``y``): the runs are
        split into ``processes`` contiguous chunks, each run by a fresh estimator in its own process. A run's
        boxes depend on its data only (:meth:`init` forgets the warm starts), so they do not depend on it.
    solver : {"auto", "highs"}
        ``"auto"`` (default): the condensed LP's chain by the dense simplex first, HiGHS for what it gives up on;
        ``"highs"``: every LP by HiGHS. The boxes agree to the certificates' tolerance (both are certified).
    constant_dB : bool
        With an interval ``dB``: True (default) when the input matrix is constant in time (a motor's torque
        constant): its error is then one set of unknowns shared by the steps of a window (module docstring),
        which costs more per step; False when it may change from step to step: each step's noise box is then
        widened by ``δΓ|u_j|`` (wider boxes). No effect without ``dB``.

    Notes
    -----
    Each step solves ``2n`` LPs (the model is built once per window length and only bounds and costs
    change). With a finite horizon, a stable (ρ(Φ) ≤ 1) model with box measurement noise uses the
    condensed LP at every step (states eliminated, :class:`CondensedWindowLP`; the first ``H`` steps as shorter
    windows from ``x_0``): the same set with ``H + 1`` rows, and bases restored aligned by time (on the
    integrated-observer paper's (68) with ``H = 40``, 2.4 (switching noise) and 9.8 (i.i.d. vertex noise) pivots per LP
    instead of 16 and 63 with the sparse window LP). Its ``2n`` objectives are solved as a chain by a dense simplex of
    our own (:class:`~intervalobs.lp.dense_simplex.DenseSimplex`): the first by the dual simplex from its
    basis of the previous step, each next one by the primal simplex from the optimum of the one before; HiGHS
    solves what it gives up on, and the sparse window LP. Every bound is certified by weak duality (module
    docstring), so the box is sound whatever the solver's accuracy. A Monte
    Carlo axis of ``y`` is processed run by run (LPs do not vectorise), in ``processes`` worker processes.
    The route of every step's solves (:class:`~intervalobs.lp.chain.SolverPath`: dense simplex, HiGHS from a
    basis, widened rows, from scratch, failed, pivots) is in ``meta["solver_path"]``, one entry a step.
    """

    summary_fields = ("horizon",)
    batched = False  # one LP per bound and run: a Monte Carlo axis is run after run

    h: float

    def __init__(
        self,
        system: LTISystem,
        bounds: Bounds,
        horizon: int | None = 50,
        h: float | None = None,
        filtered: bool = False,
        window_boxes: bool = False,
        workers: int = 1,
        processes: int = 1,
        solver: Solver = "auto",
        constant_dB: bool = True,
    ) -> None:
        if not isinstance(system, LTISystem):
            raise ArgumentTypeError(f"system: expected an LTISystem, got {type(system).__name__}")
        if not isinstance(bounds, Bounds):
            raise ArgumentTypeError(f"bounds: expected a Bounds, got {type(bounds).__name__}")
        if system.dA is not None:
            raise AssumptionError(
                "system.dA: the consistent set of an interval ΔA is not convex, so its hull is not an LP; "
                "use hull_lower_bound for a lower bound on the width of any sound estimator"
            )
        if horizon is not None and (int(horizon) != horizon or horizon < 1):
            raise DataError(f"horizon: expected a positive integer or None, got {horizon!r}")
        self.system, self.bounds = system, bounds.resolve(system)
        self.n, self.p, self.m = system.n, system.p, system.m
        self.horizon = None if horizon is None else int(horizon)
        self.filtered = bool(filtered)
        self.rows = "filtered" if self.filtered else "predicted"
        self.window_boxes = bool(window_boxes)
        if isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or workers < 1:
            raise DataError(f"workers: expected a positive integer, got {workers!r}")
        self.workers = int(workers)
        if isinstance(processes, bool) or not isinstance(processes, (int, np.integer)) or processes < 1:
            raise DataError(f"processes: expected a positive integer, got {processes!r}")
        self.processes = int(processes)
        self.solver = as_solver(solver)
        self.constant_dB = bool(constant_dB)
        self._given = (system, bounds, horizon, h, filtered, window_boxes, workers, 1, self.solver, self.constant_dB)
        # States in very different units: the LPs are solved in balanced coordinates x_b = S x (exact: S is
        # a diagonal of powers of two, systems/balancing.py); every box crosses between the two in _step.
        scales = state_scales(system, self.bounds)
        self.scales = np.ones(self.n) if scales is None else scales
        """``s`` of the balanced coordinates ``x_b = diag(s) x`` the LPs are solved in (ones: none)."""
        solved = (system, self.bounds) if scales is None else balanced(system, self.bounds, scales)
        self.model = _outer_model(*solved, h, self.constant_dB)
        self.h = float(h) if system.continuous and h is not None else float(system.dt or 1.0)
        self._windows: dict[int, SparseWindow] = {}
        self._condensed: CondensedWindowLP | None = None
        if self.condensed_allowed():
            assert self.horizon is not None
            self._condensed = CondensedWindowLP(self.model, self.horizon, self.workers, self.solver)
        self._paths: list[dict[str, int]] = []
        """The route of every step's LP solves since :meth:`init` (``meta["solver_path"]``)."""

    @classmethod
    @options_after_bounds("h")
    def design(
        cls,
        system: LTISystem,
        bounds: Bounds,
        *,
        h: float | None = None,
        horizon: int | None = 50,
        filtered: bool = False,
        window_boxes: bool = False,
        workers: int = 1,
        processes: int = 1,
        solver: Solver = "auto",
        constant_dB: bool = True,
    ) -> HullEstimator:
        """Build the estimator (there is no gain: the window LP of each step is the estimator).

        Parameters
        ----------
        system : LTISystem
            Discrete- or continuous-time model without ``dA``.
        bounds : Bounds
            Boxes of ``x0``, ``w``, ``v``.
        h : float, optional
            Sampling period of a continuous-time system.
        horizon : int or None
            Window length ``H`` in steps; ``None`` for the full history.
        filtered : bool
            Rows of :meth:`run` use ``y_k`` too (class docstring).
        window_boxes : bool
            Bound every state of the window by its earlier box.
        workers : int
            HiGHS instances solving a step's LPs in parallel threads.
        processes : int
            Worker processes for the Monte Carlo runs of :meth:`run`.
        solver : {"auto", "highs"}
            ``"highs"``: every LP by HiGHS, the dense simplex bypassed (class docstring).
        constant_dB : bool
            With an interval ``dB``: one input-matrix error shared by each window (True) or free at every
            step (class docstring).

        Returns
        -------
        HullEstimator

        Raises
        ------
        AssumptionError
            If the system has an interval ``dA`` (the consistent set is not convex).
        """
        return cls(
            system,
            bounds,
            horizon=horizon,
            h=h,
            filtered=filtered,
            window_boxes=window_boxes,
            workers=workers,
            processes=processes,
            solver=solver,
            constant_dB=constant_dB,
        )

    def condensed_allowed(self) -> bool:
        """Whether the condensed LP is used (box measurement noise, finite horizon, prior-only boxes, stable Φ).

        Returns
        -------
        bool
        """
        return (
            self.horizon is not None
            and self.model.F is None
            and not self.window_boxes
            and bool(np.max(np.abs(np.linalg.eigvals(self.model.Phi))) <= 1.0)
        )

    def _window(self, k: int) -> SparseWindow:
        if self.horizon is not None:
            size = self.horizon
        else:  # full history: capacity doubles, so rebuilds are rare
            size = max(16, 1 << int(np.ceil(np.log2(max(k, 1)))))
        if size not in self._windows:
            self._windows = {size: SparseWindow(self.model, size)}
        return self._windows[size]

    # -- protocol ------------------------------------------------------------------------------
    @shared_docs
    def init(self, x0_lower: ArrayLike | None = None, x0_upper: ArrayLike | None = None) -> ObserverState:
        """State at the first sample: the prior box of ``x_0`` and an empty record.

        Also drops the LP bases kept for warm starts, so that a record started here gives the same
        boxes whatever the estimator solved before.

        %(prior_box)s
            ``internal`` holds the step ``k``, the prior box ``x0`` and the record a window needs:
            ``y``, ``u`` and the boxes ``box_lo``/``box_hi`` of the last ``horizon`` samples (all of
            them for the full history), row ``i`` at time ``start + i``.
        """
        lo, hi = self._prior_box(self.bounds.x0, x0_lower, x0_upper)
        for window in self._windows.values():  # a record's boxes depend on its data only, not on earlier ones
            window.lp.forget_bases()
        if self._condensed is not None:
            self._condensed.forget_bases()
        self._take_path()
        self._paths = []
        internal: dict[str, Any] = {
            "k": 0,
            "x0": (lo * self.scales, hi * self.scales),
            "start": 0,
            "y": np.zeros((0, self.p)),
            "u": np.zeros((0, self.m)),
            "box_lo": np.zeros((0, self.n)),
            "box_hi": np.zeros((0, self.n)),
        }
        return ObserverState(lo.copy(), hi.copy(), internal=internal)

    @_one_blas_thread
    def step(self, state: ObserverState, y: ArrayLike, u: ArrayLike | None = None) -> ObserverState:
        """Consume ``y_k``, ``u_k``: the hull of ``x_{k+1}`` given ``y_0 … y_k`` (of ``x_k`` when ``filtered``).

        With a finite horizon the state keeps the last ``horizon`` samples only, so a step costs the
        same time and memory at every ``k``; the given state is not modified. Like :meth:`run`, a step runs
        on one BLAS thread: on the 30-tank cascade OpenBLAS's default threads took more CPU time for the same
        boxes, spinning between the small products of the certificates.

        Parameters
        ----------
        state : ObserverState
            From :meth:`init` or a previous step.
        y : array_like, shape (p,)
            Measurement at ``t_k`` (one run: LPs do not batch).
        u : array_like, shape (m,), optional
            Known input at ``t_k``; required when the system has inputs (m > 0).

        Returns
        -------
        ObserverState
        """
        return super().step(state, y, u)

    def _step(self, state: ObserverState, y: FloatArray, u: FloatArray) -> ObserverState:
        if y.ndim != 1:
            raise DimensionError(f"y: expected one sample of shape ({self.p},) (LPs do not batch), got {y.shape}")
        old = state.internal
        k, start, x0 = int(old["k"]), int(old["start"]), old["x0"]
        lo, hi = state.lower * self.scales, state.upper * self.scales  # internal boxes: balanced coordinates
        if self.filtered and k > 0:  # state: the filtered box of x_{k-1}; x_k's box from y_0 … y_{k-1}
            lo, hi = self.model.propagate(lo, hi, old["u"][-1])
            if self._certifying():
                lo, hi = self._hull(k, start, old["y"], old["u"], old["box_lo"], old["box_hi"], lo, hi, False, x0)
        ys, us = np.concatenate([old["y"], y[None]]), np.concatenate([old["u"], u[None]])
        if self.filtered:
            lo, hi = self._hull(k, start, ys, us, old["box_lo"], old["box_hi"], lo, hi, True, x0)
        box_lo, box_hi = np.concatenate([old["box_lo"], lo[None]]), np.concatenate([old["box_hi"], hi[None]])
        if not self.filtered:
            nlo, nhi = self.model.propagate(lo, hi, u)
            lo, hi = self._hull(k + 1, start, ys, us, box_lo, box_hi, nlo, nhi, False, x0)
        self._paths.append(self._take_path().as_dict())
        drop = 0 if self.horizon is None else max(ys.shape[0] - self.horizon, 0)
        internal: dict[str, Any] = {
            "k": k + 1,
            "x0": x0,
            "start": start + drop,
            "y": ys[drop:],
            "u": us[drop:],
            "box_lo": box_lo[drop:],
            "box_hi": box_hi[drop:],
        }
        return ObserverState(lo / self.scales, hi / self.scales, internal=internal)

    def _certifying(self) -> bool:
        """Whether :meth:`certificates` logs the solves: only then do filtered rows solve the predicted window too.

        The filtered window is the predicted one plus the rows of ``y_k``, so its consistent set lies inside
        the predicted one's and the predicted hull of ``x_k`` adds nothing to the filtered box beyond the
        certificates' tolerance: a filtered step solves ``2n`` LPs, like a predicted one. The predicted solves
        stay for :meth:`certificates`, whose filters with a zero weight on ``y_k`` come from them.
        """
        return self._condensed is not None and self._condensed.dual_log is not None

    def _take_path(self) -> SolverPath:
        """The routes of the LP solves since the last call (a fresh count starts)."""
        path = SolverPath()
        lps: list[RecordsPath] = [window.lp for window in self._windows.values()]
        for lp in [*lps, *([self._condensed] if self._condensed is not None else [])]:
            path.add(lp.take_path())
        return path

    def _hull(
        self,
        k: int,
        start: int,
        ys: FloatArray,
        us: FloatArray,
        box_lo: FloatArray,
        box_hi: FloatArray,
        last_lo: FloatArray,
        last_hi: FloatArray,
        use_current: bool,
        x0: tuple[FloatArray, FloatArray],
    ) -> tuple[FloatArray, FloatArray]:
        """Certified hull of ``x_k``.

        Row ``i`` of ``ys``, ``us``, ``box_*`` is time ``start + i`` (``box_*`` bound ``x_τ`` for
        ``τ < k``); ``last_*`` bound ``x_k``.
        """
        if k == 0:
            last_lo, last_hi = np.maximum(last_lo, x0[0]), np.minimum(last_hi, x0[1])
            if not use_current:
                return last_lo, last_hi
        if self._condensed is not None:
            assert self.horizon is not None
            s = max(k - self.horizon, 0)
            prior = (box_lo[s - start], box_hi[s - start]) if s < k else (last_lo, last_hi)
            lp = self._condensed
            drive, pad = lp.set_window(k, ys[s - start :], us[s - start :], prior[0], prior[1], use_current)
            low, high = lp.certified_bounds(int(use_current))
            lower, upper = np.maximum(last_lo, low + drive - pad), np.minimum(last_hi, -high + drive + pad)
            return self._consistent(k, lower, upper)
        window = self._window(k)
        sparse_lp = window.lp
        bounds = window.bounds_at(
            k, ys, us, box_lo, box_hi, last_lo, last_hi, use_current, x0[0], x0[1], self.window_boxes, start
        )
        sparse_lp.set_bounds(*bounds)
        lower = last_lo.copy()
        upper = last_hi.copy()
        key = 2 * self.n if use_current else 0
        for i in range(self.n):
            col = sparse_lp.newest_column(i)
            lower[i] = max(lower[i], sparse_lp.certified_min(col, 1.0, key + i))
            upper[i] = min(upper[i], -sparse_lp.certified_min(col, -1.0, key + i))
        return self._consistent(k, lower, upper)

    def _separate_runs(self, times: FloatArray, ys: FloatArray, us: FloatArray) -> list[Estimate]:
        """The Monte Carlo runs, in ``processes`` worker processes when there are several."""
        count = ys.shape[0]
        if self.processes == 1 or count == 1:
            return super()._separate_runs(times, ys, us)
        chunks = np.array_split(np.arange(count), min(self.processes, count))
        # fork where the platform has it: a spawned worker would import the package first (about a second).
        method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
        tasks = [(self._given, times, ys[chunk], us[chunk]) for chunk in chunks]
        with ProcessPoolExecutor(len(chunks), mp_context=multiprocessing.get_context(method)) as pool:
            return [estimate for part in pool.map(_hull_runs, tasks) for estimate in part]

    @staticmethod
    def _consistent(k: int, lower: FloatArray, upper: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Inflate the box, and refuse an empty one (the data contradict the bounds)."""
        lower, upper = inflate(lower, upper)
        if np.any(lower > upper):
            raise InconsistentDataError(
                f"y: the measurements are inconsistent with the model and its bounds at step {k} "
                "(empty consistent set): check the noise bounds"
            )
        return lower, upper

    @_one_blas_thread
    @shared_docs
    def certificates(
        self,
        t: ArrayLike,
        y: ArrayLike,
        u: ArrayLike | None = None,
        first_rows: bool = False,
        reuse: Callable[[Any, FloatArray], FloatArray] | None = None,
    ) -> dict[tuple[int, float] | tuple[int, float, int], FloatArray]:
        r"""The duality certificates of the window LPs of a record: one FIR weight set per bound.

        For the bound ``sign * (x_k)_i`` the multipliers :math:`\lambda_j` of the window's measurement
        rows ``j = 0 … H`` give the linear combination :math:`\sum_j \text{sign}\,\lambda_j^\top y_{k-H+j}`
        that the certified bound uses (module docstring); any such weights give a sound bound on any
        record (:class:`~intervalobs.observers.fir.FiniteMemoryObserver` evaluates them rigorously).

        Parameters
        ----------
        %(record)s
        first_rows : bool
            Also return the certificates of the first rows' windows (``k ≤ H``: the ``L = k`` steps from
            the prior of ``x_0``; row ``j`` is the weight of ``y_j``).
        reuse : callable, optional
            Called before the solves of every window with the window LP (its ``row_lo``, ``row_hi``, ``col_lo``,
            ``col_hi``, ``length``, ``full`` and ``dual_log`` set) and the ``2n`` costs (rows ``2i``: lower bound of
            component ``i``, ``2i + 1``: upper); returns multipliers ``(2n, rows)`` to bound those objectives with
            instead of solving them (any multipliers give a sound bound), a NaN row for each objective to solve.
            Only solved objectives give certificates (:meth:`FiniteMemoryObserver.learn
            <intervalobs.observers.fir.FiniteMemoryObserver.learn>` skips bounds its bank already attains).

        Returns
        -------
        dict
            ``(i, sign)`` → array of shape ``(count, H + 1, p)``: the row multipliers of every solve of
            the condensed window LP (steps ``k > H``) for that bound; with ``filtered`` both the
            predicted and the filtered solves (row ``H``, the weight of :math:`y_k`, is zero in the first).
            With ``first_rows``, also ``(i, sign, L)`` → ``(count, H + 1, p)`` for the windows of ``L`` steps
            anchored at ``x_0`` (rows of measurements outside the window are zero).
        """
        if self._condensed is None:
            raise AssumptionError(
                "certificates: needs the condensed window LP (finite horizon, box measurement noise, stable Φ, "
                "window_boxes=False); see condensed_allowed()"
            )
        if self.model.shared_dB is not None:
            raise AssumptionError(
                "certificates: with one constant ΔB for each window (constant_dB=True) a bound also rests on the "
                "shared ΔB, so its multipliers are not a filter of the measurements alone; use constant_dB=False"
            )
        times, ys, us = self._signals(t, y, u)
        if ys.ndim != 2:
            raise DimensionError(f"y: expected one record of shape (T, {self.p}), got shape {ys.shape}")
        lp = self._condensed
        lp.dual_log, lp.reuse = [], reuse
        try:
            self._loop(times, ys, us)
            log = lp.dual_log
        finally:
            lp.dual_log, lp.reuse = None, None
        shape = (lp.horizon + 1, self.p)
        found: dict[tuple[int, float] | tuple[int, float, int], list[FloatArray]] = {
            (i, sign): [] for i in range(self.n) for sign in (1.0, -1.0)
        }
        for i, sign, balanced_duals, length, anchored in log:
            duals = balanced_duals / self.scales[i]  # multipliers of (x_b)_i = s_i (x)_i
            if anchored and first_rows:
                found.setdefault((i, sign, length), []).append(duals.reshape(shape))
            elif not anchored:
                found[(i, sign)].append(duals.reshape(shape))
        return {key: np.array(rows).reshape(len(rows), *shape) for key, rows in found.items()}

    def meta(self) -> dict[str, Any]:
        """Facts recorded in every :class:`~intervalobs.estimate.Estimate`.

        Returns
        -------
        dict
        """
        return {
            "method": "HullEstimator",
            "condensed": self._condensed is not None,
            "horizon": "full" if self.horizon is None else self.horizon,
            "filtered": self.filtered,
            "window_boxes": self.window_boxes,
            "workers": self.workers,
            "solver": self.solver,
            "constant_dB": self.constant_dB,
            "solver_path": [dict(path) for path in self._paths],
            "h": self.h,
            "transient_s": 0.0,
            "certificate": "weak duality (Neumaier-Shcherbina), rounding subtracted",
        }


def _hull_runs(task: tuple[tuple[Any, ...], FloatArray, FloatArray, FloatArray]) -> list[Estimate]:
    """Worker of :meth:`HullEstimator.run` with ``processes``: a chunk of runs on a fresh estimator."""
    given, times, ys, us = task
    return HullEstimator(*given)._separate_runs(times, ys, us)
