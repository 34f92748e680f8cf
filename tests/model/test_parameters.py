import json
import math

import pytest

from shimmy import InvalidParameterError, Parameters
from shimmy.model.parameters import MATERIALS, PARAMETER_SPECS, check_operating_point

ISSUE_NAMES = ("Iz Ix R phi e k_psi c_psi k_delta c_delta k_a alpha_m c_lam l_g h L k_lam "
               "r1 r2 r3 k_s e_p I_nes c_nes r n H d_chamber h_chamber a_p rho_p rho_m_frac g_p e_r "
               "d_p f phi_f I2D I_pd").split()


def test_every_canonical_name_is_declared_with_unit_range_and_description():
    assert list(PARAMETER_SPECS) == ISSUE_NAMES
    for spec in PARAMETER_SPECS.values():
        assert spec.low <= spec.default <= spec.high, spec.name
        assert spec.description and spec.provenance


def test_defaults_match_model_md_where_it_gives_values():
    p = Parameters()
    assert (p.Iz, p.Ix, p.R, p.e, p.k_psi, p.k_delta, p.L) == (100, 600, 0.362, 0.12, 3.8e5, 6.1e6, 0.3)
    assert (p.r1, p.r2, p.r3, p.k_s, p.e_p) == (0.1, 0.08, 0.01, 1.2e6, 0.001)
    assert (p.a_p, p.rho_p, p.rho_m_frac, p.e_r, p.d_p) == (0.9, 7800, 0.9, 0.8, 0.001)
    assert p.phi_f == pytest.approx(math.radians(35), abs=1e-4)
    assert p.n == 24 and p.r == 0.15


def test_overrides_are_validated_and_return_new_objects():
    base = Parameters()
    changed = base.with_overrides({"r2": 0.085}, e_p="0.002")
    assert changed.r2 == 0.085 and changed.e_p == 0.002
    assert base.r2 == 0.08  # immutable


@pytest.mark.parametrize("name,value,match", [
    ("r2", 0.2, r"r2=0.2 is out of range; allowed: a number in \[0.07, 0.09\] m"),
    ("a_p", float("nan"), r"a_p=nan is not finite; allowed: a number in \[0.5, 0.95\]"),
    ("k_s", float("inf"), r"k_s=inf is not finite"),
    ("rho_p", "heavy", r"rho_p='heavy' is not a number"),
    ("rho_p", None, r"rho_p=None is not a number"),
    ("e_p", True, r"e_p=True is not a number"),
    ("n", 2.5, r"n=2.5 is not an integer"),
    ("rr2", 0.08, r"unknown parameter 'rr2' \(did you mean r2\?\)"),
])
def test_bad_overrides_name_the_field_value_and_range(name, value, match):
    with pytest.raises(InvalidParameterError, match=match) as info:
        Parameters().with_overrides({name: value})
    assert info.value.field == name


def test_geometry_that_derails_the_roller_is_refused():
    with pytest.raises(InvalidParameterError, match=r"r3=0.005 makes the roller leave its track"):
        Parameters().with_overrides(r1=0.2, r2=0.07, r3=0.005)


def test_canonical_dict_round_trips_and_hash_is_stable():
    p = Parameters().with_overrides(r2=0.075)
    d = p.to_dict()
    assert list(d) == ISSUE_NAMES
    json.dumps(d, allow_nan=False)
    assert Parameters.from_dict(d) == p
    assert p.digest() == Parameters.from_dict(json.loads(json.dumps(d))).digest()
    assert p.digest() != Parameters().digest()
    assert len(p.digest()) == 64


def test_material_presets():
    tungsten = Parameters().with_material("tungsten")
    assert (tungsten.rho_p, tungsten.e_r) == (16500, 0.6)
    assert tungsten.a_p == Parameters().a_p
    assert set(MATERIALS) == {"steel", "tungsten"}
    with pytest.raises(InvalidParameterError, match="unknown material 'gold'"):
        Parameters().with_material("gold")


def test_operating_point_ranges():
    assert check_operating_point(30, 150e3) == (30.0, 150000.0)
    with pytest.raises(InvalidParameterError, match=r"V=0.5 is out of range; allowed: a number in \[1, 500\] m/s"):
        check_operating_point(0.5, 150e3)
    with pytest.raises(InvalidParameterError, match=r"Fz=1000000.0 is out of range.*\[10000, 900000\] N"):
        check_operating_point(30, 1e6)


def test_sampled_values_may_leave_the_design_range_but_not_physics():
    from shimmy.model.parameters import Parameters as P

    p = P().with_sampled({"k_s": 1.5e6, "k_lam": 0.0021})  # k_s's design range ends at 1.4e6 N/m
    assert p.k_s == 1.5e6 and p.k_lam == 0.0021 and P().k_s == 1.2e6
    with pytest.raises(InvalidParameterError, match="k_s"):
        P().with_sampled({"k_s": -1.0})
    with pytest.raises(InvalidParameterError, match="L"):
        P().with_sampled({"L": 0.0})
    with pytest.raises(InvalidParameterError, match="r3"):  # the roller leaves its track
        P().with_sampled({"r2": 0.07, "r3": 0.002})
    with pytest.raises(InvalidParameterError, match="k_sx"):
        P().with_sampled({"k_sx": 1.0})
