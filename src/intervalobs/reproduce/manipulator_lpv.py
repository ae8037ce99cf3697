"""Reproduction ``manipulator-lpv``: Rotondo et al., Section 5 (LPV interval UIO on the two-joint manipulator).

Design: certified exact ranges of ΔA_R, ΔB_R over the parameter box; boundedness LMI (74) at the
paper's λ = 1 on a coarse grid, verified on the paper's 10 000-point grid for every subset pair; the
same with the naive bounds R·[ΔA] (infeasible at λ = 1). Simulation: the four scenarios of Section 5
(faults of 5 N·m from t = 20 s), truth by RK4 at 1 ms with our computed-torque controller, the
sampled interval UIO at 1 ms. Section ``angles_only``: the same four records with only the joint
angles measured (n_y = 2): velocity bounds of :class:`~intervalobs.observers.angles_only.AnglesOnlyObserver`
and isolation by a bank of consistency tests (the paper's signals cannot isolate: C B_un = 0). Also
defines ``CAMPAIGN`` for ``intervalobs campaign manipulator-lpv``.
"""

from __future__ import annotations

import functools
import itertools
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..design.lpv import boundedness_lmi, uio_observer_matrix, verify_boundedness
from ..diagnosis import Campaign, fault_signals, isolate, isolation_outcome, scenario_success
from ..errors import BoundsError, DesignError
from ..estimate import enclosure_report
from ..examples.manipulator import (
    _KD,
    _KP,
    FAULT_BOUND,
    FAULT_ONSET,
    LAMBDA,
    NOMINAL,
    PAPER_DELTA,
    TRUE_PARAMETERS,
    X0,
    ManipulatorModel,
    simulate_closed_loop,
)
from ..observers.angles_only import AnglesOnlyObserver
from ..observers.lpv import LPVIntervalUIO
from ..systems.bounds import Bounds
from .contract import Example, base_summary, write_reproduction

__all__ = ["CAMPAIGN", "EXAMPLE", "campaign_task", "run"]

FloatArray = NDArray[np.float64]

SEED_FILE = "001_a32a6ad4c1850a1f.txt"
SCENARIO_FAULTS = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
"""Fault directions of scenarios 1–4 (times the magnitude; Section 5 uses 5 N·m)."""
X0_RADIUS = np.array([np.pi / 12, np.pi / 12, 0.1, 0.1])
"""Our initial box x0 ± radius (the printed ξ̲0 lies above x0 in components 2 and 4)."""
H_STEP = 1e-3
T_FINAL = 30.0


def _coarse_grid(points: int = 8) -> FloatArray:
    """φ = x2 − x1 on a grid, x3, x4 ∈ {−1, 0, 1} (the (74) inequality is convex in x3, x4 on each
    orthant, so these vertices cover Θ for each φ)."""
    phis = np.linspace(-np.pi, np.pi, points, endpoint=False)
    return np.array([[0.0, p, a, b] for p in phis for a in (-1.0, 0.0, 1.0) for b in (-1.0, 0.0, 1.0)])


def _fine_grid() -> FloatArray:
    """The paper's 10 000 points: x1, x2 ∈ [−π, π], x3, x4 ∈ [−1, 1], 10 values each."""
    g = np.linspace(-np.pi, np.pi, 10)
    v = np.linspace(-1.0, 1.0, 10)
    return np.array(list(itertools.product(g, g, v, v)))


def boundedness_analysis(
    model: ManipulatorModel, lam: float, naive: bool = False, verify: bool = True
) -> dict[str, Any]:
    """Solve (74) at ``lam`` on the coarse grid and verify it on the fine grid; a dict for summary.json."""
    f = -lam * np.eye(4)

    def bounds(th: FloatArray) -> tuple[FloatArray, FloatArray]:
        if naive:
            return model.naive_rotated_bounds_at(th)
        lo, hi, _, _ = model.rotated_bounds_at(th)
        return lo, hi

    lo, hi = bounds(_coarse_grid())
    eps = (1.0, 2.0) if naive else (0.5, 1.0, 2.0)
    try:
        cert = boundedness_lmi(f, f, lo, hi, switchable=range(4), eps1_candidates=eps)
    except DesignError as exc:
        return {"lambda": lam, "feasible": False, "error": str(exc)}
    if verify:
        flo, fhi = bounds(_fine_grid())
        cert = verify_boundedness(cert, f, f, flo, fhi, switchable=range(4))
    return {"lambda": lam, **cert.as_dict()}


