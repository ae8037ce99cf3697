"""Data that contradict the model: the estimate is kept up to the first empty box and says so."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from intervalobs import Bounds, Estimate, HullEstimator, IntersectionObserver, LTISystem, simulate
from intervalobs.cli import main
from intervalobs.errors import BoundsError
from intervalobs.estimate import enclosure_report
from intervalobs.records import write_model

A = [[0.8, 0.2], [-0.1, 0.7]]
BOUNDS = Bounds(x0=(-1, 1), w=(-0.01, 0.01), v=(-0.01, 0.01))


def _contradicting_record(steps: int = 40) -> tuple[LTISystem, np.ndarray, np.ndarray, np.ndarray]:
    """A record of a plant whose true A differs from the model's for k >= 10 (a fault): times, y, x."""
    model = LTISystem(A=A, C=[[1.0, 0.0]], dt=1.0)
    faulty = LTISystem(A=[[0.8, 0.2], [-0.1, 1.3]], C=[[1.0, 0.0]], dt=1.0)
    t = np.arange(steps, dtype=float)
    before = simulate(model, BOUNDS, t[:11], seed=1)
    after = simulate(faulty, Bounds(x0=(before.x[-1], before.x[-1]), w=(-0.01, 0.01), v=(-0.01, 0.01)), t[10:], seed=2)
    x = np.concatenate([before.x[:10], after.x])
    y = np.concatenate([before.y[:10], after.y])
    return model, t, y, x


def test_hull_reports_the_first_inconsistent_time_and_keeps_the_bounds_before() -> None:
    model, t, y, x = _contradicting_record()
    estimate = HullEstimator.design(model, BOUNDS, horizon=10, filtered=True).run(t, y)
    assert not estimate.consistent
    first = estimate.inconsistent_from
    assert first is not None and 10 < first < t[-1]
    kept = estimate.t < first
    assert np.all(np.isfinite(estimate.lower[kept])) and np.all(np.isnan(estimate.lower[~kept]))
    assert np.all(estimate.lower[kept] <= estimate.upper[kept])
    fault = 11  # up to t = 10 the plant is the model: those rows hold the truth
    assert enclosure_report(t[:fault], estimate.lower[:fault], x[:fault], estimate.upper[:fault]).fraction == 1.0
    assert estimate.enclosure(x).first_violation_time == 11.0  # checked up to inconsistent_from only
    consistent = HullEstimator.design(model, BOUNDS, horizon=10, filtered=True).run(t[:10], y[:10])
    assert consistent.consistent and consistent.inconsistent_from is None
    np.testing.assert_allclose(estimate.lower[:10], consistent.lower, atol=1e-9)


def test_from_boxes_marks_each_run_from_its_own_first_empty_box() -> None:
    t = np.arange(4.0)
    lower = np.zeros((2, 4, 1))
    upper = np.ones((2, 4, 1))
    upper[0, 2], upper[1, 3] = -1.0, -1.0
    estimate = Estimate.from_boxes(t, lower, upper, meta={"method": "m"})
    assert estimate.inconsistent_from == 2.0 and "inconsistent_from=2" in repr(estimate)
    assert np.isnan(estimate.lower[0, 2:]).all() and np.isfinite(estimate.lower[1, :3]).all()
    back = Estimate.from_pandas(estimate.to_pandas())
    assert back.inconsistent_from == 2.0 and np.isnan(back.upper[0, 3, 0])
    assert Estimate.from_boxes(t, lower, upper + 2).consistent


def test_nan_bounds_and_swapped_bounds_are_still_refused_when_built_directly() -> None:
    with pytest.raises(BoundsError, match="lower > upper"):
        Estimate([0.0, 1.0], [[0.0], [1.0]], [[1.0], [0.0]])
    with pytest.raises(BoundsError, match="NaN at t = 1"):
        Estimate([0.0, 1.0], [[0.0], [np.nan]], [[1.0], [1.0]])


def test_plot_marks_the_inconsistent_time() -> None:
    pytest.importorskip("matplotlib")
    t = np.arange(4.0)
    estimate = Estimate.from_boxes(t, np.zeros((4, 1)), [[1.0], [1.0], [-1.0], [1.0]])
    figure = estimate.plot()
    assert any(line.get_label() == "data contradict the model" for line in figure.axes[0].get_lines())


def test_cli_says_it_in_one_line_with_exit_code_zero(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    model, t, y, _ = _contradicting_record()
    model_file = write_model(tmp_path / "model.toml", model, BOUNDS)
    data = tmp_path / "record.csv"
    data.write_text("t,y1\n" + "".join(f"{a},{b!r}\n" for a, b in zip(t.tolist(), y[:, 0].tolist())))
    code = main(["estimate", str(model_file), str(data), "--observer", "hull", "--out", str(tmp_path / "out")])
    printed = capsys.readouterr().out.strip().splitlines()
    assert code == 0 and len(printed) == 1 and "contradict the model from t = " in printed[0]
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["consistent"] is False and 10 < summary["inconsistent_from"] < t[-1]


def test_batched_runs_stop_one_by_one() -> None:
    """A run that contradicts the model does not take the consistent runs' bounds with it."""
    model, t, y, _ = _contradicting_record()
    good = simulate(model, BOUNDS, t, seed=3)
    estimate = IntersectionObserver.design(model, BOUNDS).run(t, np.stack([y, good.y]))
    first = estimate.inconsistent_from
    assert first is not None and 10 < first < t[-1]
    assert np.isnan(estimate.lower[0, t >= first]).all() and np.isfinite(estimate.lower[1]).all()
    single = IntersectionObserver.design(model, BOUNDS).run(t, good.y)
    np.testing.assert_allclose(estimate.lower[1], single.lower, atol=1e-12)
