"""The commands the HTTP API also answers, on the service's shared result cache.

A command states its question as the API's request (:func:`request`: the request schema's canonical
form, so its cache key is the API's), then :func:`answer` reads the result from the store that the
API, its job workers and the workbench read and fill (``SHIMMY_CACHE_DIR``), or computes it with the
service's own runner and stores it there. ``--no-cache`` computes without reading or writing the
store. :func:`emit` writes the result with where it came from: the JSON's ``"cache"`` (hit, miss or
off) and the last line of the text. The result is the service's dict either way, so a cached answer
prints exactly as a computed one.

Nothing here imports the numerics: a cached answer is printed without loading them.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from typing import Any, Callable, Sequence

from ..service.schemas import validate
from ..service.settings import cache_dir_setting
from .common import emit as emit_payload
from .common import limit, params

HIT, MISS, OFF = "hit", "miss", "off"


@dataclass(frozen=True)
class Answer:
    """A result (the service's dict) and where it came from: ``cache`` HIT (read from the shared cache),
    MISS (computed and stored there) or OFF (computed without it, for the reason ``why``)."""

    result: dict[str, Any]
    cache: str
    why: str = ""


def add_no_cache(p: argparse.ArgumentParser) -> None:
    p.add_argument("--no-cache", action="store_true",
                   help="compute without reading or writing the result cache shared with the HTTP API and the "
                        f"workbench (SHIMMY_CACHE_DIR, now {cache_dir_setting()})")


def numbers(analysis: str, args, *names: str) -> dict[str, float | int]:
    """{name: the option of that name checked against the limits the API gives it in ``analysis``}."""
    return {name: limit(analysis, name, getattr(args, name)) for name in names}


def design(args) -> dict[str, float]:
    """The design of ``--material`` and ``--set`` as the complete parameter dict of a request."""
    return params(args).to_dict()


def request(analysis: str, body: dict[str, Any]) -> dict[str, Any]:
    """The canonical request of ``analysis`` for ``body`` (every field, defaults filled), checked by the
    API's request schema: equal questions give equal requests, hence one cache key wherever asked."""
    return validate(analysis, body)


def answer(args, analysis: str, canonical: dict[str, Any],
           progress: Callable[[float, str], None] | None = None) -> Answer:
    """The result of the canonical request: from the shared cache, else computed by the service's runner and
    stored; with ``--no-cache`` computed by the same runner, the cache neither read nor written."""
    from ..service.analyses import RUNNERS, run_canonical

    if args.no_cache:
        from ..service.cache import bypassed

        with bypassed():  # nor a cached neighbour: a map is computed cold
            return Answer(RUNNERS[analysis](canonical, progress), OFF, "--no-cache")
    result, hit = run_canonical(analysis, canonical, progress)
    return Answer(result, HIT if hit else MISS)


def source(answers: Sequence[Answer]) -> tuple[str, str]:
    """(the JSON's "cache", the text's last line) of the answers one command prints: hit when each came
    from the cache, off when each was computed without it, else miss."""
    where = cache_dir_setting()
    hits = sum(a.cache == HIT for a in answers)
    if all(a.cache == OFF for a in answers):
        return OFF, f"computed without the cache ({answers[0].why})"
    if hits == len(answers):
        return HIT, f"answered from the shared cache ({where})"
    if hits:
        return MISS, (f"{hits} of {len(answers)} answered from the shared cache ({where}), the others computed "
                      "and stored there")
    return MISS, f"computed and stored in the shared cache ({where})"


def emit(payload: dict[str, Any], answers: Sequence[Answer], as_json: bool, text: str) -> None:
    """``payload`` as JSON with "cache" added, or ``text`` with a last line saying where the answer came from."""
    cache, line = source(answers)
    emit_payload(payload | {"cache": cache}, as_json, f"{text}\n{line}")


def note(answers: Sequence[Answer]) -> None:
    """Where the answer came from, on stderr: for output that is a file format (CSV on stdout)."""
    print(source(answers)[1], file=sys.stderr)
