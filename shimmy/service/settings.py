"""Deployment settings read from the environment (one place, documented in the README)."""

from __future__ import annotations

import os
import pathlib
import tempfile

#: Bumped whenever the JSON of any analysis result changes shape: old cache entries then miss.
SCHEMA_VERSION = 1

#: Limits on what one request may ask for (refused with 4xx naming the limit).
MAX_BODY_BYTES = 64 * 1024
#: Threads per web worker that run the WSGI app on complete requests (SHIMMY_WEB_THREADS).
WEB_THREADS = int(os.environ.get("SHIMMY_WEB_THREADS", "8"))
#: The headers of a connection's first request must be complete within this many seconds, else it is
#: closed (SHIMMY_HEADER_READ_SECONDS).
HEADER_READ_SECONDS = float(os.environ.get("SHIMMY_HEADER_READ_SECONDS", "10"))
#: A request body must arrive within this many seconds of the app asking for it (else 408).
BODY_READ_SECONDS = float(os.environ.get("SHIMMY_BODY_READ_SECONDS", "10"))
MAX_T_END = 600.0  # s of simulated time per request
MAX_SERIES_POINTS = 200_000  # samples per returned time series (t_end / dt_out)
MAX_NTST = 200
MAX_MAP_SLICES = 80  # classified Fz slices of one map (10, the default, plus those through regions they miss)
MAX_MAP_SPEEDS = 400  # speeds per slice on a map's output grid
MAX_STUDY_VALUES = 50  # values per study parameter
MAX_STUDY_UNITS = 200  # diagrams per study (designs x configurations, ~0.5-2 s each)
MAX_ROBUSTNESS_SAMPLES = 2048  # samples of one robustness analysis (~1 s per 100 on 2 cores)
#: Admission control of jobs, shared by the API and the workbench pages (SHIMMY_MAX_RUNNING_JOBS,
#: SHIMMY_MAX_QUEUED_JOBS): at most this many run at once on this host, each in its own process;
#: at most this many more wait queued, holding no process; beyond that a submission is refused
#: (429 with Retry-After: JOB_RETRY_AFTER_SECONDS; a 4xx, not a server error).
MAX_RUNNING_JOBS = int(os.environ.get("SHIMMY_MAX_RUNNING_JOBS", "2"))
MAX_QUEUED_JOBS = int(os.environ.get("SHIMMY_MAX_QUEUED_JOBS", "8"))
JOB_RETRY_AFTER_SECONDS = int(os.environ.get("SHIMMY_JOB_RETRY_AFTER_SECONDS", "30"))
#: A worker being started that has not been recorded after this long is taken for dead.
JOB_START_SECONDS = 60.0
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
