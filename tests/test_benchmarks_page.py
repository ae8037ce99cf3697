"""docs/benchmarks.md is committed: it must be what benchmarks/report.py makes of the JSON results."""

from __future__ import annotations

import runpy
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_benchmarks_page_matches_the_results() -> None:
    report = runpy.run_path(str(ROOT / "benchmarks" / "report.py"))
    page = (ROOT / "docs" / "benchmarks.md").read_text()
    assert page == report["render"](), "docs/benchmarks.md is stale: run `python benchmarks/report.py`"
    # The required rows: plain interval observer, zonotopic, best intersection, and their ratios.
    for row in ("interval observer (framer", "zonotopic observer", "best intersection", "FIR bank learned"):
        assert row in page
