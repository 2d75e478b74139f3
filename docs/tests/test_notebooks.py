"""The shipped notebooks run from top to bottom (nbclient), in a scratch copy
of examples/ so that their results land outside the repository."""

from __future__ import annotations

import shutil
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient

REPO = Path(__file__).resolve().parents[2]
NOTEBOOKS = sorted((REPO / "examples").glob("*.ipynb"))


def test_there_are_notebooks() -> None:
    """The notebooks checked below are the shipped ones."""
    assert NOTEBOOKS


@pytest.mark.parametrize("notebook", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_runs(notebook: Path, tmp_path: Path) -> None:
    """Every cell of the notebook runs without an error."""
    work = tmp_path / "examples"
    shutil.copytree(REPO / "examples", work, ignore=shutil.ignore_patterns("ribbar-work"))
    nb = nbformat.read(work / notebook.name, as_version=4)
    NotebookClient(nb, timeout=900, kernel_name="python3", resources={"metadata": {"path": str(work)}}).execute()
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", []) if o.output_type == "error"]
    assert not errors, errors
