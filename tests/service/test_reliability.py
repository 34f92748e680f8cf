"""The service under hostile input and faults, against a real gunicorn on loopback (slow clients, which the
proxy in front of gunicorn holds, are in test_proxy.py).

One server for the module with small job limits (1 running, 3 queued) so that floods reach the
limits quickly and anything the fuzz starts stays small. Every count and deadline is bounded;
nothing waits for a particular timing: polls run until a condition holds or a generous deadline.
Figures (fuzz counts, refusal times) are printed for the closing note (pytest -s shows them).
"""

from __future__ import annotations

import concurrent.futures
import json
import random
import shutil
import signal
import socket
import statistics
import time

import psutil
import pytest

from conftest import process_group, start_server, stop_server

pytestmark = pytest.mark.slow

# Job workers end with their last job here (no idle wait): the kill tests find the job's worker as the one
# process of its kind, started by a web worker for that job (idle workers: tests/service/test_team.py).
LIMITS = {"SHIMMY_MAX_RUNNING_JOBS": "1", "SHIMMY_MAX_QUEUED_JOBS": "3", "SHIMMY_JOB_RETRY_AFTER_SECONDS": "7",
          "SHIMMY_BODY_READ_SECONDS": "3", "SHIMMY_HEADER_READ_SECONDS": "3", "SHIMMY_JOB_WORKER_LINGER_SECONDS": "0"}
OK = {
    "/api/v1/simulate": {"config": "nes_pd", "V": 30, "Fz": 150000, "t_end": 5},
    "/api/v1/hopf": {"config": "nes", "Fz": 150000, "v_max": 200},
    "/api/v1/stability": {"Fz": 150000, "v_max": 200, "n_points": 20},
    "/api/v1/devices": {"v_max": 1.0},
    "/api/v1/jobs": {"analysis": "map", "config": "nes", "fz_min": 100000, "fz_max": 400000, "resolution": 2,
                     "n_v": 10},
}
HOSTILE = [10 ** 400, -(10 ** 400), 2 ** 63, -1, 0, 1e-320, 1e308, "30", "", "x" * 3000, None, True, False, [],
           {}, [1] * 500, {"a": {"b": {"c": [1]}}}, [[[[[]]]]], "NaN", 20.5, -0.0, "\u0000\ud7ff", 1e6]
RAW_BODIES = [b"[" * 20000 + b"]" * 20000, b"{" * 5 + b"}", b'{"config": ', b"\xff\xfe\x00", b"null", b"[1, 2]",
              b'"text"', b"3", b'{"V": NaN}', b'{"V": Infinity, "Fz": -Infinity}', b'{"V": 1' + b"0" * 400 + b"}",
              b'{"params": {"r2": 1' + b"0" * 400 + b"}}", b'{"a": 1, "a": 2}', b" " * 1000, b"{}" * 3]


@pytest.fixture(scope="module")
def srv(tmp_path_factory):
    server = start_server(tmp_path_factory.mktemp("reliability"), LIMITS)
    yield server
    cancel_all(server)
    stop_server(server)


def cancel_all(server) -> None:
    from shimmy.service import jobs

    with server.cache_env():
        s = jobs.store()
        ids = list(s.get("queue", [])) + list(s.get("running", {}))
    for job_id in ids:
        server.request("DELETE", f"/api/v1/jobs/{job_id}")

    def settled():  # a slot is free once its process is gone; every read reaps
        server.request("GET", "/api/v1/jobs/none")
        with server.cache_env():
            return not jobs.store().get("queue", []) and not jobs.store().get("running", {})

    _until(settled, what="no job queued or running")


def named(answer) -> bool:
    """A refusal in the API's shape whose message names its field."""
    if not isinstance(answer, dict) or set(answer) != {"error", "field", "allowed"}:
        return False
    field = answer["field"]
    return isinstance(field, str) and bool(field) and field.split(".")[-1].split("[")[0] in answer["error"]


