"""One result cache for every analysis, shared by all processes through one directory.

Key: SHA-256 of the canonical JSON of {analysis, canonical request (every parameter and
numerical option, defaults filled in), schema version, package version}. Values are the
JSON-ready result dicts. diskcache is process- and thread-safe on one directory, so all
gunicorn workers, the job workers and the Dash background manager share it.
"""

from __future__ import annotations

import functools
from typing import Any, Callable

import diskcache

from .. import __version__
from ..model.parameters import canonical_digest
from . import settings


@functools.lru_cache(maxsize=None)
def _open(path: str, size_limit: int) -> diskcache.Cache:
    return diskcache.Cache(path, size_limit=size_limit, eviction_policy="least-recently-stored")


def results() -> diskcache.Cache:
    return _open(str(settings.cache_dir() / "results"), settings.cache_size_limit())


def key(analysis: str, request: dict[str, Any]) -> str:
    return canonical_digest({"analysis": analysis, "request": request, "schema": settings.SCHEMA_VERSION,
                             "version": __version__})


def get(analysis: str, request: dict[str, Any]) -> dict[str, Any] | None:
    return results().get(key(analysis, request))


def get_or_compute(analysis: str, request: dict[str, Any],
                   compute: Callable[[], dict[str, Any]]) -> tuple[dict[str, Any], bool]:
    """(result, True if it came from the cache)."""
    k = key(analysis, request)
    found = results().get(k)
    if found is not None:
        return found, True
    value = compute()
    results().set(k, value)
    return value, False
