"""Background jobs for long analyses, shared by every process through the cache directory.

One admission control for the API and the workbench pages. A job record lives in a
diskcache store next to the results: id, analysis, canonical request, status (queued |
running | done | failed | cancelled), progress 0-1, message, error, timestamps. Besides the
records the store holds the queue (ids waiting, in order, at most ``MAX_QUEUED_JOBS``), the
running map (id -> the process that holds one of ``MAX_RUNNING_JOBS`` slots) and an index
request -> active job, so that an identical request already queued or running is that job.

Who waits for a job: a workbench page submits on behalf of one view of it (a ``watcher`` token the
page chose) and :func:`release` says when that view waits no more (the page was left, its question
changed, its Cancel was pressed); an API client cannot say when it leaves, so its submission pins
the job. A job nobody waits for any more (no watcher left, not pinned) is cancelled then: it holds
no slot and nobody's next job queues behind it. Identical requests share one job, so one page
leaving never cancels what another page or an API client still waits for.

A queued job holds no process. :func:`pump` (called on every submit, read and cancel, and by a
worker when it finishes) starts a worker for the first queued jobs while slots are free:
``python -m shimmy.service.worker ID`` in its own session, so that it outlives the request and
its whole process group (process pool, forkserver, resource tracker) can be ended at once. A
worker that finishes takes the next queued job itself, in the same slot; with none queued it stays
idle for ``JOB_WORKER_LINGER_SECONDS`` (holding no slot, listed in the store's idle workers), and
:func:`pump` hands the next job to it rather than starting a process: the next slider step's map
starts with the imports and the compiled kernels warm (and the process pool, if the worker's first job
made one). The server's stop ends the idle workers with the running ones; its start ends any a crash
left and begins a new generation: a worker of an earlier server (its code) takes no further job.

A job is failed only when its process is gone: the process is identified by pid and start
time (psutil), so a late heartbeat under load fails nothing, and a dead one never stays
running. Whoever finds the process gone (the thread in the web worker that started it, or
any later read) ends what is left of its process group with SIGKILL. A heartbeat is kept
only for workers on another host sharing the directory.
"""

from __future__ import annotations

import contextlib
import logging
import os
import reprlib
import signal
import socket
import subprocess
import sys
import threading
import time
import uuid
from typing import Any

import diskcache
import psutil

from ..errors import InvalidParameterError
from ..model.parameters import canonical_digest
from ..analyses.core import executors
from . import admission, analyses, cache, schemas, settings

ACTIVE = ("queued", "running")
HOST = socket.gethostname()
log = logging.getLogger(__name__)


class QueueFull(admission.Busy):
    """A job refused by a limit of the queue (``limit``: jobs_queue, jobs_per_user or jobs_queue_reserved):
    try again after ``retry_after`` seconds."""

    def __init__(self, queued: int, running: int, limit: str = "jobs_queue", message: str | None = None,
                 allowed: str | None = None):
        self.queued, self.running = queued, running
        retry = settings.JOB_RETRY_AFTER_SECONDS
        super().__init__(limit, message or f"the job queue is full ({queued} queued, {running} running); "
                         f"try again in {retry} s", retry,
                         allowed=allowed or f"a job once fewer than {settings.MAX_QUEUED_JOBS} are queued")


def store() -> diskcache.Cache:
    return cache.open_store(settings.cache_dir() / "jobs")


def _now() -> float:
    return time.time()


def _put(s: diskcache.Cache, job: dict[str, Any]) -> dict[str, Any]:
    """Store the record; a finished one expires JOB_RETENTION_HOURS from now (an active one never)."""
    job["updated"] = _now()
    final = job["status"] not in ACTIVE
    s.set(("job", job["id"]), job, expire=settings.JOB_RETENTION_HOURS * 3600 if final else None)
    return job


def update(job_id: str, **changes) -> dict[str, Any] | None:
    """Apply ``changes`` to a job atomically; a finished job is never reopened."""
    s = store()
    with s.transact():
        job = s.get(("job", job_id))
        if job is None:
            return None
        if job["status"] not in ACTIVE and "status" in changes:
            return job  # done/failed/cancelled are final
        job.update(changes)
        if job["status"] not in ACTIVE and s.get(_active(job)) == job_id:
            s.delete(_active(job))
        return _put(s, job)


