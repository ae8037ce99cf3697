"""Reproduction ``hgio-sampled``: the sampled-output high-gain paper's example, the HGIO designed for width next to the
paper's designs.

Designed for width (recommended): :meth:`HighGainIntervalObserver.design_for_width` (gain minimising
the modal steady-state width bound, disks derived from the optimum, Algorithm 1 in them) with the
modal intersample predictor and re-wrap.

Constructive design: Algorithm 1 (disks of Section 5.2, least-norm gain), Theorem 4.4 computed both
ways, the sound continuous–discrete observer of :mod:`intervalobs.observers.hgio`. Earlier design
(Thabet et al. 2021): θ = 1000 and ``L = θΔ_θ⁻¹K``; K is not printed, we take K = (1, 0, 0) (the
simplest K with ``A − LC`` Hurwitz and C-diagonalisable) and report K = (3, 3, 1) (the textbook
binomial high-gain choice) over a short horizon. Both state observers get the same output bounds.
The truth is integrated 4× finer than the observer, with bang-bang disturbances switching inside the
observer's steps and the paper's samples every 5 ms.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._docstrings import shared_docs
from ..design.high_gain import ThetaDesign, euler_radius_factor, theta_design
from ..design.regions import HalfPlane, HorizontalStrip, ModalDecomposition, modal_decomposition, place_in_disks
from ..estimate import Estimate, enclosure_report
from ..examples import hgio as example
from ..observers.continuous_nonlinear import ContinuousNonlinearObserver
from ..observers.hgio import HighGainIntervalObserver
from ..observers.window_inversion import ContinuousWindowObserver
from ..plotting import plot_widths, save_figure
from ..simulate import SampledSimulation, simulate_sampled
from ..systems.bounds import Bounds
from ..systems.continuous_nonlinear import ContinuousNonlinearSystem
from ..systems.sampled import SampledSystem
from .contract import Example, base_summary, write_reproduction

NAME = "hgio-sampled"
SEED_FILE = "004_a01fe651baa78161.txt"
RUNS = 3
SUBSTEPS = 4
THETA_ARBITRARY = 1000.0
K_ARBITRARY = np.array([1.0, 0.0, 0.0])
K_BINOMIAL = np.array([3.0, 3.0, 1.0])
BINOMIAL_HORIZON = 2.0
WIDTH_WINDOW = 5.0
EULER_HORIZON = 3.0
TUNED_DISKS = ((-2.0, 0.3), (-1.5 + 2.0j, 0.3), (-1.5 - 2.0j, 0.3))
TUNED_HORIZON = 8.0
PAPER_OBSERVER: dict[str, Any] = {"predictor": "box", "rewrap": False}
"""The observer of Theorems 4.2/4.5 as printed (box intersample predictor, no modal re-wrap)."""
WIDTH_WEIGHTS = (0.0, 1.0, 1.0)
"""x1 is measured (its box comes from the output bound); the design minimises the x2 + x3 widths."""
WIDTH_REGIONS = (HalfPlane(0.5), HorizontalStrip(5.0))
"""Constraint regions of the width design: decay rate at least 0.5, rotation below 5 rad/s."""
HULL_REFERENCE = {
    "width_mean": [0.048, 3.97, 2.75],
    "lower_bound_width_mean": [0.20, 1.27, 1.14],
    "how": "measured 2026-12-01 on this example, t >= 5 s: "
    "HullEstimator, the moving-window LP hull with e^{-|x|} in [0, 1] treated as bounded noise, window 200 "
    "samples; lower bound for any sound estimator under worst-case noise. Quoted, not recomputed here.",
}


GeneralEstimator = Callable[[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]], Estimate]
"""An estimator of the general continuous-time nonlinear path (issue 32), built for the sampled-output high-gain
paper's example: called with ``(t, y, u)`` of the reproduction's record (every run, ``y`` NaN between samples) and
returning its :class:`~intervalobs.estimate.Estimate` on the sample times it bounds (a subset of ``t``)."""

GENERAL_HORIZON = 10.0
"""Length (s) of the record the general estimators run on (2000 samples, about a minute for both); their widths
and the HGIO's are compared over ``[WIDTH_WINDOW, GENERAL_HORIZON]``."""
GENERAL_ORDER = 128
"""Generators kept by the general observer's zonotopes here (its default, 4 per state, is 16): the example's
x2-x3 block rotates (eigenvalues -0.5 ± 1.94i). With the axis box reduction (``reduction="box"``) the boxes wrap and
x2's width over the HGIO's was 15.0 (16 generators), 9.7 (64), 8.1 (128); with the default frame reduction it is
3.25, 3.07, 3.02 at the same cost per sample (``benchmarks/wrapping.json``)."""


