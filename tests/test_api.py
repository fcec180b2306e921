"""The public surface: private names stay in their modules; exceptions and tolerances are listed.

Rule checked on the package, the tests, the benchmarks and the notebooks: a name
that starts with one underscore (a function, class, method, attribute or
constant) is used only in the file that defines it. Private *modules*
(``setobs._blas``, ``setobs.lp._simplex``, ...) are package-internal; the
names they export carry no underscore.
"""

from __future__ import annotations

import ast
import inspect
import json
import re
import sys
from pathlib import Path

import numpy as np
import pytest

import setobs as so
from setobs import exceptions, tolerances

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "setobs"


def _is_private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def _sources() -> list[tuple[Path, str]]:
    out = [(p, p.read_text()) for d in ("src", "tests", "benchmarks")
           for p in sorted((ROOT / d).rglob("*.py"))]
    for p in sorted((ROOT / "notebooks").glob("*.ipynb")):
        cells = json.loads(p.read_text())["cells"]
        code = "\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "code")
        out.append((p, "\n".join(line for line in code.splitlines()
                                  if not line.lstrip().startswith(("%", "!")))))
    return out


def _defined(tree: ast.AST) -> set[str]:
    """Names a file defines (or mentions as a string, e.g. in ``__slots__``/setattr)."""
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            names.add(node.name)
        elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            names.add(node.id)
        elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
            names.add(node.attr)
        elif isinstance(node, ast.arg):
            names.add(node.arg)
        elif isinstance(node, ast.Import | ast.ImportFrom):
            names.update((a.asname or a.name).split(".")[0] for a in node.names)
    return names


def _string_attrs(tree: ast.AST) -> set[str]:
    return {node.value for node in ast.walk(tree)
            if isinstance(node, ast.Constant) and isinstance(node.value, str)
            and node.value.isidentifier()}


def private_name_uses() -> list[str]:
    # private modules: Python files, packages, and compiled extensions (their C source)
    private_modules = {p.name.split(".")[0] for p in SRC.rglob("_*")}
    bad = []
    for path, text in _sources():
        tree = ast.parse(text)
        own = _defined(tree)
        strings = _string_attrs(tree)
        rel = path.relative_to(ROOT)
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                bad += [f"{rel}:{node.lineno}: imports {a.name}" for a in node.names
                        if _is_private(a.name) and a.name not in private_modules]
            elif isinstance(node, ast.Attribute) and _is_private(node.attr):
                base = node.value
                if isinstance(base, ast.Name) and base.id in ("self", "cls"):
                    continue
                if node.attr in private_modules or node.attr in own or node.attr in strings:
                    continue
                bad.append(f"{rel}:{node.lineno}: uses .{node.attr}")
            elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                  and node.func.attr in ("setattr", "getattr") and len(node.args) >= 2
                  and isinstance(node.args[1], ast.Constant)
                  and isinstance(node.args[1].value, str) and _is_private(node.args[1].value)):
                bad.append(f"{rel}:{node.lineno}: patches {node.args[1].value}")
    return bad


def test_no_private_name_leaves_its_module():
    assert private_name_uses() == []


def test_checker_catches_a_private_use(tmp_path, monkeypatch):
    # the rule would be worthless if the checker could not see a violation
    bad = tmp_path / "tests" / "x.py"
    bad.parent.mkdir()
    bad.write_text("import setobs\nsetobs.geometry.zonotope.ConstrainedZonotope._trusted\n"
                   "mp.setattr(obj, '_solve', f)\n")
    me = sys.modules[__name__]
    monkeypatch.setattr(me, "ROOT", tmp_path)
    monkeypatch.setattr(me, "SRC", tmp_path / "src")
    found = private_name_uses()
    assert any("._trusted" in f for f in found) and any("patches _solve" in f for f in found)


def test_every_exception_lives_in_exceptions_and_is_exported():
    defined = []
    for path in SRC.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ClassDef) and node.name.endswith(("Error", "Warning")):
                defined.append((path.relative_to(SRC).as_posix(), node.name))
    # CLIError is the command line's own exit-code signal, never seen by library users
    outside = [d for d in defined if d[0] != "exceptions.py" and d[1] != "CLIError"]
    assert outside == []
    names = {n for _, n in defined if n != "CLIError"}
    assert names == set(exceptions.__all__)
    assert names <= set(so.__all__)
    for n in names:
        assert issubclass(getattr(so, n), Exception)


