"""A yaw kick during a ground run: applied at its instant, placed by time or by speed, judged against the run
without it, refused by field."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from shimmy.analyses.ground.ground_profiles import preset, profile_from_table
from shimmy.analyses.ground.ground_run import ground_run, ground_runs
from shimmy.analyses.ground.kicks import KICK_PRESETS, Kick, kick_instant, outcome_text, scenario
from shimmy.analyses.maps.margins import margins
from shimmy.errors import InvalidParameterError
from shimmy.model.equations import build_model, jacobian
from shimmy.model.parameters import Parameters

STABLE = (20.0, 40e3)  # straight rolling of `original` stable (slowest decay 0.28 /s)
N = 5  # the states of `original`


def _constant(V: float, Fz: float, duration: float) -> list[list[float]]:
    return [[0.0, V, Fz], [duration, V, Fz]]


@pytest.mark.parametrize("t_kick", [1.0005, 1.001, 0.0])
def test_the_kick_is_a_jump_at_its_instant(t_kick):
    """From rest at a stable point the gear is linear: after a yaw-rate kick at t_k the states are
    exp(J (t - t_k)) times the jump, to the integrator's tolerance; the same kick at the nearest output
    sample would be 3 % off (the instant matters, and the run splits its integration there)."""
    V, Fz = STABLE
    size = 0.01
    run = ground_run("original", _constant(V, Fz, 4.0), x0=np.zeros(N),
                     kick={"kick": "dpsi", "kick_size": size, "kick_at_time": t_kick})
    assert run.success and run.kick["applied"] and run.kick["t"] == t_kick
    assert run.kick["state_before"] == {"psi": 0.0, "dpsi": 0.0}
    assert run.kick["state_after"] == {"psi": 0.0, "dpsi": size}
    after = run.t >= t_kick - 1e-12
    assert not np.any(run.states[:, ~after])  # nothing moves before the kick
    J = jacobian(build_model("original", Parameters()), np.zeros(N), V, Fz)
    jump = np.zeros(N)
    jump[1] = size

    def error(instant: float) -> float:
        exact = np.array([scipy.linalg.expm(J * (t - instant)) @ jump for t in run.t[after]]).T
        return float(np.max(np.abs(run.states[:, after] - exact).max(axis=1) / np.abs(exact).max(axis=1)))

    assert error(t_kick) < 3e-4
    if t_kick == 1.0005:  # off the output grid: at the next sample instead it would be plainly wrong
        assert error(1.001) > 0.02


def test_a_kick_on_a_stable_case_decays():
    run = ground_run("original", _constant(*STABLE, 30.0), kick={"kick": "psi", "kick_size": 0.05,
                                                                 "kick_at_time": 2.0})
    k = run.kick
    assert k["shimmy_started"] is False and k["mode"] == "none" and not k["in_shimmy_before"]
    assert k["without_kick"]["in_shimmy"] is False
    assert run.envelope_psi[-1] < 1e-5  # decayed from 0.05 rad (rate 0.28 /s)
    (interval,) = run.shimmy_intervals  # above the threshold only while the kick dies out
    assert interval["t_start"] == pytest.approx(2.0, abs=0.1) and 0 < k["extra_time_in_shimmy_s"] < 10
    assert "no shimmy started" in outcome_text(k)


def test_the_mode_started_agrees_with_the_margins_threshold():
    """At (50 m/s, 550 kN) `original` reaches lateral shimmy from a small yaw and torsional shimmy above the
    margin's threshold (0.0165 rad): a kick from rest at t = 0 on either side of it starts the same shimmy."""
    threshold = margins("original", 50.0, 550e3).attractors
    torsional = next(a for a in threshold if a["mode"] == "torsional")["min_disturbance"]
    for factor, mode in ((0.9, "lateral"), (1.1, "torsional")):
        run = ground_run("original", _constant(50.0, 550e3, 30.0), x0=np.zeros(N),
                         kick={"kick": "psi", "kick_size": factor * torsional["value"], "kick_at_time": 0.0})
        assert run.kick["shimmy_started"] is True and run.kick["mode"] == mode
        assert run.kick["without_kick"] == {"in_shimmy": False, "mode": "none",
                                            "amplitude": {"psi": 0.0, "lateral": 0.0}}


def test_a_kick_on_a_running_shimmy_is_judged_against_the_run_without_it():
    """From the standard start the gear is in lateral shimmy within half a second at (50 m/s, 550 kN): a yaw of
    0.05 rad then switches it to torsional shimmy; once the lateral cycle is grown, neither that yaw nor a far
    larger one moves it (back on the run without the kick)."""
    rows = _constant(50.0, 550e3, 30.0)
    early = ground_run("original", rows, kick={"kick": "psi", "kick_size": 0.05, "kick_at_time": 0.5}).kick
    assert early["in_shimmy_before"] and early["shimmy_started"] is True and early["mode"] == "torsional"
    assert early["without_kick"]["mode"] == "lateral" and early["peak"]["psi"] > 0.15
    for kick in ({"kick": "psi", "kick_size": 0.05}, {"kick": "dpsi", "kick_size": 30.0}):
        late = ground_run("original", rows, kick={**kick, "kick_at_time": 10.0}).kick
        assert late["in_shimmy_before"] and late["shimmy_started"] is False and late["mode"] == "none"
        assert late["without_kick"]["mode"] == "lateral" and late["t_judged"] <= 16.0


