"""Disturbance margins, basin fractions and margin maps as service analyses: canonical requests, refusals by field, the
runner's answer (the package's, cached), the job over HTTP."""

from __future__ import annotations

import time

import pytest

from shimmy.analyses.core.executors import InlineExecutor
from shimmy.analyses.maps.margin_map import margin_map
from shimmy.analyses.maps.margins import margins
from shimmy.errors import InvalidParameterError
from shimmy.service import analyses, cache, schemas

POINT = {"config": "original", "V": 50, "Fz": 550000}
#: 2 x 2 cells centred on V 60 and 100 m/s, Fz 600 and 800 kN.
PLANE = {"config": "original", "v_min": 40, "v_max": 120, "fz_min": 500000, "fz_max": 900000, "n_v": 2, "n_fz": 2}


def test_canonical_requests_fill_the_defaults_of_the_analysis():
    a = schemas.validate("margins", POINT)
    b = schemas.validate("margins", {**POINT, "direction": "psi", "max_size": 0.4, "rtol": 0.005})
    assert a == b and cache.key("margins", a) == cache.key("margins", b)
    assert (a["direction"], a["max_size"], a["min_size"], a["scan_points"], a["rtol"], a["t_max"]) == \
        ("psi", 0.4, 0.001, 12, 0.005, 80.0)
    basin = schemas.validate("basins", POINT)
    assert (basin["radius"], basin["samples"], basin["seed"]) == (0.2, 200, 0)
    plane = schemas.validate("margin_map", {"config": "nes"})
    assert (plane["v_min"], plane["v_max"], plane["fz_min"], plane["fz_max"]) == (1.0, 200.0, 10e3, 900e3)
    assert (plane["n_v"], plane["n_fz"], plane["max_size"]) == (20, 10, 0.4)


@pytest.mark.parametrize("analysis, body, field, message", [
    ("margins", {"direction": "yaw"}, "direction", "unknown direction 'yaw'; allowed: one of psi, dpsi, delta"),
    ("margins", {"rtol": 0}, "rtol", r"allowed: a number in \[0.0001, 0.1\]"),
    ("margins", {"min_size": 0.05, "max_size": 0.01}, "min_size", "must be below max_size"),
    ("margins", {"scan_points": 100}, "scan_points", r"allowed: an integer in \[4, 40\]"),
    ("margins", {"max_size": "0.3"}, "max_size", "is not a number"),
    ("margins", {"V": 600}, "V", r"allowed: a number in \[1, 500\] m/s"),
    ("basins", {"samples": 1e6}, "samples", r"allowed: an integer in \[10, 5000\]"),
    ("basins", {"radius": 0}, "radius", r"allowed: a number in \[0.001, 1\] rad"),
    ("basins", {"kicks": 3}, "kicks", "unknown field"),
    ("margin_map", {"n_v": 1}, "n_v", r"allowed: an integer in \[2, 60\]"),
    ("margin_map", {"n_fz": 41}, "n_fz", r"allowed: an integer in \[2, 40\]"),
    ("margin_map", {"fz_min": 5e5, "fz_max": 4e5}, "fz_max", "must exceed fz_min"),
    ("margin_map", {"max_size": 0.001}, "max_size", r"allowed: a number in \[0.002, 1\] rad"),
    ("margin_map", {"V": 50}, "V", "unknown field"),
    ("simulate", {"x0": [0.1, 0, 0]}, "x0", "5 numbers for original"),
    ("simulate", {"x0": [2.5, 0, 0, 0, 0]}, "x0[0]", r"allowed: a number in \[-2, 2\] rad \(psi\)"),
    ("simulate", {"x0": [0.1, 0, 0.7, 0, 0]}, "x0[2]", r"l_g delta within \[-1.5, 1.5\] m"),
    ("simulate", {"x0": [0.1, 1e300, 0, 0, 0]}, "x0[1]", r"\[-100, 100\] rad/s \(dpsi\)"),
    ("simulate", {"config": "nes", "x0": [0.1, 0, 0, 0, 0, 0, -150]}, "x0[6]", r"\(dpsis\)"),
    ("simulate", {"x0": [0.1, 0, 0, 0, 2.0]}, "x0[4]", r"\[-1, 1\] m \(lam\)"),
    ("simulate", {"x0": [0.1, 0, 0, 0, 0], "lateral0": 0.1}, "lateral0", "is given together with x0"),
    ("simulate", {"x0": [0.1, None, 0, 0, 0]}, "x0[1]", "is not a number"),
])
def test_refusals_name_the_field(analysis, body, field, message):
    base = PLANE if analysis == "margin_map" else POINT
    with pytest.raises(InvalidParameterError, match=message) as info:
        schemas.validate(analysis, {**base, **body})
    assert info.value.field == field