def continuous_model(phi_in_field: bool) -> tuple[ContinuousNonlinearSystem, Bounds]:
    r"""The sampled-output high-gain paper's example with a clock state, and its boxes.

    States :math:`(x_1, x_2, x_3, s)` with :math:`\dot s = 1`, :math:`s(0) = 0`: the known input
    :math:`u = 3\sin s - 2\sin 3s` is then exact inside each sampling interval (a held input would not be).

    Parameters
    ----------
    phi_in_field : bool
        True: :math:`\dot x = Ax + B_u u + e^{-|x|} + d` as written. False:
        :math:`e^{-|x|} \in (0, 1]` joins the disturbance, :math:`\dot x = Ax + B_u u + 0.5 + w`,
        :math:`w \in d \pm 0.5` (every trajectory of the example is one of this model, so its bounds hold;
        the HGIO's ``phi_bounds`` use the same range).

    Returns
    -------
    ContinuousNonlinearSystem
    Bounds
    """
    a, b_u = example.A, example.B_U[:, 0]

    def f(x: Any, u: Any, p: Any) -> tuple[Any, ...]:
        drive = 3.0 * np.sin(x[3]) - 2.0 * np.sin(3.0 * x[3])
        linear = [a[i, 0] * x[0] + a[i, 1] * x[1] + a[i, 2] * x[2] + b_u[i] * drive for i in range(3)]
        extra = [np.exp(-np.abs(x[i])) for i in range(3)] if phi_in_field else [0.5] * 3
        return (*(term + more for term, more in zip(linear, extra)), 1.0 + 0.0 * x[3])

    e = np.vstack([np.eye(3), np.zeros((1, 3))])
    system = ContinuousNonlinearSystem(f, lambda x, u: (x[0],), n=4, E=e, state_names=["x1", "x2", "x3", "s"])
    given = example.bounds().resolve(example.system())
    spread = 0.0 if phi_in_field else 0.5
    x0 = (np.append(given.x0[0], 0.0), np.append(given.x0[1], 0.0))
    return system, Bounds(x0=x0, w=(given.w[0] - spread, given.w[1] + spread), v=given.v)


def _continuous_observer(phi_in_field: bool) -> GeneralEstimator:
    """The :class:`ContinuousNonlinearObserver` on :func:`continuous_model`, samples up to ``GENERAL_HORIZON``."""

    def estimate(t: NDArray[np.float64], y: NDArray[np.float64], u: NDArray[np.float64]) -> Estimate:
        system, bounds = continuous_model(phi_in_field)
        rows = np.flatnonzero(~np.isnan(y[0, :, 0]) & (t <= GENERAL_HORIZON + 1e-9))
        observer = ContinuousNonlinearObserver(system, bounds, example.SAMPLE_PERIOD, substeps=1, order=GENERAL_ORDER)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # recorded in meta["diverging"]
            full = observer.run(t[rows], y[:, rows])
        return Estimate(t[rows], full.lower[..., :3], full.upper[..., :3], meta={"diverging": full.meta["diverging"]})

    return estimate


GENERAL_WINDOW = 60
"""Samples in the window of :class:`ContinuousWindowObserver` here (after its start box)."""


def _window_observer() -> GeneralEstimator:
    """The :class:`ContinuousWindowObserver` on ``continuous_model(phi_in_field=False)``, samples up to
    ``GENERAL_HORIZON``."""

    def estimate(t: NDArray[np.float64], y: NDArray[np.float64], u: NDArray[np.float64]) -> Estimate:
        system, bounds = continuous_model(phi_in_field=False)
        rows = np.flatnonzero(~np.isnan(y[0, :, 0]) & (t <= GENERAL_HORIZON + 1e-9))
        observer = ContinuousWindowObserver(system, bounds, example.SAMPLE_PERIOD, window=GENERAL_WINDOW)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # recorded in meta["diverging"]
            full = observer.run(t[rows], y[:, rows])
        return Estimate(t[rows], full.lower[..., :3], full.upper[..., :3], meta={"diverging": full.meta["diverging"]})

    return estimate


GENERAL_ESTIMATORS: dict[str, GeneralEstimator] = {
    "continuous_nonlinear_observer": _continuous_observer(phi_in_field=True),
    "continuous_nonlinear_observer_phi_as_disturbance": _continuous_observer(phi_in_field=False),
    "continuous_window_observer": _window_observer(),
}
"""The general path (issue 32) on the same record as the HGIO, reported with ``--full`` in
``summary["design"]["general_path"]`` (width over the same window, its ratio to the recommended HGIO's, enclosure,
ms per sample)."""


