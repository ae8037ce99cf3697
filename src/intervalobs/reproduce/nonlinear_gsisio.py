"""Reproduction ``nonlinear-gsisio``: seed 003, Section V (Figs. 1–2), and what it takes to make it sound.

Recommended bounds (``x_lower``/``x_upper``, ``d_lower``/``d_upper``): :class:`NullSpaceGSISIO` on the
paper's system — the paper's own construction cannot run there (condition (8) fails structurally, and
its framers would not be correct even with a pseudo-inverse: ``naive_paper_x_lower`` shows the result
of forcing it, violated by the truth).

Input rows are one step delayed: row k of ``d``, ``d_lower``, ``d_upper`` is about :math:`d_{k-1}`
(row 0 is NaN), so the three arrays are aligned with each other. ``delta_x`` is NaN: no stability
condition of Theorem 2 holds for the paper's example (every consistent 𝓛 > 1).

Our own full-rank system (``fullrank_*`` keys, its own truth ``fullrank_state``) demonstrates the
paper's construction where (8) holds and condition (i) holds: widths stay below Lemma 5's δ.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..design.mixed_monotone import jacobian_bounds, lipschitz_bound
from ..errors import AssumptionError
from ..estimate import Estimate
from ..examples import gsisio as ex
from ..inclusion import evaluate_matrix
from ..observers.gsisio import GSISIO, NullSpaceGSISIO, gsisio_design
from ..systems.nonlinear import simulate_nonlinear
from .contract import Example, base_summary, write_reproduction

NAME = "nonlinear-gsisio"
SEED_FILE = "003_ab28b8d9baa98fb8.txt"
MONTE_CARLO_RUNS = 8
LONG_HORIZON = 500

FloatArray = NDArray[np.float64]


def _delayed(d: FloatArray) -> FloatArray:
    """Truth aligned with delayed input rows: row k holds d_{k-1}, row 0 NaN."""
    out = np.full_like(d, np.nan)
    out[..., 1:, :] = d[..., :-1, :]
    return out


def _naive_run(observer: GSISIO, y: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The paper's recursion forced through pseudo-inverses (bounds may cross: no Estimate is built)."""
    state = observer.init()
    lower, upper = [state.lower], [state.upper]
    with np.errstate(all="ignore"):
        for k in range(y.shape[0] - 1):
            state = observer.step(state, y[k])
            lower.append(state.lower)
            upper.append(state.upper)
    return np.array(lower), np.array(upper)


def _errors(est: Estimate, x: FloatArray) -> FloatArray:
    """Theorem 2's estimation error max(||x_up - x||, ||x - x_lo||)."""
    return np.maximum(np.linalg.norm(est.upper - x, axis=-1), np.linalg.norm(x - est.lower, axis=-1))


def _jacobian_norm_range(jac: Any, grid: FloatArray) -> tuple[float, float]:
    values = evaluate_matrix(jac, grid)
    norms = np.linalg.norm(values, ord=2, axis=(-2, -1))
    return float(norms.min()), float(norms.max())


