"""Model files and measured records: what ``intervalobs estimate MODEL DATA`` reads and writes.

A *model file* is TOML (``.toml``) or Python (``.py``). The TOML form holds the matrices of
:class:`~intervalobs.systems.lti.LTISystem` and the boxes of :class:`~intervalobs.systems.bounds.Bounds`::

    [model]                      # dx/dt = (A + dA) x + (B + dB) u + E w,  y = C x + F v
    A = [[0.0, 1.0], [0.0, -8.0]]
    B = [[0.0], [40.0]]          # optional, like E, F, dA and dB = [lower, upper] and dt (discrete time)
    C = [[1.0, 0.0]]
    state_names = ["angle", "speed"]
    output_names = ["encoder"]
    input_names = ["voltage"]

    [bounds]                     # [lower, upper] of each unknown
    x0 = [[-0.1, -1.0], [0.1, 1.0]]
    w = [[0.0, -0.5], [0.0, 0.5]]
    v = [[-0.002], [0.002]]

A Python model file defines ``system`` (an ``LTISystem``) and ``bounds`` (a ``Bounds``). Either
may give the sampling period ``h`` (``[model] h``, or a variable ``h``); in continuous time it
defaults to the record's spacing.

A *record* is a CSV file (or Parquet, with pyarrow installed) with a time column (``t`` or ``time``,
in seconds, or ISO 8601 datetimes) and one column per output and known input, found by the model's
names; other columns are ignored. Every problem is reported as one line naming the file, and for a
CSV file the lines concerned.
"""

from __future__ import annotations

import csv
import json
import runpy
import tomllib
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from . import _tables
from .errors import DataError, IntervalObserverError
from .estimate import Estimate
from .observers.base import SPACING_TOLERANCE, Observer
from .systems.bounds import Bounds
from .systems.lti import LTISystem

__all__ = [
    "OBSERVERS",
    "ModelFile",
    "Record",
    "design_observer",
    "estimate_record",
    "example_model",
    "read_model",
    "read_record",
    "write_bounds",
    "write_example",
    "write_model",
]

_DECIMAL_TIME_ULPS = 8 * np.finfo(float).eps
"""Relative spacing tolerance of a record's times (a check, not a bound's pad): times written as decimals
carry the rounding of their last digit, a few ulps of the largest time."""

FloatArray = NDArray[np.float64]

OBSERVERS = {
    "auto": "intervalobs.observe: the tightest estimator within 5 ms a sample, filtered rows (default)",
    "tube": "IntervalObserver.design: the gain with the smallest error tube",
    "framer": "IntervalObserver.design(method='framer'): the classical framer in searched coordinates",
    "intersection": "IntersectionObserver.design: several sound observers intersected, output contraction",
    "hull": "HullEstimator.design: the exact interval hull by linear programming (point models; slow)",
}
"""Observers ``intervalobs estimate --observer NAME`` can design from a model file."""

_MODEL_KEYS = {"A", "B", "C", "E", "F", "dA", "dB", "dt", "h", "state_names", "output_names", "input_names"}
_TIME_COLUMNS = ("t", "time")
_SHOWN_LINES = 8


@dataclass(frozen=True)
class ModelFile:
    """A model read from a file.

    Parameters
    ----------
    system : LTISystem
        The model, with its names.
    bounds : Bounds
        Boxes of the unknowns.
    h : float or None
        The sampling period the file gives (None: the record's spacing, or ``dt``).
    path : pathlib.Path
        The file.
    """

    system: LTISystem
    bounds: Bounds
    h: float | None
    path: Path


@dataclass(frozen=True)
class Record:
    """A measured record matched to a model: uniform times, outputs and known inputs.

    Parameters
    ----------
    t : numpy.ndarray, shape (T,)
        The record's times in seconds (datetimes: from the first sample).
    y : numpy.ndarray, shape (T, p)
        The model's outputs, in its order.
    u : numpy.ndarray, shape (T, m)
        The model's known inputs, in its order.
    h : float
        The sampling period (uniform spacing of ``t``).
    path : pathlib.Path
        The file.
    """

    t: FloatArray
    y: FloatArray
    u: FloatArray
    h: float
    path: Path


