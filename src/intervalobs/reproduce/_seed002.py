"""Shared pieces of the two seed-002 reproductions (no ``EXAMPLE`` here, so the registry skips it).

The naive framer below is the paper's interval observer (39)–(40) taken literally, with
:math:`\\overline{x}^+ = (A_0 - LC)\\overline{x} + \\dots` — valid only when :math:`A_0 - LC \\ge 0`. It exists
to show the failure of Figs. 4 and 9 (lost enclosure with a non-monotone gain) and is never shipped as
an observer.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..design.hinf import GainDesign, gain_properties
from ..estimate import Estimate, enclosure_report
from ..interval import interval_matvec_bounds, matvec_bounds
from ..observers.base import Observer
from ..observers.intersection import IntersectionObserver
from ..plotting import plot_widths, save_figure
from ..simulate import simulate
from ..systems import Bounds, LTISystem
from ..tightness import add_tightness

if TYPE_CHECKING:
    from matplotlib.figure import Figure

FloatArray = NDArray[np.float64]

COLORS = {"zonotopic": "tab:orange", "interval": "tab:blue", "integrated": "tab:green"}


def naive_framer(
    system: LTISystem, bounds: Bounds, L: ArrayLike, t: FloatArray, y: FloatArray, u: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """The integrated-observer paper's (39)–(40) literally: ``M x̄`` and ``M x̲`` with ``M = A0 - LC`` of any sign (NOT
    sound).

    Returns the raw ``(lower, upper)`` arrays: with a non-monotone ``M`` they may even cross.
    """
    full = bounds.resolve(system)
    assert system.dA is not None
    gain = np.asarray(L, dtype=float).reshape(system.n, system.p)
    m = system.A - gain @ system.C
    noise_lo, noise_hi = matvec_bounds(
        np.hstack([system.E, -gain @ system.F]), np.r_[full.w[0], full.v[0]], np.r_[full.w[1], full.v[1]]
    )
    lower = np.empty((*y.shape[:-1], system.n))
    upper = np.empty_like(lower)
    lo = np.broadcast_to(full.x0[0], (*y.shape[:-2], system.n))
    hi = np.broadcast_to(full.x0[1], (*y.shape[:-2], system.n))
    for k in range(t.size):
        lower[..., k, :], upper[..., k, :] = lo, hi
        if k + 1 == t.size:
            break
        xi_lo, xi_hi = interval_matvec_bounds(system.dA[0], system.dA[1], lo, hi)
        drive = y[..., k, :] @ gain.T + u[..., k, :] @ system.B.T
        lo, hi = lo @ m.T + drive + noise_lo + xi_lo, hi @ m.T + drive + noise_hi + xi_hi
    return lower, upper


def monte_carlo_enclosure(
    observers: dict[str, Observer],
    system: LTISystem,
    bounds: Bounds,
    t: FloatArray,
    u: FloatArray,
    seed: int,
    runs: int,
) -> dict[str, dict[str, float]]:
    """Enclosure of each observer over ``runs`` extreme-noise runs (vertex x0 and ΔA), vectorised."""
    sim = simulate(system, bounds, t, u=u, noise="extreme", seed=seed, runs=runs)
    out: dict[str, dict[str, float]] = {}
    for name, observer in observers.items():
        est = observer.run(t, sim.y, u)
        out[name] = enclosure_report(t, est.lower, sim.x, est.upper).as_dict()
    return out


def printed_gain_table(system: LTISystem, printed: dict[str, list[float]]) -> dict[str, dict[str, Any]]:
    """Properties of each printed gain on ``system`` (sign pattern, ρ(M), ρ(|M|), ρ(|M| + D))."""
    assert system.dA is not None
    radius = 0.5 * (system.dA[1] - system.dA[0])
    return {
        name: gain_properties(system.A, system.C, np.reshape(g, (system.n, system.p)), radius)
        for name, g in printed.items()
    }


def gain_entries(system: LTISystem, gains: dict[str, GainDesign]) -> dict[str, dict[str, Any]]:
    """Each designed gain as a dict, with ρ(|A0 - LC| + D), the sound framer's certificate including ΔA."""
    assert system.dA is not None
    radius = 0.5 * (system.dA[1] - system.dA[0])
    return {
        name: design.as_dict()
        | {"width_spectral_radius": gain_properties(system.A, system.C, design.gain, radius)["width_spectral_radius"]}
        for name, design in gains.items()
    }


