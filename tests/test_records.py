"""`intervalobs estimate MODEL DATA` on measured records: files in, bounds out, one-line errors for bad files."""

import csv
import json

import numpy as np
import pytest

from intervalobs import Bounds, LTISystem, simulate
from intervalobs.cli import main
from intervalobs.records import example_model, read_model, read_record, write_example, write_model

H = 0.02
SYSTEM = LTISystem(
    [[0.0, 1.0], [-4.0, -1.2]],
    C=[[1.0, 0.0]],
    B=[[0.0], [2.0]],
    state_names=["position", "velocity"],
    output_names=["sensor"],
    input_names=["drive"],
)
BOUNDS = Bounds(x0=([-0.5, -0.5], [0.5, 0.5]), w=([-0.05, -0.2], [0.05, 0.2]), v=([-0.01], [0.01]))


def _write_csv(path, header, columns):
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        writer.writerows([repr(v) for v in row] for row in np.column_stack(columns).tolist())
    return path


def _read_csv(path):
    with path.open() as handle:
        header = handle.readline().strip().split(",")
    return header, np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


def _record(tmp_path, seed, steps=150):
    """A record simulated with bang-bang noise (the truth), written as a measurement file would be."""
    t = H * np.arange(steps)
    drive = np.where(np.sin(1.3 * t + seed) > 0, 1.0, -0.5)[:, None]
    truth = simulate(SYSTEM, BOUNDS, t, u=drive, noise="extreme", seed=seed)
    noise_column = np.random.default_rng(seed).normal(size=steps)  # a column the model does not use
    data = _write_csv(tmp_path / f"run{seed}.csv", ["drive", "t", "other", "sensor"], [drive, t, noise_column, truth.y])
    return truth, data


