"""Sphinx configuration of the setobs documentation.

Build (from the repository root): ``python -m sphinx -W -b html docs docs/_build/html``.
The performance page is generated from ``benchmarks/results/`` (``docs/performance_page.py``).
The notebooks of ``notebooks/`` are copied into ``docs/notebooks/`` and executed
during the build (myst-nb), so their figures are rendered. With the environment
variable ``SETOBS_EXECUTED_NOTEBOOKS`` naming a directory of the same notebooks
already executed (the test suite executes each once, ``tests/conftest.py``), those
are rendered as they are instead of being executed a second time.
"""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

import setobs

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

# The performance page, generated from the benchmarks' results files (docs/performance_page).
sys.path.insert(0, str(HERE))
import performance_page  # noqa: E402

(HERE / "performance.md").write_text(performance_page.render(ROOT / "benchmarks" / "results"))

# The notebooks live in notebooks/ (where the tests run them); the docs render copies.
_nb_dst = HERE / "notebooks"
_nb_dst.mkdir(exist_ok=True)
_executed = os.environ.get("SETOBS_EXECUTED_NOTEBOOKS")
for nb in sorted((ROOT / "notebooks").glob("*.ipynb")):
    src = Path(_executed) / nb.name if _executed else nb
    if not src.is_file():
        raise FileNotFoundError(f"SETOBS_EXECUTED_NOTEBOOKS has no executed {nb.name}")
    shutil.copy2(src, _nb_dst / nb.name)

project = "setobs"
author = "the setobs developers"
copyright = "2026, the setobs developers"
release = setobs.__version__
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_nb",
]
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
exclude_patterns = ["_build", "**.ipynb_checkpoints"]
autosummary_generate = True
autosummary_imported_members = True
autodoc_typehints = "none"  # numpydoc sections carry the types
numpydoc_show_class_members = False
numpydoc_xref_param_type = False
myst_enable_extensions = ["dollarmath"]
myst_heading_anchors = 3
nb_execution_mode = "off" if _executed else "force"
nb_execution_timeout = 600
nb_execution_raise_on_error = True
nb_execution_show_tb = True
html_theme = "pydata_sphinx_theme"
html_static_path = ["_static"]
html_css_files = ["wide.css"]
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
}
html_sidebars = {"**": ["sidebar-nav-bs"], "performance": [], "index": []}
suppress_warnings = ["myst.header"]
