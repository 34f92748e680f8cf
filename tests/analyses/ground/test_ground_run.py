"""Ground runs: non-autonomous histories with V(t), Fz(t) from a profile, and what they report."""

from __future__ import annotations

import numpy as np
import pytest

import shimmy
from shimmy.analyses.diagrams.bifurcation import bifurcation
from shimmy.analyses.ground.ground_profiles import (MAX_PROFILE_POINTS, PRESETS, preset, preset_fields,
                                                   profile_from_table)
from shimmy.analyses.ground.ground_run import GroundRunOptions, _segment_hits, ground_run, ground_runs
from shimmy.analyses.diagrams.hopf_curves import FZ_SCALE, V_SCALE, hopf_curves
from shimmy.analyses.core.polylines import near_polyline
from shimmy.analyses.core.response import peak_amplitude
from shimmy.errors import InvalidParameterError

CONFIGS = ["original", "nes", "pd", "nes_pd"]


@pytest.mark.parametrize("config", CONFIGS)
def test_a_constant_profile_reproduces_simulate(config):
    reference = shimmy.simulate(config, 30.0, 150e3)
    for start in (0.0, 100.0):  # the profile's clock may start anywhere
        run = ground_run(config, [[start, 30.0, 150e3], [start + 60.0, 30.0, 150e3]])
        assert run.success and run.states.shape == reference.states.shape
        assert np.allclose(run.t - start, reference.t, rtol=0, atol=1e-9)
        scale = np.abs(reference.states).max(axis=1, keepdims=True)
        assert np.max(np.abs(run.states - reference.states) / scale) <= 1e-6
    # interior table points cut the steps (no step crosses a kink): the history agrees to the tolerance
    run = ground_run(config, [[0, 30.0, 150e3], [17.3, 30.0, 150e3], [40.0, 30.0, 150e3], [60.0, 30.0, 150e3]])
    window = run.t >= 40.0
    # table points closer together than a step can resolve are passed, not stepped to
    close = ground_run(config, [[0, 30.0, 150e3], [16.0, 30.0, 150e3], [16.0 + 4e-15, 30.0, 150e3],
                                [16.0 + 1e-13, 30.0, 150e3], [60.0, 30.0, 150e3]])
    assert close.success
    assert peak_amplitude(close.psi[window]) == pytest.approx(reference.amplitude["psi"], rel=1e-6)
    assert peak_amplitude(run.psi[window]) == pytest.approx(reference.amplitude["psi"], rel=1e-6)
    assert peak_amplitude(run.lateral[window]) == pytest.approx(reference.amplitude["lateral"], rel=1e-6)


@pytest.fixture(scope="module")
def original_branch():
    """The periodic branch of `original` from its lower (supercritical) Hopf point at 150 kN."""
    diagram = bifurcation("original", 150e3, v_range=(5.0, 16.0))
    branch = next(b for b in diagram.branches if b.kind == "periodic")
    order = np.argsort(branch.V)
    assert np.all(np.asarray(branch.stable)[order])
    return np.asarray(branch.V)[order], np.asarray(branch.max_psi)[order]


@pytest.mark.slow
def test_a_slow_ramp_through_a_supercritical_hopf_point_follows_the_periodic_branch(original_branch):
    hopf = shimmy.hopf_points("original", 150e3, v_range=(1, 50)).hopf_points[0]
    assert hopf.criticality.value == "supercritical" and hopf.V == pytest.approx(5.6118, abs=1e-3)
    run = ground_run("original", [[0.0, 5.0, 150e3], [900.0, 14.0, 150e3]])  # 0.01 m/s^2
    assert run.success
    V, amplitude = original_branch
    for v in (8.0, 10.0, 12.0, 13.5):  # well past the delayed onset
        i = int(np.searchsorted(run.V, v))
        assert run.envelope_psi[i] == pytest.approx(np.interp(v, V, amplitude), rel=0.02)
    (crossing,) = run.boundary_crossings
    assert crossing["V"] == pytest.approx(hopf.V, abs=1e-5) and crossing["direction"] == "destabilising"


def test_faster_ramps_delay_the_onset_more():
    onset_speeds, delays = [], []
    for rate in (0.05, 0.2, 1.0):  # m/s^2, from 5 to 14 m/s at 150 kN
        run = ground_run("original", [[0.0, 5.0, 150e3], [9.0 / rate, 14.0, 150e3]])
        (onset,) = run.onsets
        assert onset["crossed"] and onset["V_unstable"] == pytest.approx(5.6118, abs=1e-3)
        onset_speeds.append(onset["V_onset"])
        delays.append(run.onset_delay_s)
    assert onset_speeds[0] < onset_speeds[1] < onset_speeds[2]  # further past the static Hopf point
    assert all(d > 0 for d in delays)
    assert onset_speeds[0] > 5.6118 + 0.3  # the delay is real even at the slowest of these ramps


