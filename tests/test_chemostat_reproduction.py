"""The chemostat reproduction: contract files, enclosure and the tightness numbers it reports."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from intervalobs.front_door import ESTIMATORS
from intervalobs.reproduce import registry
from intervalobs.reproduce.contract import check_reproduction


@pytest.mark.slow
def test_chemostat_reproduction(tmp_path) -> None:
    summary = registry()["chemostat"].run(tmp_path / "chemostat", 0, True)
    assert check_reproduction(tmp_path / "chemostat") == []
    assert summary["enclosure"]["state"]["fraction"] == 1.0
    tight, design = summary["tightness"], summary["design"]
    assert tight["biomass_ratio"] >= 1.0  # the reference is a lower bound of the consistent set
    assert design["biomass_mean_width_second_half"] < 0.5  # 12 h record: the prior (width 2) forgotten at rate D
    assert design["direct"]["diverging"] is True
    free = design["kinetics_free_biomass_mean_width_second_half"]
    assert tight["biomass_consistent_inner_width_second_half"] <= free
    assert design["kinetics_free_biomass_noise_floor"] <= free < 0.5
    assert np.isfinite(summary["runtime_s"]["ms_per_sample"])
    bundle = design["bundle"]
    assert bundle["enclosure"] == 1.0
    assert tight["bundle_biomass_ratio"] >= 1.0
    assert bundle["biomass_mean_width_second_half"] < design["biomass_mean_width_second_half"]
    smoother = design["smoother"]
    assert smoother["enclosure"] == 1.0
    assert 1.0 <= tight["smoother_biomass_ratio"] < tight["bundle_biomass_ratio"]


@pytest.mark.slow
def test_chemostat_default_run_leaves_the_reference_out(tmp_path) -> None:
    summary = registry()["chemostat"].run(tmp_path / "chemostat", 0, False, full=False)
    assert check_reproduction(tmp_path / "chemostat") == []
    assert "tightness" not in summary and summary["enclosure"]["state"]["fraction"] == 1.0


def test_design_notes_quote_the_long_benchmark() -> None:
    """The bundle paragraph of docs/design.md quotes benchmarks/chemostat_long.json (widths and ratios; the
    CPU times vary from run to run and are read from the file)."""
    root = Path(__file__).resolve().parents[1]
    report = json.loads((root / "benchmarks" / "chemostat_long.json").read_text())
    design, tight = report["design"], report["tightness"]
    notes = (root / "docs" / "design.md").read_text()
    sweep = {entry["parts"]: entry for entry in design["bundle_sweep"]}

    def ratio(entry: dict[str, float]) -> float:
        return entry["biomass_mean_width_second_half"] / tight["biomass_consistent_inner_width_second_half"]

    quoted = [
        f"{tight['biomass_consistent_inner_width_second_half']:.2e}".replace("e-0", "e-"),
        f"{design['biomass_mean_width_second_half']:.3g} g/L, ratio {tight['biomass_ratio']:.0f}",
        f"256 parts {design['bundle']['biomass_mean_width_second_half']:.3g} g/L "
        f"({tight['bundle_biomass_ratio']:.0f}×)",
        *(f"{parts} parts {ratio(sweep[parts]):.3g}×" for parts in (64, 128, 1024, 4096)),
        f"smoother {design['smoother']['biomass_mean_width_second_half']:.3g} g/L "
        f"({tight['smoother_biomass_ratio']:.3g}×)",
    ]
    missing = [text for text in quoted if text not in notes]
    assert missing == []
    smoother_row = next(row for row in ESTIMATORS if row.name == "SetInversionSmoother")
    assert f"{tight['smoother_biomass_ratio']:.3g}x the consistent set" in smoother_row.width
