"""The seed-002 reproductions: contract files, the paper's constants next to ours, failure modes shown."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from intervalobs.reproduce import registry
from intervalobs.reproduce.contract import check_reproduction


def _run(name: str, out: Path) -> dict:  # type: ignore[type-arg]
    summary = registry()[name].run(out / name, 0, False)
    assert check_reproduction(out / name) == []
    return json.loads((out / name / "summary.json").read_text()) | {"_returned": summary}


def test_numerical_3state(tmp_path: Path) -> None:
    s = _run("numerical-3state", tmp_path)
    assert s["enclosure"]["state"] == {"fraction": 1.0, "max_violation": 0.0}
    s68, s70 = s["design"]["system_68"], s["design"]["system_70"]
    np.testing.assert_allclose(s68["gains"]["(54)-(55)"]["gain"], [0.3, 0.2, 0.8], atol=1e-4)
    assert s68["gains"]["(54)-(55)"]["monotone"]
    for report in [*s68["enclosure_monte_carlo"].values(), *s70["enclosure_monte_carlo"].values()]:
        assert report == {"fraction": 1.0, "max_violation": 0.0}
    # the paper's claim on the monotone case: interval/integrated no wider than zonotopic
    assert s68["width_ratio_interval_over_zonotopic"]["mean"] <= 1.0
    assert all(o["certified"] for o in s68["observers"].values())
    assert s70["monotone_design"].startswith("AssumptionError")
    assert not s70["gains"]["(54) with full P (printed form)"]["monotone"]
    assert s["paper"]["system_70"]["set_based_(19)"]["spectral_radius"] == pytest.approx(2.0704, abs=1e-3)
    naive = s70["naive"]
    assert naive["naive_interval_printed_(54a)"]["max_violation"] > 0.1  # Fig. 4: enclosure lost
    assert naive["naive_zonotopic_printed_(19)"]["final_width_max"] > 1e10  # Fig. 3: diverges
    with np.load(tmp_path / "numerical-3state" / "trajectories.npz") as z:
        assert {"zonotopic_x_lower", "interval_x_upper", "integrated_x_lower", "sys70_x"} <= set(z.files)
        naive_keys = [k for k in z.files if k.startswith("sys70_naive")]
        assert len(naive_keys) == 4


def test_two_tank(tmp_path: Path) -> None:
    s = _run("two-tank", tmp_path)
    assert s["enclosure"]["state"] == {"fraction": 1.0, "max_violation": 0.0}
    design, paper = s["design"], s["paper"]["gains"]
    for report in design["enclosure_monte_carlo"].values():
        assert report == {"fraction": 1.0, "max_violation": 0.0}
    assert design["gains"]["(54)-(55)"]["monotone"]
    assert design["width_ratio_interval_over_zonotopic"]["mean"] <= 1.0
    assert paper["set_based_(19)"]["abs_spectral_radius"] == pytest.approx(1.000014, abs=2e-6)
    assert paper["interval_(54)-(55)"]["min_entry"] == pytest.approx(-0.001)
    assert design["naive"]["naive_interval_printed_(54a)"]["max_violation"] > 0.1  # Fig. 9


def test_without_the_comparisons_the_example_and_its_enclosure_check_stay(tmp_path: Path) -> None:
    """``full=False`` (what `intervalobs reproduce` runs by default): no tightness report, same contract."""
    summary = registry()["numerical-3state"].run(tmp_path / "quick", 0, False, full=False)
    assert check_reproduction(tmp_path / "quick") == []
    assert "tightness" not in summary and summary["enclosure"]["state"] == {"fraction": 1.0, "max_violation": 0.0}
    for report in summary["design"]["system_68"]["enclosure_monte_carlo"].values():
        assert report == {"fraction": 1.0, "max_violation": 0.0}
