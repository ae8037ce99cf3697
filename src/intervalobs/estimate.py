"""The result of running an observer: time-stamped bounds of the state (and of unknown inputs)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _tables
from .errors import BoundsError, DataError, DimensionError, FileError
from .validation import as_input_path, as_names, as_truth

if TYPE_CHECKING:
    from collections.abc import Sequence

    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


__all__ = ["ENCLOSURE_TOL", "EnclosureReport", "Estimate", "enclosure_report"]

FloatArray = NDArray[np.float64]

ENCLOSURE_TOL = 1e-8
"""Relative tolerance ``(lower - x) / (1 + |x|)`` under which a sample counts as enclosed.

It only decides the *fraction*; ``max_violation`` reports the raw amount, tolerance-free. The same
rule is used by ``intervalobs check`` (:func:`intervalobs.reproduce.contract.check_reproduction`).
"""


@dataclass(frozen=True)
class EnclosureReport:
    """How well a set of bounds contains the truth.

    Parameters
    ----------
    fraction : float
        Fraction of (time ≥ transient, component[, run]) samples enclosed (see ``ENCLOSURE_TOL``).
    max_violation : float
        Largest amount by which the truth leaves the bounds (0.0 when it never does).
    first_violation_time : float or None
        Earliest time (≥ transient) with a sample outside the bounds, or None.
    """

    fraction: float
    max_violation: float
    first_violation_time: float | None

    def as_dict(self) -> dict[str, float]:
        """The report in the ``summary.json`` form: ``fraction`` and ``max_violation``.

        Returns
        -------
        dict of str to float
            ``{"fraction": ..., "max_violation": ...}``.
        """
        return {"fraction": self.fraction, "max_violation": self.max_violation}


def enclosure_report(
    t: ArrayLike, lower: ArrayLike, truth: ArrayLike, upper: ArrayLike, transient: float = 0.0
) -> EnclosureReport:
    """Compare bounds with the truth after ``transient``; time is the axis before the last.

    An infinite bound encloses every finite value (``[-inf, inf]``: no bound yet, which is sound); a
    sample whose comparison is undefined (NaN in the bounds or the truth) counts as not enclosed.

    Parameters
    ----------
    t : array_like, shape (T,)
        Times.
    lower, truth, upper : array_like, shape (..., T, n)
        Bounds and true values (leading run axes allowed).
    transient : float
        Samples before this time are ignored.

    Returns
    -------
    EnclosureReport
    """
    tt = np.asarray(t, dtype=float)
    lo, x, hi = (np.asarray(a, dtype=float) for a in (lower, truth, upper))
    if not (lo.shape == x.shape == hi.shape) or lo.ndim < 2 or lo.shape[-2] != tt.size:
        raise DimensionError(
            f"truth: expected the shape of the bounds {lo.shape} with {tt.size} time steps, got {x.shape}"
        )
    after = tt >= transient
    lo, x, hi = lo[..., after, :], x[..., after, :], hi[..., after, :]
    if x.size == 0:
        return EnclosureReport(1.0, 0.0, None)
    amount = np.maximum(lo - x, x - hi)
    amount = np.where(np.isnan(amount), np.inf, amount)
    outside = amount / (1.0 + np.abs(x)) > ENCLOSURE_TOL
    time_axis_bad = np.any(outside, axis=tuple(i for i in range(outside.ndim) if i != outside.ndim - 2))
    first = float(tt[after][np.argmax(time_axis_bad)]) if time_axis_bad.any() else None
    return EnclosureReport(float(1.0 - outside.mean()), float(max(amount.max(), 0.0)), first)


@dataclass
class Estimate:
    """Bounds produced by an observer.

    Parameters
    ----------
    t : array_like, shape (T,)
        Sample times.
    lower, upper : array_like, shape (T, n) or (M, T, n)
        State bounds; a leading axis holds Monte Carlo runs.
    input_lower, input_upper : array_like, optional
        Unknown-input bounds, shape (T, q) or (M, T, q); ``-inf``/``inf`` where no bound is available
        yet (e.g. a delayed estimate).
    meta : dict
        Method name, gains, transient time (key ``"transient_s"``) and other design facts.
    state_names : sequence of str, optional
        Names of the states (default ``x1 …``; an observer's ``run`` gives its model's names).
    input_names : sequence of str, optional
        Names of the unknown inputs (default ``d1 …``).

    Raises
    ------
    BoundsError
        A bound is NaN (not an interval: ``-inf``/``inf`` say "no bound") before
        ``meta["inconsistent_from"]``, or lower > upper somewhere.

    Notes
    -----
    **Data that contradict the model.** When an estimator's box becomes empty (the data fit no
    admissible realisation of the model: a parameter outside its box, a unit error, a wrong time
    grid), the estimate is kept and says so: :attr:`consistent` is False, :attr:`inconsistent_from`
    is the first time whose box is empty (``meta["inconsistent_from"]``), the rows before it keep
    their bounds and the rows from it on are NaN (no bound holds any more; the last bounds would
    claim a guarantee the model no longer gives). :meth:`from_boxes` builds such an estimate;
    :meth:`enclosure` checks only the rows before that time, plots stop there and mark it, and the
    tables (:meth:`to_pandas`, :meth:`to_xarray`, :meth:`save`) keep the NaN rows and the time.
    """

    t: FloatArray
    lower: FloatArray
    upper: FloatArray
    input_lower: FloatArray | None = None
    input_upper: FloatArray | None = None
    meta: dict[str, Any] = field(default_factory=dict)
    state_names: Sequence[str] = ()
    input_names: Sequence[str] = ()

    def __post_init__(self) -> None:
        self.t = np.asarray(self.t, dtype=float)
        self.lower = np.asarray(self.lower, dtype=float)
        self.upper = np.asarray(self.upper, dtype=float)
        if self.lower.shape != self.upper.shape or self.lower.ndim not in (2, 3):
            raise DimensionError(
                f"Estimate: expected lower and upper of one shape (T, n) or (M, T, n), "
                f"got {self.lower.shape} and {self.upper.shape}"
            )
        if self.lower.shape[-2] != self.t.size:
            raise DimensionError(f"Estimate: expected {self.t.size} time steps in lower, got {self.lower.shape[-2]}")
        usable = self.bounded_rows()
        _check_bounds("lower", "upper", self.t, self.lower, self.upper, usable)
        if (self.input_lower is None) != (self.input_upper is None):
            raise DimensionError("Estimate: give both input_lower and input_upper or neither")
        if self.input_lower is not None and self.input_upper is not None:
            self.input_lower = np.asarray(self.input_lower, dtype=float)
            self.input_upper = np.asarray(self.input_upper, dtype=float)
            if self.input_lower.shape != self.input_upper.shape or self.input_lower.shape[:-1] != self.lower.shape[:-1]:
                raise DimensionError(
                    f"Estimate: input bounds must have shape {self.lower.shape[:-1]} + (q,), "
                    f"got {self.input_lower.shape} and {self.input_upper.shape}"
                )
            _check_bounds("input_lower", "input_upper", self.t, self.input_lower, self.input_upper, usable)
        self.state_names = as_names("state_names", self.state_names or None, self.lower.shape[-1], "x")
        q = 0 if self.input_lower is None else self.input_lower.shape[-1]
        self.input_names = as_names("input_names", self.input_names or None, q, "d")

    def __repr__(self) -> str:
        """Method, runs, samples, time span, dimensions and the mean width at the last sample."""
        runs = f"runs={self.lower.shape[0]}, " if self.lower.ndim == 3 else ""
        inputs = f", q={self.input_lower.shape[-1]}" if self.input_lower is not None else ""
        span = f"[{self.t[0]:.4g}, {self.t[-1]:.4g}]" if self.t.size else "[]"
        final = float(np.mean(self.width()[..., -1, :])) if self.t.size and self.lower.shape[-1] else float("nan")
        method = f"method={self.meta['method']!r}, " if "method" in self.meta else ""
        broken = "" if self.consistent else f", inconsistent_from={self.inconsistent_from:.4g}"
        return (
            f"Estimate({method}{runs}samples={self.t.size}, t={span}, n={self.lower.shape[-1]}{inputs}, "
            f"final_mean_width={final:.4g}{broken})"
        )

    @classmethod
    def from_boxes(
        cls,
        t: ArrayLike,
        lower: ArrayLike,
        upper: ArrayLike,
        input_lower: ArrayLike | None = None,
        input_upper: ArrayLike | None = None,
        meta: dict[str, Any] | None = None,
    ) -> Estimate:
        """An estimator's boxes as an estimate; an empty box (lower > upper) ends its run's bounds.

        From the first row where a state or input box of a run is empty (or NaN) on, that run's
        rows are NaN, and ``meta["inconsistent_from"]`` is the earliest such time over the runs
        (see the class Notes): the data contradict the model from then on.

        Parameters
        ----------
        t : array_like, shape (T,)
            Sample times.
        lower, upper : array_like, shape (T, n) or (M, T, n)
            State boxes, as the estimator computed them.
        input_lower, input_upper : array_like, optional
            Unknown-input boxes, shape (T, q) or (M, T, q).
        meta : dict, optional
            Method facts, copied.

        Returns
        -------
        Estimate
        """
        times = np.asarray(t, dtype=float)
        boxes = [np.array(a, dtype=float) for a in (lower, upper)]
        if input_lower is not None and input_upper is not None:
            boxes += [np.array(a, dtype=float) for a in (input_lower, input_upper)]
        facts = dict(meta or {})
        after = _after_first_empty(times, boxes)
        if after is not None:
            for box in boxes:
                box[after] = np.nan
            facts["inconsistent_from"] = float(times[np.argmax(np.any(after.reshape(-1, times.size), axis=0))])
        if len(boxes) == 2:
            return cls(times, boxes[0], boxes[1], meta=facts)
        return cls(times, boxes[0], boxes[1], boxes[2], boxes[3], meta=facts)

    @property
    def inconsistent_from(self) -> float | None:
        """First time at which the data contradict the model (an empty box), or None (``meta["inconsistent_from"]``)."""
        value = self.meta.get("inconsistent_from")
        return None if value is None else float(value)

    @property
    def consistent(self) -> bool:
        """Whether the data fit the model over the whole record (no empty box; see the class Notes)."""
        return self.inconsistent_from is None

    def bounded_rows(self) -> NDArray[np.bool_]:
        """The rows before :attr:`inconsistent_from` (every row when the data fit the model).

        Returns
        -------
        numpy.ndarray of bool, shape (T,)
        """
        start = self.inconsistent_from
        return np.asarray(self.t < (np.inf if start is None else start))

    @property
    def transient(self) -> float:
        """Time after which the method claims enclosure (``meta['transient_s']``, default the first time)."""
        return float(self.meta.get("transient_s", self.t[0]))

    def enclosure(self, x: Any, transient: float | None = None) -> EnclosureReport:
        """Check that the state bounds contain the true state ``x`` (same shape as ``lower``).

        Parameters
        ----------
        x : array_like, shape (T, n) or (M, T, n), Simulation or control.TimeResponseData
            True state: an array, a :class:`~intervalobs.simulate.Simulation`, a python-control
            response (its ``states``, time-last, are turned time-first), or a pandas/xarray table of
            the states (see :func:`intervalobs.validation.as_truth`; their times must be ``t``).
        transient : float, optional
            Ignore samples before this time (default: the method's own transient).

        Returns
        -------
        EnclosureReport
            Of the rows before :attr:`inconsistent_from` (the rows after it hold no bound).
        """
        truth = as_truth("x", x, self.t, self.state_names)
        kept = self.bounded_rows()
        return enclosure_report(
            self.t[kept],
            self.lower[..., kept, :],
            truth[..., kept, :],
            self.upper[..., kept, :],
            self.transient if transient is None else transient,
        )

    def input_enclosure(self, d: ArrayLike, transient: float | None = None) -> EnclosureReport:
        """Check that the unknown-input bounds contain the true input ``d``; rows without a bound are skipped.

        Parameters
        ----------
        d : array_like, shape (T, q) or (M, T, q)
            True unknown input.
        transient : float, optional
            Ignore samples before this time (default: the method's own transient, or the first time
            at which every input bound is finite if that is later: an infinite bound encloses
            trivially, so the fraction measures the informative rows).

        Returns
        -------
        EnclosureReport

        Raises
        ------
        DataError
            When the estimate has no input bounds.
        """
        if self.input_lower is None or self.input_upper is None:
            raise DataError("Estimate.input_enclosure: this estimate has no input bounds")
        start = self.transient if transient is None else transient
        known = np.all(np.isfinite(self.input_lower) & np.isfinite(self.input_upper), axis=-1)
        while known.ndim > 1:
            known = np.all(known, axis=0)
        first_known = self.t[known][0] if known.any() else np.inf
        return enclosure_report(self.t, self.input_lower, d, self.input_upper, max(start, first_known))

    def width(self) -> FloatArray:
        """State widths ``upper - lower``.

        Returns
        -------
        numpy.ndarray
            Same shape as ``lower``: (T, n) or (M, T, n).
        """
        return self.upper - self.lower

    def save(self, path: str | Path) -> None:
        """Write the estimate to an ``.npz`` file (meta is kept as JSON).

        Parameters
        ----------
        path : str or pathlib.Path
            Destination file (NumPy appends ``.npz`` when missing).
        """
        import json

        arrays: dict[str, Any] = {"t": self.t, "lower": self.lower, "upper": self.upper}
        if self.input_lower is not None:
            arrays.update(input_lower=self.input_lower, input_upper=self.input_upper)
        arrays["meta"] = np.array(json.dumps(self.meta, default=_tables.jsonable))
        arrays["state_names"] = np.array(self.state_names, dtype=str)
        arrays["input_names"] = np.array(self.input_names, dtype=str)
        np.savez_compressed(path, **arrays)

    @classmethod
    def load(cls, path: str | Path) -> Estimate:
        """Read an estimate written by :meth:`save`.

        Parameters
        ----------
        path : str or pathlib.Path
            An ``.npz`` file written by :meth:`save`.

        Returns
        -------
        Estimate

        Raises
        ------
        FileError
            When ``path`` is missing or is not an ``.npz`` file written by :meth:`save`.
        """
        import json
        import zipfile

        file = as_input_path("path", path)
        expected = f"path: expected an .npz file written by Estimate.save, got {str(path)!r}"
        try:
            loaded = np.load(file)
        except (OSError, ValueError, EOFError, zipfile.BadZipFile):
            raise FileError(f"{expected} (not a NumPy file)") from None
        if not isinstance(loaded, np.lib.npyio.NpzFile):
            raise FileError(f"{expected} (a single array)")
        with loaded as data:
            stored = {k: data[k] for k in data.files}
        missing = [k for k in ("t", "lower", "upper", "meta") if k not in stored]
        if missing:
            raise FileError(f"{expected} (no {', '.join(missing)})")
        extra: dict[str, Any] = {k: stored[k] for k in ("input_lower", "input_upper") if k in stored}
        extra.update({k: tuple(stored[k].tolist()) for k in ("state_names", "input_names") if k in stored})
        meta = json.loads(str(stored["meta"]))
        return cls(stored["t"], stored["lower"], stored["upper"], meta=meta, **extra)

    def to_pandas(self) -> Any:
        """The bounds as a pandas ``DataFrame`` (needs the ``data`` extra).

        Indexed by time ``t`` (by ``run`` and ``t`` for a Monte Carlo estimate), with the columns
        ``NAME_lower``, ``NAME_upper`` and ``NAME_width`` of every state, then of every unknown input;
        ``attrs`` holds ``meta`` (as JSON-compatible values) and the names (``state_names``,
        ``input_names``). :meth:`from_pandas` reads it back.

        Returns
        -------
        pandas.DataFrame
        """
        attrs = {
            **_tables.plain(self.meta),
            "state_names": list(self.state_names),
            "input_names": list(self.input_names),
        }
        return _tables.to_frame(self.t, self.columns(), attrs, "Estimate.to_pandas")

    def to_xarray(self) -> Any:
        """The bounds as an xarray ``Dataset`` (needs the ``data`` extra).

        Variables ``lower``, ``upper``, ``width`` over the dimensions ``t`` and ``state`` (``run``
        first for a Monte Carlo estimate), and ``input_lower``, ``input_upper`` over ``t`` and
        ``input`` when the estimate has unknown-input bounds; the coordinates are the times and the
        names, ``attrs`` holds ``meta`` as JSON-compatible values.

        Returns
        -------
        xarray.Dataset
        """
        variables = {
            name: (values, "state", tuple(self.state_names))
            for name, values in (("lower", self.lower), ("upper", self.upper), ("width", self.width()))
        }
        if self.input_lower is not None and self.input_upper is not None:
            names = tuple(self.input_names)
            variables.update(
                input_lower=(self.input_lower, "input", names), input_upper=(self.input_upper, "input", names)
            )
        return _tables.to_dataset(self.t, variables, _tables.plain(self.meta), "Estimate.to_xarray")

    @classmethod
    def from_pandas(cls, frame: Any, input_names: Sequence[str] | None = None) -> Estimate:
        """Read an estimate from a ``DataFrame`` of ``NAME_lower``/``NAME_upper`` columns (:meth:`to_pandas`).

        The index is the time (or ``run`` and time). The names come from ``frame.attrs`` when it has
        them (a frame made by :meth:`to_pandas`); otherwise every ``NAME_lower`` column with a matching
        ``NAME_upper`` is a state, except the names in ``input_names``. ``NAME_width`` columns and any
        other column are ignored; ``meta`` is the rest of ``attrs``.

        Parameters
        ----------
        frame : pandas.DataFrame
            The table, e.g. ``pandas.read_csv(path, index_col="t")`` of a file written with ``to_csv``.
        input_names : sequence of str, optional
            The unknown inputs among the bound columns, when ``attrs`` does not name them.

        Returns
        -------
        Estimate
        """
        t, columns, attrs = _tables.from_frame(frame, "Estimate.from_pandas")
        states = attrs.pop("state_names", None)
        inputs = attrs.pop("input_names", None) if input_names is None else list(input_names)
        bounded = [c[: -len("_lower")] for c in columns if c.endswith("_lower") and f"{c[:-6]}_upper" in columns]
        inputs = list(inputs or [])
        states = [c for c in bounded if c not in inputs] if states is None else list(states)
        missing = [
            f"{n}_{end}" for n in [*states, *inputs] for end in ("lower", "upper") if f"{n}_{end}" not in columns
        ]
        if missing or not states:
            raise DataError(
                f"frame: expected NAME_lower and NAME_upper columns, got {list(columns)}: missing {missing}"
            )

        def stack(names: list[str], end: str) -> FloatArray:
            return np.stack([columns[f"{n}_{end}"] for n in names], axis=-1)

        extra: dict[str, Any] = {}
        if inputs:
            extra.update(input_lower=stack(inputs, "lower"), input_upper=stack(inputs, "upper"), input_names=inputs)
        return cls(t, stack(states, "lower"), stack(states, "upper"), meta=attrs, state_names=states, **extra)

    def columns(self) -> list[tuple[str, FloatArray]]:
        """The bounds as named columns: ``NAME_lower``, ``NAME_upper``, ``NAME_width`` of each state, then input.

        Returns
        -------
        list of (str, numpy.ndarray)
            Column name and values, shape (T,) or (M, T); the columns of :meth:`to_pandas`.
        """
        columns: list[tuple[str, FloatArray]] = []
        blocks = [(self.state_names, self.lower, self.upper)]
        if self.input_lower is not None and self.input_upper is not None:
            blocks.append((self.input_names, self.input_lower, self.input_upper))
        for names, lower, upper in blocks:
            for i, name in enumerate(names):
                width = upper[..., i] - lower[..., i]
                columns += [
                    (f"{name}_lower", lower[..., i]),
                    (f"{name}_upper", upper[..., i]),
                    (f"{name}_width", width),
                ]
        return columns

    def plot(
        self,
        truth: Any = None,
        labels: Sequence[str] | None = None,
        *,
        inputs: bool = False,
        input_truth: ArrayLike | None = None,
        run: int | None = None,
        ax: Axes | Sequence[Axes] | None = None,
        time_unit: str | None = None,
    ) -> Figure:
        """Plot each state's bounds (and the truth); see :func:`intervalobs.plotting.plot_estimate`.

        Parameters
        ----------
        truth : array_like, shape (T, n) or (M, T, n), Simulation or control.TimeResponseData, optional
            True state (as for :meth:`enclosure`), drawn as a line.
        labels : sequence of str, optional
            Panel labels (default: the state and input names).
        inputs : bool
            Also plot the unknown-input bounds.
        input_truth : array_like, shape (T, q) or (M, T, q), optional
            True unknown input.
        run : int, optional
            The Monte Carlo run to draw; None: the envelope over runs.
        ax : matplotlib.axes.Axes or sequence of Axes, optional
            Where to draw, one axes per panel; default: a new figure.
        time_unit : str, optional
            Unit of ``t`` for the time axis label (default ``meta["time_unit"]`` if present).

        Returns
        -------
        matplotlib.figure.Figure
        """
        from .plotting import plot_estimate

        return plot_estimate(
            self,
            truth=truth,
            labels=labels,
            inputs=inputs,
            input_truth=input_truth,
            run=run,
            ax=ax,
            time_unit=time_unit,
        )


def _check_bounds(
    lower_name: str,
    upper_name: str,
    t: FloatArray,
    lower: FloatArray,
    upper: FloatArray,
    usable: NDArray[np.bool_],
) -> None:
    """Refuse NaN bounds (not an interval) in the ``usable`` rows and empty ones (lower > upper), naming the first."""
    for name, values in ((lower_name, lower), (upper_name, upper)):
        missing = np.isnan(values)
        if missing.any() and (missing := missing & usable[:, None]).any():
            k = int(np.argwhere(missing)[0][-2])
            raise BoundsError(
                f"Estimate: {name}: expected numbers (-inf/inf for no bound), got NaN at t = {t[k]:g} (row {k})"
            )
    if np.any(lower > upper):
        k = int(np.argwhere(lower > upper)[0][-2])
        raise BoundsError(
            f"Estimate: expected {lower_name} <= {upper_name}, got {lower_name} > {upper_name} "
            f"at t = {t[k]:g} (row {k})"
        )


def _after_first_empty(t: FloatArray, boxes: list[FloatArray]) -> NDArray[np.bool_] | None:
    """Rows (..., T) at or after the first empty (or NaN) box of their run; None if none or the shapes differ.

    ``boxes`` alternates lower and upper arrays of shape (..., T, k); shapes that do not fit are left
    to the :class:`Estimate` constructor's checks.
    """
    lead = boxes[0].shape[:-1]
    if boxes[0].ndim < 2 or lead[-1:] != t.shape:
        return None
    empty = np.zeros(lead, dtype=bool)
    for lo, hi in zip(boxes[::2], boxes[1::2]):
        if lo.shape == hi.shape and lo.shape[:-1] == lead:
            ordered = lo <= hi  # False where empty or NaN
            if not ordered.all():
                empty |= ~ordered.all(axis=-1)
    if not empty.any():
        return None
    after = np.cumsum(empty, axis=-1) > 0
    return after if after.any() else None


def _jsonable(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return str(value)
