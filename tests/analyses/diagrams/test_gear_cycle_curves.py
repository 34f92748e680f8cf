"""The gear's fold and torus curves in (V, Fz) against one-parameter diagrams, simulation and the
Hopf curves' codimension-2 points."""

import json

import numpy as np
import pytest

from shimmy.analyses.diagrams.bifurcation import BifurcationOptions, bifurcation
from shimmy.analyses.diagrams.cycle_curves import cycle_curves
from shimmy.analyses.core.simulation import simulate
from shimmy.cli import main
from shimmy.errors import InvalidParameterError

LOADS = (450e3, 650e3, 850e3)

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def original():
    return cycle_curves("original", loads=LOADS)


def crossings(result, kind, Fz):
    return sorted(x["V"] for c in result.to_dict()["curves"] if c["kind"] == kind for x in c["crossings"]
                  if abs(x["Fz"] - Fz) < 1e-3)


@pytest.mark.parametrize("Fz", LOADS[:2])
def test_every_fold_and_torus_point_of_a_diagram_lies_on_a_continued_curve(original, Fz):
    diagram = bifurcation("original", Fz)
    found = [(s["kind"], s["V"]) for b in diagram.branches if b.kind == "periodic" for s in b.special_points
             if s["kind"] in ("LPC", "NS")]
    assert found
    for kind, V in found:
        on = crossings(original, kind, Fz)
        assert on and min(abs(v - V) for v in on) < 1e-6, (kind, V, on)


def test_the_torus_point_next_to_the_fold_at_450_kN_is_found_with_default_options():
    diagram = bifurcation("original", 450e3, options=BifurcationOptions())
    points = [(s["kind"], s["V"]) for b in diagram.branches for s in b.special_points]
    ns = [V for k, V in points if k == "NS" and V > 100]
    lpc = [V for k, V in points if k == "LPC" and V > 100]
    assert len(ns) == 1 and len(lpc) == 1
    assert 0.5 < lpc[0] - ns[0] < 5.0  # ~2 m/s below the fold


def test_the_isola_above_720_kN_is_bounded_by_two_fold_curves(original):
    """At 850 kN the torsional cycles live between two folds; a run from psi = 0.2 rad at 50 m/s
    settles on one of them, whose speed lies between the two fold crossings."""
    folds = crossings(original, "LPC", 850e3)
    assert len(folds) == 2, folds
    low, high = folds
    assert low < 50.0 < high
    run = simulate("original", 50.0, 850e3, t_end=60, x0=[0.2, 0, 0, 0, 0])
    assert run.amplitude["psi"] > 0.1  # a large torsional cycle, not the lateral one
    run_out = simulate("original", 1.05 * high, 850e3, t_end=60, x0=[0.2, 0, 0, 0, 0])
    assert run_out.amplitude["psi"] < 0.05  # past the upper fold the torsional cycle is gone


def test_fold_and_torus_curves_end_at_the_hopf_curves_codimension_2_points(original):
    """Each curve that shrinks to zero amplitude ends at a GH point (fold curves) or a double-Hopf
    point (torus curves) of the Hopf curves."""
    data = original.to_dict()
    gh, hh = data["gh_points"], data["double_hopf_points"]
    assert len(gh) == 2 and len(hh) == 2
    ended = 0
    for c in data["curves"]:
        targets = gh if c["kind"] == "LPC" else hh
        for end in c["ends"]:
            if end["kind"] != "ZA":
                continue
            ended += 1
            assert min(abs(end["V"] - t["V"]) / 10 + abs(end["Fz"] - t["Fz"]) / 1e5 for t in targets) < 2e-3, end
    assert ended >= 4
    kinds = {p["kind"] for p in data["codim2_points"]}
    assert {"GH", "HH", "LPNS"} <= kinds


