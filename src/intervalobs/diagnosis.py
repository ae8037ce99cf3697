r"""Fault isolation from interval-observer signals and Monte Carlo performance campaigns (Rotondo et al.).

* :func:`isolate`, :func:`fault_signals`, :class:`IsolationRecord`: an LPV interval UIO run on a record,
  with its isolation signals :math:`\underline\varepsilon, \overline\varepsilon` (29)–(30) projected on
  the columns of :math:`H` (27)–(28).
* :func:`first_negative_time`, :func:`isolation_outcome`: a fault :math:`j` is flagged when its
  isolation signal :math:`\underline\varepsilon^{(j)}` or :math:`\overline\varepsilon^{(j)}` becomes
  negative (Rotondo et al., (27)–(28)); before the onset of any fault that is a false alarm.
* :func:`psi_hat`, :func:`runs_for_sigma`: the Monte Carlo estimate :math:`\hat\Psi` (119) of the
  performance metric (118) and the number of runs for a standard deviation (120).
* :func:`run_campaign`: Ψ̂ over a grid (uncertainty level × fault magnitude) for several scenarios on
  Dask (a local cluster, or an existing one by address). The grid is cut into tasks for the workers
  present (:func:`campaign_tasks`); every finished task is appended to a SQLite file in the output
  folder, so an interrupted campaign resumes where it stopped, and a task that raises is recorded as a
  failed cell while the others go on; a tqdm bar shows runs done and left and runs per second; the
  result is ``psi.json`` and one heat map per scenario.
"""

from __future__ import annotations

import contextlib
import heapq
import itertools
import json
import math
import signal
import sqlite3
import sys
import threading
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import ArgumentError, BoundsError, DataError, DimensionError, SchedulerError
from .estimate import Estimate
from .observers.lpv import LPVIntervalUIO
from .validation import as_count, as_fraction, as_output_folder, as_vector

__all__ = [
    "Campaign",
    "CampaignInterrupted",
    "CampaignResult",
    "IsolationRecord",
    "campaign_tasks",
    "fault_signals",
    "first_negative_time",
    "isolate",
    "isolation_outcome",
    "psi_hat",
    "run_campaign",
    "runs_for_sigma",
    "scenario_success",
]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class IsolationRecord:
    r"""Isolation signals of a run of the interval UIO.

    Attributes
    ----------
    t : numpy.ndarray, shape (T,)
    eps_lower, eps_upper : numpy.ndarray, shape (..., T, n)
        :math:`\underline\varepsilon, \overline\varepsilon`: how far the measured outputs lie inside
        the bounds, from below and from above (negative: outside).
    signal_lower, signal_upper : numpy.ndarray, shape (..., T, q)
        Their coordinates along the columns of H, :math:`H_j^T\varepsilon/\|H_j\|^2` (the scalar of
        the projection :math:`\Pi(H^{(j)})\varepsilon` on the fault's direction).

    References
    ----------
    Rotondo et al. (:mod:`intervalobs.references`): the signals (29)–(30) and their projections (27)–(28).
    """

    t: FloatArray
    eps_lower: FloatArray
    eps_upper: FloatArray
    signal_lower: FloatArray
    signal_upper: FloatArray


def fault_signals(h_matrix: ArrayLike, eps: ArrayLike) -> FloatArray:
    r"""Coordinates :math:`H_j^T\varepsilon / \|H_j\|^2` of isolation signals along the columns of H.

    Parameters
    ----------
    h_matrix : array_like, shape (n, q)
        The unknown-input directions :math:`H = RB_{un}` of an :class:`~intervalobs.observers.lpv.LPVIntervalUIO`.
    eps : array_like, shape (..., n)
        Isolation signals :math:`\underline\varepsilon` or :math:`\overline\varepsilon`.

    Returns
    -------
    numpy.ndarray, shape (..., q)

    References
    ----------
    Rotondo et al.: H of (26), the signals (29)–(30).
    """
    h = np.asarray(h_matrix, dtype=float)
    projector = (h / np.sum(h**2, axis=0)).T  # rows: H_j^T / |H_j|^2
    return np.asarray(np.asarray(eps, dtype=float) @ projector.T)


