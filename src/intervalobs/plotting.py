"""Figures (matplotlib only). Functions take estimates and truth and return the figure."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import DimensionError

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from .estimate import Estimate

FloatArray = NDArray[np.float64]

__all__ = ["plot_estimate", "plot_psi", "plot_widths", "save_figure"]


def plot_estimate(
    estimate: Estimate,
    truth: Any = None,
    labels: Sequence[str] | None = None,
    inputs: bool = False,
    input_truth: ArrayLike | None = None,
    run: int | None = None,
    ax: Axes | Sequence[Axes] | None = None,
    time_unit: str | None = None,
) -> Figure:
    """One panel per state (and per unknown input): the bounds as a band, the truth as a line.

    A Monte Carlo estimate (bounds of shape (M, T, n)) is drawn for the run ``run``, or, when ``run``
    is None, as the envelope of all runs (lowest lower and highest upper bound at each time) with
    every run's truth as a thin line. When the data contradict the model, the bands stop at
    ``estimate.inconsistent_from`` (NaN rows), marked by a dashed red line.

    Parameters
    ----------
    estimate : Estimate
        Single-run (bounds (T, n)) or Monte Carlo (bounds (M, T, n)) estimate.
    truth : array_like, shape (T, n) or (M, T, n), Simulation or control.TimeResponseData, optional
        True state; of a :class:`~intervalobs.simulate.Simulation`, its ``x``, of a python-control
        response, its ``states`` made time-first (see :func:`intervalobs.validation.as_truth`).
    labels : sequence of str, optional
        Panel labels, states first, then unknown inputs (default: the estimate's state and input names).
    inputs : bool
        Also plot the unknown-input bounds.
    input_truth : array_like, shape (T, q) or (M, T, q), optional
        True unknown input.
    run : int, optional
        The run to draw when the estimate or the truth has a run axis; None: the envelope over runs.
    ax : matplotlib.axes.Axes or sequence of Axes, optional
        Where to draw, one axes per panel (a single Axes when there is one panel); default: a new
        figure with the panels stacked.
    time_unit : str, optional
        Unit of ``estimate.t`` for the time axis label (default ``estimate.meta["time_unit"]`` if
        present, else no unit).

    Returns
    -------
    matplotlib.figure.Figure
        The figure holding the panels (that of ``ax`` when given).

    Raises
    ------
    DimensionError
        When ``truth``, ``input_truth``, ``run`` or ``ax`` does not match the estimate.
    """
    from matplotlib.figure import SubFigure

    from .validation import as_truth

    times = estimate.t
    state_truth = None if truth is None else as_truth("truth", truth, times, estimate.state_names)
    blocks: list[tuple[str, FloatArray, FloatArray, ArrayLike | None, Sequence[str]]] = [
        ("truth", estimate.lower, estimate.upper, state_truth, estimate.state_names)
    ]
    if inputs and estimate.input_lower is not None and estimate.input_upper is not None:
        blocks.append(("input_truth", estimate.input_lower, estimate.input_upper, input_truth, estimate.input_names))
    panels = [_panel_data(*block, run, times.size) for block in blocks]
    count = sum(lower.shape[-1] for _, lower, _, _ in panels)
    if labels is not None and len(labels) != count:
        raise DimensionError(f"labels: expected {count} labels (one per panel), got {len(labels)}")
    axes = _panel_axes(ax, count)
    names = (
        list(labels) if labels is not None else [name for names, lo, _, _ in panels for name in names[: lo.shape[-1]]]
    )
    batch = run is None and estimate.lower.ndim == 3
    band = f"envelope of {estimate.lower.shape[0]} runs" if batch else "bounds"
    row = 0
    for _, lower, upper, true in panels:
        for i in range(lower.shape[-1]):
            axis = axes[row]
            axis.fill_between(times, lower[:, i], upper[:, i], color="tab:blue", alpha=0.25, lw=0, label=band)
            axis.plot(times, lower[:, i], color="tab:blue", lw=0.8)
            axis.plot(times, upper[:, i], color="tab:blue", lw=0.8)
            if true is not None:
                curves = true[..., i].reshape(-1, times.size)
                thin = curves.shape[0] > 1
                for j, curve in enumerate(curves):
                    label = (f"truth of {curves.shape[0]} runs" if thin else "truth") if j == 0 else None
                    axis.plot(
                        times, curve, color="black", lw=0.5 if thin else 1.0, alpha=0.6 if thin else 1.0, label=label
                    )
            if estimate.inconsistent_from is not None:  # the bounds stop there (NaN rows): say why
                label = "data contradict the model" if row == 0 else None
                axis.axvline(estimate.inconsistent_from, color="tab:red", ls="--", lw=0.8, label=label)
            axis.set_ylabel(names[row])
            row += 1
    unit = time_unit if time_unit is not None else estimate.meta.get("time_unit")
    for axis in axes if ax is not None else axes[-1:]:  # given axes may sit side by side
        axis.set_xlabel(f"t ({unit})" if unit else "t")
    axes[0].legend(loc="upper right", fontsize="small")
    figure = axes[0].figure
    if isinstance(figure, SubFigure):  # axes given inside a subfigure: return the figure holding it
        figure = figure.figure
    if ax is None:
        figure.tight_layout()
    return figure


def _panel_data(
    name: str,
    lower: FloatArray,
    upper: FloatArray,
    truth: ArrayLike | None,
    names: Sequence[str],
    run: int | None,
    steps: int,
) -> tuple[Sequence[str], FloatArray, FloatArray, FloatArray | None]:
    """Bounds (T, k) and truth (T, k) or (M, T, k) of one block, for ``run`` or the envelope over runs."""
    true = None if truth is None else np.asarray(truth, dtype=float)
    k = lower.shape[-1]
    if true is not None and (true.ndim not in (2, 3) or true.shape[-2:] != (steps, k)):
        raise DimensionError(f"{name}: expected shape ({steps}, {k}) or (M, {steps}, {k}), got {true.shape}")
    total = lower.shape[0] if lower.ndim == 3 else None
    if true is not None and true.ndim == 3:
        if total is not None and true.shape[0] != total:
            raise DimensionError(f"{name}: expected {total} runs (those of the estimate), got {true.shape[0]}")
        total = true.shape[0]
    if run is not None:
        if total is None:
            raise DimensionError(f"run: expected None (neither the estimate nor {name} has a run axis), got {run}")
        if not -total <= run < total:
            raise DimensionError(f"run: expected an index in [0, {total}), got {run}")
        lower, upper = (lower[run], upper[run]) if lower.ndim == 3 else (lower, upper)
        true = true[run] if true is not None and true.ndim == 3 else true
    elif lower.ndim == 3:
        lower, upper = lower.min(axis=0), upper.max(axis=0)
    elif true is not None and true.ndim == 3:
        raise DimensionError(
            f"{name}: expected shape ({steps}, {k}) for a single-run estimate (or choose run=), got {true.shape}"
        )
    return names, lower, upper, true


def _panel_axes(ax: Axes | Sequence[Axes] | None, count: int) -> list[Axes]:
    """The axes to draw ``count`` panels in: those given (checked), or a new figure's."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, grid = plt.subplots(count, 1, figsize=(7, 1.8 * count + 0.6), sharex=True, squeeze=False)
        return list(grid[:, 0])
    axes = list(np.ravel(np.asarray(ax, dtype=object)))
    if len(axes) != count:
        raise DimensionError(f"ax: expected {count} axes (one per panel), got {len(axes)}")
    return axes


def plot_widths(
    t: ArrayLike, widths: Mapping[str, ArrayLike], reference: Mapping[str, float] | None = None, log: bool = True
) -> Figure:
    """Total width (sum over components) of several estimates against time.

    Each series gets its own line style, so equal widths stay visible; a series known at isolated steps
    only (NaN elsewhere, e.g. a lower bound computed at a few steps) is drawn with markers.

    Parameters
    ----------
    t : array_like, shape (T,)
        Times.
    widths : dict of str to array_like, shape (T, n)
        Widths per method.
    reference : dict of str to float, optional
        Horizontal reference levels (e.g. a theoretical steady-state bound).
    log : bool
        Logarithmic vertical axis.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 3.5))
    styles = ("-", "--", ":", "-.")  # equal widths stay visible on top of each other
    for index, (name, width) in enumerate(widths.items()):
        total = np.sum(np.asarray(width), axis=-1)
        finite = np.isfinite(total)
        neighbour = np.zeros_like(finite)
        neighbour[1:] |= finite[:-1]
        neighbour[:-1] |= finite[1:]
        isolated = bool(np.any(finite & ~neighbour))  # values at a few steps only: a line would not show them
        ax.plot(t, total, ls=styles[index % len(styles)], marker="o" if isolated else None, ms=4, label=name)
    for name, level in (reference or {}).items():
        ax.axhline(level, ls="--", lw=0.8, color="gray", label=name)
    if log:
        ax.set_yscale("log")
    ax.set_xlabel("t")
    ax.set_ylabel("sum of widths")
    ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.01, 1.0))  # outside: never over a curve
    fig.tight_layout()
    return fig


def plot_psi(
    psi: ArrayLike,
    levels: Sequence[float],
    magnitudes: Sequence[float],
    title: str,
    level_label: str = "uncertainty level",
    magnitude_label: str = "fault magnitude",
) -> Figure:
    """Heat map of a campaign's Ψ̂ (share of runs isolated correctly) over uncertainty levels × fault magnitudes.

    Parameters
    ----------
    psi : array_like, shape (len(levels), len(magnitudes))
        Ψ̂ of each cell, in [0, 1] (NaN: not computed).
    levels, magnitudes : sequence of float
        The grid (levels are fractions, shown in %).
    title : str
        Figure title.
    level_label, magnitude_label : str
        Axis labels, with the units of the model (e.g. ``"fault magnitude (N·m)"``).

    Returns
    -------
    matplotlib.figure.Figure

    References
    ----------
    Rotondo et al. (:mod:`intervalobs.references`): Ψ̂ of (119).
    """
    import matplotlib.pyplot as plt

    data = np.asarray(psi, dtype=float)
    if data.shape != (len(levels), len(magnitudes)):
        raise DimensionError(f"psi: expected shape ({len(levels)}, {len(magnitudes)}), got {data.shape}")
    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    im = ax.imshow(data, origin="lower", vmin=0.0, vmax=1.0, cmap="viridis", aspect="auto")
    ax.set_xticks(range(len(magnitudes)), [f"{v:g}" for v in magnitudes])
    ax.set_yticks(range(len(levels)), [f"{100 * v:g}%" for v in levels])
    ax.set_xlabel(magnitude_label)
    ax.set_ylabel(level_label)
    for (i, j), v in np.ndenumerate(data):
        ax.text(j, i, f"{v:.2f}", ha="center", va="center", color="w" if v < 0.6 else "k", fontsize=8)
    ax.set_title(title)
    fig.colorbar(im, ax=ax, label="Ψ̂")
    fig.tight_layout()
    return fig


def save_figure(fig: Figure, path: str | Path) -> None:
    """Save ``fig`` as a PNG at 120 dpi and close it.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (closed afterwards, so that batch runs do not accumulate open figures).
    path : str or pathlib.Path
        Destination file.
    """
    import matplotlib.pyplot as plt

    fig.savefig(path, dpi=120)
    plt.close(fig)