def submit(analysis: str, body: dict[str, Any], user: str | None = None) -> dict[str, Any]:
    """The job for ``body`` (an API client's: it runs to the end unless deleted): done at once from the
    cache, the same job when an identical one is queued or running, else a new queued job (QueueFull
    when the queue, or ``user``'s share of it, is full)."""
    if analysis not in analyses.JOB_ANALYSES:
        from ..model.parameters import unknown_name_error

        raise unknown_name_error(analysis, list(analyses.JOB_ANALYSES), "analysis")
    request = schemas.validate(analysis, body, extra=("analysis",))
    return submit_canonical(analysis, request, user=user)


def submit_canonical(analysis: str, request: dict[str, Any], watcher: str | None = None,
                     user: str | None = None) -> dict[str, Any]:
    """The job for the canonical ``request``, as :func:`submit`; with ``watcher`` (a page view's token)
    it waits for the job until :func:`release`, else (an API client) the job is pinned. ``user``: who
    asks (None: the server does not know its users; no per-user limit applies)."""
    if watcher is not None:
        _check_watcher(watcher)
    key = cache.key(analysis, request)
    asked = _asked_key(analysis, request)
    job = {"id": uuid.uuid4().hex, "analysis": analysis, "request": request, "status": "queued", "asked_key": asked,
           "progress": 0.0, "message": "queued", "error": None, "created": _now(), "heartbeat": _now(),
           "result_key": key, "watchers": [] if watcher is None else [watcher], "pinned": watcher is None,
           "user": user, "users": [] if user is None else [user], "restarts": 0}
    s = store()
    if cache.get_key(key) is not None:
        job.update(status="done", progress=1.0, message="from the cache")
        _put(s, job)
        _bound(s)
        return job
    _reap(s)
    with s.transact():
        same = s.get(("active", asked))
        existing = s.get(("job", same)) if same else None
        if existing is not None and existing["status"] in ACTIVE:
            return _put(s, _asked_by(_watched_by(existing, watcher), user))
        queue = s.get("queue", [])
        running = s.get("running", {})
        if len(queue) >= settings.MAX_QUEUED_JOBS:
            raise QueueFull(len(queue), len(running))
        if user is not None:
            _check_share(s, user, queue, running)
        _put(s, job)
        s.set("queue", [*queue, job["id"]])
        s.set(("active", asked), job["id"])
    _bound(s)
    pump()
    return store().get(("job", job["id"])) or job


def _asked_by(job: dict[str, Any], user: str | None) -> dict[str, Any]:
    """``job`` with ``user`` among those who asked for it (who may read it)."""
    if user is not None and user not in job.setdefault("users", []):
        job["users"].append(user)
    return job


def _check_share(s: diskcache.Cache, user: str, queue: list[str], running: dict[str, Any]) -> None:
    """QueueFull if ``user`` has MAX_JOBS_PER_USER jobs queued or running, or would take one of the last
    QUEUE_RESERVED places of the queue while a job of theirs is queued or running already."""
    mine = [j for j in [*queue, *running] if user in ((s.get(("job", j)) or {}).get("users") or [])]
    if len(mine) >= settings.MAX_JOBS_PER_USER:
        raise QueueFull(len(queue), len(running), "jobs_per_user",
                        f"you have {len(mine)} jobs queued or running, the most one user may have "
                        f"(SHIMMY_MAX_JOBS_PER_USER = {settings.MAX_JOBS_PER_USER}); try again in "
                        f"{settings.JOB_RETRY_AFTER_SECONDS} s, or delete one",
                        f"a job once fewer than {settings.MAX_JOBS_PER_USER} of yours are queued or running")
    free = settings.MAX_QUEUED_JOBS - len(queue)
    if mine and free <= settings.QUEUE_RESERVED:
        raise QueueFull(len(queue), len(running), "jobs_queue_reserved",
                        f"the last {free} places of the job queue are kept for users who have no job waiting "
                        f"(SHIMMY_QUEUE_RESERVED = {settings.QUEUE_RESERVED}) and you have {len(mine)}; "
                        f"try again in {settings.JOB_RETRY_AFTER_SECONDS} s",
                        "a job once the queue has room or none of yours waits")


def get(job_id: str) -> dict[str, Any] | None:
    """The job, after settling jobs whose process is gone (:func:`_lost`) and starting queued ones on free slots."""
    pump()
    return store().get(("job", job_id))


def peek(job_id: str) -> dict[str, Any] | None:
    """The job's record as stored, without :func:`get`'s settling and starting (a read in a tight loop)."""
    return store().get(("job", job_id))


def _check_watcher(watcher: Any) -> None:
    if not isinstance(watcher, str) or not 0 < len(watcher) <= 64:
        raise InvalidParameterError("watcher", watcher, "a token of 1 to 64 characters",
                                    message=f"watcher={reprlib.repr(watcher)} is not a token of 1 to 64 characters")


