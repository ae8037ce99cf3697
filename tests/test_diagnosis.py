"""Isolation decisions, the Monte Carlo metric (118)–(120) and campaigns on Dask (seed 001)."""

from __future__ import annotations

import dataclasses
import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import closing
from pathlib import Path

import numpy as np
import pytest

from intervalobs.diagnosis import (
    MAX_BATCH,
    SCHEDULER_TIMEOUT,
    Campaign,
    CampaignInterrupted,
    _makespan,
    campaign_tasks,
    first_negative_time,
    isolation_outcome,
    psi_hat,
    run_campaign,
    runs_for_sigma,
    scenario_success,
)
from intervalobs.errors import ArgumentError, BoundsError, DataError, SchedulerError

CALLS: list[int] = []


def _toy_task(level, magnitude, run_ids, seed):
    """Success iff magnitude > 10·level (a detectability threshold growing with the uncertainty)."""
    CALLS.append(len(run_ids))
    rows = []
    for r in run_ids:
        for s in range(2):
            ok = s == 0 or magnitude > 10 * level
            rows.append((r, s, ok, False, [None, None]))
    return rows


TOY = Campaign(name="toy", task=_toy_task, scenarios=("1", "2"), levels=(0.1, 0.3), magnitudes=(1.0, 5.0), runs=6)


def test_first_negative_time_and_outcome():
    t = np.linspace(0, 4, 5)
    lower = np.array([[1, 1], [1, 1], [1, -1], [-1, 1], [2, 2]], dtype=float)
    upper = np.ones_like(lower)
    np.testing.assert_array_equal(first_negative_time(t, lower), [3.0, 2.0])
    out = isolation_outcome(t, lower, upper, onset=2.5)
    assert out["false_alarm"] is True
    assert out["isolated"] == [1, 2]
    assert out["detection_time_s"] == [3.0, 2.0]
    out = isolation_outcome(t, np.abs(lower), upper, onset=2.5)
    assert out == {"false_alarm": False, "isolated": [], "detection_time_s": [], "first_negative_s": [None, None]}


def test_scenario_success_indicator():
    fn = np.array([[np.nan, np.nan], [21.0, np.nan], [21.0, 22.0], [19.0, np.nan], [np.nan, 21.0]])
    np.testing.assert_array_equal(scenario_success(fn, [], 20.0), [True, False, False, False, False])
    np.testing.assert_array_equal(scenario_success(fn, [1], 20.0), [False, True, False, False, False])
    np.testing.assert_array_equal(scenario_success(fn, [1, 2], 20.0), [False, False, True, False, False])


def test_psi_hat_and_runs_for_sigma():
    assert psi_hat([True, False, True, True]) == 0.75
    assert runs_for_sigma(0.05) == 100  # the paper's M = 100 (120)
    assert runs_for_sigma(0.1) == 25
    with pytest.raises(BoundsError):
        runs_for_sigma(0.0)
    with pytest.raises(DataError):
        psi_hat([])


def test_campaign_writes_psi_and_resumes_only_missing_runs(tmp_path):
    CALLS.clear()
    res = run_campaign(TOY, tmp_path, batch=4, progress=False, plots=False, processes=False, workers=1)
    assert res.computed == 2 * 2 * 6 and res.reused == 0
    data = json.loads((tmp_path / "psi.json").read_text())
    assert data["runs"] == 6 and data["levels"] == [0.1, 0.3] and data["magnitudes"] == [1.0, 5.0]
    assert data["psi"]["1"] == [[1.0, 1.0], [1.0, 1.0]]
    assert data["psi"]["2"] == [[0.0, 1.0], [0.0, 1.0]]
    # an interrupted campaign: drop some finished runs, rerun -> only those are computed
    con = sqlite3.connect(tmp_path / "campaign.sqlite")
    con.execute("DELETE FROM runs WHERE level = 0.3 AND magnitude = 5.0 AND run >= 3")
    con.commit()
    con.close()
    CALLS.clear()
    res = run_campaign(TOY, tmp_path, batch=4, progress=False, plots=True, processes=False, workers=1)
    assert res.computed == 3 and res.reused == 21 and sum(CALLS) == 3
    assert json.loads((tmp_path / "psi.json").read_text())["psi"] == data["psi"]
    assert (tmp_path / "psi_scenario2.png").exists()
    CALLS.clear()
    res = run_campaign(TOY, tmp_path, progress=False, plots=False, processes=False, workers=1)
    assert res.computed == 0 and CALLS == []


