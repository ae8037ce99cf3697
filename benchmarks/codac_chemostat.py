"""Evaluation of codac (2.x) as the flow-enclosure engine of issue 32, on the Monod chemostat.

Model: biomass X and substrate S, dX/dt = (mu S / (Ks + S) - D) X, dS/dt = D (Sin - S) - mu S X / (Y (Ks + S)),
D = 0.1 /h, Sin = 5 g/L, Y = 0.5; mu = 0.4 /h and Ks = 0.5 g/L known to +-5 % (constant, unknown); S measured
every 0.1 h with noise in [-0.02, 0.02]; X0 in [1, 3], S0 in [0.3, 0.8]; a 60 h record. The parameters are
appended to the state with a zero derivative, which is how a constant unknown parameter enters codac's
``CtcLohner`` (its vector field is a function of the state only).

Two uses of codac's tools are measured, each against a truth simulated here by classical Runge-Kutta on a
1e-3 h grid (the parameters at random vertices of their box or inside it, x0 at random vertices, the noise at
+-0.02 with random signs), several runs:

- ``online``: the filter an online estimator would be. At each sample the box of (X, S, mu, Ks) is cut by the
  measurement box of S and the domain X, S >= 0, then ``CtcLohner`` (forward) encloses the flow over the
  sampling interval on a tube of slices of ``SLICE`` h (finer slices where the a-priori enclosure fails),
  giving the box at the next sample;
- ``smoother``: one tube over the whole record (slices of ``SLICE`` h) with every measurement set on its gate,
  contracted forward-backward by ``CtcLohner`` until the widths stop shrinking (by 1 %) or ``SWEEPS`` sweeps:
  the most codac's tube tools give from the whole record.

Reported: enclosure (fraction of the truth's samples inside the boxes; 1.0 is sound), the width of X over time
and its mean over the second half, ms per sample, and whether it runs over a Monte Carlo axis (codac has no
batch axis: one Python loop iteration per run, so the cost scales with the number of runs; its objects do not
pickle, so a Dask task must build them itself), and the cost of one ``CtcLohner`` call. Writes
benchmarks/codac_chemostat.json. Not run by CI or ``make bench``: ``python benchmarks/codac_chemostat.py``
in an environment with ``pip install codac`` (prints a message and exits 0 without it).
"""

from __future__ import annotations

import importlib
import json
import pickle
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

MU, KS, DILUTION, S_IN, YIELD = 0.4, 0.5, 0.1, 5.0, 0.5
PARAM_RADIUS = 0.05
NOISE = 0.02
SAMPLE = 0.1
HOURS = 60.0
SLICE = 0.1
FINE_SLICE = 0.01
SWEEPS = 4
PAVING = 32
X0 = ((1.0, 3.0), (0.3, 0.8))
RUNS = 4
FINE = 1e-3
REPORT_HOURS = (0.0, 1.0, 5.0, 10.0, 30.0, 60.0)
OUT = Path(__file__).with_name("codac_chemostat.json")


def field(x: np.ndarray, mu: np.ndarray, ks: np.ndarray) -> np.ndarray:
    """The chemostat's vector field for states (..., 2) and parameters (...)."""
    rate = mu * x[..., 1] / (ks + x[..., 1]) * x[..., 0]
    return np.stack([rate - DILUTION * x[..., 0], DILUTION * (S_IN - x[..., 1]) - rate / YIELD], axis=-1)


def truth(runs: int, seed: int) -> dict[str, np.ndarray]:
    """RK4 on a 1e-3 h grid: x0 at random vertices, the parameters at vertices (half the runs) or inside."""
    rng = np.random.default_rng(seed)
    lo, hi = np.array([b[0] for b in X0]), np.array([b[1] for b in X0])
    x = np.where(rng.random((runs, 2)) < 0.5, lo, hi)
    scale = np.where(
        np.arange(runs)[:, None] % 2 == 0, rng.choice([-1.0, 1.0], (runs, 2)), rng.uniform(-1, 1, (runs, 2))
    )
    mu, ks = MU * (1 + PARAM_RADIUS * scale[:, 0]), KS * (1 + PARAM_RADIUS * scale[:, 1])
    per_sample = round(SAMPLE / FINE)
    samples = round(HOURS / SAMPLE) + 1
    states = np.empty((runs, samples, 2))
    states[:, 0] = x
    for k in range(1, samples):
        for _ in range(per_sample):
            k1 = field(x, mu, ks)
            k2 = field(x + 0.5 * FINE * k1, mu, ks)
            k3 = field(x + 0.5 * FINE * k2, mu, ks)
            k4 = field(x + FINE * k3, mu, ks)
            x = x + FINE / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        states[:, k] = x
    # at the vertices, shrunk by 1e-12 so that the rounding of the sum keeps the realised noise in its box
    y = states[..., 1] + NOISE * (1 - 1e-12) * rng.choice([-1.0, 1.0], states.shape[:2])
    return {"x": states, "y": y, "mu": mu, "ks": ks, "t": np.arange(samples) * SAMPLE}