def _bound_ratio(model: ManipulatorModel) -> dict[str, float]:
    th = _fine_grid()
    lo, hi, _, _ = model.rotated_bounds_at(th)
    nlo, nhi = model.naive_rotated_bounds_at(th)
    w, nw = (hi - lo)[:, :2, 2:], (nhi - nlo)[:, :2, 2:]
    ok = w > 1e-9
    ratio = nw[ok] / w[ok]
    norm_ratio = np.linalg.norm(nhi - nlo, ord=2, axis=(1, 2)) / np.maximum(
        np.linalg.norm(hi - lo, ord=2, axis=(1, 2)), 1e-300
    )
    return {
        "entry_width_ratio_mean": float(ratio.mean()),
        "entry_width_ratio_max": float(ratio.max()),
        "norm_width_ratio_mean": float(norm_ratio[np.isfinite(norm_ratio) & (norm_ratio > 0)].mean()),
    }


def _figures(out_dir: Path, t: FloatArray, sig_lo: FloatArray, sig_hi: FloatArray, x: FloatArray, est: Any) -> None:
    import matplotlib.pyplot as plt

    from ..plotting import plot_estimate, save_figure

    for s in range(4):
        fig, axes = plt.subplots(2, 2, figsize=(9, 5.5), sharex=True)
        for j in range(2):
            for row, (sig, name) in enumerate(((sig_lo, "lower ε̲"), (sig_hi, "upper ε̄"))):
                ax = axes[row, j]
                ax.plot(t, sig[s, :, j], lw=1.0)
                ax.axhline(0.0, color="k", lw=0.6)
                ax.axvline(FAULT_ONSET, color="r", ls="--", lw=0.6)
                ax.set_title(f"{name}$^{{({j + 1})}}$")
                ax.set_ylim(
                    min(-0.5, float(sig[s, :, j].min()) * 1.05), max(1.5, float(np.percentile(sig[s, :, j], 99)))
                )
                if row == 1:
                    ax.set_xlabel("t (s)")
        fig.suptitle(f"Isolation signals, scenario {s + 1} (fault {SCENARIO_FAULTS[s] * 5} N·m for t > 20 s)")
        fig.tight_layout()
        fig.savefig(out_dir / f"scenario{s + 1}_isolation.png", dpi=100)
        plt.close(fig)
    fig = plot_estimate(est, truth=x, labels=["q1 (rad)", "q2 (rad)", "q̇1 (rad/s)", "q̇2 (rad/s)"], time_unit="s")
    save_figure(fig, out_dir / "scenario1_state_bounds.png")
    plt.close(fig)


HYPOTHESES = ("fault 1 absent", "fault 2 absent")
"""The angles-only isolation bank: one estimator per hypothesis, the other fault anywhere in ±5 N·m."""


