"""The kernels a web worker loads before it answers (gunicorn.conf.py's post_worker_init): each
analysis answered in the request runs once, and nothing is written to the result cache."""

from __future__ import annotations

from shimmy.service import analyses, cache, schemas, warmup


def test_every_analysis_answered_in_the_request_is_warmed_but_the_sensitivities():
    sync = {name for name, a in analyses.ANALYSES.items() if a.sync}
    assert set(warmup.QUESTIONS) == sync - {"sensitivity"}


def test_warming_runs_each_question_and_stores_nothing(tmp_path, monkeypatch):
    monkeypatch.setenv("SHIMMY_CACHE_DIR", str(tmp_path))
    assert warmup.warm_kernels() > 0.0
    for name, body in warmup.QUESTIONS.items():
        assert cache.get(name, schemas.validate(name, body)) is None

