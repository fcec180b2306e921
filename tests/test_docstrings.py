"""Docstring completeness, in the style of python-control's ``docstrings_test.py``.

Every parameter of every public function, class and public method (the names
in the ``__all__`` of the public modules) must be documented in a numpydoc
``Parameters`` section (``Attributes`` for a dataclass's fields); a documented
parameter must exist. ``UNDOCUMENTED`` is the remaining debt: the test fails when
a parameter not on it is undocumented, and when one on it has been documented
(remove it from the list), so the list can only shrink.
"""

from __future__ import annotations

import importlib
import inspect
import re

PUBLIC_MODULES = [
    "setobs", "setobs.geometry", "setobs.geometry.zonotope", "setobs.geometry.box",
    "setobs.geometry.lp", "setobs.geometry.polytope", "setobs.geometry.reduction",
    "setobs.geometry.plotting", "setobs.geometry.fastlp", "setobs.analysis",
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


def audit() -> tuple[set[str], set[str]]:
    """(undocumented parameters, documented names that are not parameters)."""
    missing, extra = set(), set()
    for qual, obj, is_class in _callables():
        try:
            sig = inspect.signature(obj)
        except (TypeError, ValueError):
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
    new = sorted(missing - UNDOCUMENTED)
    fixed = sorted(UNDOCUMENTED - missing)
    assert new == [], f"{len(new)} undocumented parameter(s): {new[:20]}"
    assert fixed == [], f"documented now, remove from UNDOCUMENTED: {fixed[:20]}"


# The remaining debt (see the module docstring). Do not add to it.
UNDOCUMENTED = frozenset({
    "setobs.analysis.diagnose.DesignVerdict(condition)",
    "setobs.analysis.diagnose.DesignVerdict(decided)",
    "setobs.analysis.diagnose.DesignVerdict(design)",
    "setobs.analysis.diagnose.DesignVerdict(exists)",
    "setobs.analysis.diagnose.DesignVerdict(numbers)",
    "setobs.analysis.diagnose.DesignVerdict(reason)",
    "setobs.analysis.diagnose.DesignVerdict(source)",
    "setobs.analysis.diagnose.Diagnosis(notes)",
    "setobs.analysis.diagnose.Diagnosis(system)",
    "setobs.analysis.existence.BoundedDOReport(q)",
    "setobs.analysis.existence.fu_wang_eq10_matrix(A)",
    "setobs.analysis.existence.fu_wang_eq10_matrix(C)",
    "setobs.analysis.existence.fu_wang_eq10_matrix(L0)",
    "setobs.analysis.existence.fu_wang_eq10_matrix(L1)",
    "setobs.analysis.existence.fu_wang_eq10_matrix(P0)",
    "setobs.analysis.existence.fu_wang_eq10_matrix(z)",
    "setobs.analysis.existence.pio_error_poles(sys)",
    "setobs.analysis.observability.ObservabilityDecomposition(A_21)",
    "setobs.analysis.observability.ObservabilityDecomposition(A_o)",
    "setobs.analysis.observability.ObservabilityDecomposition(A_obar)",
    "setobs.analysis.observability.ObservabilityDecomposition(B_o)",
    "setobs.analysis.observability.ObservabilityDecomposition(B_obar)",
    "setobs.analysis.observability.ObservabilityDecomposition(C_o)",
    "setobs.analysis.observability.ObservabilityDecomposition(Gamma_o)",
    "setobs.analysis.observability.ObservabilityDecomposition(Gamma_obar)",
    "setobs.analysis.observability.ObservabilityDecomposition(T_o)",
    "setobs.analysis.observability.ObservabilityDecomposition(T_obar)",
    "setobs.analysis.observability.ObservabilityDecomposition(output_scale)",
    "setobs.analysis.observability.ObservabilityDecomposition(report)",
    "setobs.analysis.observability.ObservabilityDecomposition(state_scale)",
    "setobs.analysis.structure.RelativeDegreeResult(decision)",
    "setobs.analysis.structure.RelativeDegreeResult(n)",
    "setobs.analysis.structure.UIOResult(decisions)",
    "setobs.analysis.structure.UIOResult(rank_G)",
    "setobs.analysis.structure.UIOResult(rank_XiG)",
    "setobs.analysis.structure.UIOResult(unstable_zeros)",
    "setobs.analysis.zeros.ZerosResult(n)",
    "setobs.analysis.zeros.ZerosResult(q)",
    "setobs.analysis.zeros.ZerosResult.outside_or_on_unit_circle(tol)",
    "setobs.geometry.fastlp.FixedStructureLP.minimize_all_unchecked(b)",
    "setobs.geometry.fastlp.FixedStructureLP.minimize_all_unchecked(b_err)",
    "setobs.geometry.fastlp.FixedStructureLP.minimize_all_unchecked(b_scale)",
    "setobs.geometry.fastlp.FixedStructureLP.minimize_all_unchecked(h)",
    "setobs.geometry.fastlp.FixedStructureLP.minimize_all_unchecked(st)",
    "setobs.geometry.fastlp.LPState(lp)",
    "setobs.geometry.fastlp.hull_from_bounds(bounds)",
    "setobs.geometry.fastlp.hull_from_bounds(c)",
    "setobs.geometry.fastlp.hull_from_bounds(c_err)",
    "setobs.geometry.fastlp.hull_objectives(W)",
    "setobs.geometry.lp.FactorPolytope.certify(w)",
    "setobs.geometry.lp.FactorPolytope.certify(w_err)",
    "setobs.geometry.lp.FactorPolytope.certify(w_pair)",
    "setobs.geometry.lp.FactorPolytope.certify(y)",
    "setobs.geometry.lp.FactorPolytope.minimize_relaxed(w)",
    "setobs.geometry.lp.FactorPolytope.minimize_relaxed(w_err)",
    "setobs.geometry.lp.FactorPolytope.minimize_relaxed(w_pair)",
    "setobs.geometry.lp.FactorPolytope.minimize_under_lock(w)",
    "setobs.geometry.lp.FactorPolytope.minimize_under_lock(w_err)",
    "setobs.geometry.lp.FactorPolytope.minimize_under_lock(w_pair)",
    "setobs.geometry.lp.FactorPolytope.objective_scale(w)",
    "setobs.geometry.lp.FactorPolytope.solve_objective(hs)",
    "setobs.geometry.lp.FactorPolytope.solve_objective(scale)",
    "setobs.geometry.lp.FactorPolytope.solve_objective(w)",
    "setobs.geometry.lp.FactorPolytope.try_compiled(w)",
    "setobs.geometry.lp.FactorPolytope.try_compiled(w_err)",
    "setobs.geometry.lp.FactorPolytope.try_compiled(w_pair)",
    "setobs.io.Record(U)",
    "setobs.io.Record(Y)",
    "setobs.io.Record(t)",
    "setobs.observers.base.PointObserver(disturbance_inputs)",
    "setobs.observers.base.PointObserver(sys)",
    "setobs.observers.base.PointObserver.run(U)",
    "setobs.observers.base.PointObserver.run(Y)",
    "setobs.observers.base.PointObserver.step(u)",
    "setobs.observers.base.PointObserver.step(y)",
    "setobs.observers.base.StateSpaceObserver(disturbance_inputs)",
    "setobs.observers.base.StateSpaceObserver(sys)",
    "setobs.observers.base.StateSpaceObserver.step(u)",
    "setobs.observers.base.StateSpaceObserver.step(y)",
    "setobs.observers.descriptor.DescriptorObserver.step(u)",
    "setobs.observers.descriptor.DescriptorObserver.step(y)",
    "setobs.observers.mbeso.decoupled_gain(A)",
    "setobs.observers.mbeso.decoupled_gain(C)",
    "setobs.observers.mbeso.decoupled_gain(E)",
    "setobs.observers.mbeso.decoupled_gain(V0)",
    "setobs.observers.mbeso.decoupled_gain(degrees)",
    "setobs.observers.mbeso.decoupled_gain(omegas)",
    "setobs.observers.mbeso.mbeso_impulse_response(k)",
    "setobs.observers.mbeso.mbeso_impulse_response(omega)",
    "setobs.observers.mbeso.mbeso_impulse_response(r)",
    "setobs.observers.uio.DelayedUIO(disturbance_inputs)",
    "setobs.observers.uio.DelayedUIO(poles)",
    "setobs.observers.uio.DelayedUIO(sys)",
    "setobs.observers.uio.DelayedUIO.step(u)",
    "setobs.observers.uio.DelayedUIO.step(y)",
    "setobs.plotting.plot_estimate_band(ax)",
    "setobs.plotting.plot_estimate_band(label)",
    "setobs.setmembership.calibrate.NoiseCalibration(info)",
    "setobs.studies.campaign.ObserverSpec(kind)",
    "setobs.studies.campaign.ObserverSpec(name)",
    "setobs.studies.campaign.ObserverSpec(params)",
    "setobs.studies.campaign.run_campaign(base_seed)",
    "setobs.studies.campaign.run_campaign(reference_window)",
    "setobs.studies.campaign.run_campaign(runs)",
    "setobs.studies.campaign.run_campaign(scenario)",
    "setobs.studies.campaign.run_campaign(specs)",
    "setobs.studies.scenarios.Scenario(extra)",
    "setobs.studies.scenarios.Scenario.disturbance(q)",
    "setobs.studies.scenarios.Scenario.disturbance(rng)",
    "setobs.studies.scenarios.Scenario.increment_set(q)",
    "setobs.studies.scenarios.Scenario.initial_state_set(n)",
    "setobs.studies.scenarios.Scenario.simulate(rng)",
    "setobs.studies.scenarios.Trajectory(D)",
    "setobs.studies.scenarios.Trajectory(U)",
    "setobs.studies.scenarios.Trajectory(X)",
    "setobs.studies.scenarios.Trajectory(Y)",
    "setobs.systems.AugmentedSystem(A)",
    "setobs.systems.AugmentedSystem(C)",
    "setobs.systems.AugmentedSystem(E)",
    "setobs.systems.AugmentedSystem(Gamma)",
})
