"""Every notebook executes top to bottom in a real Jupyter kernel (nbclient), small parameters."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests.datasets import HSM150

NOTEBOOK_DIR = Path(__file__).parents[1] / "notebooks"
NOTEBOOKS = sorted(NOTEBOOK_DIR.glob("*.ipynb"))


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_runs(path):
    if path.name.startswith(("07", "09")) and HSM150 is None:
        # the real record stays outside the repository; CI has it and says so
        if os.environ.get("SETOBS_REQUIRE_DATA") == "1":
            pytest.fail("SETOBS_REQUIRE_DATA=1 but the HSM150 record was not found "
                        "($SETOBS_DATA, <repo>/../shared/data)")
        pytest.skip("the HSM150 record is not available here")
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    nb = nbformat.read(path, as_version=4)
    # Outputs are cleared in the repository (checked here), then executed in a kernel.
    assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code")
    client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": str(NOTEBOOK_DIR)}})
    client.execute()
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])
              if o.get("output_type") == "error"]
    assert not errors


def test_there_are_nine_notebooks():
    assert [p.stem[:2] for p in NOTEBOOKS] == ["01", "02", "03", "04", "05", "06", "07", "08",
                                               "09"]