def isolate(
    observer: LPVIntervalUIO,
    t: ArrayLike,
    y: ArrayLike,
    u: ArrayLike | None = None,
    theta: ArrayLike | None = None,
) -> tuple[Estimate, IsolationRecord]:
    """Run an LPV interval UIO on a record and return the state bounds and the isolation signals.

    Parameters
    ----------
    observer : LPVIntervalUIO
        The unknown-input observer whose signals are projected on its H's columns.
    t : array_like, shape (T,)
        Uniform sample times.
    y : array_like, shape (T, p) or (M, T, p)
        Outputs.
    u : array_like, shape (T, m) or (M, T, m), optional
        Known inputs.
    theta : array_like, shape (T, n_theta) or (M, T, n_theta), optional
        Measured scheduling vector (required by designed observers).

    Returns
    -------
    estimate : Estimate
    record : IsolationRecord

    References
    ----------
    Rotondo et al.: the signals (29)–(30).
    """
    est, el, eh = observer.run_with_signals(t, y, u, theta=theta)
    return est, IsolationRecord(est.t, el, eh, fault_signals(observer.H, el), fault_signals(observer.H, eh))


def first_negative_time(t: ArrayLike, signal: ArrayLike, tol: float = 0.0) -> FloatArray:
    """First time each signal component is below ``-tol`` (NaN if never).

    Parameters
    ----------
    t : array_like, shape (T,)
        Times.
    signal : array_like, shape (..., T, q)
        Signals (time on the axis before the last).
    tol : float
        Tolerance: a value counts as negative when ``< -tol``.

    Returns
    -------
    numpy.ndarray, shape (..., q)
    """
    tt = np.asarray(t, dtype=float)
    sig = np.asarray(signal, dtype=float)
    if sig.ndim < 2 or sig.shape[-2] != tt.size:
        raise DimensionError(f"signal: expected shape (..., {tt.size}, q), got {sig.shape}")
    neg = sig < -tol
    idx = np.argmax(neg, axis=-2)
    return np.where(np.any(neg, axis=-2), tt[idx], np.nan)


def isolation_outcome(
    t: ArrayLike, signal_lower: ArrayLike, signal_upper: ArrayLike, onset: float, tol: float = 0.0
) -> dict[str, Any]:
    r"""Decisions of the isolation logic for one run: a fault is flagged when its signal goes negative.

    Parameters
    ----------
    t : array_like, shape (T,)
    signal_lower, signal_upper : array_like, shape (T, q)
        Isolation signals along the columns of H.
    onset : float
        Fault onset time (s); a negative signal at :math:`t \le` onset is a false alarm.
    tol : float
        A value is negative when ``< -tol``.

    Returns
    -------
    dict
        ``false_alarm`` (bool), ``isolated`` (1-based indices of faults whose signal went negative
        after the onset), ``detection_time_s`` (first negative time per isolated fault),
        ``first_negative_s`` (per fault, None if never).

    References
    ----------
    Rotondo et al.: the isolation logic (27)–(28).
    """
    tt = np.asarray(t, dtype=float)
    first = np.fmin(first_negative_time(tt, signal_lower, tol), first_negative_time(tt, signal_upper, tol))
    pre = tt <= onset
    early = np.fmin(
        first_negative_time(tt[pre], np.asarray(signal_lower)[pre], tol),
        first_negative_time(tt[pre], np.asarray(signal_upper)[pre], tol),
    )
    isolated = [j + 1 for j in range(first.size) if np.isfinite(first[j])]
    return {
        "false_alarm": bool(np.any(np.isfinite(early))),
        "isolated": isolated,
        "detection_time_s": [float(first[j - 1]) for j in isolated],
        "first_negative_s": [None if not np.isfinite(v) else float(v) for v in first],
    }


