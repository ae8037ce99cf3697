"""Width of the general continuous-time path on the sampled-output high-gain paper's example against the HGIO.

Runs :data:`intervalobs.reproduce.hgio_sampled.GENERAL_ESTIMATORS`' observer (``e^{-|x|}`` as disturbance, or in
the field) on the reproduction's record (seed 0, 3 runs, samples up to ``GENERAL_HORIZON``) for several
generator counts and zonotope reductions, and writes the mean widths over ``[WIDTH_WINDOW, GENERAL_HORIZON]``
divided by the recommended HGIO's, and the CPU ms per sample (all runs together), to
``benchmarks/wrapping.json`` (entries keyed ``"<model> order=<order> reduction=<reduction>"``, merged into the
file). Issue 32.

With ``--cases``, instead: the pendulum (10 s) and the chemostat (12 h) of ``benchmarks/continuous_cost.py``
(compiled kernels, substeps 2 and 1, CPU ms per sample the median of 3 after a warm-up, widths over the second half)
and the chemostat reproduction (``intervalobs reproduce chemostat``, 12 h, seed 0: the one zonotope's and the
bundle's X and S widths over the second half), for each reduction; entries keyed ``"<case> reduction=<reduction>"``.

Run with ``python benchmarks/wrapping.py [--orders 16 32 64 128] [--reductions box frame] [--field] [--cases]``.
"""

from __future__ import annotations

import argparse
import inspect
import json
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from intervalobs.examples import hgio as example
from intervalobs.observers.continuous_nonlinear import ContinuousNonlinearObserver
from intervalobs.observers.hgio import HighGainIntervalObserver
from intervalobs.reproduce import hgio_sampled as repro
from intervalobs.simulate import simulate_sampled

OUT = Path(__file__).with_name("wrapping.json")


def record() -> tuple[np.ndarray, Any, Any]:
    """The reproduction's record (seed 0) and the recommended HGIO's estimate on it."""
    system = example.system()
    bounds = example.bounds().resolve(system)
    widthwise = HighGainIntervalObserver.design_for_width(
        system,
        bounds,
        phi_radius=example.PHI_RADIUS,
        weights=repro.WIDTH_WEIGHTS,
        regions=repro.WIDTH_REGIONS,
        h=example.STEP,
        input_rate=example.INPUT_RATE,
    )
    t = np.arange(0.0, example.T_FINAL + example.STEP / 2, example.STEP)
    sim = simulate_sampled(
        system, bounds, t, u=example.input_signal, noise="extreme", seed=0, runs=repro.RUNS, substeps=repro.SUBSTEPS
    )
    return t, sim, widthwise.run(t, sim.y, sim.u)


def general(t: np.ndarray, sim: Any, hgio: Any, field: bool, order: int, reduction: str) -> dict[str, Any]:
    """One general observer's widths over the HGIO's, enclosure and CPU ms per sample."""
    system, bounds = repro.continuous_model(field)
    rows = np.flatnonzero(~np.isnan(sim.y[0, :, 0]) & (t <= repro.GENERAL_HORIZON + 1e-9))
    options: dict[str, Any] = {"substeps": 1, "order": order}
    if "reduction" in inspect.signature(ContinuousNonlinearObserver).parameters:
        options["reduction"] = reduction
    elif reduction != "box":
        raise SystemExit("this checkout has no reduction option")
    observer = ContinuousNonlinearObserver(system, bounds, example.SAMPLE_PERIOD, compiled=True, **options)
    observer.run(t[rows[:3]], sim.y[:, rows[:3]])  # warm-up: the compiled kernels loaded (or compiled) first
    start = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        est = observer.run(t[rows], sim.y[:, rows])
    seconds = time.process_time() - start
    lower, upper = est.lower[..., :3], est.upper[..., :3]
    truth = sim.x[..., rows, :]
    window = t[rows] >= repro.WIDTH_WINDOW
    width = (upper - lower)[:, window].reshape(-1, 3).mean(axis=0)
    reference = (hgio.upper - hgio.lower)[:, rows][:, window].reshape(-1, 3).mean(axis=0)
    tol = 1e-8 * (1.0 + np.abs(truth))
    enclosed = float(np.mean(np.all((lower - truth <= tol) & (truth - upper <= tol), axis=-1)))
    return {
        "width_mean": width.tolist(),
        "hgio_width_mean": reference.tolist(),
        "width_over_hgio": (width / reference).tolist(),
        "enclosure": enclosed,
        "cpu_ms_per_sample": 1000.0 * seconds / rows.size,
        "compiled": bool(est.meta["compiled"]),
    }


