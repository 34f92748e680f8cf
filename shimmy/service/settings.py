"""Deployment settings read from the environment (one place, documented in the README)."""

from __future__ import annotations

import os
import pathlib
import tempfile

#: Bumped whenever the JSON of any analysis result changes shape: old cache entries then miss.
SCHEMA_VERSION = 1

#: Limits on what one request may ask for (refused with 4xx naming the limit).
MAX_BODY_BYTES = 64 * 1024
MAX_T_END = 600.0  # s of simulated time per request
MAX_SERIES_POINTS = 200_000  # samples per returned time series (t_end / dt_out)
MAX_NTST = 200
MAX_MAP_SLICES = 80  # Fz slices of one map (40 take ~20 s on 2 cores)
MAX_MAP_SPEEDS = 400  # speeds per slice on a map's output grid
MAX_STUDY_VALUES = 50  # values per study parameter
MAX_STUDY_UNITS = 200  # diagrams per study (designs x configurations, ~0.5-2 s each)
MAX_RUNNING_JOBS = 2  # at most this many analyses run at once on this host; others wait queued
#: A queued/running job whose heartbeat is older than this has lost its worker (SHIMMY_JOB_STALE_SECONDS).
JOB_STALE_SECONDS = float(os.environ.get("SHIMMY_JOB_STALE_SECONDS", "30"))


def cache_dir() -> pathlib.Path:
    """SHIMMY_CACHE_DIR, or a per-user folder in the temporary directory."""
    path = os.environ.get("SHIMMY_CACHE_DIR") or os.path.join(tempfile.gettempdir(), f"shimmy-cache-{os.getuid()}")
    p = pathlib.Path(path)
    p.mkdir(parents=True, exist_ok=True)
    return p


def cache_size_limit() -> int:
    """SHIMMY_CACHE_SIZE_MB (default 2048) in bytes: diskcache evicts least-recently-stored beyond it."""
    return int(float(os.environ.get("SHIMMY_CACHE_SIZE_MB", "2048")) * 1024 * 1024)