def _paper_constants_check() -> dict[str, Any]:
    """Numbers that show the printed constants cannot be reproduced."""
    system = ex.paper_system()
    f_jac, g_jac = system.jacobians()
    # Df depends on x only through 0.3 x2 - 0.2 x1 (one full period covers R^2); Dg through (0.3x1+0.2x2, x1).
    theta = np.linspace(0.0, 2 * np.pi, 2001)
    grid_f = np.stack([-theta / 0.2, np.zeros_like(theta)], -1)
    a, b = np.meshgrid(np.linspace(0, 2 * np.pi, 401), np.linspace(0, 2 * np.pi, 401), indexing="ij")
    x1 = b.ravel()
    grid_g = np.stack([x1, (a.ravel() - 0.3 * x1) / 0.2], -1)
    box = ex.X0_BOX
    u = np.linspace(0, 1, 201)
    bx = np.stack(np.meshgrid(box[0][0] + u * (box[1][0] - box[0][0]), box[0][1] + u * (box[1][1] - box[0][1])), -1)
    bx = bx.reshape(-1, 2)
    printed_k = np.array(ex.PRINTED["K"])
    printed_l = np.array(ex.PRINTED["L"])
    gh = np.vstack([system.G, system.H])
    return {
        "norm_Df_range_global_sampled": _jacobian_norm_range(f_jac, grid_f),
        "norm_Df_max_on_x0_box_sampled": _jacobian_norm_range(f_jac, bx)[1],
        "norm_Dg_range_global_sampled": _jacobian_norm_range(g_jac, grid_g),
        "norm_Dg_at_0": float(np.linalg.norm(evaluate_matrix(g_jac, np.zeros(2)), 2)),
        "jacobian_f_on_x0_box": jacobian_bounds(f_jac, *box),
        "jacobian_g_on_x0_box": jacobian_bounds(g_jac, *box),
        "L_f_bound_on_x0_box": float(lipschitz_bound(*jacobian_bounds(f_jac, *box))),
        "printed_K_minus_L_times_GH_minus_G": (printed_k - printed_l) @ gh - system.G,
        "note_printed_K_L": (
            "for every left inverse J of [G; H], K - L = G J and so (K - L)[G; H] = G; the printed K, L "
            "leave the residual above, so no left inverse produces them"
        ),
    }


def _fullrank_demo(seed: int) -> tuple[dict[str, Any], dict[str, FloatArray], dict[str, Any]]:
    system = ex.fullrank_system()
    box = ex.FULLRANK_X0_BOX
    start = time.perf_counter()
    observer = GSISIO.design(system, box)
    nullspace = NullSpaceGSISIO.design(system, box)
    design_time = time.perf_counter() - start
    d_true = ex.fullrank_input()
    steps = d_true.shape[0]
    t = np.arange(steps, dtype=float)
    sim = simulate_nonlinear(system, box, d_true, noise="extreme", seed=seed)
    est = observer.run(t, sim.y)
    est_ns = nullspace.run(t, sim.y)
    hull = GSISIO.design(system, box, input_hull=True).run(t, sim.y)
    assert hull.input_lower is not None and hull.input_upper is not None
    dr = observer.design_result
    delta0 = float(np.linalg.norm(box[1] - box[0]))
    delta_x = dr.delta_x(delta0, steps)
    delta_d = dr.delta_d(delta_x, system.w[1] - system.w[0], system.v[1] - system.v[0])
    width_x = np.linalg.norm(est.width(), axis=-1)
    assert est.input_lower is not None and est.input_upper is not None
    width_d = np.linalg.norm(est.input_upper - est.input_lower, axis=-1)
    mc = simulate_nonlinear(system, box, d_true, noise="extreme", seed=seed + 7, runs=MONTE_CARLO_RUNS)
    mc_est = observer.run(t, mc.y)
    facts = {
        "system": "our own: f = (0.3x1 + 0.1 sin x2, 0.25x2 - 0.1 tanh x1), g = (x1 + 0.1 sin x2, 0.2x2 + 0.05x1), "
        "G = [0.2, -0.1]', H = [1, 0.5]' (full column rank), |w| <= 0.05, |v| <= 0.05",
        "gsisio_design": dr.as_dict(),
        "enclosure_state": est.enclosure(sim.x).as_dict(),
        "enclosure_input": est.input_enclosure(_delayed(sim.d)).as_dict(),
        "enclosure_state_monte_carlo": mc_est.enclosure(mc.x).as_dict(),
        "enclosure_input_monte_carlo": mc_est.input_enclosure(_delayed(mc.d)).as_dict(),
        "width_state_below_delta_x": bool(np.all(width_x <= delta_x)),
        "width_input_below_delta_d": bool(np.all(width_d[1:] <= delta_d[1:])),
        "mean_state_width_norm": float(width_x.mean()),
        "delta_x_steady": float(dr.delta_z / (1 - dr.script_L)),
        "input_hull_enclosure": hull.input_enclosure(_delayed(sim.d)).as_dict(),
        "input_width_ratio_lemma3_over_lp_hull": {
            "median": float(np.median(width_d[1:] / np.linalg.norm(hull.input_upper - hull.input_lower, axis=-1)[1:])),
            "min": float(np.min(width_d[1:] / np.linalg.norm(hull.input_upper - hull.input_lower, axis=-1)[1:])),
            "max": float(np.max(width_d[1:] / np.linalg.norm(hull.input_upper - hull.input_lower, axis=-1)[1:])),
        },
        "nullspace_mean_state_width_norm": float(np.linalg.norm(est_ns.width(), axis=-1).mean()),
        "nullspace_enclosure_state": est_ns.enclosure(sim.x).as_dict(),
        "design_s": design_time,
    }
    arrays = {
        "fullrank_t": t,
        "fullrank_state": sim.x,
        "fullrank_state_lower": est.lower,
        "fullrank_state_upper": est.upper,
        "fullrank_d": _delayed(sim.d),
        "fullrank_d_lower": est.input_lower,
        "fullrank_d_upper": est.input_upper,
        "fullrank_delta_x": delta_x,
        "fullrank_delta_d": delta_d,
        "fullrank_hull_d_lower": hull.input_lower,
        "fullrank_hull_d_upper": hull.input_upper,
        "fullrank_nullspace_state_lower": est_ns.lower,
        "fullrank_nullspace_state_upper": est_ns.upper,
    }
    plot_data = {"est": est, "sim": sim, "delta_x": delta_x, "delta_d": delta_d}
    return facts, arrays, plot_data


