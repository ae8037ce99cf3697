"""`make demo` timing: `intervalobs reproduce all` (the default, without ``--full``) in a fresh process.

Times the command from outside (wall seconds, and the CPU seconds of it and its worker processes), reads
each example's seconds from its output, and notes the machine: usable cores and the load average before
and after (on a shared machine the wall time depends on the other load; the CPU time much less). Writes
benchmarks/demo_timing.json, the source of the README's timing statement.
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path(__file__).with_name("demo_timing.json"))
    parser.add_argument("--full", action="store_true", help="time `reproduce all --full` instead")
    args = parser.parse_args()
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    load_before = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as results:
        command = [sys.executable, "-m", "intervalobs.cli", "reproduce", "all", "--out", results]
        command += ["--full"] if args.full else []
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        done = subprocess.run(command, capture_output=True, text=True, check=True)
        wall = time.perf_counter() - start
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    examples = {
        m["name"]: {"enclosure": float(m["fraction"]), "seconds": float(m["seconds"])}
        for m in re.finditer(
            r"^(?P<name>\S+): enclosure (?P<fraction>\S+) .*, (?P<seconds>[\d.]+) s ->", done.stdout, re.M
        )
    }
    facts = {
        "command": "intervalobs reproduce all" + (" --full" if args.full else ""),
        "wall_s": wall,
        "cpu_s": cpu,
        "cores": cores,
        "load_average_before": load_before,
        "load_average_after": os.getloadavg()[0],
        "examples": examples,
        "all_enclosed": all(e["enclosure"] == 1.0 for e in examples.values()),
    }
    args.out.write_text(json.dumps(facts, indent=2) + "\n")
    print(f"{facts['command']}: {wall:.1f} s wall, {cpu:.1f} s CPU on {cores} cores (load {load_before:.1f})")


if __name__ == "__main__":
    main()
