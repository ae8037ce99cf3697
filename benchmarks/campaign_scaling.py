"""Campaign scaling: the manipulator-lpv campaign on 1, 2 and all cores, and the cut modelled up to 64 workers.

(a) The costs of the manipulator campaign in CPU seconds, one process: a task's fixed part and its part per run
    (``campaign_task`` for 1 and ``--probe`` runs, warm), whose ratio is the campaign's ``task_overhead`` in
    runs; a level's model (``level_s``: a warm process's first task of a new level less a warm task), which a
    worker pays the first time it meets that level; and a fresh worker's start (``start_s``: importing the
    task's module, measured in a new interpreter, plus the first task's loading of the compiled kernels).
(b) ``run_campaign`` on a small grid (``--magnitudes`` cells of ``--runs`` runs, one level) with 1, 2 and
    all cores of this machine (``os.cpu_count()``): wall and CPU seconds (the local cluster's start and its
    workers included), the load average when it started, tasks, parallel efficiency ``T1 / (W T_W)``.
(c) No machine with more cores is at hand: the paper's grid (5 levels x 5 magnitudes x 100 runs) and one
    ten times larger (1000 runs a cell) are modelled for W = 1 ... 64 workers from the task sizes alone,
    each task costing ``fixed + per_run * runs`` (from (a)), plus ``level_s`` for a worker's first task of
    each level, handed out in the order ``campaign_tasks`` returns them to the first free worker: the
    efficiency ``T1 / (W T_W)`` against one worker running the one-worker cut, for warm workers (a running
    deployment whose workers have imported the library) and for fresh ones (every worker, the one-worker run's
    too, first pays ``start_s``), and that of the former fixed cut (50 runs a task, warm workers).

Writes benchmarks/campaign_scaling.json and prints a table. Measured on a shared machine, (b) is only
as good as the machine's other load; (c) is a model, not a measurement.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from intervalobs.diagnosis import campaign_tasks, run_campaign
from intervalobs.reproduce.manipulator_lpv import CAMPAIGN, campaign_task

MODEL_WORKERS = (1, 2, 4, 8, 16, 32, 64)
OLD_BATCH = 50
"""The fixed cut before issue 36: 50 runs a task, whatever the workers."""


def _import_s() -> float:
    """CPU seconds a fresh interpreter spends importing the campaign's task module (min of 3)."""
    code = "import time; import intervalobs.reproduce.manipulator_lpv; print(time.process_time())"
    runs = [subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True) for _ in range(3)]
    return min(float(run.stdout) for run in runs)


def task_cost(probe: int) -> dict[str, float]:
    """CPU seconds of a task's fixed part and runs, of a level's model and of a fresh worker's start (module doc)."""
    first, second = CAMPAIGN.levels[0], CAMPAIGN.levels[1]

    def cpu(level: float, size: int) -> float:
        start = time.process_time()
        campaign_task(level, 1.0, list(range(size)), 0)
        return time.process_time() - start

    first_task = cpu(first, 1)  # kernels loaded, level model built, one run
    seconds = {size: cpu(first, size) for size in (1, probe)}
    new_level = cpu(second, 1)
    per_run = max((seconds[probe] - seconds[1]) / (probe - 1), 1e-9)
    return {
        "start_s": _import_s() + max(first_task - new_level, 0.0),
        "level_s": max(new_level - seconds[1], 0.0),
        "one_run_s": seconds[1],
        f"{probe}_runs_s": seconds[probe],
        "fixed_s": seconds[1] - per_run,
        "per_run_s": per_run,
    }


def _cpu() -> float:
    """CPU seconds of this process and of its children that have ended (the local cluster's workers)."""
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def measured(workers: int, runs: int, magnitudes: list[float]) -> dict[str, float]:
    """Wall and CPU seconds of the small campaign on ``workers`` local workers (a fresh store)."""
    with tempfile.TemporaryDirectory() as out:
        load, cpu = os.getloadavg()[0], _cpu()
        start = time.perf_counter()
        result = run_campaign(
            CAMPAIGN, Path(out), runs=runs, levels=[0.05], magnitudes=magnitudes, workers=workers, progress=False,
            plots=False,
        )  # fmt: skip
        wall = time.perf_counter() - start
        return {"workers": workers, "wall_s": wall, "cpu_s": _cpu() - cpu, "tasks": result.tasks, "load_1min": load}


