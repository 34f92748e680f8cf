"""The optimiser on a problem with a known optimum, and on the gear; robustness against linear propagation."""

import numpy as np
import pytest

from shimmy.analyses.core.executors import open_executor
from shimmy.analyses.diagrams.hopf_curves import hopf_curves
from shimmy.analyses.decisions.optimise import Constraint, SearchProblem, figures_of, optimise, search
from shimmy.analyses.decisions.robustness import Tolerance, robustness
from shimmy.errors import InvalidParameterError
from shimmy.model.parameters import PARAMETER_SPECS, Parameters

NAMES = ["r2", "e_p"]


def _z(values):
    return np.array([(v - PARAMETER_SPECS[n].low) / (PARAMETER_SPECS[n].high - PARAMETER_SPECS[n].low)
                     for n, v in zip(NAMES, values, strict=True)])


def quadratic(task):
    """A smooth test problem in the scaled design z: maximise 1e5 (1 - (z1 - 0.3)^2 - 2 (z2 - 0.6)^2)
    with max_psi = 0.1 (z1 + z2); its gradients in the parameters' units."""
    _, _, names, values, wanted, gradient = task
    z = _z(values)
    spans = np.array([PARAMETER_SPECS[n].high - PARAMETER_SPECS[n].low for n in names])
    f = 1e5 * (1 - (z[0] - 0.3) ** 2 - 2 * (z[1] - 0.6) ** 2)
    df = 1e5 * np.array([-2 * (z[0] - 0.3), -4 * (z[1] - 0.6)]) / spans
    g = 0.1 * (z[0] + z[1])
    dg = 0.1 * np.ones(2) / spans
    figures = {}
    for key in wanted:
        value, d = (f, df) if key[0] == "min_shimmy_Fz" else (g, dg)
        figures[key] = {"value": value, "gradient": dict(zip(names, d, strict=True)) if gradient else None}
    return {"ok": True, "figures": figures}


def _best(history, sense=1):
    feasible = [h for h in history if h["feasible"]]
    return max(feasible, key=lambda h: sense * h["objective"])


@pytest.mark.parametrize("method", ["gradient", "global"])
def test_search_finds_the_known_constrained_optimum(method):
    # max -(z1-0.3)^2 - 2(z2-0.6)^2 subject to z1 + z2 <= 0.7: Lagrange gives z = (1/6, 8/15).
    problem = SearchProblem("nes", Parameters().to_dict(), NAMES, "min_shimmy_Fz", 150e3,
                       [Constraint("max_psi", "<=", 0.07, 150e3)], evaluator=quadratic)
    with open_executor(max_workers=1) as inline:
        history, message = search(problem, method, np.array([0.5, 0.5]), 8, 2, 50, 30, 10, 0, inline,
                                  lambda f, m: None)
    best = _best(history)
    tol = 1e-5 if method == "gradient" else 2e-2
    np.testing.assert_allclose(_z(list(best["design"].values())), [1 / 6, 8 / 15], atol=tol)
    assert best["objective"] == pytest.approx(1e5 * (1 - (1 / 6 - 0.3) ** 2 - 2 * (8 / 15 - 0.6) ** 2), rel=1e-3)
    assert [h["evaluation"] for h in history] == list(range(1, len(history) + 1))
    assert any(not h["feasible"] for h in history)  # the unconstrained optimum (0.3, 0.6) violates it
    if method == "gradient":
        assert "SLSQP" in message and history[0]["design"] == dict(zip(NAMES, problem.values(np.array([0.5, 0.5])),
                                                                        strict=True))
        designs = [tuple(h["design"].values()) for h in history]
        assert len(designs) == len(set(designs))  # no design evaluated twice (a local run starts from its start)


def refused(task):
    return {"ok": False, "reason": "r3=0.001 makes the roller leave its track"}


def test_search_says_so_when_no_start_design_can_be_evaluated():
    problem = SearchProblem("nes", Parameters().to_dict(), NAMES, "min_shimmy_Fz", 150e3, [], evaluator=refused)
    with open_executor(max_workers=1) as inline:
        history, message = search(problem, "gradient", np.array([0.5, 0.5]), 4, 1, 10, 2, 5, 0, inline,
                                  lambda f, m: None)
    assert len(history) == 4 and not any(h["feasible"] for h in history)
    assert message.startswith("no start design could be evaluated") and "roller" in message