def scenario_success(first_negative: ArrayLike, active: Sequence[int], onset: float) -> NDArray[np.bool_]:
    """Indicator I of a run: exactly the active faults flagged, none before the onset.

    Parameters
    ----------
    first_negative : array_like, shape (..., q)
        First negative time of each fault's signal (NaN if never).
    active : sequence of int
        1-based indices of the faults acting after the onset (empty: no fault, scenario 1).
    onset : float
        Fault onset (s).

    Returns
    -------
    numpy.ndarray of bool, shape (...)

    References
    ----------
    Rotondo et al.: the indicator of (118).
    """
    fn = np.asarray(first_negative, dtype=float)
    flagged = np.isfinite(fn)
    want = np.zeros(fn.shape[-1], dtype=bool)
    for j in active:
        want[j - 1] = True
    early = np.any(flagged & (fn <= onset), axis=-1)
    return np.asarray(np.all(flagged == want, axis=-1) & ~early)


def psi_hat(indicators: ArrayLike) -> float:
    r"""Monte Carlo estimate :math:`\hat\Psi = \frac1M\sum_i I_i`: the share of runs isolated correctly.

    Parameters
    ----------
    indicators : array_like of bool, shape (M,)

    Returns
    -------
    float

    References
    ----------
    Rotondo et al.: Ψ̂ of (119).
    """
    ind = np.asarray(indicators, dtype=float).ravel()
    if ind.size == 0:
        raise DataError("indicators: expected at least one run, got none")
    return float(ind.mean())


def runs_for_sigma(sigma: float) -> int:
    r"""Runs M with :math:`\sigma_{\hat\Psi} \le \sigma`: :math:`M \ge \lceil \sigma^{-2}/4 \rceil`.

    Parameters
    ----------
    sigma : float

    Returns
    -------
    int

    References
    ----------
    Rotondo et al.: the run count (120).
    """
    if not sigma > 0:
        raise BoundsError(f"sigma: expected a positive standard deviation, got {sigma!r}")
    return math.ceil(0.25 / sigma**2 - 1e-9)


# --------------------------------------------------------------------------------------------------
# Campaigns
# --------------------------------------------------------------------------------------------------

TaskFunction = Callable[[float, float, Sequence[int], int], list[tuple[int, int, bool, bool, list[float | None]]]]
"""``task(level, magnitude, run_ids, seed) -> [(run, scenario, success, false_alarm, first_negative), …]``."""


@dataclass(frozen=True)
class Campaign:
    """A Monte Carlo campaign definition.

    Attributes
    ----------
    name : str
        Example name (``intervalobs campaign NAME``).
    task : callable
        Runs a batch of runs of one cell for every scenario (see :data:`TaskFunction`); must be
        importable by Dask workers (a module-level function).
    scenarios : tuple of str
        Scenario names ("1", "2", ...).
    levels, magnitudes : tuple of float
        Default grid.
    runs : int
        Default runs per cell (the paper's M = 100).
    magnitude_bound : float
        Largest magnitude the task accepts (its assumption on the fault size); :func:`run_campaign`
        checks every magnitude against [0, magnitude_bound] before any task starts.
    describe : dict
        Facts copied into ``psi.json`` (what a level, a magnitude and the indicator mean).
    level_label, magnitude_label : str
        Axis labels of the heat maps, with the model's units.
    task_overhead : float
        Fixed cost of one task, in runs: a task of ``b`` runs takes about ``task_overhead + b`` times one
        run (the time loop of a batched task costs the same for 1 run or 50). :func:`campaign_tasks`
        weighs it against the workers' idle time at the end; measured by benchmarks/campaign_scaling.py.
    level_overhead : float
        Cost, in runs, that a worker pays the first time it meets a level (a model built per level and
        cached in the worker's process). When positive, :func:`campaign_tasks` orders the tasks so that
        each worker keeps to one or two levels.
    """

    name: str
    task: TaskFunction
    scenarios: tuple[str, ...]
    levels: tuple[float, ...]
    magnitudes: tuple[float, ...]
    runs: int = 100
    magnitude_bound: float = math.inf
    describe: dict[str, Any] = field(default_factory=dict)
    level_label: str = "uncertainty level"
    magnitude_label: str = "fault magnitude"
    task_overhead: float = 0.0
    level_overhead: float = 0.0


