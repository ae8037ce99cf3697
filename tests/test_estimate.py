import numpy as np
import pytest

from intervalobs import Estimate
from intervalobs.errors import BoundsError


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


@pytest.mark.parametrize("name", ["lower", "upper", "input_lower", "input_upper"])
def test_nan_bounds_are_refused_naming_which(name: str) -> None:
    arrays = {"lower": np.zeros((3, 2)), "upper": np.ones((3, 2)), "input_lower": -np.ones((3, 1))}
    arrays["input_upper"] = np.ones((3, 1))
    arrays[name][1, 0] = np.nan
    with pytest.raises(BoundsError, match=rf"^Estimate: {name}: expected numbers .*got NaN at t = 1 \(row 1\)$"):
        Estimate(np.arange(3.0), **arrays)


def test_empty_input_bounds_are_refused() -> None:
    with pytest.raises(BoundsError, match=r"^Estimate: expected input_lower <= input_upper, .* at t = 2 \(row 2\)$"):
        Estimate(np.arange(3.0), np.zeros((3, 1)), np.ones((3, 1)), np.array([[0.0], [0.0], [2.0]]), np.ones((3, 1)))


def test_infinite_bounds_mean_no_bound_and_enclose() -> None:
    """[-inf, inf] is "no bound yet": an Estimate accepts it and it encloses every finite value."""
    t = np.arange(3.0)
    lower = np.array([[-np.inf], [0.0], [0.0]])
    upper = np.array([[np.inf], [1.0], [1.0]])
    est = Estimate(t, lower, upper, lower.copy(), upper.copy())
    truth = np.array([[1e300], [0.5], [1.0]])
    report = est.enclosure(truth)
    assert report.fraction == 1.0 and report.max_violation == 0.0 and report.first_violation_time is None
    # the input fraction counts the informative rows: from the first finite input bound on
    assert est.input_enclosure(np.array([[7.0], [2.0], [0.5]])).fraction == 0.5


def test_plot_returns_a_figure():
    est = Estimate(np.arange(3.0), np.zeros((3, 2)), np.ones((3, 2)))
    fig = est.plot(truth=np.full((3, 2), 0.5))
    assert len(fig.axes) == 2


def test_repr_is_short_for_long_monte_carlo_records():
    t = np.arange(10_000.0)
    lower = np.zeros((20, t.size, 3))
    est = Estimate(t, lower, lower + 2.0, np.zeros((20, t.size, 1)), np.ones((20, t.size, 1)), meta={"method": "tube"})
    assert repr(est) == ("Estimate(method='tube', runs=20, samples=10000, t=[0, 9999], n=3, q=1, final_mean_width=2)")
    assert repr(Estimate(t[:2], lower[0, :2], lower[0, :2])) == (
        "Estimate(samples=2, t=[0, 1], n=3, final_mean_width=0)"
    )


@pytest.mark.parametrize(
    "content, pattern",
    [
        (None, r"^path: expected an existing file, got '.*' \(no such file\)$"),
        (b"hello", r"^path: expected an \.npz file written by Estimate\.save, got '.*' \(not a NumPy file\)$"),
        ("npy", r"\(a single array\)$"),
        ("other-npz", r"\(no t, lower, upper, meta\)$"),
    ],
    ids=["missing", "text", "npy", "other-npz"],
)
def test_load_refuses_what_save_did_not_write(tmp_path, content, pattern):
    from intervalobs.errors import FileError

    path = tmp_path / "estimate.npz"
    if content == "npy":
        with open(path, "wb") as f:
            np.save(f, np.ones(3))
    elif content == "other-npz":
        with open(path, "wb") as f:
            np.savez(f, a=np.ones(3))
    elif content is not None:
        path.write_bytes(content)
    with pytest.raises(FileError, match=pattern):
        Estimate.load(path)


def test_every_simulation_kind_is_a_truth_for_enclosure_and_plot() -> None:
    """A NonlinearSimulation (no times: by position) and a SampledSimulation (its grid) as the truth."""
    import matplotlib

    matplotlib.use("Agg")
    from intervalobs import Bounds, observe
    from intervalobs.simulate import simulate_nonlinear
    from intervalobs.systems import NonlinearSystem

    system = NonlinearSystem(
        lambda x: [0.9 * x[0] + 0.1 * np.sin(x[1]), 0.8 * x[1]], lambda x: [x[0]], [[1.0], [0.0]], [[1.0]]
    )
    bounds = Bounds(x0=([-1, -1], [1, 1]), w=(-0.01, 0.01), v=(-0.01, 0.01))
    truth = simulate_nonlinear(system, bounds, np.zeros((15, 1)), seed=2)
    estimate = observe(system, bounds, np.arange(15.0), truth.y)
    assert estimate.enclosure(truth).max_violation == 0.0
    assert estimate.plot(truth=truth) is not None
