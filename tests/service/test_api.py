"""HTTP API against a real gunicorn server (2 workers, shared cache directory)."""

from __future__ import annotations

import concurrent.futures
import os
import signal
import time

import pytest
from conftest import process_group

OK_BODIES = {
    "/api/v1/simulate": {"config": "nes_pd", "V": 30, "Fz": 150000, "t_end": 20},
    "/api/v1/hopf": {"config": "nes", "Fz": 150000, "v_max": 200},
    "/api/v1/stability": {"Fz": 150000, "v_max": 200, "n_points": 50},
    "/api/v1/devices": {"v_max": 1.0},
}


def test_health_and_parameters(server):
    status, _, body = server.request("GET", "/api/v1/health")
    assert status == 200 and body["status"] == "ok"
    status, _, body = server.request("GET", "/api/v1/parameters")
    names = {p["name"] for p in body["parameters"]}
    assert status == 200 and {"r2", "e_p", "k_s", "r3", "a_p", "rho_p", "k_lam"} <= names
    r2 = next(p for p in body["parameters"] if p["name"] == "r2")
    assert (r2["low"], r2["high"], r2["unit"]) == (0.07, 0.09, "m")


def test_simulate_matches_the_package_and_is_cached(server):
    import shimmy

    body = {"config": "nes_pd", "V": 30, "Fz": 150000, "t_end": 20, "params": {"r2": 0.085}}
    status, headers, first = server.request("POST", "/api/v1/simulate", body)
    assert status == 200
    direct = shimmy.simulate("nes_pd", 30, 150000, params=shimmy.Parameters().with_overrides(r2=0.085), t_end=20)
    assert first["amplitude"]["psi"] == pytest.approx(direct.amplitude["psi"], rel=1e-12)
    status, headers, second = server.request("POST", "/api/v1/simulate", body)
    assert headers["X-Shimmy-Cache"] == "hit" and second == first
    # Same design said differently (default values spelled out) -> same cache entry.
    status, headers, _ = server.request("POST", "/api/v1/simulate", {**body, "params": {"r2": 0.085, "r3": 0.01}})
    assert headers["X-Shimmy-Cache"] == "hit"


def test_series_and_spectrum(server):
    status, _, body = server.request("POST", "/api/v1/simulate", {**OK_BODIES["/api/v1/simulate"],
                                                                  "include_series": True, "series_dt": 0.005})
    assert status == 200
    assert len(body["series"]["t"]) == pytest.approx(20 / 0.005 + 1, abs=1)
    assert body["spectrum"]["dominant_hz"] == pytest.approx(body["frequency_hz"])