@pytest.mark.slow
def test_gear_optimum_is_recomputed_from_scratch_and_beats_the_nominal_design():
    result = optimise("nes", "min_shimmy_Fz", parameters=["e_p", "k_s"], starts=4, local_runs=1, seed=1)
    assert result.method == "gradient" and result.feasible
    assert result.objective_value >= result.nominal_objective
    assert result.nominal_objective == pytest.approx(hopf_curves("nes").fz_minimum["Fz"], rel=1e-7)
    params = Parameters().with_overrides(result.design)
    again = figures_of("nes", params, [("min_shimmy_Fz", None)])[("min_shimmy_Fz", None)]["value"]
    assert again == pytest.approx(result.objective_value, rel=1e-9)
    independent = hopf_curves("nes", params=params).fz_minimum["Fz"]  # the continued curve's located turning point
    assert independent == pytest.approx(result.objective_value, rel=1e-6)
    assert result.figures["optimum"]["min_shimmy_Fz"] == pytest.approx(result.objective_value, rel=1e-9)
    assert result.figures["original"]["min_shimmy_Fz"] == pytest.approx(hopf_curves("original").fz_minimum["Fz"],
                                                                          rel=1e-7)
    assert result.evaluations == len(result.history) > 4
    assert result.link_query["config"] == "nes" and float(result.link_query["e_p"]) == pytest.approx(
        result.design["e_p"])
    d = result.to_dict()
    assert {"design", "objective", "nominal_objective", "evaluations"} <= set(d)
    # Every figure of merit for the optimum, the nominal design and original (those at a load at Fz).
    for which in ("optimum", "nominal", "original"):
        assert set(result.figures[which]) == {"min_shimmy_Fz", "interval@150000", "max_psi@150000", "torsion_area"}
    nominal = figures_of("nes", Parameters(), [("max_psi", 150000.0)])[("max_psi", 150000.0)]["value"]
    assert result.figures["nominal"]["max_psi@150000"] == pytest.approx(nominal, rel=1e-9)
    # The flag says which parameters ended on a bound, and only those.
    flagged = {b["name"]: b["bound"] for b in result.at_bounds}
    for name, value in result.design.items():
        spec = PARAMETER_SPECS[name]
        on = {"low": abs(value - spec.low), "high": abs(value - spec.high)}
        near = [k for k, gap in on.items() if gap <= 1e-3 * (spec.high - spec.low)]
        assert flagged.get(name) == (near[0] if near else None)
    assert ("the range limits the optimum" in " ".join(result.warnings)) == bool(flagged)


def test_bounds_reached_names_the_parameters_on_a_bound():
    from shimmy.analyses.decisions.optimise import bounds_reached

    assert bounds_reached({"r2": 0.09, "e_p": 0.003, "k_s": 1.0e6 + 300.0}) == [
        {"name": "r2", "bound": "high", "limit": 0.09, "value": 0.09},
        {"name": "k_s", "bound": "low", "limit": 1.0e6, "value": 1.0e6 + 300.0}]  # within 0.1 % of the range
    assert bounds_reached({"k_s": 1.0e6 + 500.0}) == []  # 0.125 % of the range: inside


def test_constraints_and_options_are_checked_naming_the_field():
    assert Constraint.parse("max_psi@200000<=0.02", 150e3) == Constraint("max_psi", "<=", 0.02, 200e3)
    assert Constraint.parse("min_shimmy_Fz >= 8e4", 150e3) == Constraint("min_shimmy_Fz", ">=", 8e4, None)
    for bad, field in (("max_psi=0.02", "constraint"), ("max_psy<=1", "max_psy"), ("max_psi<=abc", "constraint"),
                       ("max_psi@5<=0.1", "constraint Fz")):
        with pytest.raises(InvalidParameterError) as info:
            Constraint.parse(bad, 150e3)
        assert field in str(info.value)
    # spaces ignored in reading (as ever), a refused part quoted as typed, its spaces kept
    assert Constraint.parse(" max_psi @ 200 000 < = 0.02 ", 150e3) == Constraint("max_psi", "<=", 0.02, 200e3)
    for bad, typed in (("max_psi <= 0.02 extra", "'0.02 extra'"), ("max_psi @ 150 kN <= 0.02", "'150 kN'"),
                       ("max _psy <= 1", "'max _psy'"), ("max_psi = 0.02", "'max_psi = 0.02' has no <= or >=")):
        with pytest.raises(InvalidParameterError) as info:
            Constraint.parse(bad, 150e3)
        assert typed in str(info.value)
    with pytest.raises(InvalidParameterError, match="objective"):
        optimise("nes", "fastest")
    with pytest.raises(InvalidParameterError, match="method"):  # the torsion area has no derivative
        optimise("nes", "torsion_area", method="gradient")
    with pytest.raises(InvalidParameterError, match="method"):  # n is a count
        optimise("pd", "max_psi", parameters=["n"], method="gradient")
    with pytest.raises(InvalidParameterError, match="no device parameters"):
        optimise("original", "min_shimmy_Fz")
    with pytest.raises(InvalidParameterError, match="not fitted"):
        optimise("original", "min_shimmy_Fz", parameters=["k_s"])
    with pytest.raises(InvalidParameterError, match="k_sx"):
        optimise("nes", "min_shimmy_Fz", parameters=["k_sx"])