def test_campaign_rejects_empty_grid(tmp_path):
    with pytest.raises(ArgumentError, match="levels, magnitudes: expected at least one of each, got 0 and 2"):
        run_campaign(TOY, tmp_path, levels=[], progress=False, processes=False)


@pytest.mark.slow
def test_manipulator_campaign_cli(tmp_path):
    """A real (small) campaign through the CLI on a local Dask cluster: no false alarm in scenario 1,
    5 N·m faults isolated at the paper's uncertainty level."""
    cmd = [sys.executable, "-m", "intervalobs.cli", "campaign", "manipulator-lpv", "--runs", "2", "--levels", "0.05",
           "--magnitudes", "0.25", "5", "--out", str(tmp_path)]  # fmt: skip
    result = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
    assert result.returncode == 0, result.stderr
    data = json.loads((tmp_path / "manipulator-lpv" / "campaign" / "psi.json").read_text())
    assert data["psi"]["1"] == [[1.0, 1.0]]
    for s in ("2", "3", "4"):
        assert data["psi"][s][0][1] == 1.0


@pytest.mark.parametrize(
    "kwargs, pattern",
    [
        ({"runs": 0}, r"^runs: expected an integer >= 1, got 0$"),
        ({"workers": 0}, r"^workers: expected an integer >= 1, got 0$"),
        ({"batch": 0}, r"^batch: expected an integer >= 1, got 0$"),
        ({"seed": -1}, r"^seed: expected an integer >= 0, got -1$"),
        ({"levels": [0.1, -1]}, r"^levels\[1\]: expected a fraction in \[0, 1\) \(0.05 means ±5 %\), got -1$"),
        ({"levels": [10]}, r"^levels\[0\]: expected a fraction in \[0, 1\)"),
        ({"magnitudes": [1.0, 9.0]}, r"^magnitudes: expected fault sizes in \[0, 5\], got 1, 9$"),
        ({"magnitudes": []}, r"^levels, magnitudes: expected at least one of each, got 2 and 0$"),
    ],
    ids=["runs", "workers", "batch", "seed", "levels-negative", "levels-percent", "magnitudes", "no-magnitudes"],
)
def test_campaign_arguments_are_checked_before_anything_runs(tmp_path, kwargs, pattern):
    CALLS.clear()
    bounded = dataclasses.replace(TOY, magnitude_bound=5.0)
    with pytest.raises(ArgumentError, match=pattern):
        run_campaign(bounded, tmp_path / "out", progress=False, processes=False, **kwargs)
    assert CALLS == [] and not (tmp_path / "out").exists()


def test_unreachable_scheduler_fails_within_the_timeout(tmp_path):
    start = time.perf_counter()
    with pytest.raises(SchedulerError, match=r"^scheduler: expected the address of a running Dask scheduler"):
        run_campaign(TOY, tmp_path, scheduler="tcp://127.0.0.1:1", progress=False)
    assert time.perf_counter() - start < SCHEDULER_TIMEOUT + 10  # not Dask's default of 30 s


STORE: list[Path] = []


