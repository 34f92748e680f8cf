"""Disturbance margins and basin fractions of the gear (shimmy.analyses.maps.margins), checked by the product's own
time histories: the study's `original` at (50 m/s, 550 kN), where a lateral and a torsional cycle coexist and a yaw
kick of about 0.016 rad separates them (measured beforehand by 60-80 s runs and bisection in psi0)."""

from __future__ import annotations

import numpy as np
import pytest

from shimmy.analyses.core.executors import InlineExecutor, open_executor
from shimmy.analyses.core.response import ResponseType
from shimmy.analyses.core.simulation import simulate
from shimmy.analyses.maps.margins import ENERGY_COMPONENTS, basins, diagram_at, margins
from shimmy.analyses.maps.point_attractors import RunUnit
from shimmy.errors import InvalidParameterError
from shimmy.model.configurations import Configuration
from shimmy.model.parameters import Parameters

POINT = ("original", 50.0, 550e3)


@pytest.fixture(scope="module")
def pool():
    with open_executor(max_workers=2) as executor:
        yield executor


@pytest.fixture(scope="module")
def yaw(pool):
    return margins(*POINT, direction="psi", executor=pool)


def test_the_yaw_threshold_separates_the_lateral_and_the_torsional_cycle(yaw):
    """Small kicks end on the lateral cycle (the standard start's), kicks above ~0.0165 rad on the torsional one;
    the threshold's two check runs and two independent 60 s time histories at -+2 % confirm it."""
    result = yaw.to_dict()
    modes = [a["mode"] for a in result["attractors"]]
    assert sorted(modes) == ["lateral", "torsional"] and not result["straight_rolling_stable"]
    lateral, torsional = (result["attractors"][modes.index(m)] for m in ("lateral", "torsional"))
    assert lateral["standard_start"] and result["standard_start"] == modes.index("lateral")
    assert lateral["amplitude"]["psi"] == pytest.approx(0.0293, rel=0.01)
    assert torsional["amplitude"]["psi"] == pytest.approx(0.1867, rel=0.01)
    assert lateral["min_disturbance"]["value"] == 0.0 and lateral["min_disturbance"]["check"]["confirmed"]
    m = torsional["min_disturbance"]
    assert {"value", "unit", "direction", "method", "tolerance"} <= set(m)
    assert (m["unit"], m["direction"]) == ("rad", "psi")
    assert 0.0155 < m["value"] < 0.0175 and m["tolerance"] <= 0.005 * m["value"]
    assert m["lower"] < m["value"] < m["upper"] and m["energy_J"] == pytest.approx(0.5 * 3.8e5 * m["value"] ** 2)
    check = m["check"]
    assert check["confirmed"] and check["below"]["mode"] == "lateral" and check["above"]["mode"] == "torsional"
    assert check["below"]["size"] == m["lower"] and check["above"]["size"] == m["upper"]
    for factor, expected in ((0.98, ResponseType.LATERAL), (1.02, ResponseType.TORSION)):
        run = simulate("original", 50.0, 550e3, x0=[factor * m["value"], 0, 0, 0, 0], t_end=60.0)
        assert run.response_type is expected and run.steady, factor
    assert result["saddles"] and result["runs"] < 40 and result["unsettled_runs"] == 0
    text = yaw.summary_text()
    assert "smallest psi: 0.01649" in text and "confirmed" in text


def test_the_same_margin_on_any_executor(yaw):
    inline = margins(*POINT, direction="psi", executor=InlineExecutor())
    assert inline.to_dict()["attractors"] == yaw.to_dict()["attractors"]


def test_early_stopped_runs_end_where_full_runs_end(yaw):
    """Runs stopped after two 1 s windows on an attractor give the label of full 80 s runs judged on their last
    20 s, on kicks sampled in the energy ball of 0.2 rad."""
    config, V, Fz = Configuration.parse(POINT[0]), POINT[1], POINT[2]
    scales = yaw.found.norm.scales(ENERGY_COMPONENTS)
    rng = np.random.default_rng(3)
    starts = []
    for _ in range(12):
        z = rng.standard_normal(4)
        z *= 0.2 * rng.random() ** 0.25 / np.linalg.norm(z)
        starts.append(tuple(float(v) for v in [*(z * scales), 0.0]))
    early = RunUnit(config, V, Fz, Parameters(), tuple(starts), yaw.found.classifier, 80.0).run()
    full = RunUnit(config, V, Fz, Parameters(), tuple(starts), yaw.found.classifier, 80.0, full=True).run()
    assert [e[0] for e in early] == [f[0] for f in full]
    assert min(e[0] for e in early) >= 0 and max(e[3] for e in early) < 20.0


