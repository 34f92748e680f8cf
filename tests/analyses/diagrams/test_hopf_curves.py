"""Hopf curves in (V, Fz) against the one-parameter eigenvalue scan and the Lyapunov coefficient."""

import numpy as np
import pytest

from shimmy.analyses.diagrams.hopf_curves import hopf_curves
from shimmy.continuation import PointKind
from shimmy.analyses.core.stability import Criticality, Linearisation, hopf_points
from shimmy.model.equations import build_model
from shimmy.model.parameters import Parameters


@pytest.fixture(scope="module")
def original():
    return hopf_curves("original")


def test_every_curve_point_is_a_hopf_point(original):
    model = build_model("original")
    for curve in original.curves:
        for (V, Fz), omega in zip(curve.p[::7], curve.omega[::7], strict=True):
            ev = Linearisation(model, Fz).eigenvalues(np.array([V]))[0]
            crit = ev[np.argmin(np.abs(ev.real))]
            assert abs(crit.real) < 1e-7 * abs(crit)
            assert abs(abs(crit.imag) - omega) < 1e-7 * omega


def test_curves_cover_every_hopf_point_of_the_slices(original):
    # At 300 kN a lateral (15.9 Hz) and a torsional (11.2 Hz) Hopf point lie 0.008 m/s apart:
    # position and frequency together identify the curve.
    for Fz in (100e3, 250e3, 300e3, 450e3, 800e3):
        for h in hopf_points("original", Fz).hopf_points:
            near = []
            for c in original.curves:
                i = int(np.argmin(np.hypot((c.p[:, 0] - h.V) / 10, (c.p[:, 1] - Fz) / 1e4)))
                if _distance(c, h.V, Fz) < 0.05 and abs(c.omega[i] / h.omega - 1) < 0.02:
                    near.append(c)
            assert len(near) == 1, (Fz, h.V)


def _distance(curve, V, Fz):
    """Distance from (V, Fz) to the curve's polyline in units of (10 m/s, 10 kN)."""
    p = curve.p / np.array([10.0, 1e4])
    q = np.array([V / 10.0, Fz / 1e4])
    a, d = p[:-1], np.diff(p, axis=0)
    s = np.clip(np.sum((q - a) * d, axis=1) / np.maximum(np.sum(d * d, axis=1), 1e-300), 0, 1)
    return float(np.min(np.linalg.norm(a + s[:, None] * d - q, axis=1)))


def test_generalised_hopf_points_change_the_criticality(original):
    gh = original.gh_points
    assert len(gh) == 2
    for g in gh:
        crit = []
        for dF in (-10e3, 10e3):
            h = min(hopf_points("original", g["Fz"] + dF).hopf_points, key=lambda h: abs(h.V - g["V"]))
            crit.append(h.criticality)
        assert set(crit) == {Criticality.SUPERCRITICAL, Criticality.SUBCRITICAL}
    # The one noted from the scan in the physics core: near Fz = 399 kN, V = 162 m/s.
    assert any(abs(g["Fz"] - 398.9e3) < 1e3 and abs(g["V"] - 162.2) < 1.0 for g in gh)


def test_lowest_load_is_a_turning_point(original):
    low = original.fz_minimum
    assert 5e4 < low["Fz"] < 7e4
    assert not [h for h in hopf_points("original", low["Fz"] - 500.0).hopf_points if h.V < 200]
    near = [h.V for h in hopf_points("original", low["Fz"] + 500.0).hopf_points]
    assert sum(abs(v - low["V"]) < 5.0 for v in near) == 2


def test_particle_damper_curves_have_no_criticality():
    result = hopf_curves("pd", n_slices=6)
    assert result.gh_points == [] and all(np.isnan(c.lyapunov).all() for c in result.curves)
    assert result.curves


def test_to_dict_and_bad_input():
    from shimmy.errors import InvalidParameterError

    with pytest.raises(InvalidParameterError, match="fz_max"):
        hopf_curves("nes", fz_range=(5e5, 1e5))
    d = hopf_curves("nes", v_range=(1, 200), fz_range=(1e5, 2e5), n_slices=3).to_dict()
    assert d["curves"] and {"V", "Fz", "frequency_hz", "lyapunov"} == set(d["curves"][0]["points"][0])


def test_double_hopf_points_have_two_pairs_on_the_axis(original):
    """Where the torsional and lateral Hopf curves cross: both pairs' real parts vanish."""
    hh = original.double_hopf_points
    assert len(hh) >= 2
    model = build_model("original")
    for point in hh:
        ev = np.linalg.eigvals(model.jacobian(np.zeros(model.n_states), point["V"], point["Fz"]))
        pairs = ev[ev.imag > 1.0]
        near = np.sort(np.abs(pairs.real))[:2]
        assert np.all(near < 1e-6 * np.abs(pairs.imag).max()), (point, ev)
        freqs = sorted(np.abs(pairs[np.argsort(np.abs(pairs.real))[:2]].imag) / (2 * np.pi))
        np.testing.assert_allclose(freqs, sorted([point["frequency_hz"], point["frequency2_hz"]]), rtol=1e-6)
    assert "double_hopf_points" in original.to_dict()


def test_the_lateral_hopf_curve_and_its_located_lowest_load(original):
    """The lateral curve (critical eigenvector mostly lateral bending) has its lowest load at a
    located turning point: 200 N above it x = 0 has two lateral Hopf points near that speed, 200 N
    below none."""
    modes = [original.mode_of_curve(c) for c in original.curves]
    assert sorted(modes) == ["lateral", "torsional"]
    low = original.lateral_minimum
    lateral = original.curves[modes.index("lateral")]
    assert low["Fz"] <= lateral.p[:, 1].min() + 1e-6
    assert 15.5 < low["frequency_hz"] < 16.5

    def near(Fz):
        return [h for h in hopf_points("original", Fz).hopf_points if abs(h.V - low["V"]) < 15.0]

    assert len(near(low["Fz"] + 200.0)) == 2 and not near(low["Fz"] - 200.0)
    assert original.to_dict()["lateral_minimum"] == low


def test_a_curve_is_not_cut_where_newton_jumps_to_another_branch():
    """A corner NES design (found by the optimiser): the torsional Hopf curve is a closed loop with its
    lowest point at ~82 kN. Newton once jumped from V = 22 to below 1 m/s in one step; the curve was cut
    there and the cut end taken for its lowest point. A correction larger than the step is now refused."""
    from shimmy.analyses.decisions.sensitivity import sensitivity

    params = Parameters().with_overrides(r2=0.08145057809022613, e_p=0.005, k_s=1399769.10649413, r3=0.005)
    result = hopf_curves("nes", params=params)
    loop = next(c for c in result.curves if c.closed)
    assert loop.stop_reasons == ["closed curve: returned to its start"]
    assert np.max(np.abs(np.diff(loop.p[:, 0]))) < 12.0  # no jump across the plane (ds_max is 10 m/s in V)
    low = result.fz_minimum
    # a located turning point
    assert any(abs(e.p[1] - low["Fz"]) < 1e-6 * low["Fz"] for e in loop.points_of(PointKind.P2_TURN))
    s = sensitivity("nes", 150e3, params=params, names=["k_s", "e_p"], amplitude=False)
    assert s.min_shimmy["source"] == "lowest point of the Hopf curves"
    assert s.min_shimmy["Fz"] == pytest.approx(low["Fz"], rel=1e-6)
