"""The notebooks in docs/notebooks run from top to bottom (executed with nbclient, as Jupyter would)."""

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "docs" / "notebooks").glob("*.ipynb"))


def test_the_notebooks_are_in_the_docs_and_kept_without_outputs():
    nbformat = pytest.importorskip("nbformat")
    index = (ROOT / "docs" / "index.md").read_text()
    assert len(NOTEBOOKS) == 3
    for path in NOTEBOOKS:
        assert f"notebooks/{path.stem}" in index, f"{path.name} is not in the docs' table of contents"
        notebook = nbformat.read(path, as_version=4)
        nbformat.validate(notebook)
        stale = [
            cell.id for cell in notebook.cells if cell.cell_type == "code" and (cell.outputs or cell.execution_count)
        ]
        assert not stale, f"{path.name}: cells {stale} keep outputs (the docs and the tests compute them afresh)"


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_runs(path):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    notebook = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(
        notebook, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(path.parent)}}
    )
    client.execute()  # raises CellExecutionError, with the cell and its traceback, when a cell fails
    figures = [o for cell in notebook.cells for o in cell.get("outputs", []) if "image/png" in o.get("data", {})]
    assert figures, f"{path.name} draws no figure"
