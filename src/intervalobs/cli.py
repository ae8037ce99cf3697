"""Command-line interface: ``intervalobs list``, ``reproduce NAME|all``, ``tightness NAME``, ``check DIR``,
``estimate MODEL DATA``, ``campaign NAME``."""

from __future__ import annotations

import argparse
import signal
import sys
import threading
import time
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from . import __version__
from . import cli_types as types
from .errors import FileError, IntervalObserverError
from .records import OBSERVERS
from .references import short_name
from .validation import as_output_folder

if TYPE_CHECKING:
    from .diagnosis import Campaign
    from .reproduce import Example

__all__ = ["main"]


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line and exit code 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        raise SystemExit(_fail(message))


def _fail(message: str) -> int:
    """Print ``intervalobs: error: MESSAGE`` on one line; return the exit code of bad input, 2."""
    sys.stderr.write(f"intervalobs: error: {message}\n")
    return 2


def _parser(examples: Sequence[str], campaigns: Sequence[str]) -> argparse.ArgumentParser:
    parser = _Parser(prog="intervalobs", description="Guaranteed interval estimation: reproduce the papers.")
    parser.add_argument("--version", action="version", version=f"intervalobs {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    commands.add_parser("list", help="list the reproducible examples")
    reproduce = commands.add_parser("reproduce", help="run an example (or all) and write its results")
    reproduce.add_argument(
        "name", metavar="NAME", type=types.choice([*examples, "all"]), help="example from `intervalobs list`, or 'all'"
    )
    reproduce.add_argument(
        "--out", type=types.output_folder, default="results", help="output folder (default: results)"
    )
    reproduce.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    reproduce.add_argument(
        "--full",
        action="store_true",
        help="also run the comparison analyses (tightness references, lower bounds, the angles-only bank): "
        "minutes instead of seconds",
    )
    reproduce.add_argument(
        "--jobs",
        type=types.count,
        default=None,
        help="examples run at once, one process each (default: the cores, at most the examples)",
    )
    reproduce.add_argument("--seed", type=types.seed, default=0, help="random seed, an integer >= 0 (default: 0)")
    tightness = commands.add_parser("tightness", help="print an example's width ratios to the exact hull")
    tightness.add_argument("name", metavar="NAME", type=types.choice(examples), help="example from `intervalobs list`")
    tightness.add_argument(
        "--results",
        type=types.input_folder,
        default=None,
        metavar="DIR",
        help="read the report from DIR/NAME/summary.json written by `reproduce` (default: run the example)",
    )
    tightness.add_argument(
        "--seed", type=types.seed, default=0, help="random seed when the example is run (default: 0)"
    )
    check = commands.add_parser("check", help="check reproduction folders against the file contract")
    check.add_argument("folders", nargs="+", metavar="DIR", help="folders written by reproduce, e.g. results/NAME")
    estimate = commands.add_parser(
        "estimate",
        help="bounds of the states over a measured record",
        description="Bounds of the states over a measured record: MODEL is a .toml or .py model file, DATA a .csv "
        "(or .parquet) record with a time column and the model's output and input columns, matched by name.",
    )
    estimate.add_argument("model", nargs="?", metavar="MODEL", help="model file (.toml or .py)")
    estimate.add_argument("data", nargs="?", metavar="DATA", help="record (.csv or .parquet)")
    estimate.add_argument(
        "--observer",
        type=types.choice(list(OBSERVERS)),
        default="auto",
        help="observer (default: auto, the choice of intervalobs.observe)",
    )
    estimate.add_argument("--time", default=None, metavar="COLUMN", help="time column (default: t or time)")
    estimate.add_argument(
        "--out",
        type=types.output_folder,
        default=None,
        metavar="DIR",
        help="output folder (default: results/DATA-name)",
    )
    estimate.add_argument("--plot", action="store_true", help="also draw bounds.png")
    estimate.add_argument(
        "--example",
        type=types.output_folder,
        default=None,
        metavar="DIR",
        help="write an example model and record into DIR, then stop",
    )
    campaign = commands.add_parser("campaign", help="Monte Carlo performance campaign of an example, on Dask")
    campaign.add_argument("name", metavar="NAME", type=types.choice(campaigns), help="example with a campaign")
    campaign.add_argument(
        "--runs", type=types.count, default=None, help="Monte Carlo runs per cell (default: the paper's)"
    )
    campaign.add_argument(
        "--levels",
        type=types.fraction,
        nargs="+",
        default=None,
        help="uncertainty levels as fractions in [0, 1): 0.05 is ±5 %% of the nominal parameters",
    )
    campaign.add_argument("--magnitudes", type=float, nargs="+", default=None, help="fault magnitudes")
    campaign.add_argument("--scheduler", default=None, help="address of a running Dask scheduler (tcp://host:port)")
    campaign.add_argument("--workers", type=types.count, default=2, help="local Dask workers (default: 2)")
    campaign.add_argument("--out", type=types.output_folder, default="results", help="output folder (default: results)")
    campaign.add_argument("--seed", type=types.seed, default=0, help="random seed, an integer >= 0 (default: 0)")
    campaign.add_argument("--no-plots", action="store_true", help="skip the heat maps")
    return parser


def _campaigns(examples: dict[str, Example]) -> dict[str, Campaign]:
    """The examples whose module defines a ``CAMPAIGN``."""
    import importlib

    from .diagnosis import Campaign

    found = {name: getattr(importlib.import_module(e.run.__module__), "CAMPAIGN", None) for name, e in examples.items()}
    return {name: c for name, c in found.items() if isinstance(c, Campaign)}


_CAMPAIGN_OPTIONS = ("runs", "levels", "magnitudes", "scheduler", "workers", "seed")
"""Options of ``intervalobs campaign`` passed on, by the same names, to :func:`~intervalobs.diagnosis.run_campaign`."""


def _campaign(args: argparse.Namespace, campaign: Campaign) -> int:
    from .diagnosis import run_campaign

    out = args.out / args.name / "campaign"
    with warnings.catch_warnings():  # failed cells: one line each below
        warnings.filterwarnings("ignore", message=r"\d+ task\(s\) of .* raised", category=RuntimeWarning)
        options = {name: getattr(args, name) for name in _CAMPAIGN_OPTIONS}
        result = run_campaign(campaign, out, plots=not args.no_plots, **options)
    print(
        f"{args.name}: campaign of {result.runs} runs per cell, {result.computed} computed, {result.reused} reused, "
        f"{result.seconds:.1f} s ({result.tasks} tasks on {result.workers} workers) -> {out / 'psi.json'}"
    )
    for failed in result.failed:
        sys.stderr.write(
            f"intervalobs: failed cell (level {failed['level']:g}, magnitude {failed['magnitude']:g}), "
            f"{len(failed['runs'])} runs: {failed['error']}\n"
        )
    return 1 if result.failed else 0


def _estimate(args: argparse.Namespace) -> int:
    """``intervalobs estimate MODEL DATA``, or ``--example DIR``: the wiring of :mod:`intervalobs.records`."""
    from . import records

    if args.example is not None:
        files = records.write_example(args.example)
        print(f"wrote {', '.join(map(str, files))}; try: intervalobs estimate {files[0]} {files[1]} --plot")
        return 0
    if args.model is None or args.data is None:
        return _fail("estimate: expected MODEL and DATA (or --example DIR), got fewer")
    start = time.perf_counter()
    model = records.read_model(args.model)
    record = records.read_record(args.data, model, time=args.time)
    out = args.out if args.out is not None else as_output_folder("--out", Path("results") / record.path.stem)
    result = records.estimate_record(model, record, args.observer)
    source = {"model": str(model.path), "data": str(record.path)}
    records.write_bounds(result, out, plot=args.plot, parquet=record.path.suffix == ".parquet", source=source)
    head = f"{record.path.name}: {record.t.size} samples every {record.h:g} s, {args.observer} observer"
    if not result.consistent:
        print(
            f"{head}: the data contradict the model from t = {result.inconsistent_from:g} s (no state fits them; "
            f"bounds kept up to it, summary.json: consistent false), {time.perf_counter() - start:.1f} s -> {out}"
        )
        return 0
    widths = ", ".join(f"{n} {w:.4g}" for n, w in zip(result.state_names, result.width()[-1]))
    print(f"{head}, final widths {widths}, {time.perf_counter() - start:.1f} s -> {out}")
    return 0


def _run_example(task: tuple[str, Path, int, bool, bool]) -> tuple[str, dict[str, Any], float]:
    """Run one example (in this process or a worker): its name, state enclosure and seconds."""
    from .reproduce import registry

    name, out, seed, plots, full = task
    start = time.perf_counter()
    (out / name).mkdir(parents=True, exist_ok=True)
    summary = registry()[name].run(out / name, seed, plots, full=full)
    return name, summary["enclosure"]["state"], time.perf_counter() - start


def _ignore_sigint() -> None:
    """Workers leave Ctrl-C to the parent, which stops them (no traceback from each)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _reproduce(args: argparse.Namespace, examples: dict[str, Example]) -> int:
    import multiprocessing
    import os

    from tqdm import tqdm

    chosen = sorted(examples, key=lambda name: -examples[name].weight) if args.name == "all" else [args.name]
    out = args.out
    tasks = [(name, out, args.seed, not args.no_plots, args.full) for name in chosen]
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    jobs = min(args.jobs or cores, len(tasks))
    written: list[str] = []
    progress = tqdm(total=len(tasks), desc="reproduce", unit="example", disable=len(tasks) == 1, file=sys.stderr)
    pool = multiprocessing.get_context("spawn").Pool(jobs, initializer=_ignore_sigint) if jobs > 1 else None
    handles_term = pool is not None and threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, lambda signum, _: sys.exit(128 + signum)) if handles_term else None
    try:
        results = pool.imap_unordered(_run_example, tasks) if pool is not None else map(_run_example, tasks)
        for name, state, seconds in results:
            written.append(name)
            progress.update()
            tqdm.write(
                f"{name}: enclosure {state['fraction']:.6g} (max violation {state['max_violation']:.3g}), "
                f"{seconds:.1f} s -> {out / name}",
                file=sys.stdout,
            )
    except KeyboardInterrupt:
        progress.close()
        rest = " ".join(name for name in chosen if name not in written)
        raise KeyboardInterrupt(
            f"{len(written)} of {len(chosen)} examples written to {out}; rerun `intervalobs reproduce NAME` for the "
            f"others: {rest}"
        ) from None
    finally:
        progress.close()
        if pool is not None:  # killed or done: the workers stop with this process
            pool.terminate()
            pool.join()
        if handles_term:
            signal.signal(signal.SIGTERM, previous)
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; returns the exit code (0 on success, 2 on bad input, 130 when interrupted, 1 when a
    campaign finished with failed cells).

    Bad input (an option out of range, an unwritable output folder, a library error) is reported on
    one line, ``intervalobs: error: ...``, with exit code 2. Ctrl-C prints one line saying what was
    saved, with exit code 130.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
    """
    from .reproduce import registry

    try:
        examples = registry()
        campaigns = _campaigns(examples)
        try:
            args = _parser(list(examples), list(campaigns)).parse_args(argv)
        except SystemExit as exc:
            return int(exc.code or 0)
        if args.command == "list":
            for example in examples.values():
                print(f"{example.name:20s}  {short_name(example.seed_file):36s}  {example.description}")
            return 0
        if args.command == "check":
            return _check(args.folders)
        if args.command == "estimate":
            return _estimate(args)
        if args.command == "campaign":
            return _campaign(args, campaigns[args.name])
        if args.command == "tightness":
            return _tightness(examples[args.name], args.results, args.seed)
        return _reproduce(args, examples)
    except IntervalObserverError as exc:
        return _fail(str(exc))
    except KeyboardInterrupt as exc:
        sys.stderr.write(f"intervalobs: interrupted{': ' + str(exc) if str(exc) else ''}\n")
        return 130


def _check(folders: Sequence[str]) -> int:
    """``intervalobs check DIR ...``: exit code 0 when every folder meets the contract, 1 otherwise."""
    from .reproduce.contract import check_reproduction

    failed = 0
    for folder in folders:
        problems = check_reproduction(Path(folder))
        print(f"{folder}: {'ok' if not problems else 'FALLS SHORT'}")
        for problem in problems:
            print(f"  - {problem}")
        failed += bool(problems)
    return 1 if failed else 0


def _tightness(example: Example, results: Path | None, seed: int) -> int:
    """``intervalobs tightness NAME``: the table of ``summary.json``'s ``tightness`` object."""
    import json
    import tempfile

    from .tightness import format_tightness

    if results is not None:
        path = results / example.name / "summary.json"
        try:
            summary = json.loads(path.read_text())
        except (OSError, ValueError):
            summary = {}
        if "tightness" not in summary:
            raise FileError(
                f"argument --results: expected a folder holding {example.name}/summary.json with a tightness report "
                f"(written by `intervalobs reproduce {example.name} --full`), got {str(results)!r}"
            )
    else:
        with tempfile.TemporaryDirectory() as tmp:
            summary = example.run(Path(tmp) / example.name, seed, False)
        if "tightness" not in summary:
            return _fail(f"NAME: expected an example with a tightness report (a linear one), got {example.name!r}")
    print(
        format_tightness(
            summary["tightness"], title=f"{example.name}: tightness ({short_name(str(summary.get('seed', '-')))})"
        )
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
