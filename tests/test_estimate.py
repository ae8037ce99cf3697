import numpy as np
import pytest

from intervalobs import BoundsError, Estimate


def test_enclosure_report_and_roundtrip(tmp_path):
    t = np.arange(4.0)
    lower, upper = np.zeros((4, 2)), np.ones((4, 2))
    truth = np.full((4, 2), 0.5)
    truth[2, 1] = 1.5
    est = Estimate(t, lower, upper, meta={"method": "test", "transient_s": 0.0})
    report = est.enclosure(truth)
    assert report.fraction == pytest.approx(7 / 8) and report.max_violation == pytest.approx(0.5)
    assert report.first_violation_time == 2.0
    assert est.enclosure(truth, transient=3.0).fraction == 1.0
    est.save(tmp_path / "e.npz")
    back = Estimate.load(tmp_path / "e.npz")
    np.testing.assert_array_equal(back.upper, upper)
    assert back.meta["method"] == "test"


def test_empty_bounds_are_refused():
    with pytest.raises(BoundsError, match="lower > upper"):
        Estimate(np.arange(2.0), np.ones((2, 1)), np.zeros((2, 1)))


def test_plot_returns_a_figure():
    est = Estimate(np.arange(3.0), np.zeros((3, 2)), np.ones((3, 2)))
    fig = est.plot(truth=np.full((3, 2), 0.5))
    assert len(fig.axes) == 2