def test_the_smallest_energy_over_all_directions_is_below_every_axis(pool, yaw):
    """The sweep includes the four axes, so its minimum is at most the yaw threshold's energy; its checks hold."""
    result = margins(*POINT, direction="energy", executor=pool).to_dict()
    torsional = next(a for a in result["attractors"] if a["mode"] == "torsional")["min_disturbance"]
    along_psi = next(a for a in yaw.to_dict()["attractors"] if a["mode"] == "torsional")["min_disturbance"]
    assert torsional["unit"] == "J" and torsional["direction"] == "energy" and torsional["check"]["confirmed"]
    assert 0 < torsional["value"] < along_psi["energy_J"]
    kick = torsional["disturbance"]
    energy = 0.5 * (3.8e5 * kick["psi"] ** 2 + 100 * kick["dpsi"] ** 2 + 6.1e6 * kick["delta"] ** 2
                    + 600 * kick["ddelta"] ** 2)
    assert energy == pytest.approx(torsional["energy_J"], rel=1e-9)
    assert result["runs"] < 800


def test_basin_fractions_are_reproducible_and_their_intervals_hold_the_shares(pool):
    a = basins(*POINT, radius=0.2, samples=40, seed=5, executor=pool).to_dict()
    b = basins(*POINT, radius=0.2, samples=40, seed=5, executor=pool).to_dict()
    assert [x["basin"] for x in a["attractors"]] == [x["basin"] for x in b["attractors"]]
    assert sum(x["basin"]["count"] for x in a["attractors"]) + a["unsettled"] + a["failed"] == 40
    for x in a["attractors"]:
        low, high = x["basin"]["ci95"]
        assert low <= x["basin"]["fraction"] <= high
    lateral = next(x for x in a["attractors"] if x["mode"] == "lateral")["basin"]
    assert lateral["fraction"] > 0.5  # most kicks up to 0.2 rad of the same energy end on the lateral cycle
    assert "95 % interval" in basins_summary_text(a)


def basins_summary_text(result):
    from shimmy.analyses.maps.summaries import basins_summary

    return basins_summary(result)


def test_a_bistable_point_where_no_yaw_kick_reaches_the_lateral_cycle(pool):
    """At (50 m/s, 350 kN) the standard start ends torsional, and no yaw angle up to 0.4 rad reaches the
    lateral cycle: its margin says so (value None) instead of a number."""
    result = margins("original", 50.0, 350e3, direction="psi", executor=pool).to_dict()
    lateral = next(a for a in result["attractors"] if a["mode"] == "lateral")
    torsional = next(a for a in result["attractors"] if a["mode"] == "torsional")
    assert torsional["standard_start"] and torsional["min_disturbance"]["value"] == 0.0
    m = lateral["min_disturbance"]
    assert m["value"] is None and not m["reached"] and "0.4 rad" in m["note"]


@pytest.mark.parametrize("overrides, field", [
    ({"direction": "yaw"}, "direction"), ({"rtol": 0}, "rtol"), ({"max_size": 2}, "max_size"),
    ({"min_size": 0.05, "max_size": 0.01}, "min_size"), ({"scan_points": 2.5}, "scan_points"), ({"t_max": 5}, "t_max"),
    ({"direction": "mix"}, "mix"), ({"direction": "mix", "mix": "psi=0, dpsi=0"}, "mix"),
    ({"direction": "mix", "mix": "psi=1,psi=2"}, "mix"), ({"direction": "mix", "mix": "psi=x"}, "mix"),
    ({"direction": "mix", "mix": "psi=nan"}, "mix"), ({"direction": "mix", "mix": "yaw=1"}, "mix"),
    ({"mix": "psi=1"}, "mix"), ({"origin": "cycle"}, "origin"), ({"phases": 33}, "phases"),
])
def test_bad_settings_are_refused_naming_the_field(overrides, field):
    with pytest.raises(InvalidParameterError) as info:
        margins(*POINT, executor=InlineExecutor(), **overrides)
    assert info.value.field == field


