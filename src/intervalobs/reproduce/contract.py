"""The file contract of a reproduction (DESIGN.md): ``summary.json``, ``trajectories.npz``, figures.

Every reproduction builds its summary with :func:`base_summary` and writes it with
:func:`write_reproduction`, so that the keys, the enclosure rule and the JSON encoding live here once.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np
from numpy.typing import ArrayLike

from ..estimate import enclosure_report

__all__ = [
    "SUMMARY_KEYS",
    "Example",
    "base_summary",
    "check_reproduction",
    "to_json",
    "write_reproduction",
]


class _Reproduction(Protocol):
    """What an example runs: ``run(out_dir, seed, plots, full=True) -> summary``.

    ``full=False`` leaves out the analyses that only compare (tightness references, lower bounds, banks of
    estimators run for comparison): the paper's example, its observers and the enclosure check stay, and
    the folder still meets the file contract. ``intervalobs reproduce`` runs that way unless given
    ``--full``.
    """

    def __call__(self, out_dir: Path, seed: int, plots: bool, full: bool = True) -> dict[str, Any]:
        """Run the example, write the contract files into ``out_dir`` and return the summary."""
        ...


@dataclass(frozen=True)
class Example:
    """A reproducible example.

    Parameters
    ----------
    name : str
        CLI name, e.g. ``"aircraft-uio"``.
    seed_file : str
        Identifier of the source paper (``"-"`` for our own examples).
    description : str
        One line for ``intervalobs list``.
    run : callable
        ``run(out_dir, seed, plots, full=True) -> dict``: runs the example, writes the contract files
        into ``out_dir`` and returns the summary; ``full=False`` skips the comparison analyses.
    weight : float
        Rough cost of ``run(..., full=False)`` relative to the cheapest examples (1): ``intervalobs
        reproduce all`` starts the heaviest first, so that its processes finish together.
    """

    name: str
    seed_file: str
    description: str
    run: _Reproduction
    weight: float = 1.0


def to_json(value: Any) -> Any:
    """Convert NumPy arrays and scalars (recursively) to plain JSON types; NaN/inf become None.

    Parameters
    ----------
    value : object
        A scalar, array, or nested dict/list/tuple of them; complex numbers become ``{"re", "im"}``.

    Returns
    -------
    object
        The same structure made of dict, list, str, int, float, bool and None.
    """
    if isinstance(value, dict):
        return {str(k): to_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_json(v) for v in value]
    if isinstance(value, np.ndarray):
        return to_json(value.tolist())
    if isinstance(value, np.generic):
        return to_json(value.item())
    if isinstance(value, float) and not np.isfinite(value):
        return None
    if isinstance(value, complex):
        return {"re": value.real, "im": value.imag}
    return value


def base_summary(
    *,
    example: str,
    seed_file: str,
    observer: str,
    t: ArrayLike,
    x: ArrayLike,
    x_lower: ArrayLike,
    x_upper: ArrayLike,
    transient_s: float,
    d: ArrayLike | None = None,
    d_lower: ArrayLike | None = None,
    d_upper: ArrayLike | None = None,
) -> dict[str, Any]:
    """A summary with every contract key filled from the trajectories.

    ``design``, ``paper`` and ``runtime_s`` are left for the caller to fill. Enclosure uses the same
    rule as ``check_reproduction.py``; input enclosure skips samples whose bounds are not yet finite.

    Parameters
    ----------
    example : str
        Example name (CLI name).
    seed_file : str
        Identifier of the source paper (``"-"`` for our own examples).
    observer : str
        Name of the observer whose bounds are reported.
    t : array_like, shape (T,)
        Sample times.
    x : array_like, shape (T, n)
        True state.
    x_lower, x_upper : array_like, shape (T, n)
        State bounds.
    transient_s : float
        Time after which the method claims enclosure.
    d : array_like, shape (T, q), optional
        True unknown input, for observers that estimate inputs.
    d_lower, d_upper : array_like, shape (T, q), optional
        Unknown-input bounds (NaN where not available yet).

    Returns
    -------
    dict
        Every key of the ``summary.json`` contract; ``enclosure.input`` holds None values when no
        input bounds are given.
    """
    tt = np.asarray(t, dtype=float)
    xl, xx, xu = (np.asarray(a, dtype=float) for a in (x_lower, x, x_upper))
    after = tt >= transient_s
    state = enclosure_report(tt, xl, xx, xu, transient_s)
    width = xu - xl
    summary: dict[str, Any] = {
        "example": example,
        "seed": seed_file,
        "observer": observer,
        "dt": float(np.median(np.diff(tt))) if tt.size > 1 else 0.0,
        "t_final": float(tt[-1]),
        "steps": int(tt.size),
        "transient_s": float(transient_s),
        "enclosure": {"state": state.as_dict()},
        "width": {
            "state_mean": width[after].mean(axis=0).tolist(),
            "state_final": width[-1].tolist(),
            "input_mean": [],
        },
        "design": {},
        "paper": {},
        "runtime_s": {"design": 0.0, "run": 0.0},
    }
    if d is not None and d_lower is not None and d_upper is not None:
        dl, dd, du = (np.asarray(a, dtype=float) for a in (d_lower, d, d_upper))
        known = after & np.all(np.isfinite(dl) & np.isfinite(du), axis=1)
        start = float(tt[known][0]) if known.any() else np.inf
        summary["enclosure"]["input"] = enclosure_report(tt, dl, dd, du, max(start, transient_s)).as_dict()
        summary["width"]["input_mean"] = (du - dl)[known].mean(axis=0).tolist() if known.any() else []
    else:
        summary["enclosure"]["input"] = {"fraction": None, "max_violation": None}
    return summary


def write_reproduction(out_dir: Path, summary: dict[str, Any], trajectories: Mapping[str, ArrayLike]) -> None:
    """Write ``summary.json`` and ``trajectories.npz`` into ``out_dir`` (created if needed).

    Parameters
    ----------
    out_dir : pathlib.Path
        Output folder of one example, e.g. ``results/aircraft-uio``.
    summary : dict
        From :func:`base_summary`, completed by the caller; converted with :func:`to_json`.
    trajectories : mapping of str to array_like
        Arrays of the contract (``t``, ``x``, ``x_lower``, ``x_upper``, ...).
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "summary.json").write_text(json.dumps(to_json(summary), indent=2) + "\n")
    arrays: dict[str, Any] = {k: np.asarray(v) for k, v in trajectories.items()}
    np.savez_compressed(out_dir / "trajectories.npz", **arrays)