@dataclass(frozen=True)
class CampaignResult:
    """``psi.json`` content plus bookkeeping.

    Attributes
    ----------
    psi : dict
        Scenario -> (levels × magnitudes) matrix of Ψ̂.
    runs : int
        Runs per cell.
    levels, magnitudes : list of float
        The grid.
    computed, reused : int
        Runs computed in this call and runs found in the SQLite file.
    seconds : float
        Wall time of this call.
    failed : list of dict
        One entry per task that raised: ``level``, ``magnitude``, ``runs`` (the run numbers it held) and
        ``error`` (the exception, one line). Their cells have Ψ̂ = NaN; running the campaign again retries them.
    tasks, workers : int
        Tasks this call submitted, and the worker threads they were cut for.
    """

    psi: dict[str, list[list[float]]]
    runs: int
    levels: list[float]
    magnitudes: list[float]
    computed: int
    reused: int
    seconds: float
    failed: list[dict[str, Any]] = field(default_factory=list)
    tasks: int = 0
    workers: int = 0


class CampaignInterrupted(KeyboardInterrupt):
    """Ctrl-C during :func:`run_campaign`: every finished batch is saved; the message says how many runs.

    Parameters
    ----------
    saved, total : int
        Runs of the requested grid in the store, and runs the grid needs.
    store : pathlib.Path
        The SQLite file; running the same campaign again computes only the missing runs.
    """

    def __init__(self, saved: int, total: int, store: Path) -> None:
        super().__init__(f"{saved} of {total} runs saved in {store}; run the same command again to resume")
        self.saved, self.total, self.store = saved, total, store


SCHEDULER_TIMEOUT = 5.0
"""Seconds :func:`run_campaign` waits for a Dask scheduler given by address before it gives up."""

MAX_BATCH = 100
"""Most runs in a task of the automatic cut (a cell of the paper's campaign): an interrupt loses at most
one task per worker."""

CUT_TOLERANCE = 0.03
"""The automatic cut takes the largest task size whose predicted time is within this fraction of the
best size's: a few per cent of balance is not worth many times the tasks."""


def _makespan(
    tasks: Sequence[tuple[float, float, Sequence[int]]], workers: int, overhead: float, level_overhead: float
) -> float:
    """Time, in runs, until ``workers`` workers finish ``tasks``, each handed in order to the first free worker.

    A task of ``b`` runs costs ``overhead + b``, plus ``level_overhead`` when its worker meets its level first.
    """
    finish = [(0.0, w) for w in range(max(workers, 1))]
    met: set[tuple[int, float]] = set()
    for level, _, ids in tasks:
        time_, w = finish[0]
        time_ += overhead + len(ids) + (0.0 if (w, level) in met else level_overhead)
        met.add((w, level))
        heapq.heapreplace(finish, (time_, w))
    return max(time_ for time_, _ in finish)


