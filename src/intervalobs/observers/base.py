"""The protocol every observer follows: ``init``/``step`` online, ``run`` on a whole record.

``init`` returns the state at the first sample (its box is the prior box of ``x(t_0)``);
``step(state, y_k, u_k)`` consumes the measurement and input at ``t_k`` and returns the next state;
``run(t, y, u)`` returns an :class:`~intervalobs.estimate.Estimate` and is written once, here: it
validates the record, loops ``step`` and collects the boxes, so it gives the same numbers as repeated
``step`` calls by construction. What row ``k`` means is the observer's :attr:`Observer.rows`, stated
in ``Estimate.meta["rows"]``:

* ``"predicted"`` (most observers): row ``k`` is the box of ``x(t_k)`` given ``y_0 … y_{k-1}``; row 0
  is the prior box and ``step`` returns the state at ``t_{k+1}``;
* ``"filtered"``: row ``k`` is the box of ``x(t_k)`` given ``y_0 … y_k``; ``step`` returns the state
  at ``t_k``;
* ``"smoothed"`` (:class:`~intervalobs.observers.set_inversion.SetInversionSmoother`): row ``k`` is the box
  of ``x(t_k)`` given the whole record; there is no ``step``, only ``run``.

A leading axis of ``y`` and ``u`` holds Monte Carlo runs: ``step`` accepts it from an unbatched state
(the prior is shared by every run) and carries it without a loop over runs. An observer overrides
``run`` only to add arguments or results around the loop (``Observer._loop``: per-sample signals,
per-row vectors of the state), or with a vectorised evaluation that is measurably faster and gives
the same numbers.
"""

from __future__ import annotations

import functools
import warnings
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal, ParamSpec, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray
from threadpoolctl import ThreadpoolController

from ..errors import ArgumentTypeError, BoundsError, DataError, DivergenceWarning, InconsistentDataError
from ..estimate import Estimate
from ..validation import as_array, as_box, as_instance, as_signal, as_time, check_both_or_neither, check_finite

__all__ = ["GROWTH_LIMIT", "Observer", "ObserverState", "check_growth", "options_after_bounds"]

FloatArray = NDArray[np.float64]

_BLAS = ThreadpoolController()

_Params = ParamSpec("_Params")
_Result = TypeVar("_Result")


def _one_blas_thread(run: Callable[_Params, _Result]) -> Callable[_Params, _Result]:
    """Run with one BLAS thread: the recursions multiply tiny matrices, where BLAS threads only
    fight over the cores (``benchmarks/results.json`` has the cost a step of the recursions)."""

    @functools.wraps(run)
    def limited(*args: _Params.args, **kwargs: _Params.kwargs) -> _Result:
        with _BLAS.limit(limits=1, user_api="blas"):
            return run(*args, **kwargs)

    return limited


_Design = TypeVar("_Design", bound=Callable[..., Any])


def options_after_bounds(*old_order: str) -> Callable[[_Design], _Design]:
    """Make every argument of a ``design`` after ``bounds`` keyword-only, warning for one release.

    Every estimator's ``design(system, bounds, *, ...)`` takes its options by keyword, ``h`` (the
    sampling period, where the estimator needs one) named the same everywhere. A call that still passes
    options by position gets them mapped to their former names with a :class:`FutureWarning`.

    .. deprecated:: 0.2.0
       Options after ``bounds`` passed by position; they stop working in the next release.

    Parameters
    ----------
    *old_order : str
        The names of the options in the order they had as positional arguments.

    Returns
    -------
    callable
        A decorator for a ``design`` (under ``@classmethod``) whose options after ``bounds`` follow ``*``.
    """

    def decorate(design: _Design) -> _Design:
        @functools.wraps(design)
        def keyword_only(cls: type, system: Any, bounds: Any, *options: Any, **keywords: Any) -> Any:
            if options:
                name = f"{cls.__name__}.{design.__name__}"
                if len(options) > len(old_order):
                    raise ArgumentTypeError(
                        f"{name}: expected at most {len(old_order) + 2} positional arguments (system, bounds, "
                        f"{', '.join(old_order)}), got {len(options) + 2}"
                    )
                names = old_order[: len(options)]
                twice = [n for n in names if n in keywords]
                if twice:
                    raise ArgumentTypeError(f"{name}: got {twice} both by position and by keyword")
                warnings.warn(
                    f"{name}: pass {', '.join(f'{n}=...' for n in names)} by keyword; options after `bounds` "
                    "given by position stop working in the next release",
                    FutureWarning,
                    stacklevel=2,
                )
                keywords.update(zip(names, options, strict=True))
            return design(cls, system, bounds, **keywords)

        return keyword_only  # type: ignore[return-value]

    return decorate


