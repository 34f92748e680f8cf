"""The warning of a result whose NES rotation leaves the cubic's range (issue: the workbench used the
cubic at 0.16 rad without a word), on time histories, ground runs and bifurcation diagrams."""

from __future__ import annotations

import pytest

from shimmy import Parameters, simulate
from shimmy.analyses.core import nes_range
from shimmy.model import nes


def test_a_run_beyond_the_range_says_so_with_the_peak_and_the_error_there():
    run = simulate("nes", 50, 350000, t_end=20)  # point D: a torsional cycle with |psi - psis| ~ 0.16 rad
    peak = nes_range.rotation_peak(run.states)
    assert peak >= run.amplitude["nes_relative"] > 0.1
    (warning,) = run.warnings
    assert warning.startswith(nes_range.WARNING_START) and f"{peak:.3g} rad" in warning
    assert f"{100 * nes_range.cubic_error(run.params, peak):.2g} %" in warning and "0.0939 rad" in warning
    assert run.to_dict()["warnings"] == [warning]
    assert simulate("nes", 50, 350000, t_end=20, exact_nes=True).warnings == []  # the exact torque: no warning
    assert simulate("original", 50, 350000, t_end=20).warnings == []  # no NES
    assert simulate("nes", 30, 20000, t_end=5).warnings == []  # stable: the rotation stays tiny


def test_the_warning_follows_the_design_range_not_a_fixed_angle():
    params = Parameters()
    n = params.nes
    limit = nes.cubic_range(n.r1, n.r2, n.r3, n.k_s, n.e_p)
    assert nes_range.warning("nes", params, 0.999 * limit, False) is None
    assert nes_range.warning("nes", params, 1.001 * limit, False) is not None
    wide = params.with_overrides(e_p=0.005)  # a stiffer prestretch: the cubic holds further
    assert nes_range.warning("nes", wide, 1.001 * limit, False) is None
    assert "may reach up to" in nes_range.warning("nes_pd", params, 0.2, False, bound=True)
    assert nes_range.warning("pd", params, 0.3, False) is None


def test_a_diagram_with_stable_cycles_beyond_the_range_says_so():
    from shimmy.analyses.diagrams.bifurcation import bifurcation

    diagram = bifurcation("nes", 350000)
    (warning,) = [w for w in diagram.warnings if w.startswith(nes_range.WARNING_START)]
    assert "on the stable cycles of this diagram" in warning
    peak = float(warning.split("reaches ")[1].split(" rad")[0])
    run = simulate("nes", 50, 350000, t_end=20)  # the stable cycle at 50 m/s is one of the diagram's
    assert peak >= run.amplitude["nes_relative"] * (1 - 1e-3)
    assert peak <= max(0.5, run.amplitude["nes_relative"])  # a value of an orbit, under pi/6
    assert "may reach" not in warning


def test_a_ground_run_beyond_the_range_says_so():
    from shimmy.analyses.ground.ground_run import ground_run

    run = ground_run("nes", "takeoff")
    assert any(w.startswith(nes_range.WARNING_START) for w in run.warnings) == (
        nes_range.rotation_peak(run.states) > nes.cubic_range(*(lambda p: (p.r1, p.r2, p.r3, p.k_s, p.e_p))(
            run.params.nes)))
    assert not [w for w in ground_run("original", "takeoff").warnings if w.startswith(nes_range.WARNING_START)]


@pytest.mark.parametrize("analysis", ["simulate", "bifurcation", "ground_run"])
def test_the_api_request_takes_the_exact_torque(analysis):
    from shimmy.service import schemas

    body = {"config": "nes", "exact_nes": True, "V": 50, "Fz": 350000, "preset": "takeoff"}
    names = {f.name for f in schemas.SCHEMAS[analysis].fields}
    assert schemas.validate(analysis, {k: v for k, v in body.items() if k in names})["exact_nes"] is True
