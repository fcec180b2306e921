"""The repository's notebooks, each executed once per test session in a real Jupyter
kernel (nbclient): :mod:`tests.test_notebooks` checks each one, and the documentation
build (:mod:`tests.test_docs`) renders the same executed copies instead of executing
them again (``SETOBS_EXECUTED_NOTEBOOKS``, ``docs/conf.py``)."""

from __future__ import annotations

from pathlib import Path

import pytest

NOTEBOOK_DIR = Path(__file__).parents[1] / "notebooks"
NOTEBOOKS = sorted(NOTEBOOK_DIR.glob("*.ipynb"))


class ExecutedNotebooks:
    """Executes each notebook at most once and keeps the executed copy in ``out``."""

    def __init__(self, out: Path) -> None:
        self.out = out
        self._done: dict[str, object] = {}

    def run(self, path: Path):
        """The executed notebook (``nbformat`` node), written to ``out``; an execution
        error is raised again on every call."""
        if path.name not in self._done:
            nbformat = pytest.importorskip("nbformat")
            nbclient = pytest.importorskip("nbclient")
            nb = nbformat.read(path, as_version=4)
            # Outputs are cleared in the repository (checked by the caller on the source).
            client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                                             resources={"metadata": {"path": str(NOTEBOOK_DIR)}})
            try:
                client.execute()
            except Exception as exc:  # (kept: the docs build and the test both report it)
                self._done[path.name] = exc
            else:
                nbformat.write(nb, self.out / path.name)
                self._done[path.name] = nb
        got = self._done[path.name]
        if isinstance(got, Exception):
            raise got
        return got
