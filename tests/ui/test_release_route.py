"""The route by which a page that is left lets its jobs go (assets/jobs.js posts there): the jobs
nobody else waits for are cancelled; what the browser sends is checked and refused by name, never a 500."""

from __future__ import annotations

import pytest

from shimmy.service import jobs, schemas, settings

ROUTE = "/_workbench/release"


@pytest.fixture
def client(tmp_path, monkeypatch):
    """The app's test client on a job store of its own in which no job starts (they stay queued)."""
    monkeypatch.setenv("SHIMMY_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(settings, "MAX_RUNNING_JOBS", 0)
    import app

    return app.server.test_client()


def _queued(watcher: str, resolution: int) -> str:
    request = schemas.validate("map", {"config": "nes", "resolution": resolution})
    return jobs.submit_canonical("map", request, watcher)["id"]


def test_a_left_page_cancels_its_jobs_but_not_one_an_api_client_waits_for(client):
    mine, shared = _queued("view-1", 3), _queued("view-1", 4)
    assert client.post("/api/v1/jobs", json={"analysis": "map", "config": "nes", "resolution": 4}).json["id"] == shared
    answer = client.post(ROUTE, json={"jobs": [{"id": mine, "watcher": "view-1"}, {"id": shared, "watcher": "view-1"},
                                               {"id": "f" * 32, "watcher": "view-1"}]})
    assert answer.status_code == 204
    assert jobs.get(mine)["status"] == "cancelled"
    assert jobs.get(shared)["status"] == "queued"  # the API client's job goes on
    assert jobs.store().get("queue") == [shared]


@pytest.mark.parametrize("body, field", [
    ({"jobs": "all"}, "jobs"),
    ([], "jobs"),
    ({"jobs": [{"id": "a" * 32, "watcher": "w"}] * 257}, "jobs"),
    ({"jobs": [{"id": 3, "watcher": "w"}]}, "jobs[0]"),
    ({"jobs": [{"id": "a" * 32}]}, "jobs[0]"),
    ({"jobs": [{"id": "a" * 32, "watcher": "w" * 65}]}, "jobs[0]"),
    ({"jobs": [{"id": "a" * 32, "watcher": "w"}, "x"]}, "jobs[1]"),
])
def test_what_the_browser_sends_is_refused_by_name(client, body, field):
    answer = client.post(ROUTE, json=body)
    assert answer.status_code == 400 and answer.json["field"] == field and field in answer.json["error"]


def test_only_a_json_post_is_taken(client):
    answer = client.post(ROUTE, data='{"jobs": []}', content_type="text/plain")
    assert answer.status_code == 415 and answer.json["field"] == "Content-Type"
    assert client.post(ROUTE, data="{", content_type="application/json").status_code == 400
    assert client.post(ROUTE, json={"jobs": []}).status_code == 204
