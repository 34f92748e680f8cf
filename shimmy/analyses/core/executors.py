"""One executor interface for independent units of work (Fz slices of a map, points of a study).

:func:`open_executor` gives a :class:`concurrent.futures.Executor`:

* a Dask distributed cluster when ``SHIMMY_DASK_SCHEDULER`` names a scheduler address
  (``tcp://host:8786``): ``distributed.Client(address).get_executor()``, whose futures are
  ordinary ``concurrent.futures`` futures;
* otherwise a local process pool with one process per core (``SHIMMY_WORKERS`` overrides the
  count). A single-threaded caller (a script, the CLI, a job worker) forks its workers: they
  start warm, with the package already imported, and scripts need no ``__main__`` guard. A
  multi-threaded caller (a web server) gets them from a forkserver that imported the package
  once, so that no thread's locks are forked along in an unknown state;
* ``max_workers=1`` (or ``SHIMMY_WORKERS=1``) runs the units in the calling process.

:func:`run_units` submits every unit, reports progress each time one finishes and returns
the results in the order of the units. :func:`run_dynamic` runs units whose results create
more units (a curve continued from a start that a diagram found), most urgent first. A unit
that raises makes the whole call raise (the remaining units are cancelled): units are pure
functions of their arguments, so a failure is a bug or bad input, never something to hide in
a partial result.
"""

from __future__ import annotations

import contextlib
import heapq
import itertools
import multiprocessing
import os
import threading
from concurrent.futures import FIRST_COMPLETED, Executor, Future, ProcessPoolExecutor, as_completed, wait
from typing import Any, Callable, Iterator, Protocol, Sequence

from ...errors import InvalidParameterError

DASK_ENV = "SHIMMY_DASK_SCHEDULER"
WORKERS_ENV = "SHIMMY_WORKERS"
#: Modules the forkserver imports once, so that forked workers start warm.
PRELOAD = ["shimmy.analyses.maps.stability_map", "shimmy.analyses.decisions.studies"]


class InlineExecutor(Executor):
    """Runs each unit at submission in the calling process (one worker, no pickling)."""

    def submit(self, fn, /, *args, **kwargs) -> Future:
        future: Future = Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except BaseException as exc:  # noqa: B036 - handed to the caller through the future
            future.set_exception(exc)
        return future


class WorkUnit(Protocol):
    """An independent unit of work: a small frozen dataclass, shipped to any process or Dask worker."""

    def run(self) -> Any: ...

    def describe(self) -> str: ...


def run_work_unit(unit: WorkUnit) -> Any:
    """Run one unit (top level, so that process pools and Dask can ship it)."""
    return unit.run()


def describe_work_unit(unit: WorkUnit) -> str:
    return unit.describe()


def worker_count(max_workers: int | None = None) -> int:
    """Local worker count: the argument, else ``SHIMMY_WORKERS``, else the number of cores."""
    if max_workers is None:
        raw = os.environ.get(WORKERS_ENV, "").strip()
        if raw:
            try:
                max_workers = int(raw)
            except ValueError:
                raise InvalidParameterError(WORKERS_ENV, raw, "a whole number from 1 to 64") from None
        else:
            max_workers = os.cpu_count() or 1
    if not 1 <= max_workers <= 64:
        raise InvalidParameterError("max_workers", max_workers, "a whole number from 1 to 64")
    return int(max_workers)


def describe(scheduler: str | None = None, max_workers: int | None = None) -> str:
    scheduler = scheduler if scheduler is not None else os.environ.get(DASK_ENV, "").strip()
    if scheduler:
        return f"dask cluster at {scheduler}"
    n = worker_count(max_workers)
    return "in process" if n == 1 else f"local process pool ({n} workers)"


def name_of(executor: Executor | None) -> str:
    """What ran a computation: :func:`describe` for the default executor, else the executor's type."""
    return describe() if executor is None else type(executor).__name__


