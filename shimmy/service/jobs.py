"""Background jobs for long analyses, shared by every process through the cache directory.

A job record lives in a diskcache store next to the results: id, analysis, canonical
request, status (queued | running | done | failed | cancelled), progress 0-1, message,
error, timestamps, the worker's pid and host, and a heartbeat. :func:`submit` answers at
once from the result cache when it can; otherwise it starts a worker process
(``python -m shimmy.service.worker ID``, its own session so it outlives the request and
can be killed as a group) which waits for one of ``MAX_RUNNING_JOBS`` slots, runs the
analysis with a progress callback, and stores the result in the shared cache.

Nothing stays running forever: the worker beats every second; a queued or running job
whose heartbeat is older than ``JOB_STALE_SECONDS`` (its worker died, the server was
restarted) is marked failed with that reason when it is next read. Cancelling sets the
status, which the worker's progress callback notices (it then stops), and terminates the
worker's process group if it runs on this host.
"""

from __future__ import annotations

import functools
import os
import signal
import socket
import subprocess
import sys
import time
import uuid
from typing import Any

import diskcache

from . import cache, schemas, settings

ACTIVE = ("queued", "running")


@functools.lru_cache(maxsize=None)
def _open(path: str) -> diskcache.Cache:
    return diskcache.Cache(path)


def store() -> diskcache.Cache:
    return _open(str(settings.cache_dir() / "jobs"))


def _now() -> float:
    return time.time()


def _put(job: dict[str, Any]) -> dict[str, Any]:
    job["updated"] = _now()
    store().set(("job", job["id"]), job)
    return job


def update(job_id: str, **changes) -> dict[str, Any] | None:
    """Apply ``changes`` to a job atomically; a finished job is never reopened."""
    with store().transact():
        job = store().get(("job", job_id))
        if job is None:
            return None
        if job["status"] not in ACTIVE and "status" in changes:
            return job  # done/failed/cancelled are final
        job.update(changes)
        return _put(job)


def submit(analysis: str, body: dict[str, Any]) -> dict[str, Any]:
    """Validate, create the job and start its worker (or finish it from the cache at once)."""
    if analysis not in schemas.JOB_ANALYSES:
        from ..model.parameters import unknown_name_error

        raise unknown_name_error(analysis, list(schemas.JOB_ANALYSES), "analysis")
    request = schemas.validate(analysis, body, extra=("analysis",))
    job = {"id": uuid.uuid4().hex, "analysis": analysis, "request": request, "status": "queued",
           "progress": 0.0, "message": "queued", "error": None, "created": _now(), "heartbeat": _now(),
           "pid": None, "host": socket.gethostname(), "result_key": cache.key(analysis, request)}
    if cache.results().get(job["result_key"]) is not None:
        job.update(status="done", progress=1.0, message="from the cache")
        return _put(job)
    _put(job)
    proc = subprocess.Popen([sys.executable, "-m", "shimmy.service.worker", job["id"]], start_new_session=True,
                            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            env={**os.environ, "SHIMMY_CACHE_DIR": str(settings.cache_dir())})
    return update(job["id"], pid=proc.pid) or job


def get(job_id: str) -> dict[str, Any] | None:
    """The job, with a stale queued/running one marked failed first."""
    job = store().get(("job", job_id))
    if job is None:
        return None
    if job["status"] in ACTIVE and _now() - job["heartbeat"] > settings.JOB_STALE_SECONDS:
        job = update(job_id, status="failed", error=(
            f"the worker running this job stopped (no heartbeat for more than {settings.JOB_STALE_SECONDS:g} s, "
            "e.g. a server restart); submit it again")) or job
    return job


def cancel(job_id: str) -> dict[str, Any] | None:
    job = get(job_id)
    if job is None or job["status"] not in ACTIVE:
        return job
    job = update(job_id, status="cancelled", message="cancelled by request", progress=job["progress"])
    pid = job.get("pid")
    if pid and job.get("host") == socket.gethostname():
        try:
            os.killpg(pid, signal.SIGTERM)
        except (ProcessLookupError, PermissionError):
            pass
    return job


def result(job: dict[str, Any]) -> dict[str, Any] | None:
    return cache.results().get(job["result_key"]) if job["status"] == "done" else None


def public(job: dict[str, Any], with_result: bool = True) -> dict[str, Any]:
    """The job as the API shows it."""
    out = {k: job[k] for k in ("id", "analysis", "status", "progress", "message", "error", "created", "updated")}
    out["request"] = job["request"]
    if with_result and job["status"] == "done":
        out["result"] = result(job)
    return out


# -- the worker side -------------------------------------------------------------------------


class Cancelled(Exception):
    pass


def run(job_id: str) -> None:
    """Run job ``job_id`` in this process (called by ``python -m shimmy.service.worker``)."""
    import threading

    from . import analyses

    job = store().get(("job", job_id))
    if job is None:
        return
    stop = threading.Event()

    def beat():
        while not stop.wait(1.0):
            update(job_id, heartbeat=_now())

    threading.Thread(target=beat, daemon=True).start()
    try:
        _wait_for_slot(job_id)
        if store().get(("job", job_id))["status"] != "queued":
            return
        update(job_id, status="running", message="running", pid=os.getpid())

        def progress(fraction: float, message: str) -> None:
            current = update(job_id, progress=float(min(max(fraction, 0.0), 1.0)), message=message)
            if current is None or current["status"] == "cancelled":
                raise Cancelled()

        try:
            analyses.run_canonical(job["analysis"], job["request"], progress)
        except Cancelled:
            return
        except Exception as exc:  # noqa: BLE001 - every failure is reported on the job
            update(job_id, status="failed", error=f"{type(exc).__name__}: {exc}")
            return
        update(job_id, status="done", progress=1.0, message="done")
    finally:
        _release_slot(job_id)
        stop.set()


def _wait_for_slot(job_id: str) -> None:
    s = store()
    while True:
        with s.transact():
            running = {k for k in s.get("slots", set()) if _alive(k)}
            if len(running) < settings.MAX_RUNNING_JOBS:
                s.set("slots", running | {job_id})
                return
            s.set("slots", running)
        job = s.get(("job", job_id))
        if job is None or job["status"] != "queued":
            return
        update(job_id, message=f"queued: {len(running)} analyses running")
        time.sleep(0.5)


def _release_slot(job_id: str) -> None:
    s = store()
    with s.transact():
        s.set("slots", set(s.get("slots", set())) - {job_id})


def _alive(job_id: str) -> bool:
    job = store().get(("job", job_id))
    return job is not None and job["status"] in ACTIVE and _now() - job["heartbeat"] <= settings.JOB_STALE_SECONDS