def _fails(capsys, *argv):
    """Run the CLI expecting bad input: exit code 2 and one line on stderr; return that line."""
    assert main(["estimate", *map(str, argv)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("intervalobs: error: "), err
    return err.strip()


def test_csv_to_estimate_to_csv_encloses_the_truth(tmp_path, capsys):
    model = write_model(tmp_path / "model.toml", SYSTEM, BOUNDS)
    for seed in (1, 2, 3):
        truth, data = _record(tmp_path, seed)
        out = tmp_path / f"out{seed}"
        chosen = "auto" if seed == 1 else "tube"  # auto (the default) runs the robust hull: one seed is enough
        extra = [] if seed == 1 else ["--observer", "tube"]
        assert main(["estimate", str(model), str(data), "--out", str(out), *extra]) == 0
        assert f"150 samples every 0.02 s, {chosen} observer" in capsys.readouterr().out
        header, table = _read_csv(out / "bounds.csv")
        assert header == ["t"] + [f"{n}_{e}" for n in SYSTEM.state_names for e in ("lower", "upper", "width")]
        np.testing.assert_array_equal(table[:, 0], truth.t)
        lower, upper = table[:, [1, 4]], table[:, [2, 5]]
        assert np.all(lower <= truth.x) and np.all(truth.x <= upper)
        summary = json.loads((out / "summary.json").read_text())
        assert summary["observer"] == chosen and summary["samples"] == 150 and "enclosure" not in summary
        assert summary["final_width"]["velocity"] == pytest.approx(upper[-1, 1] - lower[-1, 1])


def test_the_example_through_the_cli_and_through_pandas(tmp_path, capsys):
    pd = pytest.importorskip("pandas")
    assert main(["estimate", "--example", str(tmp_path)]) == 0
    assert "try: intervalobs estimate" in capsys.readouterr().out
    model_file, data, truth_file = tmp_path / "motor.toml", tmp_path / "motor.csv", tmp_path / "motor_truth.csv"
    system, bounds, h = example_model()
    model = read_model(model_file)
    assert model.h == h and model.system.state_names == system.state_names
    np.testing.assert_array_equal(model.system.dA[1], system.dA[1])
    np.testing.assert_array_equal(model.bounds.resolve(model.system).w[1], bounds.resolve(system).w[1])
    out = tmp_path / "out"
    assert main(["estimate", str(model_file), str(data), "--out", str(out), "--plot", "--observer", "tube"]) == 0
    assert (out / "bounds.png").stat().st_size > 10_000
    cli_bounds = pd.read_csv(out / "bounds.csv", index_col="t")
    truth = pd.read_csv(truth_file, index_col="t")
    for name in system.state_names:
        assert (cli_bounds[f"{name}_lower"] <= truth[name]).all() and (truth[name] <= cli_bounds[f"{name}_upper"]).all()
    # the same in Python, with pandas: read the files, design, run on the frame
    from intervalobs import Estimate, IntervalObserver

    measured = pd.read_csv(data, index_col="t")
    estimate = IntervalObserver.design(model.system, model.bounds, h=model.h).run(measured.index, measured, measured)
    report = estimate.enclosure(truth[list(system.state_names)].to_numpy())
    assert report.fraction == 1.0 and report.max_violation == 0.0
    np.testing.assert_allclose(estimate.upper, Estimate.load(out / "bounds.npz").upper, rtol=0, atol=0)


def test_python_model_datetimes_parquet_and_other_observers(tmp_path, capsys):
    truth, _ = _record(tmp_path, seed=5, steps=60)
    script = tmp_path / "model.py"
    script.write_text(
        "from intervalobs import Bounds, LTISystem\n"
        f"system = LTISystem({SYSTEM.A.tolist()}, C=[[1.0, 0.0]], B=[[0.0], [2.0]], state_names=['position', "
        "'velocity'], output_names=['sensor'], input_names=['drive'])\n"
        "bounds = Bounds(x0=([-0.5, -0.5], [0.5, 0.5]), w=([-0.05, -0.2], [0.05, 0.2]), v=([-0.01], [0.01]))\n"
        f"h = {H}\n"
    )
    stamps = np.datetime64("2026-05-01T08:00:00") + (truth.t * 1000).round().astype("timedelta64[ms]")
    dated = tmp_path / "dated.csv"
    with dated.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["time", "sensor", "drive"])
        writer.writerows(
            [str(s), repr(y), repr(u)] for s, y, u in zip(stamps, truth.y[:, 0].tolist(), truth.u[:, 0].tolist())
        )
    for observer in ("framer", "intersection"):
        out = tmp_path / observer
        assert main(["estimate", str(script), str(dated), "--observer", observer, "--out", str(out)]) == 0
        _, table = _read_csv(out / "bounds.csv")
        assert np.all(table[:, [1, 4]] <= truth.x) and np.all(truth.x <= table[:, [2, 5]])
    pa = pytest.importorskip("pyarrow")
    parquet = pytest.importorskip("pyarrow.parquet")
    columns = {"t": truth.t, "sensor": truth.y[:, 0], "drive": truth.u[:, 0]}
    parquet.write_table(pa.table(columns), tmp_path / "record.parquet")
    assert main(["estimate", str(script), str(tmp_path / "record.parquet"), "--out", str(tmp_path / "pq")]) == 0
    back = parquet.read_table(tmp_path / "pq" / "bounds.parquet")
    assert np.all(back.column("velocity_lower").to_numpy() <= truth.x[:, 1])
    capsys.readouterr()


def test_bad_records_fail_on_one_line_with_their_lines(tmp_path, capsys):
    model = write_model(tmp_path / "model.toml", SYSTEM, BOUNDS)
    t = H * np.arange(12)
    y, u = np.sin(t), np.ones(12)
    missing = _write_csv(tmp_path / "missing.csv", ["t", "sensor"], [t, y])
    assert "missing ['drive']" in _fails(capsys, model, missing)
    notime = _write_csv(tmp_path / "notime.csv", ["clock", "sensor", "drive"], [t, y, u])
    assert "a time column (t or time)" in _fails(capsys, model, notime)
    assert main(["estimate", str(model), str(notime), "--time", "clock", "--out", str(tmp_path / "clock")]) == 0
    gap = t.copy()
    gap[7:] += H
    uneven = _write_csv(tmp_path / "uneven.csv", ["t", "sensor", "drive"], [gap, y, u])
    message = _fails(capsys, model, uneven)
    assert "expected uniformly spaced times (step 0.02" in message and "got a step of 0.04 from line 8 to 9" in message
    holes = tmp_path / "holes.csv"
    lines = ["t,sensor,drive"] + [f"{tk!r},{yk!r},{uk!r}" for tk, yk, uk in zip(t.tolist(), y.tolist(), u.tolist())]
    lines[3] = f"{t[2]:.17g},,1.0"
    lines[10] = f"{t[9]:.17g},nan,1.0"
    holes.write_text("\n".join(lines) + "\n")
    assert "got empty or NaN in ['sensor'] on lines 4, 11" in _fails(capsys, model, holes)
    lines[3] = f"{t[2]:.17g},abc,1.0"
    holes.write_text("\n".join(lines) + "\n")
    assert "expected a number in column 'sensor' on line 4, got 'abc'" in _fails(capsys, model, holes)
    lines[3] = f"{t[2]:.17g},0.1"
    holes.write_text("\n".join(lines) + "\n")
    assert "expected 3 comma-separated fields on line 4, got 2" in _fails(capsys, model, holes)
    assert "DATA: expected an existing .csv or .parquet file" in _fails(capsys, model, tmp_path / "none.csv")
    discrete = write_model(tmp_path / "discrete.toml", LTISystem(0.5 * np.eye(2), [[1.0, 0.0]]), Bounds(x0=(-1, 1)))
    ok = _write_csv(tmp_path / "ok.csv", ["t", "y1"], [0.1 * np.arange(12), y])
    dt_model = tmp_path / "dt.toml"
    dt_model.write_text(discrete.read_text().replace("[model]", "[model]\ndt = 0.2"))
    assert "step 0.2, the model's), got a step of 0.1 from line 2 to 3" in _fails(capsys, dt_model, ok)


def test_bad_model_files_fail_on_one_line(tmp_path, capsys):
    data = _write_csv(tmp_path / "d.csv", ["t", "sensor", "drive"], [H * np.arange(5), np.zeros(5), np.zeros(5)])
    good = write_model(tmp_path / "good.toml", SYSTEM, BOUNDS).read_text()
    cases = {
        "broken": ("A = [[1, 2]", "expected valid TOML"),
        "no_a": (good.replace("A = ", "Z = "), "expected keys of"),
        "no_c": (good.replace("C = [[1.0, 0.0]]\n", ""), "expected the key 'C' in [model]"),
        "shape": (good.replace("C = [[1.0, 0.0]]", "C = [[1.0, 0.0, 0.0]]"), "C: expected shape any×2"),
        "box": (good.replace("x0 = [[-0.5, -0.5], [0.5, 0.5]]", "x0 = [1, 2, 3]"), "expected x0 = [lower, upper]"),
        "names": (good.replace('["sensor"]', '["a", "b"]'), "output_names: expected 1 names, got 2"),
    }
    for name, (text, expected) in cases.items():
        (tmp_path / f"{name}.toml").write_text(text)
        assert expected in _fails(capsys, tmp_path / f"{name}.toml", data), name
    (tmp_path / "bad.py").write_text("system = 1\nbounds = None\n")
    assert "expected variables 'system' (an LTISystem) and 'bounds'" in _fails(capsys, tmp_path / "bad.py", data)
    (tmp_path / "raises.py").write_text("raise RuntimeError('no model here')\n")
    assert "RuntimeError: no model here" in _fails(capsys, tmp_path / "raises.py", data)
    assert "expected MODEL and DATA (or --example DIR)" in _fails(capsys, tmp_path / "good.toml")
    assert main(["estimate", "m.toml", str(data), "--observer", "bogus"]) == 2
    capsys.readouterr()


def test_write_model_round_trips_every_field(tmp_path):
    system = LTISystem(
        np.diag([0.9, 0.5]),
        [[1.0, 1.0]],
        B=[[1.0], [0.0]],
        E=[[1.0], [0.5]],
        F=[[2.0]],
        dt=0.5,
        dA=(-0.01 * np.ones((2, 2)), 0.02 * np.ones((2, 2))),
        state_names=["a", "b"],
    )
    bounds = Bounds(x0=([-1, -2], [1, 2]), w=([-0.1], [0.3]), v=([-0.5], [0.5]))
    back = read_model(write_model(tmp_path / "m.toml", system, bounds))
    for attr in ("A", "B", "C", "E", "F"):
        np.testing.assert_array_equal(getattr(back.system, attr), getattr(system, attr))
    assert back.system.dt == 0.5 and back.h is None and back.system.state_names == ("a", "b")
    np.testing.assert_array_equal(back.system.dA[0], system.dA[0])
    resolved = back.bounds.resolve(back.system)
    np.testing.assert_array_equal(resolved.w[1], [0.3])
    t = 0.5 * np.arange(4)
    record = read_record(_write_csv(tmp_path / "r.csv", ["t", "y1", "u1"], [t, t, t]), back)
    assert record.h == 0.5 and record.y.shape == (4, 1) and record.u.shape == (4, 1)


def test_write_example_is_reproducible(tmp_path):
    first = write_example(tmp_path / "a", seconds=0.5, seed=3)
    second = write_example(tmp_path / "b", seconds=0.5, seed=3)
    assert [p.read_text() for p in first] == [p.read_text() for p in second]


@pytest.mark.parametrize(
    "case",
    ["disconnected-sensor", "point-prior-no-noise", "two-samples", "huge-values"],
)
def test_degenerate_but_valid_files_give_bounds_or_one_line(tmp_path, capsys, case):
    """Degenerate but valid models and records: exit 0 with sound bounds, or 2 with one line; never a traceback."""
    system, bounds, steps, scale = SYSTEM, BOUNDS, 40, 1.0
    if case == "disconnected-sensor":
        system = LTISystem(SYSTEM.A, C=[[0.0, 0.0]], B=SYSTEM.B, output_names=["sensor"], input_names=["drive"])
    if case == "point-prior-no-noise":
        bounds = Bounds(x0=([0.1, -0.2], [0.1, -0.2]), w=(0.0, 0.0), v=(0.0, 0.0))
    if case == "two-samples":
        steps = 2
    if case == "huge-values":
        scale = 1e9
        bounds = Bounds(x0=([-5e8, -5e8], [5e8, 5e8]), w=([-5e7, -2e8], [5e7, 2e8]), v=([-1e7], [1e7]))
    model = write_model(tmp_path / "model.toml", system, bounds)
    t = H * np.arange(steps)
    drive = scale * np.where(np.sin(1.3 * t) > 0, 1.0, -0.5)[:, None]
    truth = simulate(system, bounds, t, u=drive, noise="extreme", seed=1)
    data = _write_csv(tmp_path / "record.csv", ["t", "sensor", "drive"], [t, truth.y, drive])
    code = main(["estimate", str(model), str(data), "--observer", "tube", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code in (0, 2), err
    assert "Traceback" not in err
    if code == 2:
        assert len(err.strip().splitlines()) == 1, err
        return
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary  # written
