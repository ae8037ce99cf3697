"""Degenerate but valid linear cases for every linear estimator, and the classification of what each gives.

Used by tests/test_robustness.py. A case is a plain dict (so that it crosses to a worker process): the model
in the coordinates the estimator sees, its boxes, and a record simulated here with NumPy alone (float64 with
the noise at the vertices of its boxes, switching four times inside each sampling interval in continuous
time), independently of the library's simulators. :func:`outcome` runs one estimator on one case and says
what happened: ``"ok"``, ``"named <Error>"`` (one of the library's errors), ``"raw <Type>: message"``,
``"nonfinite"`` (an infinite or NaN bound where the method claims boundedness) or ``"violation ..."``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from scipy.linalg import expm

import intervalobs as io

Case = dict[str, Any]

STEPS = 12
"""Samples in a record: long enough for every window (horizon 5), short enough for 500 cases in minutes."""

TRUTH_ERROR = 1e-10
"""Relative error allowed to the *truth* (a float64 simulation, with expm in continuous time) against its
exact value; a bound missing the simulated truth by more is a violation."""


def matrices(case: Case) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``A, C, E, F`` of ``case`` with their shapes (a model without outputs has ``C`` of shape (0, n))."""
    A = np.asarray(case["A"], dtype=float)
    n = A.shape[0]
    C = np.asarray(case["C"], dtype=float).reshape(-1, n)
    E = np.asarray(case["E"], dtype=float).reshape(n, -1)
    F = np.asarray(case["F"], dtype=float)
    F = F.reshape(C.shape[0], F.size // C.shape[0] if C.shape[0] else 0)
    return A, C, E, F


def simulate_case(case: Case, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Times, states and outputs of one record of ``case`` (vertex noise, exact sampled matrices)."""
    A, C, E, F = matrices(case)
    n, h, dA = A.shape[0], case["h"], case.get("dA")
    if dA is not None:  # the truth at a vertex of the ΔA box
        A = A + np.where(rng.random((n, n)) < 0.5, np.asarray(dA[0]), np.asarray(dA[1]))

    def vertex(box: tuple[Any, Any], size: int) -> np.ndarray:
        lo, hi = np.broadcast_to(box[0], (size,)), np.broadcast_to(box[1], (size,))
        return np.where(rng.random(size) < 0.5, lo, hi).astype(float)

    nw, nv = E.shape[1], F.shape[1]
    x = np.zeros((STEPS, n))
    x[0] = vertex(case["x0"], n)
    if case["continuous"]:
        aug = np.zeros((n + nw, n + nw))
        aug[:n, :n], aug[:n, n:] = A, E
        part = expm(aug * (h / 4))
        step, noise = part[:n, :n], part[:n, n:]
        for k in range(STEPS - 1):
            state = x[k]
            for _ in range(4):
                state = step @ state + noise @ vertex(case["w"], nw)
            x[k + 1] = state
    else:
        for k in range(STEPS - 1):
            x[k + 1] = A @ x[k] + E @ vertex(case["w"], nw)
    y = x @ C.T + np.array([F @ vertex(case["v"], nv) for _ in range(STEPS)]).reshape(STEPS, -1)
    return np.arange(STEPS) * h, x, y


def model(case: Case) -> tuple[io.LTISystem, io.Bounds, float | None]:
    """The case's system, bounds and sampling period (None in discrete time)."""
    dt = None if case["continuous"] else case["h"]
    dA = None if case.get("dA") is None else tuple(np.asarray(b) for b in case["dA"])
    A, C, E, F = matrices(case)
    system = io.LTISystem(A, C, E=E, F=F, dt=dt, dA=dA)
    bounds = io.Bounds(x0=case["x0"], w=case["w"], v=case["v"])
    return system, bounds, case["h"] if case["continuous"] else None


BUILDERS: dict[str, Callable[[io.LTISystem, io.Bounds, float | None], Any]] = {
    "observer-tube": lambda s, b, h: io.IntervalObserver.design(s, b, h=h),
    "observer-framer": lambda s, b, h: io.IntervalObserver.design(s, b, h=h, method="framer"),
    "hull-window": lambda s, b, h: io.HullEstimator.design(s, b, h=h, horizon=5),
    "hull-full": lambda s, b, h: io.HullEstimator.design(s, b, h=h, horizon=None),
    "hull-filtered": lambda s, b, h: io.HullEstimator.design(s, b, h=h, horizon=5, filtered=True),
    "fir": lambda s, b, h: io.FiniteMemoryObserver.design(s, b, window=5, h=h),
    "intersection": lambda s, b, h: io.IntersectionObserver.design(s, b, h=h),
    "robust-hull": lambda s, b, h: io.RobustHullEstimator.design(s, b, h=h, horizon=5),
    "robust-fir": lambda s, b, h: io.RobustFiniteMemoryObserver.design(s, b, window=5, h=h),
}
"""Every linear estimator's default design, with short windows (the cases are short records)."""

CLI = "cli-estimate"
"""``intervalobs estimate`` (automatic choice) on the case written as a model file and a CSV record."""

UNCERTAIN = {"robust-hull", "robust-fir"}
"""Estimators that take an interval ΔA (the others get the case without it)."""


def outcome(name: str, case: Case) -> str:
    """What estimator ``name`` does with ``case`` (module docstring)."""
    case = dict(case)
    if name not in UNCERTAIN:
        case["dA"] = None
    rng = np.random.default_rng(case["seed"])
    t, x, y = simulate_case(case, rng)
    try:
        system, bounds, h = model(case)
        if name == CLI:
            return _command_line(system, bounds, h, t, x, y)
        estimate = BUILDERS[name](system, bounds, h).run(t, y)
    except io.IntervalObserverError as error:
        return f"named {type(error).__name__}"
    except Exception as error:  # the point: any other exception is a finding
        return f"raw {type(error).__name__}: {error}"
    return _judged(np.asarray(estimate.lower), np.asarray(estimate.upper), x)


def _command_line(system: io.LTISystem, bounds: io.Bounds, h: float | None, t: Any, x: Any, y: Any) -> str:
    """``intervalobs estimate`` on the case's files: one line and exit code 2, or bounds judged as above."""
    import contextlib
    import csv
    import io as text
    import tempfile
    from pathlib import Path

    from intervalobs.cli import main
    from intervalobs.records import write_model

    with tempfile.TemporaryDirectory() as folder:
        root = Path(folder)
        model = write_model(root / "model.toml", system, bounds, h)
        with open(root / "record.csv", "w", newline="") as handle:
            writer = csv.writer(handle)
            writer.writerow(["t", *system.output_names])
            writer.writerows(np.column_stack([t, y]).tolist())
        errors = text.StringIO()
        with contextlib.redirect_stderr(errors), contextlib.redirect_stdout(text.StringIO()):
            code = main(["estimate", str(model), str(root / "record.csv"), "--out", str(root / "out")])
        message = errors.getvalue().strip()
        if code == 2 and len(message.splitlines()) == 1 and "Traceback" not in message:
            return "named command-line error"
        if code != 0:
            return f"raw exit code {code}: {message}"
        with open(root / "out" / "bounds.csv", newline="") as handle:
            rows = list(csv.DictReader(handle))
    names = system.state_names
    lower = np.array([[float(row[f"{name}_lower"]) for name in names] for row in rows])
    upper = np.array([[float(row[f"{name}_upper"]) for name in names] for row in rows])
    return _judged(lower, upper, x)


def _judged(lower: Any, upper: Any, x: Any) -> str:
    """``"ok"``, ``"nonfinite"`` or ``"violation ..."`` of the boxes ``lower``, ``upper`` against the truth ``x``."""
    if np.any(np.isnan(lower)) or np.any(np.isnan(upper)):
        return "nonfinite"
    slack = TRUTH_ERROR * (1.0 + np.abs(x))
    missed = (lower > x + slack) | (upper < x - slack)
    if np.any(missed):
        k, i = np.argwhere(missed)[0]
        return f"violation at k = {k}, state {i}: {x[k, i]!r} not in [{lower[k, i]!r}, {upper[k, i]!r}]"
    return "ok"
