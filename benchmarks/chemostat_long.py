"""The chemostat of issue 32 over the full 60 h record (the reproduction runs 12 h to stay fast).

Runs ``intervalobs.reproduce.chemostat.run`` with ``t_final=60`` into ``results/chemostat-60h`` (or the
folder given as first argument) and writes the tightness and cost it reports to
``benchmarks/chemostat_long.json`` (about four minutes on one core, most of it the 4096-part bundle), with the bundle at
``SWEEP`` sizes.

Run with ``python benchmarks/chemostat_long.py [OUT_DIR]``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from intervalobs.reproduce.chemostat import run
from intervalobs.reproduce.contract import to_json

SWEEP = (0, 64, 128, 1024, 4096)
"""Bundle sizes run besides the reproduction's (0: one zonotope), for the width against the number of parts."""


def main() -> None:
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("results/chemostat-60h")
    summary = run(out, 0, False, t_final=60.0, sweep=SWEEP)
    report = {"tightness": summary["tightness"], "design": summary["design"], "runtime_s": summary["runtime_s"]}
    text = json.dumps(to_json(report), indent=1)
    (Path(__file__).parent / "chemostat_long.json").write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