def api_case(rng: random.Random):
    """(path, raw body, headers) of one hostile API request."""
    path = rng.choice(list(OK))
    body = json.loads(json.dumps(OK[path]))
    kind = rng.randrange(8)
    headers = {"Content-Type": "application/json"}
    if kind == 0:  # a field replaced
        body[rng.choice(list(body))] = rng.choice(HOSTILE)
    elif kind == 1:  # a design parameter replaced, or an unknown one
        name = rng.choice(["r2", "e_p", "k_s", "n", "Iz", "zz", "r2 ", ""])
        body["params"] = {name: rng.choice(HOSTILE)}
    elif kind == 2:  # params of the wrong type
        body["params"] = rng.choice(HOSTILE)
    elif kind == 3:  # an unknown field
        body[rng.choice(["surprise", "analysis2", "", "V ", "__proto__"])] = rng.choice(HOSTILE)
    elif kind == 4:  # a required field removed
        body.pop(rng.choice(list(body)))
    elif kind == 5:  # not JSON, not an object, too deep, too long a number
        return path, rng.choice(RAW_BODIES), headers
    elif kind == 6:  # another media type (a cross-site form post)
        headers = {"Content-Type": rng.choice(["text/plain", "application/x-www-form-urlencoded",
                                               "multipart/form-data; boundary=x", "application/jsonx", ""])}
    else:  # study jobs: lists of hostile values
        body = {"analysis": "study", "parameter": rng.choice(["e_p", "k_s", "zeta", 3]),
                "values": rng.choice([[rng.choice(HOSTILE)], [0.001] * rng.choice([1, 51, 400]), "x", None])}
        path = "/api/v1/jobs"
    return path, json.dumps(body).encode(), headers


def test_api_fuzz_campaign_gives_no_5xx_and_every_refusal_names_its_field(srv):
    rng = random.Random(20261201)
    cases = [api_case(rng) for _ in range(1200)]

    def one(case):
        path, raw, headers = case
        return srv.request("POST", path, raw=raw, headers=headers, timeout=120)

    with concurrent.futures.ThreadPoolExecutor(4) as pool:
        answers = list(pool.map(one, cases))
    statuses = [status for status, _, _ in answers]
    server_errors = [(c, a) for c, a in zip(cases, answers, strict=True) if a[0] >= 500]
    unnamed = [(c[0], c[1][:120], a[0], a[2]) for c, a in zip(cases, answers, strict=True)
               if 400 <= a[0] < 500 and not named(a[2])]
    busy = [a for a in answers if a[0] == 429]
    print(f"\napi fuzz: {len(answers)} requests, 5xx: {len(server_errors)}, "
          f"429 queue full: {len(busy)}, 4xx: {sum(400 <= s < 500 for s in statuses)}, "
          f"2xx: {sum(s < 300 for s in statuses)}, 4xx not naming their field: {len(unnamed)}")
    assert not server_errors, server_errors[:3]
    assert all(a[1].get("Retry-After") and named(a[2]) for a in busy)
    assert not unnamed, unnamed[:5]
    assert sum(400 <= s < 500 for s in statuses) > 900  # the campaign is hostile, not a list of valid requests


def _dependencies(srv):
    status, _, deps = srv.request("GET", "/_dash-dependencies")
    assert status == 200
    return deps


def _outputs(output: str):
    parts = output[2:-2].split("...") if output.startswith("..") else [output]
    out = []
    for part in parts:
        ident, _, prop = part.split("@")[0].rpartition(".")
        out.append({"id": json.loads(ident) if ident.startswith("{") else ident, "property": prop})
    return out if output.startswith("..") else out[0]


def _item(dep, rng, value):
    ident = dep["id"]
    if ident.startswith("{"):
        pattern = json.loads(ident)
        concrete = {k: ("x" if isinstance(v, list) else v) for k, v in pattern.items()}
        return [{"id": concrete, "property": dep["property"], "value": value}]
    return {"id": ident, "property": dep["property"], "value": value}


def callback_case(rng: random.Random, deps):
    dep = rng.choice(deps)
    body = {"output": dep["output"], "outputs": _outputs(dep["output"]),
            "inputs": [_item(i, rng, rng.choice(HOSTILE)) for i in dep["inputs"]],
            "state": [_item(s, rng, rng.choice(HOSTILE)) for s in dep["state"]],
            "changedPropIds": [f"{dep['inputs'][0]['id']}.{dep['inputs'][0]['property']}"] if dep["inputs"] else []}
    kind = rng.randrange(7)
    if kind == 0:
        body.pop(rng.choice(list(body)))
    elif kind == 1:
        body[rng.choice(list(body))] = rng.choice(HOSTILE)
    elif kind == 2:
        body["output"] = rng.choice(["nothing.children", "..a.b...c.d..", dep["output"] + "x"])
    elif kind == 3 and body["inputs"]:
        body["inputs"] = body["inputs"][:-1] if rng.random() < 0.5 else body["inputs"] + body["inputs"]
    elif kind == 4:
        return rng.choice(RAW_BODIES), {"Content-Type": "application/json"}
    elif kind == 5:
        return json.dumps(body).encode(), {"Content-Type": "text/plain"}
    return json.dumps(body).encode(), {"Content-Type": "application/json"}