def _named(run: Callable[..., Estimate]) -> Callable[..., Estimate]:
    """Label the estimate of ``run`` with the state names of the observer's model (when it has them) and
    check its widths for unbounded growth (:func:`check_growth`)."""

    @functools.wraps(run)
    def named(self: Observer, *args: Any, **kwargs: Any) -> Estimate:
        estimate = run(self, *args, **kwargs)
        names = self._channel_names("state")
        if names is not None and len(names) == estimate.lower.shape[-1]:
            estimate.state_names = names
        check_growth(estimate)
        return estimate

    return named


def _checked_init(init: Callable[..., ObserverState]) -> Callable[..., ObserverState]:
    """``init`` that refuses a prior box with only one of its two bounds (it would be ignored)."""

    @functools.wraps(init)
    def checked(self: Observer, x0_lower: Any = None, x0_upper: Any = None, *args: Any, **kwargs: Any) -> ObserverState:
        check_both_or_neither(("x0_lower", x0_lower), ("x0_upper", x0_upper))
        return init(self, x0_lower, x0_upper, *args, **kwargs)

    return checked


def _checked_step(step: Callable[..., ObserverState]) -> Callable[..., ObserverState]:
    """``step`` that refuses a ``state`` not made by ``init`` or ``step`` (None, a box, an array)."""

    @functools.wraps(step)
    def checked(self: Observer, state: Any, *args: Any, **kwargs: Any) -> ObserverState:
        as_instance("state", state, ObserverState, "the ObserverState returned by init or step")
        return step(self, state, *args, **kwargs)

    return checked


GROWTH_LIMIT = 100.0
"""Growth of a state's width, from the first tenth of a record to the last, beyond which a run that is still
growing (last tenth at least 1.5 times the largest width of the first half) is reported as diverging
(:func:`check_growth`)."""