def test_every_tolerance_is_in_tolerances_all():
    consts = {n for n, v in vars(tolerances).items()
              if n.isupper() and isinstance(v, float)}
    assert consts == set(tolerances.__all__)
    # and no module outside tolerances.py defines a module-level *_TOL / *_RTOL constant
    for path in SRC.rglob("*.py"):
        if path.name == "tolerances.py":
            continue
        for node in ast.parse(path.read_text()).body:
            if isinstance(node, ast.Assign | ast.AnnAssign):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                for t in targets:
                    if isinstance(t, ast.Name):
                        assert not t.id.lstrip("_").endswith(("_TOL", "RTOL", "ATOL")), (
                            f"{path.name}: {t.id} belongs in setobs.tolerances")


@pytest.mark.parametrize("module", ["setobs", "setobs.geometry", "setobs.analysis",
                                    "setobs.setmembership", "setobs.observers", "setobs.studies"])
def test_all_names_exist(module):
    mod = __import__(module, fromlist=["_"])
    for name in mod.__all__:
        assert hasattr(mod, name), f"{module}.__all__ lists {name}, which does not exist"
        obj = getattr(mod, name)
        if inspect.isfunction(obj) or inspect.isclass(obj):
            assert not _is_private(obj.__name__)


BASE_LAYER = ("exceptions", "tolerances", "_rounding", "_validation", "_format", "_blas",
              "_lazy", "_deprecation", "_riccati")


def test_the_base_layer_imports_nothing_above_it():
    """The package's base modules import only each other (also under TYPE_CHECKING):
    exceptions.py once imported the existence report from analysis/, the one
    import that ran upward and tied the base files into a circle with it."""
    bad = []
    for name in BASE_LAYER:
        path = ROOT / "src" / "setobs" / f"{name}.py"
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level:
                target = (node.module or "").split(".")[0]
                if node.level > 1 or target not in BASE_LAYER:
                    bad.append(f"{name}.py:{node.lineno}: from {'.' * node.level}{node.module}")
            elif isinstance(node, ast.Import):
                bad += [f"{name}.py:{node.lineno}: import {a.name}" for a in node.names
                        if a.name.split(".")[0] == "setobs"]
    assert bad == []


#: What each package may import (besides the base layer and itself): arrows point down.
ALLOWED_ABOVE_BASE = {
    "lp": set(),
    "geometry": {"lp"},
    "models": set(),
    "setmembership": {"lp", "geometry", "analysis", "models", "results", "plotting"},
}


def upward_imports(root: Path) -> list[str]:
    """Relative imports (at any depth, also inside functions) from a package in
    :data:`ALLOWED_ABOVE_BASE` to a module it may not import."""
    bad = []
    for pkg, allowed in ALLOWED_ABOVE_BASE.items():
        for path in sorted((root / pkg).rglob("*.py")):
            # the package the file is in (a subpackage's file: deeper), for the level of a
            # relative import
            here = list(path.relative_to(root).parts[:-1])
            for node in ast.walk(ast.parse(path.read_text())):
                targets = []
                if isinstance(node, ast.ImportFrom) and node.level >= 1:
                    base = here[:len(here) - (node.level - 1)] if node.level - 1 <= len(here) \
                        else []
                    mod = [p for p in (node.module or "").split(".") if p]
                    full = base + mod
                    targets = [full[0]] if full else [a.name for a in node.names]
                elif isinstance(node, ast.ImportFrom) and node.level == 0 and (
                        node.module or "").startswith("setobs."):
                    targets = [node.module.split(".")[1]]
                elif isinstance(node, ast.Import):
                    targets = [a.name.split(".")[1] for a in node.names
                               if a.name.startswith("setobs.")]
                if isinstance(node, ast.Call) and getattr(node.func, "id", "") == "lazy_module" \
                        and node.args and isinstance(node.args[0], ast.Constant) \
                        and str(node.args[0].value).startswith("setobs."):
                    targets = [str(node.args[0].value).split(".")[1]]
                for t in targets:
                    if t != pkg and t not in BASE_LAYER and t not in allowed:
                        bad.append(f"{path.relative_to(root)}:{node.lineno}: imports {t}")
    return bad


def test_no_arrow_points_up():
    """``setobs.lp`` imports nothing above the base layer; ``geometry`` only ``lp``;
    ``setmembership`` neither observers, studies, compare nor the CLI."""
    assert upward_imports(SRC) == []


