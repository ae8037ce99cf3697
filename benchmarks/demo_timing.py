"""`make demo` timing: `intervalobs reproduce all` (the default, without ``--full``) from a fresh clone.

Clones the commit checked out here (``git clone`` of this repository, then that commit) into a temporary
folder and installs it there as ``make demo`` does (``make .venv/.installed``: its own virtual environment,
the pinned versions, the package editable); the install is timed apart and left out, and the script waits
``--settle`` seconds for the install's load to decay (and, with ``--quiet-below``, for the machine's load
average to fall below a level). Then it times ``.venv/bin/intervalobs reproduce all`` in the clone, with
the thread settings of the Makefile, from outside: wall seconds, and the CPU seconds of it and its workers.
A fresh clone has no bytecode and no compiled-kernel cache, so the timing includes what a first user pays.
It reads each example's seconds and enclosure from the output, and notes the machine: usable cores and the
1-minute load average before and after (on a shared machine the wall time depends on the other load; the
CPU time much less). ``--here`` times the command in this checkout's environment instead (no clone, no
install). Writes benchmarks/demo_timing.json, the source of the README's timing statement.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
THREADS = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
"""The Makefile's exports for `make demo` (BLAS threads only fight over the cores)."""


def _git(*args: str, cwd: Path = ROOT) -> str:
    return subprocess.run(["git", *args], cwd=cwd, capture_output=True, text=True, check=True).stdout.strip()


def fresh_clone(folder: Path) -> tuple[Path, dict[str, object]]:
    """Clone this checkout's commit into ``folder`` and install it there as `make demo` does.

    Returns the clone and its facts: the commit, whether this checkout had uncommitted changes (left out of
    the clone), and the install's seconds (not part of the timing).
    """
    commit = _git("rev-parse", "HEAD")
    clone = folder / "intervalobs"
    repository = _git("rev-parse", "--path-format=absolute", "--git-common-dir")
    _git("clone", "--quiet", "--no-checkout", repository, str(clone))
    _git("checkout", "--quiet", "--detach", commit, cwd=clone)
    start = time.perf_counter()
    subprocess.run(["make", "-C", str(clone), ".venv/.installed"], capture_output=True, text=True, check=True)
    facts = {
        "commit": commit,
        "uncommitted_changes_left_out": bool(_git("status", "--porcelain", "--untracked-files=no")),
        "install_s_not_timed": time.perf_counter() - start,
    }
    return clone, facts


def wait_for_load(below: float | None, most: float) -> float:
    """Wait until the 1-minute load average is below ``below`` (at most ``most`` s); the seconds waited."""
    start = time.perf_counter()
    while below is not None and os.getloadavg()[0] >= below and time.perf_counter() - start < most:
        time.sleep(10.0)
    return time.perf_counter() - start


def timed(command: list[str], cwd: Path) -> tuple[str, float, float, float]:
    """Run ``command`` in ``cwd``: its output, wall seconds, CPU seconds (with its children), load before."""
    load = os.getloadavg()[0]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(command, cwd=cwd, env={**os.environ, **THREADS}, capture_output=True, text=True, check=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return done.stdout, wall, cpu, load


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path(__file__).with_name("demo_timing.json"))
    parser.add_argument("--full", action="store_true", help="time `reproduce all --full` instead")
    parser.add_argument("--here", action="store_true", help="this checkout's environment, no fresh clone")
    parser.add_argument(
        "--settle", type=float, default=60.0, help="seconds to wait after the install, so that its load decays (60)"
    )
    parser.add_argument("--quiet-below", type=float, help="then wait until the 1-minute load average is below this")
    parser.add_argument("--max-wait", type=float, default=1800.0, help="most seconds to wait for it (1800)")
    args = parser.parse_args()
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    clone: dict[str, object]
    with tempfile.TemporaryDirectory() as tmp:
        if args.here:
            program, clone, cwd = [sys.executable, "-m", "intervalobs.cli"], {"fresh_clone": False}, ROOT
        else:
            cwd, facts = fresh_clone(Path(tmp))
            time.sleep(args.settle)
            program, clone = [str(cwd / ".venv" / "bin" / "intervalobs")], {"fresh_clone": True, **facts}
        clone["waited_for_load_s"] = wait_for_load(args.quiet_below, args.max_wait)
        command = [
            *program,
            "reproduce",
            "all",
            "--out",
            str(Path(tmp) / "results"),
            *(["--full"] if args.full else []),
        ]
        stdout, wall, cpu, load_before = timed(command, cwd)
    examples = {
        m["name"]: {"enclosure": float(m["fraction"]), "seconds": float(m["seconds"])}
        for m in re.finditer(r"^(?P<name>\S+): enclosure (?P<fraction>\S+) .*, (?P<seconds>[\d.]+) s ->", stdout, re.M)
    }
    facts = {
        "command": "intervalobs reproduce all" + (" --full" if args.full else ""),
        **clone,
        "wall_s": wall,
        "cpu_s": cpu,
        "cores": cores,
        "load_average_before": load_before,
        "load_average_after": os.getloadavg()[0],
        "examples": examples,
        "all_enclosed": bool(examples) and all(e["enclosure"] == 1.0 for e in examples.values()),
    }
    args.out.write_text(json.dumps(facts, indent=2) + "\n")
    print(f"{facts['command']}: {wall:.1f} s wall, {cpu:.1f} s CPU on {cores} cores (load {load_before:.1f})")


if __name__ == "__main__":
    main()
