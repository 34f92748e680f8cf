"""One result cache for every analysis, shared by all processes through one directory.

Key: SHA-256 of the canonical JSON of {analysis, canonical request (every parameter and
numerical option, defaults filled in), schema version, package version}. Values are the
JSON-ready result dicts. diskcache is process- and thread-safe on one directory, so all
gunicorn workers, the job workers and the Dash pages share it.

A damaged cache never stops an analysis: an entry that cannot be read is a miss (logged,
removed, recomputed); a database that cannot be opened or queried is moved aside and rebuilt
empty; a directory deleted under a running server is recreated (every handle follows the
inode of its ``cache.db``, so all processes meet again in the new one). Where even that fails
the analyses answer uncached and :func:`health` says why (the API's health answers 503).
"""

from __future__ import annotations

import contextlib
import contextvars
import functools
import logging
import math
import os
import pathlib
import sqlite3
import time
from typing import Any, Callable, Iterator

import diskcache

from ..version import __version__
from ..model.parameters import affecting, canonical_digest
from . import settings

log = logging.getLogger(__name__)
#: What a damaged store raises: sqlite errors, a truncated or garbled pickle, a vanished file.
DAMAGE = (sqlite3.Error, OSError, EOFError, ValueError, TypeError, AttributeError, ImportError, IndexError,
          KeyError, UnicodeDecodeError, __import__("pickle").UnpicklingError)


def identity(path: pathlib.Path) -> tuple[int, int]:
    """(device, inode) of ``path``/cache.db; (0, 0) if it is missing."""
    try:
        st = os.stat(path / "cache.db")
    except OSError:
        return (0, 0)
    return (st.st_dev, st.st_ino)


_OPENED: list[diskcache.Cache] = []

#: A store's write-ahead log is checkpointed and truncated (``PRAGMA wal_checkpoint(TRUNCATE)``) once it
#: passes this size. SQLite's own checkpoint (every 1000 pages, ~4 MB) cannot start the log over while
#: another process reads an older snapshot, and with readers always present (a flood of requests on
#: several workers) the log grew with every write: 32 MB for 48 MB written by two processes while three
#: read, and 19.7 MB in the team test's job store on a loaded machine (its bound: 16 MB).
WAL_LIMIT = 6 * 2**20
#: ... tried at most this often per store and process; a try waits at most WAL_WAIT_S for the readers of
#: older snapshots to let go (reads are short), else gives up and a later one tries again. (Not waiting,
#: a try almost never found the log free: three readers and two writers took it to 42 MB; waiting 0.1 s
#: stalled every write while one reader held a snapshot. With these, 9-14 MB where it reached 18-38 MB.)
#: A try holds the writer lock while it waits, so a store whose reader lingers writes up to 0.03 s later
#: in every 0.1 s of each process that uses it: a latency cost only while its log is past the limit.
WAL_EVERY_S = 0.1
WAL_WAIT_S = 0.03
_WAL_TRIED: dict[str, float] = {}


def bound_log(path: pathlib.Path) -> bool | None:
    """Checkpoint and truncate the write-ahead log of the store at ``path`` if it passed
    :data:`WAL_LIMIT`: True if done, False if readers or a writer held it (tried again later), None
    if there was nothing to do (under the limit, or tried less than WAL_EVERY_S ago)."""
    try:
        if os.stat(path / "cache.db-wal").st_size <= WAL_LIMIT:
            return None
    except OSError:
        return None
    now = time.monotonic()
    if now - _WAL_TRIED.get(str(path), -math.inf) < WAL_EVERY_S:
        return None
    _WAL_TRIED[str(path)] = now
    try:
        # read-write, never create: a store removed meanwhile is not recreated empty here
        con = sqlite3.connect(f"file:{path / 'cache.db'}?mode=rw", uri=True, timeout=WAL_WAIT_S,
                              isolation_level=None)
        try:
            busy = con.execute("PRAGMA wal_checkpoint(TRUNCATE)").fetchone()[0]
        finally:
            con.close()
    except sqlite3.Error as exc:  # housekeeping: never fails the caller's read or write
        log.info("write-ahead log of %s not truncated: %s", path, exc)
        return False
    return not busy


@functools.lru_cache(maxsize=64)
def _open(path: str, ident: tuple[int, int], size_limit: int | None) -> diskcache.Cache:
    kwargs = {} if size_limit is None else {"size_limit": size_limit, "eviction_policy": "least-recently-stored"}
    handle = diskcache.Cache(path, **kwargs)
    _OPENED.append(handle)
    del _OPENED[:-64]
    return handle


def open_store(path: pathlib.Path, size_limit: int | None = None) -> diskcache.Cache:
    """The diskcache at ``path``, (re)built when it is missing, replaced or unreadable."""
    for attempt in range(2):
        ident = identity(path)
        try:
            if ident == (0, 0):  # missing (or deleted under us): create it, then key the handle by its inode
                path.mkdir(mode=0o700, parents=True, exist_ok=True)
                diskcache.Cache(str(path)).close()
                ident = identity(path)
            handle = _open(str(path), ident, size_limit)
            bound_log(path)
            handle.get("__probe__")  # a damaged database fails here, not in the caller's query
            return handle
        except DAMAGE as exc:
            if attempt:
                raise
            quarantine(path, exc)
    raise AssertionError("unreachable")