def test_curves_in_the_json_shape_the_command_line_promises(original, capsys):
    data = original.to_dict()
    assert data["fold_curves"] and data["torus_curves"] and data["pd_curves"] == []
    for curve in data["fold_curves"] + data["torus_curves"]:
        assert set(curve[0]) == {"V", "Fz", "period", "max_psi", "max_lateral"}
        Fz = np.array([p["Fz"] for p in curve])
        assert np.all((Fz >= 10e3 - 1e-6) & (Fz <= 900e3 + 1e-6))
    assert all(set(p) == {"kind", "V", "Fz"} for p in data["codim2_points"])
    json.dumps(data)
    assert main(["curves", "--config", "original", "--kinds", "lpc,foo"]) == 2
    assert "unknown kind (foo)" in capsys.readouterr().err


def test_bad_requests_name_the_field():
    with pytest.raises(InvalidParameterError, match="kinds"):
        cycle_curves("original", kinds=("LPC", "XX"))
    with pytest.raises(InvalidParameterError, match=r"loads\[0\]"):
        cycle_curves("original", loads=(5e6,))


def test_a_torus_start_at_a_strong_resonance_gives_no_one_point_curve():
    """`pd` at 243.7 kN: the small cycles born at the Hopf point at 4.0175 m/s have a complex pair
    next to 1:2 (|mu| 0.99, angle 3.12). A torus start on that pair converges where the pair is on
    the circle and leaves kappa's range [-1, 1] in both directions at once. That is not a curve
    (one point bounds no region): the search is told why, in a warning, and keeps no curve."""
    from shimmy.analyses.diagrams.bifurcation import STATE_SCALE, T_SCALE, V_SCALE, gear_field
    from shimmy.analyses.diagrams.cycle_curves import ContinueUnit, Start
    from shimmy.continuation import Mesh, PeriodicProblem, SpecialPoint
    from shimmy.model.configurations import Configuration
    from shimmy.model.equations import build_model
    from shimmy.model.parameters import Parameters

    Fz = 243687.15083798883  # a slice of the pd map
    diagram = bifurcation("pd", Fz, v_range=(1.0, 200.0), options=BifurcationOptions(mesh_check=False))
    born = [b for b in diagram.branches if b.kind == "periodic" and abs(b.V.min() - 4.0175) < 1e-3]
    assert len(born) == 1
    # Branches that shrink onto x = 0 end there: no fold or torus point of the constant 'orbit' x = 0
    # (a seeded branch used to pass through it and report torus points there, at 4.0175 and 4.0215 m/s)
    for b in diagram.branches:
        if b.kind == "periodic":
            assert all(p["max_psi"] > 1e-4 for p in b.to_dict()["special_points"] if p["kind"] in ("LPC", "NS")), \
                b.origin
    raw = born[0].raw
    mesh_points, u = raw.solutions[0]
    model = build_model("pd", Parameters())
    problem = PeriodicProblem(gear_field(model, Fz), Mesh(mesh_points, raw.ncol), STATE_SCALE[:model.n_states],
                              T_SCALE, V_SCALE)
    mu = problem.multipliers(u)[1:]
    pair = mu[(np.abs(mu.imag) > 1e-7 * np.abs(mu)) & (mu.real < 0)]
    angle = float(np.abs(np.angle(pair[0])))
    assert angle > 3.1 and abs(abs(pair[0]) - 1.0) < 0.02
    start = Start("NS", SpecialPoint("NS", float(raw.p[0]), 0, {"torus_angle": angle}, solution=(mesh_points, u)),
                  Fz, raw.ncol, "the cycles born at the Hopf point at 4.0175 m/s")
    curve, warning = ContinueUnit(Configuration.parse("pd"), Parameters(), start, ((1.0, 200.0), (1e4, 9e5)), ()).run()
    assert curve is None and "gives no curve" in warning and "kappa = -1 left" in warning


