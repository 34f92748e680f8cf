"""Who waits for a job: a page view (a watcher) or an API client (the job is pinned). A job nobody
waits for any more is cancelled, and the next job takes its slot; a shared job goes on while anyone
still waits for it."""

from __future__ import annotations

import time

import pytest

from shimmy.errors import InvalidParameterError
from shimmy.service import jobs, schemas, settings

from conftest import process_group

MAP = {"config": "original", "fz_min": 100000, "fz_max": 400000, "resolution": 3}


@pytest.fixture
def held(tmp_path, monkeypatch):
    """A job store of its own in which no job starts (no slot): submitted jobs stay queued."""
    monkeypatch.setenv("SHIMMY_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(settings, "MAX_RUNNING_JOBS", 0)


def _map(**changes):
    return schemas.validate("map", {**MAP, **changes})


def _queue() -> list[str]:
    return jobs.store().get("queue", [])


def test_a_job_is_cancelled_when_the_last_page_waiting_for_it_releases_it(held):
    a = jobs.submit_canonical("map", _map(), watcher="view-a")
    b = jobs.submit_canonical("map", _map(), watcher="view-b")
    assert b["id"] == a["id"] and b["watchers"] == ["view-a", "view-b"] and not b["pinned"]
    assert _queue() == [a["id"]]
    after_a = jobs.release(a["id"], "view-a")
    assert after_a["status"] == "queued" and after_a["watchers"] == ["view-b"]  # view b still waits
    assert _queue() == [a["id"]]
    after_b = jobs.release(a["id"], "view-b")
    assert after_b["status"] == "cancelled" and after_b["message"] == "cancelled: nobody waits for it any more"
    assert _queue() == []
    assert jobs.get(a["id"])["status"] == "cancelled"  # the record stays for the page that reads it
    again = jobs.submit_canonical("map", _map(), watcher="view-c")  # asked again: a new job, not the cancelled one
    assert again["id"] != a["id"] and again["status"] == "queued" and _queue() == [again["id"]]


@pytest.mark.parametrize("api_first", [True, False])
def test_a_job_an_api_client_asked_for_goes_on_when_the_page_leaves(held, api_first):
    if api_first:
        job = jobs.submit("map", MAP)
        assert job["pinned"] and job["watchers"] == []
        jobs.submit_canonical("map", _map(), watcher="view-a")
    else:
        job = jobs.submit_canonical("map", _map(), watcher="view-a")
        assert jobs.submit("map", MAP)["pinned"]  # an API client joining pins it
    after = jobs.release(job["id"], "view-a")
    assert after["status"] == "queued" and after["pinned"] and after["watchers"] == []
    assert _queue() == [job["id"]]


def test_release_by_a_stranger_or_of_an_unknown_job_changes_nothing(held):
    job = jobs.submit_canonical("map", _map(), watcher="view-a")
    assert jobs.release(job["id"], "view-z")["watchers"] == ["view-a"]
    assert jobs.get(job["id"])["status"] == "queued"
    assert jobs.release("0" * 32, "view-a") is None
    for bad in ("", "x" * 65, 3, None):
        with pytest.raises(InvalidParameterError, match=r"watcher=.* is not a token of 1 to 64 characters"):
            jobs.release(job["id"], bad)
    with pytest.raises(InvalidParameterError, match="watcher"):
        jobs.submit_canonical("map", _map(), watcher="x" * 65)


def test_past_the_watcher_limit_a_job_is_pinned_and_runs_to_the_end(held, monkeypatch):
    monkeypatch.setattr(settings, "MAX_JOB_WATCHERS", 3)
    for k in range(5):
        job = jobs.submit_canonical("map", _map(), watcher=f"view-{k}")
    assert job["watchers"] == ["view-0", "view-1", "view-2"] and job["pinned"]
    for k in range(3):
        job = jobs.release(job["id"], f"view-{k}")
    assert job["status"] == "queued"


def test_a_released_running_job_ends_its_process_and_gives_its_slot_to_the_next(tmp_path, monkeypatch):
    """One slot: the page that started a long job is left; the job queued behind it (another
    user's click) starts at once instead of waiting for work nobody waits for."""
    monkeypatch.setenv("SHIMMY_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("SHIMMY_MAX_RUNNING_JOBS", "1")  # the workers read it too
    monkeypatch.setattr(settings, "MAX_RUNNING_JOBS", 1)
    long = jobs.submit_canonical("bifurcation", schemas.validate("bifurcation", {
        "config": "original", "Fz": 320000, "v_min": 1, "v_max": 200, "ntst": 200}), watcher="left-page")
    click = jobs.submit_canonical("simulate", schemas.validate("simulate", {
        "config": "nes", "V": 31.5, "Fz": 150000, "t_end": 2}), watcher="clicking-page")
    try:
        holder = _until(lambda: (h := jobs.store().get("running", {}).get(long["id"])) and h["pid"] and h,
                        what="the long job's worker")
        assert jobs.get(click["id"])["status"] == "queued"
        assert jobs.release(long["id"], "left-page")["status"] == "cancelled"
        _until(lambda: process_group(holder["pid"]) is None and jobs.get(click["id"])["status"] != "queued",
               what="the long job's process to end and the click's job to start")
        done = _until(lambda: (j := jobs.get(click["id"]))["status"] in ("done", "failed", "cancelled") and j,
                      timeout=120, what="the click's job to finish")
        assert done["status"] == "done", done
        assert jobs.get(long["id"])["status"] == "cancelled"
    finally:
        for job in (long, click):
            jobs.cancel(job["id"])


def _until(predicate, timeout=60.0, what="condition"):
    deadline = time.time() + timeout
    while time.time() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(0.1)
    raise AssertionError(f"timed out waiting for {what}")


def test_requests_that_share_a_result_but_not_a_design_are_jobs_of_their_own(held):
    """Two maps of original at two e_p (the NES's: not in its model) share one cache key, so the second is
    answered from the first's result once it is in; but while the first is queued, the second is its own
    job with its own request (a shared job would report the first asker's design)."""
    a = jobs.submit_canonical("map", _map(params={"e_p": 0.002}))
    b = jobs.submit_canonical("map", _map(params={"e_p": 0.003}))
    same = jobs.submit_canonical("map", _map(params={"e_p": 0.003}))
    assert a["id"] != b["id"] and same["id"] == b["id"] and a["result_key"] == b["result_key"]
    assert jobs.public(b)["request"]["params"]["e_p"] == 0.003 and jobs.public(a)["request"]["params"]["e_p"] == 0.002
    assert _queue() == [a["id"], b["id"]]
