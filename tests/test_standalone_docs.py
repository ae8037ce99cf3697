"""The documentation stands alone: no path to files outside the repository in README, docs or the package."""

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", ROOT / "CHANGELOG.md", ROOT / "pyproject.toml", *sorted((ROOT / "docs").glob("*.md"))]
SOURCES = sorted((ROOT / "src").rglob("*.py")) + sorted((ROOT / "docs" / "notebooks").glob("*.ipynb"))


@pytest.mark.parametrize("path", PAGES + SOURCES, ids=lambda p: str(p.relative_to(ROOT)))
def test_no_path_outside_the_repository(path):
    for number, line in enumerate(path.read_text().splitlines(), start=1):
        assert "shared/" not in line, f"{path.relative_to(ROOT)}:{number} points outside the repository: {line.strip()}"