def angles_only_analysis(
    model: ManipulatorModel, t: FloatArray, x: FloatArray, u: FloatArray
) -> tuple[dict[str, Any], dict[str, FloatArray]]:
    """The four scenarios with only the joint angles measured: velocity bounds and isolation.

    One :class:`~intervalobs.observers.angles_only.AnglesOnlyObserver` bank, a run per scenario and fault box:
    ``±5`` N·m on both faults (the state estimator, sound in every scenario) and, for the isolation,
    the box of each hypothesis of :data:`HYPOTHESES` (fault j fixed at 0). A negative consistency
    signal of hypothesis j proves fault j.

    Parameters
    ----------
    model : ManipulatorModel
        The manipulator.
    t : numpy.ndarray, shape (T,)
        Sample times (s).
    x, u : numpy.ndarray, shape (4, T, 4) and (4, T, 2)
        Truth and known torque of the four scenarios.

    Returns
    -------
    section : dict
        The ``angles_only`` section of summary.json.
    arrays : dict
        Bounds and signals for trajectories.npz.
    """
    f = FAULT_BOUND
    boxes = np.array([[[-f, -f], [f, f]], [[0.0, -f], [0.0, f]], [[-f, 0.0], [f, 0.0]]])
    runs = x.shape[0]
    t0 = time.perf_counter()
    bank = AnglesOnlyObserver(
        model,
        float(t[1] - t[0]),
        (np.asarray(X0)[2:] - X0_RADIUS[2:], np.asarray(X0)[2:] + X0_RADIUS[2:]),
        (np.repeat(boxes[:, 0], runs, axis=0), np.repeat(boxes[:, 1], runs, axis=0)),
        decay=LAMBDA,
    )
    res, signal_lower, signal_upper = bank.run_with_signals(
        t, np.concatenate([x[..., :2]] * 3), np.concatenate([u] * 3)
    )
    elapsed = time.perf_counter() - t0
    signal = np.minimum(signal_lower, signal_upper).min(axis=-1)  # (3·runs, T)
    hyp = np.stack([signal[runs : 2 * runs], signal[2 * runs :]], axis=-1)  # (runs, T, 2): column j = hypothesis j
    pre = t <= FAULT_ONSET
    settled = t >= 0.1
    points = model.system.test_points()
    cb_un = np.hstack([np.eye(2), np.zeros((2, 2))]) @ model.system.matrix_at("B_un", points)
    scenarios: dict[str, Any] = {}
    for s in range(runs):
        enc = enclosure_report(t, res.lower[s], x[s], res.upper[s])
        width = (res.upper[s] - res.lower[s])[:, 2:]
        outcome = isolation_outcome(t, hyp[s], hyp[s], FAULT_ONSET)
        active = [j + 1 for j in range(2) if SCENARIO_FAULTS[s, j] > 0]
        first = np.array(outcome["first_negative_s"], dtype=float)
        scenarios[str(s + 1)] = {
            "fault_Nm": (FAULT_BOUND * SCENARIO_FAULTS[s]).tolist(),
            "state_enclosure": enc.as_dict(),
            "velocity_width_mean": width[settled].mean(axis=0).tolist(),
            "velocity_width_max": width[settled].max(axis=0).tolist(),
            "velocity_abs_max": np.abs(x[s][:, 2:]).max(axis=0).tolist(),
            **outcome,
            "success": bool(scenario_success(first, active, FAULT_ONSET)),
            "min_signal_before_onset": hyp[s][pre][1:].min(axis=0).tolist(),
            "min_signal_state_estimator": float(signal[s][1:].min()),
        }
    section = {
        "measured": "joint angles only, y = (q1, q2), C = (I2 0), n_y = 2",
        "estimator": "AnglesOnlyObserver: nominal momentum p = M(φ)q̇, ζ = M(φ)(q̇ − λ(q − q_k)) on each step "
        "(F = −λI), ψ over the step's flow box (velocities from the estimated box: interval scheduling), "
        "intersected with the box of p_k given by the angle increment",
        "lambda": LAMBDA,
        "h": float(t[1] - t[0]),
        "velocity_prior_box": [
            (np.asarray(X0)[2:] - X0_RADIUS[2:]).tolist(),
            (np.asarray(X0)[2:] + X0_RADIUS[2:]).tolist(),
        ],
        "state_estimator_fault_box": boxes[0].tolist(),
        "hypotheses": {name: boxes[j + 1].tolist() for j, name in enumerate(HYPOTHESES)},
        "paper_isolation": "impossible with (29)–(30): B_un = (0; M̃⁻¹) gives C B_un = 0 for C = (I2 0), so "
        "rank(C B_un) = 0 < n_un = 2 and the signals' projections on H's columns see no fault",
        "C_B_un_max_abs": float(np.abs(cb_un).max()),
        "isolation": "fault j proved when the consistency signal of the hypothesis 'fault j absent' is negative",
        "width_reference": "no hull reference computed; velocity_abs_max gives the scale",
        "width_after_s": 0.1,
        "runtime_s": elapsed,
        "scenarios": scenarios,
    }
    arrays = {
        "angles_only_x_lower": res.lower[0],
        "angles_only_x_upper": res.upper[0],
        "angles_only_lower_scenarios": res.lower[:runs],
        "angles_only_upper_scenarios": res.upper[:runs],
        "angles_only_hypothesis_signals": hyp,
    }
    return section, arrays


