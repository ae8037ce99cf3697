"""Execute the code blocks of docs/guide.md and README.md in order, as a user would."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("page", ["docs/guide.md", "README.md"])
def test_page_code_runs(page, capsys):
    text = (ROOT / page).read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert blocks, f"{page} has no python blocks"
    namespace: dict = {}
    for block in blocks:
        exec(compile(block, page, "exec"), namespace)
    assert "fraction=1.0" in capsys.readouterr().out or page != "README.md"
