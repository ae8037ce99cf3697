"""The seed-003 reproduction: contract files, the paper's numbers next to ours, the sound variant enclosed."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from intervalobs.reproduce import registry
from intervalobs.reproduce.contract import check_reproduction


@pytest.mark.slow
def test_nonlinear_gsisio(tmp_path: Path) -> None:
    registry()["nonlinear-gsisio"].run(tmp_path / "nonlinear-gsisio", 0, False)
    assert check_reproduction(tmp_path / "nonlinear-gsisio") == []
    s = json.loads((tmp_path / "nonlinear-gsisio" / "summary.json").read_text())
    assert s["enclosure"] == {
        "state": {"fraction": 1.0, "max_violation": 0.0},
        "input": {"fraction": 1.0, "max_violation": 0.0},
    }
    d = s["design"]
    assert d["rank_condition_8"] == [2, 1] and d["paper_construction"].startswith("AssumptionError")
    assert d["stability_condition"] == "none holds"
    sv = d["sound_variant"]
    assert sv["enclosure_state_monte_carlo"]["max_violation"] == 0.0
    assert sv["enclosure_input_monte_carlo"]["max_violation"] == 0.0
    assert sv["monte_carlo_state_width_norm_max_after_10_steps"] < 4.0
    assert d["naive_paper_construction_with_pinv"]["steps_violated_or_undefined"] > 0
    full = d["fullrank_example"]
    assert full["width_state_below_delta_x"] and full["width_input_below_delta_d"]
    assert full["gsisio_design"]["stability_condition"] == "(i)"
    two = d["two_hidden_example"]
    assert two["jacobian_source"] == {"f": "automatic", "g": "automatic"} and two["hidden_directions"] == 2
    assert two["width_certificate"]["holds"]
    assert two["enclosure_state"]["fraction"] == 1.0 and two["enclosure_input"]["fraction"] == 1.0
    assert two["state_width_below_certified_sequence"] and two["input_width_below_certified_sequence"]
    assert two["state_width_below_steady_bound_after_30_steps"]
    assert not sv["width_certificate"]["holds"] and "rho(Gamma)" in sv["width_certificate"]["reason"]
    for example in ("paper_example", "two_hidden_example"):
        for part in ("state", "input"):
            ratio = s["tightness"][example][part]["ratio_norm"]
            assert 1.0 <= ratio < 2.0  # a lower bound (>= 1 by soundness) and the measured gap
    for example in ("paper_example", "two_hidden_example"):  # the targets are met against the data-only bound
        for part in ("state", "input"):
            tight = s["tightness"][example][part]
            assert tight["consistent_hull_inside_ours"] and tight["consistent_target_met_norm"]
            assert 1.0 <= tight["consistent_ratio_norm"] <= min(tight["ratio_norm"], tight["target_ratio"])
    z = np.load(tmp_path / "nonlinear-gsisio" / "trajectories.npz")
    assert np.all(z["d_lower"][0] == -np.inf) and np.all(np.isnan(z["delta_x"]))
    assert np.all(np.isfinite(z["fullrank_delta_x"]))