def _sampling(example: Any) -> dict[str, Any]:
    """The sampling period and the input-rate bound that every design of the example assumes."""
    return {"h": example.STEP, "input_rate": example.INPUT_RATE}


def general_path(t: NDArray[np.float64], sim: Any, hgio: Estimate, hgio_ms_per_sample: float) -> dict[str, Any]:
    """Run every estimator of :data:`GENERAL_ESTIMATORS` on the record; widths next to the HGIO's.

    Parameters
    ----------
    t : numpy.ndarray, shape (T,)
        Grid of the record.
    sim : SampledRecord
        The truth and the measurements (``x``, ``y``, ``u``).
    hgio : Estimate
        The recommended HGIO's bounds on the grid (runs, T, n).
    hgio_ms_per_sample : float
        The HGIO's milliseconds per sample (all runs together).

    Returns
    -------
    dict
        Per estimator, over its sample times in ``[WIDTH_WINDOW, end of its estimate]``: ``width_mean``,
        ``hgio_width_mean`` (the HGIO's over the same rows), ``width_over_hgio``, ``enclosure``,
        ``ms_per_sample`` (all runs together, as ``hgio_ms_per_sample``) and ``diverging``; and the same
        estimator's boxes intersected with the HGIO's at its sample times (both contain the state, so their
        intersection does): ``intersected_width_mean``, ``intersected_over_hgio`` (never above 1) and
        ``intersected_enclosure``.
    """
    results: dict[str, Any] = {}
    for name, build_and_run in GENERAL_ESTIMATORS.items():
        start = time.perf_counter()
        est = build_and_run(t, sim.y, sim.u)
        seconds = time.perf_counter() - start
        rows = np.searchsorted(t, est.t - 1e-9)
        window = est.t >= WIDTH_WINDOW
        n = hgio.lower.shape[-1]
        width = (est.upper - est.lower)[..., window, :].reshape(-1, n).mean(axis=0)
        h_lower, h_upper = hgio.lower[..., rows, :], hgio.upper[..., rows, :]
        reference = (h_upper - h_lower)[..., window, :].reshape(-1, n).mean(axis=0)
        lower, upper = np.maximum(est.lower, h_lower), np.minimum(est.upper, h_upper)
        both = (upper - lower)[..., window, :].reshape(-1, n).mean(axis=0)
        results[name] = {
            "width_mean": width,
            "hgio_width_mean": reference,
            "width_over_hgio": width / reference,
            "intersected_width_mean": both,
            "intersected_over_hgio": both / reference,
            "intersected_enclosure": enclosure_report(est.t, lower, sim.x[..., rows, :], upper).as_dict(),
            "window_s": [WIDTH_WINDOW, float(est.t[-1])],
            "enclosure": est.enclosure(sim.x[..., rows, :]).as_dict(),
            "ms_per_sample": 1000.0 * seconds / est.t.size,
            "diverging": bool(est.meta.get("diverging", False)),
        }
    return {
        "hgio_ms_per_sample": hgio_ms_per_sample,
        "estimators": results,
        "status": "compared" if results else "no general estimator registered yet (GENERAL_ESTIMATORS)",
    }


def high_gain_gain(theta: float, K: np.ndarray) -> np.ndarray:
    """``L = θ Δ_θ⁻¹ K`` with ``Δ_θ = diag(1, 1/θ, …, 1/θ^{n-1})`` (the sampled-output high-gain paper, eq. (10)).

    Parameters
    ----------
    theta : float
        High-gain parameter.
    K : numpy.ndarray, shape (n,)
        Normalised gain.

    Returns
    -------
    numpy.ndarray, shape (n, 1)
    """
    n = K.size
    return (theta ** np.arange(1, n + 1) * K)[:, None]


def paper_designs() -> tuple[HighGainIntervalObserver, ModalDecomposition, ThetaDesign]:
    """The paper-faithful constructive observer and Theorem 4.4 read with the printed L₁ and v₁.

    Returns
    -------
    constructive : HighGainIntervalObserver
        Algorithm 1 in the paper's disks (least-norm gain), Theorems 4.2/4.5 as printed.
    printed_modal : ModalDecomposition
        Decomposition of ``A - L₁C`` for the printed L₁.
    printed : ThetaDesign
        Theorem 4.4 for the printed L₁, its paper reading with the printed v₁ (``paper_v1``).
    """
    system = example.system()
    bounds = example.bounds().resolve(system)
    d_radius, delta = bounds.w[1], bounds.v[1]  # the example's boxes are symmetric
    constructive = HighGainIntervalObserver.design(
        system,
        bounds,
        disks=example.DISKS,
        alpha_d=example.ALPHA_D,
        alpha_n=example.ALPHA_N,
        **_sampling(example),
        **PAPER_OBSERVER,
    )
    printed_l1 = np.array(example.PAPER["L1"])[:, None]
    printed_modal = modal_decomposition(system.A, system.C, printed_l1, order=[d.center for d in example.DISKS])
    printed = theta_design(
        printed_modal,
        printed_l1,
        system.C,
        d_radius,
        delta,
        example.ALPHA_D,
        example.ALPHA_N,
        paper_v1=np.array(example.PAPER["v1"]),
    )
    return constructive, printed_modal, printed