def read_model(path: str | Path) -> ModelFile:
    """Read a model file: TOML (``[model]`` and ``[bounds]`` tables) or Python (``system``, ``bounds``).

    Parameters
    ----------
    path : str or pathlib.Path
        The file; its suffix (``.toml`` or ``.py``) says which form.

    Returns
    -------
    ModelFile

    Raises
    ------
    DataError
        When the file is missing, not valid TOML/Python, lacks a key or defines an invalid model
        (the message names the file and the key).
    """
    file = Path(path)
    if not file.is_file():
        raise DataError(f"MODEL: expected an existing .toml or .py file, got {str(file)!r}")
    if file.suffix == ".py":
        return _python_model(file)
    if file.suffix != ".toml":
        raise DataError(f"MODEL: expected a .toml or .py file, got {file.name!r}")
    try:
        spec = tomllib.loads(file.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise DataError(f"{file}: expected valid TOML, got {exc}") from None
    model, boxes = spec.get("model"), spec.get("bounds")
    if not isinstance(model, dict) or not isinstance(boxes, dict):
        raise DataError(f"{file}: expected the tables [model] and [bounds], got {sorted(spec)}")
    unknown = sorted(set(model) - _MODEL_KEYS) + sorted(set(boxes) - {"x0", "w", "v"})
    if unknown:
        raise DataError(f"{file}: expected keys of {sorted(_MODEL_KEYS)} and x0, w, v, got {unknown[0]!r}")
    for key in ("A", "C"):
        if key not in model:
            raise DataError(f"{file}: expected the key {key!r} in [model], got {sorted(model)}")
    if "x0" not in boxes:
        raise DataError(f"{file}: expected the key 'x0' in [bounds], got {sorted(boxes)}")
    options = {k: v for k, v in model.items() if k != "h"}
    for key in ("dA", "dB"):
        if key in options:
            options[key] = _pair(file, key, options[key])
    try:
        system = LTISystem(**options)
        bounds = Bounds(**{k: _pair(file, k, v) for k, v in boxes.items()})
        bounds.resolve(system)
    except IntervalObserverError as exc:
        raise DataError(f"{file}: {exc}") from None
    return ModelFile(system, bounds, _period(file, model.get("h")), file)


def _python_model(file: Path) -> ModelFile:
    """A model from a Python file defining ``system``, ``bounds`` and optionally ``h``."""
    try:
        found = runpy.run_path(str(file))
    except IntervalObserverError as exc:
        raise DataError(f"{file}: {exc}") from None
    except Exception as exc:  # a user's script: any failure is reported on one line
        raise DataError(f"{file}: expected a script that runs, got {type(exc).__name__}: {exc}") from None
    system, bounds = found.get("system"), found.get("bounds")
    if not isinstance(system, LTISystem) or not isinstance(bounds, Bounds):
        raise DataError(
            f"{file}: expected variables 'system' (an LTISystem) and 'bounds' (a Bounds), got "
            f"{type(system).__name__} and {type(bounds).__name__}"
        )
    try:
        bounds.resolve(system)
    except IntervalObserverError as exc:
        raise DataError(f"{file}: {exc}") from None
    return ModelFile(system, bounds, _period(file, found.get("h")), file)


def _pair(file: Path, key: str, value: Any) -> tuple[Any, Any]:
    if not isinstance(value, list) or len(value) != 2:
        raise DataError(f"{file}: expected {key} = [lower, upper], got {json.dumps(value)[:60]}")
    return value[0], value[1]


def _period(file: Path, h: Any) -> float | None:
    if h is None:
        return None
    if isinstance(h, bool) or not isinstance(h, (int, float)) or not (np.isfinite(h) and h > 0):
        raise DataError(f"{file}: expected h a positive number of seconds, got {h!r}")
    return float(h)


def read_record(path: str | Path, model: ModelFile, time: str | None = None) -> Record:
    """Read a measured record and match its columns to the model.

    Parameters
    ----------
    path : str or pathlib.Path
        A ``.csv`` file (comma-separated, one header line) or a ``.parquet`` file.
    model : ModelFile
        The model whose output and input names select the columns.
    time : str, optional
        Name of the time column (default: ``t`` or ``time``).

    Returns
    -------
    Record

    Raises
    ------
    DataError
        When the file is missing or unreadable, a column is missing, a value is not a number, a
        used column is empty or NaN on some lines (listed), or the times are not increasing with a
        uniform spacing (that of ``dt`` or ``h`` when the model gives one).
    """
    file = Path(path)
    if not file.is_file():
        raise DataError(f"DATA: expected an existing .csv or .parquet file, got {str(file)!r}")
    if file.suffix not in (".csv", ".parquet"):
        raise DataError(f"DATA: expected a .csv or .parquet file, got {file.name!r}")
    table = _ParquetTable(file) if file.suffix == ".parquet" else _CsvTable(file)
    system = model.system
    time_name = time if time is not None else next((c for c in _TIME_COLUMNS if c in table.header), None)
    wanted = [*system.output_names, *system.input_names]
    missing = [c for c in ([time_name] if time_name else []) + wanted if c not in table.header]
    if time_name is None or missing:
        what = f"a time column ({' or '.join(_TIME_COLUMNS)}) and " if time_name is None else ""
        raise DataError(
            f"{file}: expected {what}columns named as the model's outputs and inputs {wanted}, "
            f"got {table.header}: missing {missing}"
        )
    values = {time_name: table.times(time_name), **{name: table.numbers(name) for name in wanted}}
    empty = {name: ~np.isfinite(v) for name, v in values.items()}
    bad = np.any(list(empty.values()), axis=0)
    if bad.any():
        rows = np.flatnonzero(bad)
        shown = ", ".join(str(table.where(int(r))) for r in rows[:_SHOWN_LINES])
        more = f" and {rows.size - _SHOWN_LINES} more" if rows.size > _SHOWN_LINES else ""
        raise DataError(
            f"{file}: expected a number in every used column, got empty or NaN in "
            f"{[c for c, e in empty.items() if e.any()]} on {table.unit}s {shown}{more}"
        )
    t = values[time_name]
    h = _spacing(table, t, model)
    y = np.column_stack([values[n] for n in system.output_names])
    u = np.column_stack([values[n] for n in system.input_names]) if system.m else np.zeros((t.size, 0))
    return Record(t, y, u, h, file)


class _CsvTable:
    """A CSV file: a header line, then rows of comma-separated cells (blank lines skipped)."""

    unit = "line"

    def __init__(self, file: Path) -> None:
        self.file = file
        try:
            with file.open(newline="") as handle:
                reader = csv.reader(handle)
                self.header = [cell.strip() for cell in next(reader, [])]
                self.rows: list[list[str]] = []
                self.lines: list[int] = []
                for row in reader:
                    if not any(cell.strip() for cell in row):
                        continue
                    if len(row) != len(self.header):
                        raise DataError(
                            f"{file}: expected {len(self.header)} comma-separated fields on line "
                            f"{reader.line_num}, got {len(row)}"
                        )
                    self.rows.append(row)
                    self.lines.append(reader.line_num)
        except (OSError, UnicodeDecodeError, csv.Error) as exc:
            raise DataError(f"{file}: expected a readable CSV file, got {exc}") from None
        if not self.header or not self.rows:
            raise DataError(f"{file}: expected a header line and at least one row of values, got none")

    def where(self, row: int) -> int:
        """The line of the file holding ``row``."""
        return self.lines[row]

    def cells(self, name: str) -> list[str]:
        j = self.header.index(name)
        return [row[j].strip() for row in self.rows]

    def numbers(self, name: str) -> FloatArray:
        """The column as floats; an empty cell is NaN."""
        out = np.empty(len(self.rows))
        for i, cell in enumerate(self.cells(name)):
            try:
                out[i] = float(cell) if cell else np.nan
            except ValueError:
                raise DataError(
                    f"{self.file}: expected a number in column {name!r} on line {self.lines[i]}, got {cell!r}"
                ) from None
        return out

    def times(self, name: str) -> FloatArray:
        """The time column in seconds: numbers, or ISO 8601 datetimes counted from the first one."""
        cells = self.cells(name)
        first = next((c for c in cells if c), "")
        try:
            float(first)
        except ValueError:
            try:
                stamps = np.array([c or "NaT" for c in cells], dtype="datetime64[ns]")
            except ValueError:
                raise DataError(
                    f"{self.file}: expected seconds or ISO 8601 datetimes in column {name!r}, got {first!r}"
                ) from None
            return np.where(np.isnat(stamps), np.nan, (stamps - stamps[0]) / np.timedelta64(1, "s"))
        return self.numbers(name)


class _ParquetTable:
    """A Parquet file (read with pyarrow); rows are numbered from 1."""

    unit = "row"

    def __init__(self, file: Path) -> None:
        parquet = _tables.require("pyarrow.parquet", f"{file}: reading Parquet")
        try:
            self.table = parquet.read_table(file)
        except Exception as exc:  # pyarrow's own errors, reported on one line
            raise DataError(f"{file}: expected a readable Parquet file, got {exc}") from None
        self.file = file
        self.header = list(self.table.column_names)

    def where(self, row: int) -> int:
        """The 1-based number of ``row``."""
        return row + 1

    def numbers(self, name: str) -> FloatArray:
        """The column as floats (nulls are NaN)."""
        values = self.table.column(name).to_numpy(zero_copy_only=False)
        try:
            return np.asarray(values, dtype=float)
        except (TypeError, ValueError):
            raise DataError(f"{self.file}: expected numbers in column {name!r}, got {values.dtype}") from None

    def times(self, name: str) -> FloatArray:
        """The time column in seconds; timestamps count from the first one."""
        values = self.table.column(name).to_numpy(zero_copy_only=False)
        if np.issubdtype(values.dtype, np.datetime64):
            return np.where(np.isnat(values), np.nan, (values - values[0]) / np.timedelta64(1, "s"))
        return self.numbers(name)


def _spacing(table: _CsvTable | _ParquetTable, t: FloatArray, model: ModelFile) -> float:
    """The record's uniform sampling period, checked against the model's (``dt`` or ``h``)."""
    if t.size < 2:
        raise DataError(f"{table.file}: expected at least two samples, got {t.size}")
    steps = np.diff(t)
    expected = model.system.dt if model.system.dt is not None else model.h
    h = float(expected) if expected is not None else float(steps[0])
    tolerance = SPACING_TOLERANCE * h + _DECIMAL_TIME_ULPS * float(np.max(np.abs(t)))
    off = np.flatnonzero(np.abs(steps - h) > tolerance)
    if off.size:
        k = int(off[0])
        source = "the model's" if expected is not None else "that of the first two samples"
        raise DataError(
            f"{table.file}: expected uniformly spaced times (step {h:g}, {source}), got a step of {steps[k]:g} "
            f"from {table.unit} {table.where(k)} to {table.where(k + 1)}"
        )
    return h


def design_observer(model: ModelFile, h: float, observer: str = "tube") -> Observer:
    """Design one of :data:`OBSERVERS` for the model, sampled every ``h``.

    Parameters
    ----------
    model : ModelFile
        The model and bounds.
    h : float
        Sampling period of the record (``dt`` in discrete time).
    observer : str
        A key of :data:`OBSERVERS`.

    Returns
    -------
    Observer
    """
    from .observers.hull import HullEstimator
    from .observers.intersection import IntersectionObserver
    from .observers.interval_observer import IntervalObserver

    period = None if model.system.dt is not None else h
    if observer == "tube":
        return IntervalObserver.design(model.system, model.bounds, h=period)
    if observer == "framer":
        return IntervalObserver.design(model.system, model.bounds, h=period, method="framer")
    if observer == "intersection":
        return IntersectionObserver.design(model.system, model.bounds, h=period)
    if observer == "hull":
        return HullEstimator.design(model.system, model.bounds, h=period)
    raise DataError(f"observer: expected one of {[k for k in OBSERVERS if k != 'auto']}, got {observer!r}")


def estimate_record(model: ModelFile, record: Record, observer: str = "auto") -> Estimate:
    """Bounds of the states over a measured record.

    The observer runs on the uniform grid ``k·h`` (the record's times minus the first, so that
    decimal rounding of long time stamps does not fail the spacing check); the estimate carries the
    record's own times.

    Parameters
    ----------
    model : ModelFile
        The model and bounds.
    record : Record
        The measurements, matched to the model.
    observer : str
        A key of :data:`OBSERVERS`.

    Returns
    -------
    Estimate
        With ``meta["observer"]`` the observer's key.
    """
    grid = record.h * np.arange(record.t.size)
    if observer == "auto":
        from .front_door import observe

        estimate = observe(model.system, model.bounds, grid, record.y, record.u)
    else:
        estimate = design_observer(model, record.h, observer).run(grid, record.y, record.u)
    return replace(estimate, t=record.t, meta={**estimate.meta, "observer": observer, "time_unit": "s"})


def write_bounds(
    estimate: Estimate, out: str | Path, plot: bool = False, parquet: bool = False, source: dict[str, str] | None = None
) -> list[Path]:
    """Write an estimate of a record: ``bounds.csv``, ``bounds.npz``, ``summary.json`` (and a figure).

    ``bounds.csv`` has the column ``t`` and the columns of :meth:`Estimate.columns`
    (``NAME_lower``, ``NAME_upper``, ``NAME_width``); ``bounds.npz`` is :meth:`Estimate.save`;
    ``summary.json`` holds the record's size and span, the observer and its design facts (scalars),
    whether the data fit the model (``consistent``, and ``inconsistent_from``: the first time they do
    not, else null) and per state the width at the last bounded sample and its mean after the
    transient (over the bounded samples: from ``inconsistent_from`` on the bounds are NaN). It makes no
    claim about enclosure: there is no truth to compare with.

    Parameters
    ----------
    estimate : Estimate
        A single-run estimate.
    out : str or pathlib.Path
        Output folder (created).
    plot : bool
        Also draw ``bounds.png``.
    parquet : bool
        Also write ``bounds.parquet`` (needs pyarrow).
    source : dict of str to str, optional
        Where the model and the record came from, copied into the summary.

    Returns
    -------
    list of pathlib.Path
        The files written.
    """
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    columns = estimate.columns()
    written = [folder / "bounds.csv", folder / "bounds.npz", folder / "summary.json"]
    with written[0].open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["t", *(name for name, _ in columns)])
        table = np.column_stack([estimate.t, *(values for _, values in columns)])
        writer.writerows([repr(v) for v in row] for row in table.tolist())
    estimate.save(written[1])
    kept = estimate.bounded_rows()
    after = kept & (estimate.t >= estimate.transient)
    width = estimate.width()[kept]
    last = dict(zip(estimate.state_names, width[-1].tolist())) if width.size else None
    summary = {
        **(source or {}),
        "observer": estimate.meta.get("observer"),
        "method": estimate.meta.get("method"),
        "samples": int(estimate.t.size),
        "t_start": float(estimate.t[0]),
        "t_end": float(estimate.t[-1]),
        "transient_s": estimate.transient,
        "consistent": estimate.consistent,
        "inconsistent_from": estimate.inconsistent_from,
        "design": {k: v for k, v in _tables.plain(estimate.meta).items() if isinstance(v, (int, float, bool))},
        "final_width": last,
        "mean_width_after_transient": (
            dict(zip(estimate.state_names, estimate.width()[after].mean(axis=0).tolist())) if after.any() else last
        ),
    }
    written[2].write_text(json.dumps(summary, indent=2) + "\n")
    if parquet:
        pa = _tables.require("pyarrow", "bounds.parquet")
        arrays = {"t": estimate.t, **dict(columns)}
        _tables.require("pyarrow.parquet", "bounds.parquet").write_table(
            pa.table({k: np.asarray(v) for k, v in arrays.items()}), folder / "bounds.parquet"
        )
        written.append(folder / "bounds.parquet")
    if plot:
        from .plotting import save_figure

        save_figure(estimate.plot(time_unit="s"), folder / "bounds.png")
        written.append(folder / "bounds.png")
    return written


