"""Campaign scaling: the manipulator-lpv campaign on 1, 2 and all cores, and the cut modelled up to 64 workers.

(a) The cost of one task of the manipulator campaign against its size (CPU seconds of ``campaign_task`` for
    1 and ``--probe`` runs, one process, after a warm-up): a fixed part (the time loop of the truth and of the
    observer's recursion, whatever the batch) and a part per run; their ratio is the campaign's
    ``task_overhead`` in runs. Also the design of a level's observer (``design_s``), which a worker process
    pays the first time it meets that level.
(b) ``run_campaign`` on a small grid (``--magnitudes`` cells of ``--runs`` runs, one level) with 1, 2 and
    all cores of this machine (``os.cpu_count()``): wall seconds (the local cluster's start included), tasks,
    parallel efficiency ``T1 / (W T_W)``.
(c) No machine with more cores is at hand: the paper's grid (5 levels x 5 magnitudes x 100 runs) and one
    ten times larger (1000 runs a cell) are modelled for W = 1 ... 64 workers from the task sizes alone,
    each task costing ``fixed + per_run * runs`` (from (a)), plus ``design_s`` for a worker's first task of
    each level, handed out in the order ``campaign_tasks`` returns them to the first free worker: the
    efficiency ``T1 / (W T_W)`` against one worker running the one-worker cut, and that of the former fixed
    cut (50 runs a task).

Writes benchmarks/campaign_scaling.json and prints a table. Measured on a shared machine, (b) is only
as good as the machine's other load; (c) is a model, not a measurement.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from intervalobs.diagnosis import campaign_tasks, run_campaign
from intervalobs.reproduce.manipulator_lpv import CAMPAIGN, campaign_task

MODEL_WORKERS = (1, 2, 4, 8, 16, 32, 64)
OLD_BATCH = 50
"""The fixed cut before issue 36: 50 runs a task, whatever the workers."""


def task_cost(probe: int) -> dict[str, float]:
    """CPU seconds of a level's design, and of one task of 1 run and of ``probe`` runs (after a warm-up task)."""
    start = time.process_time()
    campaign_task(0.05, 1.0, [0], 0)
    design = time.process_time() - start
    seconds = {}
    for size in (1, probe):
        start = time.process_time()
        campaign_task(0.05, 1.0, list(range(size)), 0)
        seconds[size] = time.process_time() - start
    per_run = max((seconds[probe] - seconds[1]) / (probe - 1), 1e-9)
    fixed = seconds[1] - per_run
    return {
        "design_s": design - seconds[1],
        "one_run_s": seconds[1],
        f"{probe}_runs_s": seconds[probe],
        "fixed_s": fixed,
        "per_run_s": per_run,
    }


def measured(workers: int, runs: int, magnitudes: list[float]) -> dict[str, float]:
    """Wall seconds of the small campaign on ``workers`` local workers (a fresh store)."""
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        result = run_campaign(
            CAMPAIGN, Path(out), runs=runs, levels=[0.05], magnitudes=magnitudes, workers=workers, progress=False,
            plots=False,
        )  # fmt: skip
        return {"workers": workers, "wall_s": time.perf_counter() - start, "tasks": result.tasks}


def makespan(tasks: list[tuple[float, float, list[int]]], workers: int, cost: dict[str, float]) -> float:
    """Seconds until ``workers`` workers finish ``tasks``, each handed in order to the first free worker."""
    finish = np.zeros(workers)
    levels: list[set[float]] = [set() for _ in range(workers)]
    for level, _, ids in tasks:
        w = int(np.argmin(finish))
        finish[w] += cost["fixed_s"] + cost["per_run_s"] * len(ids) + (0.0 if level in levels[w] else cost["design_s"])
        levels[w].add(level)
    return float(finish.max())


def modelled(cost: dict[str, float], runs: int) -> list[dict[str, float]]:
    """The paper's grid with ``runs`` runs a cell on W workers: the chosen cut and the former one."""
    overhead = cost["fixed_s"] / cost["per_run_s"]
    setup = cost["design_s"] / cost["per_run_s"]
    cells = [(lv, mg, list(range(runs))) for lv in CAMPAIGN.levels for mg in CAMPAIGN.magnitudes]
    old = campaign_tasks(cells, 1, batch=OLD_BATCH)
    serial = makespan(campaign_tasks(cells, 1, overhead=overhead, level_overhead=setup), 1, cost)
    serial_old = makespan(old, 1, cost)
    rows = []
    for w in MODEL_WORKERS:
        tasks = campaign_tasks(cells, w, overhead=overhead, level_overhead=setup)
        span, span_old = makespan(tasks, w, cost), makespan(old, w, cost)
        rows.append(
            {
                "workers": w,
                "tasks": len(tasks),
                "largest_task": max(len(ids) for _, _, ids in tasks),
                "makespan_s": span,
                "efficiency": serial / (w * span),
                "old_tasks": len(old),
                "old_makespan_s": span_old,
                "old_efficiency": serial_old / (w * span_old),
            }
        )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=30, help="runs per cell of the measured campaign (default 30)")
    parser.add_argument("--magnitudes", type=float, nargs="+", default=[1.0, 5.0], help="cells of the measured one")
    parser.add_argument("--probe", type=int, default=50, help="runs of the larger task in (a) (default 50)")
    parser.add_argument("--out", type=Path, default=Path(__file__).with_name("campaign_scaling.json"))
    args = parser.parse_args()
    cost = task_cost(args.probe)
    print(f"(a) one task: {cost['fixed_s']:.2f} s fixed + {cost['per_run_s']:.3f} s a run, a level's design "
          f"{cost['design_s']:.2f} s (CPU, one process)")  # fmt: skip
    cores = os.cpu_count() or 1
    runs = [measured(w, args.runs, args.magnitudes) for w in sorted({1, 2, cores})]
    for row in runs:
        row["efficiency"] = runs[0]["wall_s"] / (row["workers"] * row["wall_s"])
        print(f"(b) {row['workers']:3d} workers: {row['wall_s']:7.1f} s, {row['tasks']} tasks, efficiency "
              f"{row['efficiency']:.2f}")  # fmt: skip
    grids = {}
    for runs_a_cell in (CAMPAIGN.runs, 10 * CAMPAIGN.runs):
        model = modelled(cost, runs_a_cell)
        for row in model:
            print(f"(c) {runs_a_cell} runs a cell, {row['workers']:3d} workers: {row['tasks']:3d} tasks (largest "
                  f"{row['largest_task']:3d}), efficiency {row['efficiency']:.2f}; fixed 50-run cut: "
                  f"{row['old_tasks']} tasks, {row['old_efficiency']:.2f}")  # fmt: skip
        grids[str(runs_a_cell)] = model
    facts = {
        "cores": cores,
        "task_cost": cost,
        "measured": {"levels": [0.05], "magnitudes": args.magnitudes, "runs": args.runs, "rows": runs},
        "modelled_paper_grid": {
            "levels": CAMPAIGN.levels,
            "magnitudes": CAMPAIGN.magnitudes,
            "rows_by_runs_a_cell": grids,
        },
        "note": "measured rows on a shared machine; modelled rows from task sizes and the task cost of (a)",
    }
    args.out.write_text(json.dumps(facts, indent=2) + "\n")


if __name__ == "__main__":
    main()