@contextlib.contextmanager
def open_executor(max_workers: int | None = None, scheduler: str | None = None) -> Iterator[Executor]:
    """The executor for this environment (see the module docstring); closed on exit."""
    scheduler = scheduler if scheduler is not None else os.environ.get(DASK_ENV, "").strip()
    if scheduler:
        try:
            from distributed import Client
        except ImportError:
            raise InvalidParameterError(DASK_ENV, scheduler, "unset, or the address of a Dask scheduler with "
                                        "the 'dask' extra installed (pip install shimmy[dask])") from None
        try:
            client = Client(scheduler, timeout=10, set_as_default=False)
        except OSError as exc:
            raise InvalidParameterError(DASK_ENV, scheduler, "the address of a reachable Dask scheduler",
                                        f"cannot be reached: {exc}") from None
        try:
            executor = client.get_executor(pure=False)
            yield executor
        finally:
            client.close()
        return
    n = worker_count(max_workers)
    if n == 1:
        yield InlineExecutor()
        return
    shared = _SHARED[0]
    if shared is not None and max_workers is None and not getattr(shared, "_broken", False):
        yield shared  # the process's own pool (:func:`shared_pool`): open already, closed by its owner
        return
    if threading.active_count() == 1:
        context = multiprocessing.get_context("fork")
    else:
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload(PRELOAD)
    with ProcessPoolExecutor(max_workers=n, mp_context=context) as pool:
        yield pool


#: The pool :func:`shared_pool` made for this process, if one is open.
_SHARED: list[ProcessPoolExecutor | None] = [None]


def _ready() -> None:
    """A unit that does nothing: submitted once, it makes a pool start its workers."""


@contextlib.contextmanager
def shared_pool() -> Iterator[None]:
    """For as long as the block lasts, :func:`open_executor` (default workers, no Dask scheduler)
    hands out one local process pool made here instead of a pool per call. Made while the caller is
    still single-threaded (call it before starting threads): its workers are forked at once from
    this process, with :data:`PRELOAD` imported, so they start warm and every computation in the
    block (a job worker's jobs, one after another) uses them without starting processes. Where a
    pool per call would not be a local pool (one worker, a Dask scheduler) nothing is made."""
    try:
        own = not (os.environ.get(DASK_ENV, "").strip() or worker_count() == 1 or _SHARED[0] is not None)
    except InvalidParameterError:  # a bad SHIMMY_WORKERS: each computation says so where it opens its executor
        own = False
    if not own:
        yield
        return
    import importlib

    for module in PRELOAD:
        importlib.import_module(module)
    context = multiprocessing.get_context("fork" if threading.active_count() == 1 else "forkserver")
    if context.get_start_method() == "forkserver":
        context.set_forkserver_preload(PRELOAD)
    pool = ProcessPoolExecutor(max_workers=worker_count(), mp_context=context)
    pool.submit(_ready).result()  # a fork pool starts all its workers at its first unit: now, before any thread
    _SHARED[0] = pool
    try:
        yield
    finally:
        _SHARED[0] = None
        pool.shutdown(wait=True, cancel_futures=True)


def drop_shared_pool() -> None:
    """End the shared pool now (its running units killed): after a failed computation whose units may
    still be running there. Later calls open a pool each."""
    pool, _SHARED[0] = _SHARED[0], None
    if pool is not None:
        for process in list(getattr(pool, "_processes", {}).values()):
            process.kill()
        pool.shutdown(wait=False, cancel_futures=True)


def run_units(fn: Callable[[Any], Any], units: Sequence[Any], executor: Executor | None = None,
              progress: Callable[[float, str], None] | None = None,
              describe_unit: Callable[[Any], str] = str) -> list[Any]:
    """``[fn(u) for u in units]`` through ``executor`` (default: :func:`open_executor`),
    reporting ``progress(finished / total, "<unit> done")`` per finished unit."""
    if executor is None:
        with open_executor() as own:
            return run_units(fn, units, own, progress, describe_unit)
    report = progress or (lambda fraction, message: None)
    futures = {executor.submit(fn, unit): k for k, unit in enumerate(units)}
    results: list[Any] = [None] * len(units)
    finished = 0
    try:
        for future in as_completed(futures):
            k = futures[future]
            results[k] = future.result()
            finished += 1
            report(finished / len(units), f"{describe_unit(units[k])} done ({finished}/{len(units)})")
    finally:
        for future in futures:
            future.cancel()
    return results