def _watched_by(job: dict[str, Any], watcher: str | None) -> dict[str, Any]:
    """``job`` with ``watcher`` waiting for it too (None: an API client, which pins it). Past
    MAX_JOB_WATCHERS the job is pinned instead: it then runs to the end, as an API client's does."""
    if watcher is None or len(job.get("watchers", [])) >= settings.MAX_JOB_WATCHERS:
        job["pinned"] = True
    elif watcher not in job.setdefault("watchers", []):
        job["watchers"].append(watcher)
    return job


def cancel(job_id: str, remove: bool = True) -> dict[str, Any] | None:
    """Cancel a job whoever waits for it (a queued one leaves the queue; a running one's process
    group is ended) and, with ``remove``, delete its record: (the job as it was cancelled) or None
    if unknown."""
    s = store()
    with s.transact():
        job = s.get(("job", job_id))
        if job is None:
            return None
        if job["status"] in ACTIVE:
            _end(s, job, "cancelled by request")
        holder = s.get("running", {}).get(job_id)
        if remove:
            s.delete(("job", job_id))
    if holder is not None:
        _signal_group(holder, signal.SIGTERM)
    pump()
    return job


def release(job_id: str, watcher: str) -> dict[str, Any] | None:
    """``watcher`` waits for the job no more. A queued or running job that nobody else waits for
    (no other watcher, not pinned by an API client) is cancelled, as by :func:`cancel` but keeping its
    record; one that others wait for goes on. (The job as it is then) or None if it is unknown."""
    _check_watcher(watcher)
    s = store()
    holder = None
    with s.transact():
        job = s.get(("job", job_id))
        if job is None or watcher not in job.get("watchers", []):
            return job
        job["watchers"] = [w for w in job["watchers"] if w != watcher]
        if job["status"] in ACTIVE and not job["watchers"] and not job.get("pinned", True):
            _end(s, job, "cancelled: nobody waits for it any more")
            holder = s.get("running", {}).get(job_id)
        else:
            _put(s, job)
    if holder is not None:
        _signal_group(holder, signal.SIGTERM)
        pump()
    return job


def _asked_key(analysis: str, request: dict[str, Any]) -> str:
    """What an identical request is: the whole canonical request (every parameter), not the result's
    key (which may leave out parameters outside the configuration's model: two such requests share a
    result, but each job reports its own request)."""
    return canonical_digest({"analysis": analysis, "request": request})


def _active(job: dict[str, Any]) -> tuple[str, str]:
    """The active index's entry of a job (a record from before the index took whole requests: its result key)."""
    return ("active", job.get("asked_key", job["result_key"]))


def _end(s: diskcache.Cache, job: dict[str, Any], message: str) -> None:
    """Mark an active job cancelled and take it off the queue and the active index (in a transaction)."""
    job.update(status="cancelled", message=message)
    s.set("queue", [j for j in s.get("queue", []) if j != job["id"]])
    if s.get(_active(job)) == job["id"]:
        s.delete(_active(job))
    _put(s, job)


def result(job: dict[str, Any]) -> dict[str, Any] | None:
    return cache.as_asked(cache.get_key(job["result_key"]), job["request"]) if job["status"] == "done" else None


def public(job: dict[str, Any], with_result: bool = True) -> dict[str, Any]:
    """The job as the API shows it (with its owner: the user who asked for it first, or null)."""
    out = {k: job[k] for k in ("id", "analysis", "status", "progress", "message", "error", "created", "updated")}
    out["user"] = job.get("user")
    out["request"] = job["request"]
    if with_result and job["status"] == "done":
        out["result"] = result(job)
        if out["result"] is None:
            out["message"] = ("done, but its result has left the result cache (SHIMMY_CACHE_SIZE_MB); submit the "
                              "request again to compute it again")
    return out


def visible_to(job: dict[str, Any], user: str | None) -> bool:
    """Whether ``user`` (None: the server does not know its users) asked for ``job`` and so may read it."""
    return user is None or user in (job.get("users") or [])


def detach(job_id: str, user: str) -> dict[str, Any] | None:
    """``user`` waits for the job no more (DELETE by one of several users who asked for it): the job goes on
    for the others. (The job as it is then) or None if unknown."""
    s = store()
    with s.transact():
        job = s.get(("job", job_id))
        if job is None:
            return None
        job["users"] = [u for u in job.get("users") or [] if u != user]
        return _put(s, job)


def counts() -> dict[str, int]:
    s = store()
    return {"queued": len(s.get("queue", [])), "running": len(s.get("running", {}))}