def makespan(tasks: list[tuple[float, float, list[int]]], workers: int, cost: dict[str, float], start: float) -> float:
    """Seconds until ``workers`` workers, ready after ``start`` s, finish ``tasks``, each to the first free worker."""
    finish = np.full(workers, start)
    levels: list[set[float]] = [set() for _ in range(workers)]
    for level, _, ids in tasks:
        w = int(np.argmin(finish))
        finish[w] += cost["fixed_s"] + cost["per_run_s"] * len(ids) + (0.0 if level in levels[w] else cost["level_s"])
        levels[w].add(level)
    return float(finish.max())


def modelled(cost: dict[str, float], runs: int) -> list[dict[str, float]]:
    """The paper's grid with ``runs`` runs a cell on W workers: the chosen cut (warm and fresh) and the former one."""
    overhead = cost["fixed_s"] / cost["per_run_s"]
    setup = cost["level_s"] / cost["per_run_s"]
    cells = [(lv, mg, list(range(runs))) for lv in CAMPAIGN.levels for mg in CAMPAIGN.magnitudes]
    old = campaign_tasks(cells, 1, batch=OLD_BATCH)
    one = campaign_tasks(cells, 1, overhead=overhead, level_overhead=setup)
    serial, serial_fresh = makespan(one, 1, cost, 0.0), makespan(one, 1, cost, cost["start_s"])
    serial_old = makespan(old, 1, cost, 0.0)
    rows = []
    for w in MODEL_WORKERS:
        tasks = campaign_tasks(cells, w, overhead=overhead, level_overhead=setup)
        span, span_old = makespan(tasks, w, cost, 0.0), makespan(old, w, cost, 0.0)
        span_fresh = makespan(tasks, w, cost, cost["start_s"])
        rows.append(
            {
                "workers": w,
                "tasks": len(tasks),
                "largest_task": max(len(ids) for _, _, ids in tasks),
                "makespan_s": span,
                "efficiency": serial / (w * span),
                "fresh_makespan_s": span_fresh,
                "fresh_efficiency": serial_fresh / (w * span_fresh),
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
    print(f"(a) one task: {cost['fixed_s']:.3f} s fixed + {cost['per_run_s']:.3f} s a run, a level's model "
          f"{cost['level_s']:.2f} s, a fresh worker's start {cost['start_s']:.2f} s (CPU, one process)")  # fmt: skip
    cores = os.cpu_count() or 1
    runs = [measured(w, args.runs, args.magnitudes) for w in sorted({1, 2, cores})]
    for row in runs:
        row["efficiency"] = runs[0]["wall_s"] / (row["workers"] * row["wall_s"])
        print(f"(b) {row['workers']:3d} workers: {row['wall_s']:7.1f} s wall, {row['cpu_s']:7.1f} s CPU, "
              f"{row['tasks']} tasks, efficiency {row['efficiency']:.2f} (load {row['load_1min']:.1f})")  # fmt: skip
    grids = {}
    for runs_a_cell in (CAMPAIGN.runs, 10 * CAMPAIGN.runs):
        model = modelled(cost, runs_a_cell)
        for row in model:
            print(f"(c) {runs_a_cell} runs a cell, {row['workers']:3d} workers: {row['tasks']:3d} tasks (largest "
                  f"{row['largest_task']:3d}), efficiency {row['efficiency']:.2f} (fresh workers "
                  f"{row['fresh_efficiency']:.2f}); fixed 50-run cut: "
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
        "note": "measured rows on a shared machine (load_1min: its load average when each started); modelled rows "
        "from task sizes and the costs of (a)",
    }
    args.out.write_text(json.dumps(facts, indent=2) + "\n")


if __name__ == "__main__":
    main()