# Bad inputs for every endpoint: (path, body or raw bytes, expected status, field named).
BAD = [
    (path, {**ok, **change}, status, field)
    for path, ok in OK_BODIES.items()
    for change, status, field in [
        ({"params": {"r2": 0.5}}, 422, "params.r2"),
        ({"params": {"nonsense": 1}}, 422, "params.nonsense"),
        ({"params": {"r2": "abc"}}, 422, "params.r2"),
        ({"params": 3}, 422, "params"),
        ({"material": "gold"}, 422, "material"),
        ({"surprise": 1}, 422, "surprise"),
    ]
] + [
    ("/api/v1/simulate", {"config": "nes_pd", "V": 30}, 422, "Fz"),
    ("/api/v1/simulate", {"config": "nes", "V": "fast", "Fz": 150000}, 422, "V"),
    ("/api/v1/simulate", {"config": "nes", "V": 1e6, "Fz": 150000}, 422, "V"),
    ("/api/v1/simulate", {"config": "nes", "V": 30, "Fz": 150000, "t_end": 1e5}, 422, "t_end"),
    ("/api/v1/simulate", {"config": "nes", "V": 30, "Fz": 150000, "t_end": 600, "include_series": True,
                          "series_dt": 0.001}, 422, "series_dt"),
    # a sampling interval off the 1 ms grid is refused, not rounded to it
    ("/api/v1/simulate", {"config": "nes", "V": 30, "Fz": 150000, "include_series": True, "series_dt": 0.0015}, 422,
     "series_dt"),
    ("/api/v1/jobs", {"analysis": "ground_run", "config": "nes", "series_dt": 0.0155}, 422, "series_dt"),
    # a key given twice: which value was meant? (the parser kept the last)
    ("/api/v1/hopf", b'{"Fz": 1, "config": "original", "Fz": 150000}', 400, "Fz"),
    ("/api/v1/simulate", b'{"config": "nes", "V": 30, "Fz": 150000, "params": {"r2": 0.08, "r2": 0.09}}', 400, "r2"),
    ("/api/v1/simulate", {"config": "nesx", "V": 30, "Fz": 150000}, 422, "config"),
    ("/api/v1/simulate", {"config": "nes", "V": True, "Fz": 150000}, 422, "V"),
    ("/api/v1/simulate", b'{"config": "nes", "V": NaN, "Fz": 150000}', 422, "V"),
    ("/api/v1/simulate", b'{"config": "nes", "V": 30, "Fz": Infinity}', 422, "Fz"),
    ("/api/v1/simulate", b'{"config": ', 400, "body"),
    ("/api/v1/simulate", b"[1, 2]", 400, "body"),
    ("/api/v1/simulate", b"", 400, "body"),
    ("/api/v1/simulate", b" " * 70000, 413, "body"),
    ("/api/v1/hopf", {"config": "nes", "Fz": 150000, "v_min": 100, "v_max": 50}, 422, "v_max"),
    ("/api/v1/hopf", {"Fz": 150000}, 422, "config"),
    # Each value in range, together off the NES track: the constraint names the field it blames.
    ("/api/v1/hopf", {"config": "nes", "Fz": 150000, "params": {"r1": 0.2, "r2": 0.07}}, 422, "params.r3"),
    ("/api/v1/stability", {"Fz": 150000, "n_points": 1e6}, 422, "n_points"),
    ("/api/v1/stability", {"Fz": 150000, "n_points": 20.5}, 422, "n_points"),
    ("/api/v1/devices", {"v_max": -1}, 422, "v_max"),
    ("/api/v1/jobs", {"config": "nes", "Fz": 150000}, 422, "analysis"),
    ("/api/v1/jobs", {"analysis": "dance"}, 422, "analysis"),
    ("/api/v1/jobs", {"analysis": "bifurcation", "config": "nes", "Fz": 150000, "ntst": 5000}, 422, "ntst"),
    ("/api/v1/jobs", {"analysis": "bifurcation", "config": "nes"}, 422, "Fz"),
    ("/api/v1/jobs", {"analysis": "hopf_curves", "config": "nes", "fz_min": 5e5, "fz_max": 1e5}, 422, "fz_max"),
    ("/api/v1/jobs", {"analysis": "simulate", "config": "nes", "V": 30, "Fz": 150000, "t_end": -1}, 422, "t_end"),
    ("/api/v1/jobs", {"analysis": "map", "config": "nes", "resolution": 500}, 422, "resolution"),
    ("/api/v1/jobs", {"analysis": "map", "config": "nes", "n_v": 5000}, 422, "n_v"),
    ("/api/v1/jobs", {"analysis": "map"}, 422, "config"),
    ("/api/v1/jobs", {"analysis": "map", "config": "nes", "fz_min": 5e5, "fz_max": 1e5}, 422, "fz_max"),
    ("/api/v1/jobs", {"analysis": "study", "values": [0.001]}, 422, "parameter"),
    ("/api/v1/jobs", {"analysis": "study", "parameter": "zeta", "values": [1]}, 422, "parameter"),
    ("/api/v1/jobs", {"analysis": "study", "parameter": "e_p"}, 422, "values"),
    ("/api/v1/jobs", {"analysis": "study", "parameter": "e_p", "values": []}, 422, "values"),
    ("/api/v1/jobs", {"analysis": "study", "parameter": "e_p", "values": 0.001}, 422, "values"),
    ("/api/v1/jobs", {"analysis": "study", "parameter": "e_p", "values": [0.001, 0.5]}, 422, "values[1]"),
    ("/api/v1/jobs", {"analysis": "study", "parameter": "e_p", "values": [0.001, "x"]}, 422, "values[1]"),
    ("/api/v1/jobs", {"analysis": "study", "parameter": "e_p", "values": [0.001] * 51}, 422, "values"),
    ("/api/v1/jobs", {"analysis": "study", "parameter": "e_p", "values": [0.001], "configs": ["nes", "x"]}, 422,
     "configs[1]"),
    ("/api/v1/jobs", {"analysis": "study", "parameter": "e_p", "values": [0.001], "parameter2": "k_s"}, 422,
     "values2"),
    ("/api/v1/jobs", {"analysis": "study", "parameter": "e_p", "values": [0.001] * 20, "parameter2": "k_s",
                      "values2": [1.2e6] * 20}, 422, "values"),
    # Sensitivities, optimiser, robustness (issue 16): refused before any job is queued.
    ("/api/v1/sensitivity", {"config": "nes", "names": ["r2", "zeta"]}, 422, "names[1]"),
    ("/api/v1/sensitivity", {"config": "nes", "Fz": 5}, 422, "Fz"),
    ("/api/v1/jobs", {"analysis": "sensitivity", "config": "nes", "amplitude": "yes"}, 422, "amplitude"),
    ("/api/v1/jobs", {"analysis": "optimise", "config": "nes", "objective": "speed"}, 422, "objective"),
    ("/api/v1/jobs", {"analysis": "optimise", "config": "nes", "parameters": ["e_p", "zeta"]}, 422, "parameters[1]"),
    ("/api/v1/jobs", {"analysis": "optimise", "config": "nes", "parameters": ["a_p"]}, 422, "parameters[0]"),
    ("/api/v1/jobs", {"analysis": "optimise", "config": "original"}, 422, "parameters"),
    ("/api/v1/jobs", {"analysis": "optimise", "config": "nes", "constraints": ["max_psi=0.02"]}, 422,
     "constraints[0]"),
    ("/api/v1/jobs", {"analysis": "optimise", "config": "nes", "constraints": ["max_psy<=0.02"]}, 422,
     "constraints[0].figure"),
    ("/api/v1/jobs", {"analysis": "optimise", "config": "nes", "constraints": ["max_psi<=0.02", "max_psi<=7"]}, 422,
     "constraints[1].value"),
    ("/api/v1/jobs", {"analysis": "optimise", "config": "nes",
                      "constraints": [{"figure": "max_psi", "op": "<", "value": 0.1}]}, 422, "constraints[0].op"),
    ("/api/v1/jobs", {"analysis": "optimise", "config": "nes", "constraints": "max_psi<=0.02"}, 422, "constraints"),
    ("/api/v1/jobs", {"analysis": "optimise", "config": "nes", "starts": 2, "local_runs": 3}, 422, "local_runs"),
    ("/api/v1/jobs", {"analysis": "optimise", "config": "nes", "objective": "torsion_area", "method": "gradient"},
     422, "method"),
    ("/api/v1/jobs", {"analysis": "robustness", "config": "nes"}, 422, "tolerances"),
    ("/api/v1/jobs", {"analysis": "robustness", "config": "nes", "tolerances": ["k_lam=0.8"]}, 422,
     "tolerances[0].relative"),
    ("/api/v1/jobs", {"analysis": "robustness", "config": "nes", "tolerances": ["k_lam=0.05", "zeta=0.1"]}, 422,
     "tolerances[1].name"),
    ("/api/v1/jobs", {"analysis": "robustness", "config": "nes", "tolerances": ["k_lam"]}, 422, "tolerances[0]"),
    ("/api/v1/jobs", {"analysis": "robustness", "config": "nes",
                      "tolerances": [{"name": "k_s", "relative": 0.05, "distribution": "gauss"}]}, 422,
     "tolerances[0].distribution"),
    ("/api/v1/jobs", {"analysis": "robustness", "config": "nes", "tolerances": ["k_lam=0.05"], "samples": 10 ** 6},
     422, "samples"),
    # A disturbance in the robustness, a kick in a ground run (issue 29).
    ("/api/v1/jobs", {"analysis": "robustness", "config": "nes", "tolerances": ["k_lam=0.05"], "disturbance": 5},
     422, "disturbance"),
    ("/api/v1/jobs", {"analysis": "robustness", "config": "nes", "tolerances": ["k_lam=0.05"], "disturbance": 0.1,
                      "samples": 512}, 422, "samples"),
    ("/api/v1/jobs", {"analysis": "ground_run", "config": "nes", "kick": "psi", "kick_size": 0.7,
                      "kick_at_time": 1}, 422, "kick_size"),
    ("/api/v1/jobs", {"analysis": "ground_run", "config": "nes", "preset": "landing", "kick": "dpsi", "kick_size": 1,
                      "kick_at_speed": 100}, 422, "kick_at_speed"),
]