def _angles_only_figure(out_dir: Path, t: FloatArray, x: FloatArray, arrays: dict[str, FloatArray]) -> None:
    import matplotlib.pyplot as plt

    lo, hi, hyp = (
        arrays["angles_only_lower_scenarios"],
        arrays["angles_only_upper_scenarios"],
        arrays["angles_only_hypothesis_signals"],
    )
    fig, axes = plt.subplots(2, 2, figsize=(10, 6))
    for j in range(2):
        ax = axes[0, j]
        ax.plot(t, lo[3, :, 2 + j] - x[3, :, 2 + j], lw=0.8, label="lower − truth")
        ax.plot(t, hi[3, :, 2 + j] - x[3, :, 2 + j], lw=0.8, label="upper − truth")
        ax.axhline(0.0, color="k", lw=0.6)
        ax.axvline(FAULT_ONSET, color="r", ls="--", lw=0.6)
        ax.set_ylim(-0.05, 0.05)
        ax.set_title(f"q̇{j + 1} bounds − truth (rad/s), scenario 4, angles only")
        ax.set_xlabel("t (s)")
        ax.legend(loc="upper right", fontsize=8)
    window = (t >= FAULT_ONSET - 0.02) & (t <= FAULT_ONSET + 0.02)
    for col, s in enumerate((1, 2)):
        ax = axes[1, col]
        for j in range(2):
            ms = 1e3 * (t[window] - FAULT_ONSET)
            ax.plot(ms, hyp[s, window, j], marker=".", ms=3, lw=0.8, label=f"hypothesis: {HYPOTHESES[j]}")
        ax.axhline(0.0, color="k", lw=0.6)
        ax.axvline(0.0, color="r", ls="--", lw=0.6)
        ax.set_yscale("symlog", linthresh=1e-3)
        ax.set_title(f"consistency signals, scenario {s + 1} (fault {s} from 20 s)")
        ax.set_xlabel("t − 20 s (ms)")
        ax.legend(loc="lower left", fontsize=8)
    fig.tight_layout()
    fig.savefig(out_dir / "angles_only.png", dpi=100)
    plt.close(fig)