def versus_paper(printed: dict[str, list[float]], ours: dict[str, tuple[GainDesign, str]]) -> dict[str, dict[str, Any]]:
    """Each printed gain next to the gain we compute for the same role, with the reason they differ."""
    table: dict[str, dict[str, Any]] = {}
    for name, (design, reason) in ours.items():
        paper = np.asarray(printed[name], dtype=float)
        table[name] = {
            "paper": paper.tolist(),
            "ours": design.gain.ravel().tolist(),
            "lmi": design.lmi,
            "max_abs_difference": float(np.max(np.abs(design.gain.ravel() - paper))),
            "reason": reason,
        }
    return table


def mean_width(estimate: Estimate) -> list[float]:
    """Mean width per state over the record."""
    return [float(v) for v in estimate.width().mean(axis=0)]


def plot_comparison(
    t: FloatArray,
    truth: FloatArray,
    bounds: dict[str, tuple[FloatArray, FloatArray]],
    labels: list[str],
    title: str,
    clip: float | None = None,
) -> Figure:
    """One panel per state: each method's bounds as a pair of lines, the truth in black.

    ``clip`` limits the vertical axis to the truth's range widened by that factor of its spread
    (for diverging naive variants).
    """
    import matplotlib.pyplot as plt

    n = truth.shape[-1]
    fig, axes = plt.subplots(n, 1, figsize=(7.5, 2.0 * n + 0.8), sharex=True, squeeze=False)
    cycle = ["tab:orange", "tab:blue", "tab:green", "tab:red", "tab:purple", "tab:brown"]
    for i in range(n):
        ax = axes[i, 0]
        for j, (name, (lo, hi)) in enumerate(bounds.items()):
            color = next((c for key, c in COLORS.items() if name.startswith(key)), cycle[(j + 3) % len(cycle)])
            style = "--" if "naive" in name else (":" if name.startswith("integrated") else "-")
            width = max(3.0 - 0.9 * j, 1.0)  # coinciding bounds stay visible
            ax.plot(t, lo[:, i], style, color=color, lw=width, label=name)
            ax.plot(t, hi[:, i], style, color=color, lw=width)
        ax.plot(t, truth[:, i], color="black", lw=1.2, label="truth")
        if clip is not None:
            spread = float(np.ptp(truth[:, i])) or 1.0
            ax.set_ylim(truth[:, i].min() - clip * spread, truth[:, i].max() + clip * spread)
        ax.set_ylabel(labels[i])
    axes[0, 0].legend(loc="upper right", fontsize="x-small", ncol=2)
    axes[0, 0].set_title(title, fontsize="medium")
    axes[-1, 0].set_xlabel("t")
    fig.tight_layout()
    return fig


def add_seed002_tightness(
    summary: dict[str, Any],
    out_dir: Path,
    plots: bool,
    system: LTISystem,
    bounds: Bounds,
    record: tuple[NDArray[np.float64], Any, NDArray[np.float64] | None],
    estimates: dict[str, Estimate],
    observers: dict[str, Observer],
    **options: Any,
) -> None:
    """The tightness report of a seed-002 example (``--full``): its observers and their intersection.

    The zonotopic, interval, integrated and tube estimates, and the IntersectionObserver of the last three
    observers, go to :func:`~intervalobs.tightness.add_tightness` from sample 20 with a window of 40; the
    figure ``tightness.png`` is written with ``plots``.

    Parameters
    ----------
    summary : dict
        The example's summary (the report is added to it).
    out_dir : pathlib.Path
        The example's folder.
    plots : bool
        Also write ``tightness.png``.
    system, bounds : LTISystem, Bounds
        The example.
    record : tuple
        ``(t, sim, u)``: sample times, the simulation (its ``y``, ``x`` and ``dA``) and the known input.
    estimates, observers : dict
        The example's estimates and observers by name.
    **options
        Further arguments of :func:`~intervalobs.tightness.add_tightness` (windows, strides, steps).
    """
    t, sim, u = record
    compared = {name: estimates[name] for name in ("zonotopic", "interval", "integrated", "tube")}
    members = [observers["interval"], observers["tube"], observers["zonotopic"]]
    compared["intersection"] = IntersectionObserver.design(system, bounds, extra=members).run(t, sim.y, u)
    tightness = add_tightness(
        summary,
        system,
        bounds,
        t,
        sim.y,
        u,
        compared,
        start=20,
        horizon=40,
        samples=0,
        truth=(sim.dA, sim.x),
        **options,
    )
    if plots:
        out_dir.mkdir(parents=True, exist_ok=True)
        save_figure(plot_widths(tightness.t, tightness.widths), out_dir / "tightness.png")