def listing(status: str | None = None, user: str | None = None, limit: int = 100) -> dict[str, Any]:
    """Every job record (newest first, at most ``limit`` shown), with who asked for each, the total, the
    queue in order and the jobs queued and running per user (the admin's view, GET /api/v1/jobs)."""
    s = store()
    _reap(s)
    records = []
    for key in list(s):
        if isinstance(key, tuple) and len(key) == 2 and key[0] == "job":
            job = s.get(key)
            if job is not None:
                records.append(job)
    by_user: dict[str, dict[str, int]] = {}
    for job in records:
        if job["status"] in ACTIVE:
            owner = job.get("user") or "anonymous"
            counts_of = by_user.setdefault(owner, {"queued": 0, "running": 0})
            counts_of[job["status"]] += 1
    chosen = [j for j in records if (status is None or j["status"] == status)
              and (user is None or user in (j.get("users") or []) or (user == "anonymous" and not j.get("users")))]
    chosen.sort(key=lambda j: j["created"], reverse=True)
    shown = []
    for job in chosen[:limit]:
        item = public(job, with_result=False)
        item["users"] = job.get("users") or []
        item["restarts"] = job.get("restarts", 0)
        shown.append(item)
    return {"total": len(chosen), "records": len(records), "shown": len(shown), "jobs": shown,
            "queue": list(s.get("queue", [])), "running": sorted(s.get("running", {})), "by_user": by_user,
            "draining": s.get("draining") is not None,
            "limits": {"max_running": settings.MAX_RUNNING_JOBS, "max_queued": settings.MAX_QUEUED_JOBS,
                       "max_jobs_per_user": settings.MAX_JOBS_PER_USER,
                       "max_running_per_user": settings.MAX_RUNNING_JOBS_PER_USER,
                       "retention_hours": settings.JOB_RETENTION_HOURS,
                       "max_records": settings.MAX_JOB_RECORDS}}


# -- bounded storage ---------------------------------------------------------------------------

#: Entries of the store besides the records: queue, running, idle, generation, draining, the active index,
#: health probes.
_BOOKKEEPING = 16


def _bound(s: diskcache.Cache) -> None:
    """Keep at most MAX_JOB_RECORDS records: expired ones are removed, then the oldest finished ones.
    Cheap when under the bound (the store's count is one read)."""
    limit = settings.MAX_JOB_RECORDS + _BOOKKEEPING + settings.MAX_QUEUED_JOBS + settings.MAX_RUNNING_JOBS
    if len(s) <= limit:
        return
    try:
        s.expire()
        prune(s)
    except cache.DAMAGE as exc:  # pruning is housekeeping: a busy or damaged store must not fail a submission
        log.warning("job records not pruned: %s", exc)


def prune(s: diskcache.Cache | None = None) -> int:
    """Remove the oldest finished records beyond MAX_JOB_RECORDS (by creation: the store's insertion
    order); the number removed."""
    s = s or store()
    s.expire()
    keys = [k for k in s if isinstance(k, tuple) and len(k) == 2 and k[0] == "job"]
    excess = len(keys) - settings.MAX_JOB_RECORDS
    removed = 0
    for key in keys:
        if removed >= excess:
            break
        with s.transact():
            job = s.get(key)
            if job is not None and job["status"] not in ACTIVE:
                s.delete(key)
                removed += 1
    return removed


# -- restarts and upgrades -----------------------------------------------------------------------


def drain() -> dict[str, int]:
    """Start no more jobs (submissions still queue) until :func:`resume` or the server's next start."""
    s = store()
    s.set("draining", {"since": _now()})
    return counts()


def resume() -> dict[str, int]:
    s = store()
    s.delete("draining")
    pump()
    return counts()


def draining() -> bool:
    return store().get("draining") is not None


def _requeue(s: diskcache.Cache, job_ids: list[str], message: str, restart: bool) -> list[str]:
    """Put active jobs back at the head of the queue (in this order), their slots freed (in a transaction)."""
    back = []
    running = dict(s.get("running", {}))
    for job_id in job_ids:
        running.pop(job_id, None)
        job = s.get(("job", job_id))
        if job is None or job["status"] not in ACTIVE:
            continue
        job.update(status="queued", progress=0.0, message=message, sketch=None)
        if restart:
            job["restarts"] = job.get("restarts", 0) + 1
        _put(s, job)
        back.append(job_id)
    queue = [j for j in s.get("queue", []) if j not in back]
    s.set("queue", back + queue)
    s.set("running", running)
    return back