def test_the_import_checker_sees_an_arrow_up(tmp_path):
    (tmp_path / "lp").mkdir()
    (tmp_path / "lp" / "x.py").write_text("def f():\n    from ..geometry import Box\n")
    (tmp_path / "geometry").mkdir()
    (tmp_path / "geometry" / "y.py").write_text(
        "from .._lazy import lazy_module\nm = lazy_module('setobs.setmembership.smfdo')\n")
    (tmp_path / "setmembership").mkdir()
    assert upward_imports(tmp_path) == ["lp/x.py:2: imports geometry",
                                        "geometry/y.py:2: imports setmembership"]


def unasserted_tests(root: Path) -> list[str]:
    """Test functions under ``root`` with no ``assert``, no ``pytest.raises`` /
    ``pytest.warns`` / ``pytest.fail`` and no call of an ``assert*`` or ``check*``
    helper: tests that cannot fail."""
    bad = []
    for f in sorted(root.rglob("test_*.py")):
        for node in ast.walk(ast.parse(f.read_text())):
            if not (isinstance(node, ast.FunctionDef) and node.name.startswith("test")):
                continue
            found = False
            for a in ast.walk(node):
                if isinstance(a, ast.Assert):
                    found = True
                elif isinstance(a, ast.Call):
                    fn = a.func
                    name = fn.attr if isinstance(fn, ast.Attribute) else getattr(fn, "id", "")
                    found = name in ("raises", "warns", "fail") or name.startswith(
                        ("assert", "check", "_check"))
                if found:
                    break
            if not found:
                bad.append(f"{f.relative_to(root)}::{node.name}")
    return bad


def test_every_test_can_fail(tmp_path):
    """No test without an assertion (checked on the AST of every test module);
    the checker sees one when there is one."""
    assert unasserted_tests(ROOT / "tests") == []
    (tmp_path / "test_x.py").write_text("def test_nothing():\n    x = 1 + 1\n")
    assert unasserted_tests(tmp_path) == ["test_x.py::test_nothing"]


def test_no_issue_numbers_in_the_repository():
    """Code, tests, docs, notebooks and benchmarks say the behaviour or the finding, not
    the number of the internal ticket that asked for it (a reader has no tracker)."""
    word = "iss" + "ue"
    pattern = re.compile(rf"\b{word}s? ?#?\d+|\b{word}-\d+|\(#\d+\)", re.IGNORECASE)
    roots = [ROOT / d for d in ("src", "tests", "docs", "notebooks", "benchmarks")]
    files = [ROOT / "README.md", ROOT / "pyproject.toml"]
    for r in roots:
        files += [p for p in r.rglob("*") if p.is_file() and p.suffix in (
            ".py", ".md", ".rst", ".ipynb", ".json", ".c", ".toml", ".yaml", ".txt", ".sh")
            and "_build" not in p.parts and "generated" not in p.parts
            and p.parent != ROOT / "docs" / "notebooks"]   # (the docs build's copies)
    found = []
    for p in files:
        for i, line in enumerate(p.read_text(errors="replace").splitlines(), 1):
            if pattern.search(line):
                found.append(f"{p.relative_to(ROOT)}:{i}: {line.strip()[:80]}")
    assert not found, "\n".join(found)


def test_every_raise_in_the_library_is_a_setobs_error():
    """No ``raise ValueError(...)`` (or any other built-in exception) in ``src/``: every
    error a user can catch is a :class:`SetobsError` (its subclasses also derive from the
    built-in with the same meaning, so ``except ValueError`` keeps working)."""
    import builtins

    bad = []
    for path in SRC.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, ast.Raise) or node.exc is None:
                continue
            exc = node.exc.func if isinstance(node.exc, ast.Call) else node.exc
            name = exc.id if isinstance(exc, ast.Name) else None
            obj = getattr(builtins, name, None) if name else None
            if isinstance(obj, type) and issubclass(obj, BaseException):
                bad.append(f"{path.relative_to(SRC)}:{node.lineno}: raise {name}")
    assert bad == [], bad
    for name in exceptions.__all__:
        cls = getattr(exceptions, name)
        if issubclass(cls, Exception) and not issubclass(cls, Warning):
            assert issubclass(cls, exceptions.SetobsError), name
    from setobs.cli import CLIError

    assert issubclass(CLIError, exceptions.SetobsError)