def quarantine(path: pathlib.Path, exc: BaseException) -> None:
    """Move a damaged store aside (kept for inspection, named .broken-TIME) so it is rebuilt empty."""
    aside = path.with_name(f"{path.name}.broken-{time.time():.0f}-{os.getpid()}")
    log.error("cache %s is damaged (%s: %s); moved to %s and rebuilt empty", path, type(exc).__name__, exc, aside)
    _open.cache_clear()
    try:
        path.rename(aside)
    except OSError as exc2:  # another process moved it first; its rebuilt store is used
        log.warning("could not move %s aside: %s", path, exc2)


_BYPASSED: contextvars.ContextVar[bool] = contextvars.ContextVar("shimmy_cache_bypassed", default=False)


@contextlib.contextmanager
def bypassed() -> Iterator[None]:
    """Within it nothing reads or writes the cache beside the analysis itself: the nearest cached
    design is not looked up (a map is computed cold) and no warm start is kept (``--no-cache``)."""
    token = _BYPASSED.set(True)
    try:
        yield
    finally:
        _BYPASSED.reset(token)


def is_bypassed() -> bool:
    return _BYPASSED.get()


def results() -> diskcache.Cache:
    return open_store(settings.cache_dir() / "results", settings.cache_size_limit())


#: Analyses of one configuration whose result depends on the design only through that configuration's
#: model: their key holds only the parameters that enter it (:func:`~shimmy.model.parameters.affecting`),
#: so the map of ``original`` is one entry however the NES and damper sliders stand. (Analyses that
#: report parameter values, sample or search them, or cover several configurations key them all.)
MODEL_ONLY = frozenset({"map", "hopf", "bifurcation", "hopf_curves", "simulate", "ground_run", "margins",
                        "margin_map", "growth"})  # growth: one configuration's part of "stability"


def key(analysis: str, request: dict[str, Any]) -> str:
    keyed = request
    if analysis in MODEL_ONLY and isinstance(request.get("params"), dict) and isinstance(request.get("config"), str):
        keyed = {**request, "params": affecting(request["params"], request["config"])}
    return canonical_digest({"analysis": analysis, "request": keyed, "schema": settings.SCHEMA_VERSION,
                             "version": __version__})


def as_asked(value: dict[str, Any] | None, request: dict[str, Any]) -> dict[str, Any] | None:
    """A cached ``value`` as the answer to ``request``: the same numbers, its ``params`` the request's (a
    MODEL_ONLY result may have been computed for a design that differs in parameters outside the model)."""
    if isinstance(value, dict) and "params" in value and "params" in request and value["params"] != request["params"]:
        return {**value, "params": request["params"]}
    return value


def get(analysis: str, request: dict[str, Any]) -> dict[str, Any] | None:
    return as_asked(get_key(key(analysis, request)), request)


def get_key(k: str) -> dict[str, Any] | None:
    """The cached value of ``k``, or None: a missing, unreadable or damaged entry is a miss."""
    try:
        store = results()
    except DAMAGE as exc:
        log.error("result cache unusable, answering uncached: %s", exc)
        return None
    try:
        return store.get(k)
    except DAMAGE as exc:
        log.warning("cache entry %s unreadable (%s: %s): removed, will be recomputed", k[:12], type(exc).__name__,
                    exc)
        try:
            store.delete(k)
        except DAMAGE:
            quarantine(settings.cache_dir() / "results", exc)
        return None


def put(k: str, value: dict[str, Any]) -> None:
    try:
        results().set(k, value)
    except DAMAGE as exc:
        log.error("result not cached (%s: %s)", type(exc).__name__, exc)


def get_or_compute(analysis: str, request: dict[str, Any],
                   compute: Callable[[], dict[str, Any]]) -> tuple[dict[str, Any], bool]:
    """(result, True if it came from the cache); within :func:`bypassed` computed, the cache neither
    read nor written (an analysis's parts asked through here follow its ``--no-cache``)."""
    if is_bypassed():
        return compute(), False
    k = key(analysis, request)
    found = as_asked(get_key(k), request)
    if found is not None:
        return found, True
    value = compute()
    put(k, value)
    return value, False


def health() -> dict[str, Any]:
    """{"ok": bool, "detail": str}: a value written to each store can be read back."""
    try:
        root = settings.cache_dir()
        for name in ("results", "jobs"):
            store = open_store(root / name)
            probe = f"__health__{os.getpid()}"
            store.set(probe, name, expire=60)
            if store.get(probe) != name:
                return {"ok": False, "detail": f"the {name} store does not return what was written"}
    except Exception as exc:  # noqa: BLE001 - whatever is wrong is what health reports
        return {"ok": False, "detail": f"{type(exc).__name__}: {exc}"}
    return {"ok": True, "detail": str(root)}


def close_all() -> None:
    """Close every store this process opened (before it forks: a child must not share a connection)."""
    for handle in list(_OPENED):
        try:
            handle.close()
        except DAMAGE:
            pass
    _OPENED.clear()
    _open.cache_clear()
