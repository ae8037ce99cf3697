import json
import subprocess
import sys

import pytest

from intervalobs.cli import main


def test_list_names_every_example(capsys):
    assert main(["list"]) == 0
    assert "spring-mass-lti" in capsys.readouterr().out


def test_bad_name_is_one_line_exit_2(capsys):
    assert main(["reproduce", "no-such-example"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: NAME: expected one of")


def test_bad_option_is_one_line_exit_2(capsys):
    assert main(["reproduce", "all", "--seed", "x"]) == 2
    assert capsys.readouterr().err.startswith("error:")


def test_version():
    out = subprocess.run([sys.executable, "-m", "intervalobs.cli", "--version"], capture_output=True, text=True)
    assert out.returncode == 0 and out.stdout.startswith("intervalobs ")


def test_reproduce_own_example_meets_the_contract(tmp_path):
    assert main(["reproduce", "spring-mass-lti", "--out", str(tmp_path), "--no-plots"]) == 0
    summary = json.loads((tmp_path / "spring-mass-lti" / "summary.json").read_text())
    assert summary["enclosure"]["state"] == {"fraction": 1.0, "max_violation": 0.0}
    checker = "/work/shared/tools/check_reproduction.py"
    import os

    if os.path.exists(checker):
        result = subprocess.run([sys.executable, checker, str(tmp_path / "spring-mass-lti")], capture_output=True)
        assert result.returncode == 0, result.stdout


@pytest.mark.slow
def test_reproduce_all(tmp_path):
    assert main(["reproduce", "all", "--out", str(tmp_path)]) == 0
