"""Docstring completeness, in the style of python-control's ``docstrings_test.py``.

Every parameter of every public function, class and public method (the names
in the ``__all__`` of the public modules) must be documented in a numpydoc
``Parameters`` section (``Attributes`` for a dataclass's fields); a documented
parameter must exist.
"""

from __future__ import annotations

import importlib
import inspect
import re

PUBLIC_MODULES = [
    "setobs", "setobs.geometry", "setobs.geometry.zonotope", "setobs.geometry.box",
    "setobs.lp.factor", "setobs.geometry.polytope", "setobs.geometry.reduction",
    "setobs.lp", "setobs.lp.fastlp", "setobs.lp.certificate", "setobs.lp.highs",
    "setobs.lp.boxlp", "setobs.analysis",
    "setobs.setmembership", "setobs.setmembership.estimates", "setobs.observers",
    "setobs.studies", "setobs.compare", "setobs.plotting", "setobs.io", "setobs.systems",
    "setobs.examples", "setobs.results", "setobs.exceptions",
]

_SECTION = re.compile(r"\n\s*(Parameters|Other Parameters|Attributes)\n\s*-{3,}\n(.*?)"
                      r"(?=\n\s*[A-Z][A-Za-z ]+\n\s*-{3,}|\Z)", re.S)
_ENTRY = re.compile(r"^(\*{0,2}[A-Za-z_]\w*(?:\s*,\s*\*{0,2}[A-Za-z_]\w*)*)\s*(?::|$)")


def documented(doc: str) -> dict[str, set[str]]:
    """Names in the Parameters / Attributes sections of a numpydoc docstring."""
    out: dict[str, set[str]] = {"Parameters": set(), "Attributes": set()}
    for kind, body in _SECTION.findall(doc):
        key = "Attributes" if kind == "Attributes" else "Parameters"
        indent = None
        for line in body.split("\n"):
            if not line.strip():
                continue
            lead = len(line) - len(line.lstrip())
            indent = lead if indent is None else min(indent, lead)
            if lead != indent:
                continue
            m = _ENTRY.match(line.strip())
            if m:
                out[key].update(n.strip().lstrip("*") for n in m.group(1).split(","))
    return out


def _callables():
    seen = set()
    for modname in PUBLIC_MODULES:
        mod = importlib.import_module(modname)
        for name in getattr(mod, "__all__", []):
            obj = getattr(mod, name)
            if id(obj) in seen or inspect.ismodule(obj):
                continue
            seen.add(id(obj))
            if inspect.isfunction(obj):
                yield f"{obj.__module__}.{name}", obj, False
            elif inspect.isclass(obj):
                if not issubclass(obj, BaseException):
                    yield f"{obj.__module__}.{name}", obj, True
                for attr, val in vars(obj).items():
                    func = val.__func__ if isinstance(val, classmethod | staticmethod) else val
                    if not attr.startswith("_") and inspect.isfunction(func):
                        yield f"{obj.__module__}.{name}.{attr}", func, False


_DELEGATE = re.compile(r"see\s+:func:`(setobs(?:\.\w+)+)`")


def delegate_of(obj):
    """The function a thin method hands its arguments to: its docstring has no
    Parameters section and names one function as ``see :func:`setobs....```; the
    method's parameters must be among that function's, which documents them."""
    doc = inspect.getdoc(obj) or ""
    m = _DELEGATE.search(doc)
    if m is None or documented(doc)["Parameters"]:
        return None
    modname, _, name = m.group(1).rpartition(".")
    return getattr(importlib.import_module(modname), name, None)


def delegated_gaps(obj, target) -> list[str]:
    """Parameters of a thin method that its delegate does not take, position by
    position (an instance method's first argument goes to the delegate's first), or
    does not document."""
    mine = [p.name for p in inspect.signature(obj).parameters.values()]
    theirs = list(inspect.signature(target).parameters)
    if mine and mine[0] == "self":
        mine, theirs = mine[1:], theirs[1:]
    elif mine and mine[0] == "cls":
        mine = mine[1:]
    docs = documented(inspect.getdoc(target) or "")["Parameters"]
    return [p for i, p in enumerate(mine) if i >= len(theirs) or theirs[i] not in docs]


def audit() -> tuple[set[str], set[str]]:
    """(undocumented parameters, documented names that are not parameters)."""
    missing, extra = set(), set()
    for qual, obj, is_class in _callables():
        try:
            sig = inspect.signature(obj)
        except (TypeError, ValueError):
            continue
        target = None if is_class else delegate_of(obj)
        if target is not None:  # ("see :func:`...`": the delegate's parameters)
            missing |= {f"{qual}({p})" for p in delegated_gaps(obj, target)}
            continue
        doc = documented(inspect.getdoc(obj) or "")
        known = doc["Parameters"] | (doc["Attributes"] if is_class else set())
        params = {p.name for p in sig.parameters.values() if p.name not in ("self", "cls")}
        missing |= {f"{qual}({p})" for p in params - known}
        if not is_class:
            extra |= {f"{qual}({p})" for p in doc["Parameters"] - params}
    return missing, extra


def test_parser_reads_numpydoc():
    doc = """Summary.

    Parameters
    ----------
    a, b : float
        Two numbers.
    c : int
        Continued on
        more lines: not_a_name
    **kwargs
        Passed on.

    Returns
    -------
    out : float
    """
    assert documented(inspect.cleandoc(doc))["Parameters"] == {"a", "b", "c", "kwargs"}


def test_documented_parameters_exist():
    _, extra = audit()
    assert sorted(extra) == []


def test_every_parameter_is_documented():
    missing, _ = audit()
    assert sorted(missing) == [], f"{len(missing)} undocumented parameter(s)"


def test_a_delegate_must_take_the_method_s_parameters():
    """The "see :func:`...`" form is accepted only when the named function takes (and
    documents) every parameter of the method, position by position."""
    def method(self, tol):
        """Summary; see :func:`setobs.geometry.reduction.remove_redundancy`."""

    def wrong(self, tolerance):
        """Summary; see :func:`setobs.geometry.reduction.remove_redundancy`."""

    def too_many(self, tol, extra):
        """Summary; see :func:`setobs.geometry.reduction.remove_redundancy`."""

    from setobs.geometry.reduction import remove_redundancy

    assert delegate_of(method) is remove_redundancy
    assert delegated_gaps(method, remove_redundancy) == []
    assert delegated_gaps(wrong, remove_redundancy) == []  # (by position: tol)
    assert delegated_gaps(too_many, remove_redundancy) == ["extra"]


def test_audit_sees_an_undocumented_parameter():
    def f(a, b):
        """Summary.

        Parameters
        ----------
        a : int
            Documented.
        """

    doc = documented(inspect.getdoc(f))
    assert set(inspect.signature(f).parameters) - doc["Parameters"] == {"b"}
