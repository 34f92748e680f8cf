"""The executor interface: inline, local process pool, and a real Dask cluster on loopback.

The Dask fixture starts `dask scheduler` and two `dask worker` processes (one thread each) on
127.0.0.1 and checks that maps and studies computed there equal the local ones.
"""

import math
import os
from concurrent.futures import ProcessPoolExecutor

import pytest

from shimmy.errors import InvalidParameterError
from shimmy.model.parameters import Parameters
from shimmy.service.dask_cluster import loopback_cluster
from shimmy.analyses.core.executors import (DASK_ENV, PRELOAD, WORKERS_ENV, InlineExecutor, describe, drop_shared_pool,
                                           open_executor, run_dynamic, run_units, shared_pool, worker_count)
from shimmy.analyses.maps.stability_map import stability_map
from shimmy.analyses.decisions.studies import study

distributed = pytest.importorskip("distributed")


def _worker_state(_):
    import sys

    return os.getpid(), all(m in sys.modules for m in PRELOAD)


def test_a_shared_pool_is_handed_out_open_with_its_workers_started_warm(monkeypatch):
    """Within shared_pool every open_executor() gets the one pool (not closed by the call), whose
    workers were started when it was made, with the preloaded modules imported; after
    drop_shared_pool calls open pools of their own again."""
    monkeypatch.setenv(WORKERS_ENV, "2")
    monkeypatch.delenv(DASK_ENV, raising=False)
    with shared_pool():
        with open_executor() as first:
            pids = {p.pid for p in first._processes.values()}
            assert len(pids) == 2  # started before any unit of a computation
            states = run_units(_worker_state, [0, 1, 2, 3], first)
        with open_executor() as second:
            assert second is first and not first._shutdown_thread
            assert {pid for pid, _ in run_units(_worker_state, [0, 1], second)} <= pids
        assert all(warm for _, warm in states) and {pid for pid, _ in states} <= pids
        with open_executor(max_workers=2) as own:  # a caller that asks for its own count gets its own pool
            assert own is not first
        drop_shared_pool()
        with open_executor() as third:
            assert third is not first and isinstance(third, ProcessPoolExecutor)
    monkeypatch.setenv(WORKERS_ENV, "1")
    with shared_pool():
        with open_executor() as inline:
            assert isinstance(inline, InlineExecutor)


def test_run_units_keeps_the_order_and_reports_each_unit():
    seen = []
    with open_executor(max_workers=2) as pool:
        assert isinstance(pool, ProcessPoolExecutor)
        out = run_units(math.sqrt, [16.0, 1.0, 81.0, 4.0], pool, lambda f, m: seen.append((f, m)))
    assert out == [4.0, 1.0, 9.0, 2.0]
    assert [f for f, _ in seen] == [0.25, 0.5, 0.75, 1.0]
    assert all("done" in m for _, m in seen)


def test_run_dynamic_runs_the_most_urgent_unit_first_including_units_added_on_the_way():
    """One worker: units run strictly by priority; a unit's result adds more, which overtake the
    waiting ones of lower priority; progress never decreases although the total grows."""
    order, seen = [], []

    def done(unit, result):
        order.append(unit)
        assert result == math.sqrt(unit)
        return [(0, 100.0), (0, 121.0)] if unit == 4.0 else []

    messages = []
    with ProcessPoolExecutor(max_workers=1) as pool:
        count = run_dynamic(math.sqrt, [(2, 9.0), (1, 4.0), (3, 16.0), (2, 25.0)], pool, done,
                            lambda f, m: (seen.append(f), messages.append(m)),
                            tally=lambda u: "large" if u > 50 else "small")
    assert count == 6
    assert order == [4.0, 100.0, 121.0, 9.0, 25.0, 16.0]
    assert seen == sorted(seen) and seen[-1] == 1.0
    assert messages[0].endswith("(1/4 small, 0/2 large)") and messages[-1].endswith("(4/4 small, 2/2 large)")