@pytest.mark.parametrize("path,body,status,field", BAD, ids=[f"{p}-{f}-{i}" for i, (p, _, _, f) in enumerate(BAD)])
def test_bad_input_gets_4xx_naming_the_field(server, path, body, status, field):
    raw = body if isinstance(body, bytes) else None
    got, _, answer = server.request("POST", path, None if raw is not None else body, raw=raw)
    assert got == status, answer
    assert answer["field"] == field
    assert set(answer) == {"error", "field", "allowed"} and answer["allowed"]
    assert field.split(".")[-1] in answer["error"] or field == "body"


def test_unknown_paths_methods_and_jobs(server):
    for path in ("/api/v1/nothing", "/api/v1", "/api/v1/"):  # the bare prefix too (it was the workbench's page)
        status, _, body = server.request("GET", path)
        assert status == 404 and body["field"] == "path", (path, body)
    for limit in ("%C2%B2", "%EF%BC%95", "0", "1001", "5x"):  # "²" and "５" are digits to str.isdigit (a 500)
        status, _, body = server.request("GET", f"/api/v1/jobs?limit={limit}")
        assert status == 422 and body["field"] == "limit", (limit, body)
    # a misspelt or repeated query parameter is refused, not left at its default or taken once
    status, _, body = server.request("GET", "/api/v1/jobs?limt=5")
    assert status == 422 and body["field"] == "query parameter" and "did you mean limit" in body["error"], body
    status, _, body = server.request("GET", "/api/v1/jobs?status=done&status=foo")
    assert status == 422 and body["field"] == "status" and "2 times" in body["error"], body
    status, _, body = server.request("GET", "/api/v1/jobs?status=done&limit=5")
    assert status == 200 and len(body["jobs"]) <= 5, body
    # where an endpoint takes no query parameter, one is refused, not ignored (the body says the analysis)
    for method, path, sent in (("POST", "/api/v1/hopf?config=nes", {"config": "original"}),
                               ("GET", "/api/v1/parameters?name=r2", None), ("GET", "/api/v1/jobs/abc?x=1", None),
                               ("POST", "/api/v1/jobs?analysis=map", {"analysis": "map", "config": "nes"})):
        status, _, body = server.request(method, path, sent)
        assert status == 422 and body["field"] == "query parameter" and body["allowed"] == "none", (path, body)
        assert repr(path.split("?")[1].split("=")[0]) in body["error"], body
    status, _, body = server.request("GET", "/api/v1/health?probe=1")  # a probe may stamp its request
    assert status == 200 and body["status"] == "ok"
    status, _, body = server.request("GET", "/api/v1/nothing?x=1")
    assert status == 404 and body["field"] == "path"
    status, headers, body = server.request("GET", "/api/v1/simulate")
    assert status == 405 and body["allowed"] == "POST" and headers["Allow"] == "POST"
    status, headers, body = server.request("PUT", "/api/v1/jobs/abc", {})
    assert status == 405 and headers["Allow"] == "DELETE, GET"
    status, _, body = server.request("GET", "/api/v1/jobs/doesnotexist")
    assert status == 404 and body["field"] == "id"
    status, _, body = server.request("DELETE", "/api/v1/jobs/doesnotexist")
    assert status == 404


