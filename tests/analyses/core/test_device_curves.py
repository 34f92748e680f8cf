import numpy as np
import pytest

from shimmy import GeometryError, InvalidParameterError, Parameters
from shimmy.analyses.core.device_curves import nes_curve, pd_curves
from shimmy.model.nes import VALID_ANGLE


def test_nes_curve_spans_the_valid_range_and_is_consistent():
    c = nes_curve(n_points=101)
    assert c.angle.size == 101 and np.abs(c.angle).max() == pytest.approx(0.98 * VALID_ANGLE)
    assert c.torque_exact[50] == 0.0 and c.stiffness_exact[50] == pytest.approx(c.k1)
    # stiffness is the slope of the torque along the curve (second-order differences, fine grid)
    fine = nes_curve(n_points=4001)
    slope = np.gradient(fine.torque_exact, fine.angle)
    np.testing.assert_allclose(slope[1:-1], fine.stiffness_exact[1:-1], rtol=1e-4)
    assert c.cubic_error_at["0.1"] == pytest.approx(0.0123, abs=5e-4)
    assert c.cubic_error_at["0.05"] < c.cubic_error_at["0.1"] < c.cubic_error_at["0.2"]
    assert set(c.to_dict()) >= {"angle", "torque_exact", "torque_cubic", "k1", "k3"}


def test_nes_curve_follows_the_design():
    stiffer = nes_curve(params=Parameters().with_overrides(e_p=0.002))
    assert stiffer.k1 == pytest.approx(2 * nes_curve().k1)


def test_pd_curves_for_design_and_presets():
    curves = pd_curves(params=Parameters().with_material("tungsten"), v_max=1.0, n_points=11)
    assert [c.material for c in curves] == ["design", "steel", "tungsten"]
    design, steel, tungsten = curves
    np.testing.assert_array_equal(design.torsional_damping, tungsten.torsional_damping)
    assert np.all(tungsten.torsional_damping[1:] > steel.torsional_damping[1:])
    assert design.torsional_damping[0] == 0.0 and design.torque[0] == 0.0
    np.testing.assert_allclose(design.torque, design.torsional_damping * design.rate)


def test_bad_curve_requests():
    with pytest.raises(InvalidParameterError, match=r"fraction=1.0 is out of range"):
        nes_curve(fraction=1.0)
    with pytest.raises(InvalidParameterError, match=r"v_max=-1.0 is out of range"):
        pd_curves(v_max=-1.0)
    assert issubclass(GeometryError, ValueError)