def paper_design_facts(
    constructive: HighGainIntervalObserver, printed_modal: ModalDecomposition, printed: ThetaDesign
) -> dict[str, Any]:
    """The keys of ``summary["design"]`` about the paper's designs that need no simulation.

    docs/paper-notes.md quotes them (checked by the test suite).

    Parameters
    ----------
    constructive : HighGainIntervalObserver
        The paper-faithful constructive observer (:func:`paper_designs`).
    printed_modal : ModalDecomposition
        Decomposition of ``A - L₁C`` for the printed L₁.
    printed : ThetaDesign
        Theorem 4.4 for the printed L₁ and v₁.

    Returns
    -------
    dict
        Gain, eigenvalues, disk margins, v₁, Theorem 4.4 in both readings for our and the printed L₁.
    """
    placement, ours = constructive.placement, constructive.theta_design
    assert placement is not None and ours is not None
    p1 = placement.modal.p1
    return {
        "L1": placement.L.ravel(),
        "p1": p1,
        "omega1": placement.modal.omega1,
        "eigenvalues": placement.eigenvalues,
        "disk_margins": placement.margins,
        "v1": placement.modal.v1,
        "v1_condition": placement.modal.condition,
        "radius_matrix_abscissa": placement.radius_abscissa,
        "alpha": ours.alpha_sound,
        "theta": ours.theta_sound,
        "alpha_theta_reading": "sound: (42) solved in real numbers at t = 1 s (paper readings under theorem44_*); "
        "the observer does not use theta (it cancels)",
        "lambda_min_M2": ours.lambda_min_M2,
        "theorem44_ours": _theta_dict(ours),
        "theorem44_with_printed_L1_v1": _theta_dict(printed),
        "printed_L1_eigenvalues": printed_modal.eigenvalues,
    }


