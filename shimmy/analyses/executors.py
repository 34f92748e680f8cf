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
the results in the order of the units. A unit that raises makes the whole call raise (the
remaining units are cancelled): units are pure functions of their arguments, so a failure
is a bug or bad input, never something to hide in a partial result.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import threading
from concurrent.futures import Executor, Future, ProcessPoolExecutor, as_completed
from typing import Any, Callable, Iterator, Sequence

from ..errors import InvalidParameterError

DASK_ENV = "SHIMMY_DASK_SCHEDULER"
WORKERS_ENV = "SHIMMY_WORKERS"
#: Modules the forkserver imports once, so that forked workers start warm.
PRELOAD = ["shimmy.analyses.stability_map", "shimmy.analyses.studies"]


class InlineExecutor(Executor):
    """Runs each unit at submission in the calling process (one worker, no pickling)."""

    def submit(self, fn, /, *args, **kwargs) -> Future:
        future: Future = Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except BaseException as exc:  # noqa: B036 - handed to the caller through the future
            future.set_exception(exc)
        return future


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
    if threading.active_count() == 1:
        context = multiprocessing.get_context("fork")
    else:
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload(PRELOAD)
    with ProcessPoolExecutor(max_workers=n, mp_context=context) as pool:
        yield pool


def run_units(fn: Callable[[Any], Any], units: Sequence[Any], executor: Executor | None = None,
              progress: Callable[[float, str], None] | None = None,
              describe_unit: Callable[[Any], str] = str, tally: Callable[[Any], str] | None = None) -> list[Any]:
    """``[fn(u) for u in units]`` through ``executor`` (default: :func:`open_executor`),
    reporting ``progress(finished / total, "<unit> done (k/n)")`` per finished unit. With ``tally``
    (unit -> the plural noun it is counted as, e.g. "slices"), the count is per noun, so that it
    counts what the caller asked for: "(3/40 slices, 1/2 curve sets)"."""
    if executor is None:
        with open_executor() as own:
            return run_units(fn, units, own, progress, describe_unit, tally)
    report = progress or (lambda fraction, message: None)
    futures = {executor.submit(fn, unit): k for k, unit in enumerate(units)}
    results: list[Any] = [None] * len(units)
    nouns = [tally(u) for u in units] if tally else None
    totals = {n: nouns.count(n) for n in dict.fromkeys(nouns)} if nouns else {}
    counts = dict.fromkeys(totals, 0)
    finished = 0
    try:
        for future in as_completed(futures):
            k = futures[future]
            results[k] = future.result()
            finished += 1
            if nouns:
                counts[nouns[k]] += 1
                count = ", ".join(f"{counts[n]}/{totals[n]} {n}" for n in totals)
            else:
                count = f"{finished}/{len(units)}"
            report(finished / len(units), f"{describe_unit(units[k])} done ({count})")
    finally:
        for future in futures:
            future.cancel()
    return results