def test_openapi_document_lists_every_endpoint_and_field(server):
    status, _, doc = server.request("GET", "/api/v1/openapi.json")
    assert status == 200 and doc["openapi"].startswith("3.")
    assert {"/health", "/parameters", "/simulate", "/hopf", "/sensitivity", "/jobs", "/jobs/{id}"} <= set(doc["paths"])
    schemas = doc["components"]["schemas"]
    assert {"job_sensitivity", "job_optimise", "job_robustness"} <= set(schemas)
    assert {"sensitivity", "optimise", "robustness"} <= set(schemas["Job"]["properties"]["analysis"]["enum"])
    tolerances = schemas["job_robustness"]["properties"]["tolerances"]
    assert tolerances["type"] == "array" and tolerances["minItems"] == 1 and "oneOf" in tolerances["items"]
    assert schemas["job_optimise"]["properties"]["objective"]["enum"][:-1] == ["min_shimmy_Fz", "interval", "max_psi",
                                                                              "torsion_area"]
    sim = doc["components"]["schemas"]["simulate_request"]
    assert sim["properties"]["V"]["minimum"] == 1 and sim["properties"]["V"]["maximum"] == 500
    assert set(sim["required"]) == {"config", "V", "Fz"}


def test_forty_concurrent_requests_all_answered(server):
    bodies = [{"config": c, "V": v, "Fz": 150000, "t_end": 5} for c in ("original", "nes", "pd", "nes_pd")
              for v in (10, 20, 30, 40, 50)]
    bodies += bodies  # half of them repeat: cache hits under concurrency

    def one(body):
        return server.request("POST", "/api/v1/simulate", body, timeout=120)

    with concurrent.futures.ThreadPoolExecutor(40) as pool:
        answers = list(pool.map(one, bodies))
    assert len(answers) == 40 and all(status == 200 for status, _, _ in answers)
    by_key = {}
    for body, (_, _, result) in zip(bodies, answers, strict=True):
        by_key.setdefault((body["config"], body["V"]), set()).add(result["amplitude"]["psi"])
    assert all(len(v) == 1 for v in by_key.values())


