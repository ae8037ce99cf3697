"""Command-line interface: ``intervalobs list``, ``reproduce NAME|all``, ``tightness NAME``, ``check DIR``,
``estimate MODEL DATA``, ``campaign NAME``."""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from . import __version__
from .errors import IntervalObserverError
from .records import OBSERVERS

__all__ = ["main"]


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line and exit code 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        sys.stderr.write(f"error: {message}\n")
        raise SystemExit(2)


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="intervalobs", description="Guaranteed interval estimation: reproduce the papers.")
    parser.add_argument("--version", action="version", version=f"intervalobs {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    commands.add_parser("list", help="list the reproducible examples")
    reproduce = commands.add_parser("reproduce", help="run an example (or all) and write its results")
    reproduce.add_argument("name", help="example name from `intervalobs list`, or 'all'")
    reproduce.add_argument("--out", default="results", help="output folder (default: results)")
    reproduce.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    reproduce.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    tightness = commands.add_parser("tightness", help="print an example's width ratios to the exact hull")
    tightness.add_argument("name", help="example name from `intervalobs list`")
    tightness.add_argument(
        "--results", default=None, help="read DIR/NAME/summary.json if it has a tightness report (else run it)"
    )
    tightness.add_argument("--seed", type=int, default=0, help="random seed when the example is run (default: 0)")
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
    estimate.add_argument("--observer", choices=list(OBSERVERS), default="tube", help="observer (default: tube)")
    estimate.add_argument("--time", default=None, metavar="COLUMN", help="time column (default: t or time)")
    estimate.add_argument("--out", default=None, metavar="DIR", help="output folder (default: results/DATA-name)")
    estimate.add_argument("--plot", action="store_true", help="also draw bounds.png")
    estimate.add_argument(
        "--example", default=None, metavar="DIR", help="write an example model and record into DIR, then stop"
    )
    campaign = commands.add_parser("campaign", help="Monte Carlo performance campaign of an example, on Dask")
    campaign.add_argument("name", help="example with a campaign (e.g. manipulator-lpv)")
    campaign.add_argument("--runs", type=int, default=None, help="Monte Carlo runs per cell (default: the paper's)")
    campaign.add_argument("--levels", type=float, nargs="+", default=None, help="uncertainty levels")
    campaign.add_argument("--magnitudes", type=float, nargs="+", default=None, help="fault magnitudes")
    campaign.add_argument("--scheduler", default=None, help="address of an existing Dask scheduler")
    campaign.add_argument("--workers", type=int, default=2, help="local Dask workers (default: 2)")
    campaign.add_argument("--out", default="results", help="output folder (default: results)")
    campaign.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    campaign.add_argument("--no-plots", action="store_true", help="skip the heat maps")
    return parser


def _campaign(args: argparse.Namespace) -> int:
    import importlib

    from .diagnosis import Campaign, run_campaign
    from .reproduce import registry

    example = registry().get(args.name)
    found = getattr(importlib.import_module(example.run.__module__), "CAMPAIGN", None) if example else None
    if not isinstance(found, Campaign):
        sys.stderr.write(f"error: NAME: expected an example with a campaign (manipulator-lpv), got {args.name!r}\n")
        return 2
    out = Path(args.out) / args.name / "campaign"
    try:
        result = run_campaign(
            found,
            out,
            runs=args.runs,
            levels=args.levels,
            magnitudes=args.magnitudes,
            scheduler=args.scheduler,
            workers=args.workers,
            seed=args.seed,
            plots=not args.no_plots,
        )
    except IntervalObserverError as exc:
        sys.stderr.write(f"error: {args.name}: {exc}\n")
        return 2
    print(
        f"{args.name}: campaign of {result.runs} runs per cell, {result.computed} computed, {result.reused} reused, "
        f"{result.seconds:.1f} s -> {out / 'psi.json'}"
    )
    return 0


def _estimate(args: argparse.Namespace) -> int:
    """``intervalobs estimate MODEL DATA``, or ``--example DIR``: the wiring of :mod:`intervalobs.records`."""
    from . import records

    if args.example is not None:
        files = records.write_example(args.example)
        print(f"wrote {', '.join(map(str, files))}; try: intervalobs estimate {files[0]} {files[1]} --plot")
        return 0
    if args.model is None or args.data is None:
        sys.stderr.write("error: estimate: expected MODEL and DATA (or --example DIR), got fewer\n")
        return 2
    start = time.perf_counter()
    try:
        model = records.read_model(args.model)
        record = records.read_record(args.data, model, time=args.time)
        result = records.estimate_record(model, record, args.observer)
        out = Path(args.out) if args.out is not None else Path("results") / record.path.stem
        source = {"model": str(model.path), "data": str(record.path)}
        records.write_bounds(result, out, plot=args.plot, parquet=record.path.suffix == ".parquet", source=source)
    except IntervalObserverError as exc:
        sys.stderr.write(f"error: {exc}\n")
        return 2
    widths = ", ".join(f"{n} {w:.4g}" for n, w in zip(result.state_names, result.width()[-1]))
    print(
        f"{record.path.name}: {record.t.size} samples every {record.h:g} s, {args.observer} observer, "
        f"final widths {widths}, {time.perf_counter() - start:.1f} s -> {out}"
    )
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; returns the exit code (0 on success, 2 on bad input).

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
    """
    from tqdm import tqdm

    from .reproduce import registry

    try:
        args = _parser().parse_args(argv)
    except SystemExit as exc:
        return int(exc.code or 0)
    if args.command == "campaign":
        return _campaign(args)
    if args.command == "check":
        return _check(args.folders)
    if args.command == "estimate":
        return _estimate(args)
    examples = registry()
    if args.command == "list":
        for example in examples.values():
            print(f"{example.name:20s}  {example.seed_file:26s}  {example.description}")
        return 0
    if args.command == "tightness":
        return _tightness(examples, args.name, args.results, args.seed)
    if args.name != "all" and args.name not in examples:
        sys.stderr.write(f"error: NAME: expected one of {', '.join(['all', *examples])}, got {args.name!r}\n")
        return 2
    chosen = list(examples.values()) if args.name == "all" else [examples[args.name]]
    out = Path(args.out)
    progress = tqdm(chosen, desc="reproduce", unit="example", disable=len(chosen) == 1, file=sys.stderr)
    for example in progress:
        progress.set_postfix_str(example.name)
        start = time.perf_counter()
        try:
            summary = example.run(out / example.name, args.seed, not args.no_plots)
        except IntervalObserverError as exc:
            sys.stderr.write(f"error: {example.name}: {exc}\n")
            return 2
        state = summary["enclosure"]["state"]
        tqdm.write(
            f"{example.name}: enclosure {state['fraction']:.6g} (max violation {state['max_violation']:.3g}), "
            f"{time.perf_counter() - start:.1f} s -> {out / example.name}",
            file=sys.stdout,
        )
    return 0


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


def _tightness(examples: dict[str, Any], name: str, results: str | None, seed: int) -> int:
    """``intervalobs tightness NAME``: the table of ``summary.json``'s ``tightness`` object."""
    import json
    import tempfile

    from .tightness import format_tightness

    if name not in examples:
        sys.stderr.write(f"error: NAME: expected one of {', '.join(examples)}, got {name!r}\n")
        return 2
    summary: dict[str, Any] | None = None
    if results is not None:
        path = Path(results) / name / "summary.json"
        if path.is_file():
            summary = json.loads(path.read_text())
    if summary is None or "tightness" not in summary:
        with tempfile.TemporaryDirectory() as tmp:
            try:
                summary = examples[name].run(Path(tmp) / name, seed, False)
            except IntervalObserverError as exc:
                sys.stderr.write(f"error: {name}: {exc}\n")
                return 2
    if "tightness" not in summary:
        sys.stderr.write(f"error: NAME: {name!r} has no tightness report (not a linear example)\n")
        return 2
    print(format_tightness(summary["tightness"], title=f"{name}: tightness (seed {summary.get('seed')})"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