@shared_docs
def run(out_dir: Path, seed: int, plots: bool, full: bool = True) -> dict[str, Any]:
    """Design both observers, simulate with bang-bang disturbances, write the contract files.

    %(reproduction_run)s
    full : bool
        Also run the short-horizon studies (:func:`_short_horizon_studies`) and the general continuous-time
        path on the same record (:func:`general_path`, ``summary["design"]["general_path"]``).

    %(reproduction_summary)s
    """
    system = example.system()
    bounds = example.bounds().resolve(system)
    d_radius, delta = bounds.w[1], bounds.v[1]  # the example's boxes are symmetric
    start = time.perf_counter()
    constructive, printed_modal, printed = paper_designs()
    assert constructive.placement is not None and constructive.theta_design is not None
    placement, ours = constructive.placement, constructive.theta_design
    l_arbitrary = high_gain_gain(THETA_ARBITRARY, K_ARBITRARY)
    arbitrary = HighGainIntervalObserver(
        system,
        bounds,
        l_arbitrary,
        example.STEP,
        output_gain=placement.L,
        theta=THETA_ARBITRARY,
        input_rate=example.INPUT_RATE,
        **PAPER_OBSERVER,
    )
    design_time = time.perf_counter() - start
    start = time.perf_counter()
    widthwise = HighGainIntervalObserver.design_for_width(
        system,
        bounds,
        phi_radius=example.PHI_RADIUS,
        weights=WIDTH_WEIGHTS,
        regions=WIDTH_REGIONS,
        **_sampling(example),
    )
    assert widthwise.width_design is not None
    width_design_time = time.perf_counter() - start

    t = np.arange(0.0, example.T_FINAL + example.STEP / 2, example.STEP)
    sim = simulate_sampled(
        system, bounds, t, u=example.input_signal, noise="extreme", seed=seed, runs=RUNS, substeps=SUBSTEPS
    )
    start = time.perf_counter()
    est_c = constructive.run(t, sim.y, sim.u)
    est_a = arbitrary.run(t, sim.y, sim.u)
    run_time = time.perf_counter() - start
    start = time.perf_counter()
    est_w = widthwise.run(t, sim.y, sim.u)
    width_run_time = time.perf_counter() - start

    studies = _short_horizon_studies(system, bounds, t, sim, (constructive, arbitrary, printed), est_c) if full else {}
    design_studies = {k: studies[k] for k in ("paper_euler_scheme", "tuned_disks_design", "binomial_design") if full}

    c45 = (est_c.meta["theorem45_lower"], est_c.meta["theorem45_upper"])
    a45 = (est_a.meta["theorem45_lower"], est_a.meta["theorem45_upper"])
    window = t >= WIDTH_WINDOW
    width_c = (c45[1] - c45[0])[:, window].mean(axis=(0, 1))
    width_a = (a45[1] - a45[0])[:, window].mean(axis=(0, 1))
    width_r = (est_c.upper - est_c.lower)[:, window].mean(axis=(0, 1))
    cx = sim.x[..., :1]
    output_report = enclosure_report(t, est_c.meta["output_lower"], cx, est_c.meta["output_upper"])
    width_design = widthwise.width_design
    w45 = (est_w.meta["theorem45_lower"], est_w.meta["theorem45_upper"])
    width_w = (est_w.upper - est_w.lower)[:, window].mean(axis=(0, 1))
    width_w_runs = (est_w.upper - est_w.lower)[:, window].mean(axis=1)
    width_theta = theta_design(
        width_design.placement.modal,
        width_design.L,
        system.C,
        d_radius,
        delta,
        example.ALPHA_D,
        example.ALPHA_N,
    )
    hull = np.array(HULL_REFERENCE["width_mean"])
    width_summary = {
        "label": "designed for width (recommended): gain minimising the modal steady-state width bound, "
        "disks derived from the optimum, Algorithm 1 in them; modal predictor and re-wrap on",
        "L1": width_design.L.ravel(),
        "optimum_L1": width_design.optimum_L.ravel(),
        "eigenvalues": width_design.placement.eigenvalues,
        "disks": [{"center": d.center, "radius": d.radius} for d in width_design.disks],
        "disk_margins": width_design.placement.margins,
        "constraint_regions": [repr(r) for r in width_design.regions],
        "v1_condition": width_design.placement.modal.condition,
        "separation": width_design.placement.modal.separation,
        "weights": width_design.weights,
        "output_radius_assumed": width_design.output_radius,
        "phi_radius": example.PHI_RADIUS,
        "bound_width_mean_theorem45": width_design.bound.mean,
        "bound_width_sup_theorem45": width_design.bound.sup,
        "measured_width_mean_theorem45": (w45[1] - w45[0])[:, window].mean(axis=(0, 1)),
        "width_mean": width_w,
        "width_mean_per_run": width_w_runs,
        "width_over_hull": width_w / hull,
        "goal": {"x1_max": 0.3, "x2_max": 8.0, "x3_max": 5.5, "met": bool(np.all(width_w <= [0.3, 8.0, 5.5]))},
        "enclosure": est_w.enclosure(sim.x).as_dict(),
        "output_width_mean": (est_w.meta["output_upper"] - est_w.meta["output_lower"])[:, window].mean(),
        "radius_matrix_abscissa": width_design.placement.radius_abscissa,
        "theorem44_sound": _theta_dict(width_theta),
        "output_gain": widthwise.output_gain.ravel(),
        "output_radius_abscissa": widthwise.output_radius_abscissa,
    }
    all_runs = {
        "recommended": est_w.enclosure(sim.x).as_dict(),
        "width_design_theorem45": enclosure_report(t, w45[0], sim.x, w45[1]).as_dict(),
        "constructive_refined": est_c.enclosure(sim.x).as_dict(),
        "constructive_theorem45": enclosure_report(t, *c45[:1], sim.x, c45[1]).as_dict(),
        "arbitrary_theta1000_theorem45": enclosure_report(t, a45[0], sim.x, a45[1]).as_dict(),
        **({"binomial_theta1000_theorem45": studies["binomial_enclosure"]} if full else {}),
        "output_Cx": output_report.as_dict(),
    }

    summary = base_summary(
        example=NAME,
        seed_file=SEED_FILE,
        observer="HighGainIntervalObserver.design_for_width (refined report)",
        t=t,
        x=sim.x[0],
        x_lower=est_w.lower[0],
        x_upper=est_w.upper[0],
        transient_s=0.0,
    )
    p1 = placement.modal.p1
    summary["design"] = {
        "width_design": width_summary,
        "reference": {**HULL_REFERENCE, "width_design_over_hull": width_w / hull},
        "constructive_label": "paper-faithful constructive design: the paper's disks, least-norm Algorithm 1 "
        "(L1 = 0 here), Theorems 4.2/4.5 with the box predictor, no re-wrap; the keys below without a prefix",
        **paper_design_facts(constructive, printed_modal, printed),
        "theta_used_by_observer": "none: theta cancels in exact arithmetic; the observer works in zeta = e^{theta t} z",
        "euler_radius_factor": {
            f"theta={th:g}": [euler_radius_factor(float(p), th, example.STEP) for p in sorted(set(np.round(p1, 6)))]
            for th in (0.0, ours.theta_sound, printed.theta_paper, THETA_ARBITRARY)
        },
        **design_studies,
        "arbitrary_design": {
            "theta": THETA_ARBITRARY,
            "K": K_ARBITRARY,
            "L": l_arbitrary.ravel(),
            "eigenvalues": arbitrary.state_modal.decomposition.eigenvalues,
            "width_mean_theorem45": width_a,
            **({"continuous_output": studies["continuous_output"]} if full else {}),
        },
        "constructive_width_mean_theorem45": width_c,
        "constructive_width_mean_refined": width_r,
        "recommended_width_mean": width_w,
        "previous_recommended_width_mean": width_r,
        "width_ratio_constructive_over_theta1000": width_c / width_a,
        "width_window_s": [WIDTH_WINDOW, example.T_FINAL],
        "output_width_mean": (est_c.meta["output_upper"] - est_c.meta["output_lower"])[:, window].mean(),
        "enclosure_all_runs": all_runs,
        "runs": RUNS,
        "truth_substeps": SUBSTEPS,
        "sample_period_s": example.SAMPLE_PERIOD,
        **(
            {
                "general_path": general_path(
                    t, sim, est_w, 1000.0 * width_run_time / int(np.sum(~np.isnan(sim.y[0, :, 0])))
                )
            }
            if full
            else {}
        ),
    }
    summary["paper"] = {
        "p1": example.PAPER["p1"],
        "omega1": example.PAPER["omega1"],
        "L1": example.PAPER["L1"],
        "alpha": example.PAPER["alpha"],
        "theta": example.PAPER["theta"],
        "theta_arbitrary": THETA_ARBITRARY,
        "claim": "constructive bounds narrower than the theta = 1000 design (Fig. 2)",
    }
    summary["runtime_s"] = {
        "design": design_time,
        "run": run_time,
        "width_design": width_design_time,
        "width_run": width_run_time,
    }
    write_reproduction(
        out_dir,
        summary,
        {
            "t": t,
            "x": sim.x[0],
            "x_lower": est_w.lower[0],
            "x_upper": est_w.upper[0],
            "width_design_x_lower": est_w.lower[0],
            "width_design_x_upper": est_w.upper[0],
            "width_design_theorem45_x_lower": w45[0][0],
            "width_design_theorem45_x_upper": w45[1][0],
            "constructive_x_lower": c45[0][0],
            "constructive_x_upper": c45[1][0],
            "constructive_refined_x_lower": est_c.lower[0],
            "constructive_refined_x_upper": est_c.upper[0],
            "arbitrary_theta1000_x_lower": a45[0][0],
            "arbitrary_theta1000_x_upper": a45[1][0],
            "y": sim.y[0],
            "y_lower": est_w.meta["output_lower"][0],
            "y_upper": est_w.meta["output_upper"][0],
            "constructive_y_lower": est_c.meta["output_lower"][0],
            "constructive_y_upper": est_c.meta["output_upper"][0],
        },
    )
    if plots:
        _figures(out_dir, t, sim.x[0], sim.y[0], est_c, est_w, a45)
    return summary