def _wait(server, job_id, until=("done", "failed", "cancelled"), timeout=120):
    seen = []
    deadline = time.time() + timeout
    while time.time() < deadline:
        _, _, job = server.request("GET", f"/api/v1/jobs/{job_id}")
        seen.append((job["status"], job["progress"]))
        if job["status"] in until:
            return job, seen
        time.sleep(0.2)
    raise AssertionError(f"job {job_id} still {seen[-1]} after {timeout} s")


#: a question no other test on the shared server asks (the workbench's diagram of `original` at 150 kN is at
#: ntst 40): its job is computed here, queued and running, not answered from the cache
FRESH_DIAGRAM = {"analysis": "bifurcation", "config": "original", "Fz": 150000, "v_min": 1, "v_max": 200, "ntst": 41}


def test_job_runs_to_completion_with_progress_and_is_cached(server):
    body = FRESH_DIAGRAM
    status, headers, job = server.request("POST", "/api/v1/jobs", body)
    assert status == 202 and job["status"] in ("queued", "running") and headers["Location"].endswith(job["id"])
    done, seen = _wait(server, job["id"])
    assert done["status"] == "done" and done["progress"] == 1.0
    assert done["result"]["max_psi"] == pytest.approx(0.2148, abs=1e-3)
    progress = [p for s, p in seen if s == "running"]
    assert progress == sorted(progress)  # monotone
    # The same request again: done at once from the cache.
    status, _, again = server.request("POST", "/api/v1/jobs", body)
    assert status == 202 and again["status"] == "done"


def test_map_and_study_jobs_give_what_the_package_gives(server):
    from shimmy.analyses.maps.stability_map import stability_map
    from shimmy.analyses.decisions.studies import study

    body = {"analysis": "map", "config": "original", "fz_min": 100000, "fz_max": 400000, "resolution": 4,
            "n_v": 20}
    _, _, job = server.request("POST", "/api/v1/jobs", body)
    done, seen = _wait(server, job["id"])
    assert done["status"] == "done", done
    result = done["result"]
    local = stability_map("original", v_range=(1, 200), fz_range=(1e5, 4e5), resolution=4, n_v=20)
    assert result["types"] == local.types and result["min_shimmy_Fz"] == pytest.approx(local.min_shimmy_Fz)
    assert result["metrics"]["torsion_area"] > 0
    assert len({p for s, p in seen if s == "running"}) >= 2  # progress per finished slice

    body = {"analysis": "study", "parameter": "e_p", "values": [0.0005, 0.005], "configs": ["nes"]}
    _, _, job = server.request("POST", "/api/v1/jobs", body)
    done, _ = _wait(server, job["id"])
    assert done["status"] == "done", done
    assert done["result"]["rows"] == study("e_p", [0.0005, 0.005], configs=["nes"]).rows


# Jobs that run for several seconds (a fine mesh at a load with four Hopf points: ~6 s here), so
# that they are still running when the test acts on them; they never run to the end.
LONG_JOB = {"analysis": "bifurcation", "config": "original", "v_min": 1, "v_max": 200, "ntst": 200}


