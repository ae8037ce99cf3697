"""docs/paper-notes.md quotes the reproductions' numbers: those that need no simulation, recomputed
fresh, must be what the page says (the slow reproduction tests check the others; see paper_notes.py)."""

from __future__ import annotations

import json
from typing import Any

import pytest

from intervalobs.examples import hgio as hgio_example
from intervalobs.reproduce import aircraft_uio, hgio_sampled, registry
from intervalobs.reproduce.contract import to_json
from paper_notes import QUOTES, Quote, misquoted, number, render


def _as_read(summary: dict[str, Any]) -> dict[str, Any]:
    """The summary as ``summary.json`` holds it (complex numbers as ``{"re", "im"}``, arrays as lists)."""
    return json.loads(json.dumps(to_json(summary)))


def test_numbers_are_written_as_on_the_page() -> None:
    assert number(-2.0108e-5, ".3e") == "−2.011e-5"
    assert number(2.1e-16, ".0e") == "2e-16"
    assert number(7.259, "+.3f") == "+7.259"
    summary = {"a": [1.0, -2.5], "b": {"c": [{"re": -1.0, "im": 2.0}, {"re": -1.0, "im": -2.0}]}}
    assert (
        render(Quote("x = ({a:.1f}); y {b:.2f| / }", {"a": "a", "b": "a"}), summary)
        == "x = (1.0, −2.5); y 1.00 / −2.50"
    )
    with pytest.raises(KeyError):
        render(Quote("{v}", {"v": "b.d"}), summary)


def test_seed000_design_numbers_match_a_fresh_design() -> None:
    observer = aircraft_uio._observer()
    summary = _as_read(
        {"design": aircraft_uio.design_facts(observer), "paper": {"checks": aircraft_uio._paper_checks(observer)}}
    )
    problems, checked = misquoted("aircraft-uio", summary, partial=True)
    assert problems == []
    assert checked == 16  # ρ_x, ρ_ξ and their paper formula, misprints, poles, residuals, …


def test_seed004_design_numbers_match_a_fresh_design() -> None:
    summary = _as_read({"design": hgio_sampled.paper_design_facts(*hgio_sampled.paper_designs())})
    printed = summary["design"]["theorem44_with_printed_L1_v1"]
    assert printed["alpha_paper_reading"] == pytest.approx(hgio_example.PAPER["alpha"], abs=2e-4)  # the printed v₁
    problems, checked = misquoted("hgio-sampled", summary, partial=True)
    assert problems == []
    assert checked == 9  # α, θ, (34) start time, (35) abscissa, |v₁dʳ|, printed eigenvalues, …


def test_every_quote_names_a_reproduction() -> None:
    assert set(QUOTES) <= set(registry())