def cases(reduction: str) -> dict[str, Any]:
    """The continuous_cost cases and the chemostat reproduction with ``reduction``."""
    import functools
    import sys
    import tempfile

    from intervalobs.reproduce import chemostat

    sys.path.insert(0, str(Path(__file__).parent))
    import continuous_cost

    out: dict[str, Any] = {}
    for name, make in (
        ("pendulum_10s", continuous_cost.pendulum_record),
        ("chemostat_12h", continuous_cost.chemostat_record),
    ):
        system, bounds, h, t, y, u, truth = make()
        for substeps in (2, 1):
            observer = ContinuousNonlinearObserver(
                system, bounds, h, substeps=substeps, compiled=True, reduction=reduction
            )
            observer.run(t, y, u)
            costs = []
            for _ in range(3):
                clock = time.process_time()
                estimate = observer.run(t, y, u)
                costs.append(1000.0 * (time.process_time() - clock) / t.size)
            inside = (estimate.lower <= truth) & (truth <= estimate.upper)
            out[f"{name} substeps={substeps}"] = {
                "cpu_ms_per_sample": float(np.median(costs)),
                "mean_width_second_half": (estimate.upper - estimate.lower)[t >= 0.5 * t[-1]].mean(axis=0).tolist(),
                "enclosure": float(inside.mean()),
            }
    original = chemostat.ContinuousNonlinearObserver
    chemostat.ContinuousNonlinearObserver = functools.partial(original, reduction=reduction)  # type: ignore[misc]
    try:
        with tempfile.TemporaryDirectory() as folder:
            clock = time.process_time()
            summary = chemostat.run(Path(folder), 0, False, full=False)
            seconds = time.process_time() - clock
    finally:
        chemostat.ContinuousNonlinearObserver = original  # type: ignore[misc]
    bundle = summary["design"]["bundle"]
    out["reproduce_chemostat_12h"] = {
        "one_zonotope_biomass_mean_width_second_half": summary["design"]["biomass_mean_width_second_half"],
        "one_zonotope_width_state_mean": summary["width"]["state_mean"],
        "bundle": dict(bundle),
        "enclosure": summary.get("enclosure"),
        "cpu_s": seconds,
    }
    return out


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--orders", type=int, nargs="+", default=[16, 32, 64, 128])
    parser.add_argument("--reductions", nargs="+", default=["box"])
    parser.add_argument("--field", action="store_true", help="e^{-|x|} in the field (default: as disturbance)")
    parser.add_argument("--label", default="", help="suffix of the entries' keys")
    parser.add_argument("--cases", action="store_true", help="the pendulum and the chemostat instead")
    args = parser.parse_args()
    if args.cases:
        results = json.loads(OUT.read_text()) if OUT.exists() else {}
        for reduction in args.reductions:
            for key, entry in cases(reduction).items():
                results[f"{key} reduction={reduction}"] = entry
                print(key, reduction, json.dumps(entry, default=float), flush=True)
            OUT.write_text(json.dumps(results, indent=1, default=float) + "\n")
        return
    t, sim, hgio = record()
    results = json.loads(OUT.read_text()) if OUT.exists() else {}
    model = "phi_in_field" if args.field else "phi_as_disturbance"
    for reduction in args.reductions:
        for order in args.orders:
            entry = general(t, sim, hgio, args.field, order, reduction)
            key = f"{model} order={order} reduction={reduction}{args.label}"
            results[key] = entry
            print(key, json.dumps(entry), flush=True)
            OUT.write_text(json.dumps(results, indent=1) + "\n")


if __name__ == "__main__":
    main()
