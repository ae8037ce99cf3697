"""Tightness report: ratios ≥ 1 for sound observers, the table, the CLI subcommand."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from intervalobs import Bounds, IntervalObserver, LTISystem, simulate
from intervalobs.cli import main
from intervalobs.tightness import HullLowerBound, add_tightness, format_tightness, tightness_reference, tightness_report


def system_and_data(uncertain: bool) -> tuple[LTISystem, Bounds, np.ndarray, object]:
    A = np.array([[0.8, 0.1, 0.3], [0.0, 0.8, 0.2], [0.01, 0.0, 0.8]])
    d = 0.01 * np.ones((3, 3))
    system = LTISystem(A, [[0.0, 0.0, 1.0]], E=0.08 * np.eye(3), F=[[0.2]], dt=1.0, dA=(-d, d) if uncertain else None)
    bounds = Bounds((-np.ones(3), np.ones(3)), w=(-np.ones(3), np.ones(3)), v=(-np.ones(1), np.ones(1)))
    t = np.arange(40, dtype=float)
    return system, bounds, t, simulate(system, bounds, t, noise="extreme", seed=0)


def test_report_ratios_are_at_least_one_for_sound_observers() -> None:
    system, bounds, t, sim = system_and_data(uncertain=False)
    estimates = {
        "tube": IntervalObserver.design(system, bounds).run(t, sim.y),
        "framer": IntervalObserver.design(system, bounds, method="framer").run(t, sim.y),
    }
    reference = tightness_reference(system, bounds, t, sim.y, horizon=10)
    report = tightness_report(t, estimates, reference, start=5)
    assert report["reference"]["kind"] == "hull"
    for row in report["observers"].values():
        assert row["ratio"] >= 1.0 and row["reference_inside"]
    text = format_tightness(report, title="demo")
    assert "demo" in text and "framer" in text and "hull" in text


def test_uncertain_system_gets_a_labelled_lower_bound(tmp_path: Path) -> None:
    system, bounds, t, sim = system_and_data(uncertain=True)
    estimates = {"tube": IntervalObserver.design(system, bounds).run(t, sim.y)}
    summary: dict = {}
    result = add_tightness(
        summary,
        system,
        bounds,
        t,
        sim.y,
        None,
        estimates,
        horizon=10,
        samples=0,
        truth=(sim.dA, sim.x),
        fir_window=5,
        mccormick_horizon=5,
        mccormick_steps=30,
    )
    assert isinstance(result.reference, HullLowerBound)
    report = summary["tightness"]
    assert report["reference"]["kind"] == "lower_bound"
    assert "LOWER BOUND" in format_tightness(report)
    assert report["observers"]["tube"]["ratio"] >= 1.0
    fir = report["observers"]["RobustFiniteMemoryObserver"]
    assert fir["enclosure"] == report["observers"]["tube"]["enclosure"] == 1.0
    assert fir["reference_inside"] and fir["ratio"] >= 1.0 and fir["ms_per_step"] > 0 and fir["learn_s"] > 0
    assert fir["mean_width"] <= report["observers"]["tube"]["mean_width"]  # intersected with IntervalObserver
    # the McCormick window LP on the first 30 steps only: compared with the lower bound on those steps
    tight = report["observers"]["RobustHullEstimator McCormick"]
    assert tight["enclosure"] == 1.0 and tight["reference_inside"] and tight["ratio"] >= 1.0
    assert tight["ms_per_step"] > 0 and tight["horizon"] == 5
    assert tight["steps"] == [0, 29] and tight["steps_used"] == 30
    bound = np.sum(result.widths["lower bound (no sound estimator below)"], axis=-1)
    assert tight["reference_mean_width"] == pytest.approx(np.mean(bound[:30]), rel=1e-12)
    assert tight["ratio"] == pytest.approx(tight["mean_width"] / tight["reference_mean_width"], rel=1e-12)
    assert np.all(np.isnan(result.widths["RobustHullEstimator McCormick"][30:]))
    assert "steps" not in report["observers"]["tube"]  # the whole record
    assert "RobustHullEstimator McCormick * " in format_tightness(report)
    assert "oracle_hull" in report
    # the widths figure's data, drawn by the caller (this module writes no files)
    assert set(result.widths) == {
        "tube",
        "RobustFiniteMemoryObserver",
        "RobustHullEstimator McCormick",
        "lower bound (no sound estimator below)",
        "hull if ΔA were known",
    }
    assert all(w.shape == (t.size, system.n) for w in result.widths.values())
    assert not any(tmp_path.iterdir())


def test_cli_prints_the_table_from_a_results_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    report = {
        "reference": {"kind": "hull", "label": "exact hull", "mean_width": 1.0, "horizon": 40},
        "observers": {"interval": {"mean_width": 2.0, "ratio": 2.0, "reference_inside": True}},
        "best": "interval",
        "steps": [20, 199],
    }
    folder = tmp_path / "spring-mass-lti"
    folder.mkdir()
    (folder / "summary.json").write_text(json.dumps({"seed": "-", "tightness": report}))
    assert main(["tightness", "spring-mass-lti", "--results", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "interval" in out and "2.000" in out


def test_cli_rejects_unknown_names(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["tightness", "no-such-example"]) == 2
    assert "error:" in capsys.readouterr().err