def _holder(server, job_id, timeout=30):
    """The process that holds the job's slot, as the jobs store records it: {pid, started, host}."""
    from shimmy.service import jobs

    deadline = time.time() + timeout
    with server.cache_env():
        while time.time() < deadline:
            holder = jobs.store().get("running", {}).get(job_id)
            if holder and holder["pid"]:
                return holder
            time.sleep(0.1)
    raise AssertionError(f"job {job_id} holds no process after {timeout} s")


def _group_gone(pgid, timeout=30):
    """True once no process of group ``pgid`` is left (zombies included)."""
    import psutil

    deadline = time.time() + timeout
    while time.time() < deadline:
        left = [p for p in psutil.process_iter(["pid"]) if process_group(p.pid) == pgid]
        if not left:
            return True
        time.sleep(0.2)
    return False


def test_job_cancelled_and_deleted_leaves_no_process(server):
    body = {**LONG_JOB, "Fz": 300000}
    status, _, job = server.request("POST", "/api/v1/jobs", body)
    assert status == 202
    _wait(server, job["id"], until=("running",), timeout=60)
    holder = _holder(server, job["id"])
    status, _, cancelled = server.request("DELETE", f"/api/v1/jobs/{job['id']}")
    assert status == 200 and cancelled["status"] == "cancelled"
    status, _, later = server.request("GET", f"/api/v1/jobs/{job['id']}")
    assert status == 404 and later["field"] == "id"
    assert _group_gone(holder["pid"])


def test_job_whose_worker_is_killed_is_failed_and_its_group_ends(server):
    """kill -9 of the worker alone (not its group): the job turns failed, nothing of its group survives."""
    body = {**LONG_JOB, "Fz": 310000}
    _, _, job = server.request("POST", "/api/v1/jobs", body)
    _wait(server, job["id"], until=("running",), timeout=60)
    holder = _holder(server, job["id"])
    os.kill(holder["pid"], signal.SIGKILL)
    failed, _ = _wait(server, job["id"], until=("failed", "done"), timeout=60)
    assert failed["status"] == "failed" and "ended without a result" in failed["error"]
    assert _group_gone(holder["pid"])


def test_sensitivity_answers_in_the_request_and_as_a_job_from_one_cache_entry(server):
    body = {"config": "pd", "Fz": 150000, "names": ["k_lam", "a_p", "rho_p", "e_p"]}
    status, headers, first = server.request("POST", "/api/v1/sensitivity", body)
    assert status == 200 and headers["X-Shimmy-Cache"] == "miss"
    assert {"hopf_points", "min_shimmy_Fz", "max_psi", "no_effect", "quantities", "methods"} <= set(first)
    assert [h["V"] for h in first["hopf_points"]] == sorted(h["V"] for h in first["hopf_points"])
    assert {"dV_dp", "domega_dp", "destabilising", "criticality"} <= set(first["hopf_points"][0])
    keys = [q["key"] for q in first["quantities"]]
    assert keys[:2] == ["hopf_V1", "hopf_V2"] and "min_shimmy_Fz" in keys
    row = first["quantities"][0]["rows"][0]
    assert row["name"] == "k_lam" and {"per_percent", "per_half_range", "unit", "reason"} <= set(row)
    # The damper's packing and density leave straight rolling's linearisation unchanged; e_p is not fitted.
    assert "slope is zero at rest" in first["no_effect"]["hopf"]["a_p"]
    assert "slope is zero at rest" in first["no_effect"]["hopf"]["rho_p"]
    assert first["no_effect"]["hopf"]["e_p"] == "not fitted in this configuration"
    status, _, job = server.request("POST", "/api/v1/jobs", {"analysis": "sensitivity", **body,
                                                             "names": ["rho_p", "e_p", "a_p", "k_lam"]})
    assert status == 202 and job["status"] == "done"  # the same question (names in another order): cached
    _, _, done = server.request("GET", f"/api/v1/jobs/{job['id']}")
    assert done["result"] == first