def campaign_tasks(
    cells: Sequence[tuple[float, float, Sequence[int]]],
    workers: int,
    batch: int | None = None,
    overhead: float = 0.0,
    level_overhead: float = 0.0,
) -> list[tuple[float, float, list[int]]]:
    """Cut the runs left in each cell into tasks for ``workers`` workers.

    Each cell's runs are split into tasks of nearly equal size (differing by at most one run), of at
    most ``batch`` runs. With ``batch=None`` the size is chosen in 1 ... :data:`MAX_BATCH` to minimise
    the predicted time to finish them all on ``workers`` workers, a task of ``b`` runs costing
    ``overhead + b`` runs' time, handed in order to the first free worker (the order Dask receives them:
    largest first, or level-affine, below; a worker's first task of a level costs ``level_overhead`` more);
    among times within
    :data:`CUT_TOLERANCE` of the best, the largest size wins (fewest tasks: least bookkeeping).

    With ``level_overhead > 0`` the order is level-affine instead (:func:`_level_affine`): a worker that
    takes the first free task gets a contiguous share of the level-major list, so it meets one or two
    levels instead of all of them.

    Parameters
    ----------
    cells : sequence of (level, magnitude, run numbers)
        The runs left in each cell of the grid.
    workers : int
        Worker threads that will run the tasks.
    batch : int, optional
        Most runs per task (default: chosen as above).
    overhead : float
        Fixed cost of a task, in runs (:attr:`Campaign.task_overhead`).
    level_overhead : float
        Cost of a worker's first task of a level, in runs (:attr:`Campaign.level_overhead`).

    Returns
    -------
    list of (level, magnitude, list of int)
        The tasks, largest first (or level-affine).
    """

    def cut(size: int) -> list[tuple[float, float, list[int]]]:
        tasks: list[tuple[float, float, list[int]]] = []
        for level, magnitude, ids in cells:
            parts = math.ceil(len(ids) / size)
            edges = [round(i * len(ids) / parts) for i in range(parts + 1)] if parts else []
            tasks += [(level, magnitude, list(ids[a:b])) for a, b in itertools.pairwise(edges)]
        return sorted(tasks, key=lambda task: -len(task[2]))

    def order(size: int) -> list[tuple[float, float, list[int]]]:
        return _level_affine(cut(size), workers, overhead, level_overhead) if level_overhead > 0 else cut(size)

    if batch is None:
        largest = min(MAX_BATCH, max((len(ids) for _, _, ids in cells), default=1))
        times = {size: _makespan(order(size), workers, overhead, level_overhead) for size in range(1, largest + 1)}
        best = min(times.values())
        batch = max(size for size, time_ in times.items() if time_ <= best * (1 + CUT_TOLERANCE))
    return order(batch)


def _level_affine(
    tasks: list[tuple[float, float, list[int]]], workers: int, overhead: float, level_overhead: float
) -> list[tuple[float, float, list[int]]]:
    """Order ``tasks`` so that handing each to the first free worker gives worker ``w`` the ``w``-th share.

    The tasks are listed level by level (largest first within a level) and split into ``workers``
    contiguous shares of equal runs. The order follows the dispatch it will meet: the worker predicted to be
    free first (costs as in :func:`_makespan`) gets the next task of its own share, or, once its share is
    done, the last task of the share with the most runs left. Each worker then meets one or two levels
    (levels over workers more when there are fewer workers than levels).
    """
    ordered = sorted(tasks, key=lambda task: task[0])  # stable: largest first within a level
    total = sum(len(ids) for _, _, ids in ordered) or 1
    shares: list[list[tuple[float, float, list[int]]]] = [[] for _ in range(max(workers, 1))]
    done = 0
    for task in ordered:
        shares[min(int((done + len(task[2]) / 2) * len(shares) / total), len(shares) - 1)].append(task)
        done += len(task[2])
    for share in shares:
        share.reverse()  # pop() takes the share's next task
    finish = [(0.0, w) for w in range(len(shares))]
    met: set[tuple[int, float]] = set()
    out: list[tuple[float, float, list[int]]] = []
    while len(out) < len(ordered):
        time_, w = finish[0]
        own = shares[w] or max(shares, key=lambda share: sum(len(ids) for _, _, ids in share))
        task = own.pop() if own is shares[w] else own.pop(0)
        time_ += overhead + len(task[2]) + (0.0 if (w, task[0]) in met else level_overhead)
        met.add((w, task[0]))
        heapq.heapreplace(finish, (time_, w))
        out.append(task)
    return out


def _open_store(path: Path) -> sqlite3.Connection:
    con = sqlite3.connect(path)
    con.execute(
        "CREATE TABLE IF NOT EXISTS runs (level REAL, magnitude REAL, run INTEGER, scenario INTEGER, "
        "success INTEGER, false_alarm INTEGER, first_negative TEXT, seed INTEGER, "
        "PRIMARY KEY (level, magnitude, run, scenario, seed))"
    )
    con.commit()
    return con


def _done_runs(con: sqlite3.Connection, level: float, magnitude: float, seed: int, scenarios: int) -> set[int]:
    rows = con.execute(
        "SELECT run FROM runs WHERE level = ? AND magnitude = ? AND seed = ? GROUP BY run HAVING COUNT(*) = ?",
        (level, magnitude, seed, scenarios),
    ).fetchall()
    return {int(r[0]) for r in rows}