def run(out_dir: Path, seed: int, plots: bool) -> dict[str, Any]:
    """Recompute the paper's design, run the sound variant on its example and the paper's on ours.

    Parameters
    ----------
    out_dir : pathlib.Path
        Output folder.
    seed : int
        Random seed of the simulations.
    plots : bool
        Write the PNG figures.

    Returns
    -------
    dict
        The summary written to ``summary.json``.
    """
    system = ex.paper_system()
    start = time.perf_counter()
    design = gsisio_design(system)
    try:
        GSISIO.design(system, ex.X0_BOX)
        paper_construction = "unexpectedly designed"
    except AssumptionError as exc:
        paper_construction = f"AssumptionError: {exc}"
    observer = NullSpaceGSISIO.design(system, ex.X0_BOX)
    naive = GSISIO(system, design, ex.X0_BOX, tight=False)
    design_time = time.perf_counter() - start

    steps = ex.STEPS
    t = np.arange(steps, dtype=float)
    d_true = ex.paper_input(steps)
    sim = simulate_nonlinear(system, ex.X0_BOX, d_true, noise="extreme", seed=seed)
    start = time.perf_counter()
    est = observer.run(t, sim.y)
    run_time = time.perf_counter() - start
    naive_lower, naive_upper = _naive_run(naive, sim.y)
    assert est.input_lower is not None and est.input_upper is not None
    d_rows = _delayed(sim.d)

    # Monte Carlo over a longer horizon: several noise seeds and input amplitudes, all vectorised
    scale = np.linspace(0.5, 2.0, MONTE_CARLO_RUNS)[:, None, None]
    mc_d = ex.paper_input(LONG_HORIZON)[None] * scale
    mc = simulate_nonlinear(system, ex.X0_BOX, mc_d, noise="extreme", seed=seed + 1, runs=MONTE_CARLO_RUNS)
    mc_est = observer.run(np.arange(LONG_HORIZON, dtype=float), mc.y)
    long_width = np.linalg.norm(mc_est.width(), axis=-1)

    width_x = np.linalg.norm(est.width(), axis=-1)
    width_d = np.linalg.norm(est.input_upper - est.input_lower, axis=-1)
    naive_violation = np.maximum(naive_lower - sim.x, sim.x - naive_upper).max(axis=-1)
    naive_bad = np.flatnonzero(~(naive_violation <= 0))
    full_facts, full_arrays, full_plot = _fullrank_demo(seed)

    summary = base_summary(
        example=NAME,
        seed_file=SEED_FILE,
        observer="NullSpaceGSISIO",
        t=t,
        x=sim.x,
        x_lower=est.lower,
        x_upper=est.upper,
        transient_s=0.0,
        d=d_rows,
        d_lower=est.input_lower,
        d_upper=est.input_upper,
    )
    U, S, Vt = np.linalg.svd(system.H)
    summary["design"] = {
        **design.as_dict(),
        "paper_construction": paper_construction,
        "lemma4": {"sigma": float(S[0]), "V1": Vt[0], "U1": U[:, 0], "U2": U[:, 1], "V2": Vt[1]},
        "hidden_state_direction_G_V2": system.G @ Vt[1],
        "constants_check": _paper_constants_check(),
        "naive_paper_construction_with_pinv": {
            "steps_violated_or_undefined": int(naive_bad.size),
            "first_violation_step": int(naive_bad[0]) if naive_bad.size else None,
            "max_violation": float(np.nanmax(naive_violation)),
            "note": "(9) solved with pseudo-inverses although (8) fails and rho(K1 + L1) > 1: not a framer",
        },
        "sound_variant": {
            "observer": "NullSpaceGSISIO",
            "Z": observer.Z,
            "R": observer.R,
            "slope_U2g_along_t_global": [observer.slope[0], observer.slope[1]],
            "gain_factors": observer.gain_factors,
            "splits": observer._range.splits,
            "newton_steps": observer.newton_steps,
            "mean_state_width_norm": float(width_x.mean()),
            "mean_input_width_norm": float(np.nanmean(width_d)),
            "monte_carlo_runs": MONTE_CARLO_RUNS,
            "monte_carlo_steps": LONG_HORIZON,
            "monte_carlo_input_scales": scale.ravel(),
            "enclosure_state_monte_carlo": mc_est.enclosure(mc.x).as_dict(),
            "enclosure_input_monte_carlo": mc_est.input_enclosure(_delayed(mc.d)).as_dict(),
            "monte_carlo_mean_state_width_norm": float(long_width.mean()),
            "monte_carlo_state_width_norm_max_after_10_steps": float(long_width[..., 10:].max()),
            "monte_carlo_mean_input_width_norm": float(
                np.nanmean(np.linalg.norm(mc_est.input_upper - mc_est.input_lower, axis=-1))  # type: ignore[operator]
            ),
        },
        "choices": {
            "unknown_input": "examples.gsisio.paper_input (the paper shows its d only in Fig. 1)",
            "x0": "a random vertex of the printed initial box",
            "noise": "bang-bang between the printed bounds (extreme)",
            "steps": steps,
            "jacobian_domain": "whole plane (the Jacobians are globally bounded)",
        },
        "fullrank_example": full_facts,
    }
    summary["paper"] = ex.PRINTED
    summary["runtime_s"] = {"design": design_time, "run": run_time}
    trajectories: dict[str, Any] = {
        "t": t,
        "x": sim.x,
        "x_lower": est.lower,
        "x_upper": est.upper,
        "d": d_rows,
        "d_lower": est.input_lower,
        "d_upper": est.input_upper,
        "delta_x": np.full(steps, np.nan),
        "naive_paper_x_lower": naive_lower,
        "naive_paper_x_upper": naive_upper,
        **full_arrays,
    }
    write_reproduction(out_dir, summary, trajectories)
    if plots:
        _figures(out_dir, t, sim.x, d_rows, est, full_plot)
    return summary


