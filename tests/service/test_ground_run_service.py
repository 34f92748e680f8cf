"""The ground run as a service analysis: canonical requests, refusals by field, the job over HTTP."""

from __future__ import annotations

import time

import pytest

from shimmy.analyses.ground.ground_run import ground_run
from shimmy.errors import InvalidParameterError
from shimmy.service import analyses, cache, schemas


def test_canonical_requests_fill_the_preset_and_share_a_key():
    a = schemas.validate("ground_run", {"config": "nes", "preset": "landing"})
    b = schemas.validate("ground_run", {"config": "nes", "preset": "landing", "preset_options": {"V_touchdown": 65}})
    assert a == b and cache.key("ground_run", a) == cache.key("ground_run", b)
    assert a["preset_options"]["V_touchdown"] == 65.0 and a["profile"] is None and a["series_dt"] == 0.01
    table = schemas.validate("ground_run", {"config": "nes", "profile": [[0, 10, 150000], [10, 20, 150000]],
                                            "preset": "taxi"})
    assert table["preset"] is None and table["preset_options"] == {}
    assert table["profile"] == [[0.0, 10.0, 150000.0], [10.0, 20.0, 150000.0]]


@pytest.mark.parametrize("body, field, message", [
    ({"profile": [[0, 10, 150000], [0, 20, 150000]]}, "profile[1].t", r"\(row 2 of the table\) does not increase"),
    ({"profile": [[0, 10, 150000], [5, 20, 1e6]]}, "profile[1].Fz", r"\(row 2 of the table\) is out of range"),
    ({"profile": [[0, 10, 150000], [5, "20", 1e5]]}, "profile[1].V", r"\(row 2 of the table\) is not a number"),
    ({"profile": [[0, 10, 150000]]}, "profile", r"allowed: a list of 2 to 2000 rows"),
    ({"profile": "takeoff"}, "profile", r"allowed: a list of 2 to 2000 rows"),
    ({"profile": [[0, 10, 150000], [700, 20, 150000]]}, "profile", r"makes the run too long"),
    ({"profile": [[0, 10, 150000], [5, 20, 1e5]], "preset_options": {"V_rotate": 70}}, "preset_options",
     "is given with a profile table"),
    ({"preset": "cruise"}, "preset", "unknown preset 'cruise'"),
    ({"preset_options": {"V_rotat": 70}}, "preset_options.V_rotat", "did you mean V_rotate"),
    ({"preset_options": {"V_rotate": 300}}, "preset_options.V_rotate", r"allowed: a number in \[20, 150\] m/s"),
    ({"psi_threshold": 0}, "psi_threshold", r"allowed: a number in \[1e-06, 1\] rad"),
    ({"series_dt": 0.001, "preset": "taxi", "preset_options": {"duration": 600}}, "series_dt", "too many samples"),
])
def test_refusals_name_the_field(body, field, message):
    with pytest.raises(InvalidParameterError, match=message) as e:
        schemas.validate("ground_run", {"config": "original", **body})
    assert e.value.field == field


def test_a_kick_is_canonical_and_a_scenario_is_its_preset_with_its_kick():
    joint = schemas.validate("ground_run", {"config": "nes", "preset": "runway_joint"})
    plain = schemas.validate("ground_run", {"config": "nes", "preset": "takeoff", "kick": "dpsi", "kick_size": 1,
                                            "kick_at_speed": 60})
    assert joint == plain and cache.key("ground_run", joint) == cache.key("ground_run", plain)
    assert (joint["preset"], joint["kick"], joint["kick_size"], joint["kick_at_time"], joint["kick_at_speed"]) == \
        ("takeoff", "dpsi", 1.0, None, 60.0)
    moved = schemas.validate("ground_run", {"config": "nes", "preset": "runway_joint", "kick_at_time": 5})
    assert (moved["kick"], moved["kick_at_time"], moved["kick_at_speed"]) == ("dpsi", 5.0, None)
    none = schemas.validate("ground_run", {"config": "nes"})
    assert none["kick"] is None and none["kick_size"] is None
    text = schemas.SCHEMAS["ground_run"].openapi()
    assert text["properties"]["kick"]["enum"] == ["psi", "dpsi", None] and "kick_at_speed" in text["description"]