def _interrupting_task(level, magnitude, run_ids, seed):
    """The toy task; the third batch is interrupted as by Ctrl-C (SIGINT to this process) once the
    first two are in the store."""
    if len(CALLS) == 2:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            with closing(sqlite3.connect(STORE[0])) as con:
                if con.execute("SELECT COUNT(*) FROM runs").fetchone()[0] == 2 * 3 * 2:
                    break
            time.sleep(0.05)
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(1)  # the interrupt arrives while this batch runs
    return _toy_task(level, magnitude, run_ids, seed)


@pytest.fixture
def sigint_raises() -> Iterator[None]:
    """SIGINT raises KeyboardInterrupt, as in a terminal session: Python installs that handler only if SIGINT was not
    ignored at its start, and a suite started in the background of a shell inherits SIG_IGN."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


@pytest.mark.skipif(not hasattr(signal, "SIGINT") or sys.platform == "win32", reason="POSIX signals")
def test_interrupted_campaign_saves_finished_batches_and_resumes(tmp_path, sigint_raises):
    CALLS.clear()
    STORE[:] = [tmp_path / "campaign.sqlite"]
    interrupted = dataclasses.replace(TOY, task=_interrupting_task)
    with pytest.raises(CampaignInterrupted) as caught:
        run_campaign(interrupted, tmp_path, batch=3, progress=False, plots=False, processes=False, workers=1)
    store = tmp_path / "campaign.sqlite"
    with closing(sqlite3.connect(store)) as con:
        in_store = con.execute("SELECT COUNT(*) FROM runs").fetchone()[0] // 2  # two scenarios per run
    assert caught.value.saved == in_store == 2 * 3 and caught.value.total == 24
    assert str(caught.value) == f"6 of 24 runs saved in {store}; run the same command again to resume"
    CALLS.clear()
    res = run_campaign(TOY, tmp_path, batch=3, progress=False, plots=False, processes=False, workers=1)
    assert res.reused == 6 and res.computed == 18 and sum(CALLS) == 18
    assert res.psi == {"1": [[1.0, 1.0], [1.0, 1.0]], "2": [[0.0, 1.0], [0.0, 1.0]]}


def _failing_task(level, magnitude, run_ids, seed):
    """The toy task, except that the cell (0.3, 5.0) raises once its first task has been saved."""
    if level == 0.3 and magnitude == 5.0 and min(run_ids) > 0:
        raise FloatingPointError("the model overflowed\nsecond line")
    return _toy_task(level, magnitude, run_ids, seed)


def test_a_failing_task_is_recorded_and_the_others_go_on(tmp_path):
    CALLS.clear()
    failing = dataclasses.replace(TOY, task=_failing_task)
    with pytest.warns(RuntimeWarning, match=r"1 task\(s\) of toy raised \(first: FloatingPointError: the model"):
        res = run_campaign(failing, tmp_path, batch=3, progress=False, plots=False, processes=False, workers=1)
    assert res.failed == [
        {"level": 0.3, "magnitude": 5.0, "runs": [3, 4, 5], "error": "FloatingPointError: the model overflowed"}
    ]
    assert res.computed == 21 and sum(CALLS) == 21  # every other task ran, the failing cell's first one too
    assert np.isnan(res.psi["2"][1][1]) and res.psi["2"][0] == [0.0, 1.0] and res.psi["2"][1][0] == 0.0
    with closing(sqlite3.connect(tmp_path / "campaign.sqlite")) as con:
        assert con.execute("SELECT COUNT(*) FROM runs").fetchone()[0] == 21 * 2
    assert json.loads((tmp_path / "psi.json").read_text())["failed"] == res.failed
    CALLS.clear()  # the retry computes only the failed task's runs
    res = run_campaign(TOY, tmp_path, batch=3, progress=False, plots=False, processes=False, workers=1)
    assert res.failed == [] and res.computed == 3 and res.reused == 21 and sum(CALLS) == 3
    assert res.psi == {"1": [[1.0, 1.0], [1.0, 1.0]], "2": [[0.0, 1.0], [0.0, 1.0]]}
    assert "failed" not in json.loads((tmp_path / "psi.json").read_text())


def _efficiency(sizes: list[int], workers: int, overhead: float, serial_sizes: list[int]) -> float:
    """Runs per worker-time against one worker, the tasks handed out largest first."""
    finish = np.zeros(workers)
    for size in sorted(sizes, reverse=True):
        finish[np.argmin(finish)] += overhead + size
    return (len(serial_sizes) * overhead + sum(serial_sizes)) / (workers * finish.max())


@pytest.mark.parametrize("workers", [2, 3, 7, 16, 64])
@pytest.mark.parametrize("left", [[100] * 25, [100, 37, 3, 60]], ids=["paper-grid", "resumed"])
def test_tasks_are_cut_for_the_workers_present(left, workers):
    cells = [(0.1, float(i), list(range(100 - n, 100))) for i, n in enumerate(left)]
    tasks = campaign_tasks(cells, workers)
    sizes = [len(ids) for _, _, ids in tasks]
    for level, magnitude, ids in cells:  # every run left in exactly one task of its own cell
        assert sorted(r for lv, mg, part in tasks if (lv, mg) == (level, magnitude) for r in part) == ids
    assert max(sizes) <= MAX_BATCH and sizes == sorted(sizes, reverse=True)
    serial = [len(ids) for _, _, ids in campaign_tasks(cells, 1)]
    assert _efficiency(sizes, workers, 0.0, serial) >= (0.97 if sum(left) >= 25 * workers else 0.5)
    # a task's fixed cost (the manipulator's: about 60 runs) makes fewer, larger tasks the better cut
    heavy = [len(ids) for _, _, ids in campaign_tasks(cells, workers, overhead=60.0)]
    assert len(heavy) <= len(tasks) and max(heavy) >= max(sizes)
    assert max(len(ids) for _, _, ids in campaign_tasks(cells, workers, batch=7)) == 7


@pytest.mark.parametrize("workers", [2, 3, 8, 16, 64])
def test_a_level_cost_orders_the_tasks_so_each_worker_keeps_to_few_levels(workers):
    """With a cost per worker and level (the manipulator's model, ~14 runs), the order hands each worker of a
    first-free dispatch a contiguous share of the levels: every run still in one task of its cell, at most
    levels/workers + 2 levels per worker, and a shorter predicted campaign than the largest-first order (one
    task a worker: one task and one level long)."""
    levels = [0.02, 0.05, 0.1, 0.15, 0.2]
    cells = [(lv, mg, list(range(100))) for lv in levels for mg in (0.25, 0.5, 1.0, 2.0, 5.0)]
    tasks = campaign_tasks(cells, workers, overhead=0.5, level_overhead=14.0)
    for level, magnitude, ids in cells:
        assert sorted(r for lv, mg, part in tasks if (lv, mg) == (level, magnitude) for r in part) == ids
    finish, met = np.zeros(workers), [set() for _ in range(workers)]
    for level, _, ids in tasks:  # the first free worker takes the next task
        w = int(np.argmin(finish))
        finish[w] += 0.5 + len(ids) + (0.0 if level in met[w] else 14.0)
        met[w].add(level)
    assert max(len(m) for m in met) <= len(levels) / workers + 2
    batch = max(len(ids) for _, _, ids in tasks)
    plain = campaign_tasks(cells, workers, batch=batch, overhead=0.5)
    shorter = _makespan(tasks, workers, 0.5, 14.0)
    assert shorter < _makespan(plain, workers, 0.5, 14.0) if len(tasks) > workers else shorter <= batch + 14.5


def test_progress_shows_runs_per_second_and_the_cut(tmp_path, capsys):
    run_campaign(TOY, tmp_path, progress=True, plots=False, processes=False, workers=1)
    err = capsys.readouterr().err
    assert "run/s" in err and "4 tasks, 1 workers" in err and "24/24" in err
