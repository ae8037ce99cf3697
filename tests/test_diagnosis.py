"""Isolation decisions, the Monte Carlo metric (118)–(120) and campaigns on Dask (seed 001)."""

from __future__ import annotations

import json
import sqlite3
import subprocess
import sys

import numpy as np
import pytest

from intervalobs.diagnosis import (
    Campaign,
    first_negative_time,
    isolation_outcome,
    psi_hat,
    run_campaign,
    runs_for_sigma,
    scenario_success,
)
from intervalobs.errors import BoundsError, DataError

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
    with pytest.raises(DataError):
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