def example_model() -> tuple[LTISystem, Bounds, float]:
    """A small DC motor to start from: angle and speed, a voltage input, an encoder with noise.

    Returns
    -------
    system : LTISystem
        ``θ̇ = ω``, ``ω̇ = −8ω + 40u + w`` (uncertain friction: ``ΔA`` of ±0.4 on it), ``y = θ + v``.
    bounds : Bounds
        Initial angle within ±0.1 rad, speed within ±1 rad/s, ``|w| ≤ 0.5``, ``|v| ≤ 0.002`` rad.
    h : float
        Sampling period, 0.01 s.
    """
    system = LTISystem(
        [[0.0, 1.0], [0.0, -8.0]],
        C=[[1.0, 0.0]],
        B=[[0.0], [40.0]],
        dA=([[0.0, 0.0], [0.0, -0.4]], [[0.0, 0.0], [0.0, 0.4]]),
        state_names=["angle", "speed"],
        output_names=["encoder"],
        input_names=["voltage"],
    )
    bounds = Bounds(x0=([-0.1, -1.0], [0.1, 1.0]), w=([0.0, -0.5], [0.0, 0.5]), v=([-0.002], [0.002]))
    return system, bounds, 0.01


def write_model(path: str | Path, system: LTISystem, bounds: Bounds, h: float | None = None) -> Path:
    """Write a model file in the TOML form :func:`read_model` reads.

    Parameters
    ----------
    path : str or pathlib.Path
        Destination (``.toml``).
    system : LTISystem
        The model.
    bounds : Bounds
        Boxes of its unknowns.
    h : float, optional
        Sampling period to record (continuous time).

    Returns
    -------
    pathlib.Path
    """
    full = bounds.resolve(system)

    def line(key: str, value: Any) -> str:
        return f"{key} = {json.dumps(value, default=_tables.jsonable)}"

    model = [
        "[model]  # dx/dt = (A + dA) x + (B + dB) u + E w,  y = C x + F v  (x[k+1] = ... with dt)",
        line("A", system.A),
        line("C", system.C),
    ]
    if system.m:
        model.append(line("B", system.B))
    if not np.array_equal(system.E, np.eye(system.n)):
        model.append(line("E", system.E))
    if not np.array_equal(system.F, np.eye(system.p)):
        model.append(line("F", system.F))
    for key in ("dA", "dB"):
        if getattr(system, key) is not None:
            model.append(line(key, list(getattr(system, key))))
    if system.dt is not None:
        model.append(line("dt", system.dt))
    if h is not None:
        model.append(f"h = {h!r}  # sampling period of the records, seconds")
    model += [line(f"{kind}_names", getattr(system, f"{kind}_names")) for kind in ("state", "output", "input")]
    boxes = ["[bounds]  # [lower, upper] of the initial state, process noise w, measurement noise v"]
    boxes += [line(name, list(box)) for name, box in (("x0", full.x0), ("w", full.w), ("v", full.v))]
    file = Path(path)
    file.write_text("\n".join([*model, "", *boxes, ""]))
    return file