def server_started() -> dict[str, list[str]]:
    """When the server starts (gunicorn's ``on_starting``, before any web worker): jobs stop draining; a
    job whose process is gone is queued again, at most JOB_RESTARTS times, then failed saying why. Queued
    jobs are started by the web workers (:func:`pump`). (What was queued again and what failed, by id.)"""
    s = store()
    s.delete("draining")
    with s.transact():  # a new generation: workers of an earlier server (its code) take no further job
        s.set("generation", uuid.uuid4().hex)
        idle = dict(s.get("idle", {}))
        s.set("idle", {key: h for key, h in idle.items() if h.get("host") != HOST})
    for holder in idle.values():  # idle workers left by a server that did not stop cleanly
        if holder.get("host") == HOST and _is_process(holder):
            _signal_group(holder, signal.SIGKILL)
    gone = [(job_id, holder) for job_id, holder in list(s.get("running", {}).items())
            if not _alive(s, job_id, holder)]
    for _, holder in gone:
        _signal_group(holder, signal.SIGKILL)  # what is left of its group, if anything
    requeued, failed = [], []
    with s.transact():
        for job_id, holder in gone:
            job = s.get(("job", job_id))
            if job is None or job["status"] not in ACTIVE:
                _release(s, job_id, holder)
            elif job.get("restarts", 0) < settings.JOB_RESTARTS:
                requeued += _requeue(s, [job_id], "queued again: its process ended with the server; it starts "
                                     "again from the beginning", restart=True)
            else:
                _release(s, job_id, holder)
                job.update(status="failed", error=f"the process running this job ended without a result when the "
                           f"server stopped, {job.get('restarts', 0) + 1} times; submit it again")
                _put(s, job)
                if s.get(_active(job)) == job_id:
                    s.delete(_active(job))
                failed.append(job_id)
    return {"requeued": requeued, "failed": failed}


def server_stopping(grace: float = 5.0) -> list[str]:
    """When the server stops (gunicorn's ``on_exit``, its web workers gone): end the processes of the jobs
    running on this host (SIGTERM, then SIGKILL after ``grace`` seconds) and queue those jobs again at
    the head of the queue, so that they start again when the server does. The ids queued again."""
    s = store()
    with s.transact():  # idle workers end with the server (the next one starts its own, with its code)
        holders = {job_id: h for job_id, h in s.get("running", {}).items() if h.get("host") == HOST}
        idle = dict(s.get("idle", {}))
        holders.update({("idle", key): h for key, h in idle.items() if h.get("host") == HOST and _is_process(h)})
        s.set("idle", {key: h for key, h in idle.items() if h.get("host") != HOST})
    for holder in holders.values():
        _signal_group(holder, signal.SIGTERM)
    deadline = time.time() + grace
    while time.time() < deadline and any(_group_alive(h) for h in holders.values()):
        time.sleep(0.1)
    for holder in holders.values():
        _signal_group(holder, signal.SIGKILL)
    pids = {h.get("pid") for h in holders.values()}
    with s.transact():  # a worker may have taken the next job in its slot meanwhile: every job of those pids
        held = [job_id for job_id, h in s.get("running", {}).items() if h.get("host") == HOST and h.get("pid") in pids]
        return _requeue(s, held, "queued again: the server stopped while it ran; it starts again from the "
                        "beginning when the server starts", restart=False)


def _group_alive(holder: dict[str, Any]) -> bool:
    pid = holder.get("pid")
    if not pid:
        return False
    try:
        os.killpg(pid, 0)
        return True
    except (ProcessLookupError, PermissionError):
        return False


# -- processes -------------------------------------------------------------------------------


def pump() -> None:
    """Settle jobs whose process is gone (:func:`_lost`), then start workers for queued jobs on free slots."""
    s = store()
    _reap(s)
    starting = []
    with s.transact():
        if s.get("draining") is not None:
            return
        running = dict(s.get("running", {}))
        queue = list(s.get("queue", []))
        idle = dict(s.get("idle", {}))
        generation = s.get("generation")
        mine = {key: h for key, h in idle.items() if h.get("host") == HOST}
        waiting = [key for key, h in mine.items() if h.get("generation") == generation and _is_process(h)]
        while len(running) < settings.MAX_RUNNING_JOBS:
            job_id, owner = _choose(s, queue, running)
            if job_id is None:
                break
            if waiting:  # an idle worker takes it (it reads the running map): warm, no process to start
                _hand(s, running, job_id, idle.pop(waiting.pop(0)), owner)
                continue
            _hand(s, running, job_id, {"pid": None, "started": None, "host": HOST}, owner)
            starting.append(job_id)
        s.set("queue", queue)
        s.set("running", running)
        # this host's entries: those still waiting (the dead and the earlier generation's dropped); others' kept
        s.set("idle", {**{key: h for key, h in idle.items() if key not in mine}, **{key: idle[key] for key in waiting}})
    for job_id in starting:
        _start(s, job_id)