def run_campaign(
    campaign: Campaign,
    out_dir: str | Path,
    runs: int | None = None,
    levels: Sequence[float] | None = None,
    magnitudes: Sequence[float] | None = None,
    scheduler: str | None = None,
    workers: int = 2,
    batch: int | None = None,
    seed: int = 0,
    progress: bool = True,
    plots: bool = True,
    processes: bool = True,
) -> CampaignResult:
    r"""Run (or resume) a Monte Carlo campaign on Dask and write ``psi.json`` and heat maps.

    Each task is one batch of runs of one cell (level, magnitude), all scenarios, computed with a
    leading Monte Carlo axis; the batches are cut for the worker threads present when the campaign
    starts (:func:`campaign_tasks`). Results are appended to ``out_dir/campaign.sqlite`` as soon as a
    task finishes; runs already in the file (same seed) are not recomputed. A task that raises is
    recorded in :attr:`CampaignResult.failed` (and ``psi.json``), with a ``RuntimeWarning``, and the
    others go on: its cell's Ψ̂ is NaN until a later call computes the runs it lacks.

    Parameters
    ----------
    campaign : Campaign
        Definition (task function, scenarios, default grid).
    out_dir : str or Path
        Output folder (created).
    runs : int, optional
        Runs M per cell (default ``campaign.runs``).
    levels, magnitudes : sequence of float, optional
        Grid (default the campaign's).
    scheduler : str, optional
        Address of an existing Dask scheduler; default: a local cluster with ``workers`` processes. Its
        workers should be connected before the call: the tasks are cut for the threads present then.
    workers : int
        Local worker processes (one thread each); with ``scheduler``, the number of threads to cut the
        tasks for if none is connected yet.
    batch : int, optional
        Most runs per task (default: :func:`campaign_tasks` chooses for the workers present).
    seed : int
        Base seed (run i of a cell always draws the same realisation).
    progress : bool
        Show a tqdm bar (runs done / left) on stderr.
    plots : bool
        Write one heat-map PNG per scenario.
    processes : bool
        Local cluster of processes (default) or of threads in this process.

    Returns
    -------
    CampaignResult

    Raises
    ------
    ArgumentError
        When a count is below 1, a level is not a fraction in [0, 1) or a magnitude is outside
        [0, ``campaign.magnitude_bound``] (checked before anything runs).
    FileError
        When ``out_dir`` cannot be written.
    SchedulerError
        When the scheduler at ``scheduler`` does not answer within :data:`SCHEDULER_TIMEOUT` seconds.
    CampaignInterrupted
        On Ctrl-C (a ``KeyboardInterrupt``), after the finished batches are saved.
    """
    start = time.perf_counter()
    m, lv, mg = _campaign_grid(campaign, runs, levels, magnitudes)
    as_count("workers", workers)
    if batch is not None:
        as_count("batch", batch)
    as_count("seed", seed, minimum=0)
    out = as_output_folder("out_dir", out_dir)
    out.mkdir(parents=True, exist_ok=True)
    con = _open_store(out / "campaign.sqlite")
    n_s = len(campaign.scenarios)
    cells, reused = _runs_to_compute(con, lv, mg, seed, n_s, m)
    total = len(lv) * len(mg) * m
    report: dict[str, Any] = {"computed": 0, "failed": [], "tasks": 0, "workers": 0}
    if cells:
        try:
            report = _compute(
                campaign, cells, con, seed, (scheduler, workers, processes, batch), progress, (reused, total)
            )
        except KeyboardInterrupt:
            saved = sum(len({i for i in _done_runs(con, lvl, mag, seed, n_s) if i < m}) for lvl in lv for mag in mg)
            con.close()
            raise CampaignInterrupted(saved, total, out / "campaign.sqlite") from None
        except SchedulerError:
            con.close()
            raise
    psi = _psi(con, campaign, lv, mg, seed, m)
    con.close()
    failed = report["failed"]
    result = CampaignResult(
        psi,
        m,
        lv,
        mg,
        report["computed"],
        reused,
        time.perf_counter() - start,
        failed,
        report["tasks"],
        report["workers"],
    )
    _write_psi(out, campaign, result)
    if plots:
        _heatmaps(result, out, campaign)
    return result


