"""Every notebook executes top to bottom in a real Jupyter kernel (nbclient), small parameters."""

from __future__ import annotations

import os

import pytest

from tests.datasets import HSM150
from tests.notebooks import NOTEBOOKS


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_runs(path, executed_notebooks):
    if path.name.startswith(("07", "09")) and HSM150 is None:
        # the real record stays outside the repository; CI has it and says so
        if os.environ.get("SETOBS_REQUIRE_DATA") == "1":
            pytest.fail("SETOBS_REQUIRE_DATA=1 but the HSM150 record was not found "
                        "($SETOBS_DATA, <repo>/../shared/data)")
        pytest.skip("the HSM150 record is not available here")
    nbformat = pytest.importorskip("nbformat")
    # Outputs are cleared in the repository (checked here), then executed in a kernel.
    src = nbformat.read(path, as_version=4)
    assert all(not c.get("outputs") for c in src.cells if c.cell_type == "code")
    nb = executed_notebooks.run(path)
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])
              if o.get("output_type") == "error"]
    assert not errors
    # (and the executed copy has outputs: it ran)
    assert any(c.get("outputs") for c in nb.cells if c.cell_type == "code")


def test_there_are_ten_notebooks():
    assert [p.stem[:2] for p in NOTEBOOKS] == ["01", "02", "03", "04", "05", "06", "07", "08",
                                               "09", "10"]