def test_callback_fuzz_campaign_gives_no_5xx(srv):
    rng = random.Random(907)
    deps = _dependencies(srv)
    cases = [callback_case(rng, deps) for _ in range(400)]

    def one(case):
        raw, headers = case
        return srv.request("POST", "/_dash-update-component", raw=raw, headers=headers, timeout=120)

    with concurrent.futures.ThreadPoolExecutor(4) as pool:
        answers = list(pool.map(one, cases))
    statuses = [a[0] for a in answers]
    unnamed = [a for a in answers if 400 <= a[0] < 500 and not named(a[2])]
    print(f"\ncallback fuzz: {len(answers)} requests over {len(deps)} callbacks, 5xx: "
          f"{sum(s >= 500 for s in statuses)}, 4xx: {sum(400 <= s < 500 for s in statuses)}, "
          f"2xx: {sum(s < 300 for s in statuses)}, 4xx not naming their field: {len(unnamed)}")
    assert all(s < 500 for s in statuses), [a for a in answers if a[0] >= 500][:3]
    assert not unnamed, unnamed[:3]
    cancel_all(srv)
    _until(lambda: not _zombies_below(srv.proc.pid), what="no zombie left by the campaign")


def _workers(srv):
    """Job worker processes of this server's cache (by their command line and environment) that run or
    start a job: not those idle in the store's list, waiting for the next job (they hold no slot)."""
    from shimmy.service import jobs

    with srv.cache_env():
        idle = {holder["pid"] for holder in jobs.store().get("idle", {}).values()}
    out = []
    for p in psutil.process_iter(["cmdline", "pid"]):
        try:
            if "shimmy.service.worker" in (p.info["cmdline"] or []) and p.pid not in idle and \
                    p.environ().get("SHIMMY_CACHE_DIR") == str(srv.cache_dir):
                out.append(p)
        except psutil.Error:
            pass
    return out


def _until(predicate, timeout=60.0, what="condition"):
    deadline = time.time() + timeout
    while time.time() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(0.2)
    raise AssertionError(f"timed out waiting for {what}")


def test_job_flood_is_bounded_refused_with_retry_after_and_deduplicated(srv):
    cancel_all(srv)
    bodies = [{**OK["/api/v1/jobs"], "fz_max": 400000 + 1000 * k, "resolution": 40} for k in range(12)]
    answers, refusal_times = [], []
    for body in bodies:
        t0 = time.perf_counter()
        answers.append(srv.request("POST", "/api/v1/jobs", body))
        if answers[-1][0] == 429:
            refusal_times.append(time.perf_counter() - t0)
    accepted = [a for a in answers if a[0] == 202]
    refused = [a for a in answers if a[0] == 429]
    print(f"\njob flood: {len(accepted)} accepted, {len(refused)} refused (429), median time to refuse "
          f"{1e3 * statistics.median(refusal_times):.1f} ms, worker processes {len(_workers(srv))}")
    assert len(accepted) == 4 and len(refused) == 8  # 1 running + 3 queued
    assert all(a[1]["Retry-After"] == "7" and a[2]["field"] == "analysis" and "queue is full" in a[2]["error"]
               for a in refused)
    assert len(_workers(srv)) <= 1  # queued jobs hold no process
    # The same request again is the same job, queued or running.
    status, _, again = srv.request("POST", "/api/v1/jobs", bodies[1])
    assert status == 202 and again["id"] == accepted[1][2]["id"]
    cancel_all(srv)
    _until(lambda: not _workers(srv), what="the workers to end after the cancels")


def _dispatch_payload(deps, fz_kn):
    dep = next(d for d in deps if "bif-go.data" in d["output"] and d["inputs"][0]["id"] == "bif-run")
    values = {"bif-fz": fz_kn, "bif-vmin": 1, "bif-vmax": 200, "bif-configs": ["original", "nes", "pd", "nes_pd"]}
    state = [{"id": json.loads(s["id"]) if s["id"].startswith("{") else s["id"], "property": s["property"],
              "value": values.get(s["id"], {})} for s in dep["state"]]
    return {"output": dep["output"], "outputs": _outputs(dep["output"]),
            "inputs": [{"id": "bif-run", "property": "n_clicks", "value": 1}], "state": state,
            "changedPropIds": ["bif-run.n_clicks"]}