def run(out_dir: Path, seed: int = 0, plots: bool = True, full: bool = True) -> dict[str, Any]:
    """Run the reproduction and write the contract files (summary.json, trajectories.npz, PNGs).

    Parameters
    ----------
    out_dir : Path
        Output folder.
    seed : int
        Unused (the scenarios are deterministic); kept for the CLI contract.
    plots : bool
        Write the figures.
    full : bool
        Also run the angles-only isolation bank (:func:`angles_only_analysis`) and (74) with the naive bounds.

    Returns
    -------
    dict
        The summary.
    """
    del seed
    t_start = time.perf_counter()
    model = ManipulatorModel()
    certificate = {
        "method": "vertex ranges certified by interval forward-mode derivatives; ã, c̃ affine (linear-fractional lemma)",
        "entries": list(model.bounds.names),
        "slack_max": model.bounds.slack.max(axis=1).tolist(),
        "delta_A_R_exact": bool(np.all(model.bounds.slack[4:8] == 0.0)),
        "certified_fraction_b": model.bounds.certified_fraction[:, 1].tolist(),
    }
    # Theorem 4.1 with the paper's Γ = −λI and H* (rows 3–4 = −λI): F from (101) on the grid
    grid = _coarse_grid()
    h_mat = np.vstack([np.eye(2), np.zeros((2, 2))])
    h_star = np.zeros((4, 4))
    h_star[2:, :2] = -LAMBDA * np.eye(2)
    f_grid = uio_observer_matrix(model.r_matrix(grid), h_mat, model.b_matrix(grid), -LAMBDA * np.eye(2), h_star)
    f_deviation = float(np.max(np.abs(f_grid + LAMBDA * np.eye(4))))
    exact = boundedness_analysis(model, LAMBDA)
    naive = {}
    if full:
        naive["lmi_74_naive_lambda_1"] = boundedness_analysis(model, LAMBDA, naive=True, verify=False)
        naive["lmi_74_naive_lambda_2"] = boundedness_analysis(model, 2.0, naive=True)
    ratio = _bound_ratio(model)
    t_design = time.perf_counter() - t_start

    t0 = time.perf_counter()
    t = np.arange(0.0, T_FINAL + H_STEP / 2, H_STEP)
    faults = FAULT_BOUND * SCENARIO_FAULTS
    params = np.tile(TRUE_PARAMETERS, (4, 1))
    x, u = simulate_closed_loop(t, params, faults)
    x0 = np.asarray(X0)
    obs = LPVIntervalUIO(
        model,
        H_STEP,
        -LAMBDA * np.eye(4),
        bounds=Bounds(x0=(x0 - X0_RADIUS, x0 + X0_RADIUS)),
        unknown_input=(-FAULT_BOUND * np.ones(2), FAULT_BOUND * np.ones(2)),
    )
    est, rec = isolate(obs, t, x, u)
    t_run = time.perf_counter() - t0
    angles_only, angles_arrays = angles_only_analysis(model, t, x, u) if full else ({}, {})

    scenarios: dict[str, Any] = {}
    pre = t <= FAULT_ONSET
    for s in range(4):
        outcome = isolation_outcome(t, rec.signal_lower[s], rec.signal_upper[s], FAULT_ONSET)
        horizon = pre if s > 0 else np.ones_like(pre)
        enc = enclosure_report(t[horizon], est.lower[s][horizon], x[s][horizon], est.upper[s][horizon])
        active = [j + 1 for j in range(2) if SCENARIO_FAULTS[s, j] > 0]
        scenarios[str(s + 1)] = {
            "fault_Nm": (faults[s]).tolist(),
            **outcome,
            "success": bool(scenario_success(np.array(outcome["first_negative_s"], dtype=float), active, FAULT_ONSET)),
            "state_enclosure_no_fault": {**enc.as_dict(), "until_s": float(t[horizon][-1])},
            "min_signal_before_onset": [
                float(np.min(rec.signal_lower[s][pre])),
                float(np.min(rec.signal_upper[s][pre])),
            ],
        }

    summary = base_summary(
        example=EXAMPLE.name,
        seed_file=SEED_FILE,
        observer="LPVIntervalUIO (interval UIO of Rotondo et al.), sound sampled-data step",
        t=t,
        x=x[0],
        x_lower=est.lower[0],
        x_upper=est.upper[0],
        transient_s=0.0,
    )
    summary["design"] = {
        "H": obs.H.tolist(),
        "lambda": LAMBDA,
        "F": (-LAMBDA * np.eye(4)).tolist(),
        "Gamma": (-LAMBDA * np.eye(2)).tolist(),
        "H_star": h_star.tolist(),
        "F_from_101_max_deviation_from_minus_lambda_I": f_deviation,
        "S": "S = R (A + λ I)  (36)–(42) with C = I",
        "bounds": "exact ranges of ΔA_R, ΔB_R over the parameter box (certified vertex extremes)",
        "bounds_certificate": certificate,
        "naive_vs_exact_width": ratio,
        "lmi_74_exact_lambda_1": exact,
        **naive,
        "analysis_margin": exact.get("fine_margin"),
        "x0_box": [(x0 - X0_RADIUS).tolist(), (x0 + X0_RADIUS).tolist()],
        "controller": "computed torque, nominal model, Kp = Kd = 4; reference q1 = π/12 + 0.5 sin 0.5t, "
        "q2 = −π/12 + 0.5 sin 0.7t",
        "truth_integrator": "RK4, h = 1 ms, torque held over each sample",
        "observer_step": "exact expm(Fh) and ∫expm(Fs)ds on interval enclosures of the step (flow box)",
        "fault_bounds": [-FAULT_BOUND, FAULT_BOUND],
        "negative_tolerance": 0.0,
        "scenarios": scenarios,
    }
    summary["scenarios"] = scenarios
    summary["paper"] = {
        "lambda": 1.0,
        "lmi_74": "assessed on a 10 000-point grid, feasible (no margin printed)",
        "detection_time_s": {"2": [21.16], "3": [20.02]},
        "isolated_by": {"2": "ε̄(1)", "3": "ε̄(2)", "4": "ε̄(1), ε̄(2)"},
        "xi0_lower_printed": [-np.pi / 6, np.pi / 6, np.pi / 12, np.pi / 12],
        "x0": list(X0),
        "nominal": list(NOMINAL),
        "delta": list(PAPER_DELTA),
        "true_parameters": list(TRUE_PARAMETERS),
    }
    summary["runtime_s"] = {"design": t_design, "run": t_run}
    if full:
        summary["angles_only"] = angles_only
        summary["runtime_s"]["angles_only"] = angles_only["runtime_s"]
    write_reproduction(
        out_dir,
        summary,
        {
            "t": t,
            "x": x[0],
            "x_lower": est.lower[0],
            "x_upper": est.upper[0],
            "x_scenarios": x,
            "lower_scenarios": est.lower,
            "upper_scenarios": est.upper,
            "signal_lower": rec.signal_lower,
            "signal_upper": rec.signal_upper,
            "u": u,
            **angles_arrays,
        },
    )
    if plots:
        from ..estimate import Estimate

        _figures(out_dir, t, rec.signal_lower, rec.signal_upper, x[0], Estimate(t, est.lower[0], est.upper[0]))
        if full:
            _angles_only_figure(out_dir, t, x, angles_arrays)
    return summary