def lohner(codac: Any) -> Any:
    """``CtcLohner`` on the field of (X, S, mu, Ks), the parameters constant."""
    v = codac.VectorVar(4)
    rate = v[2] * v[1] / (v[3] + v[1]) * v[0]
    f = codac.AnalyticFunction(
        [v], codac.vec(rate - DILUTION * v[0], DILUTION * (S_IN - v[1]) - rate / YIELD, 0.0 * v[2], 0.0 * v[3])
    )
    return codac.CtcLohner(f)


def initial_box(codac: Any) -> Any:
    return codac.IntervalVector(
        [
            list(X0[0]),
            list(X0[1]),
            [MU * (1 - PARAM_RADIUS), MU * (1 + PARAM_RADIUS)],
            [KS * (1 - PARAM_RADIUS), KS * (1 + PARAM_RADIUS)],
        ]
    )


def measured(codac: Any, box: Any, y: float) -> Any:
    """The box cut by the measurement of S and the domain X, S >= 0."""
    cut = codac.IntervalVector(box)
    cut[0] = cut[0] & codac.Interval(0.0, np.inf)
    cut[1] = cut[1] & (codac.Interval(y) + codac.Interval(-NOISE, NOISE)) & codac.Interval(0.0, np.inf)
    return cut


def as_array(box: Any) -> np.ndarray:
    return np.array([[box[i].lb(), box[i].ub()] for i in range(2)])


def split(codac: Any, pieces: list[Any], cap: int) -> list[Any]:
    """Bisect the piece that is widest (relative to the prior box, over X, mu and Ks) until there are ``cap``."""
    scale = (X0[0][1] - X0[0][0], np.inf, 2 * PARAM_RADIUS * MU, 2 * PARAM_RADIUS * KS)
    pieces = list(pieces)
    while len(pieces) < cap:
        rel = np.array([[p[i].diam() / scale[i] for i in range(4)] for p in pieces])
        j, i = np.unravel_index(int(np.argmax(rel)), rel.shape)
        piece = pieces.pop(int(j))
        left, right, mid = codac.IntervalVector(piece), codac.IntervalVector(piece), piece[int(i)].mid()
        left[int(i)] = codac.Interval(piece[int(i)].lb(), mid)
        right[int(i)] = codac.Interval(mid, piece[int(i)].ub())
        pieces += [left, right]
    return pieces


def online(codac: Any, ctc: Any, y: np.ndarray, cap: int = 1) -> tuple[np.ndarray, float, dict[str, Any]]:
    """Forward filter on a paving of ``cap`` boxes (1: a single box): each piece cut by the measurement (empty
    pieces dropped), the pieces bisected back to ``cap``, each moved over one sampling interval by
    ``CtcLohner``; the rows are the hulls, (T, 2, 2). Rows after a failure (every piece empty, or no enclosure
    even with the fine slices) are infinite."""
    boxes = np.full((y.size, 2, 2), [-np.inf, np.inf])
    pieces, refined, failed = [initial_box(codac)], 0, None
    start = time.perf_counter()
    for k in range(y.size):
        pieces = [c for c in (measured(codac, p, float(y[k])) for p in pieces) if not c.is_empty()]
        if not pieces:
            failed = f"empty at {k * SAMPLE:g} h"
            break
        hull = np.array([as_array(p) for p in pieces])
        boxes[k] = np.stack([hull[:, :, 0].min(axis=0), hull[:, :, 1].max(axis=0)], axis=-1)
        if k + 1 == y.size:
            break
        moved = []
        for piece in split(codac, pieces, cap):
            nxt = None
            for width in (SLICE, FINE_SLICE):
                nxt = lohner_step(codac, ctc, piece, k * SAMPLE, width)
                if nxt is not None:
                    break
                refined += 1
            if nxt is None:
                break
            moved.append(nxt)
        if nxt is None:
            failed = f"no enclosure at {k * SAMPLE:g} h"
            break
        pieces = moved
    ms = (time.perf_counter() - start) / (k + 1) * 1e3
    return boxes, ms, {"fine_slice_steps": refined, "failed": failed, "hours_covered": k * SAMPLE}


def lohner_step(codac: Any, ctc: Any, box: Any, t0: float, width: float) -> Any:
    """The box at ``t0 + SAMPLE`` from ``box`` at ``t0`` (None: codac found no enclosure or an unbounded one)."""
    tube = codac.SlicedTube(codac.create_tdomain(codac.Interval(t0, t0 + SAMPLE), width), codac.IntervalVector(4))
    tube.set(box, t0)
    try:
        out = ctc.contract(tube, codac.TimePropag.FWD)(t0 + SAMPLE)
    except RuntimeError:
        return None
    return out if np.all(np.isfinite(as_array(out))) and not out.is_empty() else None