def _short_horizon_studies(
    system: SampledSystem,
    bounds: Bounds,
    t: np.ndarray,
    sim: SampledSimulation,
    designs: tuple[HighGainIntervalObserver, HighGainIntervalObserver, ThetaDesign],
    est_c: Estimate,
) -> dict[str, Any]:
    """The studies over the first seconds: the binomial gain, the paper's Euler scheme, tuned disks, Fig. 2(b).

    Parameters
    ----------
    system, bounds : SampledSystem, Bounds
        The example.
    t : numpy.ndarray
        Sample times of the record.
    sim : SampledSimulation
        The record (``RUNS`` runs).
    designs : tuple
        The constructive observer, the θ = 1000 one and the paper's θ design.
    est_c : Estimate
        The constructive observer's estimate over the whole record.

    Returns
    -------
    dict
        ``binomial_design``, ``binomial_enclosure``, ``paper_euler_scheme``, ``tuned_disks_design``,
        ``continuous_output``: entries of the summary's ``design``.
    """
    constructive, arbitrary, printed = designs
    assert constructive.placement is not None
    placement = constructive.placement
    # textbook binomial K over a short horizon (its gains reach 1e9: the widths say why)
    short = t <= BINOMIAL_HORIZON
    binomial = HighGainIntervalObserver(
        system,
        bounds,
        high_gain_gain(THETA_ARBITRARY, K_BINOMIAL),
        example.STEP,
        output_gain=placement.L,
        theta=THETA_ARBITRARY,
        input_rate=example.INPUT_RATE,
        **PAPER_OBSERVER,
    )
    est_b = binomial.run(t[short], sim.y[:, short], sim.u[short])

    # what theta does to the paper's Euler implementation (not sound; summary only, not saved as bounds)
    euler_window = t <= EULER_HORIZON
    exact_width = (est_c.meta["theorem45_upper"] - est_c.meta["theorem45_lower"])[:, euler_window]
    euler: dict[str, Any] = {"horizon_s": EULER_HORIZON}
    for theta in (printed.theta_paper, 100.0, THETA_ARBITRARY):
        paper_euler = HighGainIntervalObserver(
            system,
            bounds,
            placement.L,
            example.STEP,
            theta=theta,
            input_rate=example.INPUT_RATE,
            scheme="paper-euler",
            **PAPER_OBSERVER,
        )
        est_e = paper_euler.run(t[euler_window], sim.y[:, euler_window], sim.u[euler_window])
        lo_e, hi_e = est_e.meta["theorem45_lower"], est_e.meta["theorem45_upper"]
        report = enclosure_report(t[euler_window], lo_e, sim.x[:, euler_window], hi_e)
        euler[f"theta={theta:g}"] = {
            "enclosure": report.as_dict(),
            "first_violation_s": report.first_violation_time,
            "width_over_exact": (hi_e - lo_e)[:, -500:].mean(axis=(0, 1)) / exact_width[:, -500:].mean(axis=(0, 1)),
        }

    # disks that need output injection: Algorithm 1 gives a nonzero gain and the measurement is used
    tuned_window = t <= TUNED_HORIZON
    tuned_placement = place_in_disks(system.A, system.C, TUNED_DISKS)
    tuned = HighGainIntervalObserver(
        system,
        bounds,
        tuned_placement.L,
        example.STEP,
        output_gain=placement.L,
        input_rate=example.INPUT_RATE,
        **PAPER_OBSERVER,
    )
    est_t = tuned.run(t[tuned_window], sim.y[:, tuned_window], sim.u[tuned_window])
    late = t[tuned_window] >= WIDTH_WINDOW
    tuned_summary = {
        "disks": [{"center": c, "radius": r} for c, r in TUNED_DISKS],
        "L1": tuned.L.ravel(),
        "eigenvalues": tuned.state_modal.decomposition.eigenvalues,
        "horizon_s": TUNED_HORIZON,
        "enclosure": est_t.enclosure(sim.x[:, tuned_window]).as_dict(),
        "width_mean_theorem45": (est_t.meta["theorem45_upper"] - est_t.meta["theorem45_lower"])[:, late].mean(
            axis=(0, 1)
        ),
        "width_mean_refined": (est_t.upper - est_t.lower)[:, late].mean(axis=(0, 1)),
        "constructive_width_mean_refined_same_window": (est_c.upper - est_c.lower)[:, tuned_window][:, late].mean(
            axis=(0, 1)
        ),
    }

    # the earlier design in its own setting (Fig. 2(b)): the output measured at every grid point
    y_every_step = sim.x[:, tuned_window] @ system.C.T + sim.v[:, tuned_window]
    est_cont = arbitrary.run(t[tuned_window], y_every_step, sim.u[tuned_window])
    continuous_summary = {
        "horizon_s": TUNED_HORIZON,
        "enclosure": enclosure_report(
            t[tuned_window], est_cont.meta["theorem45_lower"], sim.x[:, tuned_window], est_cont.meta["theorem45_upper"]
        ).as_dict(),
        "width_mean_theorem45": (est_cont.meta["theorem45_upper"] - est_cont.meta["theorem45_lower"])[:, late].mean(
            axis=(0, 1)
        ),
    }
    c45 = (est_c.meta["theorem45_lower"], est_c.meta["theorem45_upper"])
    b45 = (est_b.meta["theorem45_lower"], est_b.meta["theorem45_upper"])
    width_c_short = (c45[1] - c45[0])[:, short].mean(axis=(0, 1))
    width_b_short = (b45[1] - b45[0]).mean(axis=(0, 1))
    return {
        "binomial_design": {
            "K": K_BINOMIAL,
            "L": high_gain_gain(THETA_ARBITRARY, K_BINOMIAL).ravel(),
            "eigenvalues": binomial.state_modal.decomposition.eigenvalues,
            "horizon_s": BINOMIAL_HORIZON,
            "width_ratio_constructive_over_binomial": width_c_short / width_b_short,
        },
        "binomial_enclosure": enclosure_report(t[short], b45[0], sim.x[:, short], b45[1]).as_dict(),
        "paper_euler_scheme": euler,
        "tuned_disks_design": tuned_summary,
        "continuous_output": continuous_summary,
    }