def _figures(
    out_dir: Path, t: FloatArray, x: FloatArray, d_rows: FloatArray, est: Estimate, full: dict[str, Any]
) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..plotting import save_figure

    assert est.input_lower is not None and est.input_upper is not None
    # Fig. 1: states and (delayed) inputs with their bounds
    fig, axes = plt.subplots(4, 1, figsize=(8, 9), sharex=True)
    series = [
        (est.lower[:, 0], est.upper[:, 0], x[:, 0], "$x_1$"),
        (est.lower[:, 1], est.upper[:, 1], x[:, 1], "$x_2$"),
        (est.input_lower[:, 0], est.input_upper[:, 0], d_rows[:, 0], "$d_{1,k-1}$"),
        (est.input_lower[:, 1], est.input_upper[:, 1], d_rows[:, 1], "$d_{2,k-1}$"),
    ]
    for ax, (lo, hi, truth, label) in zip(axes, series):
        ax.fill_between(t, lo, hi, color="tab:blue", alpha=0.25, lw=0, label="bounds")
        ax.plot(t, lo, color="tab:blue", lw=0.7)
        ax.plot(t, hi, color="tab:blue", lw=0.7)
        ax.plot(t, truth, color="black", lw=1.0, label="truth")
        ax.set_ylabel(label)
    axes[0].legend(loc="upper right", fontsize="small")
    axes[0].set_title("Seed 003 example, sound variant (NullSpaceGSISIO), bang-bang noise")
    axes[-1].set_xlabel("step k")
    fig.tight_layout()
    save_figure(fig, out_dir / "fig1_states_inputs.png")

    # Fig. 2: errors and widths (no stability condition holds: no delta bound exists for this example)
    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    err_x = _errors(est, x)
    width_x = np.linalg.norm(est.width(), axis=-1)
    err_d = np.maximum(
        np.linalg.norm(est.input_upper - d_rows, axis=-1), np.linalg.norm(d_rows - est.input_lower, axis=-1)
    )
    width_d = np.linalg.norm(est.input_upper - est.input_lower, axis=-1)
    axes[0].plot(t, err_x, label=r"$\|\tilde x_k\|$")
    axes[0].plot(t, width_x, label=r"$\|\Delta^x_k\|$")
    axes[0].set_ylabel("state")
    axes[1].plot(t, err_d, label=r"$\|\tilde d_{k-1}\|$")
    axes[1].plot(t, width_d, label=r"$\|\Delta^d_{k-1}\|$")
    axes[1].set_ylabel("input")
    for ax in axes:
        ax.legend(fontsize="small")
    axes[0].set_title("Errors and widths (no Theorem 2 condition holds here: no δ bound exists)")
    axes[-1].set_xlabel("step k")
    fig.tight_layout()
    save_figure(fig, out_dir / "fig2_errors_widths.png")

    # Our full-rank system: the paper's construction, widths below Lemma 5's delta
    fe: Estimate = full["est"]
    sim = full["sim"]
    assert fe.input_lower is not None and fe.input_upper is not None
    tt = fe.t
    fig, axes = plt.subplots(4, 1, figsize=(8, 9), sharex=True)
    for i in range(2):
        axes[i].fill_between(tt, fe.lower[:, i], fe.upper[:, i], color="tab:green", alpha=0.25, lw=0)
        axes[i].plot(tt, sim.x[:, i], color="black", lw=1.0)
        axes[i].set_ylabel(f"$x_{i + 1}$")
    drow = _delayed(sim.d)
    axes[2].fill_between(tt, fe.input_lower[:, 0], fe.input_upper[:, 0], color="tab:green", alpha=0.25, lw=0)
    axes[2].plot(tt, drow[:, 0], color="black", lw=1.0)
    axes[2].set_ylabel("$d_{k-1}$")
    axes[3].semilogy(tt, np.linalg.norm(fe.width(), axis=-1), label=r"$\|\Delta^x_k\|$")
    axes[3].semilogy(tt, full["delta_x"], "--", label=r"$\delta^x_k$ (Lemma 5)")
    axes[3].semilogy(tt, _errors(fe, sim.x), label=r"$\|\tilde x_k\|$")
    axes[3].semilogy(tt, np.linalg.norm(fe.input_upper - fe.input_lower, axis=-1), label=r"$\|\Delta^d_{k-1}\|$")
    axes[3].semilogy(tt, full["delta_d"], ":", label=r"$\delta^d_{k-1}$ (Lemma 5, corrected)")
    axes[3].legend(fontsize="small", ncol=2)
    axes[0].set_title("Our full-rank-H system: the paper's GSISIO, condition (i) holds")
    axes[-1].set_xlabel("step k")
    fig.tight_layout()
    save_figure(fig, out_dir / "fig3_fullrank_paper_construction.png")


EXAMPLE = Example(NAME, SEED_FILE, "seed 003 GSISIO nonlinear example: paper's design checked, sound variant", run)
