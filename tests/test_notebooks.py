"""The notebooks in docs/notebooks are stored executed (a reader sees their outputs on the web) and run from
top to bottom (executed with nbclient, as Jupyter would) to outputs of the same kinds."""

import runpy
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "docs" / "notebooks").glob("*.ipynb"))


def _kinds(notebook) -> list[list[str]]:
    """Per code cell, the kinds of its outputs (stream name, or the MIME types of a result or display)."""
    kinds = []
    for cell in notebook.cells:
        if cell.cell_type == "code":
            kinds.append(sorted({o.get("name") or ",".join(sorted(o.get("data", {}))) for o in cell.outputs}))
    return kinds


def test_the_notebooks_are_in_the_docs_and_stored_executed():
    nbformat = pytest.importorskip("nbformat")
    index = (ROOT / "docs" / "index.md").read_text()
    assert len(NOTEBOOKS) == 3
    for path in NOTEBOOKS:
        assert f"notebooks/{path.stem}" in index, f"{path.name} is not in the docs' table of contents"
        notebook = nbformat.read(path, as_version=4)
        nbformat.validate(notebook)
        code = [cell for cell in notebook.cells if cell.cell_type == "code"]
        counts = [cell.execution_count for cell in code]
        assert counts == list(range(1, len(code) + 1)), f"{path.name}: not executed top to bottom (`make notebooks`)"
        errors = [o for cell in code for o in cell.outputs if o.output_type == "error"]
        assert not errors, f"{path.name} is stored with an error: run `make notebooks`"
        figures = [o for cell in code for o in cell.outputs if "image/png" in o.get("data", {})]
        assert figures, f"{path.name} is stored without its figures: run `make notebooks`"


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_runs_to_the_stored_kinds_of_output(path):
    nbformat = pytest.importorskip("nbformat")
    pytest.importorskip("nbclient")
    execute = runpy.run_path(str(ROOT / "docs" / "notebooks" / "execute.py"))["execute"]
    stored = nbformat.read(path, as_version=4)
    assert _kinds(execute(path)) == _kinds(stored), f"{path.name}: stored outputs are stale (`make notebooks`)"
