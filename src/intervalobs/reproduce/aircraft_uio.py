"""Reproduction ``aircraft-uio`` (the aircraft UIO paper, §5): state and unknown-input bounds on the aircraft model.

What it does:

1. computes E, P from A, C, D (W = 0) and compares them with the printed ones; checks the printed K, T;
2. designs K, T (pole search, Metzler block form of T N T⁻¹; here the real distinct winner) and the observer;
3. simulates the exact truth for 20 s at Te = 1e-4 (200 001 samples) under four smooth worst-case noise
   realisations (sine / plateau measurement noise × sine / vertex process noise);
4. runs the observer with the provable difference enclosure of ẏ (recommended), and, for comparison,
   with the paper's HOSM (λ = 100, µ1 = 1.1) and with Levant-tuned gains, measuring the HOSM error;
5. adds two known control inputs (rudder steps, aileron sine, through the model's control matrix
   ``B = D``) on top of the unknown inputs: held commands (point-known) and continuous commands whose
   steps fall inside sampling steps (interval-known per step), and compares the widths with the
   no-input case;
6. writes summary.json, trajectories.npz (run 0) and the figures.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from .._docstrings import shared_docs
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


def _observer(
    derivative: str = "difference", hosm: HOSMDifferentiator | None = None, known_inputs: bool = False
) -> UnknownInputIntervalObserver:
    return UnknownInputIntervalObserver.design(
        ac.aircraft_system(known_inputs),
        ac.aircraft_bounds(),
        D=ac.D,
        h=ac.TE,
        noise_rate=np.full(4, ac.DELTA_DOT_BAR),
        output_accel=np.full(4, ac.OUTPUT_ACCEL),
        derivative=derivative,  # type: ignore[arg-type]
        hosm=hosm,
        mu1=ac.MU1,
        hosm_transient=HOSM_TRANSIENT,
    )


def design_facts(observer: UnknownInputIntervalObserver) -> dict[str, Any]:
    """The design part of ``summary["design"]`` that needs no simulation (docs/paper-notes.md quotes it).

    Parameters
    ----------
    observer : UnknownInputIntervalObserver
        The designed observer.

    Returns
    -------
    dict
        Decoupling, coordinates, poles, the limit widths ρ_x, ρ_ξ and the paper's formula for them.
    """
    dec, co = observer.decoupling, observer.coords
    paper_rho_x, paper_rho_xi = observer.paper_rho()
    return {
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
        "poles": co.poles.real,
        "eig_N": np.sort(np.linalg.eigvals(co.N).real),
        "metzler_check": co.metzler_check,
        "metzler_form_M": co.M,
        "max_abs_TNTinv_minus_M": co.form_residual,
        "cond_T": co.cond_T,
        "pole_candidates_score": co.tried,
        "rho_x": observer.rho_x,
        "rho_xi": observer.rho_xi,
        "paper_formula_rho_x": paper_rho_x,
        "paper_formula_rho_xi": paper_rho_xi,
    }


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


@shared_docs
def run(out_dir: Path, seed: int, plots: bool, full: bool = True) -> dict[str, Any]:
    """Run the example and write summary.json, trajectories.npz and the figures into ``out_dir``.

    %(reproduction_run)s
    full : bool
        Also run the study with the rudder and aileron commands known (:func:`_known_inputs`).

    %(reproduction_summary)s
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
    known = _known_inputs(t, seed, est) if full else None
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
    width_final = est.width()[:, -1, :].max(axis=0)
    assert est.input_lower is not None and est.input_upper is not None
    input_final = (est.input_upper - est.input_lower)[:, -1, :].max(axis=0)
    summary["design"] = {
        **design_facts(observer),
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
        **({"known_inputs": known[0]} if known is not None else {}),
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
    if known is not None:
        _, known_est, known_rec = known
        trajectories.update(
            {
                # own truth (a different record): names outside the checker's "<observer>_x_lower" pattern
                "known_input_truth_state": known_rec.x,
                "known_input_truth_xi": known_rec.xi,
                "known_input_state_lower": known_est.lower,
                "known_input_state_upper": known_est.upper,
                "known_input_xi_lower": known_est.input_lower,
                "known_input_xi_upper": known_est.input_upper,
                "known_input_u": known_rec.u,
            }
        )
    write_reproduction(out_dir, summary, trajectories)
    if plots:
        _figures(out_dir, est0, rec0, observer, hosm_estimates)
        if known is not None:
            _known_input_figure(out_dir, known[1], known[2], est0)
    return summary


KNOWN_INPUT_CASES = (
    ("held", "sine", "sine"),
    ("held", "plateau", "vertex"),
    ("continuous", "plateau", "vertex"),
    ("continuous", "sine", "sine"),
)
"""(command kind, measurement-noise kind, process-noise kind) of the known-input runs."""


def _known_inputs(t: np.ndarray, seed: int, free: Estimate) -> tuple[dict[str, Any], Estimate, ac.AircraftRecord]:
    """Runs with the rudder/aileron commands known; widths against the no-input runs ``free``."""
    observer = _observer(known_inputs=True)
    after = t >= 1.0
    assert free.input_lower is not None and free.input_upper is not None
    free_w = free.width()[:, after].mean(axis=(0, 1))
    free_wi = (free.input_upper - free.input_lower)[:, after].mean(axis=(0, 1))
    cases = []
    shown: tuple[Estimate, ac.AircraftRecord] | None = None
    for i, (kind, dk, ok) in enumerate(KNOWN_INPUT_CASES):
        rec = ac.simulate_aircraft(t, seed=seed * 100 + 50 + i, delta_kind=dk, omega_kind=ok, control=kind)
        u = rec.u if kind == "held" else ac.control_box(t)
        est = observer.run(t, rec.y, u)
        assert est.input_lower is not None and est.input_upper is not None
        width = est.width()[after].mean(axis=0)
        input_width = (est.input_upper - est.input_lower)[after].mean(axis=0)
        cases.append(
            {
                "command": kind,
                "delta": dk,
                "omega": ok,
                "state": est.enclosure(rec.x).as_dict(),
                "input": est.input_enclosure(rec.xi).as_dict(),
                "mean_state_width_after_1s": width,
                "mean_input_width_after_1s": input_width,
                "state_width_ratio_to_no_input": width / free_w,
                "input_width_ratio_to_no_input": input_width / free_wi,
                "max_abs_g_dot": float(np.abs(rec.psi_ddot).max()),
            }
        )
        if kind == "continuous" and shown is None:
            shown = (est, rec)
    assert shown is not None
    summary = {
        "B": ac.B_CONTROL,
        "inputs": "u1 rudder: steps +0.1 rad at 2.00005 s, -0.15 rad at 6.00003 s (inside sampling steps); "
        "u2 aileron: 0.2 sin(0.8 t) rad",
        "held": "command sampled at t_k and held (zero-order hold, point-known)",
        "continuous": "the command itself; the observer gets per-step boxes (control_box)",
        "no_input_mean_state_width_after_1s": free_w,
        "no_input_mean_input_width_after_1s": free_wi,
        "PB_max": float(np.abs(observer.decoupling.P @ ac.B_CONTROL).max()),
        "cases": cases,
        "max_state_width_ratio": float(max(np.max(c["state_width_ratio_to_no_input"]) for c in cases)),
        "max_input_width_ratio": float(max(np.max(c["input_width_ratio_to_no_input"]) for c in cases)),
        "all_enclosed": all(c["state"]["max_violation"] == 0.0 and c["input"]["max_violation"] == 0.0 for c in cases),
    }
    return summary, shown[0], shown[1]


def _known_input_figure(out_dir: Path, est: Estimate, rec: ac.AircraftRecord, free: Estimate) -> None:
    import matplotlib.pyplot as plt

    from ..plotting import save_figure

    t = est.t
    sl = slice(None, None, 20)
    assert est.input_lower is not None and est.input_upper is not None
    fig, axes = plt.subplots(4, 2, figsize=(11, 9), sharex=True)
    flat = axes.ravel()
    flat[0].plot(t[sl], rec.u[sl, 0], label="rudder $u_1$")
    flat[0].plot(t[sl], rec.u[sl, 1], label="aileron $u_2$")
    flat[0].set_title("known commands [rad]")
    flat[0].legend(fontsize="small")
    panels = [(est.lower[:, i], est.upper[:, i], rec.x[:, i], f"$x_{i + 1}$") for i in range(5)]
    panels += [(est.input_lower[:, j], est.input_upper[:, j], rec.xi[:, j], rf"$\xi_{j + 1}$") for j in range(2)]
    for a, (lo, hi, truth, label) in zip(flat[1:], panels):
        a.fill_between(t[sl], lo[sl], hi[sl], color="tab:blue", alpha=0.35, lw=0, label="bounds")
        a.plot(t[sl], truth[sl], color="black", lw=0.8, label="truth")
        late = t >= 1.0
        a.set_ylim(min(truth.min(), lo[late].min()) - 0.2, max(truth.max(), hi[late].max()) + 0.2)
        a.set_title(label)
    flat[1].legend(fontsize="small", loc="upper right")
    for a in axes[-1]:
        a.set_xlabel("t [s]")
    fig.suptitle("Fig. 10: aircraft with known rudder/aileron commands (continuous, per-step boxes) and unknown ξ")
    fig.tight_layout()
    save_figure(fig, out_dir / "fig10_known_inputs.png")


def _figures(
    out_dir: Path,
    est: Estimate,
    rec: ac.AircraftRecord,
    observer: UnknownInputIntervalObserver,
    hosm_estimates: dict[str, Estimate],
) -> None:
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
    enclosures = (
        (paper, "tab:red", 0.2, "HOSM λ=100, µ1=1.1 (paper)"),
        (levant, "tab:green", 0.3, "HOSM Levant gains, µ1=1.1"),
        (est, "tab:blue", 0.4, "difference enclosure (recommended)"),
    )
    for enclosure, colour, alpha, label in enclosures:
        assert enclosure.input_lower is not None and enclosure.input_upper is not None
        ax.fill_between(
            t[window],
            enclosure.input_lower[window, 0],
            enclosure.input_upper[window, 0],
            color=colour,
            alpha=alpha,
            lw=0,
            label=label,
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
    weight=8.0,
)
