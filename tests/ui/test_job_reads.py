"""How a page's read of its jobs waits (ui.jobs._awaited): on the real job store, a read that finds its
job running and nothing new to draw waits for the job to end and answers as soon as it does; it does not
wait for a queued job, nor when something is due to be drawn, and never longer than WAIT_S."""

from __future__ import annotations

import threading
import time

import pytest

from shimmy.service import jobs, schemas, settings
from ui import jobs as page_jobs


@pytest.fixture
def job(tmp_path, monkeypatch):
    """A map job on a job store of its own, queued (no job starts by itself here)."""
    monkeypatch.setenv("SHIMMY_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(settings, "MAX_RUNNING_JOBS", 0)
    return jobs.submit_canonical("map", schemas.validate("map", {"config": "nes", "resolution": 3}), "view-1")["id"]


@pytest.fixture
def reads(monkeypatch):
    """How many times the job store is read through ui.jobs (the real reads, counted)."""
    count = [0]
    real = jobs.get

    def get(job_id):
        count[0] += 1
        return real(job_id)

    monkeypatch.setattr(page_jobs.jobs, "get", get)
    return count


def _never_due(_records) -> bool:
    return False


def test_a_running_job_that_ends_is_answered_as_soon_as_it_does(job, reads, monkeypatch):
    monkeypatch.setattr(page_jobs, "WAIT_S", 60.0)  # far longer than the job takes to end below
    jobs.update(job, status="running")
    ender = threading.Timer(0.2, lambda: jobs.update(job, status="done"))
    clock = time.monotonic()
    ender.start()
    try:
        records = page_jobs._awaited([job], [jobs.get(job)], _never_due)
    finally:
        ender.join()
    assert records[0]["status"] == "done"
    assert time.monotonic() - clock < 30.0  # answered at the change, not at the end of the wait
    assert reads[0] >= 2


def test_nothing_new_is_answered_after_the_wait(job, reads, monkeypatch):
    monkeypatch.setattr(page_jobs, "WAIT_S", 0.1)
    jobs.update(job, status="running")
    clock = time.monotonic()
    records = page_jobs._awaited([job], [jobs.get(job)], _never_due)
    assert records[0]["status"] == "running" and time.monotonic() - clock >= 0.1
    assert reads[0] >= 2  # read again while it waited


def test_a_queued_job_or_something_to_draw_is_answered_at_once(job, reads, monkeypatch):
    monkeypatch.setattr(page_jobs, "WAIT_S", 60.0)
    first = [jobs.get(job)]
    assert page_jobs._awaited([job], first, _never_due) == first  # queued: not waited for
    jobs.update(job, status="running")
    running = [jobs.get(job)]
    assert page_jobs._awaited([job], running, lambda records: True) == running  # a sketch due: drawn now
    assert reads[0] == 2  # the two reads above, none while answering