def check_growth(estimate: Estimate) -> None:
    """Warn and record in ``meta`` when the widths of a run grow without bound.

    For every run and state: the largest width over the last tenth of the record over the largest over its
    first tenth (``meta["width_growth"]``, the worst; NaN rows, where a run has no bound, are left out). A run
    is diverging (``meta["diverging"]``) when a finite width becomes infinite, or when that ratio exceeds
    :data:`GROWTH_LIMIT` while the widths still grow (the last tenth at least 1.5 times the largest width of
    the first half): bounded growth that has settled, e.g. from an exactly known initial state to the steady
    width, is not, however the steady widths fluctuate. Only the rows before the data contradict the model
    (:attr:`Estimate.inconsistent_from`) are judged; records of fewer than 10 such rows are not, and records
    of fewer than 30 only for bounds that become infinite (a tenth of one or two samples, which the data may
    pin exactly, is no scale to measure growth against).

    Parameters
    ----------
    estimate : Estimate
        The result of a run; its ``meta`` is updated in place.
    """
    bounded = estimate.bounded_rows()
    rows = slice(None) if bounded.all() else bounded  # a slice keeps views: no copy of a consistent record
    lower = np.asarray(estimate.lower, dtype=float)[..., rows, :]
    upper = np.asarray(estimate.upper, dtype=float)[..., rows, :]
    steps = lower.shape[-2]
    if steps < 10:
        return
    tenth = steps // 10
    with warnings.catch_warnings(), np.errstate(invalid="ignore"):
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN windows: rows a run has no bound for
        early = np.nanmax(upper[..., :tenth, :] - lower[..., :tenth, :], axis=-2)
        first_half = np.nanmax(upper[..., : steps // 2, :] - lower[..., : steps // 2, :], axis=-2)
        late = np.nanmax(upper[..., -tenth:, :] - lower[..., -tenth:, :], axis=-2)
        lost = np.isfinite(early) & np.isposinf(late)
        floor = 1e-9 * (1.0 + np.nanmax(np.abs(lower[..., :tenth, :]), axis=-2))
        ratio = np.where(np.isfinite(early) & np.isfinite(late), late / np.maximum(early, floor), 0.0)
    growing = (ratio > GROWTH_LIMIT) & (late >= 1.5 * first_half) & (steps >= 30)
    worst = float(np.max(ratio)) if ratio.size else 0.0
    diverging = bool(np.any(lost) or np.any(growing))
    reported = bool(estimate.meta.get("diverging", False))  # an estimator's own verdict (it warned already)
    estimate.meta.update(width_growth=np.inf if np.any(lost) else worst, diverging=diverging or reported)
    if diverging and not reported:
        warnings.warn(
            f"{estimate.meta.get('method', 'the observer')}: the widths grow without bound (a state's width grew "
            f"{estimate.meta['width_growth']:.3g} times from the first tenth of the record to the last and is still "
            "growing); the bounds hold but say nothing about the state: the estimation error of this design is "
            "unstable for this model (a gain that makes it contract, more outputs, or a smaller disturbance box)",
            DivergenceWarning,
            stacklevel=3,
        )


SPACING_TOLERANCE = 1e-9
"""Relative deviation of a record's sample spacing from ``h`` that :meth:`Observer._check_spacing` accepts."""


@dataclass
class ObserverState:
    """The state of an observer between two samples.

    Parameters
    ----------
    lower, upper : numpy.ndarray, shape (n,) or (M, n)
        Current state box.
    input_lower, input_upper : numpy.ndarray or None
        Current unknown-input box, for observers that estimate inputs.
    internal : dict
        Method-specific arrays (e.g. the box in observer coordinates).
    """

    lower: FloatArray
    upper: FloatArray
    input_lower: FloatArray | None = None
    input_upper: FloatArray | None = None
    internal: dict[str, Any] = field(default_factory=dict)


class Observer(ABC):
    """Base class of all observers.

    Subclasses set ``n`` (states), ``p`` (outputs), ``m`` (known inputs), ``h`` (the sampling period
    their bounds assume, when they assume one), :attr:`rows`, and implement :meth:`init` and
    ``_step`` (one step on a validated sample); :meth:`step` validates a sample and :meth:`run` a
    record, once, at the boundary, then both call ``_step``.
    """

    n: int
    p: int
    m: int
    h: float | None = None
    """The sampling period a record must have (``dt`` in discrete time); None: any spacing."""
    rows: Literal["predicted", "filtered", "smoothed"] = "predicted"
    """What row ``k`` of :meth:`run` bounds: ``x(t_k)`` given ``y_0 … y_{k-1}``, given ``y_0 … y_k``, or given the
    whole record."""
    batched: bool = True
    """Whether :meth:`step` takes a leading axis of runs; if not, :meth:`run` loops over the runs one by one."""
    missing_samples: bool = False
    """Whether a measurement may be missing (a row of NaN in ``y``): then the observer only predicts."""
    summary_fields: tuple[str, ...] = ()
    """Attributes that :meth:`__repr__` shows after ``n, p, m, h``: the method's own facts (gain, window, …)."""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        """Every ``run`` written by a subclass runs its hot loop on one BLAS thread (see ``_one_blas_thread``)
        and labels its estimate with the model's state names; every ``init`` and ``step`` checks its
        arguments first (``_checked_init``, ``_checked_step``)."""
        super().__init_subclass__(**kwargs)
        if "run" in cls.__dict__:
            cls.run = _named(_one_blas_thread(cls.__dict__["run"]))  # type: ignore[method-assign]
        if "init" in cls.__dict__:
            cls.init = _checked_init(cls.__dict__["init"])  # type: ignore[method-assign]
        if "step" in cls.__dict__:
            cls.step = _checked_step(cls.__dict__["step"])  # type: ignore[method-assign]

    @abstractmethod
    def init(self, x0_lower: ArrayLike | None = None, x0_upper: ArrayLike | None = None) -> ObserverState:
        """State at the first sample, from the prior box of ``x(t_0)`` (default: the design bounds).

        Parameters
        ----------
        x0_lower, x0_upper : array_like, shape (n,), optional
            Prior box of the initial state; both or neither.

        Returns
        -------
        ObserverState
        """

    @_checked_step
    def step(self, state: ObserverState, y: ArrayLike, u: ArrayLike | None = None) -> ObserverState:
        """Consume ``y_k`` (and ``u_k``) and return the next state.

        Parameters
        ----------
        state : ObserverState
            State at ``t_k`` (``"predicted"`` rows) or at ``t_{k-1}`` (``"filtered"`` rows).
        y : array_like, shape (p,) or (M, p)
            Measurement at ``t_k``.
        u : array_like, shape (m,) or (M, m), optional
            Known input at ``t_k``; required when the system has inputs (m > 0).

        Returns
        -------
        ObserverState
            State at ``t_{k+1}`` (``"predicted"`` rows: its box bounds ``x(t_{k+1})`` given
            ``y_0 … y_k``) or at ``t_k`` (``"filtered"`` rows: ``x(t_k)`` given ``y_0 … y_k``).
        """
        yk, uk = self._sample(y, u)
        return self._step(state, yk, uk)

    def _step(self, state: ObserverState, y: FloatArray, u: FloatArray) -> ObserverState:
        """:meth:`step` on a validated sample (``u`` broadcast to ``y``'s leading axes); the base loop calls it."""
        raise NotImplementedError(f"{type(self).__name__}: _step is not implemented (its run has its own loop)")

    @_named
    @_one_blas_thread
    def run(self, t: ArrayLike, y: ArrayLike, u: ArrayLike | None = None) -> Estimate:
        """Bounds over a whole record: :meth:`init`, then :meth:`step` at every sample.

        Parameters
        ----------
        t : array_like, shape (T,)
            Sample times (datetimes count as seconds from the first one).
        y : array_like, shape (T, p) or (M, T, p)
            Measurements; a leading axis holds Monte Carlo runs. A pandas ``DataFrame`` or an xarray
            ``DataArray`` is matched to the model's output names and its time index must be ``t``
            (see :func:`intervalobs.validation.as_signal`).
        u : array_like, shape (T, m) or (M, T, m), optional
            Known inputs; required when the system has inputs (m > 0). Labelled like ``y``.

        Returns
        -------
        Estimate
            Row ``k`` bounds ``x(t_k)`` as :attr:`rows` says (``meta["rows"]``); input bounds, when the
            observer estimates unknown inputs, are ``[-inf, inf]`` where it has none yet.
        """
        times, ys, us = self._signals(t, y, u)
        if self.batched or ys.ndim == 2:
            return self._loop(times, ys, us)[0]
        runs = self._separate_runs(times, ys, us)

        def stacked(name: str) -> FloatArray | None:
            values = [getattr(r, name) for r in runs]
            return None if values[0] is None else np.stack(values)

        lower, upper = np.stack([r.lower for r in runs]), np.stack([r.upper for r in runs])
        meta = {k: v for k, v in runs[0].meta.items() if k != "inconsistent_from"}
        return Estimate.from_boxes(times, lower, upper, stacked("input_lower"), stacked("input_upper"), meta)

    def _separate_runs(self, times: FloatArray, ys: FloatArray, us: FloatArray) -> list[Estimate]:
        """The Monte Carlo runs of an unbatched observer (leading axis of ``ys``, ``us``), one after another."""
        return [self._loop(times, ys[i], us[i])[0] for i in range(ys.shape[0])]

    def meta(self) -> dict[str, Any]:
        """Design facts recorded in every :class:`~intervalobs.estimate.Estimate` of :meth:`run`.

        Returns
        -------
        dict
            At least ``method``; :meth:`run` adds ``rows`` and, unless given here, ``transient_s``
            (the first sample time).
        """
        return {"method": type(self).__name__}

    def _loop(
        self,
        times: FloatArray,
        ys: FloatArray,
        us: FloatArray,
        state: ObserverState | None = None,
        signals: dict[str, FloatArray] | None = None,
        collect: tuple[str, ...] = (),
    ) -> tuple[Estimate, dict[str, FloatArray]]:
        """The one time loop: ``step`` at every sample, boxes collected as :attr:`rows` says.

        ``state`` defaults to :meth:`init`; ``signals`` are further per-sample arguments of ``step``
        (time-first like ``ys``); ``collect`` names vectors of ``state.internal`` returned per row.
        The loop stops once every run's box is empty or ``step`` raises
        :class:`~intervalobs.errors.InconsistentDataError` (the data contradict the model): the rows
        from each run's first inconsistent sample on are NaN (:meth:`Estimate.from_boxes`).
        """
        lead, steps, fresh = ys.shape[:-2], times.size, state is None
        state = self.init() if state is None else state
        signals = signals or {}
        lower = np.full((*lead, steps, self.n), np.nan)
        upper = np.full_like(lower, np.nan)
        inputs: list[FloatArray] = []  # allocated at the first input bound; "no bound yet" is [-inf, inf]
        extras: dict[str, FloatArray] = {}

        def store(k: int, current: ObserverState) -> None:
            lower[..., k, :], upper[..., k, :] = current.lower, current.upper
            if current.input_lower is not None and current.input_upper is not None:
                if not inputs:
                    shape = (*lead, steps, np.shape(current.input_lower)[-1])
                    inputs.extend((np.full(shape, -np.inf), np.full(shape, np.inf)))
                inputs[0][..., k, :], inputs[1][..., k, :] = current.input_lower, current.input_upper
            for key in collect:
                value = np.asarray(current.internal[key])
                if key not in extras:
                    extras[key] = np.full((*lead, steps, value.shape[-1]), np.nan)
                extras[key][..., k, :] = value

        filtered = self.rows == "filtered"
        if not filtered:
            store(0, state)
        for k in range(steps if filtered else steps - 1):
            extra = {name: signal[..., k, :] for name, signal in signals.items()}
            try:
                state = self._step(state, ys[..., k, :], us[..., k, :], **extra)
            except InconsistentDataError:
                if lead and fresh:  # one run contradicts the model: the others keep their bounds
                    return self._loop_runs(times, ys, us, signals, collect)
                if lead:
                    raise
                for box in (lower, upper, *inputs):
                    box[..., k:, :] = np.nan  # y_k contradicts the model: no bound from t_k on
                break
            store(k if filtered else k + 1, state)
            if np.all(np.any(~(state.lower <= state.upper), axis=-1)):
                break
        meta = {"transient_s": float(times[0]), **self.meta(), "rows": self.rows}
        input_lower, input_upper = inputs if inputs else (None, None)
        return Estimate.from_boxes(times, lower, upper, input_lower, input_upper, meta), extras

    def _loop_runs(
        self,
        times: FloatArray,
        ys: FloatArray,
        us: FloatArray,
        signals: dict[str, FloatArray],
        collect: tuple[str, ...],
    ) -> tuple[Estimate, dict[str, FloatArray]]:
        """:meth:`_loop` run by run, from :meth:`init`, stacked: each run stops at its own inconsistent sample."""
        lead = ys.shape[:-2]
        runs = [
            self._loop(times, ys[i], us[i], None, {key: value[i] for key, value in signals.items()}, collect)
            for i in np.ndindex(lead)
        ]

        def stacked(values: list[Any]) -> Any:
            return None if values[0] is None else np.stack(values).reshape(*lead, *values[0].shape)

        lower, upper, input_lower, input_upper = (
            stacked([getattr(e, key) for e, _ in runs]) for key in ("lower", "upper", "input_lower", "input_upper")
        )
        meta = {k: v for k, v in runs[0][0].meta.items() if k != "inconsistent_from"}
        extras = {key: stacked([x[key] for _, x in runs]) for key in collect}
        return Estimate.from_boxes(times, lower, upper, input_lower, input_upper, meta), extras

    def __repr__(self) -> str:
        """``Name(n=…, p=…, m=…, h=…, fact=…)`` with the facts named by :attr:`summary_fields` that are set."""
        facts = {name: getattr(self, name, None) for name in ("n", "p", "m", "h", *self.summary_fields)}
        shown = ", ".join(f"{name}={_short(value)}" for name, value in facts.items() if value is not None)
        return f"{type(self).__name__}({shown})"

    def _sample(self, y: ArrayLike, u: ArrayLike | None) -> tuple[FloatArray, FloatArray]:
        """Validate one sample for :meth:`step`: ``y`` (p,) or (M, p); ``u`` (m,) or (M, m) (None only if m = 0)."""
        yk = as_array("y", y).reshape(-1) if np.ndim(y) == 0 else as_array("y", y)
        if yk.ndim not in (1, 2) or yk.shape[-1] != self.p:
            raise DataError(f"y: expected finite values with last dimension {self.p}, got shape {yk.shape}")
        check_finite("y", yk, self.missing_samples)
        return yk, self._input(u, yk.shape[:-1])

    def _input(self, u: ArrayLike | None, lead: tuple[int, ...]) -> FloatArray:
        """The known input of one sample, validated and broadcast to ``(*lead, m)``.

        A missing ``u`` is zero only for a system without inputs: with ``m > 0`` the bounds would
        silently assume ``u = 0`` and lose the guarantee, so it is refused (pass zeros explicitly).
        """
        if u is None:
            if self.m > 0:
                raise DataError(
                    f"u: expected the known input, shape ({self.m},) or (M, {self.m}) (the system has "
                    f"m = {self.m}; pass zeros for u = 0), got None"
                )
            return np.zeros((*lead, 0))
        uk = as_array("u", u).reshape(-1) if np.ndim(u) == 0 else as_array("u", u)
        if uk.ndim not in (1, 2) or uk.shape[-1] != self.m or not np.all(np.isfinite(uk)):
            raise DataError(f"u: expected finite values with last dimension {self.m}, got shape {uk.shape}")
        try:
            return np.broadcast_to(uk, (*np.broadcast_shapes(lead, uk.shape[:-1]), self.m))
        except ValueError:
            raise DataError(f"u: expected leading shape {lead} (that of y), got shape {uk.shape}") from None

    def _signals(self, t: ArrayLike, y: ArrayLike, u: ArrayLike | None) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Validate ``t``, ``y``, ``u``; return them with ``u`` broadcast to ``y``'s leading axes."""
        times = as_time("t", t)
        if self.h is not None:
            self._check_spacing(times, self.h)
        ys = as_signal(
            "y", y, times.size, self.p, t=times, names=self._channel_names("output"), missing=self.missing_samples
        )
        return times, ys, self._record_input(u, ys, times)

    def _channel_names(self, kind: str) -> tuple[str, ...] | None:
        """The model's ``state``/``output``/``input`` names, or None when its model has none."""
        names = getattr(getattr(self, "system", None), f"{kind}_names", None)
        return None if names is None else tuple(names)

    def _record_input(self, u: ArrayLike | None, ys: FloatArray, times: FloatArray | None = None) -> FloatArray:
        """The known input of a record, validated and broadcast to the leading axes of ``ys``.

        As in :meth:`_input`, a missing ``u`` is zero only when the system has no inputs; a labelled
        ``u`` is matched to the model's input names and its time index checked against ``times``.
        """
        if u is None:
            if self.m > 0:
                raise DataError(
                    f"u: expected the known input, shape ({ys.shape[-2]}, {self.m}) or (M, {ys.shape[-2]}, "
                    f"{self.m}) (the system has m = {self.m}; pass zeros for u = 0), got None"
                )
            return np.zeros((*ys.shape[:-1], 0))
        us = as_signal("u", u, ys.shape[-2], self.m, t=times, names=self._channel_names("input"))
        if us.ndim < ys.ndim:
            us = np.broadcast_to(us, (*ys.shape[:-1], self.m))
        return us

    def _prior_box(
        self, default: tuple[FloatArray, FloatArray], x0_lower: ArrayLike | None, x0_upper: ArrayLike | None
    ) -> tuple[FloatArray, FloatArray]:
        """The prior box of ``x(t_0)`` for :meth:`init`: the given one (validated) or ``default``."""
        if x0_lower is None or x0_upper is None:
            return default
        return as_box("x0", (x0_lower, x0_upper), self.n)

    def _prior_boxes(
        self, default: tuple[FloatArray, FloatArray], x0_lower: ArrayLike | None, x0_upper: ArrayLike | None
    ) -> tuple[FloatArray, FloatArray]:
        """As :meth:`_prior_box`, also accepting one box a run (leading axes); copies, never views of ``default``."""
        if x0_lower is None and x0_upper is None:
            return default[0].copy(), default[1].copy()
        if x0_lower is None or x0_upper is None:
            raise BoundsError("x0_lower, x0_upper: give both or neither")
        lo, hi = np.array(x0_lower, dtype=float), np.array(x0_upper, dtype=float)
        if lo.ndim == 1:
            return as_box("x0", (lo, hi), self.n)
        if lo.shape != hi.shape or lo.shape[-1] != self.n or np.any(lo > hi) or not np.all(np.isfinite(lo + hi)):
            raise BoundsError(f"x0: expected finite boxes of shape (..., {self.n}) with lower <= upper")
        return lo, hi

    def _check_spacing(self, times: FloatArray, h: float) -> None:
        """A record must be sampled every ``h``, the period the design assumed (``dt`` in discrete time)."""
        if times.size > 1:
            spacing = np.diff(times)
            if np.max(np.abs(spacing - h)) > SPACING_TOLERANCE * h:
                raise DataError(
                    f"t: expected uniform spacing h = {h:g} (the design's sampling period), "
                    f"got spacings in [{spacing.min():g}, {spacing.max():g}]"
                )


def _short(value: Any) -> str:
    """A few characters for a repr: 4 significant digits, class names for objects, shapes for arrays."""
    if isinstance(value, (bool, int, str)):
        return repr(value)
    if isinstance(value, (float, np.floating)):
        return f"{float(value):.4g}"
    if isinstance(value, np.ndarray):
        return f"array{value.shape}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_short(v) for v in value) + "]"
    return type(value).__name__


def record_consistency(estimate: Estimate, flags: NDArray[np.bool_]) -> list[float | None]:
    """Write ``consistent`` and ``inconsistent_from`` into ``estimate.meta`` from per-row consistency flags.

    ``inconsistent_from`` is the earliest time over the runs (None when every run fits the model), as
    :attr:`Estimate.inconsistent_from` reads it; for a batch, ``consistent`` is a list per run and
    ``inconsistent_from_runs`` the time of each run.

    Parameters
    ----------
    estimate : Estimate
        The run's estimate (its ``t`` gives the times).
    flags : numpy.ndarray of bool, shape (T,) or (M, T)
        Whether the record up to each row is consistent with the model.

    Returns
    -------
    list of float or None
        Per run, the first time the record contradicts the model (None when it never does).
    """
    first = np.where(flags.all(-1), -1, np.argmin(flags, axis=-1))
    starts = [None if k < 0 else float(estimate.t[k]) for k in np.atleast_1d(first)]
    estimate.meta["consistent"] = bool(flags.all()) if flags.ndim == 1 else flags.all(-1).tolist()
    times = [start for start in starts if start is not None]
    estimate.meta["inconsistent_from"] = min(times) if times else None
    if flags.ndim > 1:
        estimate.meta["inconsistent_from_runs"] = starts
    return starts
