"""Records in and out: model names, pandas/xarray exports of estimates and simulations, labelled records in run."""

import sys

import numpy as np
import pytest

from intervalobs import Bounds, Estimate, IntervalObserver, LTISystem, Simulation, simulate
from intervalobs.errors import DataError, DimensionError

pd = pytest.importorskip("pandas")
xr = pytest.importorskip("xarray")

H = 0.01


@pytest.fixture(scope="module")
def setup():
    system = LTISystem(
        [[0.0, 1.0], [-2.0, -0.5]],
        C=[[1.0, 0.0]],
        B=[[0.0], [1.0]],
        state_names=["position", "velocity"],
        output_names=["p_meas"],
        input_names=["force"],
    )
    bounds = Bounds(x0=([-1, -1], [1, 1]), w=([-0.1, -0.1], [0.1, 0.1]), v=([-0.01], [0.01]))
    observer = IntervalObserver.design(system, bounds, h=H)
    t = np.arange(0.0, 4.0, H)
    truth = simulate(system, bounds, t, u=np.sin(t)[:, None], noise="extreme", seed=4)
    return system, bounds, observer, truth


def test_names_default_given_and_checked():
    plain = LTISystem(np.eye(3), np.ones((2, 3)), B=np.ones((3, 1)))
    assert plain.state_names == ("x1", "x2", "x3") and plain.output_names == ("y1", "y2")
    assert plain.input_names == ("u1",)
    with pytest.raises(DimensionError, match=r"state_names: expected 2 names, got 1"):
        LTISystem(np.eye(2), [[1.0, 0.0]], state_names=["a"])
    with pytest.raises(DimensionError, match=r"output_names: expected distinct names, got 'a' more than once"):
        LTISystem(np.eye(2), np.eye(2), output_names=["a", "a"])
    with pytest.raises(DimensionError, match=r"input_names: expected a sequence of 1 non-empty strings"):
        LTISystem(np.eye(2), np.eye(2), B=np.ones((2, 1)), input_names="force")


def test_from_control_takes_the_labels():
    control = pytest.importorskip("control")
    labelled = control.ss(
        [[0, 1], [-2, -1]], [[0], [1]], [[1, 0]], 0, states=["pos", "vel"], inputs=["F"], outputs=["p"]
    )
    system = LTISystem.from_control(labelled)
    assert (system.state_names, system.output_names, system.input_names) == (("pos", "vel"), ("p",), ("F",))
    renamed = LTISystem.from_control(labelled, output_names=["angle"])
    assert renamed.output_names == ("angle",) and renamed.state_names == ("pos", "vel")
    unlabelled = LTISystem.from_control(control.ss([[0, 1], [-2, -1]], [[0], [1]], [[1, 0]], 0))
    assert unlabelled.state_names == ("x[0]", "x[1]")


def test_observer_estimate_carries_the_state_names(setup):
    _, _, observer, truth = setup
    estimate = observer.run(truth.t, truth.y, truth.u)
    assert estimate.state_names == ("position", "velocity") and estimate.input_names == ()
    fig = estimate.plot(truth=truth.x)
    assert [ax.get_ylabel() for ax in fig.axes] == ["position", "velocity"]


def test_a_dataframe_record_gives_the_numbers_of_the_arrays(setup):
    _, _, observer, truth = setup
    reference = observer.run(truth.t, truth.y, truth.u)
    frame = truth.to_pandas()  # columns position, velocity, p_meas, force: matched by name, the rest ignored
    assert list(frame.columns) == ["position", "velocity", "p_meas", "force"]
    from_frame = observer.run(frame.index, frame, frame)
    np.testing.assert_array_equal(from_frame.lower, reference.lower)
    np.testing.assert_array_equal(from_frame.upper, reference.upper)
    series = observer.run(truth.t, frame["p_meas"], frame["force"])
    np.testing.assert_array_equal(series.upper, reference.upper)
    stamped = frame.set_index(pd.Timestamp("2026-03-01 12:00") + pd.to_timedelta(truth.t, unit="s"))
    by_date = observer.run(stamped.index, stamped, stamped)
    np.testing.assert_allclose(by_date.upper, reference.upper, rtol=1e-12, atol=1e-12)
    dataset = truth.to_xarray()
    swapped = dataset["y"].transpose("output", "t")  # time dimension found by name, moved first
    np.testing.assert_array_equal(observer.run(truth.t, swapped, dataset["u"]).lower, reference.lower)


