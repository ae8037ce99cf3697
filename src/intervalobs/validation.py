"""Validation of user input at the boundary of the library.

Every model class, observer and simulation converts its arguments through these functions, so that a
wrong shape, an empty interval, a count of zero or a missing file is reported once, in one line with
the argument's name, the expected and the actual value, and never surfaces as a traceback from deep
inside NumPy. The command-line interface converts its options through the same functions
(:mod:`intervalobs.cli_types`).
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Literal, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._docstrings import shared_docs
from .errors import ArgumentError, ArgumentTypeError, BoundsError, DataError, DimensionError, FileError

__all__ = [
    "as_array",
    "as_box",
    "as_choice",
    "as_count",
    "as_fraction",
    "as_input_path",
    "as_instance",
    "as_matrix",
    "as_names",
    "as_output_folder",
    "as_positive",
    "as_signal",
    "as_time",
    "as_truth",
    "as_vector",
    "check_both_or_neither",
    "check_finite",
    "check_no_kwargs",
    "labelled_parts",
]

FloatArray = NDArray[np.float64]
T = TypeVar("T")


def _named(name: str, message: str) -> str:
    """``"name: message"``; the bare message when ``name`` is empty (argparse adds the option's name)."""
    return f"{name}: {message}" if name else message


@shared_docs
def as_array(name: str, value: ArrayLike) -> FloatArray:
    """Convert ``value`` to a float array of any shape, refusing what the conversion would lose.

    NumPy would turn complex numbers into their real parts (with a ``ComplexWarning``) and text such as
    ``"0.1"`` into numbers; both hide a mistake of the caller, so both are refused. Complex values whose
    imaginary parts are all exactly zero lose nothing and are accepted.

    %(argument_name)s
    value : array_like
        The user's value.

    Returns
    -------
    numpy.ndarray
        ``value`` as float64, same shape.

    Raises
    ------
    ArgumentTypeError
        When ``value`` holds text, complex numbers with a nonzero imaginary part, or objects that are
        not numbers.
    """
    if value is None:
        raise ArgumentTypeError(_named(name, "expected a numeric array, got None"))
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as exc:  # ragged nested sequences
        raise ArgumentTypeError(_named(name, f"expected a numeric array, got {type(value).__name__}")) from exc
    if raw.dtype.kind in "USV":
        raise ArgumentTypeError(_named(name, f"expected real numbers, got text ({raw.dtype})"))
    if raw.dtype.kind == "c":
        imaginary = float(np.max(np.abs(raw.imag), initial=0.0))
        if imaginary != 0.0:
            raise ArgumentTypeError(
                _named(name, f"expected real numbers, got complex values (largest imaginary part {imaginary:g})")
            )
        raw = raw.real
    if raw.dtype.kind == "O" and any(v is None or isinstance(v, (str, bytes, complex)) for v in raw.flat):
        raise ArgumentTypeError(_named(name, "expected real numbers, got None, text or complex entries"))
    try:
        return np.array(raw, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ArgumentTypeError(_named(name, f"expected a numeric array, got {type(value).__name__}")) from exc


@shared_docs
def as_matrix(
    name: str, value: ArrayLike, shape: tuple[int | None, int | None] = (None, None), finite: bool = True
) -> FloatArray:
    """Convert ``value`` to a 2-D float array and check its shape.

    %(argument_name)s
    value : array_like
        Matrix; a scalar or a 1-D array is accepted where the expected shape makes it unambiguous
        (a scalar for a 1×1 matrix, a 1-D array for one row or one column).
    shape : tuple of int or None
        Expected shape; ``None`` leaves a dimension free.
    finite : bool
        Reject NaN and inf.

    Returns
    -------
    numpy.ndarray
        The matrix, shape ``shape``.
    """
    arr = as_array(name, value)
    rows, cols = shape
    if arr.ndim == 0:
        arr = arr.reshape(1, 1)
    elif arr.ndim == 1:
        if cols == 1 and rows in (None, arr.size):
            arr = arr.reshape(-1, 1)
        elif rows == 1 or rows is None or cols in (None, arr.size):
            arr = arr.reshape(1, -1)
    if arr.ndim != 2 or (rows is not None and arr.shape[0] != rows) or (cols is not None and arr.shape[1] != cols):
        want = "×".join("any" if d is None else str(d) for d in shape)
        raise DimensionError(f"{name}: expected shape {want}, got {np.shape(value)}")
    if finite and not np.all(np.isfinite(arr)):
        raise BoundsError(f"{name}: expected finite entries, got NaN or inf")
    return arr


@shared_docs
def as_vector(name: str, value: ArrayLike, size: int | None = None, finite: bool = True) -> FloatArray:
    """Convert ``value`` to a 1-D float array of length ``size`` (a scalar is broadcast).

    %(argument_name)s
    value : array_like
        The user's value.
    size : int, optional
        Expected length (any length when None).
    finite : bool
        Reject NaN and inf entries.

    Returns
    -------
    numpy.ndarray, shape (size,)

    Raises
    ------
    DimensionError
        When ``value`` is not numeric or not a vector of length ``size``.
    BoundsError
        When ``finite`` and an entry is NaN or inf.
    """
    arr = as_array(name, value)
    if arr.ndim == 0 and size is not None:
        arr = np.full(size, float(arr))
    if arr.ndim != 1 or (size is not None and arr.size != size):
        raise DimensionError(f"{name}: expected a vector of length {size}, got shape {np.shape(value)}")
    if finite and not np.all(np.isfinite(arr)):
        raise BoundsError(f"{name}: expected finite entries, got NaN or inf")
    return arr


@shared_docs
def as_box(
    name: str, value: Sequence[ArrayLike] | tuple[ArrayLike, ArrayLike], size: int | None = None
) -> tuple[FloatArray, FloatArray]:
    """Convert a ``(lower, upper)`` pair to two finite vectors with ``lower <= upper``.

    %(argument_name)s
    value : tuple of array_like
        ``(lower, upper)``; scalars are broadcast to ``size``.
    size : int, optional
        Expected length.

    Returns
    -------
    lower, upper : numpy.ndarray
    """
    if not isinstance(value, (tuple, list)) or len(value) != 2:
        raise BoundsError(f"{name}: expected a (lower, upper) pair, got {type(value).__name__}")
    lower = as_vector(f"{name} lower", value[0], size)
    upper = as_vector(f"{name} upper", value[1], size if size is not None else lower.size)
    if lower.shape != upper.shape:
        raise DimensionError(f"{name}: lower has shape {lower.shape}, upper has shape {upper.shape}")
    bad = np.flatnonzero(lower > upper)
    if bad.size:
        i = int(bad[0])
        raise BoundsError(f"{name}: expected lower <= upper, got lower[{i}]={lower[i]:g} > upper[{i}]={upper[i]:g}")
    return lower, upper


@shared_docs
def as_time(name: str, value: ArrayLike) -> FloatArray:
    """Convert a time vector: 1-D, finite, strictly increasing, at least one sample.

    Datetimes and durations (NumPy ``datetime64``/``timedelta64``, a pandas ``DatetimeIndex`` or
    ``TimedeltaIndex``) become seconds, datetimes counted from the first sample.

    %(argument_name)s
    value : array_like
        The user's time vector.

    Returns
    -------
    numpy.ndarray, shape (T,)

    Raises
    ------
    DimensionError
        When ``value`` is not a non-empty 1-D array.
    DataError
        When a time is not finite or the times do not increase strictly.
    """
    arr = as_array(name, _seconds(value))
    if arr.ndim != 1 or arr.size == 0:
        raise DimensionError(f"{name}: expected a non-empty 1-D time vector, got shape {np.shape(value)}")
    if not np.all(np.isfinite(arr)):
        raise DataError(f"{name}: expected finite times, got NaN or inf")
    if arr.size > 1 and np.any(np.diff(arr) <= 0):
        raise DataError(f"{name}: expected strictly increasing times")
    return arr


@shared_docs
def as_signal(
    name: str,
    value: ArrayLike,
    steps: int,
    width: int,
    t: FloatArray | None = None,
    names: Sequence[str] | None = None,
    missing: bool = False,
) -> FloatArray:
    """Convert a time-first signal of shape (T, width) or (M, T, width) and check it is finite.

    A 1-D array is read as (T,) when ``width == 1``. A pandas ``Series``/``DataFrame`` or an xarray
    ``DataArray`` is accepted too (see :func:`labelled_parts`): its channels are taken by name when
    they are labelled with strings (every name of ``names`` must be there; other columns are
    ignored; a model whose names are the defaults ``y1``, ``y2`` … takes as many columns by
    position), in order otherwise, and its time index, when it has one, must be ``t``.

    %(argument_name)s
    value : array_like, pandas.Series, pandas.DataFrame or xarray.DataArray
        The user's signal.
    steps : int
        Expected number of samples ``T``.
    width : int
        Expected number of channels.
    t : numpy.ndarray, shape (T,), optional
        The record's times, checked against a labelled signal's time index.
    names : sequence of str, optional
        The channels' names in the model (e.g. ``LTISystem.output_names``).
    missing : bool
        Accept rows that are entirely NaN: no sample at that time (NaN means nothing else).

    Returns
    -------
    numpy.ndarray, shape (T, width) or (M, T, width)

    Raises
    ------
    DataError
        When the shape is wrong, a value is NaN or inf, a named channel is missing or the time index
        differs from ``t``.
    """
    parts = labelled_parts(value)
    if parts is not None:
        value = _select_channels(name, *parts, t=t, names=names)
    arr = as_array(name, value)
    if arr.ndim == 1 and width == 1:
        arr = arr.reshape(-1, 1)
    if arr.ndim not in (2, 3) or arr.shape[-2:] != (steps, width):
        raise DataError(f"{name}: expected shape ({steps}, {width}) or (runs, {steps}, {width}), got {arr.shape}")
    check_finite(name, arr, missing)
    return arr


@shared_docs
def check_finite(name: str, values: FloatArray, missing: bool = False) -> None:
    """Refuse NaN and inf in a signal; with ``missing``, a row (last axis) entirely NaN is a missing sample.

    %(argument_name)s
    values : numpy.ndarray, shape (..., width)
        The signal (one sample or a record).
    missing : bool
        Accept rows that are entirely NaN.

    Raises
    ------
    DataError
        At the first value that is inf, or NaN in a row that is not entirely NaN (or NaN at all
        without ``missing``).
    """
    bad = ~np.isfinite(values)
    if missing:
        bad &= ~np.all(np.isnan(values), axis=-1, keepdims=True)
    if np.any(bad):
        where = tuple(int(i) for i in np.argwhere(bad)[0])
        allowed = " (a missing sample is a row of NaN)" if missing else ""
        raise DataError(f"{name}: expected finite values{allowed}, got NaN or inf at index {where}")


@shared_docs
def as_truth(name: str, value: Any, t: FloatArray, names: Sequence[str]) -> FloatArray:
    """The true state of a record, time-first, from an array, a simulation or a python-control response.

    Accepted: an array of shape (T, n) or (M, T, n); any simulation of the library (its ``x``:
    :class:`~intervalobs.simulate.Simulation`, ``SampledSimulation`` on its grid, ``NonlinearSimulation``);
    a python-control ``TimeResponseData`` (its ``states``, which python-control stores time-last, (n, T)
    or (n, M, T): moved to time-first here); a pandas ``DataFrame`` or an xarray ``DataArray``. The last
    three carry times, which must be ``t``, and state labels, which select
    the states by ``names`` when they are all there (in order otherwise).

    %(argument_name)s
    value : array_like, Simulation, control.TimeResponseData, pandas.DataFrame or xarray.DataArray
        The truth.
    t : numpy.ndarray, shape (T,)
        The times of the bounds it is compared with.
    names : sequence of str
        The state names of those bounds.

    Returns
    -------
    numpy.ndarray, shape (T, n) or (M, T, n)

    Raises
    ------
    DataError
        When the truth's times are not ``t``.
    """
    parts: tuple[Any, Any, Any] | None
    if hasattr(value, "states") and hasattr(value, "time"):  # python-control's TimeResponseData
        if value.states is None:
            raise DataError(f"{name}: expected a response with states (return_x=True), got none")
        parts = (np.moveaxis(np.asarray(value.states, dtype=float), 0, -1), _seconds(value.time), value.state_labels)
    elif dataclasses.is_dataclass(value) and hasattr(value, "x"):  # any of the library's simulations
        if not hasattr(value, "t"):  # NonlinearSimulation: time-first, on the samples
            return as_array(name, value.x)
        names_of = getattr(value, "state_names", None)
        times = value.t  # type: ignore[union-attr]  # checked above
        parts = (value.x, times, None if names_of is None else list(names_of))
    else:
        parts = labelled_parts(value)
    if parts is None:
        return as_array(name, value)
    values, times, channels = parts
    if channels is not None and not all(c in channels for c in names):
        channels = None  # labels that are not the state names: positional
    return as_array(name, _select_channels(name, values, times, channels, t=t, names=names))


@shared_docs
def as_names(name: str, value: Sequence[str] | None, size: int, prefix: str) -> tuple[str, ...]:
    """Names of ``size`` channels: the given ones, or ``prefix1 … prefixN`` when None.

    %(argument_name)s
    value : sequence of str or None
        The user's names: distinct, non-empty strings, one per channel.
    size : int
        Number of channels.
    prefix : str
        Stem of the default names (``"x"`` gives ``x1, x2, …``).

    Returns
    -------
    tuple of str

    Raises
    ------
    DimensionError
        When the number of names is not ``size``, a name is not a non-empty string or a name repeats.
    """
    if value is None:
        return tuple(f"{prefix}{i + 1}" for i in range(size))
    if isinstance(value, str) or not all(isinstance(v, str) and v for v in value):
        raise DimensionError(f"{name}: expected a sequence of {size} non-empty strings, got {value!r}")
    names = tuple(value)
    if len(names) != size:
        raise DimensionError(f"{name}: expected {size} names, got {len(names)}: {list(names)}")
    repeated = sorted({v for v in names if names.count(v) > 1})
    if repeated:
        raise DimensionError(f"{name}: expected distinct names, got {repeated[0]!r} more than once")
    return names


def labelled_parts(value: Any) -> tuple[Any, FloatArray | None, list[str] | None] | None:
    """Split a pandas ``Series``/``DataFrame`` or an xarray ``DataArray`` into values, times and channel names.

    Neither library is imported: the objects are recognised by their attributes. A pandas
    ``RangeIndex`` (the default of a frame built from a bare array) and an xarray time dimension
    without a coordinate carry no time. The time dimension of a ``DataArray`` is the one named
    ``t`` or ``time``, else the one before the last (the only one for 1-D data); it is moved there.

    Parameters
    ----------
    value : object
        Anything; only pandas and xarray objects are split.

    Returns
    -------
    tuple or None
        ``(values, times in seconds or None, channel names or None)``, or None for anything else.
    """
    if hasattr(value, "dims") and hasattr(value, "coords") and hasattr(value, "transpose"):
        dims = list(value.dims)
        if not dims:
            return None
        time_dim = next((d for d in dims if d in ("t", "time")), dims[-2] if len(dims) > 1 else dims[0])
        if len(dims) > 1 and dims.index(time_dim) != len(dims) - 2:
            others = [d for d in dims if d != time_dim]
            value = value.transpose(*others[:-1], time_dim, others[-1])
            dims = list(value.dims)
        times = _seconds(value.coords[time_dim].values) if time_dim in value.coords else None
        channels = None
        if len(dims) > 1 and dims[-1] in value.coords:
            channels = value.coords[dims[-1]].values.tolist()
        return value.values, times, channels
    if hasattr(value, "index") and hasattr(value, "to_numpy"):
        index = value.index
        times = None if type(index).__name__ == "RangeIndex" else _seconds(index)
        columns = list(value.columns) if hasattr(value, "columns") else None
        return value.to_numpy(), times, columns
    return None


def _select_channels(
    name: str,
    values: Any,
    times: FloatArray | None,
    channels: list[Any] | None,
    *,
    t: FloatArray | None,
    names: Sequence[str] | None,
) -> Any:
    """The channels of a labelled signal in the model's order, after checking its time index against ``t``."""
    if times is not None and t is not None:
        if times.size != t.size:
            raise DataError(f"{name}: expected {t.size} samples (those of t), got a time index of {times.size}")
        scale = max(float(np.max(np.abs(t))), float(np.max(np.diff(t))) if t.size > 1 else 1.0, 1e-300)
        off = np.abs(times - t) > 1e-9 * scale
        if off.any():
            k = int(np.argmax(off))
            raise DataError(
                f"{name}: expected its time index to be t, got {times[k]:g} at sample {k} where t = {t[k]:g}"
            )
    if channels is None or names is None or not any(isinstance(c, str) for c in channels):
        return values  # unlabelled channels (or no model names): taken in order, as for an array
    missing = [n for n in names if n not in channels]
    if missing and len(channels) == len(names) and _default_names(names):
        return values  # a model with unnamed channels (y1, y2, …): the columns are matched by position
    if missing:
        raise DataError(
            f"{name}: expected columns named {list(names)} (the model's names), got {channels}: missing {missing}"
        )
    return np.take(np.asarray(values), [channels.index(n) for n in names], axis=-1)


def _default_names(names: Sequence[str]) -> bool:
    """Whether ``names`` are the default names of a model's channels: one letter and 1, 2, … (``y1``, ``y2``)."""
    prefix = names[0][:1] if names else ""
    return bool(names) and list(names) == [f"{prefix}{i + 1}" for i in range(len(names))]


def _seconds(value: Any) -> Any:
    """Datetimes as seconds since the first one, durations as seconds; anything else unchanged."""
    if getattr(value, "tz", None) is not None:
        value = value.tz_convert(None)
    kind = getattr(getattr(value, "dtype", None), "kind", None)
    if kind not in ("M", "m"):
        return value
    arr = np.asarray(value)
    if kind == "M":
        arr = arr - arr[0]
    return arr / np.timedelta64(1, "s")


def check_no_kwargs(function: str, kwargs: dict[str, Any], allowed: Sequence[str] = ()) -> None:
    """Raise ``TypeError`` naming the first keyword of ``kwargs`` that is not in ``allowed``.

    Every public function that takes ``**kwargs`` calls this first, so a misspelt option fails loudly
    instead of being ignored (``tests/test_kwargs.py`` checks it).

    Parameters
    ----------
    function : str
        Name of the calling function, used in the message.
    kwargs : dict of str to object
        The keywords the caller received.
    allowed : sequence of str
        The keywords it understands.

    Raises
    ------
    TypeError
        ``"<function>: unexpected keyword argument '<name>'; allowed: [...]"``.
    """
    unknown = [k for k in kwargs if k not in allowed]
    if unknown:
        raise ArgumentTypeError(f"{function}: unexpected keyword argument {unknown[0]!r}; allowed: {sorted(allowed)}")


def _describe(value: object) -> str:
    """``repr`` of a scalar argument plus its type when the repr does not show it (``'0.1' (str)``)."""
    shown = repr(value)
    return (
        shown
        if isinstance(value, (int, float)) and not isinstance(value, bool)
        else f"{shown} ({type(value).__name__})"
    )


@shared_docs
def as_count(name: str, value: object, minimum: int = 1) -> int:
    """Check that ``value`` is an integer of at least ``minimum`` (runs, workers, a seed, a batch size).

    %(argument_name)s
    value : object
        The user's value; a ``bool`` or a float is refused even when it is integral.
    minimum : int
        Smallest accepted value.

    Returns
    -------
    int

    Raises
    ------
    ArgumentTypeError
        When ``value`` is not an integer.
    ArgumentError
        When ``value < minimum``.
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ArgumentTypeError(_named(name, f"expected an integer >= {minimum}, got {_describe(value)}"))
    if value < minimum:
        raise ArgumentError(_named(name, f"expected an integer >= {minimum}, got {value}"))
    return int(value)


def _as_real(name: str, value: object, expected: str) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ArgumentTypeError(_named(name, f"expected {expected}, got {_describe(value)}"))
    return float(value)


@shared_docs
def as_fraction(name: str, value: object) -> float:
    """Check that ``value`` is a fraction in [0, 1) (a relative uncertainty level: 0.05 means ±5 %).

    %(argument_name)s
    value : object
        The user's value.

    %(not_real)s
    ArgumentError
        When ``value`` is outside [0, 1).
    """
    expected = "a fraction in [0, 1) (0.05 means ±5 %)"
    fraction = _as_real(name, value, expected)
    if not 0.0 <= fraction < 1.0:
        raise ArgumentError(_named(name, f"expected {expected}, got {fraction:g}"))
    return fraction


@shared_docs
def as_positive(name: str, value: object, what: str = "a positive number") -> float:
    """Check that ``value`` is a finite real number > 0 (a sampling period, a step, a time-out).

    %(argument_name)s
    value : object
        The user's value; text such as ``"0.1"`` is refused.
    what : str
        What the value is, for the message ("a positive sampling period").

    %(not_real)s
    ArgumentError
        When ``value`` is not finite and positive.
    """
    number = _as_real(name, value, what)
    if not (math.isfinite(number) and number > 0.0):
        raise ArgumentError(_named(name, f"expected {what}, got {number:g}"))
    return number


@shared_docs
def as_choice(name: str, value: T, choices: Sequence[T]) -> T:
    """Check that ``value`` is one of ``choices`` (a method name, an objective, an example).

    %(argument_name)s
    value : object
        The user's value.
    choices : sequence
        The accepted values.

    Returns
    -------
    object
        ``value``, one of ``choices``.

    Raises
    ------
    ArgumentError
        When ``value`` is not in ``choices``.
    """
    if value not in choices:
        raise ArgumentError(_named(name, f"expected one of {', '.join(map(repr, choices))}, got {value!r}"))
    return value


@shared_docs
def as_instance(name: str, value: object, kind: type[T], what: str) -> T:
    """Check that ``value`` is an instance of ``kind``.

    %(argument_name)s
    value : object
        The user's value.
    kind : type
        The expected class.
    what : str
        What is expected, for the message ("the state returned by init or step").

    Returns
    -------
    object
        ``value``, an instance of ``kind``.

    Raises
    ------
    ArgumentTypeError
        When ``value`` is not a ``kind``.
    """
    if not isinstance(value, kind):
        raise ArgumentTypeError(_named(name, f"expected {what}, got {type(value).__name__}"))
    return value


def check_both_or_neither(first: tuple[str, object], second: tuple[str, object]) -> None:
    """Check that two optional arguments that only make sense together are both given or both omitted.

    Parameters
    ----------
    first, second : tuple of (str, object)
        Each argument's name and value (None when omitted).

    Raises
    ------
    ArgumentError
        When exactly one of them is None.
    """
    (name1, value1), (name2, value2) = first, second
    if (value1 is None) != (value2 is None):
        given, missing = (name1, name2) if value2 is None else (name2, name1)
        raise ArgumentError(f"{name1}, {name2}: expected both or neither, got {given} without {missing}")


@shared_docs
def as_output_folder(name: str, path: str | Path) -> Path:
    """Check, before anything is computed, that results can be written into the folder ``path``.

    The folder need not exist: its nearest existing ancestor must be a folder in which a file can
    be created (tried with a temporary file, which is removed). Nothing is created.

    %(argument_name)s
    path : str or pathlib.Path
        The output folder.

    Returns
    -------
    pathlib.Path
        ``path``, which may not exist yet.

    Raises
    ------
    FileError
        When ``path`` or an ancestor is a file, or the folder cannot be written.
    """
    folder = Path(path)
    existing = folder
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        raise FileError(_named(name, f"expected a folder to write into, got {str(path)!r} ({existing} is a file)"))
    try:
        with tempfile.TemporaryFile(dir=existing):
            pass
    except OSError:
        raise FileError(
            _named(name, f"expected a writable folder, got {str(path)!r} (cannot create a file in {existing})")
        ) from None
    return folder


@shared_docs
def as_input_path(name: str, path: str | Path, kind: Literal["file", "folder"] = "file") -> Path:
    """Check that the file (or folder) ``path`` exists.

    %(argument_name)s
    path : str or pathlib.Path
        A file or folder to read.
    kind : {"file", "folder"}
        What ``path`` must be.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    FileError
        When ``path`` does not exist or is not a ``kind``.
    """
    found = Path(path)
    if not (found.is_dir() if kind == "folder" else found.is_file()):
        state = ("a file" if kind == "folder" else "a folder") if found.exists() else f"no such {kind}"
        raise FileError(_named(name, f"expected an existing {kind}, got {str(path)!r} ({state})"))
    return found