def test_page_computations_go_through_the_same_admission_control(srv):
    cancel_all(srv)
    deps = _dependencies(srv)
    messages = []
    for k in range(6):  # 6 x 4 configurations: far more than 1 running + 3 queued
        status, _, answer = srv.request("POST", "/_dash-update-component", _dispatch_payload(deps, 150 + k))
        assert status == 200, answer
        messages.append(json.dumps(answer))
        assert len(_workers(srv)) <= 1
    assert any("busy" in m and "queue is full" in m for m in messages)
    cancel_all(srv)
    _until(lambda: not _workers(srv), what="the workers to end after the cancels")


def _zombies_below(root_pid):
    try:
        tree = psutil.Process(root_pid).children(recursive=True)
    except psutil.Error:
        return []
    out = []
    for p in tree:
        try:
            if p.status() == psutil.STATUS_ZOMBIE:
                out.append(p.pid)
        except psutil.Error:
            pass
    return out


def test_killed_web_worker_leaves_no_orphan_or_zombie(srv):
    cancel_all(srv)
    body = {"analysis": "bifurcation", "config": "original", "v_min": 1, "v_max": 200, "ntst": 200, "Fz": 320000}
    _, _, job = srv.request("POST", "/api/v1/jobs", body)
    worker = _until(lambda: _workers(srv), what="the job's worker")[0]
    web_worker = worker.parent()
    assert web_worker is not None and web_worker.pid != srv.proc.pid  # started by a web worker
    web_worker.send_signal(signal.SIGKILL)
    # The job goes on under the arbiter (child subreaper), then is cancelled: nothing of it survives.
    _until(lambda: (p := worker.parent()) is not None and p.pid == srv.proc.pid, what="the arbiter to adopt the job")
    _until(lambda: srv.request("GET", "/api/v1/health")[0] == 200, what="a new web worker")
    status, _, _ = srv.request("DELETE", f"/api/v1/jobs/{job['id']}")
    assert status == 200
    _until(lambda: not psutil.pid_exists(worker.pid), what="the worker to end and be reaped")
    _until(lambda: not _zombies_below(srv.proc.pid), what="no zombie below the arbiter")
    assert not [p for p in psutil.process_iter() if process_group(p.pid) == worker.pid]


def test_killed_job_worker_fails_its_job_and_takes_its_group_with_it(srv):
    cancel_all(srv)
    body = {"analysis": "map", "config": "original", "fz_min": 100000, "fz_max": 800000, "resolution": 40}
    _, _, job = srv.request("POST", "/api/v1/jobs", body)
    worker = _until(lambda: _workers(srv), what="the job's worker")[0]
    _until(lambda: len(_group(worker.pid)) > 1, what="the map's process pool")
    members = _group(worker.pid)
    worker.send_signal(signal.SIGKILL)
    _until(lambda: srv.request("GET", f"/api/v1/jobs/{job['id']}")[2]["status"] == "failed", what="failed")
    _until(lambda: not _group(worker.pid), what="the group to end")
    print(f"\nkill -9 of a map worker: {len(members)} processes in its group, none left")
    _until(lambda: not _zombies_below(srv.proc.pid), what="no zombie below the arbiter")


def _group(pgid):
    return [p.pid for p in psutil.process_iter() if process_group(p.pid) == pgid]


def test_corrupted_result_entry_is_a_miss_and_recomputed(srv):
    body = {"config": "nes", "V": 31, "Fz": 150000, "t_end": 20, "include_series": True}
    status, headers, first = srv.request("POST", "/api/v1/simulate", body)
    assert status == 200 and headers["X-Shimmy-Cache"] == "miss"
    files = sorted((srv.cache_dir / "results").rglob("*.val"), key=lambda p: p.stat().st_mtime)
    assert files, "a time series this large is stored in its own file"
    files[-1].write_bytes(b"\x80\x04garbage" * 10)
    status, headers, second = srv.request("POST", "/api/v1/simulate", body)
    assert status == 200 and headers["X-Shimmy-Cache"] == "miss" and second == first
    status, headers, _ = srv.request("POST", "/api/v1/simulate", body)
    assert headers["X-Shimmy-Cache"] == "hit"