TYRE_AND_SPRING = ("k_lam", "c_lam", "L", "k_s")


def test_small_tolerances_sampled_spread_equals_linear_propagation():
    result = robustness("nes_pd", {n: 0.002 for n in TYRE_AND_SPRING}, samples=128, seed=3)
    assert len(result.hopf_points) == 2
    for h in result.hopf_points + [result.min_shimmy]:
        assert h["std"] == pytest.approx(h["linear_std"], rel=0.03)
        assert h["mean"] == pytest.approx(h["nominal"], rel=1e-3)
    for p, prob in result.p_shimmy.items():  # 0.2 % moves no operating point across a boundary
        assert prob == pytest.approx(result.p_shimmy_linear[p], abs=1e-6), p


def test_sampled_and_linear_figures_agree_for_engineering_tolerances():
    """5 % on the tyre constants and the NES spring: samples may leave the design ranges (k_s at 3
    standard deviations), they are not truncated; an operating point near a boundary has an
    intermediate probability of shimmy, predicted by linear propagation to a few per cent."""
    tols = [f"{n}=0.05" for n in ("k_lam", "c_lam", "L", "h", "k_a", "alpha_m", "k_s")]
    result = robustness("nes_pd", tols, samples=256)
    assert result.refused == 0 and not any("not physical" in w for w in result.warnings)
    for h in result.hopf_points + [result.min_shimmy]:
        assert h["std"] == pytest.approx(h["linear_std"], rel=0.05)
        assert len(h["samples"]) == 256
    assert 0.02 < result.p_shimmy["B"] < 0.2
    assert result.p_shimmy["B"] == pytest.approx(result.p_shimmy_linear["B"], abs=0.03)
    wide = robustness("nes", ["k_s=0.1"], samples=64)  # 1.2e6 +- 3 x 0.12e6 N/m: past both range ends
    for h in wide.hopf_points:
        assert h["std"] == pytest.approx(h["linear_std"], rel=0.03)


def test_robustness_is_reproducible_for_a_seed():
    tols = ["k_lam=0.05", "k_s=0.05:uniform"]
    a = robustness("nes", tols, samples=32, seed=7).to_dict()
    b = robustness("nes", tols, samples=32, seed=7).to_dict()
    c = robustness("nes", tols, samples=32, seed=8).to_dict()
    assert a["hopf_points"] == b["hopf_points"] and a["p_shimmy"] == b["p_shimmy"]
    assert a["hopf_points"][0]["samples"] != c["hopf_points"][0]["samples"]
    u = Tolerance.parse("k_s=0.05:uniform")
    assert u.std_factor == pytest.approx(0.05 / np.sqrt(3))
    spread = np.array(a["hopf_points"][1]["samples"])
    assert spread.size == 32


def test_tolerances_are_checked_naming_the_field():
    with pytest.raises(InvalidParameterError, match="k_sx"):
        Tolerance.parse("k_sx=0.05")
    with pytest.raises(InvalidParameterError, match="tolerance k_s"):
        Tolerance.parse("k_s=0.3")  # normal: at most 20 % (5 standard deviations from zero)
    assert Tolerance.parse("k_s=0.3:uniform").relative == 0.3
    with pytest.raises(InvalidParameterError, match="integer"):
        Tolerance.parse("n=0.05")
    with pytest.raises(InvalidParameterError, match="distribution"):
        Tolerance.parse("k_s=0.05:cauchy")
    with pytest.raises(InvalidParameterError, match="distribution=''"):  # a ':' with nothing after it: not normal
        Tolerance.parse("k_s=0.05:")
    assert Tolerance.parse(" k_s = 0.05 : uni form ") == Tolerance.parse("k_s=0.05:uniform")
    with pytest.raises(InvalidParameterError, match="'0.05 extra'"):  # quoted as typed, its space kept
        Tolerance.parse("k_s = 0.05 extra")
    with pytest.raises(InvalidParameterError, match="'k_s 0.05' has no ="):
        Tolerance.parse("k_s 0.05")
    with pytest.raises(InvalidParameterError, match="tolerance"):
        robustness("nes", [])
