"""Figures of estimates: single runs, Monte Carlo batches (one run or the envelope), given axes."""

from __future__ import annotations

from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pytest

from intervalobs import Bounds, Estimate, IntervalObserver, LTISystem, simulate
from intervalobs.errors import DimensionError
from intervalobs.plotting import plot_estimate, plot_widths

RUNS = 5


@pytest.fixture(scope="module")
def record():
    """A guide-like batch: 2-state system with an input, 5 runs of extreme noise."""
    system = LTISystem([[0.0, 1.0], [-2.0, -3.0]], C=[[1.0, 0.0]], B=[[0.0], [1.0]])
    bounds = Bounds(x0=([-1.0, -1.0], [1.0, 1.0]), w=([-0.05, -0.05], [0.05, 0.05]), v=([-0.02], [0.02]))
    t = np.arange(0.0, 4.0, 0.05)
    u = np.sin(t)[:, None]
    truth = simulate(system, bounds, t, u=u, seed=2, runs=RUNS)
    estimate = IntervalObserver.design(system, bounds, h=0.05).run(t, truth.y, u)
    return truth, estimate


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def _band(axis):
    """Lower and upper bound lines of a panel (drawn right after the band)."""
    return axis.lines[0].get_ydata(), axis.lines[1].get_ydata()


def test_batch_envelope_contains_every_run_and_draws_every_truth(record) -> None:
    truth, estimate = record
    fig = estimate.plot(truth=truth)
    assert len(fig.axes) == 2
    for i, axis in enumerate(fig.axes):
        lower, upper = _band(axis)
        np.testing.assert_array_equal(lower, estimate.lower[..., i].min(axis=0))
        np.testing.assert_array_equal(upper, estimate.upper[..., i].max(axis=0))
        assert len(axis.lines) == 2 + RUNS  # two bound lines, one truth line per run
        assert np.all(estimate.lower[..., i] >= lower) and np.all(estimate.upper[..., i] <= upper)
    assert "envelope of 5 runs" in [t.get_text() for t in fig.axes[0].get_legend().get_texts()]


def test_one_run_of_a_batch_with_the_simulation_as_truth(record) -> None:
    truth, estimate = record
    fig = estimate.plot(truth=truth, run=3)
    for i, axis in enumerate(fig.axes):
        lower, upper = _band(axis)
        np.testing.assert_array_equal(lower, estimate.lower[3, :, i])
        np.testing.assert_array_equal(upper, estimate.upper[3, :, i])
        assert len(axis.lines) == 3
        np.testing.assert_array_equal(axis.lines[2].get_ydata(), truth.x[3, :, i])
    single = plot_estimate(estimate, truth=truth.x[-1], run=-1)  # a shared (T, n) truth with a chosen run
    np.testing.assert_array_equal(_band(single.axes[1])[1], estimate.upper[-1, :, 1])


def test_given_axes_time_unit_and_backend(record) -> None:
    truth, estimate = record
    backend = matplotlib.get_backend()
    fig, axes = plt.subplots(1, 3)
    before = plt.get_fignums()
    out = estimate.plot(truth=truth, run=0, ax=axes[1:], time_unit="s", labels=["position (m)", "speed (m/s)"])
    assert out is fig and plt.get_fignums() == before  # drew into the given axes, no new figure
    assert not axes[0].lines and axes[2].get_xlabel() == "t (s)" and axes[1].get_ylabel() == "position (m)"
    assert matplotlib.get_backend() == backend
    one = plot_estimate(estimate, run=0, inputs=True)  # no unknown input: nothing more to draw
    assert one.axes[-1].get_xlabel() == "t"


def test_time_unit_from_meta_and_a_single_run() -> None:
    t = np.arange(5.0)
    lower = np.zeros((5, 1))
    estimate = Estimate(t, lower, lower + 1.0, meta={"time_unit": "min"})
    fig = estimate.plot(truth=np.full((5, 1), 0.5))
    assert fig.axes[0].get_xlabel() == "t (min)" and len(fig.axes[0].lines) == 3


@pytest.mark.parametrize(
    ("options", "match"),
    [
        ({"run": RUNS}, r"run: expected an index in \[0, 5\), got 5"),
        ({"truth": np.zeros((3, 2))}, r"truth: expected shape \(80, 2\)"),
        ({"truth": np.zeros((RUNS + 1, 80, 2))}, "truth: expected 5 runs"),
        ({"labels": ["only one"]}, "labels: expected 2 labels"),
        ({"ax": "one axes"}, "ax: expected 2 axes"),
    ],
    ids=["run-out-of-range", "truth-shape", "truth-runs", "labels", "ax-count"],
)
def test_mismatches_name_the_argument(record, options, match) -> None:
    _, estimate = record
    with pytest.raises(DimensionError, match=match):
        estimate.plot(**options)


def test_single_run_estimate_refuses_a_batch_truth_without_run(record) -> None:
    truth, estimate = record
    single = Estimate(estimate.t, estimate.lower[0], estimate.upper[0])
    with pytest.raises(DimensionError, match="choose run="):
        single.plot(truth=truth)
    fig = single.plot(truth=truth, run=0)
    np.testing.assert_array_equal(fig.axes[0].lines[2].get_ydata(), truth.x[0, :, 0])
    with pytest.raises(DimensionError, match="run: expected None"):
        single.plot(run=0)


def test_the_library_never_switches_the_backend_or_shows() -> None:
    """Figures are for the caller to show or save: no module of the package picks a backend or blocks."""
    import intervalobs

    root = Path(intervalobs.__file__).parent
    calls = ("matplotlib.use(", "switch_backend(", "plt.show(")
    found = [f"{p.relative_to(root)}: {c}" for p in root.rglob("*.py") for c in calls if c in p.read_text()]
    assert found == []


def test_plot_psi_labels_the_axes_with_the_campaign_units() -> None:
    from intervalobs.plotting import plot_psi

    fig = plot_psi([[0.5, 1.0]], [0.1], [1.0, 2.0], "demo", "level (%)", "fault (N·m)")
    ax = fig.axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel(), ax.get_title()) == ("fault (N·m)", "level (%)", "demo")
    with pytest.raises(DimensionError, match=r"^psi: expected shape \(1, 2\), got \(2,\)"):
        plot_psi([0.5, 1.0], [0.1], [1.0, 2.0], "demo")


def test_widths_known_at_a_few_steps_get_markers_and_equal_widths_stay_visible() -> None:
    t = np.arange(10.0)
    sparse = np.full((10, 2), np.nan)
    sparse[[3, 7]] = 0.5
    dense = np.ones((10, 2))
    fig = plot_widths(t, {"a": dense, "b": dense, "bound": sparse})
    lines = fig.axes[0].get_lines()
    assert [line.get_marker() for line in lines] == ["None", "None", "o"]
    assert lines[0].get_linestyle() != lines[1].get_linestyle()
    plt.close(fig)