def test_a_failing_unit_fails_the_call():
    with pytest.raises(ValueError, match="math domain error"):
        run_units(math.sqrt, [1.0, -1.0, 4.0], InlineExecutor())


def _refuse(value):
    return Parameters().with_overrides({"n": value})  # n is a count: 50.5 is refused


def test_a_refusal_in_a_process_pool_worker_reaches_the_caller_as_itself():
    """A field's refusal raised in a worker used to break the pool (BrokenProcessPool): the error
    could not be rebuilt from its pickle. It arrives as the same error, field and value."""
    with ProcessPoolExecutor(max_workers=1) as pool:
        with pytest.raises(InvalidParameterError) as err:
            run_units(_refuse, [24.0, 50.5], pool)
        assert err.value.field == "n" and err.value.value == 50.5 and "is not an integer" in str(err.value)
        assert pool.submit(_refuse, 20.0).result().pd.n == 20.0  # the pool still works


def test_worker_count_comes_from_the_argument_the_environment_or_the_cores(monkeypatch):
    monkeypatch.delenv(WORKERS_ENV, raising=False)
    monkeypatch.delenv(DASK_ENV, raising=False)
    assert worker_count(3) == 3
    assert worker_count() == (os.cpu_count() or 1)
    monkeypatch.setenv(WORKERS_ENV, "1")
    assert describe() == "in process"
    with open_executor() as ex:
        assert isinstance(ex, InlineExecutor)
    monkeypatch.setenv(WORKERS_ENV, "many")
    with pytest.raises(InvalidParameterError) as err:
        worker_count()
    assert err.value.field == WORKERS_ENV
    with pytest.raises(InvalidParameterError):
        worker_count(0)


def test_an_unreachable_scheduler_is_named():
    with pytest.raises(InvalidParameterError) as err:
        with open_executor(scheduler="tcp://127.0.0.1:9"):
            pass
    assert err.value.field == DASK_ENV


@pytest.fixture(scope="module")
def dask_cluster(tmp_path_factory):
    """A real scheduler and two single-threaded worker processes on loopback; yields the address."""
    with loopback_cluster(n_workers=2, log_dir=tmp_path_factory.mktemp("dask")) as address:
        yield address


def test_a_study_on_the_dask_cluster_equals_the_local_one(dask_cluster, monkeypatch):
    args = ("e_p", [0.0005, 0.005])
    kwargs = dict(configs=["original", "nes"], Fz=150e3)
    local = study(*args, **kwargs, executor=InlineExecutor())
    seen = []
    monkeypatch.setenv(DASK_ENV, dask_cluster)
    remote = study(*args, **kwargs, progress=lambda f, m: seen.append(f))
    assert remote.executor == f"dask cluster at {dask_cluster}"
    assert remote.rows == local.rows
    # the four sampled diagrams fill the first half, the curves (Hopf, min shimmy, the max_psi grid) the rest
    assert seen[:4] == [0.125, 0.25, 0.375, 0.5] and seen == sorted(seen) and seen[-1] == 1.0


def test_a_map_on_the_dask_cluster_equals_the_local_one(dask_cluster):
    kwargs = dict(v_range=(1.0, 200.0), fz_range=(1.0e5, 4.0e5), resolution=4, n_v=30)
    local = stability_map("original", **kwargs)
    with open_executor(scheduler=dask_cluster) as ex:
        workers = ex._client.scheduler_info()["workers"]
        assert len(workers) == 2 and all(w["host"] == "127.0.0.1" for w in workers.values())
        remote = stability_map("original", executor=ex, **kwargs)
    assert remote.types == local.types
    assert remote.fold_curves == local.fold_curves and remote.torus_curves == local.torus_curves
    assert remote.hopf_curves == local.hopf_curves
    assert remote.min_shimmy == local.min_shimmy
    assert {t for row in remote.types for t in row} >= {"Torsion", "Bistable"}