@pytest.mark.parametrize("body, field, message", [
    ({"kick": "psi", "kick_size": 0.7, "kick_at_time": 1}, "kick_size", r"\[-0.5, 0.5\] rad"),
    ({"kick": "dpsi", "kick_size": "2", "kick_at_time": 1}, "kick_size", "is not a number"),
    ({"kick": "dpsi", "kick_size": 2, "kick_at_time": 1, "kick_at_speed": 30}, "kick_at_time", "both"),
    ({"kick_at_speed": 30}, "kick_at_speed", "is given without a kick"),
    ({"kick": "dpsi", "kick_size": 2, "kick_at_speed": 100}, "kick_at_speed", r"never reached .* \[5, 80\] m/s"),
    ({"preset": "touchdown_yaw", "kick_at_time": 40}, "kick_at_time", r"outside the landing profile's run"),
    ({"preset": "runway_joint", "profile": [[0, 10, 150000], [10, 20, 150000]]}, "preset", "is a scenario"),
    ({"profile": [[0, 10, 150000], [10, 20, 150000]], "kick": "psi", "kick_size": 0.1, "kick_at_speed": 25},
     "kick_at_speed", r"never reached by the table profile; allowed: a speed the run reaches: \[10, 20\]"),
])
def test_kick_refusals_name_the_field(body, field, message):
    with pytest.raises(InvalidParameterError, match=message) as e:
        schemas.validate("ground_run", {"config": "original", **body})
    assert e.value.field == field


def test_the_service_result_is_the_package_result_with_the_hopf_curves(tmp_path, monkeypatch):
    monkeypatch.setenv("SHIMMY_CACHE_DIR", str(tmp_path))
    body = {"config": "pd", "preset": "takeoff", "preset_options": {"V_rotate": 70}, "hopf_curves": True,
            "series_dt": 0.02, "params": {"a_p": 0.8}}
    result, cached = analyses.run("ground_run", body)
    assert not cached
    from shimmy import Parameters

    direct = ground_run("pd", "takeoff", params=Parameters().with_overrides(a_p=0.8), preset_options={"V_rotate": 70})
    assert result["time_in_shimmy_s"] == direct.time_in_shimmy_s
    assert result["peak_psi"] == direct.peak_psi and result["onset_delay_s"] == direct.onset_delay_s
    assert len(result["t"]) == len(direct.t[::20]) and result["series_dt"] == pytest.approx(0.02)
    assert result["hopf_curves"] and all(len(c["V"]) == len(c["Fz"]) > 2 for c in result["hopf_curves"])
    again, cached = analyses.run("ground_run", body)
    assert cached and again == result
    kicked, _ = analyses.run("ground_run", {**body, "hopf_curves": False, "kick": "psi", "kick_size": 0.05,
                                            "kick_at_time": 3.0})
    direct = ground_run("pd", "takeoff", params=Parameters().with_overrides(a_p=0.8), preset_options={"V_rotate": 70},
                        kick={"kick": "psi", "kick_size": 0.05, "kick_at_time": 3.0})
    assert kicked["kick"] == direct.kick and kicked["kick"]["t"] == 3.0


def test_ground_run_job_over_http(server):
    body = {"analysis": "ground_run", "config": "nes_pd", "preset": "landing", "hopf_curves": True}
    status, _, job = server.request("POST", "/api/v1/jobs", body)
    assert status == 202, job
    deadline = time.time() + 120
    while job["status"] in ("queued", "running") and time.time() < deadline:
        time.sleep(0.2)
        _, _, job = server.request("GET", f"/api/v1/jobs/{job['id']}")
    assert job["status"] == "done", job
    result = job["result"]
    for key in ("t", "V", "Fz", "psi", "lateral", "envelope_psi", "envelope_lateral", "time_in_shimmy_s",
                "peak_psi", "peak_lateral", "boundary_crossings", "onset_delay_s", "hopf_curves"):
        assert key in result, key
    assert result["boundary_crossings"][0]["curve"] == "hopf"
    status, _, answer = server.request("POST", "/api/v1/jobs", {"analysis": "ground_run", "config": "nes",
                                                                "profile": [[0, 10, 150000], [5, 600, 150000]]})
    assert status == 422 and answer["field"] == "profile[1].V" and "row 2" in answer["error"]
    _, _, doc = server.request("GET", "/api/v1/openapi.json")
    assert "job_ground_run" in doc["components"]["schemas"]
    profile = doc["components"]["schemas"]["job_ground_run"]["properties"]["profile"]
    assert profile["maxItems"] == 2000 and profile["items"]["maxItems"] == 3


@pytest.mark.parametrize("body, field", [
    ({"preset_options": {"V_rotate": "70"}}, "preset_options.V_rotate"),
    ({"preset_options": {"V_rotate": 10 ** 400}}, "preset_options.V_rotate"),
    ({"preset_options": {"V_rotate": [70]}}, "preset_options.V_rotate"),
    ({"preset_options": "fast"}, "preset_options"),
    ({"profile": [[0, 10, 150000], [5, 10 ** 400, 1e5]]}, "profile[1].V"),
    ({"profile": [[0, 10, 150000], {"t": 5}]}, "profile[1]"),
    ({"profile": [[0, 10, 150000], 5]}, "profile[1]"),
    ({"profile": [[0, 10, 150000], [5, [10], 1e5]]}, "profile[1].V"),
])
def test_hostile_values_are_refused_by_name(body, field):
    with pytest.raises(InvalidParameterError) as e:
        schemas.validate("ground_run", {"config": "original", **body})
    assert e.value.field == field
    assert field.split(".")[-1].split("[")[0] in str(e.value)
