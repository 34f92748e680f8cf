"""Deployment settings read from the environment (one place, documented in the README)."""

from __future__ import annotations

import ipaddress
import math
import os
import pathlib
import socket
import tempfile

#: Bumped whenever the JSON of any analysis result changes shape or meaning: old cache entries (and the warm
#: starts kept beside them) then miss. 2: the Latent map type, margins from an orbit and along a mix, simulate's x0.
SCHEMA_VERSION = 2

#: Limits on what one request may ask for (refused with 4xx naming the limit).
MAX_BODY_BYTES = 64 * 1024
#: Threads per web worker (gunicorn's gthread worker, gunicorn.conf.py) that run the WSGI app
#: (SHIMMY_WEB_THREADS). Quick computations take at most MAX_FAST_COMPUTATIONS of them and wait in at most
#: FAST_WAITING more; the rest (at least FAST_RESERVED_THREADS) stay free for health, cached answers and the pages.
WEB_THREADS = int(os.environ.get("SHIMMY_WEB_THREADS", "32"))
#: Slow clients, held by the buffering proxy in front of gunicorn (nginx, shimmy.service.nginx), which
#: passes a request on only once it is complete: the headers of a request must be complete within this
#: many seconds of the connection's first byte being awaited, else the connection is closed
#: (SHIMMY_HEADER_READ_SECONDS; nginx's client_header_timeout).
HEADER_READ_SECONDS = float(os.environ.get("SHIMMY_HEADER_READ_SECONDS", "10"))
#: A request body may pause at most this many seconds between two reads, else the connection is closed
#: (SHIMMY_BODY_READ_SECONDS; nginx's client_body_timeout). The app itself, when a client reaches it
#: directly (gunicorn alone on loopback), waits at most this long for a body announced longer than sent (408).
BODY_READ_SECONDS = float(os.environ.get("SHIMMY_BODY_READ_SECONDS", "10"))
#: A client that stops reading an answer for this many seconds is disconnected (SHIMMY_SEND_SECONDS;
#: nginx's send_timeout): the proxy holds the answer, never a gunicorn thread.
SEND_SECONDS = float(os.environ.get("SHIMMY_SEND_SECONDS", "30"))
#: An idle keep-alive connection is closed after this many seconds (SHIMMY_KEEPALIVE_SECONDS; nginx's
#: keepalive_timeout), and after KEEPALIVE_REQUESTS requests.
KEEPALIVE_SECONDS = float(os.environ.get("SHIMMY_KEEPALIVE_SECONDS", "15"))
KEEPALIVE_REQUESTS = 1000
#: The longest time the proxy waits for the app's answer (nginx's proxy_read_timeout), the same as
#: gunicorn's worker --timeout in `python -m shimmy serve` and the image.
REQUEST_SECONDS = 120
MAX_T_END = 600.0  # s of simulated time per request
MAX_SERIES_POINTS = 200_000  # samples per returned time series (t_end / dt_out)
MAX_NTST = 200
MAX_MAP_SLICES = 80  # classified Fz slices of one map (10, the default, plus those through regions they miss)
MAX_MAP_SPEEDS = 400  # speeds per slice on a map's output grid
MAX_STUDY_VALUES = 50  # values per study parameter
MAX_STUDY_UNITS = 200  # diagrams per study (designs x configurations, ~0.5-2 s each)
MAX_ROBUSTNESS_SAMPLES = 2048  # samples of one robustness analysis (~1 s per 100 on 2 cores)
MAX_DISTURBED_SAMPLES = 256  # with a disturbance (margins at nine points: ~5 s per sample and core)
#: Admission control of jobs, shared by the API and the workbench pages (SHIMMY_MAX_RUNNING_JOBS,
#: SHIMMY_MAX_QUEUED_JOBS): at most this many run at once on this host, each in its own process;
#: at most this many more wait queued, holding no process; beyond that a submission is refused
#: (429 with Retry-After: JOB_RETRY_AFTER_SECONDS; a 4xx, not a server error).
MAX_RUNNING_JOBS = int(os.environ.get("SHIMMY_MAX_RUNNING_JOBS", "2"))
MAX_QUEUED_JOBS = int(os.environ.get("SHIMMY_MAX_QUEUED_JOBS", "8"))
JOB_RETRY_AFTER_SECONDS = int(os.environ.get("SHIMMY_JOB_RETRY_AFTER_SECONDS", "30"))
#: Per user (per token), when the server knows its users (SHIMMY_AUTH=token): at most this many of
#: one user's jobs queued or running (SHIMMY_MAX_JOBS_PER_USER), at most this many running at once
#: (SHIMMY_MAX_RUNNING_JOBS_PER_USER; default: all slots but one, so that another user's first job
#: starts at once), and a user who already has a job waiting may not take the last QUEUE_RESERVED
#: places of the queue (they are kept for the first job of somebody else).
MAX_JOBS_PER_USER = int(os.environ.get("SHIMMY_MAX_JOBS_PER_USER", "4"))
MAX_RUNNING_JOBS_PER_USER = int(os.environ.get("SHIMMY_MAX_RUNNING_JOBS_PER_USER",
                                               str(max(1, MAX_RUNNING_JOBS - 1))))