def _campaign_grid(
    campaign: Campaign, runs: int | None, levels: Sequence[float] | None, magnitudes: Sequence[float] | None
) -> tuple[int, list[float], list[float]]:
    """The runs per cell and the grid of :func:`run_campaign`, checked (the campaign's defaults for None)."""
    m = as_count("runs", campaign.runs if runs is None else runs)
    lv = [as_fraction(f"levels[{i}]", v) for i, v in enumerate(campaign.levels if levels is None else levels)]
    mg = [float(v) for v in as_vector("magnitudes", campaign.magnitudes if magnitudes is None else magnitudes)]
    if not lv or not mg:
        raise ArgumentError(f"levels, magnitudes: expected at least one of each, got {len(lv)} and {len(mg)}")
    if not all(0.0 <= v <= campaign.magnitude_bound for v in mg):
        got = ", ".join(f"{v:g}" for v in mg)
        raise ArgumentError(f"magnitudes: expected fault sizes in [0, {campaign.magnitude_bound:g}], got {got}")
    return m, lv, mg


def _runs_to_compute(
    con: sqlite3.Connection, levels: list[float], magnitudes: list[float], seed: int, scenarios: int, runs: int
) -> tuple[list[tuple[float, float, list[int]]], int]:
    """The cells with runs missing from the store (level, magnitude, run indices) and the count of runs reused."""
    cells: list[tuple[float, float, list[int]]] = []
    reused = 0
    for level in levels:
        for magnitude in magnitudes:
            done = _done_runs(con, level, magnitude, seed, scenarios)
            todo = [i for i in range(runs) if i not in done]
            reused += runs - len(todo)
            if todo:
                cells.append((level, magnitude, todo))
    return cells, reused


def _write_psi(out: Path, campaign: Campaign, result: CampaignResult) -> None:
    """``psi.json`` of a campaign, with a ``RuntimeWarning`` naming the cells whose task raised."""
    failed = result.failed
    facts = {
        "runs": result.runs,
        "levels": result.levels,
        "magnitudes": result.magnitudes,
        "psi": result.psi,
        **campaign.describe,
    }
    (out / "psi.json").write_text(json.dumps({**facts, "failed": failed} if failed else facts, indent=2) + "\n")
    if failed:
        cells_failed = ", ".join(f"({f['level']:g}, {f['magnitude']:g})" for f in failed)
        warnings.warn(
            f"{len(failed)} task(s) of {campaign.name} raised (first: {failed[0]['error']}); cells (level, magnitude) "
            f"{cells_failed} have Ψ̂ = NaN; run the same campaign again to retry them",
            RuntimeWarning,
            stacklevel=3,
        )


def _psi(
    con: sqlite3.Connection, campaign: Campaign, levels: list[float], magnitudes: list[float], seed: int, runs: int
) -> dict[str, list[list[float]]]:
    """Ψ̂ of every scenario and cell from the store; NaN for a cell that lacks some of its ``runs`` runs."""
    psi: dict[str, list[list[float]]] = {}
    for s_idx, s_name in enumerate(campaign.scenarios):
        mat = []
        for level in levels:
            row = []
            for magnitude in magnitudes:
                vals = con.execute(
                    "SELECT success FROM runs "
                    "WHERE level = ? AND magnitude = ? AND seed = ? AND scenario = ? AND run < ?",
                    (level, magnitude, seed, s_idx, runs),
                ).fetchall()
                row.append(psi_hat([v[0] for v in vals]) if len(vals) == runs else float("nan"))
            mat.append(row)
        psi[s_name] = mat
    return psi


