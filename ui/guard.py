"""The server's front door: security headers on every response, and a 400 naming what is wrong
for a malformed request to the Dash callback endpoint. (Who may send it is checked before, by
:func:`shimmy.service.auth.install`: app.py installs it first.)

Headers: ``X-Content-Type-Options: nosniff``, ``X-Frame-Options: DENY``, ``Referrer-Policy:
no-referrer`` and a Content-Security-Policy under which the pages work: scripts only from this
server plus the hashes of Dash's inline scripts (``app.csp_hashes()``), inline styles (Plotly
writes them), data/blob images (the PNG export), no plugins, no framing.

Dash's own dispatcher indexes the request body without checking it (a missing ``output``, a
string where a list belongs, an unknown callback all raise inside it, answered 500). The
check here runs before it, against the app's own callback map: the body is a JSON object
(parsed by the API's bounded parser), ``output`` names a registered callback, ``inputs`` and
``state`` list exactly the declared ids and properties, ``outputs`` and ``changedPropIds`` have
their shapes. A callback that then fails on the values a client chose (a string where a page
expects a number) is answered 400 too, and logged with its traceback.
"""

from __future__ import annotations

import json
import logging
from typing import Any

import flask
from werkzeug.exceptions import HTTPException

from shimmy.service.admission import Busy
from shimmy.service.api import RequestRefused, error, parse_json

log = logging.getLogger(__name__)


class BadCallback(RequestRefused):
    status = 400

    def __init__(self, message: str, field: str, allowed: str):
        super().__init__(message if field in message else f"{field}: {message}", field, allowed)


def install(app) -> None:
    """Check every POST to ``app``'s callback endpoint before Dash dispatches it; add the
    security headers to every response of its server."""
    path = app.config.routes_pathname_prefix + "_dash-update-component"
    server = app.server
    policy: list[tuple[int, str]] = [(-1, "")]  # (number of inline scripts, the policy naming their hashes)

    @server.after_request
    def _headers(response):
        # Dash registers one more inline script (dash pages' document.title callback) in a hook of the
        # first request (app.py runs that hook at import; this stays the safety net): a response of
        # another thread served meanwhile must not fix the policy without it (it did: under load every
        # page then broke on "Executing inline script violates ..."). The policy is made again whenever
        # the app's count of inline scripts differs from the one it was made at (Dash has no public
        # count; the list only grows, the count is read before the hashes), and replaced whole (one
        # assignment: a thread reads the old one or the new one).
        count = len(app._inline_scripts)
        known, text = policy[0]
        if known != count:
            text = "; ".join([
                "default-src 'self'", "script-src 'self' " + " ".join(app.csp_hashes()),
                "style-src 'self' 'unsafe-inline'", "img-src 'self' data: blob:", "font-src 'self' data:",
                "connect-src 'self'", "object-src 'none'", "base-uri 'self'", "form-action 'self'",
                "frame-ancestors 'none'"])
            policy[0] = (count, text)
        response.headers["Content-Security-Policy"] = text
        response.headers["X-Content-Type-Options"] = "nosniff"
        response.headers["X-Frame-Options"] = "DENY"
        response.headers["Referrer-Policy"] = "no-referrer"
        return response

    @server.before_request
    def _check_callback():
        if flask.request.path != path or flask.request.method != "POST":
            return None
        try:
            check(app, parse_json(flask.request))
        except RequestRefused as exc:
            return exc.response()
        return None

    @server.errorhandler(Exception)
    def _unexpected(exc: Exception):
        if isinstance(exc, HTTPException):
            return exc
        if isinstance(exc, Busy):  # a limit of the admission control that a page did not catch itself
            return error(str(exc), exc.field, exc.allowed, 429, exc.headers())
        if flask.request.path == path:
            log.warning("callback refused its inputs: %s", exc, exc_info=exc)
            return BadCallback(f"the callback could not use the values sent ({type(exc).__name__}: {exc})"[:400],
                               "inputs", "the values the page's own controls produce").response()
        log.error("unexpected error on %s", flask.request.path, exc_info=exc)
        return flask.Response(json.dumps({"error": "internal error", "field": None, "allowed": None}), 500,
                              mimetype="application/json")


def check(app, body: Any) -> None:
    """Raise :class:`BadCallback` naming the first part of ``body`` that Dash could not use."""
    if not isinstance(body, dict):
        raise BadCallback("a callback request is a JSON object", "body", "a JSON object")
    output = body.get("output")
    if not isinstance(output, str) or "callback" not in app.callback_map.get(output, {}):  # clientside: none
        raise BadCallback(f"output={_short(output)} is not a callback of this app", "output",
                          "the output key of a registered callback")
    callback = app.callback_map[output]
    for key in ("inputs", "state"):
        declared = callback.get(key, [])
        given = body.get(key, [])
        if not isinstance(given, list) or len(given) != len(declared):
            raise BadCallback(f"{key} must list the {len(declared)} declared values", key,
                              f"a list of {len(declared)} {{id, property, value}} objects")
        for k, (want, item) in enumerate(zip(declared, given, strict=True)):
            _check_item(f"{key}[{k}]", want, item)
    outputs = body.get("outputs", [])
    for k, item in enumerate(outputs if isinstance(outputs, list) else [outputs]):
        for part in item if isinstance(item, list) else [item]:
            if not isinstance(part, dict) or not isinstance(part.get("property"), str) or "id" not in part:
                raise BadCallback(f"outputs[{k}] is not an {{id, property}} object", f"outputs[{k}]",
                                  "an {id, property} object")
    changed = body.get("changedPropIds", [])
    if not isinstance(changed, list) or not all(isinstance(c, str) for c in changed):
        raise BadCallback("changedPropIds must be a list of strings", "changedPropIds", "a list of 'id.property'")


def _check_item(field: str, declared: dict[str, Any], item: Any) -> None:
    pattern = declared["id"].startswith("{")
    parts = item if pattern and isinstance(item, list) else [item]
    if len(parts) > 1000:
        raise BadCallback(f"{field} lists {len(parts)} components", field, "at most 1000")
    for part in parts:
        if not isinstance(part, dict) or part.get("property") != declared["property"]:
            raise BadCallback(f"{field} is not the declared {declared['id']}.{declared['property']}", field,
                              f"an object with id {declared['id']} and property {declared['property']}")
        if pattern:
            if not isinstance(part.get("id"), dict):
                raise BadCallback(f"{field}.id is not a pattern-matching id", f"{field}.id", "an object id")
        elif part.get("id") != declared["id"]:
            raise BadCallback(f"{field}.id={_short(part.get('id'))} is not the declared {declared['id']}",
                              f"{field}.id", declared["id"])


def _short(value: Any) -> str:
    import reprlib

    return reprlib.repr(value)