def test_optimise_and_robustness_jobs_complete_with_their_results(server):
    body = {"analysis": "optimise", "config": "nes", "parameters": ["e_p"], "starts": 2, "local_runs": 1,
            "constraints": ["max_psi<=0.5"], "params": {"k_s": 1.3e6}}
    _, _, opt = server.request("POST", "/api/v1/jobs", body)
    body = {"analysis": "robustness", "config": "nes", "tolerances": ["k_lam=0.05", "k_s=0.05:uniform"],
            "samples": 16}
    _, _, rob = server.request("POST", "/api/v1/jobs", body)
    done, _ = _wait(server, rob["id"])
    assert done["status"] == "done", done
    result = done["result"]
    assert [t["name"] for t in result["tolerances"]] == ["k_lam", "k_s"]
    assert len(result["hopf_points"]) == 2 and len(result["hopf_points"][0]["samples"]) == 16
    assert {"mean", "std", "p05", "p95", "linear_std"} <= set(result["min_shimmy_Fz"])
    assert set(result["p_shimmy"]) == set(result["p_shimmy_linear"]) == set("ABCDEFGHI")
    done, seen = _wait(server, opt["id"], timeout=180)
    assert done["status"] == "done", done
    result = done["result"]
    assert result["parameters"] == ["e_p"] and set(result["design"]) == {"e_p"}
    assert result["objective"] >= result["nominal_objective"] and result["evaluations"] == len(result["history"])
    assert set(result["figures"]) == {"optimum", "nominal", "original"}
    assert result["constraints"] == [{"figure": "max_psi", "op": "<=", "value": 0.5, "Fz": 150000.0, "unit": "rad"}]
    # The workbench link carries the whole design: the searched value and the rest of the base design.
    assert result["link_query"]["config"] == "nes" and float(result["link_query"]["k_s"]) == 1.3e6
    assert float(result["link_query"]["e_p"]) == pytest.approx(result["design"]["e_p"])
    assert any(0 < p < 1 for s, p in seen if s == "running")  # progress while it ran


# --- The OpenAPI document describes the answers (its response schemas checked against real ones) ---
# At the end of the module: the job bodies below are those the tests above ran, so most answers come
# from this server's cache. Each answer is validated (jsonschema, the 2020-12 dialect of OpenAPI 3.1)
# and every key it has must be declared by the schema (openapi_check.undeclared).

RESULT_JOBS = [
    {"analysis": "simulate", "config": "nes_pd", "V": 30, "Fz": 150000, "t_end": 20},
    FRESH_DIAGRAM,
    {"analysis": "hopf_curves", "config": "nes"},
    {"analysis": "map", "config": "original", "fz_min": 100000, "fz_max": 400000, "resolution": 4, "n_v": 20},
    {"analysis": "study", "parameter": "e_p", "values": [0.0005, 0.005], "configs": ["nes"]},
    {"analysis": "study", "parameter": "e_p", "values": [0.0005, 0.005], "parameter2": "k_s",
     "values2": [1.2e6, 1.4e6], "configs": ["nes"]},
    {"analysis": "ground_run", "config": "original", "preset": "takeoff", "hopf_curves": True},
    {"analysis": "ground_run", "config": "nes", "preset": "runway_joint"},  # a yaw-rate kick at 60 m/s
    {"analysis": "sensitivity", "config": "nes", "names": ["r2", "k_s"]},
    {"analysis": "optimise", "config": "nes", "parameters": ["e_p"], "starts": 2, "local_runs": 1,
     "constraints": ["max_psi<=0.5"], "params": {"k_s": 1.3e6}},
    {"analysis": "robustness", "config": "nes", "tolerances": ["k_lam=0.05", "k_s=0.05:uniform"], "samples": 16},
    {"analysis": "margins", "config": "original", "V": 50, "Fz": 550000},
    {"analysis": "margins", "config": "original", "V": 50, "Fz": 550000, "direction": "mix",
     "mix": "psi=0.01,dpsi=0.1", "origin": "standard_attractor", "phases": 2},
    {"analysis": "basins", "config": "original", "V": 50, "Fz": 550000, "samples": 10},
    {"analysis": "margin_map", "config": "original", "n_v": 4, "n_fz": 3},
]


def _answer_schema(doc, path, method, status):
    return doc["paths"][path][method]["responses"][str(status)]["content"]["application/json"]["schema"]


def _check_answer(doc, schema, answer, result_schema=None, result=None):
    from openapi_check import errors, undeclared

    assert errors(doc, schema, answer) == []
    if result_schema is not None:
        assert undeclared(doc, result_schema, result) == []
    else:
        assert undeclared(doc, schema, answer) == []


