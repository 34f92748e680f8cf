"""A service a team can share, against real gunicorn servers on loopback: who may use it (tokens, the
sign-in page, 401 / 403), fair shares of the job queue and of the quick computations, bounded storage
under a flood, and queued and running jobs across a restart.

Every count and deadline is bounded; polls run until a condition holds or a generous deadline. The
figures (times, sizes, counts) are printed for the closing note (pytest -s shows them).
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import http.client
import json
import os
import random
import re
import signal
import statistics
import subprocess
import sys
import threading
import time
import urllib.parse
from pathlib import Path

import psutil
import pytest

from conftest import ROOT, start_server, stop_server
from test_reliability import api_case, callback_case, named

pytestmark = pytest.mark.slow

USERS = {"alice": "compute", "bob": "compute", "root": "admin", "reader": "read", "temp": "compute"}
TEAM = {"SHIMMY_AUTH": "token", "SHIMMY_MAX_RUNNING_JOBS": "2", "SHIMMY_MAX_QUEUED_JOBS": "8",
        "SHIMMY_MAX_JOBS_PER_USER": "3", "SHIMMY_JOB_RETRY_AFTER_SECONDS": "7",
        "SHIMMY_FAST_PER_USER_PER_SECOND": "3", "SHIMMY_FAST_PER_USER_BURST": "6",
        "SHIMMY_LOGIN_ATTEMPTS_PER_MINUTE": "8",
        # every request in the log, at the most talkative level: the tokens must still be absent
        "GUNICORN_CMD_ARGS": "--access-logfile - --log-level debug"}
#: A bifurcation job that runs for several seconds (never to its end here).
LONG = {"analysis": "bifurcation", "config": "original", "v_min": 1, "v_max": 200, "ntst": 200}


@contextlib.contextmanager
def cache_env(cache_dir: Path):
    before = os.environ.get("SHIMMY_CACHE_DIR")
    os.environ["SHIMMY_CACHE_DIR"] = str(cache_dir)
    try:
        yield
    finally:
        if before is None:
            os.environ.pop("SHIMMY_CACHE_DIR", None)
        else:
            os.environ["SHIMMY_CACHE_DIR"] = before


def make_tokens(cache_dir: Path, users: dict[str, str]) -> dict[str, tuple[str, str]]:
    """{user: (token id, secret)} made with the command line, as an administrator would."""
    out = {}
    env = {**os.environ, "SHIMMY_CACHE_DIR": str(cache_dir), "PYTHONPATH": str(ROOT)}
    for user, scope in users.items():
        done = subprocess.run([sys.executable, "-m", "shimmy", "tokens", "create", "--user", user, "--scope", scope],
                              capture_output=True, text=True, env=env, cwd=ROOT, timeout=120)
        assert done.returncode == 0, done.stderr
        secret = done.stdout.strip().splitlines()[-1]
        out[user] = (re.search(r"tok_[0-9a-f]{8}", done.stdout).group(0), secret)
    return out


def bearer(secret: str) -> dict[str, str]:
    return {"Authorization": f"Bearer {secret}"}


def raw(server, method: str, path: str, body: bytes | None = None, headers: dict[str, str] | None = None,
        timeout: float = 60.0):
    """(status, headers, text) of one request, redirects not followed."""
    parts = urllib.parse.urlsplit(server.base)
    conn = http.client.HTTPConnection(parts.hostname, parts.port, timeout=timeout)
    try:
        conn.request(method, path, body=body, headers=headers or {})
        resp = conn.getresponse()
        return resp.status, resp.headers, resp.read().decode("utf-8", "replace")
    finally:
        conn.close()


def _workers_ready(cache_dir, workers: int = 2) -> bool:
    """Every web worker of the server logging into ``cache_dir`` has loaded its kernels (gunicorn.conf.py)."""
    return (cache_dir / "gunicorn.log").read_text().count("kernels loaded") >= workers


def until(predicate, timeout=60.0, what="condition", every=0.2):
    deadline = time.time() + timeout
    while time.time() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(every)
    raise AssertionError(f"timed out waiting for {what}")


@pytest.fixture(scope="module")
def team(tmp_path_factory):
    cache_dir = tmp_path_factory.mktemp("team")
    made = make_tokens(cache_dir, USERS)
    server = start_server(cache_dir, TEAM)
    server.tokens = made
    server.auth = {user: bearer(secret) for user, (_, secret) in made.items()}
    yield server
    cancel_everything(server)
    stop_server(server)


def cancel_everything(server) -> None:
    admin = server.auth["root"]
    status, _, listing = server.request("GET", "/api/v1/jobs?limit=1000", headers=admin)
    if status != 200:
        return
    for job in listing["jobs"]:
        if job["status"] in ("queued", "running"):
            server.request("DELETE", f"/api/v1/jobs/{job['id']}", headers=admin)
    until(lambda: not server.request("GET", "/api/v1/jobs?limit=1", headers=admin)[2]["running"], 60,
          "no job running")


def callback_body(server, output_part: str, headers):
    """A well-formed callback request of the callback whose output names ``output_part`` (inputs {})."""
    status, _, deps = server.request("GET", "/_dash-dependencies", headers=headers)
    assert status == 200, deps
    dep = next(d for d in deps if output_part in d["output"])

    def item(d):
        ident = json.loads(d["id"]) if d["id"].startswith("{") else d["id"]
        return {"id": ident, "property": d["property"], "value": {}}

    outputs = []
    for part in (dep["output"][2:-2].split("...") if dep["output"].startswith("..") else [dep["output"]]):
        ident, _, prop = part.split("@")[0].rpartition(".")
        outputs.append({"id": json.loads(ident) if ident.startswith("{") else ident, "property": prop})
    return {"output": dep["output"], "outputs": outputs if dep["output"].startswith("..") else outputs[0],
            "inputs": [item(i) for i in dep["inputs"]], "state": [item(s) for s in dep["state"]],
            "changedPropIds": []}


# -- who may use it ---------------------------------------------------------------------------


def test_api_page_callback_and_job_refuse_a_missing_or_bad_credential_and_take_a_good_one(team):
    alice, bob, root, reader = (team.auth[u] for u in ("alice", "bob", "root", "reader"))
    secret = team.tokens["alice"][1]
    forged = f"{team.tokens['alice'][0]}.{int(time.time()) + 3600}.00ff00ff00ff00ff.AAAA"
    bad = [{}, bearer("shm_" + "A" * 43), bearer(secret[:-1] + ("A" if secret[-1] != "A" else "B")),
           bearer(secret + "x"), {"Authorization": "Basic YWxpY2U6c2VjcmV0"}, {"Authorization": "Bearer"},
           {"Authorization": secret}, {"Authorization": "Bearer " + secret + " " + secret},
           {"Cookie": "shimmy_session=tok_00000000.1.2.3"}, {"Cookie": f"shimmy_session={forged}"},
           {"Authorization": "Bearer \u00e9t\u00e9"}]
    page = callback_body(team, "dev-torque.figure", alice)
    job = {"analysis": "simulate", "config": "nes", "V": 33.3, "Fz": 150000, "t_end": 2}
    cases = [("POST", "/api/v1/hopf", {"config": "nes", "Fz": 150500}, 200),
             ("GET", "/api/v1/parameters", None, 200), ("GET", "/api/v1/openapi.json", None, 200),
             ("POST", "/_dash-update-component", page, 200), ("POST", "/api/v1/jobs", job, 202)]
    for method, path, body, ok in cases:
        answers = [team.request(method, path, body, headers=h) for h in bad]
        statuses = {a[0] for a in answers}
        assert statuses == {401}, (path, [a[0] for a in answers])
        assert len({json.dumps(a[2]) for a in answers}) == 1, path  # the same words whatever was wrong
        assert all(named(a[2]) and a[2]["field"] == "Authorization" for a in answers)
        assert all(a[1]["WWW-Authenticate"] == 'Bearer realm="shimmy"' for a in answers)
        status, _, answer = team.request(method, path, body, headers=alice)
        assert status == ok, (path, answer)
    print(f"\nauth on: {len(bad)} bad credentials x {len(cases)} requests (API, page callback, job): all 401; "
          "the right token: 200/202")
    # The job: its owner and an admin read it; another user and a reader do not see it.
    _, _, submitted = team.request("POST", "/api/v1/jobs", job, headers=alice)
    path = f"/api/v1/jobs/{submitted['id']}"
    assert submitted["user"] == "alice"
    assert team.request("GET", path, headers=bob)[0] == 404
    assert team.request("GET", path, headers=reader)[0] == 404
    assert team.request("DELETE", path, headers=bob)[0] == 404
    assert team.request("GET", path, headers=root)[0] == 200
    done = until(lambda: (j := team.request("GET", path, headers=alice)[2])["status"] in ("done", "failed") and j,
                 120, "alice's job")
    assert done["status"] == "done" and done["result"]["amplitude"]["psi"] >= 0
    # Scopes: read may read, not compute; only an admin lists every job.
    status, _, refused = team.request("POST", "/api/v1/hopf", {"config": "nes", "Fz": 150600}, headers=reader)
    assert status == 403 and named(refused) and "read" in refused["error"]
    assert team.request("GET", "/api/v1/parameters", headers=reader)[0] == 200
    assert team.request("GET", "/api/v1/jobs", headers=alice)[0] == 403
    status, _, listing = team.request("GET", "/api/v1/jobs", headers=root)
    assert status == 200 and listing["total"] >= 1 and all(j["users"] == ["alice"] for j in listing["jobs"])
    # Health stays open and says nothing about users.
    status, _, health = team.request("GET", "/api/v1/health")
    assert status == 200 and set(health) == {"status", "version", "time"}


def _cookie(headers) -> str:
    found = [v for k, v in headers.items() if k.lower() == "set-cookie"]
    assert len(found) == 1, found
    return found[0]


def test_the_workbench_signs_in_with_a_token_into_a_session_cookie(team):
    html = {"Accept": "text/html"}
    status, headers, _ = raw(team, "GET", "/map?config=nes", headers=html)
    assert status == 303 and headers["Location"] == "/login?next=%2Fmap%3Fconfig%3Dnes"
    status, _, page = raw(team, "GET", "/login?next=/map")
    assert status == 200 and 'name="token"' in page and 'type="password"' in page
    form = {"Content-Type": "application/x-www-form-urlencoded"}

    def login(token, nxt="/map"):
        return raw(team, "POST", "/login", urllib.parse.urlencode({"token": token, "next": nxt}).encode(), form)

    status, headers, page = login("shm_" + "B" * 43)
    assert status == 401 and "not accepted" in page and "Set-Cookie" not in headers
    status, headers, page = login(team.tokens["reader"][1])
    assert status == 403 and "Set-Cookie" not in headers
    status, headers, _ = login(team.tokens["alice"][1])
    assert status == 303 and headers["Location"] == "/map"
    cookie = _cookie(headers)
    assert "HttpOnly" in cookie and "SameSite=Lax" in cookie and "Secure" not in cookie  # served over http
    assert team.tokens["alice"][1] not in cookie  # the cookie names the token by its id, never carries it
    session = {"Cookie": cookie.split(";")[0]}
    status, _, page = raw(team, "GET", "/map?config=nes", headers={**html, **session})
    assert status == 200 and "<html" in page.lower()
    body = json.dumps(callback_body(team, "dev-torque.figure", session)).encode()
    status, _, _ = raw(team, "POST", "/_dash-update-component", body,
                       {**session, "Content-Type": "application/json"})
    assert status == 200
    assert raw(team, "GET", "/api/v1/parameters", headers=session)[0] == 200
    # Never sent elsewhere after signing in; a tampered cookie is no cookie.
    assert login(team.tokens["alice"][1], "//evil.example/x")[1]["Location"] == "/"
    assert login(team.tokens["alice"][1], "https://evil.example/")[1]["Location"] == "/"
    value = session["Cookie"]
    tampered = {"Cookie": value[:-2] + ("AA" if not value.endswith("AA") else "BB")}
    json_type = {"Content-Type": "application/json"}
    assert raw(team, "POST", "/_dash-update-component", body, {**tampered, **json_type})[0] == 401
    status, headers, _ = raw(team, "POST", "/logout", b"", {**session, **form})
    assert status == 303 and headers["Location"] == "/login" and "shimmy_session=;" in _cookie(headers)


def test_revoking_a_token_ends_its_requests_and_sessions_at_once(team):
    form = {"Content-Type": "application/x-www-form-urlencoded"}
    token_id, secret = team.tokens["temp"]
    _, headers, _ = raw(team, "POST", "/login", urllib.parse.urlencode({"token": secret}).encode(), form)
    session = {"Cookie": _cookie(headers).split(";")[0]}
    assert team.request("GET", "/api/v1/parameters", headers=session)[0] == 200
    assert team.request("GET", "/api/v1/parameters", headers=bearer(secret))[0] == 200
    done = subprocess.run([sys.executable, "-m", "shimmy", "tokens", "revoke", token_id], capture_output=True,
                          text=True, env={**os.environ, "SHIMMY_CACHE_DIR": str(team.cache_dir),
                                          "PYTHONPATH": str(ROOT)}, cwd=ROOT, timeout=120)
    assert done.returncode == 0, done.stderr
    for _ in range(4):  # both web workers
        assert team.request("GET", "/api/v1/parameters", headers=bearer(secret))[0] == 401
        assert team.request("GET", "/api/v1/parameters", headers=session)[0] == 401


# -- fair shares ------------------------------------------------------------------------------


def test_one_users_flood_leaves_room_for_anothers_first_job(team):
    alice, bob, root = team.auth["alice"], team.auth["bob"], team.auth["root"]
    cancel_everything(team)
    answers = [team.request("POST", "/api/v1/jobs", {**LONG, "Fz": 300000 + 1000 * k}, headers=alice)
               for k in range(10)]
    accepted = [a for a in answers if a[0] == 202]
    refused = [a for a in answers if a[0] == 429]
    assert len(accepted) == 3 and len(refused) == 7
    assert all(a[1]["X-Shimmy-Limit"] == "jobs_per_user" and a[1]["Retry-After"] == "7" and named(a[2])
               and "SHIMMY_MAX_JOBS_PER_USER" in a[2]["error"] for a in refused)
    clock = time.perf_counter()
    status, _, job = team.request("POST", "/api/v1/jobs", {**LONG, "Fz": 250000}, headers=bob)
    assert status == 202
    until(lambda: team.request("GET", f"/api/v1/jobs/{job['id']}", headers=bob)[2]["status"] != "queued", 60,
          "bob's job to start", every=0.1)
    started = time.perf_counter() - clock

    def by_user():  # alice holds the other slot once the previous test's cancelled jobs have let go of it
        status, _, listing = team.request("GET", "/api/v1/jobs?status=running", headers=root)
        assert status == 200
        return listing if listing["by_user"].get("alice", {}).get("running") == 1 else None

    listing = until(by_user, 60, "alice's first job to run beside bob's", every=0.1)
    print(f"\nflood: alice 10 jobs -> {len(accepted)} accepted, {len(refused)} refused (429 jobs_per_user); "
          f"bob's first job started {started:.2f} s after it was submitted; by user {listing['by_user']}")
    assert started < 15
    assert listing["by_user"]["alice"] == {"queued": 2, "running": 1}
    assert listing["by_user"]["bob"]["running"] == 1 and listing["total"] == 2
    assert {j["user"] for j in listing["jobs"]} == {"alice", "bob"}
    # One of several users who asked for the same job deletes it: it goes on for the other.
    same = {**LONG, "Fz": 300000 + 1000 * 2}
    status, _, shared = team.request("POST", "/api/v1/jobs", same, headers=bob)
    assert status == 202 and shared["id"] == accepted[2][2]["id"]
    status, _, mine = team.request("DELETE", f"/api/v1/jobs/{shared['id']}", headers=bob)
    assert status == 200 and "goes on for them" in mine["message"]
    assert team.request("GET", f"/api/v1/jobs/{shared['id']}", headers=bob)[0] == 404
    assert team.request("GET", f"/api/v1/jobs/{shared['id']}", headers=alice)[2]["status"] in ("queued", "running")
    cancel_everything(team)


def test_one_users_burst_of_quick_computations_is_held_to_its_rate(team):
    alice, bob = team.auth["alice"], team.auth["bob"]
    answers = [team.request("POST", "/api/v1/hopf", {"config": "original", "Fz": 160000 + 10 * k}, headers=alice)
               for k in range(14)]
    ok = [a for a in answers if a[0] == 200]
    limited = [a for a in answers if a[0] == 429]
    assert len(ok) + len(limited) == len(answers) and 5 <= len(ok) <= 10 and limited
    assert all(a[1]["X-Shimmy-Limit"] == "fast_rate" and int(a[1]["Retry-After"]) >= 1 and named(a[2])
               for a in limited)
    status, _, _ = team.request("POST", "/api/v1/hopf", {"config": "original", "Fz": 170001}, headers=bob)
    assert status == 200  # another user's bucket is full
    status, headers, _ = team.request("POST", "/api/v1/hopf", {"config": "original", "Fz": 160000}, headers=alice)
    assert status == 200 and headers["X-Shimmy-Cache"] == "hit"  # a cached answer costs nothing
    print(f"\nrate: alice 14 uncached /hopf in a row -> {len(ok)} answered, {len(limited)} refused (429 fast_rate, "
          f"Retry-After {limited[0][1]['Retry-After']} s); bob's next: 200")


# -- hostile input with auth on ------------------------------------------------------------------


def test_hostile_campaign_with_auth_on_gives_no_5xx(team):
    rng = random.Random(28)
    alice, secret = team.auth["alice"], team.tokens["alice"][1]
    credentials = [("good", alice)] * 6 + [("none", {}), ("wrong", bearer("shm_" + "C" * 43)),
                                           ("wrong", bearer(secret[::-1])), ("wrong", {"Authorization": "Basic eA=="}),
                                           ("read", team.auth["reader"])]
    api = [(*api_case(rng), rng.choice(credentials)) for _ in range(7500)]  # with the callbacks: 10 000 in all
    status, _, deps = team.request("GET", "/_dash-dependencies", headers=alice)
    assert status == 200
    callbacks = [(*callback_case(rng, deps), rng.choice(credentials)) for _ in range(2500)]

    def one(case):
        path, body, headers, (kind, credential) = case
        return kind, team.request("POST", path, raw=body, headers={**headers, **credential}, timeout=120)

    clock = time.perf_counter()
    with concurrent.futures.ThreadPoolExecutor(4) as pool:
        answers = list(pool.map(one, api + [("/_dash-update-component", b, h, c) for b, h, c in callbacks]))
    elapsed = time.perf_counter() - clock
    statuses = [a[1][0] for a in answers]
    server_errors = [a for a in answers if a[1][0] >= 500]
    unauthenticated = [a for a in answers if a[0] in ("none", "wrong")]
    unnamed = [a for a in answers if 400 <= a[1][0] < 500 and not named(a[1][2])]
    print(f"\nhostile campaign, auth on: {len(api)} API + {len(callbacks)} callback requests in {elapsed:.0f} s; "
          f"5xx: {len(server_errors)}; 401: {statuses.count(401)} (all {len(unauthenticated)} without a good "
          f"credential), 403: {statuses.count(403)}, 429: {statuses.count(429)}, other 4xx: "
          f"{sum(400 <= s < 500 for s in statuses) - statuses.count(401) - statuses.count(403) - statuses.count(429)}"
          f", 2xx: {sum(s < 300 for s in statuses)}; 4xx not naming their field: {len(unnamed)}")
    assert not server_errors, server_errors[:3]
    assert all(a[1][0] == 401 for a in unauthenticated)
    assert not unnamed, unnamed[:3]
    cancel_everything(team)


def test_tokens_never_appear_in_the_logs(team):
    """Every request in the access log at the debug level (TEAM's GUNICORN_CMD_ARGS): a token sent in the header,
    a wrong one, one pasted into the sign-in form, and the session cookie appear nowhere."""
    form = {"Content-Type": "application/x-www-form-urlencoded"}
    secret = team.tokens["root"][1]
    assert team.request("POST", "/api/v1/hopf", {"config": "nes", "Fz": 151234}, headers=bearer(secret))[0] == 200
    assert team.request("POST", "/api/v1/hopf", {"config": "nes", "Fz": 151234},
                        headers=bearer(secret[:-3] + "abc"))[0] == 401
    status, headers, _ = raw(team, "POST", "/login", urllib.parse.urlencode({"token": secret}).encode(), form)
    assert status == 303
    cookie = _cookie(headers).split(";")[0].split("=", 1)[1]
    assert team.request("GET", "/api/v1/parameters", headers={"Cookie": f"shimmy_session={cookie}"})[0] == 200
    raw(team, "POST", "/login", urllib.parse.urlencode({"token": secret[:-3] + "abc"}).encode(), form)
    time.sleep(1.0)  # the access log is written after the response
    log = (team.cache_dir / "gunicorn.log").read_text(errors="replace")
    assert '"POST /api/v1/hopf HTTP/1.1" 401' in log and '"POST /login HTTP/1.1" 303' in log  # it logs requests
    leaked = [user for user, (_, secret) in team.tokens.items() if secret in log or secret[4:20] in log]
    assert not leaked
    assert "shimmy_session=" not in log and cookie not in log and cookie.split(".")[-1] not in log
    assert secret[:-3] + "abc" not in log
    print(f"\nlogs: {len(log.splitlines())} lines (access log and debug level), no token or session in them")


def test_sign_in_attempts_are_limited(team):
    form = {"Content-Type": "application/x-www-form-urlencoded"}
    answers = []
    for k in range(20):  # the limit is 8 a minute from one address (the window may turn once meanwhile)
        answers.append(raw(team, "POST", "/login", urllib.parse.urlencode({"token": f"shm_wrong{k:040d}"}).encode(),
                           form))
        if answers[-1][0] == 429:
            break
    status, headers, page = answers[-1]
    assert status == 429 and 1 <= int(headers["Retry-After"]) <= 60 and "too many sign-in attempts" in page
    # wrong attempts are 401 until the limit: 8 a minute from one address, shared with the sign-ins of
    # the tests before this one in the same minute (so there may be fewer than 8 here, never more)
    assert {a[0] for a in answers[:-1]} <= {401} and len(answers) - 1 <= 8
    good = raw(team, "POST", "/login", urllib.parse.urlencode({"token": team.tokens["bob"][1]}).encode(), form)
    assert good[0] == 429  # the limit counts attempts, right or wrong: no guessing behind a good one
    assert team.request("GET", "/api/v1/parameters", headers=team.auth["bob"])[0] == 200  # API tokens go on
    print(f"\nsign-in: {len(answers) - 1} wrong attempts answered 401, then 429 (Retry-After "
          f"{headers['Retry-After']} s)")


# -- quick computations under admission control ---------------------------------------------------


@pytest.fixture(scope="module")
def narrow(tmp_path_factory):
    """One web worker with 7 threads, one computation slot and two waiting places (auth off)."""
    server = start_server(tmp_path_factory.mktemp("narrow"), {"SHIMMY_WEB_THREADS": "7",
                                                              "SHIMMY_MAX_FAST_COMPUTATIONS": "1",
                                                              "SHIMMY_FAST_WAIT_SECONDS": "2"}, workers=1)
    yield server
    stop_server(server)


def test_a_burst_of_uncached_sensitivities_is_refused_not_left_stalling_the_worker(narrow):
    stop, health = threading.Event(), []

    def watch():
        while not stop.is_set():
            clock = time.perf_counter()
            status, _, _ = narrow.request("GET", "/api/v1/health", timeout=30)
            health.append((status, time.perf_counter() - clock))
            time.sleep(0.05)

    watcher = threading.Thread(target=watch)
    watcher.start()
    clock = time.perf_counter()
    with concurrent.futures.ThreadPoolExecutor(16) as pool:
        answers = list(pool.map(lambda k: narrow.request("POST", "/api/v1/sensitivity", {
            "config": "nes", "Fz": 150000 + 100 * k}, timeout=120), range(16)))
    elapsed = time.perf_counter() - clock
    stop.set()
    watcher.join()
    ok = [a for a in answers if a[0] == 200]
    busy = [a for a in answers if a[0] == 429]
    times = [t for _, t in health]
    print(f"\nburst: 16 uncached /sensitivity at once on 1 worker (1 slot, 2 waiting places): {len(ok)} answered, "
          f"{len(busy)} refused 429 in {elapsed:.1f} s; health during it: {len(times)} answers, median "
          f"{1e3 * statistics.median(times):.0f} ms, max {1e3 * max(times):.0f} ms")
    assert len(ok) + len(busy) == 16 and ok and len(busy) >= 8
    assert all(a[1]["X-Shimmy-Limit"] == "fast_concurrency" and a[1]["Retry-After"] and named(a[2]) for a in busy)
    assert all(s == 200 for s, _ in health) and statistics.median(times) < 0.5 and max(times) < 3
    # What was computed is answered from the cache at once, however busy the worker.
    status, headers, _ = narrow.request("POST", "/api/v1/sensitivity", {"config": "nes", "Fz": 150000 + 100 * next(
        k for k, a in enumerate(answers) if a[0] == 200)})
    assert status == 200 and headers["X-Shimmy-Cache"] == "hit"


# -- bounded storage ---------------------------------------------------------------------------


def disk(path: Path) -> int:
    return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())


def parts(store: Path) -> dict[str, int]:
    """Bytes on disk of a diskcache store: its values in files, its database, its write-ahead log."""
    files = sum(p.stat().st_size for p in store.rglob("*.val"))
    size = {name: (store / name).stat().st_size if (store / name).exists() else 0
            for name in ("cache.db", "cache.db-wal")}
    return {"values": files, "db": size["cache.db"], "wal": size["cache.db-wal"], "all": disk(store)}


def test_a_flood_of_distinct_requests_leaves_the_disk_bounded(tmp_path):
    limits = {"SHIMMY_CACHE_SIZE_MB": "2", "SHIMMY_MAX_JOB_RECORDS": "100"}
    server = start_server(tmp_path, limits)
    try:
        clock = time.perf_counter()
        with concurrent.futures.ThreadPoolExecutor(6) as pool:
            statuses = list(pool.map(lambda k: server.request("POST", "/api/v1/devices", {
                "v_max": 0.01 + k * 0.003})[0], range(5000)))
        flood = time.perf_counter() - clock
        assert statuses.count(200) == 5000, {s: statuses.count(s) for s in set(statuses)}
        results = parts(tmp_path / "results")
        jobs_made = []

        def simulate_then_job(k):
            body = {"config": "nes", "V": 20 + k * 0.01, "Fz": 150000, "t_end": 0.5}
            assert server.request("POST", "/api/v1/simulate", body)[0] == 200
            status, _, job = server.request("POST", "/api/v1/jobs", {"analysis": "simulate", **body})
            assert status == 202 and job["status"] == "done", job  # answered from the cache: a record at once
            return job["id"]

        with concurrent.futures.ThreadPoolExecutor(6) as pool:
            jobs_made = list(pool.map(simulate_then_job, range(500)))
        from shimmy.service import jobs

        with cache_env(tmp_path):
            records = [k for k in jobs.store() if isinstance(k, tuple) and k[0] == "job"]
        results_after, job_store = parts(tmp_path / "results"), parts(tmp_path / "jobs")
        newest = server.request("GET", f"/api/v1/jobs/{jobs_made[-1]}")
        oldest = server.request("GET", f"/api/v1/jobs/{jobs_made[0]}")
        mb = lambda d: ", ".join(f"{k} {v / 1e6:.2f}" for k, v in d.items())  # noqa: E731
        print(f"\nstorage: 5000 distinct /devices in {flood:.0f} s (37 kB each, 185 MB asked) -> result cache "
              f"(MB) {mb(results)} (limit 2 MB of values); then 500 job records -> {len(records)} kept (limit 100); "
              f"result cache {mb(results_after)}; job store {mb(job_store)}; newest job {newest[0]} with its "
              f"result, oldest {oldest[0]}")
        # The limit bounds the values (diskcache evicts the least recently stored past it, one value over at most);
        # the database holds the keys and small values, and sqlite's write-ahead log, checkpointed every 1000 pages
        # (4 MB) when no reader holds it back, is an overhead of a few MB that does not grow with the flood.
        for store in (results, results_after):
            assert store["values"] <= 2.1e6 and store["db"] < 2e6 and store["wal"] < 16e6
        assert len(records) <= 100 + 16 + 8 + 2 and job_store["db"] < 2e6 and job_store["wal"] < 16e6
        assert newest[0] == 200 and newest[2]["result"] is not None  # the latest results stay readable
        assert oldest[0] == 404  # the oldest record went first
    finally:
        stop_server(server)


# -- restarts ----------------------------------------------------------------------------------


def job_workers(cache_dir: Path):
    out = []
    for p in psutil.process_iter(["cmdline"]):
        try:
            if "shimmy.service.worker" in (p.info["cmdline"] or []) and \
                    p.environ().get("SHIMMY_CACHE_DIR") == str(cache_dir):
                out.append(p)
        except psutil.Error:
            pass
    return out


def test_queued_and_running_jobs_survive_a_restart_and_run_after_it(tmp_path):
    from shimmy.service import jobs

    limits = {"SHIMMY_MAX_RUNNING_JOBS": "1"}
    server = start_server(tmp_path, limits)
    quick = [{"analysis": "simulate", "config": "nes", "V": 41 + k, "Fz": 150000, "t_end": 3} for k in range(2)]
    try:
        # every web worker serving first: one still loading its kernels holds the stop back for seconds (it
        # takes gunicorn's signal after), long enough for a job of a few seconds to end before the stop (CI)
        until(lambda: _workers_ready(tmp_path), 120, "the web workers to load their kernels")
        # a job that runs for many seconds (a cold map), not a diagram of two: still running at the stop
        _, _, long_job = server.request("POST", "/api/v1/jobs", {"analysis": "map", "config": "original"})
        until(lambda: server.request("GET", f"/api/v1/jobs/{long_job['id']}")[2]["status"] == "running", 60,
              "the long job to run")
        queued = [server.request("POST", "/api/v1/jobs", q)[2]["id"] for q in quick]
        assert server.request("GET", f"/api/v1/jobs/{long_job['id']}")[2]["status"] == "running"
    finally:
        stop_server(server)  # graceful: the running job's process ends, the job waits queued again
    with cache_env(tmp_path):
        store = jobs.store()
        assert store.get("queue") == [long_job["id"], *queued] and store.get("running") == {}
        requeued = store.get(("job", long_job["id"]))  # read, not jobs.get: that would start it from here
    assert requeued["status"] == "queued" and "server stopped" in requeued["message"]
    assert not job_workers(tmp_path)
    clock = time.perf_counter()
    server = start_server(tmp_path, limits)
    try:
        ids = [long_job["id"], *queued]

        def finished():  # read from the store: no request to the server starts them
            with cache_env(tmp_path):
                found = [jobs.store().get(("job", i)) for i in ids]
            return all(j["status"] in ("done", "failed", "cancelled") for j in found) and found

        found = until(finished, 240, "the jobs queued before the restart to finish", every=0.5)
        ran = time.perf_counter() - clock
        assert [j["status"] for j in found] == ["done"] * 3, [(j["status"], j["error"]) for j in found]
        assert server.request("GET", f"/api/v1/jobs/{queued[-1]}")[2]["result"]["amplitude"]["psi"] >= 0
        print(f"\nrestart (graceful): 1 running + 2 queued jobs before the stop; all 3 done {ran:.0f} s after the "
              "start (server start included), with no request")
        # An unclean stop (the whole server killed, as a container's end does): the job runs again once.
        _, _, killed = server.request("POST", "/api/v1/jobs", {**LONG, "Fz": 330000})
        until(lambda: server.request("GET", f"/api/v1/jobs/{killed['id']}")[2]["status"] == "running", 60,
              "the second long job to run")
        victims = [server.proc.pid, *(c.pid for c in psutil.Process(server.proc.pid).children(recursive=True))]
        workers = job_workers(tmp_path)
        # the server first: a web worker that outlives its job's process by a moment records the job failed
        # (as it should when only that process dies), which is not what killing everything at once leaves
        for pid in victims:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
        for worker in workers:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(worker.pid, signal.SIGKILL)
        server.proc.wait(timeout=30)
        server.log.close()
        with cache_env(tmp_path):
            assert jobs.store().get(("job", killed["id"]))["status"] == "running"  # as the kill left it
        server = start_server(tmp_path, limits)
        again = until(lambda: (j := server.request("GET", f"/api/v1/jobs/{killed['id']}")[2])["status"] in (
            "done", "failed") and j, 240, "the killed job to run again")
        assert again["status"] == "done", again
        with cache_env(tmp_path):
            assert jobs.store().get(("job", killed["id"]))["restarts"] == 1
        print("restart (kill -9 of the server and its job): the job queued again at the start and done")
    finally:
        stop_server(server)


def test_a_finished_worker_waits_idle_for_the_next_job_and_ends_with_the_server(tmp_path):
    """A worker with no job left stays idle (listed in the store, holding no slot) and the next job is
    handed to it: the same warm process runs it. Its linger time up, it ends by itself; the server's stop
    ends it too."""
    from shimmy.service import jobs

    def run(server, V):
        _, _, job = server.request("POST", "/api/v1/jobs", {"analysis": "simulate", "config": "nes", "V": V,
                                                            "Fz": 150000, "t_end": 2})
        done = until(lambda: (j := server.request("GET", f"/api/v1/jobs/{job['id']}")[2])["status"] in (
            "done", "failed") and j, 120, f"the job at V = {V} to finish")
        assert done["status"] == "done", done
        with cache_env(tmp_path):
            return jobs.store().get(("job", job["id"]))["worker"]

    def idle():
        with cache_env(tmp_path):
            s = jobs.store()
            return s.get("running", {}) == {} and {holder["pid"] for holder in s.get("idle", {}).values()}

    server = start_server(tmp_path, {"SHIMMY_JOB_WORKER_LINGER_SECONDS": "60"})
    try:
        first = run(server, 41)
        assert until(idle, 30, "the worker to be listed idle") == {first}
        assert [p.pid for p in job_workers(tmp_path)] == [first]
        assert run(server, 42) == first  # handed to the idle worker: no new process
        assert until(idle, 30, "the worker idle again") == {first}
    finally:
        stop_server(server)
    assert not job_workers(tmp_path)  # the idle worker ended with the server
    with cache_env(tmp_path):
        assert jobs.store().get("idle") == {}
    server = start_server(tmp_path, {"SHIMMY_JOB_WORKER_LINGER_SECONDS": "1"})
    try:
        third = run(server, 43)
        until(lambda: not job_workers(tmp_path), 60, "the idle worker to end after its linger time")
        with cache_env(tmp_path):
            assert jobs.store().get("idle") == {}
        assert run(server, 44) != third  # a new process (the old one ended: waited for above)
    finally:
        stop_server(server)