def test_a_labelled_record_is_checked_against_t_and_the_names(setup):
    _, _, observer, truth = setup
    frame = truth.to_pandas()
    shifted = frame.set_index(frame.index + 1e-3 * (np.arange(len(frame)) >= 7))
    with pytest.raises(DataError, match=r"y: expected its time index to be t, got 0\.071 at sample 7 where t = 0\.07"):
        observer.run(truth.t, shifted, frame)
    with pytest.raises(DataError, match=r"y: expected columns named \['p_meas'\].*missing \['p_meas'\]"):
        observer.run(truth.t, frame[["position"]], frame)
    with pytest.raises(DataError, match=r"u: expected columns named \['force'\]"):
        observer.run(truth.t, frame, frame.rename(columns={"force": "torque"}))
    with pytest.raises(DataError, match=r"t: expected uniform spacing h = 0\.01"):
        observer.run(frame.index[::2], frame.iloc[::2], frame.iloc[::2])
    bare = pd.DataFrame(truth.y)  # a frame without names or time: read like the array
    np.testing.assert_array_equal(
        observer.run(truth.t, bare, truth.u).lower, observer.run(truth.t, truth.y, truth.u).lower
    )


def test_estimate_tables_round_trip(tmp_path):
    t = np.arange(5.0)
    rng = np.random.default_rng(0)
    lower = rng.normal(size=(5, 2))
    inputs = np.full((5, 1), -np.inf), np.full((5, 1), np.inf)
    inputs[0][2:], inputs[1][2:] = -1.0, 2.0
    est = Estimate(t, lower, lower + 1.0, *inputs, meta={"method": "test", "gain": np.eye(2)}, state_names=["a", "b"])
    frame = est.to_pandas()
    assert list(frame.columns) == [f"{n}_{e}" for n in ("a", "b", "d1") for e in ("lower", "upper", "width")]
    assert frame.attrs["gain"] == [[1.0, 0.0], [0.0, 1.0]] and frame.index.name == "t"
    back = Estimate.from_pandas(frame)
    assert back.state_names == ("a", "b") and back.input_names == ("d1",) and back.meta["method"] == "test"
    np.testing.assert_array_equal(back.lower, est.lower)
    np.testing.assert_array_equal(back.input_upper, est.input_upper)
    frame.to_csv(tmp_path / "bounds.csv")  # attrs are lost in a CSV: the inputs are named instead
    read = pd.read_csv(tmp_path / "bounds.csv", index_col="t")
    from_csv = Estimate.from_pandas(read, input_names=["d1"])
    assert from_csv.state_names == ("a", "b")
    np.testing.assert_array_equal(from_csv.upper, est.upper)
    np.testing.assert_array_equal(from_csv.input_lower, est.input_lower)
    dataset = est.to_xarray()
    assert dataset["lower"].dims == ("t", "state") and list(dataset["state"].values) == ["a", "b"]
    np.testing.assert_allclose(dataset["width"].values, np.ones((5, 2)), rtol=1e-15)
    assert dataset["input_lower"].dims == ("t", "input") and dataset.attrs["method"] == "test"
    est.save(tmp_path / "e.npz")
    assert Estimate.load(tmp_path / "e.npz").state_names == ("a", "b")
    with pytest.raises(DataError, match=r"frame: expected NAME_lower and NAME_upper columns"):
        Estimate.from_pandas(read[["a_lower"]])


def test_monte_carlo_tables_have_a_run_level(setup):
    system, bounds, observer, _ = setup
    t = np.arange(0.0, 0.5, H)
    runs = simulate(system, bounds, t, u=np.cos(t)[:, None], seed=2, runs=3)
    frame = runs.to_pandas()
    assert frame.index.names == ["run", "t"] and len(frame) == 3 * t.size
    back = Simulation.from_pandas(frame)
    np.testing.assert_array_equal(back.x, runs.x)
    np.testing.assert_array_equal(back.dA, runs.dA)
    estimate = observer.run(t, runs.y, runs.u)
    np.testing.assert_array_equal(Estimate.from_pandas(estimate.to_pandas()).upper, estimate.upper)
    assert estimate.to_xarray()["upper"].dims == ("run", "t", "state")
    assert runs.to_xarray()["u"].shape == (3, t.size, 1)


def test_simulation_table_and_name_clash(setup):
    system, bounds, _, truth = setup
    back = Simulation.from_pandas(truth.to_pandas())
    assert back.output_names == ("p_meas",) and back.w.shape == (truth.t.size, 0)
    np.testing.assert_array_equal(back.u, truth.u)
    clash = LTISystem(system.A, system.C, state_names=["p", "v"], output_names=["p"])
    with pytest.raises(DataError, match=r"expected distinct column names, got 'p' twice"):
        simulate(clash, bounds, truth.t[:3]).to_pandas()
    with pytest.raises(DataError, match=r"output_names: expected columns of frame"):
        Simulation.from_pandas(truth.to_pandas(), output_names=["q"])


