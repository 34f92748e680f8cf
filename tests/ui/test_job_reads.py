"""How a page reads its jobs (ui.jobs): on the real job store, a read that finds its job running and
nothing new to show waits for something to show and answers as soon as there is (the job's end, its
progress); it does not wait for a queued job, nor when a sketch is due, and never longer than WAIT_S. While
a page follows the design by itself its sketch is redrawn at most every LIVE_SKETCH_S. An answer on its way names
the watcher of the jobs it read (the page drops it if a later action came first)."""

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


def _statuses(records):
    return [None if r is None else r["status"] for r in records]


def _progress(records):
    return [None if r is None else (r["status"], r["progress"], r["message"]) for r in records]


def _never(_records) -> bool:
    return False


def test_a_running_job_that_ends_is_answered_as_soon_as_it_does(job, monkeypatch):
    monkeypatch.setattr(page_jobs, "WAIT_S", 60.0)  # far longer than the job takes to end below
    jobs.update(job, status="running")
    ender = threading.Timer(0.2, lambda: jobs.update(job, status="done"))
    clock = time.monotonic()
    ender.start()
    try:
        records = page_jobs._awaited([job], [jobs.get(job)], _statuses, _never)
    finally:
        ender.join()
    assert records[0]["status"] == "done"
    assert time.monotonic() - clock < 30.0  # answered at the change, not at the end of the wait


def test_progress_ends_the_wait_where_the_page_shows_it(job, monkeypatch):
    monkeypatch.setattr(page_jobs, "WAIT_S", 60.0)
    jobs.update(job, status="running", progress=0.1, message="Hopf curves")
    mover = threading.Timer(0.2, lambda: jobs.update(job, progress=0.5, message="slices"))
    clock = time.monotonic()
    mover.start()
    try:
        records = page_jobs._awaited([job], [jobs.get(job)], _progress, _never)
    finally:
        mover.join()
    assert (records[0]["status"], records[0]["message"]) == ("running", "slices")
    assert time.monotonic() - clock < 30.0


def test_nothing_new_is_answered_after_the_wait(job, monkeypatch):
    monkeypatch.setattr(page_jobs, "WAIT_S", 0.1)
    jobs.update(job, status="running")
    clock = time.monotonic()
    records = page_jobs._awaited([job], [jobs.get(job)], _progress, _never)
    assert records[0]["status"] == "running" and 0.1 <= time.monotonic() - clock < 30.0


def test_a_queued_job_or_a_sketch_due_is_answered_at_once(job, monkeypatch):
    monkeypatch.setattr(page_jobs, "WAIT_S", 60.0)
    reads = [0]
    real = jobs.peek

    def peek(job_id):  # the real read, counted
        reads[0] += 1
        return real(job_id)

    monkeypatch.setattr(page_jobs.jobs, "peek", peek)
    first = [jobs.get(job)]
    assert page_jobs._awaited([job], first, _statuses, _never) == first  # queued: not waited for
    jobs.update(job, status="running")
    running = [jobs.get(job)]
    assert page_jobs._awaited([job], running, _statuses, lambda records: True) == running  # drawn now
    assert reads[0] == 0


def test_a_live_pages_sketch_is_redrawn_at_most_every_live_sketch_s():
    ids = ["a"]
    grown = [{"status": "running", "sketch": {"hopf_curves": [[1, 2], [3]], "fold_curves": [[4]]}}]  # size 4
    assert page_jobs._sketch_due(grown, ids, None, live=True)  # the first: at once
    now = {"jobs": ids, "sizes": [4], "at": time.time()}
    assert not page_jobs._sketch_due(grown, ids, now, live=True)  # nothing new
    smaller = {**now, "sizes": [2]}
    assert not page_jobs._sketch_due(grown, ids, smaller, live=True)  # grown, but drawn just now
    assert page_jobs._sketch_due(grown, ids, smaller, live=False)  # a page that is not live: at once
    earlier = {**smaller, "at": time.time() - 2 * page_jobs.LIVE_SKETCH_S}
    assert page_jobs._sketch_due(grown, ids, earlier, live=True)
    assert not page_jobs._sketch_due([{"status": "queued"}], ids, None, live=True)  # no sketch yet
    assert not page_jobs._sketch_due([None], ids, None, live=False)


def test_the_veiled_clock_remembers_its_second_per_run():
    assert page_jobs._clock_drawn({"jobs": ["a"], "clock": 2}, ["a"]) == 2
    assert page_jobs._clock_drawn({"jobs": ["b"], "clock": 2}, ["a"]) is None  # another run's
    assert page_jobs._clock_drawn({"jobs": ["a"], "clock": True}, ["a"]) is None  # not a second
    assert page_jobs._clock_drawn(None, ["a"]) is None


def test_results_found_done_are_drawn_only_while_the_page_still_waits_for_them(job):
    """The poll found the job done and signalled its draw; before the draw, a later action of the page (a cached
    answer to new controls, drawn at once) let the job go. Drawn then, the older answer would replace it."""
    jobs.update(job, status="done")
    go = {"jobs": [job], "requests": [{"config": "nes"}], "watcher": "view-1", "asked": time.time()}
    ready = {**go, "tick": 3}
    assert page_jobs._still_awaited(ready, go)
    assert not page_jobs._still_awaited(ready, None)  # the later action's answer: the page waits for nothing
    assert not page_jobs._still_awaited(ready, {**go, "jobs": ["other"], "watcher": "view-2"})  # other jobs
    assert not page_jobs._still_awaited(ready, {**go, "watcher": "view-2"})  # the same job, asked again
    assert not page_jobs._still_awaited({**ready, "jobs": []}, {**go, "jobs": []})
    # the store not yet changed in the browser, but the service has seen the page let the job go
    jobs.release(job, "view-1")
    assert not page_jobs._still_awaited(ready, go)


def test_an_answer_on_its_way_names_the_watcher_it_was_of_and_only_what_it_updates():
    figure = {"data": [{"x": [1.0], "y": [2.0]}], "layout": {}}
    landed = page_jobs.landing({"jobs": ["a"], "requests": [{}], "watcher": "view-1"},
                               (figure, page_jobs.no_update, "", None, page_jobs.no_update))
    assert landed["watcher"] == "view-1" and landed["n"] == 5
    assert landed["set"] == [[0, figure], [2, ""], [3, None]]  # an empty line and a cleared store are updates
    assert page_jobs.landing(None, (page_jobs.no_update,))["watcher"] is None  # the page waited for nothing
    assert page_jobs.landing(None, ())["id"] != page_jobs.landing(None, ())["id"]  # each lands, even if equal