def _hand(s: diskcache.Cache, running: dict[str, Any], job_id: str, holder: dict[str, Any],
          owner: str | None) -> None:
    """Inside the transaction that hands ``job_id`` to a slot: ``holder`` takes it in ``running`` (the caller
    stores that map), and the job's heartbeat is now (a holder on another host is judged by it: a job queued
    for a while would read as stale until its worker's first update)."""
    running[job_id] = {**holder, "claimed": _now(), "user": owner}
    job = s.get(("job", job_id))
    if job is not None:
        job["heartbeat"] = _now()
        _put(s, job)


def _choose(s: diskcache.Cache, queue: list[str], running: dict[str, Any]) -> tuple[str | None, str | None]:
    """Take from ``queue`` (in place) the job to start next: of the queued jobs whose owner runs fewer than
    MAX_RUNNING_JOBS_PER_USER, the one whose owner runs the fewest, the oldest first (anonymous jobs: no
    per-user limit). Entries that are no longer queued leave the queue. (job id, owner) or (None, None)."""
    load: dict[str, int] = {}
    for holder in running.values():
        if holder.get("user") is not None:
            load[holder["user"]] = load.get(holder["user"], 0) + 1
    best, best_rank = None, None
    for position, job_id in enumerate(list(queue)):
        job = s.get(("job", job_id))
        if job is None or job["status"] != "queued":
            queue.remove(job_id)
            continue
        owner = job.get("user")
        mine = load.get(owner, 0) if owner is not None else 0
        if owner is not None and mine >= settings.MAX_RUNNING_JOBS_PER_USER:
            continue
        rank = (mine, position)
        if best_rank is None or rank < best_rank:
            best, best_rank = (job_id, owner), rank
    if best is None:
        return None, None
    queue.remove(best[0])
    return best


def _start(s: diskcache.Cache, job_id: str) -> None:
    try:
        proc = subprocess.Popen([sys.executable, "-m", "shimmy.service.worker", job_id], start_new_session=True,
                                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                env={**os.environ, "SHIMMY_CACHE_DIR": str(settings.cache_dir())})
    except OSError as exc:
        _release(s, job_id)
        update(job_id, status="failed", error=f"could not start a worker: {exc}")
        return
    holder = {"pid": proc.pid, "started": _create_time(proc.pid), "host": HOST, "claimed": _now()}
    with s.transact():
        running = dict(s.get("running", {}))
        if job_id in running and running[job_id]["pid"] is None:
            running[job_id] = {**holder, "user": running[job_id].get("user")}
            s.set("running", running)
    threading.Thread(target=_wait, args=(proc, job_id), daemon=True, name=f"job-{job_id[:8]}").start()


def _wait(proc: subprocess.Popen, job_id: str) -> None:
    """In the process that started a worker: reap it, end what is left of its group, fail the job
    it held (if it ended without finishing it) and start the next queued ones."""
    code = proc.wait()
    _signal_group({"pid": proc.pid, "host": HOST}, signal.SIGKILL)
    try:
        s = store()
        for held, holder in list(s.get("running", {}).items()):
            if holder.get("pid") == proc.pid and holder.get("host") == HOST:
                _lost(s, held, holder, code)
        pump()
    except Exception:  # noqa: BLE001 - a broken store is reported by health; this thread must not die loudly
        log.exception("after the worker of job %s", job_id)


def _death(code: int | None = None, requeued: int | None = None) -> str:
    """Why a job failed when its process ended: while running it, or (``requeued``: how often it was
    queued again already) before starting it."""
    how = "" if code is None else (f" (killed by signal {-code})" if code < 0 else f" (exit status {code})")
    if requeued is not None:
        return (f"the process this job was handed to ended before starting it{how}, and it had been queued "
                f"again {requeued} time(s) already; submit it again")
    return f"the process running this job ended without a result{how}; submit it again"