def test_openapi_document_is_valid_openapi_3_1(server):
    from openapi_spec_validator import validate

    _, _, doc = server.request("GET", "/api/v1/openapi.json")
    validate(doc)  # raises on the first fault, naming it
    for path, item in doc["paths"].items():
        for method, op in item.items():
            if method == "parameters":
                continue
            ok = [s for s in op["responses"] if s.startswith("2")]
            assert all("content" in op["responses"][s] for s in ok), (path, method)
    for path in ("/health", "/parameters"):
        status, _, answer = server.request("GET", "/api/v1" + path)
        assert status == 200
        _check_answer(doc, _answer_schema(doc, path, "get", 200), answer)


def test_every_quick_answer_matches_its_response_schema(server):
    _, _, doc = server.request("GET", "/api/v1/openapi.json")
    bodies = {**OK_BODIES, "/api/v1/sensitivity": {"config": "nes", "names": ["r2"]},
              "/api/v1/simulate": {**OK_BODIES["/api/v1/simulate"], "include_series": True, "series_dt": 0.005}}
    assert {p.removeprefix("/api/v1") for p in bodies} == {p for p, i in doc["paths"].items()
                                                           if "post" in i and p != "/jobs"}
    for path, body in bodies.items():
        status, _, answer = server.request("POST", path, body, timeout=120)
        assert status == 200, answer
        _check_answer(doc, _answer_schema(doc, path.removeprefix("/api/v1"), "post", 200), answer)


def test_every_job_result_matches_its_response_schema(server):
    _, _, doc = server.request("GET", "/api/v1/openapi.json")
    from shimmy.service.analyses import JOB_ANALYSES

    assert {b["analysis"] for b in RESULT_JOBS} == set(JOB_ANALYSES)
    schema = _answer_schema(doc, "/jobs/{id}", "get", 200)
    for body in RESULT_JOBS:
        status, _, job = server.request("POST", "/api/v1/jobs", body)
        assert status == 202, job
        done, _ = _wait(server, job["id"], timeout=240)
        assert done["status"] == "done", done
        own = {"$ref": f"#/components/schemas/Job_{body['analysis']}"}  # the same as the oneOf, with clearer errors
        _check_answer(doc, own, done, {"$ref": f"#/components/schemas/{body['analysis']}_result"}, done["result"])
        _check_answer(doc, schema, done, {"$ref": f"#/components/schemas/{body['analysis']}_result"}, done["result"])
        broken = {**done, "result": {**done["result"], "version": 1}}  # the check can fail: a wrong type is seen
        from openapi_check import errors
        assert errors(doc, schema, broken)


def test_refusals_match_the_documented_status_and_error_schema(server):
    _, _, doc = server.request("GET", "/api/v1/openapi.json")
    error = {"$ref": "#/components/schemas/Error"}
    cases = [("POST", "/simulate", {"config": "nes", "V": 30}, None, 422, "Fz"),
             ("POST", "/simulate", None, b"{not json", 400, "body"),
             ("POST", "/simulate", None, b"[1, 2]", 400, "body"),
             ("POST", "/jobs", {"config": "nes"}, None, 422, "analysis"),
             ("POST", "/jobs", {"analysis": "robustness", "config": "nes",
                                "tolerances": [{"name": "r2", "relative": 0.05, "distribution": {}}]}, None, 422,
              "tolerances[0].distribution"),
             ("GET", "/jobs/doesnotexist", None, None, 404, "id")]
    for method, path, body, raw, status, field in cases:
        got, _, answer = server.request(method, "/api/v1" + path, body, raw=raw)
        assert (got, answer["field"]) == (status, field), answer
        documented = doc["paths"]["/jobs/{id}" if path.startswith("/jobs/") else path][method.lower()]["responses"]
        assert str(status) in documented and documented[str(status)]["content"]["application/json"]["schema"] == error
        _check_answer(doc, error, answer)
    _, _, answer = server.request("POST", "/api/v1/jobs", {"config": "nes"})
    assert answer["error"].startswith("analysis is required; allowed: one of simulate")
    assert "no job" in doc["paths"]["/jobs/{id}"]["get"]["responses"]["404"]["description"]