EXAMPLE = Example(
    name="manipulator-lpv",
    seed_file=SEED_FILE,
    description="LPV interval UIO, fault isolation on a two-joint manipulator (4 scenarios)",
    run=run,
    weight=15.0,
)


# --------------------------------------------------------------------------------------------------
# Monte Carlo campaign (Fig. 5–8)
# --------------------------------------------------------------------------------------------------

CAMPAIGN_H = 2e-3
CAMPAIGN_SUBSTEPS = 2
CAMPAIGN_T_FINAL = 26.0
CAMPAIGN_BLOCK_ROWS = 8192
"""Samples times runs whose enclosures a task evaluates at once (LPVIntervalObserver.advance_many): long enough
blocks that the per-sample overhead of the array calls vanishes, short enough to stay in cache."""
CAMPAIGN_TASK_OVERHEAD = 0.5
"""Fixed cost of a campaign task in runs. Its 13 000-sample time loop (truth and observer) runs compiled, so a task
costs nearly its runs alone (issue 36; it was 60 runs when the loop ran in Python); the half run stands for Dask's
bookkeeping and the store. benchmarks/campaign_scaling.py measures it (``task_cost`` in campaign_scaling.json)."""
CAMPAIGN_LEVEL_OVERHEAD = 2.0
"""Cost, in runs, of a worker's first task of a level: the model's certified extremes (about 0.25 s, 2 runs of
0.12 s) built once per level and process. benchmarks/campaign_scaling.py measures it (``level_s``)."""


@functools.lru_cache(maxsize=16)
def _campaign_model(level: float) -> ManipulatorModel:
    return ManipulatorModel(delta=(level * NOMINAL[0], level * NOMINAL[1], level * NOMINAL[2]))


@functools.lru_cache(maxsize=16)
def _campaign_observer(level: float) -> LPVIntervalUIO:
    model = _campaign_model(level)
    x0 = np.asarray(X0)
    return LPVIntervalUIO(
        model,
        CAMPAIGN_H,
        -LAMBDA * np.eye(4),
        bounds=Bounds(x0=(x0 - X0_RADIUS, x0 + X0_RADIUS)),
        unknown_input=(-FAULT_BOUND * np.ones(2), FAULT_BOUND * np.ones(2)),
    )