def _connect(scheduler: str | None, workers: int, processes: bool) -> tuple[Any, Any]:
    """A Dask client, on a new local cluster (returned too) or on the scheduler at ``scheduler``."""
    from dask.distributed import Client, LocalCluster

    if scheduler is None:
        with _sigint_ignored():
            cluster = LocalCluster(
                n_workers=workers, threads_per_worker=1, processes=processes, dashboard_address=None, silence_logs=40
            )
        try:
            return Client(cluster), cluster
        except BaseException:
            cluster.close()
            raise
    try:
        return Client(scheduler, timeout=SCHEDULER_TIMEOUT), None
    except (OSError, TimeoutError, ValueError):
        raise SchedulerError(
            f"scheduler: expected the address of a running Dask scheduler (tcp://host:port), got {scheduler!r} "
            f"(no answer within {SCHEDULER_TIMEOUT:g} s)"
        ) from None


def _compute(
    campaign: Campaign,
    cells: list[tuple[float, float, list[int]]],
    con: sqlite3.Connection,
    seed: int,
    where: tuple[str | None, int, bool, int | None],
    progress: bool,
    done_of_total: tuple[int, int],
) -> dict[str, Any]:
    """Run the runs left in ``cells`` on Dask, appending each finished task to the store.

    ``where`` is (scheduler, workers, processes, batch) of :func:`run_campaign`. Returns ``computed``
    (runs), ``failed`` (one entry per task that raised), ``tasks`` and ``workers``.
    """
    from dask.distributed import as_completed
    from tqdm import tqdm

    scheduler, workers, processes, batch = where
    client, cluster = _connect(scheduler, workers, processes)
    bar = None
    report: dict[str, Any] = {"computed": 0, "failed": []}
    try:
        threads = sum(client.nthreads().values()) or workers
        tasks = campaign_tasks(cells, threads, batch, campaign.task_overhead, campaign.level_overhead)
        report.update(tasks=len(tasks), workers=threads)
        bar = tqdm(
            total=done_of_total[1],
            initial=done_of_total[0],
            desc=campaign.name,
            unit="run",
            smoothing=0.0,
            postfix=f"{len(tasks)} tasks, {threads} workers",
            disable=not progress,
            file=sys.stderr,
        )
        futures = [client.submit(campaign.task, lvl, mag, ids, seed, pure=False) for lvl, mag, ids in tasks]
        meta = {f.key: task for f, task in zip(futures, tasks)}
        for fut in as_completed(futures):
            lvl, mag, ids = meta[fut.key]
            try:
                rows = fut.result()
            except Exception as exc:  # a task's failure is the user's model's: record it, keep the others
                error = f"{type(exc).__name__}: {exc}".splitlines()[0]
                report["failed"].append({"level": lvl, "magnitude": mag, "runs": ids, "error": error})
                continue
            con.executemany(
                "INSERT OR REPLACE INTO runs VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
                [(lvl, mag, r, s, int(ok), int(fa), json.dumps(fn), seed) for r, s, ok, fa, fn in rows],
            )
            con.commit()
            report["computed"] += len(ids)
            bar.update(len(ids))
    finally:
        if bar is not None:
            bar.close()
        client.close()
        if cluster is not None:
            cluster.close()
    return report


@contextlib.contextmanager
def _sigint_ignored() -> Iterator[None]:
    """Ignore SIGINT while the local Dask cluster starts its worker processes.

    Ctrl-C in a terminal goes to the whole process group. Processes started while it is ignored
    inherit that, so the workers never see it (instead of printing a traceback each) and only this
    process handles it: it saves what finished and stops them. A Ctrl-C pressed during the start
    (a few seconds) is lost; pressed later, it is handled.
    """
    main = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN) if main else None
    try:
        yield
    finally:
        if main:
            signal.signal(signal.SIGINT, previous)


def _heatmaps(result: CampaignResult, out: Path, campaign: Campaign) -> None:
    from .plotting import plot_psi, save_figure

    for s_name, mat in result.psi.items():
        title = f"{campaign.name}: estimated Ψ̂, scenario {s_name} (M = {result.runs})"
        fig = plot_psi(mat, result.levels, result.magnitudes, title, campaign.level_label, campaign.magnitude_label)
        save_figure(fig, out / f"psi_scenario{s_name}.png")