@pytest.mark.parametrize("args, overrides, field", [
    (("original", 600.0, 550e3), {}, "V"), (("original", 50.0, 550e3), {"samples": 3}, "samples"),
    (("original", 50.0, 550e3), {"radius": -1}, "radius"), (("gear", 50.0, 550e3), {}, "config"),
])
def test_bad_basin_input_is_refused_naming_the_field(args, overrides, field):
    with pytest.raises(InvalidParameterError) as info:
        basins(*args, executor=InlineExecutor(), **overrides)
    assert info.value.field == field


def test_a_diagram_of_another_load_is_refused():
    other = diagram_at(Configuration.ORIGINAL, 550e3, Parameters(), 200.0)
    with pytest.raises(InvalidParameterError) as info:
        margins("original", 50.0, 850e3, diagram=other, executor=InlineExecutor())
    assert info.value.field == "diagram"


def test_a_run_is_on_an_attractor_only_within_ten_percent_and_nearer_to_it_than_to_every_saddle():
    """The classifier on its own: energy-weighted amplitudes (k_psi = 4, k_delta = 1: e = (2 psi, delta))."""
    from shimmy.analyses.core.basins import UNSETTLED
    from shimmy.analyses.maps.point_attractors import AttractorSet

    cycles = AttractorSet(((0.0, 0.0), (0.5, 0.0), (0.0, 2.0)), (True, False, False), ((0.3, 0.0),), 4.0, 1.0)
    assert cycles.label(0.52, 0.0, False) == 1 and cycles.label(0.0, 1.85, False) == 2
    assert cycles.label(0.56, 0.0, False) == UNSETTLED  # 12 % off
    assert cycles.label(0.3, 0.0, True) == UNSETTLED  # on the saddle
    assert cycles.label(0.005, 0.0, True) == 0 and cycles.label(0.005, 0.0, False) == UNSETTLED  # x = 0 if falling
    assert cycles.label(0.02, 0.0, True) == UNSETTLED  # 0.04 > 5 % of the smallest cycle's 0.6
    assert cycles.decaying() == UNSETTLED
    alone = AttractorSet(((0.0, 0.0),), (True,), (), 4.0, 1.0)
    assert alone.decaying() == 0 and alone.label(0.0004, 0.0, True) == 0 and alone.label(0.0006, 0.0, True) == UNSETTLED


@pytest.fixture(scope="module")
def from_cycle(pool):
    return margins(*POINT, direction="psi", origin="standard_attractor", phases=4, executor=pool)


def test_kicks_from_the_standard_starts_cycle_find_the_torsional_threshold_over_its_phases(from_cycle):
    """Kicked on the lateral cycle the standard start reaches, at four phases of its period, the smallest yaw kick to
    the torsional cycle is the smallest over the phases, and two independent 60 s time histories from that phase's
    state, kicked 2 % below and above it, end on the lateral and on the torsional cycle."""
    result = from_cycle.to_dict()
    origin = result["origin"]
    assert origin["kind"] == "standard_attractor" and origin["mode"] == "lateral" and origin["phases"] == 4
    assert origin["period_s"] == pytest.approx(0.0624, rel=0.02)
    modes = [a["mode"] for a in result["attractors"]]
    lateral, torsional = (result["attractors"][modes.index(m)] for m in ("lateral", "torsional"))
    assert lateral["min_disturbance"]["value"] == 0.0  # the origin's own attractor: the smallest kick stays there
    m = torsional["min_disturbance"]
    by_phase = {row["phase"]: row["value"] for row in m["by_phase"]}
    assert {0.0, 0.25, 0.5, 0.75} <= set(by_phase) and m["check"]["confirmed"]
    assert m["value"] == min(v for v in by_phase.values() if v is not None) == by_phase[m["phase"]]
    sampled = min(v for p, v in by_phase.items() if p in (0.0, 0.25, 0.5, 0.75) and v is not None)
    assert m["value"] <= sampled  # located between the sampled phases: no larger than the best of them
    step = 1 / 32
    neighbours = [by_phase.get(round((m["phase"] + s) % 1.0, 12)) for s in (-step, step)]
    assert all(v is not None and v >= m["value"] for v in neighbours)  # a local minimum to 1/32 of the period
    assert m["value"] > 0.05  # far above the 0.0165 rad from straight rolling: the lateral cycle holds
    base = np.array(m["origin_state"])
    assert abs(base[0]) <= 0.0293 * 1.02 and abs(base[2]) > 0.0  # a state on the lateral cycle
    for factor, expected in ((0.98, ResponseType.LATERAL), (1.02, ResponseType.TORSION)):
        x0 = base.copy()
        x0[0] += factor * m["value"]
        run = simulate("original", 50.0, 550e3, x0=list(x0), t_end=60.0)
        assert run.response_type is expected and run.steady, factor
    assert "from the lateral limit cycle the standard start reaches" in from_cycle.summary_text()