def campaign_task(
    level: float, magnitude: float, run_ids: Sequence[int], seed: int
) -> list[tuple[int, int, bool, bool, list[float | None]]]:
    r"""Runs ``run_ids`` of one cell for the four scenarios, batched (one leading axis of 4·M runs).

    Uncertainty level ``level``: the observer's box is :math:`(a, b, c)(1 \pm \text{level})`, and each
    run draws its true :math:`\tilde a, \tilde b, \tilde c` uniformly in that box (the same draw for the
    four scenarios and every magnitude: run i of level ℓ uses ``default_rng([seed, ℓ·1e6, i])``).
    Faults of size ``magnitude`` act after 20 s in the directions of the scenario. Truth: RK4 at 1 ms;
    observer: 2 ms samples; horizon 26 s.

    Parameters
    ----------
    level : float
        Uncertainty level (relative half-width of the a, b, c intervals).
    magnitude : float
        Fault size (N·m).
    run_ids : sequence of int
        Run numbers of the cell to compute.
    seed : int
        Base seed.

    Returns
    -------
    list of tuple
        ``(run, scenario index, success, false_alarm, first negative time per fault)``.
    """
    if not 0.0 <= magnitude <= FAULT_BOUND:
        raise BoundsError(f"magnitude: expected a fault size in [0, {FAULT_BOUND:g}] , got {magnitude:g}")
    from ..examples.manipulator_kernel import closed_loop_block  # Numba only where a campaign runs

    obs = _campaign_observer(float(level))
    model = _campaign_model(float(level))
    ids = list(run_ids)
    m = len(ids)
    params = np.array(
        [np.random.default_rng([seed, round(level * 1e6), i]).uniform(model.p_lower, model.p_upper) for i in ids]
    )
    par = np.tile(params, (4, 1))
    faults = np.repeat(magnitude * SCENARIO_FAULTS, m, axis=0)
    x = np.tile(np.asarray(X0), (4 * m, 1))
    st = obs.init()
    zl = np.tile(st.internal["z_lower"], (4 * m, 1))
    zu = np.tile(st.internal["z_upper"], (4 * m, 1))
    first = np.full((4 * m, 2), np.nan)
    t = np.arange(0.0, CAMPAIGN_T_FINAL + CAMPAIGN_H / 2, CAMPAIGN_H)
    nominal, gains, step = np.asarray(NOMINAL), np.array([_KP, _KD]), CAMPAIGN_H / CAMPAIGN_SUBSTEPS
    samples = max(CAMPAIGN_BLOCK_ROWS // (4 * m), 1)
    for start in range(0, t.size, samples):
        tb = t[start : start + samples]
        xs, us = np.empty((tb.size, 4 * m, 4)), np.empty((tb.size, 4 * m, 2))
        closed_loop_block(x, tb, faults, FAULT_ONSET, par, nominal, gains, step, CAMPAIGN_SUBSTEPS, xs, us)
        *_, el, eh, zl, zu = obs.advance_many(zl, zu, xs, us)  # the truth of the block, then the observer on it
        neg = (fault_signals(obs.H, el) < 0) | (fault_signals(obs.H, eh) < 0)  # (samples, runs, faults)
        new = np.any(neg, axis=0) & np.isnan(first)
        first[new] = tb[np.argmax(neg, axis=0)][new]
    rows: list[tuple[int, int, bool, bool, list[float | None]]] = []
    for s in range(4):
        active = [j + 1 for j in range(2) if SCENARIO_FAULTS[s, j] > 0]
        block = first[s * m : (s + 1) * m]
        ok = scenario_success(block, active, FAULT_ONSET)
        for r, run_id in enumerate(ids):
            fn = [None if np.isnan(v) else float(v) for v in block[r]]
            early = bool(np.any(block[r] <= FAULT_ONSET))
            rows.append((run_id, s, bool(ok[r]), early, fn))
    return rows


CAMPAIGN = Campaign(
    name="manipulator-lpv",
    task=campaign_task,
    scenarios=("1", "2", "3", "4"),
    levels=(0.02, 0.05, 0.1, 0.15, 0.2),
    magnitudes=(0.25, 0.5, 1.0, 2.0, 5.0),
    runs=100,
    magnitude_bound=FAULT_BOUND,
    level_label="uncertainty level (% of nominal a, b, c)",
    magnitude_label="fault magnitude (N·m)",
    task_overhead=CAMPAIGN_TASK_OVERHEAD,
    level_overhead=CAMPAIGN_LEVEL_OVERHEAD,
    describe={
        "level": "relative half-width of the a, b, c intervals (true values uniform in the box)",
        "magnitude": "fault size (N·m) acting for t > 20 s",
        "indicator": "exactly the scenario's faults flagged (a signal < 0) after 20 s, none before",
        "horizon_s": CAMPAIGN_T_FINAL,
        "observer_step_s": CAMPAIGN_H,
    },
)
