"""The nearest cached design: where a map one slider step away is warmed from.

Every map the service computes leaves its warm start
(:meth:`~shimmy.analyses.maps.stability_map.StabilityMap.warm_start`: its curves' seeds with their
points, slices and arrangement, ~1.2 MB for `nes`) in the shared result cache, and its design in an
index of the maps of the same question but the design (configuration, plane, grid, options: the
request without ``params``). :func:`nearest` reads that index (one small entry, however many
designs it lists) and returns the warm start of the nearest design within :data:`MAX_DISTANCE`, so
finding a neighbour costs one cache read and a few dozen comparisons.

The index keeps the ``KEEP`` most recent designs of each question; a warm start whose entry
the cache has evicted is skipped. Updates are transactions of the store (diskcache ``transact``),
so the gunicorn workers, job workers and the command line can all add to one index.
"""

from __future__ import annotations

import logging
from typing import Any

from ..model.parameters import Parameters, design_distance
from . import cache

log = logging.getLogger(__name__)
#: Largest relative change of any design parameter between a map and the map it is warmed from
#: (one slider step is 0.5 % of a range; e_p +10 %, r2 -0.005 m, k_s +10 %, a_p +0.05 are 6-10 %):
#: farther designs are computed cold. The warm map's own check (the arrangement of its curves)
#: is what decides whether warming is right; this only bounds what is tried.
MAX_DISTANCE = 0.25
KEEP = 32  # designs listed per question


def _question(analysis: str, request: dict[str, Any]) -> str:
    return "neighbours:" + cache.key(analysis, {k: v for k, v in request.items() if k != "params"})


def _start_key(analysis: str, request: dict[str, Any]) -> str:
    return "warm:" + cache.key(analysis, request)


def remember(analysis: str, request: dict[str, Any], start: dict[str, Any]) -> None:
    """Keep ``start`` (a warm start of the result of ``request``) and list its design."""
    if cache.is_bypassed():
        return
    try:  # never fails the computed map it is called for: a locked store (diskcache.Timeout) included
        store = cache.results()
        store.set(_start_key(analysis, request), start)
        question = _question(analysis, request)
        with store.transact():
            listed = [e for e in (store.get(question) or []) if e["params"] != request["params"]]
            store.set(question, ([{"params": request["params"], "key": _start_key(analysis, request)}]
                                 + listed)[:KEEP])
    except Exception as exc:  # noqa: BLE001 - see above
        log.error("warm start not kept (%s: %s)", type(exc).__name__, exc)


def _ranked(analysis: str, request: dict[str, Any]) -> list[dict[str, Any]]:
    """The listed designs of the same question within reach, nearest first."""
    if cache.is_bypassed():
        return []
    try:
        store = cache.results()
        listed = store.get(_question(analysis, request)) or []
        here = Parameters.from_dict(request["params"])
        config = request.get("config")  # a parameter outside its model is no distance
        ranked = sorted((design_distance(here, Parameters.from_dict(e["params"]), config), k)
                        for k, e in enumerate(listed) if e["params"] != request["params"])
        # a warm start the cache has evicted (large entries go first) is no neighbour
        return [listed[k] for distance, k in ranked if distance <= MAX_DISTANCE and listed[k]["key"] in store]
    except Exception as exc:  # noqa: BLE001 - an unreadable index or store: no neighbour, the map is cold
        log.warning("neighbour index unreadable (%s: %s): computing cold", type(exc).__name__, exc)
        return []


def within_reach(analysis: str, request: dict[str, Any]) -> bool:
    """Whether a design near enough to warm from is listed (one small read: for a page deciding to
    compute by itself)."""
    return bool(_ranked(analysis, request))


def nearest(analysis: str, request: dict[str, Any]) -> dict[str, Any] | None:
    """The warm start of the nearest other design of the same question within :data:`MAX_DISTANCE`,
    or None."""
    for entry in _ranked(analysis, request):
        start = cache.get_key(entry["key"])
        if start is not None:
            return start
    return None
