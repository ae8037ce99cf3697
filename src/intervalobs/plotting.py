"""Figures (matplotlib only). Functions take estimates and truth and return the figure."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from .estimate import Estimate

__all__ = ["plot_estimate", "plot_widths", "save_figure"]


def plot_estimate(
    estimate: Estimate,
    truth: ArrayLike | None = None,
    labels: list[str] | None = None,
    inputs: bool = False,
    input_truth: ArrayLike | None = None,
) -> Figure:
    """One panel per state (and per unknown input): the bounds as a band, the truth as a line.

    Parameters
    ----------
    estimate : Estimate
        A single-run estimate (2-D bounds).
    truth : array_like, shape (T, n), optional
        True state.
    labels : list of str, optional
        Panel titles.
    inputs : bool
        Also plot the unknown-input bounds.
    input_truth : array_like, shape (T, q), optional
        True unknown input.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    blocks = [(estimate.lower, estimate.upper, truth, "x")]
    if inputs and estimate.input_lower is not None and estimate.input_upper is not None:
        blocks.append((estimate.input_lower, estimate.input_upper, input_truth, "d"))
    count = sum(b[0].shape[-1] for b in blocks)
    fig, axes = plt.subplots(count, 1, figsize=(7, 1.8 * count + 0.6), sharex=True, squeeze=False)
    row = 0
    for lower, upper, true, name in blocks:
        for i in range(lower.shape[-1]):
            ax = axes[row, 0]
            ax.fill_between(estimate.t, lower[:, i], upper[:, i], color="tab:blue", alpha=0.25, lw=0, label="bounds")
            ax.plot(estimate.t, lower[:, i], color="tab:blue", lw=0.8)
            ax.plot(estimate.t, upper[:, i], color="tab:blue", lw=0.8)
            if true is not None:
                ax.plot(estimate.t, np.asarray(true)[:, i], color="black", lw=1.0, label="truth")
            title = labels[row] if labels is not None and row < len(labels) else f"${name}_{{{i + 1}}}$"
            ax.set_ylabel(title)
            row += 1
    axes[0, 0].legend(loc="upper right", fontsize="small")
    axes[-1, 0].set_xlabel("t")
    fig.tight_layout()
    return fig


def plot_widths(
    t: ArrayLike, widths: Mapping[str, ArrayLike], reference: Mapping[str, float] | None = None, log: bool = True
) -> Figure:
    """Total width (sum over components) of several estimates against time.

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

    fig, ax = plt.subplots(figsize=(7, 3.5))
    for name, width in widths.items():
        ax.plot(t, np.sum(np.asarray(width), axis=-1), label=name)
    for name, level in (reference or {}).items():
        ax.axhline(level, ls="--", lw=0.8, color="gray", label=name)
    if log:
        ax.set_yscale("log")
    ax.set_xlabel("t")
    ax.set_ylabel("sum of widths")
    ax.legend(fontsize="small")
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