def write_example(folder: str | Path, seconds: float = 10.0, seed: int = 0) -> tuple[Path, Path, Path]:
    """Write a model file, a measured record and its truth to start from.

    The record is a simulation of :func:`example_model` with worst-case (bang-bang) noise and a
    square-wave voltage: ``motor.csv`` has the columns ``t``, ``encoder``, ``voltage`` (what a
    measurement would have), ``motor_truth.csv`` the true ``angle`` and ``speed``.

    Parameters
    ----------
    folder : str or pathlib.Path
        Output folder (created).
    seconds : float
        Length of the record.
    seed : int
        Seed of the simulated noise.

    Returns
    -------
    model, data, truth : pathlib.Path
        ``motor.toml``, ``motor.csv``, ``motor_truth.csv``.
    """
    from .simulate import simulate

    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    system, bounds, h = example_model()
    t = np.round(np.arange(0.0, seconds, h), 10)
    voltage = np.where(np.sin(2 * np.pi * 0.5 * t) >= 0, 1.0, -1.0)[:, None]
    sim = simulate(system, bounds, t, u=voltage, noise="extreme", seed=seed)
    model = write_model(out / "motor.toml", system, bounds, h)
    data, truth = out / "motor.csv", out / "motor_truth.csv"
    for file, names, values in (
        (data, [*system.output_names, *system.input_names], np.column_stack([sim.y, sim.u])),
        (truth, list(system.state_names), sim.x),
    ):
        with file.open("w", newline="") as handle:
            writer = csv.writer(handle)
            writer.writerow(["t", *names])
            writer.writerows([repr(v) for v in row] for row in np.column_stack([t, values]).tolist())
    return model, data, truth