def test_missing_pandas_names_the_extra(monkeypatch, setup):
    monkeypatch.setitem(sys.modules, "pandas", None)
    monkeypatch.setitem(sys.modules, "xarray", None)
    estimate = Estimate(np.arange(2.0), np.zeros((2, 1)), np.ones((2, 1)))
    with pytest.raises(ImportError, match=r"Estimate\.to_pandas: expected pandas .*intervalobs\[data\]"):
        estimate.to_pandas()
    with pytest.raises(ImportError, match=r"Simulation\.to_xarray: expected xarray .*intervalobs\[data\]"):
        setup[3].to_xarray()


def test_csv_record_through_pandas_is_enclosed(tmp_path, setup):
    """A measured record written to CSV, read back with pandas and estimated: the truth is enclosed."""
    system, bounds, observer, _ = setup
    t = np.arange(0.0, 6.0, H)
    for seed in (11, 12):
        truth = simulate(system, bounds, t, u=np.sign(np.sin(3 * t))[:, None], noise="extreme", seed=seed)
        truth.to_pandas().to_csv(tmp_path / "record.csv")
        record = pd.read_csv(tmp_path / "record.csv", index_col="t")
        estimate = observer.run(record.index, record, record)
        report = estimate.enclosure(record[list(system.state_names)].to_numpy())
        assert report.fraction == 1.0 and report.max_violation == 0.0
        widths = estimate.to_pandas()["velocity_width"]
        assert widths.iloc[-1] < widths.iloc[100] < widths.iloc[0]


def test_a_python_control_response_is_a_truth(setup):
    """python-control's time-last responses (one trace or several) are compared time-first, by state label."""
    control = pytest.importorskip("control")
    system, bounds, _, _ = setup
    labelled = control.ss(system.A, system.B, system.C, 0, states=["velocity", "position"])  # other order
    assert LTISystem.from_control(labelled).state_names == ("velocity", "position")
    plant = control.ss(system.A, system.B, system.C, 0, states=list(system.state_names))
    sampled = control.c2d(plant, H)  # zero-order hold, as the observers assume
    observer = IntervalObserver.design(LTISystem.from_control(plant), bounds, h=H)
    t = np.arange(0.0, 2.0, H)
    resp = control.forced_response(sampled, T=t, U=np.cos(3 * t), X0=[0.9, -0.7])
    estimate = observer.run(resp.time, resp.outputs.T, resp.inputs.T)
    assert resp.states.shape == (2, t.size) and estimate.enclosure(resp).max_violation == 0.0
    assert estimate.enclosure(resp) == estimate.enclosure(resp.states.T)
    frame = pd.DataFrame(resp.states.T[:, ::-1], index=t, columns=["velocity", "position"])  # reordered by name
    assert estimate.enclosure(frame).max_violation == 0.0
    assert estimate.enclosure(frame.to_numpy()).max_violation > 0.0  # the same columns taken in order miss
    late = control.forced_response(sampled, T=t + H, U=np.cos(3 * t), X0=[0.9, -0.7])
    with pytest.raises(DataError, match=r"x: expected its time index to be t, got 0\.01 at sample 0 where t = 0"):
        estimate.enclosure(late)
    fig = estimate.plot(truth=resp)
    np.testing.assert_array_equal(fig.axes[1].lines[-1].get_ydata(), resp.states[1])


def test_a_model_with_default_names_takes_the_columns_by_position() -> None:
    system = LTISystem([[0.9, 0.1], [0.0, 0.8]], [[1.0, 0.0], [0.0, 1.0]], dt=1.0)  # outputs y1, y2
    bounds = Bounds(x0=(-1, 1), w=(-0.01, 0.01), v=(-0.01, 0.01))
    t = np.arange(10.0)
    truth = simulate(system, bounds, t)
    frame = pd.DataFrame({"position": truth.y[:, 0], "speed": truth.y[:, 1]}, index=t)
    observer = IntervalObserver.design(system, bounds)
    by_position = observer.run(t, frame)
    np.testing.assert_array_equal(by_position.lower, observer.run(t, truth.y).lower)
    with pytest.raises(DataError, match="missing"):
        observer.run(t, frame[["position"]])  # one column for two outputs: not matched by position
