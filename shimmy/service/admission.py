"""Admission control of the work done in the request: a bounded number of quick computations per web
worker, a rate per user, and the sign-in attempts per client address. A request beyond a limit is
refused at once (:class:`Busy`: 429 with ``Retry-After`` and ``X-Shimmy-Limit`` naming the limit),
never left holding a thread.

The quick analyses (``POST /simulate``, ``/hopf``, ``/stability``, ``/devices``, ``/sensitivity`` and
the workbench pages that draw them) compute in the web worker's threads. A cached answer takes no
slot. A miss takes one of ``MAX_FAST_COMPUTATIONS`` slots of this worker, or waits for one among at
most ``FAST_WAITING`` others for at most ``FAST_WAIT_SECONDS``; the worker's other threads (at least
``FAST_RESERVED_THREADS``) stay free for health checks, cached answers, job polls and pages. When
the server knows its users, one user holds at most ``MAX_FAST_COMPUTATIONS`` of a worker's slots
and waiting places together, and computes at most ``FAST_PER_USER_PER_SECOND`` answers a second
on average (a token bucket of ``FAST_PER_USER_BURST``, shared by every worker through the cache
directory), so one user's burst leaves room for everyone else.
"""

from __future__ import annotations

import contextlib
import math
import sys
import threading
import time
from collections import Counter
from typing import Iterator

from . import cache, settings

#: The limits a 429 names (its ``X-Shimmy-Limit`` header).
LIMITS = {
    "jobs_queue": "SHIMMY_MAX_QUEUED_JOBS",
    "jobs_per_user": "SHIMMY_MAX_JOBS_PER_USER",
    "jobs_queue_reserved": "SHIMMY_QUEUE_RESERVED",
    "fast_concurrency": "SHIMMY_MAX_FAST_COMPUTATIONS",
    "fast_per_user": "SHIMMY_MAX_FAST_COMPUTATIONS",
    "fast_rate": "SHIMMY_FAST_PER_USER_PER_SECOND",
    "login_attempts": "SHIMMY_LOGIN_ATTEMPTS_PER_MINUTE",
}


class Busy(Exception):
    """A request refused by a limit: ``limit`` (a key of :data:`LIMITS`), the message, and when to try again."""

    def __init__(self, limit: str, message: str, retry_after: float, field: str = "analysis",
                 allowed: str | None = None):
        super().__init__(message)
        self.limit, self.field = limit, field
        self.retry_after = max(1, int(math.ceil(retry_after)))
        self.allowed = allowed or f"a request once the limit ({LIMITS[limit]}) leaves room"

    def headers(self) -> dict[str, str]:
        return {"Retry-After": str(self.retry_after), "X-Shimmy-Limit": self.limit}


def requester() -> str | None:
    """The user of the request being served (the workbench's or an API client's), or None when the server
    does not know its users (SHIMMY_AUTH=none), outside a request (the command line, a job) or before
    Flask is even loaded."""
    flask = sys.modules.get("flask")
    if flask is None or not flask.has_request_context():
        return None
    principal = flask.g.get("principal")
    return principal.user if principal is not None and principal.identified else None


# -- quick computations in this worker ------------------------------------------------------

_gate = threading.Condition()
_computing = 0
_waiting = 0
_held: Counter[str] = Counter()  # per user: computing or waiting in this worker