@pytest.mark.parametrize("config", ["original", "nes"])
@pytest.mark.parametrize("name", ["takeoff", "landing"])
def test_crossings_agree_with_the_hopf_curves(config, name):
    profile = preset(name)
    run = ground_run(config, profile)
    curves = hopf_curves(config, v_range=(1.0, 200.0))
    scale = np.array([V_SCALE, FZ_SCALE])
    path = np.column_stack([profile.V, profile.Fz]) / scale
    expected = sum(len(_segment_hits(path[j], path[j + 1], c.p / scale)) for c in curves.curves
                   for j in range(len(path) - 1))
    assert expected >= 1 and len(run.boundary_crossings) == expected
    for crossing in run.boundary_crossings:
        q = np.array([crossing["V"], crossing["Fz"]]) / scale
        assert any(near_polyline(c.p / scale, q) is not None for c in curves.curves)  # on a continued curve
        # and exactly on the Hopf curve: straight rolling has a Hopf point there at that load
        at_load = shimmy.hopf_points(config, crossing["Fz"], v_range=(1.0, 200.0)).hopf_points
        assert min(abs(h.V - crossing["V"]) for h in at_load) < 1e-6
        V, Fz = profile.at(crossing["t"])
        assert (V, Fz) == pytest.approx((crossing["V"], crossing["Fz"]))


def test_takeoff_report_invariants():
    run = ground_run("original", "takeoff")
    assert run.success and run.profile.name == "takeoff"
    t, dt = run.t, run.options.dt_out
    assert t[0] == 0.0 and t[-1] == pytest.approx(30.0)
    assert run.V[0] == 5.0 and run.V[-1] == pytest.approx(80.0) and run.Fz[-1] == pytest.approx(20e3)
    assert np.all(run.envelope_psi >= np.abs(run.psi)) and np.all(run.envelope_lateral >= np.abs(run.lateral))
    assert run.peak_psi["value"] == pytest.approx(np.abs(run.psi).max())
    i = int(np.argmax(np.abs(run.psi)))
    assert (run.peak_psi["t"], run.peak_psi["V"]) == (t[i], run.V[i])
    total = sum(iv["duration_s"] for iv in run.shimmy_intervals)
    assert run.time_in_shimmy_s == pytest.approx(total) and 0 < total < t[-1]
    assert run.speed_range[0] >= 5.0 and run.speed_range[1] <= 80.0
    # the onset follows the crossing into the unstable region, and the amplitude is above threshold then
    onset = run.onsets[0]
    assert onset["t_onset"] == pytest.approx(onset["t_unstable"] + run.onset_delay_s)
    j = int(np.searchsorted(t, onset["t_onset"]))
    assert abs(run.psi[j]) > 0.01 or abs(run.lateral[j]) > 0.001
    assert np.all(np.abs(run.psi[t < onset["t_onset"] - dt]) <= 0.01)
    # a higher threshold: less time in shimmy
    higher = ground_run("original", "takeoff", psi_threshold=0.05, lateral_threshold=0.01)
    assert higher.time_in_shimmy_s < run.time_in_shimmy_s


def test_json_keys_of_a_run():
    out = ground_run("nes", "landing").to_dict(series_stride=10)
    for key in ("t", "V", "Fz", "psi", "lateral", "envelope_psi", "envelope_lateral", "time_in_shimmy_s",
                "peak_psi", "peak_lateral", "boundary_crossings", "onset_delay_s", "psis", "nes_relative"):
        assert key in out, key
    assert set(out["boundary_crossings"][0]) >= {"t", "V", "Fz", "curve"}
    assert len(out["t"]) == len(out["psi"]) == len(out["envelope_psi"])
    import json

    json.dumps(out, allow_nan=False)


def test_four_configuration_comparison():
    comparison = ground_runs("takeoff")
    rows = {r["config"]: r for r in comparison.table()}
    assert list(rows) == CONFIGS
    assert rows["original"]["peak_psi_ratio"] == 1.0 and rows["original"]["time_in_shimmy_change_s"] == 0.0
    # the devices cut the torsional peak; the particle damper by about an order of magnitude
    assert rows["nes"]["peak_psi_ratio"] < 1.0 and rows["pd"]["peak_psi_ratio"] < 0.2
    assert rows["nes_pd"]["time_in_shimmy_s"] < rows["original"]["time_in_shimmy_s"]