def test_at_speed_is_the_first_time_the_profile_reaches_it():
    takeoff = preset("takeoff")  # 5 m/s + 2.5 m/s^2 t
    assert kick_instant(Kick("dpsi", 1.0, at_speed=60.0), takeoff) == pytest.approx(22.0, abs=1e-12)
    assert kick_instant(Kick("dpsi", 1.0, at_speed=61.3), takeoff) == pytest.approx(22.52, abs=1e-12)
    landing = preset("landing")  # 65 m/s - 2.5 m/s^2 t
    assert kick_instant(Kick("psi", 0.01, at_speed=40.0), landing) == pytest.approx(10.0, abs=1e-12)
    assert kick_instant(Kick("psi", 0.01, at_speed=65.0), landing) == 0.0
    table = profile_from_table([[100.0, 10.0, 1e5], [110.0, 30.0, 1e5], [120.0, 10.0, 1e5], [130.0, 30.0, 1e5]])
    assert kick_instant(Kick("psi", 0.01, at_speed=20.0), table) == pytest.approx(105.0)  # the first of three
    assert kick_instant(Kick("psi", 0.01, at_time=117.5), table) == 117.5  # the profile's clock
    run = ground_run("original", table, kick={"kick": "dpsi", "kick_size": 2.0, "kick_at_speed": 20.0})
    assert run.kick["t"] == pytest.approx(105.0) and run.kick["V"] == pytest.approx(20.0)
    assert run.kick["state_after"]["dpsi"] - run.kick["state_before"]["dpsi"] == pytest.approx(2.0)
    i = int(np.searchsorted(run.t, 105.0))  # the sample at 105 s is the first with the kick
    assert run.t[i] == pytest.approx(105.0) and run.states[1, i] == pytest.approx(run.kick["state_after"]["dpsi"])


def test_scenarios_are_presets_with_a_kick():
    assert set(KICK_PRESETS) == {"runway_joint", "touchdown_yaw"}
    joint = ground_run("nes", "runway_joint")
    assert joint.profile.name == "takeoff" and joint.kick["kind"] == "dpsi" and joint.kick["at_speed"] == 60.0
    assert joint.kick["t"] == pytest.approx(22.0) and joint.kick["shimmy_started"] is not None
    touchdown = ground_run("original", "touchdown_yaw")
    assert touchdown.profile.name == "landing" and touchdown.kick["t"] == 0.0
    assert touchdown.states[0, 0] == pytest.approx(0.001 + 0.05)  # the standard start, yawed at touchdown
    # fields given for a scenario take the place of its own: the size alone, or the instant as a whole
    assert scenario("runway_joint", {"kick_size": 2.0}) == ("takeoff", {"kick": "dpsi", "kick_size": 2.0,
                                                                        "kick_at_time": None, "kick_at_speed": 60.0})
    assert scenario("runway_joint", {"kick_at_time": 5.0})[1]["kick_at_speed"] is None
    comparison = ground_runs("runway_joint", configs=["original", "nes"])
    rows = comparison.table()
    assert all(r["kick_mode"] in ("none", "torsional", "lateral", "both") for r in rows)
    assert "kick dpsi +1 rad/s at t = 22 s" in comparison.summary_text()
    assert comparison.to_dict(include_series=False)["runs"]["nes"]["kick"]["at_speed"] == 60.0


@pytest.mark.parametrize("kick, field, message", [
    ({"kick": "yaw", "kick_size": 0.1, "kick_at_time": 1.0}, "kick", "unknown kick 'yaw'"),
    ({"kick": "psi", "kick_size": 0.6, "kick_at_time": 1.0}, "kick_size",
     r"kick_size=0.6 is out of range; allowed: a number in \[-0.5, 0.5\] rad \(a kick in psi"),
    ({"kick": "dpsi", "kick_size": -60, "kick_at_time": 1.0}, "kick_size",
     r"kick_size=-60 is out of range; allowed: a number in \[-50, 50\] rad/s \(a kick in dpsi"),
    ({"kick": "psi", "kick_size": float("nan"), "kick_at_time": 1.0}, "kick_size", "is not finite"),
    ({"kick": "psi", "kick_at_time": 1.0}, "kick_size", "kick_size is required with a kick"),
    ({"kick": "psi", "kick_size": 0.1}, "kick_at_time", "neither given"),
    ({"kick": "psi", "kick_size": 0.1, "kick_at_time": 1.0, "kick_at_speed": 30.0}, "kick_at_time",
     "both kick_at_time and kick_at_speed given"),
    ({"kick_size": 0.1}, "kick_size", "kick_size=0.1 is given without a kick"),
    ({"kick": "psi", "kick_size": 0.1, "kick_at_time": 30.0}, "kick_at_time",
     r"kick_at_time=30 s is outside the takeoff profile's run; allowed: a time within the run: \[0, 30\) s"),
    ({"kick": "psi", "kick_size": 0.1, "kick_at_speed": 90.0}, "kick_at_speed",
     r"kick_at_speed=90 m/s is never reached by the takeoff profile; allowed: a speed the run reaches: \[5, 80\]"),
    ({"kick": "psi", "kick_size": 0.1, "kick_at_speed": 80.0}, "kick_at_speed", "only at its last row"),
    ({"kick": "psi", "kick_size": 0.1, "kick_at_speed": 600.0}, "kick_at_speed", r"\[1, 500\] m/s"),
])
def test_bad_kicks_are_refused_naming_the_field(kick, field, message):
    with pytest.raises(InvalidParameterError, match=message) as err:
        ground_run("original", "takeoff", kick=kick)
    assert err.value.field == field
