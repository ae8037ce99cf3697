r"""Finite-memory (FIR) estimators: linear filters chosen by LP at design time, evaluated soundly online.

For a point model :math:`x_{k+1} = \Phi x_k + \Gamma u_k + G\,\eta_k`, :math:`\eta_k` in a box of
centre :math:`c` and radius :math:`r` (discrete time: :math:`G = E` and the box of :math:`w`, so noise
channels that drive several states keep their structure; continuous time: :math:`G = I` and the box
of the sound sampled model of :mod:`intervalobs.systems.sampling`), and
:math:`y_k = C x_k + F v_k`, write :math:`s = k - N`. Then :math:`x_k` and the window's
measurements :math:`y_{s+j}`, :math:`j = 0 \dots N-1`, are affine in :math:`x_s`, the noises and the
known inputs. The estimate of every component is a fixed linear combination of the :math:`N` last
measurements plus a known input term,

.. math:: \hat x_k = \sum_{j<N} K_j y_{s+j} + \sum_{l<N} M_l u_{s+l} + d,

with error :math:`x_k - \hat x_k = R x_s + \sum_l D_l G \tilde\eta_{s+l} - \sum_j K_j F \tilde v_{s+j}`
(tildes: deviations from the box centres),
:math:`D_l = \Phi^{N-1-l} - \sum_{j>l} K_j C \Phi^{j-1-l}`, :math:`R = \Phi^N - \sum_j K_j C\Phi^j`.
*Any* weights give a sound box, :math:`\hat x_k + R\,[\underline x_s, \overline x_s] \pm \text{radius}`,
with a sound box of :math:`x_s`; the observer holds a **bank** of weight sets per component and
intersects their boxes. With ``filtered=True`` the weights also multiply :math:`y_k` (``W = N + 1``
weights instead of ``W = N``; :math:`j` runs to :math:`N`). Two ways to fill it:

- :meth:`FiniteMemoryObserver.design`: one set per component, by an LP minimising the worst-case error
  ``sum |D G| r + sum |K F| r_v`` (per noise channel) subject to :math:`R = 0` (unbiased in the unknown :math:`x_s`). By
  Smolyak's theorem a linear algorithm attains the radius of information of the window, so for large
  ``N`` the radius approaches the half-width of the exact hull's *worst case*. Its width does not
  depend on the data, so it can never beat the largest hull width (docs/tightness.md).
- :meth:`FiniteMemoryObserver.learn`: that set plus the duality certificates of the exact window hull
  (:meth:`~intervalobs.observers.hull.HullEstimator.certificates`) on simulated extreme-noise records.
  The hull's bound for a record *is* the FIR box of its certificate (weak duality, the prior being
  the box of :math:`x_s`), so the bank reproduces the LP wherever its optimal certificate is in the
  bank, and is sound everywhere else: the width follows the data without any LP online.

**Soundness.** The LP optimum is never used as a bound. The radius is *evaluated* in NumPy from the
weights and rounded upward; the residual :math:`R` (about 1e-10 for the worst-case filter, not
exactly zero; large for certificates) is bounded with the observer's own box of :math:`x_s` (sound by
induction). :math:`D_l`, :math:`R`, :math:`M_l` and :math:`d` are themselves computed in floating
point (powers of :math:`\Phi` by repeated products, then sums over the window): their error is at
most :math:`\gamma_D` times the same expressions with every matrix replaced by its absolute value,
:math:`\gamma_D = 4(N + 1)(n + p + n_G + 2)\,\varepsilon` (first-order bound of ``N n + n + W p + n_G`` roundings
per entry, with a factor 4 to spare), and that error times the magnitudes of the noise box, the
input and the prior box is added to the radius. The rounding of the online sums is bounded by
:math:`\gamma\,(\sum|K_j||y| + \sum|M_l||u| + |d|)` with :math:`\gamma = (2W + 8)\,\varepsilon`
(``W`` weights); the result is intersected with a sound fallback observer
(default: the tube :class:`IntervalObserver`), and with
the one-step interval prediction of the previous own box (:math:`\Phi` box, plus the input and the
noise box, inflated). An intersection of sound boxes is sound.

**The first rows** (``k < N``) have no full window. They use filters of their own on the growing
window :math:`y_0 \dots y_{k-1}` (``… y_k`` when filtered), with :math:`s = 0` in the equations above
(``L = k`` steps instead of ``N``): the box of :math:`x_0` bounds :math:`R x_0`, and the same rounding
argument holds with ``N`` replaced by ``L``. :meth:`FiniteMemoryObserver.learn` fills them with the
certificates of the window hull's first steps, whose windows start at the prior of :math:`x_0`.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from numpy.typing import ArrayLike, NDArray

from .._docstrings import shared_docs
from ..design.fir_bank import _Coverage, _noise_channels, _worst_case_gains
from ..errors import AssumptionError, DataError
from ..estimate import Estimate
from ..interval import ROUNDING_MARGIN, inflate, matvec_bounds
from ..simulate import noise_signal, simulate
from ..systems.bounds import Bounds, ResolvedBounds
from ..systems.lti import LTISystem, refuse_uncertain_input
from ..systems.sampling import sampled_model
from ..validation import as_box, as_choice
from .base import Observer, ObserverState, options_after_bounds
from .hull import HullEstimator
from .interval_observer import IntervalObserver

__all__ = ["FiniteMemoryObserver"]

FloatArray = NDArray[np.float64]
_EPS = float(np.finfo(float).eps)


class FiniteMemoryObserver(Observer):
    r"""A bank of linear FIR estimators of window ``N``, intersected with each other and a sound fallback.

    Row ``k`` of :meth:`run` is the box of :math:`x_k` given :math:`y_{k-N} \dots y_{k-1}` (and
    :math:`y_k` when ``filtered``), the observer's own box of :math:`x_{k-N}`, the prediction of its
    previous box and the fallback's box; see the module docstring for the equations. Build it with
    :meth:`design` (one worst-case-optimal filter per component) or :meth:`learn` (plus the hull's
    certificates: data-dependent width).

    Parameters
    ----------
    system : LTISystem
        Point model (no ``dA``); continuous time needs ``h``.
    bounds : Bounds
        Initial-state and noise boxes.
    gains : numpy.ndarray, shape (n, B, N, p) or (n, N, p); ``N + 1`` instead of ``N`` when filtered
        Weights ``K_j`` of ``B`` filters per component (row ``i``: component ``i``), oldest
        measurement first; a 3-D array is a bank of one.
    fallback : Observer
        Sound observer run in parallel; its box is intersected with the filters'.
    h : float, optional
        Sampling period of a continuous-time system.
    lp_seconds : float
        Design-time LP cost (recorded in :meth:`meta`).
    filtered : bool
        Whether the last weight multiplies :math:`y_k` (rows of :meth:`run` are then filtered boxes,
        like :class:`~intervalobs.observers.hull.HullEstimator` with ``filtered=True``).
    first : sequence of array_like
        Banks of the first rows, before a full window exists (growing windows from the prior): entry ``j``,
        shape (n, B_j, j + 1, p), weighs ``y_0 … y_j`` for row ``j + 1`` (row ``j`` when filtered), with the
        box of :math:`x_0` in place of that of :math:`x_s`; at most ``N - 1`` entries (``N`` when filtered).
        Rows without one come from the fallback and the prediction.
    """

    summary_fields = ("window", "filtered")
    covers_dA = False
    """Whether the filters' radii cover an interval ``ΔA`` (:class:`~intervalobs.observers.robust_fir.
    RobustFiniteMemoryObserver`); a point model is required otherwise."""

    h: float

    def __init__(
        self,
        system: LTISystem,
        bounds: Bounds,
        gains: ArrayLike,
        fallback: Observer,
        h: float | None = None,
        lp_seconds: float = 0.0,
        filtered: bool = False,
        first: Sequence[ArrayLike] = (),
    ) -> None:
        if not self.covers_dA:  # the ΔA bank bounds ΔB with ΔA (delta_linearisation's R_u)
            refuse_uncertain_input(system, type(self).__name__)
        if system.dA is not None and not self.covers_dA:
            raise AssumptionError("FiniteMemoryObserver: point models only (system.dA must be None)")
        self.system = system
        self.bounds = bounds.resolve(system)
        self.n, self.p, self.m = system.n, system.p, system.m
        model = sampled_model(system, self.bounds, h)
        self.h = model.h if system.continuous else float(system.dt or 1.0)
        k = np.asarray(gains, dtype=float)
        if k.ndim == 3:
            k = k[:, None]
        if k.ndim != 4 or k.shape[0] != self.n or k.shape[3] != self.p or min(k.shape[1:3]) < 1:
            raise DataError(f"gains: expected shape (n={self.n}, B, N, p={self.p}), got {np.shape(gains)}")
        if not np.all(np.isfinite(k)):
            raise DataError("gains: expected finite values")
        self.filtered = bool(filtered)
        self.rows = "filtered" if self.filtered else "predicted"
        self.window = int(k.shape[2]) - self.filtered
        if self.window < 1:
            raise DataError(f"gains: a filtered bank needs at least 2 weights (N + 1), got {k.shape[2]}")
        self.K = k
        self.fallback = fallback
        self.lp_seconds = float(lp_seconds)
        self.training: dict[str, float] = {}
        """Training of :meth:`learn` with a ``tolerance`` or ``selection="cover"``: ``solved`` and ``reused`` LPs
        (bounded by a stored certificate instead), and ``gap``: the full windows' shortfall of the stored
        certificates on the windows they had not seen (median over the bounds of their mean over the last 10 solves,
        relative to the component's width): what more training could still gain."""
        noise = _noise_channels(system, self.bounds, model)
        output = (system.C, system.F, self.bounds.centre("v"), self.bounds.radius("v"))
        self._bank = _FilterBank(k, self.window, model.Phi, model.Gamma, noise, output)
        self.residual, self.radius, self.M, self.offset = (
            self._bank.residual,
            self._bank.radius,
            self._bank.M,
            self._bank.offset,
        )
        self._model = model
        if len(first) > self.window - 1 + self.filtered or (first and self.covers_dA):
            raise DataError(
                f"first: expected at most {self.window - 1 + self.filtered} banks of the first rows"
                f"{' (none under ΔA)' if self.covers_dA else ''}, got {len(first)}"
            )
        self._first = []
        for j, entry in enumerate(first):  # entry j: row j + 1 - filtered, j + 1 weights on y_0 … y_j
            gains_j = np.asarray(entry, dtype=float)
            if gains_j.ndim != 4 or gains_j.shape[::2] != (self.n, j + 1) or gains_j.shape[3] != self.p:
                raise DataError(
                    f"first[{j}]: expected shape (n={self.n}, B, {j + 1}, p={self.p}), got {np.shape(entry)}"
                )
            if gains_j.shape[1] < 1 or not np.all(np.isfinite(gains_j)):
                raise DataError(f"first[{j}]: expected at least one filter per component, finite values")
            self._first.append(_FilterBank(gains_j, j + 1 - self.filtered, model.Phi, model.Gamma, noise, output))

    # -- design ----------------------------------------------------------------------------------
    @classmethod
    @options_after_bounds("window", "h", "fallback")
    def design(
        cls,
        system: LTISystem,
        bounds: Bounds,
        *,
        window: int = 40,
        h: float | None = None,
        fallback: Observer | None = None,
    ) -> FiniteMemoryObserver:
        """One filter per component by LP (minimise the evaluated worst-case error, unbiased in ``x_s``).

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
        full = bounds.resolve(system)
        gains, elapsed = _worst_case_gains(system, full, window, h)
        if fallback is None:
            fallback = IntervalObserver.design(system, full, h=h)
        return cls(system, full, gains, fallback, h=h, lp_seconds=elapsed)

    @classmethod
    def learn(
        cls,
        system: LTISystem,
        bounds: Bounds,
        window: int = 10,
        records: int = 6,
        steps: int = 200,
        seed: int = 0,
        size: int | None = None,
        h: float | None = None,
        fallback: Observer | None = None,
        filtered: bool = False,
        first_records: int | None = None,
        tolerance: float | None = None,
        selection: str = "random",
    ) -> FiniteMemoryObserver:
        """A bank: the worst-case filter plus the exact window hull's certificates on simulated records.

        Each training record is simulated with extreme noise (alternately i.i.d. vertices and the
        simulator's switching bang-bang noise, which make the consistent set's faces active); the
        window hull of every step is solved by :class:`~intervalobs.observers.hull.HullEstimator`
        and its duality certificate becomes a filter of the bank. Every filter is sound on every
        record; the bank is as tight as the LP on records whose optimal certificates it holds.
        The first ``N - 1`` rows (``N`` when filtered) get banks of their own: the certificates of the
        hull's growing windows from the prior of :math:`x_0` (rows ``k ≤ N``), and the zero filter (the
        prior's open-loop image), so a short record is tight from its start.

        Parameters
        ----------
        system : LTISystem
            Point model (no ``dA``) with a stable sampled matrix (the condensed window LP).
        bounds : Bounds
            Initial-state and noise boxes.
        window : int
            Memory ``N`` of the filters and horizon of the training hulls.
        records : int
            Number of simulated training records.
        steps : int
            Length of each training record (at least ``window + 2``).
        seed : int
            Seed of the training noise (the bank is deterministic given it).
        size : int, optional
            Keep at most this many filters per component (the worst-case one and ``size - 1`` certificates chosen
            as ``selection`` says): online cost against tightness (docs/tightness.md). Default: all.
        h : float, optional
            Sampling period of a continuous-time system.
        fallback : Observer, optional
            Sound observer to intersect with; default :meth:`IntervalObserver.design`.
        filtered : bool
            Learn filters that also use :math:`y_k` (certificates of the filtered window hull; the
            worst-case filter gets a zero weight on :math:`y_k`): rows are filtered boxes.
        first_records : int, optional
            Number of further short training records (``window + 1`` samples) for the banks of the first rows
            (growing windows from the prior of :math:`x_0`); those banks also take the first rows of the
            ``records``, and 0 leaves them to those alone. Default ``records * steps // (4 * window)`` (30 with
            the other defaults): a quarter of the main training's samples, since a window from the wide prior
            costs the hull about twice a full one (30 tanks).
        tolerance : float, optional
            Solve a training window's LP only where the bank may still fall short: a bound (component, sign,
            window shape) whose stored certificates came within ``tolerance`` of the LP on average over its
            last ``COVERAGE_PATIENCE`` = 10 solves (shortfall relative to the width of the component's box) is
            solved on one window in 10 only, and bounded by its best stored certificate on the others (the
            stored certificates are ranked by their value on the window; the chosen one's bound is certified).
            Default: every LP is solved.
        selection : {"random", "cover"}
            How ``size`` picks the certificates of the full windows: a random subset, or ``"cover"``: greedily, each
            the one that adds the most to the summed lower- and upper-end bounds over the training windows (tighter
            for the same size). The first rows' banks keep a random subset.

        Returns
        -------
        FiniteMemoryObserver
            ``meta()["bank"]`` is the number of filters per component.
        """
        _check_training(window, records, steps, size, first_records, tolerance, selection)
        cover = size is not None and selection == "cover"
        coverage = None if tolerance is None and not cover else _Coverage(-np.inf if tolerance is None else tolerance)
        full = bounds.resolve(system)
        worst, elapsed = _worst_case_gains(system, full, window, h)
        if filtered:  # a predicted filter is a filtered one with no weight on y_k
            worst = np.concatenate([worst, np.zeros_like(worst[:, :1])], axis=1)
        hull = HullEstimator.design(system, full, horizon=int(window), h=h, filtered=filtered)
        if not hull.condensed_allowed():
            raise AssumptionError(
                "FiniteMemoryObserver.learn: needs the condensed window LP of HullEstimator "
                "(box measurement noise: F with one nonzero per column; stable sampled matrix)"
            )
        period = hull.h if system.continuous else float(system.dt or 1.0)
        t = np.arange(int(steps)) * period
        # A stream of its own: training records never coincide with a user's simulate(..., seed=...).
        rng = np.random.default_rng([int(seed), 0xF1B])
        last = int(filtered)
        start = time.perf_counter()
        if first_records is None:
            first_records = int(records) * int(steps) // (4 * int(window))
        bank, first = _train(
            hull, full, t, int(records), int(first_records), int(window), last, rng, int(seed), coverage
        )
        elapsed += time.perf_counter() - start
        training = {} if coverage is None else coverage.summary()
        if cover and coverage is not None and size is not None:
            gains = coverage.select(worst, size)
        else:
            gains = _assemble(bank, worst, size, rng)
        # Rows before the window is full: the certificates, and the zero filter (the prior's open-loop image).
        early = [_assemble(found, np.zeros((system.n, j + 1, system.p)), size, rng) for j, found in enumerate(first)]
        if fallback is None:
            fallback = IntervalObserver.design(system, full, h=h)
        observer = cls(system, full, gains, fallback, h=h, lp_seconds=elapsed, filtered=filtered, first=early)
        observer.training = training
        return observer

    # -- online ----------------------------------------------------------------------------------
    def _window_terms(self, ys: FloatArray, us: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Every filter's estimate and pad, shape (..., n B), from windows ``ys`` (..., W, p), ``us`` (..., N, m)."""
        return self._bank.terms(ys, us)

    def _bank_box(
        self, est: FloatArray, pad: FloatArray, rows_lo: FloatArray, rows_hi: FloatArray, us: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """Intersection of the filters' boxes, given their window terms and boxes ``rows_*`` (..., N, n) of
        ``x_s … x_{k-1}`` (the first bounds ``R x_s``) with the window's inputs ``us`` (..., N, m)."""
        return self._bank.box(est, pad, rows_lo[..., 0, :], rows_hi[..., 0, :])

    def _fir(
        self, ys: FloatArray, us: FloatArray, rows_lo: FloatArray, rows_hi: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """Box of ``x_k`` from a window ``ys`` (..., W, p), ``us`` (..., N, m) and boxes of ``x_s … x_{k-1}``."""
        return self._bank_box(*self._window_terms(ys, us), rows_lo, rows_hi, us)

    def _predict(self, lower: FloatArray, upper: FloatArray, u: FloatArray) -> tuple[FloatArray, FloatArray]:
        """One-step interval prediction of the own box (Φ box + Γu + noise box), inflated for rounding."""
        model = self._model
        lo, hi = matvec_bounds(model.Phi, lower, upper)
        drive = u @ model.Gamma.T + model.noise_center
        return inflate(lo + drive - model.noise_radius, hi + drive + model.noise_radius)

    def _measured(
        self, ys: list[FloatArray], us: list[FloatArray], rows: list[Any], lower: FloatArray, upper: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """Intersect a box with the bank's; ``rows`` holds the rows before it (``rows[0]``: ``x_{k-N}``, or ``x_0``
        while fewer than ``N``: then the bank of the first rows, if any, with ``rows[0]`` or this box as prior)."""
        count = len(rows)
        y_win = np.stack(ys[len(ys) - count - self.filtered :], axis=-2)
        lead = y_win.shape[:-2]
        u_win = np.zeros((*lead, count, self.m))
        for j, v in enumerate(us[len(us) - count :]):
            u_win[..., j, :] = v
        if count < self.window:
            if count - 1 + self.filtered >= len(self._first):
                return lower, upper
            bank = self._first[count - 1 + self.filtered]
            prior_lo, prior_hi = rows[0] if rows else (lower, upper)
            f_lo, f_hi = bank.box(*bank.terms(y_win, u_win), prior_lo, prior_hi)
            return np.maximum(lower, f_lo), np.minimum(upper, f_hi)
        rows_lo = np.stack([np.broadcast_to(lo, y_win.shape[:-2] + lo.shape[-1:]) for lo, _ in rows], axis=-2)
        rows_hi = np.stack([np.broadcast_to(hi, y_win.shape[:-2] + hi.shape[-1:]) for _, hi in rows], axis=-2)
        f_lo, f_hi = self._fir(y_win, u_win, rows_lo, rows_hi)
        return np.maximum(lower, f_lo), np.minimum(upper, f_hi)

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
        # "rows": the last N rows before the next one to compute (row 1, or row 0 when filtered).
        rows = [] if self.filtered else [(inner.lower, inner.upper)]
        internal: dict[str, Any] = {"fallback": inner, "k": 0, "ys": [], "us": [], "rows": rows}
        return ObserverState(inner.lower, inner.upper, internal=internal)

    def _step(self, state: ObserverState, y: FloatArray, u: FloatArray) -> ObserverState:
        """Consume ``y_k``, ``u_k``; return the box of ``x_{k+1}`` (fallback ∩ prediction ∩ bank).

        When ``filtered``, the bank's box of ``x_k`` given ``y_k`` (row ``k`` of the filtered form) is
        ``internal["filtered_lower"/"filtered_upper"]`` of the result, and the state's box is the prediction.
        """
        yk, uk = y, u
        old = state.internal
        keep = self.window + 1
        ys, us, rows = (old["ys"] + [yk])[-keep:], (old["us"] + [uk])[-keep:], old["rows"]
        lower, upper = state.lower, state.upper
        internal: dict[str, Any] = {}
        if self.filtered:  # row k uses y_k and the inputs up to u_{k-1}
            lower, upper = self._measured(ys, us[:-1], rows, lower, upper)
            rows = [*rows, (lower, upper)][-self.window :]
            internal.update(filtered_lower=lower, filtered_upper=upper)
        inner = self.fallback._step(old["fallback"], yk, uk)
        p_lo, p_hi = self._predict(lower, upper, uk)
        lower, upper = np.maximum(inner.lower, p_lo), np.minimum(inner.upper, p_hi)
        if not self.filtered:  # row k + 1 uses y_{k+1-N} … y_k
            lower, upper = self._measured(ys, us, rows, lower, upper)
            rows = [*rows, (lower, upper)][-self.window :]
        internal.update(fallback=inner, k=old["k"] + 1, ys=ys, us=us, rows=rows)
        return ObserverState(lower, upper, internal=internal)

    @shared_docs
    def run(self, t: ArrayLike, y: ArrayLike, u: ArrayLike | None = None) -> Estimate:
        """Bounds over a whole record, vectorised over Monte Carlo runs (and over the bank).

        Parameters
        ----------
        %(runs)s
        u : array_like, shape (T, m) or (M, T, m), optional
            Known inputs.

        Returns
        -------
        Estimate
            Row ``k`` is the box of ``x(t_k)`` given ``y_0 … y_{k-1}`` (``… y_k`` when ``filtered``).
        """
        times, ys, us = self._signals(t, y, u)
        base = self.fallback.run(times, ys, us)
        lower, upper = base.lower.copy(), base.upper.copy()
        big_n, last, steps = self.window, int(self.filtered), times.size
        # Window terms of a block of rows at a time (two matrix products), at most ~2e6 numbers each.
        block = max(1, 2_000_000 // (max(1, ys[..., 0, 0].size) * self._bank.offset_flat.size))
        head = stop = big_n
        est = pad = np.empty(0)
        for k in range(steps):  # rows k - 1 and k - N (or 0) are final
            if k > 0:
                p_lo, p_hi = self._predict(lower[..., k - 1, :], upper[..., k - 1, :], us[..., k - 1, :])
                lower[..., k, :] = np.maximum(lower[..., k, :], p_lo)
                upper[..., k, :] = np.minimum(upper[..., k, :], p_hi)
            if k < big_n:  # a growing window from x_0, if the bank of row k exists
                if 0 <= k - 1 + last < len(self._first):
                    bank = self._first[k - 1 + last]
                    terms = bank.terms(ys[..., : k + last, :], us[..., :k, :])
                    f_lo, f_hi = bank.box(*terms, lower[..., 0, :], upper[..., 0, :])
                    lower[..., k, :] = np.maximum(lower[..., k, :], f_lo)
                    upper[..., k, :] = np.minimum(upper[..., k, :], f_hi)
                continue
            if k >= stop:
                head, stop = k, min(k + block, steps)
                y_win = sliding_window_view(ys[..., head - big_n : stop - 1 + last, :], big_n + last, axis=-2)
                u_win = sliding_window_view(us[..., head - big_n : stop - 1, :], big_n, axis=-2)
                est, pad = self._window_terms(np.swapaxes(y_win, -1, -2), np.swapaxes(u_win, -1, -2))
            f_lo, f_hi = self._bank_box(
                est[..., k - head, :],
                pad[..., k - head, :],
                lower[..., k - big_n : k, :],
                upper[..., k - big_n : k, :],
                us[..., k - big_n : k, :],
            )
            lower[..., k, :] = np.maximum(lower[..., k, :], f_lo)
            upper[..., k, :] = np.minimum(upper[..., k, :], f_hi)
        return Estimate.from_boxes(times, lower, upper, meta={**self.meta(), "rows": self.rows})

    def meta(self) -> dict[str, Any]:
        """Design facts recorded in every :class:`~intervalobs.estimate.Estimate`.

        Returns
        -------
        dict
            ``method``, ``window``, ``filtered``, ``bank`` (filters per component), ``radius`` (evaluated, rounded
            up) and ``residual`` (max ``|R|``) of each component's first filter (the worst-case one),
            ``lp_seconds``, ``training`` (:attr:`training`), ``fallback`` (its meta).
        """
        fallback_meta = self.fallback.meta() if hasattr(self.fallback, "meta") else {}
        return {
            "method": "FiniteMemoryObserver",
            "window": self.window,
            "filtered": self.filtered,
            "bank": int(self.K.shape[1]),
            "radius": self.radius[:, 0].tolist(),
            "residual": float(np.max(np.abs(self.residual[:, 0]))),
            "lp_seconds": self.lp_seconds,
            "training": dict(self.training),
            "fallback": fallback_meta,
            "transient_s": float(self.window * self.h),
        }


class _FilterBank:
    r"""The filters of one window length, evaluated once from their weights (module docstring).

    ``gains`` (n, B, W, p) weigh ``W = L`` measurements (``L + 1`` when ``y_k`` is used) of a window of
    ``L`` steps; ``L = 0`` (only :math:`y_k`) is allowed. The model pieces are ``Φ``, ``Γ``, the noise
    channels ``G`` with their box (centre ``c``, radius ``r``), ``C``, ``F`` and the box of ``v``.
    """

    def __init__(
        self,
        gains: FloatArray,
        length: int,
        phi: FloatArray,
        gamma: FloatArray,
        noise: tuple[FloatArray, FloatArray, FloatArray],
        output: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
    ) -> None:
        k, big_n = gains, length
        noise_map, c, r = noise
        c_mat, f_mat, v_c, v_r = output
        n, p, m, banks = phi.shape[0], c_mat.shape[0], gamma.shape[1], k.shape[1]
        weights = k.shape[2]  # L, or L + 1 when y_k is used
        self.K, self.length, self.n = k, big_n, n
        powers, abs_powers = [np.eye(n)], [np.eye(n)]
        for _ in range(big_n):
            powers.append(phi @ powers[-1])
            abs_powers.append(np.abs(phi) @ abs_powers[-1])
        c_powers = np.stack([c_mat @ power for power in powers])  # (L + 1, p, n)
        abs_c_powers = np.stack([np.abs(c_mat) @ power for power in abs_powers])
        abs_k = np.abs(k)
        # Magnitudes bounding the rounding of D_l and R (module docstring): γ_D times these.
        d_mag = np.empty((big_n, n, banks, n))
        # D_l = Φ^{L-1-l} - Σ_{j>l} K_j C Φ^{j-1-l}, per component i and filter b: shape (L, n, B, n).
        d_mats = np.empty((big_n, n, banks, n))
        for l_ in range(big_n):
            d_mats[l_] = powers[big_n - 1 - l_][:, None, :]
            d_mats[l_] -= np.einsum("ibjp,jpq->ibq", k[:, :, l_ + 1 :, :], c_powers[: weights - 1 - l_])
            d_mag[l_] = abs_powers[big_n - 1 - l_][:, None, :]
            d_mag[l_] += np.einsum("ibjp,jpq->ibq", abs_k[:, :, l_ + 1 :, :], abs_c_powers[: weights - 1 - l_])
        kf = np.einsum("ibjp,pq->ibjq", k, f_mat)
        self.residual = powers[big_n][:, None, :] - np.einsum("ibjp,jpq->ibq", k, c_powers[:weights])
        r_mag = abs_powers[big_n][:, None, :] + np.einsum("ibjp,jpq->ibq", abs_k, abs_c_powers[:weights])
        gamma_d = 4.0 * (big_n + 1) * (n + p + noise_map.shape[1] + 2) * _EPS
        self.d_mats, self.d_mag, self.gamma_d = d_mats, d_mag, gamma_d  # for the ΔA terms of a subclass
        self.M = np.einsum("libq,qm->libm", d_mats, gamma)  # (L, n, B, m)
        d_noise = np.einsum("libq,qw->libw", d_mats, noise_map)  # D_l G: the process noise enters as G w_l
        self.offset = np.einsum("libw,w->ib", d_noise, c) - np.einsum("ibjq,q->ib", kf, v_c)
        radius = np.einsum("libw,w->ib", np.abs(d_noise), r) + np.einsum("ibjq,q->ib", np.abs(kf), v_r)
        noise_mag = np.einsum("libq,qw->libw", d_mag, np.abs(noise_map))
        radius += gamma_d * np.einsum("libw,w->ib", noise_mag, r + np.abs(c))  # rounding of D_l G (noise, d)
        # Upward rounding of the evaluation itself (sums of L (n + nv) nonnegative terms).
        terms = weights * (n + f_mat.shape[1])
        self.radius = radius * (1 + (terms + 4) * _EPS) + ROUNDING_MARGIN * radius
        sums = (2 * weights + 8) * _EPS
        # One matrix for a whole window z = (y_s … y_{s+W-1}, u_s … u_{s+L-1}) → every filter's estimate.
        rows = n * banks
        window_weights = [k.reshape(rows, weights * p), np.moveaxis(self.M, 0, 2).reshape(rows, big_n * m)]
        self.window_weights = np.concatenate(window_weights, axis=1).T  # (W p + L m, n B)
        # pad = |z| @ pad_weights + pad_const: rounding of the sums, and of M_l = D_l Γ times |u|.
        input_mag = np.moveaxis(np.einsum("libq,qm->libm", d_mag, np.abs(gamma)), 0, 2).reshape(rows, big_n * m)
        self.pad_weights = sums * np.abs(self.window_weights)
        self.pad_weights[weights * p :] += gamma_d * input_mag.T
        self.pad_const = (sums * np.abs(self.offset) + self.radius).ravel()
        self.offset_flat = self.offset.ravel()
        # R x_s ∈ R c ± (|R| r + rounding of c, r, both products and of R itself): half @ A + |c| @ B.
        gamma_res = (2 * n + 8) * _EPS
        abs_residual, residual_mag = np.abs(self.residual).reshape(rows, n).T, gamma_d * r_mag.reshape(rows, n).T
        self.residual_t = self.residual.reshape(rows, n).T  # (n, n B)
        self.half_weights = (1 + gamma_res) * abs_residual + residual_mag
        self.centre_weights = gamma_res * abs_residual + residual_mag

    def terms(self, ys: FloatArray, us: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Every filter's estimate and pad (radius + rounding of the sums), shape (..., n B), from windows
        ``ys`` (..., W, p) and ``us`` (..., L, m): two matrix products for any number of windows."""
        z = np.concatenate([ys.reshape(*ys.shape[:-2], -1), us.reshape(*us.shape[:-2], -1)], axis=-1)
        return z @ self.window_weights + self.offset_flat, np.abs(z) @ self.pad_weights + self.pad_const

    def box(
        self, est: FloatArray, pad: FloatArray, prior_lo: FloatArray, prior_hi: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """Intersection of the filters' boxes from their window terms and a box (..., n) of ``x_s`` (for ``R x_s``)."""
        centre, half = 0.5 * (prior_lo + prior_hi), 0.5 * (prior_hi - prior_lo)
        res_c = centre @ self.residual_t
        res_r = half @ self.half_weights + np.abs(centre) @ self.centre_weights
        low, high = est - pad + res_c - res_r, est + pad + res_c + res_r  # broadcast over runs
        shape = (*low.shape[:-1], self.n, -1)
        return inflate(np.max(low.reshape(shape), axis=-1), np.min(high.reshape(shape), axis=-1))


def _assemble(
    found: list[list[FloatArray]], base: FloatArray, size: int | None, rng: np.random.Generator
) -> FloatArray:
    """A bank (n, B, W, p): each component's ``base`` filter, then its distinct ``found`` filters (a random subset
    of ``size - 1`` of them when ``size`` is given); components with fewer repeat their base filter (a duplicate
    changes nothing)."""
    members = []
    for i, filters in enumerate(found):
        unique = np.unique(np.concatenate(filters), axis=0) if filters else base[i][None][:0]
        if size is not None:
            unique = unique[np.sort(rng.permutation(unique.shape[0])[: int(size) - 1])]
        members.append(np.concatenate([base[i][None], unique]))
    count = max(m.shape[0] for m in members)
    return np.stack(
        [np.concatenate([m, np.repeat(base[i][None], count - m.shape[0], 0)]) for i, m in enumerate(members)]
    )


def _check_training(
    window: object,
    records: object,
    steps: object,
    size: object,
    first_records: object,
    tolerance: object,
    selection: object,
) -> None:
    """Refuse a training option of :meth:`FiniteMemoryObserver.learn` that is not what it documents."""
    least_steps = int(window) + 2 if isinstance(window, (int, np.integer)) else 2  # one full window at least
    checks = [("records", records, 1), ("steps", steps, least_steps)]
    checks += [("size", size, 1)] if size is not None else []
    checks += [("first_records", first_records, 0)] if first_records is not None else []
    for name, value, least in checks:
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
            raise DataError(f"{name}: expected an integer >= {least}, got {value!r}")
    if tolerance is not None and (
        isinstance(tolerance, bool) or not isinstance(tolerance, (int, float)) or not 0 <= tolerance < np.inf
    ):
        raise DataError(f"tolerance: expected a finite number >= 0 or None, got {tolerance!r}")
    as_choice("selection", selection, ("random", "cover"))


def _train(
    hull: HullEstimator,
    full: ResolvedBounds,
    t: NDArray[Any],
    records: int,
    first_records: int,
    window: int,
    last: int,
    rng: np.random.Generator,
    seed: int,
    coverage: _Coverage | None,
) -> tuple[list[list[FloatArray]], list[list[list[FloatArray]]]]:
    """The hull's certificates on simulated extreme-noise records: per component, those of the full windows
    (``bank[i]``) and those of the first rows (``first[j][i]``: row ``j + 1 - last``, ``j + 1`` weights, windows
    from ``x_0``), as filters (weights, outputs) signed as bounds from below. ``rng`` draws the long records'
    noise (and goes on to choose the bank's members); ``seed`` starts the short records' own stream."""
    system = hull.system
    bank: list[list[FloatArray]] = [[] for _ in range(system.n)]
    first: list[list[list[FloatArray]]] = [[[] for _ in range(system.n)] for _ in range(window - 1 + last)]
    # Short records (window + 1 samples) for the first rows only: i.i.d. vertex or switching noise, both from
    # a vertex of the x_0 box (the prior's faces are what the first rows' certificates depend on).
    short = np.random.default_rng([seed, 0xF1B, 1])
    for record in range(records + first_records):
        if record < records:
            noise, own, times = _training_noise(system, full, t.size, record, rng), rng, t
        else:
            noise, own, times = ("vertex", "extreme")[record % 2], short, t[: window + 1]
        sim = simulate(system, full, times, noise=noise, seed=int(own.integers(2**31)))
        for key, duals in hull.certificates(times, sim.y, sim.u, first_rows=True, reuse=coverage).items():
            i, sign, *length = key  # length: the steps of a window from x_0 (first rows)
            weights = length[0] + last if length else window + last
            if weights <= len(first) or not length:  # (row N from x_0 is left to the full bank)
                (first[weights - 1] if length else bank)[i].append(sign * duals[:, :weights, :])
        if coverage is not None:
            coverage.settle()  # the record's last window
    return bank, first


def _training_noise(
    system: LTISystem, bounds: ResolvedBounds, steps: int, record: int, rng: np.random.Generator
) -> Any:
    """Extreme training noise: i.i.d. vertices (even records) or the simulator's switching bang-bang."""
    if record % 2:
        return "extreme"
    fine = 10 if system.continuous else 1  # simulate's default substeps
    return {
        "w": noise_signal("vertex", *bounds.w, steps * fine, rng),
        "v": noise_signal("vertex", *bounds.v, steps, rng),
    }