def test_presets_state_their_assumptions_and_take_settings():
    for name in PRESETS:
        p = preset(name)
        assert p.assumptions and p.settings and len(p.t) >= 2
        assert {f["name"] for f in preset_fields(name)} == set(p.settings)
    p = preset("takeoff", {"V_rotate": 70.0, "acceleration": 2.0})
    assert p.V[-1] == pytest.approx(70.0) and p.duration == pytest.approx(32.5)
    landing = preset("landing")
    assert landing.Fz[0] == pytest.approx(40e3) and landing.Fz[-1] > landing.Fz[0]
    assert landing.V[-1] == pytest.approx(8.0)
    taxi = preset("taxi", {"load_variation": 0.1})
    assert taxi.Fz.max() == pytest.approx(165e3, rel=1e-2) and taxi.duration == 60.0  # sampled every 0.5 s
    with pytest.raises(InvalidParameterError, match=r"V_rotate=10.0 is out of range; allowed: a number in \[20, 150"):
        preset("takeoff", {"V_rotate": 10.0})
    with pytest.raises(InvalidParameterError, match="unknown takeoff setting 'V_rotat'.*did you mean V_rotate") as e:
        preset("takeoff", {"V_rotat": 70.0})
    assert e.value.field == "preset_options.V_rotat"
    with pytest.raises(InvalidParameterError, match="must exceed V_start; allowed: a number above V_start = 45") as e:
        preset("takeoff", {"V_start": 45.0, "V_rotate": 40.0})
    assert e.value.field == "preset_options.V_rotate"
    with pytest.raises(InvalidParameterError, match="unknown preset 'take-off'"):
        preset("take-off")


GOOD = [[0.0, 10.0, 150e3], [10.0, 20.0, 120e3], [20.0, 30.0, 100e3]]


def _with(row: int, column: int, value):
    rows = [list(r) for r in GOOD]
    rows[row][column] = value
    return rows


@pytest.mark.parametrize("rows, field, message", [
    (_with(1, 0, 0.0), "profile[1].t", r"profile\[1\].t=0.0 \(row 2 of the table\) does not increase; allowed: "
                                       r"a time above the previous row's t = 0 s"),
    (_with(2, 0, 5.0), "profile[2].t", r"\(row 3 of the table\) does not increase"),
    (_with(2, 1, 600.0), "profile[2].V", r"profile\[2\].V=600.0 \(row 3 of the table\) is out of range; allowed: "
                                         r"a number in \[1, 500\] m/s"),
    (_with(0, 1, 0.5), "profile[0].V", r"\(row 1 of the table\) is out of range"),
    (_with(1, 2, 5e3), "profile[1].Fz", r"profile\[1\].Fz=5000.0 \(row 2 of the table\) is out of range; allowed: "
                                        r"a number in \[10000, 900000\] N"),
    (_with(1, 2, float("nan")), "profile[1].Fz", r"\(row 2 of the table\) is not finite"),
    (_with(0, 1, "fast"), "profile[0].V", r"\(row 1 of the table\) is not a number"),
    (_with(2, 0, None), "profile[2].t", r"\(row 3 of the table\) is not a number"),
    ([GOOD[0], [10.0, 20.0]], "profile[1]", r"\(row 2 of the table\) has 2 columns; allowed: 3 numbers"),
    ([GOOD[0]], "profile", r"profile has 1 row; allowed: 2 to 2000 rows"),
    ([[i * 0.1, 10.0, 1e5] for i in range(MAX_PROFILE_POINTS + 1)], "profile", "has 2001 rows"),
    ([[0.0, 10.0, 1e5], [4000.0, 10.0, 1e5]], "profile[1].t", r"makes the run 4000 s long"),
    ("not a table", "profile", "is not a table"),
])
def test_bad_profiles_are_refused_naming_the_row_and_column(rows, field, message):
    with pytest.raises(InvalidParameterError, match=message) as e:
        profile_from_table(rows)
    assert e.value.field == field
    with pytest.raises(InvalidParameterError, match=message):  # before any work
        ground_run("original", rows) if not isinstance(rows, str) else profile_from_table(rows)


