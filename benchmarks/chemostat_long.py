"""The chemostat of issue 32 over the full 60 h record (the reproduction runs 12 h to stay fast).

Runs ``intervalobs.reproduce.chemostat.run`` with ``t_final=60`` into ``results/chemostat-60h`` (or the
folder given as first argument) and prints the tightness and cost it reports (about a minute on one core).

Run with ``python benchmarks/chemostat_long.py [OUT_DIR]``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from intervalobs.reproduce.chemostat import run


def main() -> None:
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("results/chemostat-60h")
    summary = run(out, 0, False, t_final=60.0)
    print(json.dumps({"tightness": summary["tightness"], "runtime_s": summary["runtime_s"]}, indent=1, default=str))


if __name__ == "__main__":
    main()