def test_a_fold_start_next_to_a_hopf_point_converges():
    """`nes_pd` at 277 kN: the diagram's LPC point at V = 127.387 m/s, 0.3 m/s above a Hopf point,
    starts the fold curve, which crosses the whole speed range. (Small cycles: the fold test
    function is nearly flat; with the condensed LU its rounding noise once gave Newton
    corrections of 1.6e-9, above the tolerance, that never shrank, and the curve was lost.)"""
    from shimmy.analyses.diagrams.cycle_curves import ContinueUnit, starts_of_diagram
    from shimmy.model.configurations import Configuration
    from shimmy.model.parameters import Parameters

    Fz = 277e3
    diagram = bifurcation("nes_pd", Fz, v_range=(1.0, 200.0), options=BifurcationOptions(mesh_check=False))
    starts = [s for s in starts_of_diagram(diagram, Fz) if s.kind == "LPC" and abs(s.point.p - 127.387) < 0.01]
    assert len(starts) == 1
    curve, warning = ContinueUnit(Configuration.parse("nes_pd"), Parameters(), starts[0],
                                  ((1.0, 200.0), (1e4, 9e5)), ()).run()
    assert warning is None and curve is not None, warning
    V = curve.curve.p[:, 0]
    assert V.min() == pytest.approx(1.0) and V.max() == pytest.approx(200.0)


def test_a_longer_trace_of_a_known_curve_takes_its_place(original):
    """A curve traced from another start may run on past a known curve's end (towards a GH or
    double-Hopf point, where a trace's end depends on the amplitudes it met): the longer trace
    replaces the shorter in its place, never both kept (the same boundary twice)."""
    import dataclasses

    from shimmy.analyses.diagrams.cycle_curves import GearCycleCurve, same_curve, with_curve

    l_g = 2.5
    full = max(original.curves, key=lambda c: len(c.curve.p))
    cut = len(full.curve.p) * 3 // 5
    c = full.curve
    short = GearCycleCurve(full.kind, dataclasses.replace(c, p=c.p[:cut], period=c.period[:cut], x_max=c.x_max[:cut],
                                                          x_min=c.x_min[:cut], kappa=c.kappa[:cut],
                                                          multipliers=c.multipliers[:cut],
                                                          solutions=c.solutions[:cut]), full.origin)
    others = [k for k in original.curves if k is not full]
    assert same_curve(short, full, l_g) and not same_curve(full, short, l_g)
    assert with_curve([others[0], short, *others[1:]], full, l_g) == [others[0], full, *others[1:]]
    assert with_curve(others, full, l_g) == [*others, full]


def test_a_fold_whose_multiplier_meets_the_trivial_one_is_no_torus_point():
    """`nes_pd` at 278.5 kN: at the fold of cycles at 130.25 m/s the multiplier through +1 and the
    trivial one came out of the eigenvalue solver as a complex pair 6.6e-6 rad off +1, and the diagram
    reported a torus point there too, where no torus curve passes. The diagram reports the fold only,
    and such a pair starts no torus curve."""
    from shimmy.analyses.diagrams.cycle_curves import RESONANCE_ANGLE, Start, continue_start, starts_of_diagram
    from shimmy.continuation import SpecialPoint
    from shimmy.model.configurations import Configuration
    from shimmy.model.parameters import Parameters

    Fz = 278491.6201117318  # a slice of the nes_pd map
    diagram = bifurcation("nes_pd", Fz, v_range=(1.0, 200.0), options=BifurcationOptions(mesh_check=False))
    at_fold = [s for s in starts_of_diagram(diagram, Fz) if abs(s.point.p - 130.247) < 1e-2]
    assert [s.kind for s in at_fold] == ["LPC"]
    fold = at_fold[0]
    torus = Start("NS", SpecialPoint("NS", fold.point.p, 0, {"torus_angle": 6.6e-6}, solution=fold.point.solution),
                  Fz, fold.ncol, "the fold's pair at +1")
    assert 6.6e-6 < RESONANCE_ANGLE
    assert continue_start(Configuration.parse("nes_pd"), Parameters(), torus, ((1.0, 200.0), (1e4, 9e5)), ()) \
        == (None, None)
