"""Tables of time-stamped channels, shared by the exports of :class:`~intervalobs.estimate.Estimate` and
:class:`~intervalobs.simulate.Simulation`: pandas and xarray are optional (the ``data`` extra) and
imported here only, with a one-line error naming the extra when they are missing.

A table is indexed by time ``t`` (and by ``run`` first when it holds Monte Carlo runs); its columns
are named channels, each a (T,) or (M, T) array.
"""

from __future__ import annotations

import importlib
import json
from types import ModuleType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .errors import DataError

FloatArray = NDArray[np.float64]


def require(module: str, caller: str) -> ModuleType:
    """Import an optional dependency of the ``data`` extra, or raise a one-line ``ImportError``."""
    try:
        return importlib.import_module(module)
    except ImportError:
        raise ImportError(
            f"{caller}: expected {module} to be installed (pip install 'intervalobs[data]'), got none"
        ) from None


def jsonable(value: Any) -> Any:
    """``value`` with NumPy arrays and scalars as lists and numbers, anything else unknown as a string."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return str(value)


def plain(meta: dict[str, Any]) -> dict[str, Any]:
    """A JSON-compatible copy of ``meta`` (what ``attrs`` of a table or dataset holds)."""
    return dict(json.loads(json.dumps(meta, default=jsonable)))


def to_frame(t: FloatArray, columns: list[tuple[str, FloatArray]], attrs: dict[str, Any], caller: str) -> Any:
    """A pandas ``DataFrame`` of the named (T,) or (M, T) channels, indexed by ``t`` (or by ``run`` and ``t``)."""
    pd = require("pandas", caller)
    names = [name for name, _ in columns]
    repeated = sorted({n for n in names if names.count(n) > 1})
    if repeated:
        raise DataError(f"{caller}: expected distinct column names, got {repeated[0]!r} twice (rename a channel)")
    runs = np.shape(columns[0][1])[0] if columns and np.ndim(columns[0][1]) == 2 else None
    if runs is None:
        index = pd.Index(t, name="t")
    else:
        index = pd.MultiIndex.from_product([range(runs), t], names=["run", "t"])
    frame = pd.DataFrame({name: np.reshape(v, -1) for name, v in columns}, index=index)
    frame.attrs.update(attrs)
    return frame


def from_frame(frame: Any, caller: str) -> tuple[FloatArray, dict[str, FloatArray], dict[str, Any]]:
    """Times, every column as a (T,) or (M, T) array, and the attributes of a table written by :func:`to_frame`."""
    if not (hasattr(frame, "index") and hasattr(frame, "columns")):
        raise DataError(f"{caller}: expected a pandas DataFrame, got {type(frame).__name__}")
    index = frame.index
    if getattr(index, "nlevels", 1) == 2:
        runs = index.get_level_values(0).unique()
        t = np.asarray(index.get_level_values(1)[: len(index) // max(len(runs), 1)], dtype=float)
        shape: tuple[int, ...] = (len(runs), t.size)
        if len(index) != len(runs) * t.size:
            raise DataError(f"{caller}: expected every run to have the same {t.size} times, got {len(index)} rows")
    else:
        t = np.asarray(index, dtype=float)
        shape = (t.size,)
    columns = {str(c): np.asarray(frame[c], dtype=float).reshape(shape) for c in frame.columns}
    return t, columns, dict(frame.attrs)


def to_dataset(
    t: FloatArray,
    variables: dict[str, tuple[FloatArray, str, tuple[str, ...]]],
    attrs: dict[str, Any],
    caller: str,
) -> Any:
    """An xarray ``Dataset``: each variable ``(values (..., T, k), channel dimension, channel names)``."""
    xr = require("xarray", caller)
    data_vars = {}
    coords: dict[str, Any] = {"t": t}
    for name, (values, dim, names) in variables.items():
        dims = ("run", "t", dim) if np.ndim(values) == 3 else ("t", dim)
        data_vars[name] = (dims, values)
        coords[dim] = list(names)
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)
