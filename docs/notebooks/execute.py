"""Execute every notebook of this folder in place, as Jupyter would, and store it with its outputs.

``make notebooks`` runs it after a notebook or the library changes; ``tests/test_notebooks.py`` checks that the
stored notebooks are executed and that running them afresh gives outputs of the same kinds.
"""

from __future__ import annotations

import sys
from pathlib import Path

import nbclient
import nbformat

HERE = Path(__file__).resolve().parent


def execute(path: Path) -> nbformat.NotebookNode:
    """Run ``path`` from top to bottom in a fresh kernel (working directory: this folder); return it executed."""
    notebook = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(
        notebook,
        timeout=600,
        kernel_name="python3",
        resources={"metadata": {"path": str(HERE)}},
        record_timing=False,
    )
    client.execute()  # raises CellExecutionError, with the cell and its traceback, when a cell fails
    return notebook


def main(paths: list[str]) -> None:
    """Execute and store the notebooks ``paths`` (default: every notebook of this folder)."""
    for path in [Path(p) for p in paths] or sorted(HERE.glob("*.ipynb")):
        notebook = execute(path)
        notebook.metadata.pop("widgets", None)
        for cell in notebook.cells:  # no execution timestamps: a re-run changes only what the code prints and draws
            cell.metadata.pop("execution", None)
        nbformat.write(notebook, path)
        print(f"executed {path.name}")


if __name__ == "__main__":
    main(sys.argv[1:])