def test_the_orbit_kicked_is_a_cycle_of_the_attractor(from_cycle):
    """The states the kicks are added to lie on the lateral cycle: one period from each returns to it (within 2 % of
    the amplitude; the period is the mean spacing of the yaw maxima on the 1 ms samples), and their yaw angles
    reach the cycle's amplitude of the diagram."""
    from shimmy.analyses.maps.point_attractors import OrbitUnit
    from shimmy.model import integrator
    from shimmy.model.equations import build_model

    found = from_cycle.found
    unit = OrbitUnit(Configuration.ORIGINAL, 50.0, 550e3, Parameters(), (0.001, 0, 0, 0, 0), found.classifier,
                     found.standard, 80.0, 16)
    orbit = unit.run()
    states, period = orbit["states"], orbit["period"]
    assert orbit["settled"] and states.shape == (16, integrator.N_FULL)
    model = build_model(Configuration.ORIGINAL, Parameters())
    out = np.empty((2, integrator.N_FULL))
    scale = np.abs(states).max(axis=0)[:4]
    for x in states[::4]:
        integrator.integrate(x.copy(), period, period, 50.0, 550e3, model.coefficients, *model.flags, 1e-9, 1e-12,
                             10_000_000, out)
        assert np.all(np.abs(out[1, :4] - x[:4]) <= 0.02 * scale)
    assert states[0, 0] == pytest.approx(found.attractors[found.standard]["amplitude"]["psi"], rel=0.02)


def test_a_mix_along_one_component_is_that_component(yaw, pool):
    """A mix of one component is that component's direction: the same threshold, in J of the same energy, and as a
    multiple of the mix; a mix of two keeps its proportions at the threshold, confirmed by its check runs."""
    torsional = next(a for a in yaw.to_dict()["attractors"] if a["mode"] == "torsional")["min_disturbance"]
    mix = margins(*POINT, direction="mix", mix="psi=0.002", executor=pool).to_dict()
    m = next(a for a in mix["attractors"] if a["mode"] == "torsional")["min_disturbance"]
    assert m["unit"] == "J" and m["mix"] == "psi=0.002"
    assert m["equivalent_psi"] == pytest.approx(torsional["value"], rel=1e-12)
    assert m["factor"] == pytest.approx(torsional["value"] / 0.002, rel=1e-12)
    two = margins(*POINT, direction="mix", mix="dpsi=0.1, psi=0.01", executor=pool).to_dict()
    m = next(a for a in two["attractors"] if a["mode"] == "torsional")["min_disturbance"]
    assert two["options"]["mix"] == "psi=0.01,dpsi=0.1" and m["check"]["confirmed"]
    assert m["disturbance"]["dpsi"] == pytest.approx(10.0 * m["disturbance"]["psi"], rel=1e-12)
    assert m["disturbance"]["psi"] == pytest.approx(0.01 * m["factor"], rel=1e-12)


def test_where_the_standard_start_ends_on_straight_rolling_the_kicks_start_there(pool):
    """At a point where straight rolling is the standard start's attractor, origin standard_attractor is straight
    rolling, and says so: the same thresholds as from straight rolling."""
    point = ("original", 5.0, 150e3)  # below the first Hopf speed (6.7 m/s at 150 kN)
    plain = margins(*point, executor=pool).to_dict()
    assert next(a for a in plain["attractors"] if a["standard_start"])["mode"] == "equilibrium"
    kicked = margins(*point, origin="standard_attractor", executor=pool).to_dict()
    assert kicked["origin"]["kind"] == "straight_rolling" and "standard start ends on straight" in \
        kicked["origin"]["note"]
    assert [a["min_disturbance"]["value"] for a in kicked["attractors"]] == \
        [a["min_disturbance"]["value"] for a in plain["attractors"]]