_FRACTION_TOLERANCE = 1e-12
"""How far a summary's claimed enclosure fraction may differ from the recomputed one (a ratio of counts
printed to full precision: any larger difference is a different count)."""


SUMMARY_KEYS = (
    "example",
    "seed",
    "observer",
    "dt",
    "t_final",
    "steps",
    "transient_s",
    "enclosure",
    "width",
    "design",
    "paper",
    "runtime_s",
)
"""Keys every ``summary.json`` has."""


def check_reproduction(folder: Path) -> list[str]:
    """Check a reproduction folder against the file contract, recomputing enclosure from the trajectories.

    The contract: ``summary.json`` has :data:`SUMMARY_KEYS`; ``trajectories.npz`` has ``t``, ``x``,
    ``x_lower``, ``x_upper``; after ``transient_s`` the recommended bounds and every other
    ``NAME_x_lower``/``NAME_x_upper`` pair (except those whose name contains ``naive``, kept to show how a
    naive method fails) are finite and contain ``x`` by the rule of
    :func:`~intervalobs.estimate.enclosure_report`; so do ``d_lower``/``d_upper`` around ``d`` where finite;
    and the state enclosure fraction in ``summary.json`` is the one the trajectories give.

    Parameters
    ----------
    folder : pathlib.Path
        A folder written by ``intervalobs reproduce NAME``, e.g. ``results/aircraft-uio``.

    Returns
    -------
    list of str
        One line per problem found; empty when the folder meets the contract.
    """
    try:
        summary = json.loads((folder / "summary.json").read_text())
        with np.load(folder / "trajectories.npz") as npz:
            arrays = {key: npz[key] for key in npz.files}
    except (OSError, ValueError) as exc:
        return [f"{folder}: cannot read summary.json and trajectories.npz ({exc})"]
    problems = [f"summary.json: no key {key!r}" for key in SUMMARY_KEYS if key not in summary]
    problems += [f"trajectories.npz: no array {key!r}" for key in ("t", "x", "x_lower", "x_upper") if key not in arrays]
    if problems:
        return problems
    t, x = arrays["t"], arrays["x"]
    transient = float(summary["transient_s"])
    after = t >= transient
    pairs = {"recommended": ("x_lower", "x_upper")}
    for key in arrays:
        if key.endswith("_x_lower") and "naive" not in key:
            pairs[key[: -len("_x_lower")]] = (key, key[: -len("_x_lower")] + "_x_upper")
    for name, (lower_key, upper_key) in pairs.items():
        if upper_key not in arrays:
            problems.append(f"{name}: {lower_key} has no {upper_key}")
            continue
        lower, upper = arrays[lower_key], arrays[upper_key]
        if not lower.shape == upper.shape == x.shape or x.shape[0] != t.size:
            problems.append(f"{name}: bounds of shape {lower.shape}, {upper.shape} for x {x.shape} and t {t.shape}")
            continue
        if not (np.all(np.isfinite(lower[after])) and np.all(np.isfinite(upper[after]))):
            problems.append(f"{name}: bounds not finite after the transient ({transient:g} s)")
            continue
        report = enclosure_report(t, lower, x, upper, transient)
        if report.fraction < 1.0:
            problems.append(
                f"{name}: truth outside the bounds by up to {report.max_violation:.3g} "
                f"(first at t = {report.first_violation_time:.6g})"
            )
        if name == "recommended":
            claimed = summary["enclosure"].get("state", {}).get("fraction")
            if claimed is None or abs(float(claimed) - report.fraction) > _FRACTION_TOLERANCE:
                problems.append(
                    f"summary.json: state enclosure fraction {claimed}, the trajectories give {report.fraction:.12g}"
                )
    if {"d", "d_lower", "d_upper"} <= arrays.keys():
        d_lower, d, d_upper = arrays["d_lower"], arrays["d"], arrays["d_upper"]
        known = after & np.all(np.isfinite(d_lower) & np.isfinite(d_upper), axis=1)
        report = enclosure_report(t[known], d_lower[known], d[known], d_upper[known])
        if report.fraction < 1.0:
            problems.append(f"input bounds: truth outside by up to {report.max_violation:.3g}")
    return problems