def _lost(s: diskcache.Cache, job_id: str, holder: dict[str, Any], code: int | None = None) -> None:
    """The slot holder of ``job_id`` ended. A job it ran is failed (the job may be what ended it); one it
    had not started yet (a worker that died starting, an idle one killed after the job was handed to it)
    is queued again at the head of the queue, at most ``JOB_RESTARTS`` times, then failed saying so."""
    with s.transact():  # (one transaction: a second caller that saw the same holder finds it gone and stops)
        if s.get("running", {}).get(job_id) != holder:
            return  # settled already (by another process's check, or the starter's), or handed on since
        job = s.get(("job", job_id))
        unstarted = job is not None and job["status"] == "queued"
        if unstarted and job.get("restarts", 0) < settings.JOB_RESTARTS:
            _requeue(s, [job_id], "queued again: the process it was handed to ended before starting it",
                     restart=True)
            return
        _release(s, job_id, holder)
        update(job_id, status="failed", error=_death(code, job.get("restarts", 0) if unstarted else None))


def _reap(s: diskcache.Cache) -> None:
    """Settle every job whose slot holder is gone (:func:`_lost`), and end what is left of its process group."""
    gone = [(job_id, holder) for job_id, holder in list(s.get("running", {}).items())
            if not _alive(s, job_id, holder)]
    for job_id, holder in gone:
        _signal_group(holder, signal.SIGKILL)
        _lost(s, job_id, holder)


def _alive(s: diskcache.Cache, job_id: str, holder: dict[str, Any]) -> bool:
    if holder.get("host") != HOST:  # another machine's worker: only its heartbeat can tell
        job = s.get(("job", job_id))
        return job is not None and _now() - job["heartbeat"] <= settings.JOB_STALE_SECONDS
    if holder.get("pid") is None:  # being started: Popen returns within milliseconds
        return _now() - holder.get("claimed", 0) < settings.JOB_START_SECONDS
    return _is_process(holder)


def _is_process(holder: dict[str, Any]) -> bool:
    """The process ``holder`` names (pid and start time, on this host) is running."""
    try:
        p = psutil.Process(holder["pid"])
        return p.status() != psutil.STATUS_ZOMBIE and abs(p.create_time() - holder["started"]) < 0.05
    except (psutil.NoSuchProcess, psutil.AccessDenied, TypeError, KeyError):
        return False


def _create_time(pid: int) -> float | None:
    try:
        return psutil.Process(pid).create_time()
    except psutil.Error:
        return None


def _signal_group(holder: dict[str, Any], sig: int) -> None:
    pid = holder.get("pid")
    if pid and holder.get("host") == HOST:
        try:
            os.killpg(pid, sig)  # the worker leads its own session: the group id is its pid
        except (ProcessLookupError, PermissionError):
            pass


def _release(s: diskcache.Cache, job_id: str, holder: dict[str, Any] | None = None) -> None:
    with s.transact():
        running = dict(s.get("running", {}))
        if job_id in running and (holder is None or running[job_id] == holder):
            del running[job_id]
            s.set("running", running)


# -- the worker side -------------------------------------------------------------------------


class Cancelled(Exception):
    pass


#: Analyses that run their units through a process pool: a worker slot that starts with one forks its
#: pool once (:func:`shimmy.analyses.core.executors.shared_pool`) for all its jobs.
POOLED = frozenset({"map", "margin_map", "margins", "study", "robustness", "optimise"})


def run(job_id: str) -> None:
    """Run job ``job_id`` in this process (``python -m shimmy.service.worker``), then the next
    queued jobs in the same slot until the queue is empty, then those handed to it while it waits
    idle (:func:`_linger`)."""
    me = {"pid": os.getpid(), "started": _create_time(os.getpid()), "host": HOST,
          "generation": store().get("generation")}
    stop = threading.Event()
    current = [job_id]

    def beat():
        while not stop.wait(1.0):
            if current[0] is not None:
                update(current[0], heartbeat=_now())

    # running from now (the slot is this process's); then the slot's process pool, forked before the
    # heartbeat thread exists: warm for every job of the slot
    first = update(job_id, status="running", message="running", heartbeat=_now()) or {}
    with executors.shared_pool() if first.get("analysis") in POOLED else contextlib.nullcontext():
        threading.Thread(target=beat, daemon=True).start()
        try:
            while job_id is not None:
                current[0] = job_id
                if not _run_one(job_id):  # cancelled: the canceller's SIGTERM for this group is on its way
                    return
                job_id = _next(job_id, me)
                if job_id is None:
                    current[0] = None  # no job's heartbeat while idle
                    job_id = _linger(me)
        finally:
            stop.set()


def _run_one(job_id: str) -> bool:
    """Run one job; False if it was cancelled."""
    job = update(job_id, status="running", message="running", heartbeat=_now(), worker=os.getpid())
    if job is None or job["status"] != "running":
        return job is not None and job["status"] != "cancelled"

    try:
        analyses.run_canonical(job["analysis"], job["request"], _Progress(job_id))
    except Cancelled:
        return False
    except Exception as exc:  # noqa: BLE001 - every failure is reported on the job
        executors.drop_shared_pool()  # units of the failed job may still run there
        update(job_id, status="failed", error=f"{type(exc).__name__}: {exc}", sketch=None)
        return True
    update(job_id, status="done", progress=1.0, message="done", sketch=None)
    return True