def _theta_dict(design: Any) -> dict[str, Any]:
    return {
        "lambda_min_M2": design.lambda_min_M2,
        "alpha_paper_reading": design.alpha_paper,
        "theta_paper_reading": design.theta_paper,
        "alpha_sound_reading": design.alpha_sound,
        "theta_sound_reading": design.theta_sound,
        "condition34_from_t_paper": design.t_star_paper,
        "condition34_from_t_sound": design.t_star_sound,
        "abs_v1_dr_at_t0": design.condition34_at_0,
        "mat35_abscissa_paper": design.mat_abscissa_paper,
        "mat35_abscissa_sound": design.mat_abscissa_sound,
        "M1_abscissa": design.radius_abscissa,
    }


def _figures(
    out_dir: Path,
    t: np.ndarray,
    x: np.ndarray,
    y: np.ndarray,
    est_c: Estimate,
    est_w: Estimate,
    a45: tuple[np.ndarray, np.ndarray],
) -> None:
    import matplotlib.pyplot as plt

    labels = ["$x_1$", "$x_2$", "$x_3$"]
    panels = (
        (est_c.lower[0], est_c.upper[0], "(a) paper-faithful constructive design ($L_1 = 0$)", "tab:blue"),
        (est_w.lower[0], est_w.upper[0], "(b) designed for width (recommended)", "tab:green"),
        (
            a45[0][0],
            a45[1][0],
            "(c) earlier design θ = 1000, K = (1, 0, 0), unrefined",
            "tab:gray",
        ),
    )
    fig, axes = plt.subplots(3, 3, figsize=(14, 7.5), sharex=True)
    for i in range(3):
        for col, (lo, hi, title, colour) in enumerate(panels):
            ax = axes[i, col]
            ax.fill_between(t, lo[:, i], hi[:, i], color=colour, alpha=0.3, lw=0, label="bounds")
            ax.plot(t, x[:, i], color="black", lw=0.7, label="truth")
            ax.set_ylabel(labels[i])
            if i == 0:
                ax.set_title(title, fontsize=9)
                ax.legend(fontsize=7, loc="upper right")
        low = min(np.min(p[0][t >= WIDTH_WINDOW, i]) for p in panels[:2])
        high = max(np.max(p[1][t >= WIDTH_WINDOW, i]) for p in panels[:2])
        for col in range(2):
            axes[i, col].set_ylim(low - 0.1 * (high - low), high + 0.1 * (high - low))
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    fig.tight_layout()
    save_figure(fig, out_dir / "states.png")

    hull = np.broadcast_to(np.array(HULL_REFERENCE["width_mean"]), x.shape)
    widths = {
        "paper-faithful constructive (refined)": est_c.upper[0] - est_c.lower[0],
        "designed for width (refined)": est_w.upper[0] - est_w.lower[0],
        "earlier high-gain design θ = 1000 (not refined)": a45[1][0] - a45[0][0],
        "LP hull reference (mean, quoted)": hull,
    }
    save_figure(plot_widths(t, widths), out_dir / "widths.png")

    zoom = t <= 0.2
    fig, ax = plt.subplots(1, 1, figsize=(8, 3.2))
    for est, colour, label in ((est_c, "tab:blue", "constructive"), (est_w, "tab:green", "designed for width")):
        ax.fill_between(
            t[zoom],
            est.meta["output_lower"][0][zoom, 0],
            est.meta["output_upper"][0][zoom, 0],
            color=colour,
            alpha=0.3,
            lw=0,
            label=f"output bounds, {label}",
        )
    ax.plot(t[zoom], x[zoom, 0], color="black", lw=0.8, label="$Cx = x_1$")
    have = ~np.isnan(y[:, 0]) & zoom
    ax.errorbar(t[have], y[have, 0], yerr=0.1, fmt=".", ms=3, lw=0.5, color="tab:red", label="samples ± δ")
    ax.set_xlabel("t [s]")
    ax.set_title("bounds of the measured output between samples, first 0.2 s", fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    save_figure(fig, out_dir / "output.png")


EXAMPLE = Example(
    NAME,
    SEED_FILE,
    "sampled outputs, a nonlinear term: the observer designed for width, next to the paper's two designs",
    run,
    weight=16.0,
)
