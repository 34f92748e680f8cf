"""A service a team can share, without a server: the tokens store, where the server listens and what
that asks for, fair shares of the job queue, bounded job records, restarts (the job store's side)."""

from __future__ import annotations

import json
import os
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest

from shimmy.service import admission, jobs, schemas, settings, tokens

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def private(tmp_path, monkeypatch):
    """A cache directory (and tokens file) of the test's own."""
    monkeypatch.setenv("SHIMMY_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("SHIMMY_TOKENS_FILE", raising=False)
    return tmp_path


def test_a_token_is_kept_only_hashed_in_a_private_file_and_revoked_at_once(private):
    record, secret = tokens.create("alice", "compute")
    assert secret.startswith("shm_") and len(secret) >= 40 and record.id.startswith("tok_")
    path = private / "tokens.json"
    text = path.read_text()
    assert secret not in text and tokens.digest(secret) in text  # SHA-256 of the secret, never the secret
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    assert tokens.verify(secret) == record
    for wrong in (secret[:-1] + ("A" if secret[-1] != "A" else "B"), "", "shm_" + "x" * 43, secret + " ", "é" * 50,
                  "x" * 10_000, None):
        assert tokens.verify(wrong) is None
    other, other_secret = tokens.create("bob", "read")
    assert tokens.verify(other_secret).user == "bob" and [t.id for t in tokens.listed()] == [record.id, other.id]
    assert tokens.revoke(record.id) == [record]
    assert tokens.verify(secret) is None and tokens.by_id(record.id) is None  # the next check refuses it
    assert tokens.verify(other_secret) is not None
    with pytest.raises(tokens.TokenError, match="user="):
        tokens.create("bad name", "read")
    with pytest.raises(tokens.TokenError, match="scope="):
        tokens.create("carol", "root")


def test_the_tokens_command_prints_the_token_last_and_lists_no_secret(private):
    env = {**os.environ, "SHIMMY_CACHE_DIR": str(private), "PYTHONPATH": str(ROOT)}

    def run(*args):
        return subprocess.run([sys.executable, "-m", "shimmy", "tokens", *args], capture_output=True, text=True,
                              env=env, cwd=ROOT, timeout=120)

    made = run("create", "--user", "alice", "--scope", "admin")
    assert made.returncode == 0, made.stderr
    secret = made.stdout.strip().splitlines()[-1]
    assert tokens.verify(secret).user == "alice" and tokens.verify(secret).scope == "admin"
    listed = run("list", "--json")
    rows = json.loads(listed.stdout)
    assert [(r["user"], r["scope"]) for r in rows] == [("alice", "admin")] and secret not in listed.stdout
    assert "digest" not in listed.stdout and tokens.digest(secret) not in listed.stdout
    assert run("create", "--user", "x", "--scope", "root").returncode == 2
    assert run("revoke", "tok_00000000").returncode == 2
    gone = run("revoke", "--user", "alice")
    assert gone.returncode == 0 and rows[0]["id"] in gone.stdout and tokens.verify(secret) is None


@pytest.mark.parametrize("address, loopback", [
    ("127.0.0.1:8050", True), ("localhost:8050", True), ("[::1]:8050", True), ("127.0.0.5:1", True), ("::1", True),
    ("0.0.0.0:8050", False), ("[::]:8050", False), (":8050", False), ("192.0.2.7:8050", False),
    ("unix:/tmp/shimmy.sock", False), ("fd://3", False), ("no-such-host.invalid:8050", False)])
def test_where_the_server_listens(address, loopback):
    assert settings.is_loopback(address) is loopback


@pytest.mark.parametrize("env, listen, outcome", [
    ({}, ["127.0.0.1:8050"], "none"),
    ({}, ["0.0.0.0:8050"], "token"),
    ({"SHIMMY_AUTH": "token"}, ["127.0.0.1:8050"], "token"),
    ({"SHIMMY_AUTH": "none"}, ["127.0.0.1:8050", "localhost:9000"], "none"),
    ({"SHIMMY_AUTH": "none"}, ["0.0.0.0:8050"], "SHIMMY_ALLOW_ANONYMOUS"),
    ({"SHIMMY_AUTH": "none", "SHIMMY_ALLOW_ANONYMOUS": "1"}, ["0.0.0.0:8050"], "none"),
    ({"SHIMMY_AUTH": "oidc"}, ["127.0.0.1:8050"], "not built"),
    ({"SHIMMY_AUTH": "ldap"}, ["127.0.0.1:8050"], "not one of"),
])
def test_auth_mode_from_the_listen_address_and_the_settings(monkeypatch, env, listen, outcome):
    for name in ("SHIMMY_AUTH", "SHIMMY_ALLOW_ANONYMOUS"):
        monkeypatch.delenv(name, raising=False)
    for name, value in env.items():
        monkeypatch.setenv(name, value)
    if outcome in ("none", "token"):
        assert settings.auth_mode(listen) == outcome
    else:
        with pytest.raises(settings.AuthSettingError, match=outcome):
            settings.auth_mode(listen)


def test_gunicorn_refuses_to_start_beyond_loopback_without_authentication(tmp_path):
    """SHIMMY_AUTH=none on 0.0.0.0: the arbiter stops in on_starting, before it binds anything."""
    env = {**os.environ, "SHIMMY_CACHE_DIR": str(tmp_path), "SHIMMY_AUTH": "none", "PYTHONPATH": str(ROOT)}
    env.pop("SHIMMY_ALLOW_ANONYMOUS", None)
    done = subprocess.run([sys.executable, "-m", "gunicorn", "app:server", "--bind", "0.0.0.0:0", "--workers", "1",
                           "--no-control-socket"], cwd=ROOT, env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode != 0
    assert "SHIMMY_ALLOW_ANONYMOUS" in done.stderr and "Listening at" not in done.stderr


# -- fair shares ------------------------------------------------------------------------------

MAP = {"config": "original", "fz_min": 100000, "fz_max": 400000, "resolution": 3}


@pytest.fixture
def held(private, monkeypatch):
    """A job store in which no job starts (no slot): submitted jobs stay queued."""
    monkeypatch.setattr(settings, "MAX_RUNNING_JOBS", 0)
    monkeypatch.setattr(settings, "MAX_QUEUED_JOBS", 8)
    monkeypatch.setattr(settings, "MAX_JOBS_PER_USER", 3)
    monkeypatch.setattr(settings, "QUEUE_RESERVED", 2)
    return private


def _map(k: int):
    return schemas.validate("map", {**MAP, "fz_max": 400000 + 1000 * k})


def test_a_user_gets_a_share_of_the_queue_and_the_last_places_are_kept_for_others(held):
    mine = [jobs.submit_canonical("map", _map(k), user="alice") for k in range(3)]
    with pytest.raises(jobs.QueueFull) as refused:
        jobs.submit_canonical("map", _map(3), user="alice")
    assert refused.value.limit == "jobs_per_user" and "SHIMMY_MAX_JOBS_PER_USER" in str(refused.value)
    assert refused.value.headers()["Retry-After"] == str(settings.JOB_RETRY_AFTER_SECONDS)
    # The same question as one of alice's is that job, whoever asks: no new place taken.
    again = jobs.submit_canonical("map", _map(0), user="bob")
    assert again["id"] == mine[0]["id"] and again["users"] == ["alice", "bob"]
    for k, user in enumerate(["bob", "carol", "dave"]):
        jobs.submit_canonical("map", _map(10 + k), user=user)
    assert len(jobs.store().get("queue")) == 6  # 2 places left: kept for users with nothing waiting
    with pytest.raises(jobs.QueueFull) as reserved:
        jobs.submit_canonical("map", _map(20), user="bob")
    assert reserved.value.limit == "jobs_queue_reserved"
    jobs.submit_canonical("map", _map(21), user="erin")  # a first job still gets in
    jobs.submit_canonical("map", _map(22), user="frank")
    with pytest.raises(jobs.QueueFull) as full:
        jobs.submit_canonical("map", _map(23), user="gina")
    assert full.value.limit == "jobs_queue" and "queue is full" in str(full.value)
    # Anonymous (the server does not know its users): the global limits only, as before.
    listing = jobs.listing()
    assert listing["by_user"]["alice"] == {"queued": 3, "running": 0} and listing["total"] == 8
    assert {j["user"] for j in listing["jobs"]} == {"alice", "bob", "carol", "dave", "erin", "frank"}


def test_a_free_slot_goes_to_the_user_who_runs_the_fewest(held, monkeypatch):
    monkeypatch.setattr(settings, "MAX_JOBS_PER_USER", 8)
    monkeypatch.setattr(settings, "QUEUE_RESERVED", 0)
    monkeypatch.setattr(settings, "MAX_RUNNING_JOBS_PER_USER", 1)
    a = [jobs.submit_canonical("map", _map(k), user="alice")["id"] for k in range(3)]
    b = jobs.submit_canonical("map", _map(9), user="bob")["id"]
    s = jobs.store()
    queue, running = list(s.get("queue")), {}
    first, owner = jobs._choose(s, queue, running)
    assert (first, owner) == (a[0], "alice")
    running[first] = {"user": "alice"}
    second, owner = jobs._choose(s, queue, running)
    assert (second, owner) == (b, "bob")  # behind alice's two, but alice runs one already
    running[second] = {"user": "bob"}
    assert jobs._choose(s, queue, running) == (None, None)  # each runs their share: the rest wait
    assert queue == a[1:]


# -- bounded storage -------------------------------------------------------------------------


def _cached_simulation(k: int):
    """A simulate request whose result is in the cache (a fake one: the job is answered from it at once)."""
    from shimmy.service import cache

    request = schemas.validate("simulate", {"config": "nes", "V": 30.0 + k * 1e-3, "Fz": 150000, "t_end": 1})
    cache.put(cache.key("simulate", request), {"fake": k})
    return request


def test_job_records_are_capped_and_expire_while_old_results_stay_readable(private, monkeypatch):
    monkeypatch.setattr(settings, "MAX_JOB_RECORDS", 20)
    made = [jobs.submit_canonical("simulate", _cached_simulation(k)) for k in range(120)]
    assert all(j["status"] == "done" for j in made)
    s = jobs.store()
    kept = [k for k in s if isinstance(k, tuple) and k[0] == "job"]
    assert len(kept) <= 20 + jobs._BOOKKEEPING + settings.MAX_QUEUED_JOBS + settings.MAX_RUNNING_JOBS
    assert jobs.prune() >= 0 and len([k for k in s if isinstance(k, tuple) and k[0] == "job"]) <= 20
    assert jobs.get(made[0]["id"]) is None  # the oldest went first
    newest = jobs.get(made[-1]["id"])
    assert newest is not None and jobs.public(newest)["result"] == {"fake": 119}
    # Retention: a finished record expires; an active one never does.
    monkeypatch.setattr(settings, "JOB_RETENTION_HOURS", 1 / 3600)  # one second
    monkeypatch.setattr(settings, "MAX_RUNNING_JOBS", 0)
    short = jobs.submit_canonical("simulate", _cached_simulation(500))
    waiting = jobs.submit_canonical("map", _map(1))
    time.sleep(1.5)
    assert jobs.get(short["id"]) is None and jobs.get(waiting["id"])["status"] == "queued"


def test_a_job_whose_result_left_the_cache_says_so(private):
    from shimmy.service import cache

    job = jobs.submit_canonical("simulate", _cached_simulation(1))
    cache.results().delete(job["result_key"])
    shown = jobs.public(jobs.get(job["id"]))
    assert shown["status"] == "done" and shown["result"] is None and "left the result cache" in shown["message"]


# -- restarts ----------------------------------------------------------------------------------


def test_a_job_whose_process_ended_with_the_server_is_queued_again_once_then_failed(held):
    job = jobs.submit_canonical("map", _map(1), user="alice")
    s = jobs.store()
    gone = {"pid": 2 ** 22 + 1, "started": 1.0, "host": jobs.HOST, "claimed": time.time(), "user": "alice"}

    def as_running():
        with s.transact():
            s.set("queue", [q for q in s.get("queue") if q != job["id"]])
            s.set("running", {job["id"]: gone})
            jobs.update(job["id"], status="running", message="running")

    as_running()
    assert jobs.server_started() == {"requeued": [job["id"]], "failed": []}
    again = jobs.get(job["id"])
    assert again["status"] == "queued" and again["restarts"] == 1 and "queued again" in again["message"]
    assert s.get("queue")[0] == job["id"] and s.get("running") == {}
    as_running()
    assert jobs.server_started() == {"requeued": [], "failed": [job["id"]]}
    failed = jobs.get(job["id"])
    assert failed["status"] == "failed" and "submit it again" in failed["error"] and s.get("running") == {}


def test_a_job_whose_worker_ended_before_starting_it_is_queued_again_once_then_failed(held):
    """A job handed to a process that ends before starting it (a worker that died starting, an idle one
    killed) never ran: queued again at the head of the queue (JOB_RESTARTS times), whether the ending is
    seen by the server's check of slot holders (pump) or by the thread that started the process; then
    failed, saying it never started. A job that was running when its process ended is failed at once."""
    job = jobs.submit_canonical("map", _map(6), user="alice")
    s = jobs.store()

    def handed_to_a_process_that_ends(job_id: str, status: str) -> tuple[subprocess.Popen, dict]:
        proc = subprocess.Popen([sys.executable, "-c", "raise SystemExit(3)"])
        holder = {"pid": proc.pid, "started": jobs._create_time(proc.pid), "host": jobs.HOST,
                  "claimed": time.time(), "user": "alice"}
        with s.transact():
            s.set("queue", [q for q in s.get("queue") if q != job_id])
            s.set("running", {job_id: holder})
        if status != "queued":
            jobs.update(job_id, status=status, message=status)
        proc.wait(30)
        return proc, holder

    proc, holder = handed_to_a_process_that_ends(job["id"], "queued")
    jobs.pump()  # finds the slot holder gone
    again = jobs.get(job["id"])
    assert again["status"] == "queued" and again["restarts"] == 1, again
    assert "ended before starting it" in again["message"]
    assert s.get("queue")[0] == job["id"] and s.get("running") == {}
    jobs._lost(s, job["id"], holder, 3)  # another process that saw the same holder: settled already, no change
    assert jobs.get(job["id"])["status"] == "queued" and s.get("queue")[0] == job["id"]
    jobs._wait(handed_to_a_process_that_ends(job["id"], "queued")[0], job["id"])  # the starter sees it end
    failed = jobs.get(job["id"])
    assert failed["status"] == "failed" and s.get("running") == {} and job["id"] not in s.get("queue")
    assert "ended before starting it (exit status 3)" in failed["error"] and "submit it again" in failed["error"]
    ran = jobs.submit_canonical("map", _map(7), user="alice")
    jobs._wait(handed_to_a_process_that_ends(ran["id"], "running")[0], ran["id"])
    failed = jobs.get(ran["id"])
    assert failed["status"] == "failed" and failed["restarts"] == 0
    assert "ended without a result (exit status 3)" in failed["error"]


def test_a_job_handed_to_a_slot_has_a_fresh_heartbeat(held, monkeypatch):
    """A holder on another host is judged alive by its job's heartbeat: a job queued for an hour and then
    handed on must not read as stale (and be settled under its new worker) before that worker's first update."""
    job = jobs.submit_canonical("map", _map(8))
    jobs.update(job["id"], heartbeat=time.time() - 3600)
    monkeypatch.setattr(settings, "MAX_RUNNING_JOBS", 1)
    monkeypatch.setattr(jobs, "_start", lambda s, job_id: None)  # the slot is taken; no process starts
    jobs.pump()
    s = jobs.store()
    assert list(s.get("running")) == [job["id"]] and time.time() - jobs.get(job["id"])["heartbeat"] < 60
    elsewhere = {"pid": 1, "started": 1.0, "host": "another-host", "claimed": time.time(), "user": None}
    assert jobs._alive(s, job["id"], elsewhere)


def test_draining_starts_nothing_until_resumed(held, monkeypatch):
    monkeypatch.setattr(settings, "MAX_RUNNING_JOBS", 2)
    jobs.drain()
    job = jobs.submit_canonical("map", _map(2))  # submissions still queue
    assert jobs.get(job["id"])["status"] == "queued" and jobs.counts() == {"queued": 1, "running": 0}
    assert jobs.listing()["draining"]
    assert jobs.server_started() == {"requeued": [], "failed": []} and not jobs.draining()  # a start resumes
    jobs.cancel(job["id"])


# -- admission of quick computations ------------------------------------------------------------


def test_the_fast_gate_refuses_beyond_its_slots_and_a_users_share(monkeypatch, private):
    import threading

    monkeypatch.setattr(settings, "MAX_FAST_COMPUTATIONS", 1)
    monkeypatch.setattr(settings, "FAST_WAITING", 1)
    monkeypatch.setattr(settings, "FAST_WAIT_SECONDS", 0.3)
    monkeypatch.setattr(settings, "FAST_PER_USER_PER_SECOND", 0)
    inside, leave = threading.Event(), threading.Event()

    def hold():
        with admission.fast_slot("hopf", "alice"):
            inside.set()
            leave.wait(10)

    t = threading.Thread(target=hold)
    t.start()
    inside.wait(10)
    with pytest.raises(admission.Busy) as mine:  # alice holds her share of this worker
        with admission.fast_slot("hopf", "alice"):
            pass
    assert mine.value.limit == "fast_per_user"
    clock = time.monotonic()
    with pytest.raises(admission.Busy) as crowded:  # bob waits for the slot, then is refused in bounded time
        with admission.fast_slot("hopf", "bob"):
            pass
    assert crowded.value.limit == "fast_concurrency" and time.monotonic() - clock < 2
    assert crowded.value.headers()["X-Shimmy-Limit"] == "fast_concurrency"
    leave.set()
    t.join()
    with admission.fast_slot("hopf", "bob"):
        assert admission.fast_load() == {"computing": 1, "waiting": 0}
    assert admission.fast_load() == {"computing": 0, "waiting": 0}


def test_the_rate_per_user_refills(monkeypatch, private):
    monkeypatch.setattr(settings, "FAST_PER_USER_PER_SECOND", 4.0)
    monkeypatch.setattr(settings, "FAST_PER_USER_BURST", 2.0)
    admission.take_rate("hopf", "alice")
    admission.take_rate("hopf", "alice")
    with pytest.raises(admission.Busy) as refused:
        admission.take_rate("hopf", "alice")
    assert refused.value.limit == "fast_rate" and refused.value.retry_after >= 1
    admission.take_rate("hopf", "bob")  # another user's bucket is full
    time.sleep(0.3)
    admission.take_rate("hopf", "alice")  # refilled at 4 a second


# -- idle job workers ---------------------------------------------------------------------------


def _me() -> dict:
    """This process as a job worker of the store's current generation."""
    return {"pid": os.getpid(), "started": jobs._create_time(os.getpid()), "host": jobs.HOST,
            "generation": jobs.store().get("generation")}


def test_an_idle_worker_is_handed_the_next_job_and_leaves_when_the_server_stops(held, monkeypatch):
    """A worker whose queue is empty is listed idle (in the same transaction that frees its slot); pump
    hands the next job to it (no process started); the server's stop unlists it and it leaves."""
    monkeypatch.setattr(settings, "MAX_RUNNING_JOBS", 1)
    monkeypatch.setattr(settings, "JOB_WORKER_LINGER_SECONDS", 30.0)
    monkeypatch.setattr(jobs, "_start", lambda s, job_id: pytest.fail("a process was started for " + job_id))
    jobs.server_started()
    me, s = _me(), jobs.store()
    with s.transact():
        s.set("running", {"finished": {**me, "claimed": time.time(), "user": None}})
    assert jobs._next("finished", me) is None
    assert list(s.get("idle").values()) == [me] and s.get("running") == {}
    job = jobs.submit_canonical("map", _map(3))  # submit pumps: handed to this process
    assert s.get("running")[job["id"]]["pid"] == me["pid"] and s.get("idle") == {}
    assert jobs._linger(me) == job["id"]
    jobs._release(s, job["id"])
    assert jobs._next(job["id"], me) is None and len(s.get("idle")) == 1
    with s.transact():  # the server's stop unlists it (and signals its group: not this test process)
        s.set("idle", {})
    clock = time.monotonic()
    assert jobs._linger(me) is None and time.monotonic() - clock < 5  # no longer listed: it leaves at once


def test_a_worker_of_an_earlier_server_takes_no_further_job(held, monkeypatch):
    """After a restart (a new generation) a worker that outlived the old server, running old code, is
    neither listed idle nor handed jobs, nor does it take the next queued one."""
    monkeypatch.setattr(settings, "MAX_RUNNING_JOBS", 1)
    monkeypatch.setattr(settings, "JOB_WORKER_LINGER_SECONDS", 30.0)
    started = []
    monkeypatch.setattr(jobs, "_start", lambda s, job_id: started.append(job_id))
    jobs.server_started()
    old, s = _me(), jobs.store()
    with s.transact():
        s.set("running", {"finished": {**old, "claimed": time.time(), "user": None}})
    jobs.server_started()  # the server restarts while that worker runs its job
    waiting = jobs.submit_canonical("map", _map(4))
    assert started == [] and s.get("queue") == [waiting["id"]]  # its slot is still held
    assert jobs._next("finished", old) is None  # the queued job is not its to take
    assert s.get("idle", {}) == {} and jobs._linger(old) is None
    jobs.pump()  # the slot is free: a new worker starts for it
    assert started == [waiting["id"]]
    stale = {**old, "generation": "earlier"}
    with s.transact():  # an idle entry of an earlier generation is never handed a job (and is dropped)
        s.set("running", {})
        s.set("idle", {jobs._idle_key(stale): stale})
    another = jobs.submit_canonical("map", _map(5))
    assert started[-1] == another["id"] and s.get("idle") == {}


@pytest.mark.parametrize("value", ["abc", "-1", "nan", "5000"])
def test_a_bad_idle_wait_is_refused_by_name_with_its_range(value):
    """SHIMMY_JOB_WORKER_LINGER_SECONDS out of [0, 3600] s (or not a number) stops the import that reads it."""
    env = {**os.environ, "SHIMMY_JOB_WORKER_LINGER_SECONDS": value, "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, "-c", "import shimmy.service.settings"], env=env, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode != 0
    assert f"SHIMMY_JOB_WORKER_LINGER_SECONDS={value!r} is not a number of seconds in [0, 3600]" in done.stderr