class _Progress:
    """A running job's progress (``progress(fraction, message)``) and :meth:`sketch`: what of its
    answer is known so far, kept on the job's record (``job["sketch"]``, not in the API's view) for
    the pages to draw before the answer is done, dropped when it ends. Either raises
    :class:`Cancelled` once the job is cancelled."""

    def __init__(self, job_id: str):
        self.job_id = job_id

    def __call__(self, fraction: float, message: str) -> None:
        self._check(update(self.job_id, progress=float(min(max(fraction, 0.0), 1.0)), message=message))

    def sketch(self, partial: dict[str, Any]) -> None:
        self._check(update(self.job_id, sketch=partial))

    @staticmethod
    def _check(now: dict[str, Any] | None) -> None:
        if now is None or now["status"] == "cancelled":
            raise Cancelled()


#: How often an idle worker reads the store for a job (seconds).
IDLE_POLL_SECONDS = 0.05


def _linger(me: dict[str, Any]) -> str | None:
    """After its last job, listed idle by :func:`_next`: wait up to ``JOB_WORKER_LINGER_SECONDS`` until
    :func:`pump` hands this process a job (an entry of the running map with its pid and start time) or a
    job is queued that a free slot may take; that job's id, or None (the process then ends) when the time
    is up, the jobs drain, another server generation starts or this process is no longer listed (the
    server's stop). Polls by reads; a transaction only to take a job or to leave."""
    if settings.JOB_WORKER_LINGER_SECONDS <= 0:  # not listed by _next: nothing can be handed to it
        return None
    s = store()
    key = _idle_key(me)
    deadline = time.monotonic() + settings.JOB_WORKER_LINGER_SECONDS
    while True:
        running = s.get("running", {})
        handed = any(_same_process(h, me) for h in running.values())
        leave = (time.monotonic() >= deadline or s.get("draining") is not None or key not in s.get("idle", {})
                 or s.get("generation") != me.get("generation"))
        free = False
        if not (handed or leave) and s.get("queue") and len(running) < settings.MAX_RUNNING_JOBS:
            free = _choose(s, list(s.get("queue", [])), dict(running))[0] is not None  # reads only
        if handed or leave or free:
            with s.transact():
                running = dict(s.get("running", {}))
                mine = next((job_id for job_id, h in running.items() if _same_process(h, me)), None)
                listed = key in s.get("idle", {})
                if mine is None and listed and s.get("draining") is None and \
                        s.get("generation") == me.get("generation") and len(running) < settings.MAX_RUNNING_JOBS:
                    queue = list(s.get("queue", []))
                    mine, owner = _choose(s, queue, running)
                    if mine is not None:
                        _hand(s, running, mine, me, owner)
                        s.set("queue", queue)
                        s.set("running", running)
                if mine is not None or leave or not listed:
                    idle = dict(s.get("idle", {}))
                    idle.pop(key, None)
                    s.set("idle", idle)
                    return mine
        time.sleep(IDLE_POLL_SECONDS)


def _same_process(holder: dict[str, Any], me: dict[str, Any]) -> bool:
    return holder.get("pid") == me["pid"] and holder.get("host") == me["host"] and holder.get("started") == me["started"]


def _next(finished: str, me: dict[str, Any]) -> str | None:
    """Hand this process's slot from ``finished`` to the first queued job, or give it up (and, in the same
    transaction, list this process among the idle workers, see :func:`_linger`). A worker of an earlier
    server generation takes no further job."""
    s = store()
    with s.transact():
        running = dict(s.get("running", {}))
        running.pop(finished, None)
        queue = list(s.get("queue", []))
        nxt = None
        current = s.get("generation") == me.get("generation")
        if current and s.get("draining") is None and len(running) < settings.MAX_RUNNING_JOBS:
            nxt, owner = _choose(s, queue, running)
            if nxt is not None:
                _hand(s, running, nxt, me, owner)
        s.set("queue", queue)
        s.set("running", running)
        if nxt is None and current and s.get("draining") is None and settings.JOB_WORKER_LINGER_SECONDS > 0:
            s.set("idle", {**s.get("idle", {}), _idle_key(me): me})
    return nxt


def _idle_key(me: dict[str, Any]) -> str:
    return f"{me['host']}:{me['pid']}"