def test_the_service_answer_is_the_package_answer_and_is_cached(tmp_path, monkeypatch):
    monkeypatch.setenv("SHIMMY_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("SHIMMY_WORKERS", "1")
    result, cached = analyses.run("margins", POINT)
    assert not cached
    direct = margins("original", 50.0, 550e3, executor=InlineExecutor()).to_dict()
    assert result["attractors"] == direct["attractors"]
    again, cached = analyses.run("margins", POINT)
    assert cached and again == result


def test_the_margin_map_of_the_service_is_the_package_map(tmp_path, monkeypatch):
    monkeypatch.setenv("SHIMMY_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("SHIMMY_WORKERS", "1")
    result, cached = analyses.run("margin_map", PLANE)
    assert not cached
    direct = margin_map("original", v_range=(40.0, 120.0), fz_range=(5e5, 9e5), n_v=2, n_fz=2,
                        executor=InlineExecutor()).to_dict()
    assert result["points"] == direct["points"] and result["counts"] == direct["counts"]
    assert analyses.run("margin_map", PLANE)[1]


def test_margins_and_basins_jobs_over_http(server):
    jobs = {}
    for analysis, extra in (("margins", {}), ("basins", {"samples": 20})):
        status, _, job = server.request("POST", "/api/v1/jobs", {"analysis": analysis, **POINT, **extra})
        assert status == 202, job
        jobs[analysis] = job
    deadline = time.time() + 180
    for analysis, job in jobs.items():
        while job["status"] in ("queued", "running") and time.time() < deadline:
            time.sleep(0.3)
            _, _, job = server.request("GET", f"/api/v1/jobs/{job['id']}")
        assert job["status"] == "done", job
        if "result" not in job:  # done at once (the server's cache had it): the POST's answer has no result
            _, _, job = server.request("GET", f"/api/v1/jobs/{job['id']}")
        jobs[analysis] = job["result"]
    torsional = next(a for a in jobs["margins"]["attractors"] if a["mode"] == "torsional")
    assert {"value", "unit", "direction", "method", "tolerance"} <= set(torsional["min_disturbance"])
    assert 0.0155 < torsional["min_disturbance"]["value"] < 0.0175
    assert sum(a["basin"]["count"] for a in jobs["basins"]["attractors"]) + jobs["basins"]["unsettled"] == 20
    status, _, answer = server.request("POST", "/api/v1/jobs", {"analysis": "margins", **POINT, "direction": "yaw"})
    assert status == 422 and answer["field"] == "direction"
    _, _, doc = server.request("GET", "/api/v1/openapi.json")
    props = doc["components"]["schemas"]["job_margins"]["properties"]
    assert props["direction"]["enum"][:6] == ["psi", "dpsi", "delta", "ddelta", "mix", "energy"]
    assert props["origin"]["enum"][:2] == ["straight_rolling", "standard_attractor"] and "mix" in props
    for body, field in (({"direction": "mix", "mix": "psi=0.01,yaw=1"}, "mix"), ({"direction": "mix"}, "mix"),
                        ({"mix": "psi=1"}, "mix"), ({"origin": "cycle"}, "origin"), ({"phases": 0}, "phases")):
        status, _, answer = server.request("POST", "/api/v1/jobs", {"analysis": "margins", **POINT, **body})
        assert status == 422 and answer["field"] == field, (body, answer)
    assert "job_basins" in doc["components"]["schemas"]
    props = doc["components"]["schemas"]["job_margin_map"]["properties"]
    assert (props["n_v"]["maximum"], props["n_fz"]["maximum"]) == (60, 40)


def test_a_margin_map_job_over_http(server):
    status, _, job = server.request("POST", "/api/v1/jobs", {"analysis": "margin_map", **PLANE})
    assert status == 202, job
    deadline = time.time() + 180
    while True:  # read at least once: the submission's answer has no result (done at once where another
        _, _, job = server.request("GET", f"/api/v1/jobs/{job['id']}")  # test on this server asked the same)
        if job["status"] not in ("queued", "running") or time.time() > deadline:
            break
        time.sleep(0.3)
    assert job["status"] == "done", job
    assert [p["V"] for p in job["result"]["points"]] == [60.0, 100.0, 60.0]
    status, _, answer = server.request("POST", "/api/v1/jobs", {"analysis": "margin_map", **PLANE, "n_v": 100})
    assert status == 422 and answer["field"] == "n_v"


def test_a_simulation_from_a_margins_check_state_ends_where_the_check_run_ended(tmp_path, monkeypatch):
    """A margin's check run starts from a whole state (``check.above.x0``: the orbit's state plus the kick); the
    time history from that ``x0`` (the workbench's Run from this kick) ends on the attractor the check ended on."""
    monkeypatch.setenv("SHIMMY_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("SHIMMY_WORKERS", "1")
    result, _ = analyses.run("margins", {**POINT, "origin": "standard_attractor", "phases": 2})
    torsional = next(a for a in result["attractors"] if a["mode"] == "torsional")["min_disturbance"]
    above = torsional["check"]["above"]
    assert above["mode"] == "torsional" and len(above["x0"]) == 5 and any(above["x0"][1:])
    run, _ = analyses.run("simulate", {**POINT, "x0": above["x0"], "t_end": 80})
    assert run["response_type"] == "Torsion" and run["start"]["x0"] == above["x0"]
    assert run["start"]["psi0"] == above["x0"][0] and run["start"]["lateral0"] == pytest.approx(2.5 * above["x0"][2])
