"""Reproduction ``aircraft-uio`` (seed 000, §5): state and unknown-input bounds on the aircraft model.

What it does:

1. computes E, P from A, C, D (W = 0) and compares them with the printed ones; checks the printed K, T;
2. designs K, T (real distinct poles, T = V⁻¹, diagonal T N T⁻¹) and the observer;
3. simulates the exact truth for 20 s at Te = 1e-4 (200 001 samples) under four smooth worst-case noise
   realisations (sine / plateau measurement noise × sine / vertex process noise);
4. runs the observer with the provable difference enclosure of ẏ (recommended), and, for comparison,
   with the paper's HOSM (λ = 100, µ1 = 1.1) and with Levant-tuned gains, measuring the HOSM error;
5. writes summary.json, trajectories.npz (run 0) and the figures.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from ..design.differentiator import HOSMDifferentiator, levant_gains, settling_time
from ..estimate import Estimate
from ..examples import aircraft as ac
from ..observers.unknown_input import UnknownInputIntervalObserver
from .contract import Example, base_summary, write_reproduction

NAME = "aircraft-uio"
SEED_FILE = "000_8977db2ea356505f.txt"
T_FINAL = 20.0
NOISE_CASES = (("sine", "sine"), ("plateau", "vertex"), ("sine", "vertex"), ("plateau", "sine"))
"""(measurement-noise kind, process-noise kind) of each Monte Carlo run."""
HOSM_TRANSIENT = 1.0


def _observer(derivative: str = "difference", hosm: HOSMDifferentiator | None = None) -> UnknownInputIntervalObserver:
    return UnknownInputIntervalObserver.design(
        ac.aircraft_system(),
        ac.aircraft_bounds(),
        ac.D,
        ac.TE,
        noise_rate=np.full(4, ac.DELTA_DOT_BAR),
        output_accel=np.full(4, ac.OUTPUT_ACCEL),
        derivative=derivative,  # type: ignore[arg-type]
        hosm=hosm,
        mu1=ac.MU1,
        hosm_transient=HOSM_TRANSIENT,
    )


def _paper_checks(observer: UnknownInputIntervalObserver) -> dict[str, Any]:
    """Compare the printed E, P with ours; check the printed K, T against Hypothesis 6."""
    e_paper = np.array(ac.PAPER["E"], dtype=float)
    p_paper = np.array(ac.PAPER["P"], dtype=float)
    ours_e, ours_p = observer.decoupling.E, observer.decoupling.P

    def misprints(paper: np.ndarray, ours: np.ndarray, name: str) -> list[dict[str, Any]]:
        bad = np.argwhere(np.abs(paper - ours) > 1e-3 * np.maximum(np.abs(ours), 1e-3))
        return [
            {
                "entry": f"{name}({i + 1},{j + 1})",
                "printed": float(paper[i, j]),
                "computed": float(ours[i, j]),
            }
            for i, j in bad
        ]

    rest = np.abs(e_paper - ours_e)
    wrong = misprints(e_paper, ours_e, "E") + misprints(p_paper, ours_p, "P")
    mask_e = np.abs(e_paper - ours_e) <= 1e-3 * np.maximum(np.abs(ours_e), 1e-3)
    mask_p = np.abs(p_paper - ours_p) <= 1e-3 * np.maximum(np.abs(ours_p), 1e-3)
    agree = max(float(rest[mask_e].max()), float(np.abs(p_paper - ours_p)[mask_p].max()))
    k_paper = np.array(ac.PAPER["K_printed"], dtype=float).T
    t_paper = np.array(ac.PAPER["T"], dtype=float)
    n_paper = ours_p @ ac.A - k_paper @ ac.C
    j_paper = t_paper @ n_paper @ np.linalg.inv(t_paper)
    off = j_paper[~np.eye(5, dtype=bool)]
    return {
        "misprints": wrong,
        "max_difference_elsewhere": agree,
        "printed_K_T_metzler_check": float(off.min()),
        "printed_K_eig_N": [complex(v) for v in np.linalg.eigvals(n_paper)],
        "printed_pole_count": len(ac.PAPER["poles"]),
    }


def _single(est: Estimate, i: int) -> Estimate:
    """Run ``i`` of a Monte Carlo estimate."""
    assert est.input_lower is not None and est.input_upper is not None
    return Estimate(est.t, est.lower[i], est.upper[i], est.input_lower[i], est.input_upper[i], est.meta)


def run(out_dir: Path, seed: int, plots: bool) -> dict[str, Any]:
    """Run the example and write summary.json, trajectories.npz and the figures into ``out_dir``.

    Parameters
    ----------
    out_dir : pathlib.Path
        Output folder.
    seed : int
        Seed of the noise realisations.
    plots : bool
        Write the PNG figures.

    Returns
    -------
    dict
        The summary.
    """
    start = time.perf_counter()
    observer = _observer()
    design_time = time.perf_counter() - start
    t = np.arange(round(T_FINAL / ac.TE) + 1, dtype=float) * ac.TE
    records = [
        ac.simulate_aircraft(t, seed=seed * 100 + i, delta_kind=dk, omega_kind=ok)
        for i, (dk, ok) in enumerate(NOISE_CASES)
    ]
    y = np.stack([r.y for r in records])
    x = np.stack([r.x for r in records])
    xi = np.broadcast_to(records[0].xi, (len(records), *records[0].xi.shape))
    start = time.perf_counter()
    est = observer.run(t, y)
    run_time = time.perf_counter() - start
    mc_state = est.enclosure(x)
    mc_input = est.input_enclosure(xi)
    per_run = [
        {
            "delta": dk,
            "omega": ok,
            "state": est_r.enclosure(r.x).as_dict(),
            "input": est_r.input_enclosure(r.xi).as_dict(),
        }
        for (dk, ok), r, est_r in zip(
            NOISE_CASES,
            records,
            (_single(est, i) for i in range(len(records))),
        )
    ]
    # HOSM: the paper's gains and Levant-tuned gains, measured on every run
    paper_hosm = HOSMDifferentiator(1, [ac.HOSM_LAMBDA, ac.HOSM_LAMBDA])
    levant_hosm = HOSMDifferentiator(1, levant_gains(1, ac.OUTPUT_ACCEL))
    psi_dot = np.stack([r.psi_dot for r in records])
    hosm_report: dict[str, Any] = {}
    hosm_estimates: dict[str, Estimate] = {}
    for name, diff in (("paper_lambda100", paper_hosm), ("levant_gains", levant_hosm)):
        q = diff.run(y, ac.TE)[..., 1]
        err = q - psi_dot
        after = t >= HOSM_TRANSIENT
        claimed = ac.MU1 * np.sqrt(ac.DELTA_BAR)
        hosm_obs = _observer("hosm", diff)
        h_est = hosm_obs.run(t, y[:1], hosm_q1=q[:1])
        hosm_estimates[name] = _single(h_est, 0)
        h0 = _single(h_est, 0)
        inp = h0.input_enclosure(xi[0], HOSM_TRANSIENT)
        hosm_report[name] = {
            "gains": diff.gains.tolist(),
            "max_error_after_transient": float(np.abs(err[..., after, :]).max()),
            "claimed_mu1_sqrt_delta": float(claimed),
            "beta_paper": hosm_obs.beta.tolist(),
            "settling_time_to_beta": settling_time(t, err, hosm_obs.beta),
            "input_enclosure_with_beta_run0": inp.as_dict(),
        }
    # the paper's step is not the problem for the state bounds: they do not use ẏ here
    rec0 = records[0]
    est0 = _single(est, 0)
    summary = base_summary(
        example=NAME,
        seed_file=SEED_FILE,
        observer="UnknownInputIntervalObserver",
        t=t,
        x=rec0.x,
        x_lower=est0.lower,
        x_upper=est0.upper,
        transient_s=observer.transient_s,
        d=rec0.xi,
        d_lower=est0.input_lower,
        d_upper=est0.input_upper,
    )
    dec, co = observer.decoupling, observer.coords
    width_final = est.width()[:, -1, :].max(axis=0)
    assert est.input_lower is not None and est.input_upper is not None
    input_final = (est.input_upper - est.input_lower)[:, -1, :].max(axis=0)
    paper_rho_x, paper_rho_xi = observer.paper_rho()
    summary["design"] = {
        "E": dec.E,
        "P": dec.P,
        "W": dec.W,
        "PD_residual": dec.decoupling_residual,
        "rank_CD": dec.rank_CD,
        "rank_D": dec.rank_D,
        "observability_margin_PA_C": dec.observability_margin,
        "K": co.K,
        "T": co.T,
        "L": co.L,
        "poles": co.poles,
        "eig_N": np.sort(np.linalg.eigvals(co.N).real),
        "metzler_check": co.metzler_check,
        "max_offdiagonal_TNTinv": co.offdiagonal,
        "cond_T": co.cond_T,
        "pole_candidates_score": co.tried,
        "rho_x": observer.rho_x,
        "rho_xi": observer.rho_xi,
        "paper_formula_rho_x": paper_rho_x,
        "paper_formula_rho_xi": paper_rho_xi,
        "final_width_over_rho_x": width_final / observer.rho_x,
        "final_input_width_over_rho_xi": input_final / observer.rho_xi,
        "initial_width": 2.0,
        "mu1": ac.MU1,
        "transient_s": observer.transient_s,
        "derivative": {
            "method": "difference quotient of consecutive samples (provable)",
            "radius": observer.rate_radius + 0.5 * ac.OUTPUT_ACCEL * ac.TE,
            "assumptions": "|dδ/dt| <= 1e-2 (paper), |d²ψ/dt²| <= L = λ/1.1 (Levant's rule, paper's λ)",
            "L": ac.OUTPUT_ACCEL,
            "max_abs_psi_ddot_in_simulation": float(max(np.abs(r.psi_ddot).max() for r in records)),
        },
        "hosm": hosm_report,
        "monte_carlo": {
            "runs": len(records),
            "state": mc_state.as_dict(),
            "input": mc_input.as_dict(),
            "per_run": per_run,
        },
        "noise": {
            "delta": "sine: 1e-2 sin(t + φ) (largest admissible frequency); plateau: ±1e-2, ramps at 1e-2/s",
            "omega": "sine: 1e-2 cos(t + φ); vertex: constant ±1e-2",
        },
        "truth": "closed-form solution (exact at every sample)",
    }
    summary["paper"] = {
        "E": ac.PAPER["E"],
        "P": ac.PAPER["P"],
        "K": np.array(ac.PAPER["K_printed"]).T,
        "T": ac.PAPER["T"],
        "poles": ac.PAPER["poles"],
        "mu1": ac.MU1,
        "hosm_lambda": ac.HOSM_LAMBDA,
        "Te": ac.TE,
        "checks": _paper_checks(observer),
    }
    summary["runtime_s"] = {"design": design_time, "run": run_time}
    trajectories: dict[str, Any] = {
        "t": t,
        "x": rec0.x,
        "x_lower": est0.lower,
        "x_upper": est0.upper,
        "d": rec0.xi,
        "d_lower": est0.input_lower,
        "d_upper": est0.input_upper,
        "hosm_paper_d_lower": hosm_estimates["paper_lambda100"].input_lower,
        "hosm_paper_d_upper": hosm_estimates["paper_lambda100"].input_upper,
    }
    write_reproduction(out_dir, summary, trajectories)
    if plots:
        _figures(out_dir, est0, rec0, observer, hosm_estimates)
    return summary


def _figures(
    out_dir: Path,
    est: Estimate,
    rec: ac.AircraftRecord,
    observer: UnknownInputIntervalObserver,
    hosm_estimates: dict[str, Estimate],
) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..plotting import save_figure

    t = est.t
    every = 20
    sl = slice(None, None, every)
    assert est.input_lower is not None and est.input_upper is not None
    panels = [(est.lower[:, i], est.upper[:, i], rec.x[:, i], f"$x_{i + 1}$") for i in range(5)]
    panels += [(est.input_lower[:, j], est.input_upper[:, j], rec.xi[:, j], rf"$\xi_{j + 1}$") for j in range(2)]
    for k, (lo, hi, truth, label) in enumerate(panels, start=1):
        fig, (ax, zoom) = plt.subplots(1, 2, figsize=(10, 3.2), gridspec_kw={"width_ratios": [2, 1]})
        for a, window in ((ax, sl), (zoom, slice(int(10.0 / ac.TE), int(12.0 / ac.TE), 5))):
            a.fill_between(t[window], lo[window], hi[window], color="tab:blue", alpha=0.3, lw=0, label="bounds")
            a.plot(t[window], lo[window], color="tab:blue", lw=0.6)
            a.plot(t[window], hi[window], color="tab:blue", lw=0.6)
            a.plot(t[window], truth[window], color="black", lw=0.9, label="truth")
            a.set_xlabel("t [s]")
        ax.set_ylabel(label)
        if k <= 5:
            ax.set_ylim(
                min(truth.min(), lo[int(1.0 / ac.TE) :].min()) - 0.3,
                max(truth.max(), hi[int(1.0 / ac.TE) :].max()) + 0.3,
            )
        else:
            ax.set_ylim(-2.0, 2.0)
        ax.set_title(f"Fig. {k}: bounds of {label} (left: 0–20 s, right: zoom 10–12 s)")
        ax.legend(loc="upper right", fontsize="small")
        fig.tight_layout()
        name = f"fig{k}_x{k}.png" if k <= 5 else f"fig{k}_xi{k - 5}.png"
        save_figure(fig, out_dir / name)
    # widths against the asymptotic bounds
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.6))
    w = est.width()
    for i in range(5):
        line = axes[0].plot(t[sl], w[sl, i], lw=1.0, label=f"$x_{i + 1}$")[0]
        axes[0].axhline(observer.rho_x[i], ls="--", lw=0.8, color=line.get_color())
    wi = est.input_upper - est.input_lower
    for j in range(2):
        line = axes[1].plot(t[sl], wi[sl, j], lw=1.0, label=rf"$\xi_{j + 1}$")[0]
        axes[1].axhline(observer.rho_xi[j], ls="--", lw=0.8, color=line.get_color())
    for a, title in zip(axes, ("state widths vs ρ_x (dashed)", "input widths vs ρ_ξ (dashed)")):
        a.set_yscale("log")
        a.set_xlabel("t [s]")
        a.set_title(title)
        a.legend(fontsize="small", ncol=2)
    fig.tight_layout()
    save_figure(fig, out_dir / "fig8_widths.png")
    # derivative enclosure: HOSM (paper) vs difference, unknown input 1
    fig, ax = plt.subplots(figsize=(10, 3.4))
    window = slice(int(5.0 / ac.TE), int(5.05 / ac.TE))
    paper = hosm_estimates["paper_lambda100"]
    levant = hosm_estimates["levant_gains"]
    assert paper.input_lower is not None and paper.input_upper is not None
    assert levant.input_lower is not None and levant.input_upper is not None
    ax.fill_between(
        t[window],
        paper.input_lower[window, 0],
        paper.input_upper[window, 0],
        color="tab:red",
        alpha=0.2,
        lw=0,
        label="HOSM λ=100, µ1=1.1 (paper)",
    )
    ax.fill_between(
        t[window],
        levant.input_lower[window, 0],
        levant.input_upper[window, 0],
        color="tab:green",
        alpha=0.3,
        lw=0,
        label="HOSM Levant gains, µ1=1.1",
    )
    ax.fill_between(
        t[window],
        est.input_lower[window, 0],
        est.input_upper[window, 0],
        color="tab:blue",
        alpha=0.4,
        lw=0,
        label="difference enclosure (recommended)",
    )
    ax.plot(t[window], rec.xi[window, 0], color="black", lw=1.0, label=r"truth $\xi_1$")
    ax.set_xlabel("t [s]")
    ax.set_title(r"Fig. 9: $\xi_1$ bounds from three derivative enclosures (50 ms window)")
    ax.legend(fontsize="small", loc="upper right")
    fig.tight_layout()
    save_figure(fig, out_dir / "fig9_derivative.png")


EXAMPLE = Example(
    NAME,
    SEED_FILE,
    "unknown-input interval observer on the 5-state lateral aircraft model (state and input bounds)",
    run,
)