QUEUE_RESERVED = int(os.environ.get("SHIMMY_QUEUE_RESERVED", str(max(1, MAX_QUEUED_JOBS // 4))))
#: Bounded storage of job records: a finished job's record (status, request; its result is in the result
#: cache) is kept this many hours (SHIMMY_JOB_RETENTION_HOURS), and at most this many records are kept,
#: the oldest finished ones removed first (SHIMMY_MAX_JOB_RECORDS). Queued and running jobs never expire.
JOB_RETENTION_HOURS = float(os.environ.get("SHIMMY_JOB_RETENTION_HOURS", "168"))
MAX_JOB_RECORDS = int(os.environ.get("SHIMMY_MAX_JOB_RECORDS", "5000"))
#: A job whose process was found gone when the server started (killed with the server, the machine
#: restarted), or whose worker ended before starting it, is queued again this many times in all, then
#: failed with a message saying so.
JOB_RESTARTS = 1
#: Admission control of the quick analyses answered in the request (POST /simulate, /hopf, /stability,
#: /devices, /sensitivity and the pages that draw them): per web worker at most MAX_FAST_COMPUTATIONS
#: compute at once (SHIMMY_MAX_FAST_COMPUTATIONS), at most FAST_WAITING more wait up to
#: FAST_WAIT_SECONDS for one of them (SHIMMY_FAST_WAIT_SECONDS); beyond, 429 with Retry-After
#: FAST_RETRY_AFTER_SECONDS. A cached answer takes no slot.
MAX_FAST_COMPUTATIONS = int(os.environ.get("SHIMMY_MAX_FAST_COMPUTATIONS", "2"))
FAST_RESERVED_THREADS = 4
FAST_WAITING = max(0, WEB_THREADS - MAX_FAST_COMPUTATIONS - FAST_RESERVED_THREADS)
FAST_WAIT_SECONDS = float(os.environ.get("SHIMMY_FAST_WAIT_SECONDS", "15"))
FAST_RETRY_AFTER_SECONDS = int(os.environ.get("SHIMMY_FAST_RETRY_AFTER_SECONDS", "2"))
#: Per user (SHIMMY_AUTH=token): quick computations (cache misses) per second, on average
#: (SHIMMY_FAST_PER_USER_PER_SECOND) and in a burst (SHIMMY_FAST_PER_USER_BURST); beyond, 429.
FAST_PER_USER_PER_SECOND = float(os.environ.get("SHIMMY_FAST_PER_USER_PER_SECOND", "5"))
FAST_PER_USER_BURST = float(os.environ.get("SHIMMY_FAST_PER_USER_BURST", "20"))
#: Sign-in: failed attempts per client address and minute before 429 (SHIMMY_LOGIN_ATTEMPTS_PER_MINUTE),
#: and how long a workbench session lasts (SHIMMY_SESSION_HOURS).
LOGIN_ATTEMPTS_PER_MINUTE = int(os.environ.get("SHIMMY_LOGIN_ATTEMPTS_PER_MINUTE", "10"))
SESSION_HOURS = float(os.environ.get("SHIMMY_SESSION_HOURS", "12"))
#: A worker being started that has not been recorded after this long is taken for dead.
JOB_START_SECONDS = 60.0


class JobSettingError(ValueError):
    """A job setting from the environment that is not a number in its range."""


def _seconds(name: str, default: str, high: float) -> float:
    """The environment's ``name`` as seconds in [0, high]; a value that is not is refused by name."""
    raw = os.environ.get(name, default)
    try:
        value = float(raw)
    except ValueError:
        value = math.nan
    if not 0.0 <= value <= high:  # NaN too
        raise JobSettingError(f"{name}={raw!r} is not a number of seconds in [0, {high:g}]")
    return value


#: A job worker whose queue is empty stays this long, idle and registered, for the next job
#: (SHIMMY_JOB_WORKER_LINGER_SECONDS, 0 to 3600; 0: it ends at once): a slider step's map then starts in a
#: process whose imports and kernels are warm (~0.8 s sooner than a new worker).
JOB_WORKER_LINGER_SECONDS = _seconds("SHIMMY_JOB_WORKER_LINGER_SECONDS", "60", 3600.0)
#: Only for a worker on another host sharing the directory: no heartbeat for this long means it is gone
#: (SHIMMY_JOB_STALE_SECONDS). Workers on this host are judged by their process, never by a late beat.
JOB_STALE_SECONDS = float(os.environ.get("SHIMMY_JOB_STALE_SECONDS", "30"))
#: Page views one job records as waiting for it (jobs.release); beyond, the job is pinned (runs to the end).
MAX_JOB_WATCHERS = 64
#: Requests one page action may send (configurations x designs); more are refused by name.
MAX_PAGE_REQUESTS = 8


class CacheDirectoryError(RuntimeError):
    """The cache directory is not private to this user (its values are unpickled)."""


def cache_dir_setting() -> pathlib.Path:
    """Where the cache directory is, without creating or checking it: SHIMMY_CACHE_DIR, or a per-user
    folder in the temporary directory (``/tmp/shimmy-cache-UID``)."""
    return pathlib.Path(os.environ.get("SHIMMY_CACHE_DIR")
                        or os.path.join(tempfile.gettempdir(), f"shimmy-cache-{os.getuid()}"))


def cache_dir() -> pathlib.Path:
    """The cache directory (:func:`cache_dir_setting`); created 0700 and refused if another user owns it
    or anyone else may write to it."""
    p = cache_dir_setting()
    p.mkdir(mode=0o700, parents=True, exist_ok=True)
    st = p.stat()
    if st.st_uid != os.getuid():
        raise CacheDirectoryError(f"cache directory {p} belongs to uid {st.st_uid}, not to this user "
                                  f"(uid {os.getuid()}); set SHIMMY_CACHE_DIR to a directory of your own")
    if st.st_mode & 0o022:
        raise CacheDirectoryError(f"cache directory {p} is writable by group or others (mode "
                                  f"{st.st_mode & 0o777:o}); chmod go-w it or set SHIMMY_CACHE_DIR elsewhere")
    return p


def cache_size_limit() -> int:
    """SHIMMY_CACHE_SIZE_MB (default 2048) in bytes: diskcache evicts least-recently-stored beyond it."""
    return int(float(os.environ.get("SHIMMY_CACHE_SIZE_MB", "2048")) * 1024 * 1024)


def tokens_file() -> pathlib.Path:
    """Where the API tokens are kept (hashed): SHIMMY_TOKENS_FILE, or ``tokens.json`` in the cache directory."""
    explicit = os.environ.get("SHIMMY_TOKENS_FILE")
    return pathlib.Path(explicit) if explicit else cache_dir() / "tokens.json"


# -- who may use the service -----------------------------------------------------------------

AUTH_MODES = ("token", "oidc", "none")


class AuthSettingError(RuntimeError):
    """SHIMMY_AUTH asks for something this server will not do (the server refuses to start)."""


def _listed(name: str) -> list[str]:
    return [a.strip() for a in os.environ.get(name, "").split(",") if a.strip()]


def listen_addresses() -> list[str]:
    """Where clients reach the server: the addresses gunicorn listens on, as gunicorn.conf.py recorded them
    from gunicorn's ``bind`` setting (SHIMMY_LISTEN, comma-separated; empty if it was not started through
    it), and those of the proxy in front of it (SHIMMY_PROXY_LISTEN, set by ``python -m shimmy serve``).
    With a proxy named, gunicorn's Unix sockets count as reached through it only (the proxy's address
    stands for them)."""
    own, proxy = _listed("SHIMMY_LISTEN"), _listed("SHIMMY_PROXY_LISTEN")
    return [a for a in own if not (proxy and a.startswith("unix:"))] + proxy


class ProxySettingError(RuntimeError):
    """SHIMMY_TRUSTED_PROXY names something that is not an address (the server refuses to start)."""


def trusted_proxies() -> frozenset[str]:
    """The peers whose forwarding headers are believed (SHIMMY_TRUSTED_PROXY, comma-separated): ``unix``
    (a client of gunicorn's Unix socket: the proxy ``python -m shimmy serve`` starts) and IP addresses.
    A request from one of them takes its client address from X-Forwarded-For and its scheme from
    X-Forwarded-Proto, which that proxy sets; from anyone else (and when the setting is empty, the
    default) those headers are ignored and the client address is the connection's."""
    out = set()
    for entry in _listed("SHIMMY_TRUSTED_PROXY"):
        if entry != "unix":
            try:
                entry = str(ipaddress.ip_address(entry))
            except ValueError:
                raise ProxySettingError(f"SHIMMY_TRUSTED_PROXY={os.environ['SHIMMY_TRUSTED_PROXY']!r}: {entry!r} is "
                                        "neither 'unix' nor an IP address; allowed: a comma-separated list of "
                                        "them (the proxy's own address), or nothing") from None
        out.add(entry)
    return frozenset(out)


def is_loopback(address: str) -> bool:
    """Whether a gunicorn bind address is reachable from this machine only: a TCP address whose host is a
    loopback address or resolves only to loopback addresses. A Unix socket or an inherited file descriptor
    counts as beyond loopback (a proxy in front of it may serve anyone)."""
    if address.startswith(("unix:", "fd://")) or "/" in address:
        return False
    host = address.removeprefix("tcp://")
    if host.startswith("["):  # [::1]:8050
        host = host[1:].partition("]")[0]
    elif host.count(":") == 1:
        host = host.partition(":")[0]
    if host in ("", "0.0.0.0", "::", "*"):
        return False
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        pass
    try:
        found = {info[4][0] for info in socket.getaddrinfo(host, None)}
    except OSError:
        return False
    return bool(found) and all(ipaddress.ip_address(a.split("%")[0]).is_loopback for a in found)


def beyond_loopback(addresses: list[str] | None = None) -> bool:
    """Whether any address the server listens on is reachable from other machines."""
    addresses = listen_addresses() if addresses is None else addresses
    return any(not is_loopback(a) for a in addresses)


def auth_mode(addresses: list[str] | None = None) -> str:
    """``token`` or ``none``: SHIMMY_AUTH, by default ``none`` on loopback and ``token`` beyond it.
    AuthSettingError for an unknown mode, for ``oidc`` (not built) and for ``none`` beyond loopback
    without SHIMMY_ALLOW_ANONYMOUS=1."""
    exposed = beyond_loopback(addresses)
    mode = os.environ.get("SHIMMY_AUTH", "").strip().lower() or ("token" if exposed else "none")
    if mode not in AUTH_MODES:
        raise AuthSettingError(f"SHIMMY_AUTH={mode!r} is not one of {', '.join(AUTH_MODES)}")
    if mode == "oidc":
        raise AuthSettingError("SHIMMY_AUTH=oidc: single sign-on is not built in this version; use SHIMMY_AUTH=token "
                               "(API tokens, and a sign-in page taking a token for the workbench)")
    if mode == "none" and exposed and os.environ.get("SHIMMY_ALLOW_ANONYMOUS", "") != "1":
        raise AuthSettingError("SHIMMY_AUTH=none while listening beyond loopback (" + ", ".join(
            listen_addresses() if addresses is None else addresses) + "): anyone who can reach the port could use "
            "the service; use SHIMMY_AUTH=token, bind 127.0.0.1, or set SHIMMY_ALLOW_ANONYMOUS=1 to waive it")
    return mode


def cookie_secure() -> bool | None:
    """SHIMMY_COOKIE_SECURE: 1 marks the session cookie Secure always (behind a proxy that ends TLS), 0
    never; unset (None): Secure when the request came over https."""
    value = os.environ.get("SHIMMY_COOKIE_SECURE", "").strip()
    return None if value == "" else value == "1"
