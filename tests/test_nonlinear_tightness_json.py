"""benchmarks/nonlinear_tightness.json: every case's ratios to the consistent-set inner hull (issue 32).

Reads the committed results (the benchmark is not run here): the reference is a lower bound of the consistent set's
hull, so a sound estimator's width is at least its own (ratio >= 1), and every estimator encloses the truth.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

RESULTS = Path(__file__).resolve().parents[1] / "benchmarks" / "nonlinear_tightness.json"
CASES = ("chemostat", "cstr", "pendulum", "compartments")
ESTIMATORS = ("zonotope", "bundle", "smoother")


def _cases() -> dict:
    return json.loads(RESULTS.read_text())["cases"]


def test_every_case_reports_every_estimator() -> None:
    cases = _cases()
    assert set(CASES) <= set(cases)
    for name in CASES:
        assert set(ESTIMATORS) <= set(cases[name]["estimators"]), name


@pytest.mark.parametrize("name", CASES)
def test_ratios_are_at_least_one_and_the_truth_is_enclosed(name: str) -> None:
    case = _cases()[name]
    reference = case["reference"]["mean_width_second_half"]
    assert all(width > 0.0 for width in reference), reference
    for estimator, entry in case["estimators"].items():
        assert entry["enclosure"] == 1.0, (name, estimator)
        assert len(entry["ratio"]) == len(reference), (name, estimator)
        assert all(ratio >= 1.0 for ratio in entry["ratio"]), (name, estimator, entry["ratio"])
        for width, inner, ratio in zip(entry["mean_width_second_half"], reference, entry["ratio"], strict=True):
            assert ratio == pytest.approx(width / inner, rel=1e-12), (name, estimator)