def smoother(codac: Any, ctc: Any, y: np.ndarray) -> tuple[np.ndarray, float, dict[str, Any]]:
    """One tube over the record, every measurement on its gate, forward-backward sweeps of ``CtcLohner``."""
    start = time.perf_counter()
    tube = codac.SlicedTube(
        codac.create_tdomain(codac.Interval(0.0, (y.size - 1) * SAMPLE), FINE_SLICE), codac.IntervalVector(4)
    )
    tube.set(measured(codac, initial_box(codac), float(y[0])), 0.0)
    for k in range(1, y.size):
        tube.set(measured(codac, codac.IntervalVector(4), float(y[k])), k * SAMPLE)
    previous, sweeps, failed = np.inf, 0, None
    for sweeps in range(1, SWEEPS + 1):
        try:
            tube = ctc.contract(tube, codac.TimePropag.FWD_BWD)
        except RuntimeError as exc:
            failed = f"sweep {sweeps}: {exc}"
            break
        width = float(np.sum([tube(k * SAMPLE)[0].diam() for k in range(y.size)]))
        if not width < 0.99 * previous:
            break
        previous = width
    boxes = np.array([as_array(tube(k * SAMPLE)) for k in range(y.size)])
    return boxes, (time.perf_counter() - start) / y.size * 1e3, {"sweeps": sweeps, "failed": failed}


def summary(boxes: np.ndarray, x: np.ndarray, t: np.ndarray) -> dict[str, Any]:
    inside = (boxes[..., 0] <= x) & (x <= boxes[..., 1])
    width = boxes[:, 0, 1] - boxes[:, 0, 0]
    half = t >= HOURS / 2
    return {
        "enclosure": float(np.mean(inside)),
        "x_width_at_hours": {f"{h:g}": float(width[round(h / SAMPLE)]) for h in REPORT_HOURS},
        "x_mean_width_second_half": float(np.mean(width[half])),
        "s_mean_width_second_half": float(np.mean((boxes[:, 1, 1] - boxes[:, 1, 0])[half])),
    }


def overview(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Per method: the worst enclosure, how many runs reached the end of the record, the cost per sample."""
    ms = [r["ms_per_sample"] for r in rows]
    return {
        "enclosure_min": min(r["enclosure"] for r in rows),
        "runs_to_end": sum(r["extra"].get("failed") is None for r in rows),
        "runs": len(rows),
        "ms_per_sample_min": min(ms),
        "ms_per_sample_max": max(ms),
        "x_mean_width_second_half": [r["x_mean_width_second_half"] for r in rows],
        "x_width_at_1h": [r["x_width_at_hours"]["1"] for r in rows],
    }


def call_cost(codac: Any, ctc: Any, calls: int = 200) -> float:
    """ms of one ``CtcLohner`` call over a sampling interval (slices of ``SLICE`` h) from a small box (0.01 wide
    around a point of the record, where the a-priori enclosure succeeds at once): the floor of any use."""
    box = codac.IntervalVector([[1.99, 2.0], [0.545, 0.555], [MU, MU], [KS, KS]])
    start = time.perf_counter()
    for _ in range(calls):
        lohner_step(codac, ctc, box, 0.0, SLICE)
    return (time.perf_counter() - start) / calls * 1e3


def picklable(codac: Any, ctc: Any) -> bool:
    """Whether codac's objects can be sent to another process (a Dask worker) as they are."""
    try:
        pickle.dumps((initial_box(codac), ctc))
    except TypeError:
        return False
    return True


def main() -> int:
    try:
        codac = importlib.import_module("codac")
    except ImportError:
        print("codac is not installed (pip install codac): the codac evaluation is skipped")
        return 0
    data = truth(RUNS, seed=2026)
    ctc = lohner(codac)
    result: dict[str, Any] = {
        "codac_version": getattr(codac, "__version__", "?"),
        "runs": RUNS,
        "hours": HOURS,
        "batch_axis": False,
        "picklable": picklable(codac, ctc),
        "lohner_call_ms": call_cost(codac, ctc),
        "timing": "wall seconds of one process on a shared 2-core machine (one Python loop iteration per run)",
    }
    methods: dict[str, Callable[[Any, Any, np.ndarray], tuple[np.ndarray, float, dict[str, Any]]]] = {
        "online": online,
        f"paving{PAVING}": lambda c, f, y: online(c, f, y, PAVING),
        "smoother": smoother,
    }
    for name, method in methods.items():
        rows = []
        for r in range(RUNS):
            boxes, ms, extra = method(codac, ctc, data["y"][r])
            rows.append({**summary(boxes, data["x"][r], data["t"]), "ms_per_sample": ms, "extra": extra})
            print(name, r, rows[-1], flush=True)
        result[name] = rows
    result["summary"] = {name: overview(result[name]) for name in methods}
    OUT.write_text(json.dumps(result, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