def test_corrupted_database_is_rebuilt_and_health_stays_honest(tmp_path):
    """A cache.db that is garbage when the server starts (damaged while it was down) is moved aside."""
    (tmp_path / "results").mkdir(mode=0o700)
    (tmp_path / "results" / "cache.db").write_bytes(b"this is not a database" * 200)
    server = start_server(tmp_path, LIMITS)
    try:
        for _ in range(4):  # both web workers, either order
            status, _, answer = server.request("POST", "/api/v1/hopf", {"config": "nes", "Fz": 151000})
            assert status == 200, answer
        status, _, health = server.request("GET", "/api/v1/health")
        assert status == 200 and health["status"] == "ok"
        assert list(tmp_path.glob("results.broken-*"))  # kept aside for inspection
        status, headers, _ = server.request("POST", "/api/v1/hopf", {"config": "nes", "Fz": 151000})
        assert headers["X-Shimmy-Cache"] == "hit"  # the rebuilt store caches again
    finally:
        stop_server(server)


def test_deleted_cache_directory_is_recreated_and_jobs_still_run(srv):
    cancel_all(srv)
    shutil.rmtree(srv.cache_dir)
    status, _, health = srv.request("GET", "/api/v1/health")
    assert status == 200 and health["status"] == "ok"
    assert (srv.cache_dir.stat().st_mode & 0o777) == 0o700
    body = {"analysis": "simulate", "config": "nes", "V": 32, "Fz": 150000, "t_end": 5}
    status, _, job = srv.request("POST", "/api/v1/jobs", body)
    assert status == 202
    done = _until(lambda: (j := srv.request("GET", f"/api/v1/jobs/{job['id']}")[2]).get("status") in
                  ("done", "failed") and j, what="the job to finish")
    assert done["status"] == "done" and done["result"]["amplitude"]["psi"] > 0


def test_body_shorter_than_its_content_length_is_answered_408_in_bounded_time(srv):
    """gunicorn reached directly (one user on loopback): the app's own body deadline, SHIMMY_BODY_READ_SECONDS.
    Behind the proxy such a request never reaches the app (tests/service/test_proxy.py)."""
    host, port = srv.base.removeprefix("http://").split(":")
    with socket.create_connection((host, int(port)), timeout=30) as s:
        t0 = time.perf_counter()
        s.sendall(b"POST /api/v1/simulate HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                  b"Content-Length: 1000\r\n\r\n{\"config\": \"nes\"")
        answer = b""
        while b"}" not in answer:
            chunk = s.recv(4096)
            if not chunk:
                break
            answer += chunk
        elapsed = time.perf_counter() - t0
    head, _, body = answer.partition(b"\r\n\r\n")
    assert head.startswith(b"HTTP/1.1 408"), answer[:200]
    assert json.loads(body)["field"] == "body"
    assert elapsed < 3 + 20  # the limit (3 s here) plus a generous margin, far from gunicorn's 120 s timeout


def _download(srv, output, value):
    dep = next(d for d in _dependencies(srv) if d["output"] == output)
    body = {"output": output, "outputs": _outputs(output),
            "inputs": [{"id": i["id"], "property": i["property"], "value": 1} for i in dep["inputs"]],
            "state": [{"id": json.loads(dep["state"][0]["id"]) if dep["state"][0]["id"].startswith("{")
                       else dep["state"][0]["id"], "property": "data", "value": value}],
            "changedPropIds": [f"{dep['inputs'][0]['id']}.n_clicks"]}
    t0 = time.perf_counter()
    status, _, _ = srv.request("POST", "/_dash-update-component", body)
    return status, time.perf_counter() - t0


def test_crafted_downloads_never_compute(srv):
    """Download callbacks given requests the client made up serialise only what is cached: nothing is computed."""
    from shimmy.service import cache, schemas

    cancel_all(srv)
    maps = [{"config": c, "resolution": 40, "fz_max": 880000.0} for c in ("original", "nes", "pd", "nes_pd")]
    history = {"config": "nes", "V": 33.0, "Fz": 150000.0, "t_end": 600.0, "include_series": True}
    design = {"params": {"r2": 0.0811}}
    for output, value, analysis, requests in [("map-download.data", maps, "map", maps),
                                              ("th-download.data", [history], "simulate", [history]),
                                              ("dev-download.data", design, "devices", [design])]:
        status, elapsed = _download(srv, output, value)
        assert status in (200, 204) and elapsed < 30, output  # the map alone would take minutes
        assert not _workers(srv)
        with srv.cache_env():
            assert all(cache.get(analysis, schemas.validate(analysis, r)) is None for r in requests), output
    # A list longer than a page can send is refused, not served.
    many = [{"config": "nes", "resolution": 2, "fz_max": 400000.0 + k} for k in range(20)]
    assert _download(srv, "map-download.data", many)[0] in (200, 204)
