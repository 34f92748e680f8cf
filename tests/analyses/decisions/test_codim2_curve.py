"""The GH and double-Hopf points followed in a design parameter, against the points the Hopf-curve
continuation locates (a test function's sign change along a continued curve: an independent
computation) at designs of the grid; a parameter that does not enter the equations leaves them
where they are; points that merge end with a bracket; the off-axis Lyapunov test function on a
textbook normal form."""

import math

import numpy as np
import pytest

from shimmy.analyses.decisions.codim2_curve import END_TOL, codim2_curves
from shimmy.analyses.decisions.study_curves import parameter_range
from shimmy.analyses.diagrams.hopf_curves import hopf_curves
from shimmy.continuation.lyapunov import first_lyapunov_coefficient, hopf_eigenvectors
from shimmy.model.parameters import Parameters


@pytest.fixture(scope="module")
def nes_e_p():
    return codim2_curves("nes", "e_p", values=(0.0008, 0.003))


def _by(curves):
    return {(c.quantity, c.point): c for c in curves}


def test_the_points_equal_the_hopf_curves_located_points_at_grid_designs(nes_e_p):
    curves, warnings = nes_e_p
    assert warnings == []
    by = _by(curves)
    assert sorted(by) == sorted((q, k) for q in ("gh_Fz", "gh_V", "double_hopf_Fz", "double_hopf_V") for k in (1, 2))
    lo, hi = parameter_range("e_p", Parameters())
    for theta in (lo, 0.0008, 0.003, hi):
        located = hopf_curves("nes", params=Parameters().with_overrides({"e_p": theta}))
        for kind, points in (("gh", located.gh_points), ("double_hopf", located.double_hopf_points)):
            assert len(points) == 2
            for k in (1, 2):
                Fz, V = by[(f"{kind}_Fz", k)].value_at(theta), by[(f"{kind}_V", k)].value_at(theta)
                near = min(points, key=lambda q: abs(q["Fz"] - Fz) / 1e5 + abs(q["V"] - V) / 10)
                assert Fz == pytest.approx(near["Fz"], rel=1e-6) and V == pytest.approx(near["V"], rel=1e-6)


def test_a_parameter_outside_the_equations_leaves_the_points_where_they_are():
    """e_p is the NES's: the original gear's points do not move (to Newton's tolerance)."""
    curves, warnings = codim2_curves("original", "e_p", n=5)
    assert warnings == [] and len(curves) == 8
    for c in curves:
        assert None not in c.values
        assert max(c.values) - min(c.values) <= 1e-8 * max(c.values)


def test_points_that_meet_end_there_with_a_bracket_and_no_values_past_it():
    """In k_psi the original gear's two GH points approach each other and vanish together: each
    ends (Newton no longer converges however short the step) at nearly the same k_psi and (V, Fz),
    bracketed to END_TOL of the range; past the end the values are None, not zero."""
    curves, warnings = codim2_curves("original", "k_psi", n=21)
    by = _by(curves)
    lo, hi = parameter_range("k_psi", Parameters())
    ends = []
    for k in (1, 2):
        c = by[("gh_Fz", k)]
        upper = [s for s in c.special_points if s["kind"] == "end" and s["p"] > Parameters().k_psi]
        assert len(upper) == 1
        end = upper[0]
        a, b = end["bracket"]
        assert a == end["p"] and 0 < b - a <= END_TOL * (hi - lo) * 1.0000001
        assert c.value_at(end["p"]) == end["value"] and all(v is None for t, v in zip(c.p, c.values) if t > b)
        ends.append(end)
    assert ends[0]["p"] == pytest.approx(ends[1]["p"], rel=0.05)
    assert ends[0]["Fz"] == pytest.approx(ends[1]["Fz"], rel=0.03) and ends[0]["V"] == pytest.approx(ends[1]["V"], rel=0.03)
    assert any("GH point 1 ends above k_psi" in w for w in warnings)


def test_the_lyapunov_test_function_on_a_normal_form_on_and_off_the_axis():
    """x' = a x - w y + s x r^2, y' = w x + a y + s y r^2 (r^2 = x^2 + y^2), beside a decoupled stable
    pair: l1 = 2 s / w on the axis (a = 0); off it the same value (the cubic terms are the same)
    with the pair found by its frequency, not by being nearest the axis."""
    w, s = 3.0, -0.7

    def jacobian(a):
        def J(z):
            x, y = z[0], z[1]
            r2 = x * x + y * y
            top = np.array([[a + s * (r2 + 2 * x * x), -w + 2 * s * x * y],
                            [w + 2 * s * x * y, a + s * (r2 + 2 * y * y)]], dtype=complex)
            out = np.zeros((4, 4), dtype=complex)
            out[:2, :2] = top
            out[2:, 2:] = [[-0.05, -9.0], [9.0, -0.05]]  # nearer the axis than the pair followed when a = 0.2
            return out
        return J

    assert first_lyapunov_coefficient(jacobian(0.0), 4) == pytest.approx(2 * s / w, rel=1e-6)
    assert first_lyapunov_coefficient(jacobian(0.2), 4, omega_hint=w) == pytest.approx(2 * s / w, rel=1e-6)
    omega, q, p = hopf_eigenvectors(jacobian(0.2)(np.zeros(4)).real, omega_hint=w)
    A = jacobian(0.2)(np.zeros(4)).real
    assert omega == pytest.approx(w) and np.allclose(A @ q, (0.2 + 1j * w) * q)
    assert np.allclose(A.T @ p, (0.2 - 1j * w) * p) and np.vdot(p, q) == pytest.approx(1.0)
    assert math.isclose(hopf_eigenvectors(A)[0], 9.0)  # without the hint: the pair nearest the axis


def test_the_study_carries_the_points_with_their_numbers():
    from shimmy.analyses.decisions.studies import study

    out = study("e_p", [0.0008, 0.003], configs=["nes_pd"]).to_dict()
    points = [c for c in out["curves"] if c["quantity"].startswith(("gh_", "double_hopf_"))]
    # nes_pd is not smooth at rest (the particle damper): no GH points, two double-Hopf points
    assert sorted((c["quantity"], c["point"]) for c in points) == sorted(
        (q, k) for q in ("double_hopf_Fz", "double_hopf_V") for k in (1, 2))
    assert all(c["unit"] == ("N" if c["quantity"].endswith("Fz") else "m/s") for c in points)
