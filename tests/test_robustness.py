"""Never crash, never hang: every linear estimator on degenerate but valid cases (tests/robustness.py).

Hypothesis draws the cases: one to three states, no outputs or zero rows and columns of ``C``, ``E`` and
``F``, zero-width boxes, magnitudes from 1e-9 to 1e9, coordinates scaled over 10^±6, marginally stable
``A``, discrete and continuous time, a 1 % ``ΔA`` for the robust estimators. Each case runs in a worker
process with a time limit, so that a native crash (a signal) or a hang is a finding of the case that caused
it, not the end of the test run. Asserted: no signal, no time-out, no exception other than the library's
named errors, no NaN, and every returned box contains the independently simulated truth.
"""

from __future__ import annotations

import multiprocessing
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from robustness import BUILDERS, CLI, Case

CASE_TIME_LIMIT = 60.0
"""Seconds a case may take (design and a 12-sample run) before it counts as a hang."""


class _Worker:
    """One worker process running :func:`~robustness.outcome`, restarted after a crash or a time-out."""

    def __init__(self) -> None:
        self._process: Any = None

    def _start(self) -> None:
        context = multiprocessing.get_context("spawn")
        self._conn, child = context.Pipe()
        self._process = context.Process(target=_serve, args=(child,), daemon=True)
        self._process.start()

    def run(self, name: str, case: Case) -> str:
        if self._process is None or not self._process.is_alive():
            self._start()
        self._conn.send((name, case))
        if not self._conn.poll(CASE_TIME_LIMIT):
            self._process.kill()
            self._process = None
            return "time-out"
        try:
            return str(self._conn.recv())
        except EOFError:
            code = self._process.exitcode
            self._process = None
            return f"crash (exit code {code})"


def _serve(conn: Any) -> None:
    import sys

    sys.path.insert(0, __file__.rsplit("/", 1)[0])
    from robustness import outcome as run_case

    while True:
        name, case = conn.recv()
        conn.send(run_case(name, case))


_WORKER = _Worker()


@st.composite
def cases(draw: st.DrawFn) -> Case:
    """A degenerate or extreme but valid linear case (module docstring)."""
    n = draw(st.integers(1, 3))
    p = draw(st.integers(0, 2))
    seed = draw(st.integers(0, 2**16))
    rng = np.random.default_rng(seed)
    continuous = draw(st.booleans())
    radius = draw(st.sampled_from([0.3, 0.9, 1.0]))  # 1.0: marginally stable (an eigenvalue on the boundary)
    A = rng.normal(size=(n, n))
    if continuous:
        A = A - (np.max(np.linalg.eigvals(A).real) + (1.0 - radius) * 3.0) * np.eye(n)
    else:
        A = A * radius / max(np.max(np.abs(np.linalg.eigvals(A))), 1e-12)
    C = rng.normal(size=(p, n)) * (rng.random((p, n)) < draw(st.sampled_from([0.0, 0.5, 1.0])))
    E = np.eye(n) * (rng.random(n) < draw(st.sampled_from([0.5, 1.0])))
    F = np.eye(p)
    magnitude = 10.0 ** draw(st.sampled_from([-9, 0, 0, 6, 9]))
    centre = rng.normal(size=n) * magnitude
    x0_radius = draw(st.sampled_from([0.0, 1e-3, 1.0])) * max(magnitude, 1.0) * np.ones(n)
    w_radius = draw(st.sampled_from([0.0, 1e-3, 0.1])) * max(magnitude, 1.0)
    v_radius = draw(st.sampled_from([0.0, 1e-3, 0.1])) * max(magnitude, 1.0)
    if draw(st.booleans()):  # coordinates z = D x scaled over up to 10^±6
        D = 10.0 ** rng.uniform(-6, 6, n)
        A, C, E, centre, x0_radius = D[:, None] * A / D, C / D, D[:, None] * E, D * centre, D * x0_radius
    h = draw(st.sampled_from([0.1, 1.0])) if continuous else 1.0
    dA = (-0.01 * np.abs(A), 0.01 * np.abs(A))
    return {
        "A": A.tolist(),
        "C": C.reshape(p, n).tolist(),
        "E": E.tolist(),
        "F": F.tolist(),
        "x0": ((centre - x0_radius).tolist(), (centre + x0_radius).tolist()),
        "w": (-w_radius, w_radius),
        "v": (-v_radius, v_radius),
        "continuous": continuous,
        "h": h,
        "dA": (dA[0].tolist(), dA[1].tolist()),
        "seed": seed,
    }


def _acceptable(result: str) -> bool:
    return result == "ok" or result.startswith("named ")


def test_the_reported_crash_case_gives_sound_bounds() -> None:
    """An all-zero output row with a finite horizon ended the process with SIGSEGV inside HiGHS."""
    case = {
        "A": [[0.5, 0.1], [0.0, 0.5]],
        "C": [[0.0, 0.0]],
        "E": [[1.0, 0.0], [0.0, 1.0]],
        "F": [[1.0]],
        "x0": ([0.9, -0.1], [1.1, 0.1]),
        "w": (-0.01, 0.01),
        "v": (-0.01, 0.01),
        "continuous": False,
        "h": 1.0,
        "dA": None,
        "seed": 0,
    }
    assert _WORKER.run("hull-window", case) == "ok"
    assert _WORKER.run("hull-window", {**case, "continuous": True, "A": [[-0.5, 0.1], [0.0, -0.5]]}) == "ok"


@pytest.mark.slow
@pytest.mark.parametrize("name", [*sorted(BUILDERS), CLI])
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True)
@given(case=cases())
def test_degenerate_cases_end_in_sound_bounds_or_a_named_error(name: str, case: Case) -> None:
    result = _WORKER.run(name, case)
    assert _acceptable(result), result