@contextlib.contextmanager
def fast_slot(analysis: str, user: str | None = None) -> Iterator[None]:
    """Hold one of this worker's computation slots while the block runs (Busy when none comes)."""
    global _computing, _waiting
    if user is not None:
        take_rate(analysis, user)
    deadline = time.monotonic() + settings.FAST_WAIT_SECONDS
    with _gate:
        if user is not None and _held[user] >= settings.MAX_FAST_COMPUTATIONS:
            raise Busy("fast_per_user", f"analysis {analysis!r} not computed now: {_held[user]} of your "
                       f"computations already run or wait in this worker, the most one user may have "
                       f"(SHIMMY_MAX_FAST_COMPUTATIONS = {settings.MAX_FAST_COMPUTATIONS}); try again in "
                       f"{settings.FAST_RETRY_AFTER_SECONDS} s", settings.FAST_RETRY_AFTER_SECONDS,
                       allowed=f"at most {settings.MAX_FAST_COMPUTATIONS} of one user's computations at once")
        if _computing >= settings.MAX_FAST_COMPUTATIONS:
            if _waiting >= settings.FAST_WAITING:
                raise _crowded(analysis)
            _waiting += 1
            if user is not None:
                _held[user] += 1
            try:
                while _computing >= settings.MAX_FAST_COMPUTATIONS:
                    left = deadline - time.monotonic()
                    if left <= 0:
                        raise _crowded(analysis)
                    _gate.wait(left)
            except BaseException:
                if user is not None:
                    _release_user(user)
                raise
            finally:
                _waiting -= 1
        elif user is not None:
            _held[user] += 1
        _computing += 1
    try:
        yield
    finally:
        with _gate:
            _computing -= 1
            if user is not None:
                _release_user(user)
            _gate.notify()


def _release_user(user: str) -> None:
    _held[user] -= 1
    if _held[user] <= 0:
        del _held[user]


def _crowded(analysis: str) -> Busy:
    return Busy("fast_concurrency", f"analysis {analysis!r} not computed now: {_computing} computations run in "
                f"this worker (SHIMMY_MAX_FAST_COMPUTATIONS = {settings.MAX_FAST_COMPUTATIONS}) and "
                f"{_waiting} wait for them; try again in {settings.FAST_RETRY_AFTER_SECONDS} s",
                settings.FAST_RETRY_AFTER_SECONDS,
                allowed=f"a computation once fewer than {settings.MAX_FAST_COMPUTATIONS} run in the worker")


def fast_load() -> dict[str, int]:
    """This worker's computations running and waiting (for tests and the admin's view)."""
    with _gate:
        return {"computing": _computing, "waiting": _waiting}


# -- shared counters (every worker, through the cache directory) ----------------------------------


def _store():
    return cache.open_store(settings.cache_dir() / "limits")


def take_rate(analysis: str, user: str) -> None:
    """Take one computation from ``user``'s bucket (FAST_PER_USER_BURST, refilled at
    FAST_PER_USER_PER_SECOND), or Busy saying when the next one is there."""
    rate, burst = settings.FAST_PER_USER_PER_SECOND, max(1.0, settings.FAST_PER_USER_BURST)
    if rate <= 0:
        return
    s = _store()
    now = time.time()
    with s.transact():
        tokens, then = s.get(("rate", user), (burst, now))
        tokens = min(burst, tokens + (now - then) * rate)
        if tokens < 1.0:
            s.set(("rate", user), (tokens, now), expire=burst / rate + 60)
            wait = (1.0 - tokens) / rate
            raise Busy("fast_rate", f"analysis {analysis!r} not computed now: you asked for more than "
                       f"{rate:g} computations a second (SHIMMY_FAST_PER_USER_PER_SECOND, bursts of {burst:g}); "
                       f"try again in {max(1, math.ceil(wait))} s", wait,
                       allowed=f"at most {rate:g} computations a second per user")
        s.set(("rate", user), (tokens - 1.0, now), expire=burst / rate + 60)


def take_login_attempt(address: str) -> None:
    """Count one sign-in attempt from ``address`` in the current minute; Busy beyond the limit."""
    limit = settings.LOGIN_ATTEMPTS_PER_MINUTE
    now = time.time()
    window = int(now // 60)
    s = _store()
    key = ("login", address[:64], window)
    with s.transact():
        count = s.get(key, 0) + 1
        s.set(key, count, expire=120)
    if count > limit:
        raise Busy("login_attempts", f"too many sign-in attempts from this address ({limit} a minute, "
                   f"SHIMMY_LOGIN_ATTEMPTS_PER_MINUTE); try again in {60 * (window + 1) - now:.0f} s",
                   60 * (window + 1) - now, field="token", allowed=f"at most {limit} attempts a minute")