#: Words a shape error's message uses (sizes, dimensions, indices of coordinates).
SHAPE_WORDS = re.compile(
    r"shape|rows|columns|length|dimension|components|entries|square|2-D|vector|per row|"
    r"must have|at least one (row|state|point)|0 x 0|dims|differ|out of range|"
    r"indices in|component must be in")


def dimension_errors_about_values(root: Path) -> list[str]:
    """``raise DimensionError(...)`` whose message (its string parts) says nothing
    about a shape: such an error is a value error or an argument error."""
    bad = []
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if not (isinstance(node, ast.Raise) and isinstance(node.exc, ast.Call)
                    and getattr(node.exc.func, "id", "") == "DimensionError"):
                continue
            text = " ".join(c.value for c in ast.walk(node.exc)
                            if isinstance(c, ast.Constant) and isinstance(c.value, str))
            if not SHAPE_WORDS.search(text):
                bad.append(f"{path.relative_to(root)}:{node.lineno}: {text[:60]}")
    return bad


def test_dimension_error_is_only_for_shapes(tmp_path):
    """``DimensionError`` for shapes only; a value out of range is an
    ``InvalidValueError``, a wrong kind of argument an ``ArgumentError``."""
    assert dimension_errors_about_values(SRC) == []
    (tmp_path / "x.py").write_text(
        "def f(x):\n    raise DimensionError(f'x must be positive, got {x}')\n")
    assert dimension_errors_about_values(tmp_path) == ["x.py:2: x must be positive, got "]


def code_lines(text: str, node: ast.ClassDef | ast.FunctionDef) -> int:
    """The lines of ``node`` that hold code: docstrings, comments and blank lines do not
    count (a class may grow its documentation, not its logic)."""
    docs: set[int] = set()
    for inner in ast.walk(node):
        body = getattr(inner, "body", None)
        if (isinstance(inner, ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef) and body
                and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant)
                and isinstance(body[0].value.value, str)):
            docs.update(range(body[0].lineno, body[0].end_lineno + 1))
    lines = text.splitlines()
    return sum(1 for i in range(node.lineno, node.end_lineno + 1)
               if i not in docs and lines[i - 1].strip()
               and not lines[i - 1].lstrip().startswith("#"))


def test_code_lines_skip_docstrings_comments_and_blanks():
    text = ('class K:\n    """Doc.\n\n    More.\n    """\n\n    # note\n    def f(self):\n'
            '        """One."""\n        return 1\n')
    node = ast.parse(text).body[0]
    assert code_lines(text, node) == 3  # class K:, def f, return 1


def test_setmembership_is_composed_not_inherited():
    """No class in ``setmembership/`` has more than one base, and :class:`setobs.SMFDO`
    (the loop over its engines, the public interface) stays under 250 lines of code
    (docstrings and comments not counted)."""
    bad, smfdo_lines = [], None
    for path in sorted((SRC / "setmembership").rglob("*.py")):
        text = path.read_text()
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.ClassDef):
                if len(node.bases) > 1:
                    bad.append(f"{path.name}: {node.name}")
                if node.name == "SMFDO":
                    smfdo_lines = code_lines(text, node)
    assert bad == []
    assert smfdo_lines is not None and smfdo_lines < 250


def test_the_smfdo_model_is_frozen_and_steps_leave_it_alone():
    """A run changes the state, never the model: every attribute of the model is the
    same object before and after, and assigning one raises."""
    from setobs.exceptions import ImmutableError

    sys_ = so.examples.chang2006()
    obs = so.SMFDO(sys_, window=5, measurement_noise=0.05, state_bounds=True)
    before = dict(vars(obs.model))
    rng = np.random.default_rng(3)
    x = np.zeros(sys_.n)
    Y = []
    for k in range(30):
        Y.append(sys_.Xi @ x + rng.uniform(-0.05, 0.05, sys_.l))
        x = sys_.Phi @ x + sys_.G @ np.array([np.sin(0.2 * k)] * sys_.q)
    obs.run(np.array(Y))
    assert obs.k == 29 and obs.stats["fast"] + obs.stats["reference"] == 30
    after = vars(obs.model)
    assert after.keys() == before.keys()
    assert all(after[key] is before[key] for key in before)
    with pytest.raises(ImmutableError):
        obs.model.window = 3
    with pytest.raises(AttributeError):
        obs.window = 3  # (read-only on the observer too)