def run_dynamic(fn: Callable[[Any], Any], units: Sequence[tuple[float, Any]], executor: Executor,
                on_done: Callable[[Any, Any], Sequence[tuple[float, Any]]],
                progress: Callable[[float, str], None] | None = None,
                describe_unit: Callable[[Any], str] = str, tally: Callable[[Any], str] | None = None) -> int:
    """Run ``(priority, unit)`` pairs through ``executor``, lowest priority value first;
    ``on_done(unit, result)`` (called in this process as units finish) returns more
    ``(priority, unit)`` pairs to run. Returns the number of units run.

    At most one unit per worker is in flight (a local pool's processes, a Dask cluster's threads;
    inline: one), so that an urgent unit created late (the longest one, on the critical path)
    starts at the next free worker instead of queueing behind the rest. Units that finish
    together are handed to ``on_done`` in the order they were submitted. ``progress`` gets
    finished / (finished + known) units, never decreasing although units are added on the way;
    with ``tally`` (unit -> the plural noun it is counted as) the message counts per noun,
    finished of known: "(3/10 slices, 2/5 curve units)"."""
    report = progress or (lambda fraction, message: None)
    order = itertools.count()
    ready: list[tuple[float, int, Any]] = []
    for priority, unit in units:
        heapq.heappush(ready, (priority, next(order), unit))
    width = _width(executor)
    running: dict[Future, tuple[int, Any]] = {}
    submitted = itertools.count()
    finished, shown = 0, 0.0
    done_by: dict[str, int] = {}
    known_by: dict[str, int] = {}

    def count(unit: Any) -> None:
        if tally is not None:
            noun = tally(unit)
            known_by[noun] = known_by.get(noun, 0) + 1
            done_by.setdefault(noun, 0)

    for _, unit in units:
        count(unit)
    try:
        while ready or running:
            while ready and len(running) < width:
                _, _, unit = heapq.heappop(ready)
                running[executor.submit(fn, unit)] = (next(submitted), unit)
            done, _ = wait(list(running), return_when=FIRST_COMPLETED)
            for future in sorted(done, key=lambda f: running[f][0]):  # finished together: as submitted
                _, unit = running.pop(future)
                result = future.result()
                finished += 1
                for priority, more in on_done(unit, result):
                    heapq.heappush(ready, (priority, next(order), more))
                    count(more)
                total = finished + len(running) + len(ready)
                shown = max(shown, finished / total)
                if tally is not None:
                    done_by[tally(unit)] += 1
                    counted = ", ".join(f"{done_by[n]}/{known_by[n]} {n}" for n in known_by)
                else:
                    counted = f"{finished}/{total}"
                report(shown, f"{describe_unit(unit)} done ({counted})")
    finally:
        for future in running:
            future.cancel()
    return finished


def executor_width(executor: Executor) -> int:
    """Units in flight at once on ``executor``: its workers (threads of a Dask cluster; one inline)."""
    return _width(executor)


def _width(executor: Executor) -> int:
    """Units in flight at once on ``executor``: its workers (threads of a Dask cluster)."""
    if isinstance(executor, InlineExecutor):
        return 1
    workers = getattr(executor, "_max_workers", None)
    if workers:
        return int(workers)
    client = getattr(executor, "_client", None)  # distributed's ClientExecutor
    if client is not None:
        try:
            return max(1, sum(client.nthreads().values()))
        except Exception:  # noqa: BLE001 - a cluster that cannot say: no limit, Dask queues them
            return 10 ** 9
    return 10 ** 9
