"""The maps stay true: every module has a line in ``docs/develop.md``, every test module a
row in ``tests/README.md``, and neither names a file that does not exist.

Each checker is also shown a map that misses a file and one that names a stale file.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "setobs"
TESTS = ROOT / "tests"


def library_modules(src: Path) -> set[str]:
    """Every module file of the package (``.py`` and compiled ``.c`` sources), relative to
    the package, packages' ``__init__.py`` excepted (a package is its paragraph)."""
    return {p.relative_to(src).as_posix() for pattern in ("*.py", "*.c")
            for p in src.rglob(pattern) if p.name != "__init__.py"}


def develop_map(text: str) -> set[str]:
    """The modules that ``docs/develop.md``'s "One line per module" section names.

    A paragraph headed ``Name (`pkg/`)`` holds ``pkg``'s modules; a heading without a
    package holds the top-level ones. Every backticked ``x.py`` or ``x.c`` counts.
    """
    section = text.split("## One line per module", 1)[1].split("\n## ", 1)[0]
    package, named = "", set()
    for line in section.splitlines():
        if line and not line.startswith((" ", "-")):
            found = re.search(r"\(`([\w/]+)/`\)", line)
            package = found.group(1) + "/" if found else ""
            continue
        named.update(package + name for name in re.findall(r"`([\w.]+\.(?:py|c))`", line))
    return named


def map_gaps(library: set[str], named: set[str]) -> tuple[list[str], list[str]]:
    """(modules the map misses, names in the map that are no module)."""
    return sorted(library - named), sorted(named - library)


def readme_rows(text: str) -> set[str]:
    """The test modules that ``tests/README.md``'s table names (its first column)."""
    return set(re.findall(r"^\| `([\w/]+\.py)` \|", text, flags=re.MULTILINE))


def collect_test_files(tests: Path) -> set[str]:
    return {p.relative_to(tests).as_posix() for p in tests.rglob("test_*.py")}


def test_every_module_has_a_line_in_the_developer_map():
    missing, stale = map_gaps(library_modules(SRC),
                                   develop_map((ROOT / "docs" / "develop.md").read_text()))
    assert missing == [], f"modules without a line in docs/develop.md: {missing}"
    assert stale == [], f"docs/develop.md names files that do not exist: {stale}"


def test_every_test_module_has_a_row_in_the_tests_readme():
    rows = readme_rows((TESTS / "README.md").read_text())
    files = collect_test_files(TESTS)
    assert sorted(files - rows) == [], "test modules without a row in tests/README.md"
    assert sorted(rows - files) == [], "tests/README.md rows for files that do not exist"


def test_the_map_checkers_see_a_missing_and_a_stale_file(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    for name in ("__init__.py", "a.py", "sub/__init__.py", "sub/b.py", "sub/_k.c"):
        (pkg / name).write_text("")
    text = ("# map\n\n## One line per module\n\nBase\n\n- `a.py`: one.\n\n"
            "Sub (`sub/`)\n\n- `b.py` and `gone.py`: two.\n\n## Next\n\n- `c.py`\n")
    missing, stale = map_gaps(library_modules(pkg), develop_map(text))
    assert missing == ["sub/_k.c"]
    assert stale == ["sub/gone.py"]
    (tmp_path / "t").mkdir()
    (tmp_path / "t" / "test_one.py").write_text("")
    (tmp_path / "t" / "test_two.py").write_text("")
    rows = readme_rows("| module | kind |\n|---|---|\n| `t/test_one.py` | x |\n")
    assert collect_test_files(tmp_path) - rows == {"t/test_two.py"}