def test_options_and_start_are_checked():
    with pytest.raises(InvalidParameterError, match=r"psi_threshold=0.0 is out of range; allowed: a number in "):
        GroundRunOptions(psi_threshold=0.0)
    with pytest.raises(InvalidParameterError, match="rtol"):
        GroundRunOptions(rtol=1.0)
    with pytest.raises(InvalidParameterError, match="x0.*has the wrong length"):
        ground_run("nes", GOOD, x0=[0.0] * 5)
    with pytest.raises(InvalidParameterError, match="preset_options.*only with a preset profile"):
        ground_run("nes", GOOD, preset_options={"V_rotate": 70.0})


def test_integration_failure_is_reported_with_the_part_computed():
    run = ground_run("original", "takeoff", max_steps=500)
    assert not run.success and "step budget" in run.message
    assert 0 < run.t.size < 30001 and run.t.size == run.envelope_psi.size


def _cli(*args):
    import subprocess
    import sys

    return subprocess.run([sys.executable, "-m", "shimmy", "ground-run", *args], capture_output=True, text=True,
                          timeout=120)


def test_command_line_json_csv_and_refusals(tmp_path):
    import json

    out = _cli("--config", "nes", "--profile", "takeoff", "--profile-set", "V_rotate=70", "--set", "e_p=0.002",
               "--json", "--csv", str(tmp_path / "run.csv"))
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    for key in ("t", "V", "Fz", "psi", "lateral", "envelope_psi", "envelope_lateral", "time_in_shimmy_s",
                "peak_psi", "peak_lateral", "boundary_crossings", "onset_delay_s"):
        assert key in data, key
    assert data["V"][-1] == pytest.approx(70.0) and data["params"]["e_p"] == 0.002
    assert data["t"][1] - data["t"][0] == pytest.approx(0.01)
    assert (tmp_path / "run.csv").read_text().startswith("t,V,Fz,psi,lateral,envelope_psi")
    table = tmp_path / "profile.csv"
    table.write_text("t,V,Fz\n# a ramp\n0,5,150000\n20,40,120000\n")
    out = _cli("--config", "all", "--profile", str(table))
    assert out.returncode == 0, out.stderr
    assert all(name in out.stdout for name in CONFIGS) and "crosses the hopf curve" in out.stdout
    table.write_text("t,V,Fz\n0,5,150000\n\n20,600,120000\n")
    out = _cli("--config", "nes", "--profile", str(table))
    assert out.returncode == 2
    assert "line 4: profile[1].V=600.0 (row 2 of the table) is out of range" in out.stderr
    out = _cli("--config", "nes", "--profile", "takeoff", "--profile-set", "V_rotate=200")
    assert out.returncode == 2 and "V_rotate=200 is out of range; allowed: a number in [20, 150] m/s" in out.stderr
    # a kick: a scenario, its size changed; a kick with a table
    out = _cli("--config", "original", "--profile", "touchdown_yaw", "--kick-size", "0.1", "--json")
    assert out.returncode == 0, out.stderr
    kick = json.loads(out.stdout)["kick"]
    assert (kick["kind"], kick["size"], kick["t"], kick["applied"]) == ("psi", 0.1, 0.0, True)
    table.write_text("t,V,Fz\n0,5,150000\n20,40,120000\n")
    out = _cli("--config", "all", "--profile", str(table), "--kick", "dpsi", "--kick-size", "3", "--kick-at-speed",
               "22.5")
    assert out.returncode == 0, out.stderr
    assert out.stdout.count("kick dpsi +3 rad/s at t = 10 s, V = 22.5 m/s: ") == 4


@pytest.mark.slow
def test_fold_and_torus_crossings_agree_with_the_one_parameter_diagram():
    """A taxi at 600 kN crosses the fold and torus curves of `original` (continued in two parameters) where the
    diagram in V at that load has its LPC and NS points."""
    run = ground_run("original", "taxi", preset_options={"Fz_static": 600e3}, cycle_curves=True)
    assert run.success and not run.warnings
    kinds = [c["curve"] for c in run.boundary_crossings]
    assert kinds.count("fold") == 2 and kinds.count("torus") == 2  # out on the way up and back on the way down
    diagram = bifurcation("original", 600e3, v_range=(1.0, 20.0))
    located = {"fold": [], "torus": []}
    for b in diagram.branches:
        for s in b.special_points:
            if s["kind"] in ("LPC", "NS"):
                located["fold" if s["kind"] == "LPC" else "torus"].append(s["V"])
    for c in run.boundary_crossings:
        assert c["Fz"] == pytest.approx(600e3)
        assert min(abs(v - c["V"]) for v in located[c["curve"]]) < 0.01 * c["V"]  # the polyline's chord error
