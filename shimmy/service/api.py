"""HTTP API under /api/v1 (a Flask blueprint mounted on the Dash app's server).

JSON in and out; errors as {"error", "field", "allowed"} with a 4xx status. The OpenAPI
document is generated from the request schemas (:mod:`shimmy.service.schemas`).

Every request but ``GET /health`` is checked (:mod:`shimmy.service.auth`): with ``SHIMMY_AUTH=token``
it needs ``Authorization: Bearer TOKEN`` (or a workbench session) of the scope the request needs
(read: GET; compute: the analyses, submitting and deleting one's jobs; admin: every user's jobs),
else 401 (no or a bad credential) or 403 (a scope too small). A limit of the admission control
(:mod:`shimmy.service.admission`, the job queue's shares) answers 429 with ``Retry-After`` and
``X-Shimmy-Limit`` naming the limit.
"""

from __future__ import annotations

import json
import math
import reprlib
import time
from typing import Any

from flask import Blueprint, Response, request
from werkzeug.exceptions import HTTPException

from ..version import __version__
from ..continuation import errors as engine_errors
from ..errors import ConvergenceError, GeometryError, InvalidParameterError, ShimmyError
from ..model.parameters import PARAMETER_SPECS, unknown_name_error
from . import admission, analyses, auth, cache, jobs, result_schemas, schemas, settings
from .request_fields import field_key
from .analyses import JOB_ANALYSES, SYNC_ANALYSES

PREFIX = "/api/v1"
api = Blueprint("api", __name__, url_prefix=PREFIX)


def _json(payload: Any, status: int = 200, headers: dict[str, str] | None = None) -> Response:
    body = json.dumps(_clean(payload), allow_nan=False, separators=(",", ":"))
    return Response(body, status=status, mimetype="application/json", headers=headers)


def _clean(x):
    """NaN/inf -> null, numpy scalars -> Python (JSON has no NaN)."""
    if isinstance(x, dict):
        return {k: _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if hasattr(x, "item") and not isinstance(x, (str, bytes)):
        return _clean(x.item())
    return x


def error(message: str, field: str | None, allowed: str | None, status: int = 400,
          headers: dict[str, str] | None = None) -> Response:
    return _json({"error": message, "field": field, "allowed": allowed}, status, headers)


class RequestRefused(Exception):
    """A request refused before any analysis sees it (transport, size, media type, JSON syntax)."""

    status = 400

    def __init__(self, message: str, field: str | None, allowed: str | None, status: int | None = None,
                 headers: dict[str, str] | None = None):
        super().__init__(message)
        self.field, self.allowed, self.headers = field, allowed, headers or {}
        if status is not None:
            self.status = status

    def response(self) -> Response:
        return error(str(self), self.field, self.allowed, self.status, self.headers)


def _parse_int(text: str):
    # A JSON integer too long for a float becomes inf, which every number field refuses by name
    # (float() of the int would raise OverflowError; int() of > 4300 digits raises ValueError).
    return int(text) if len(text) <= 18 else float(text)


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """A JSON object whose keys are all different (a key given twice is refused: which value was meant?)."""
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise RequestRefused(f"body gives {field_key(key)} twice ({reprlib.repr(out[key])} and "
                                 f"{reprlib.repr(value)}); allowed: each key once", field_key(key), "each key once")
        out[key] = value
    return out


def parse_json(req) -> Any:
    """The JSON body of ``req``: application/json only, at most MAX_BODY_BYTES, read within
    BODY_READ_SECONDS, nested at most as deep as the parser allows; RequestRefused otherwise."""
    mimetype = (req.mimetype or "").lower()
    if mimetype != "application/json":
        raise RequestRefused(f"Content-Type {req.content_type or '(none)'!r} is not accepted", "Content-Type",
                             "application/json", 415)
    length = req.content_length
    if length is not None and length > settings.MAX_BODY_BYTES:
        raise _too_large()
    sock = req.environ.get("gunicorn.socket")
    try:
        if sock is not None:  # a body announced longer than sent ends in a bounded time, not at the worker timeout
            sock.settimeout(settings.BODY_READ_SECONDS)
        raw = req.get_data(cache=True)
    except (OSError, HTTPException) as exc:
        if isinstance(exc, HTTPException) and exc.code == 413:
            raise _too_large() from None
        raise RequestRefused(f"the request body did not arrive complete within {settings.BODY_READ_SECONDS:g} s "
                             f"({type(exc).__name__})", "body", f"Content-Length bytes within "
                             f"{settings.BODY_READ_SECONDS:g} s", 408, {"Connection": "close"}) from None
    finally:
        if sock is not None:
            try:
                sock.settimeout(None)
            except OSError:
                pass
    if len(raw) > settings.MAX_BODY_BYTES:
        raise _too_large()
    if not raw.strip():
        raise RequestRefused("body is empty; allowed: a JSON object", "body", "a JSON object")
    try:
        # NaN/Infinity parse to floats and are refused by the field they are in
        return json.loads(raw, parse_int=_parse_int, object_pairs_hook=_unique_keys)
    except RecursionError:
        raise RequestRefused("body is nested too deeply", "body", "a JSON object nested at most a few hundred "
                             "levels") from None
    except ValueError as exc:
        raise RequestRefused(f"body={reprlib.repr(raw[:80].decode('utf-8', 'replace'))} is not valid JSON ({exc})",
                             "body", "a JSON object") from None


def _too_large() -> RequestRefused:
    return RequestRefused(f"request body above the limit of {settings.MAX_BODY_BYTES} bytes", "body",
                          f"at most {settings.MAX_BODY_BYTES} bytes", 413)


def _body() -> Any:
    return parse_json(request)


@api.errorhandler(RequestRefused)
def _refused(exc: RequestRefused):
    return exc.response()


@api.errorhandler(admission.Busy)
def _busy(exc: admission.Busy):
    return error(str(exc), exc.field, exc.allowed, 429, exc.headers())


@api.errorhandler(InvalidParameterError)  # listed with the engine's class: Flask follows the MRO,
@api.errorhandler(engine_errors.InvalidInputError)  # where ShimmyError comes before the engine's class
def _invalid(exc: engine_errors.InvalidInputError):
    message = str(exc)
    if len(message) > 600:  # a huge value is named, not echoed back whole
        message = f"{exc.field}={reprlib.repr(exc.value)} is refused; allowed: {exc.allowed}"
    return error(message, exc.field, exc.allowed, 400 if exc.field == "body" else 422)


@api.errorhandler(GeometryError)
def _geometry(exc: GeometryError):
    return error(str(exc), "params", "a design whose NES roller stays on its track", 422)


@api.errorhandler(ConvergenceError)
@api.errorhandler(engine_errors.ConvergenceError)
def _convergence(exc: engine_errors.ConvergenceError):
    return error(f"the solver did not converge: {exc}", None, None, 422)


@api.errorhandler(ShimmyError)
@api.errorhandler(engine_errors.ContinuationError)
def _shimmy(exc: Exception):
    return error(str(exc), None, None, 422)


@api.route("", defaults={"anything": ""}, methods=["GET", "POST", "PUT", "PATCH", "DELETE"])
@api.route("/", defaults={"anything": ""}, methods=["GET", "POST", "PUT", "PATCH", "DELETE"])
@api.route("/<path:anything>", methods=["GET", "POST", "PUT", "PATCH", "DELETE"])
def _unmatched(anything: str):
    """Everything under /api/v1 that no endpoint takes: 405 for a known path, else 404 (JSON)."""
    methods = _methods_of(anything)
    if methods:
        return error(f"method {request.method} not allowed on {request.path}", "method", ", ".join(methods), 405,
                     {"Allow": ", ".join(methods)})
    return error(f"no such endpoint: {request.method} {request.path}", "path", f"see {PREFIX}/openapi.json", 404)


def _methods_of(subpath: str) -> list[str]:
    """The documented methods of PREFIX/``subpath`` (empty for an unknown path)."""
    route = "/jobs/{id}" if subpath.startswith("jobs/") and subpath.count("/") == 1 else "/" + subpath
    return sorted(_METHODS.get(route, ()))


def needed_scope(method: str, subpath: str) -> str | None:
    """The scope a request needs (None: open to all): health is open; GET /jobs (every user's jobs) is
    admin; other reads are read; everything else (the analyses, submitting and deleting jobs) compute."""
    if subpath == "health":
        return None
    if method in ("GET", "HEAD", "OPTIONS"):
        return "admin" if subpath.rstrip("/") == "jobs" else "read"
    return "compute"


@api.before_request
def _authenticate():
    """Every request but health needs a credential of the scope it needs (401 / 403 otherwise)."""
    scope = needed_scope(request.method, request.path.removeprefix(PREFIX + "/"))
    if scope is None:
        return None
    outcome = auth.authorise(request, scope)
    if isinstance(outcome, auth.Principal):
        return None
    status, message = outcome
    return error(message, "Authorization", "Authorization: Bearer TOKEN (a token of scope "
                 f"{scope}{'' if scope == 'admin' else ' or above'})", status,
                 auth.challenge_headers() if status == 401 else {"Cache-Control": "no-store"})


def _user() -> str | None:
    """Who asks, when the server knows its users (None: SHIMMY_AUTH=none, one anonymous user)."""
    principal = auth.current()
    return principal.user if principal.identified else None


@api.before_request
def _options():
    """OPTIONS lists exactly the documented methods (Flask's own answer would add the catch-all's)."""
    if request.method != "OPTIONS":
        return None
    methods = _methods_of(request.path.removeprefix(PREFIX + "/"))
    if not methods:
        return error(f"no such endpoint: {request.path}", "path", f"see {PREFIX}/openapi.json", 404)
    return Response(status=204, headers={"Allow": ", ".join([*methods, "OPTIONS"])})


#: The endpoints a query string reaches: GET /jobs reads its own; health ignores one; no endpoint (404/405).
_QUERY_TAKEN = frozenset(f"{api.name}.{name}" for name in ("list_jobs", "health", "_unmatched"))


@api.before_request
def _no_stray_query():
    """A query parameter is refused where the endpoint takes none (every one but GET /jobs; health, which
    probes may stamp, ignores it): an analysis reads its JSON body only, so ``POST /hopf?config=nes`` would
    otherwise answer for the body's configuration without a word."""
    if not request.args or request.method == "OPTIONS" or request.endpoint in _QUERY_TAKEN:
        return None
    key = next(iter(request.args))
    where = "the JSON body" if request.method in ("POST", "PUT", "PATCH") else "the path"
    return error(f"query parameter {reprlib.repr(key)} is not taken by {request.method} {request.path} (it "
                 f"reads {where} only)", "query parameter", "none", 422)


@api.get("/health")
def health():
    """ok (200), or degraded (503) when the cache cannot store and return a value."""
    state = cache.health()
    body = {"status": "ok" if state["ok"] else "degraded", "version": __version__, "time": time.time()}
    if not state["ok"]:
        body["cache"] = state["detail"]
    return _json(body, 200 if state["ok"] else 503)


@api.get("/parameters")
def parameters():
    return _json({"parameters": [s.to_dict() for s in PARAMETER_SPECS.values()]})


def _sync(analysis: str):
    result, cached = analyses.run(analysis, _body())
    return _json(result, headers={"X-Shimmy-Cache": "hit" if cached else "miss"})


@api.post("/simulate")
def simulate():
    return _sync("simulate")


@api.post("/hopf")
def hopf():
    return _sync("hopf")


@api.post("/stability")
def stability():
    return _sync("stability")


@api.post("/devices")
def devices():
    return _sync("devices")


@api.post("/sensitivity")
def sensitivity():
    return _sync("sensitivity")


@api.post("/jobs")
def submit_job():
    body = _body()
    if not isinstance(body, dict):
        raise InvalidParameterError("body", type(body).__name__, "a JSON object", "is not a JSON object")
    if "analysis" not in body:
        allowed = "one of " + ", ".join(JOB_ANALYSES)
        raise InvalidParameterError("analysis", None, allowed, message=f"analysis is required; allowed: {allowed}")
    analysis = body["analysis"]
    if not isinstance(analysis, str):
        raise InvalidParameterError("analysis", analysis, "one of " + ", ".join(JOB_ANALYSES),
                                    "is not a string")
    try:
        job = jobs.submit(analysis, body, user=_user())
    except jobs.QueueFull as exc:
        return error(f"analysis {analysis!r} not queued: {exc}", "analysis", exc.allowed, 429, exc.headers())
    return _json(jobs.public(job, with_result=False), 202, headers={"Location": f"{PREFIX}/jobs/{job['id']}"})


#: the query parameters of GET /jobs
LIST_QUERY = ("status", "limit", "user")


@api.get("/jobs")
def list_jobs():
    """Every job record with who asked for it, the total, the queue and the jobs per user (admin scope)."""
    for key in request.args:  # a misspelt one would leave its setting at the default without a word
        if key not in LIST_QUERY:
            raise unknown_name_error(key, LIST_QUERY, "query parameter")
        if len(request.args.getlist(key)) > 1:
            return error(f"query parameter {key!r} given {len(request.args.getlist(key))} times", key,
                         "each at most once", 422)
    status = request.args.get("status")
    statuses = ("queued", "running", "done", "failed", "cancelled")
    if status is not None and status not in statuses:
        return error(f"status={reprlib.repr(status)} is not a job status", "status", "one of " + ", ".join(statuses),
                     422)
    raw_limit = request.args.get("limit", "100")
    if not (raw_limit.isascii() and raw_limit.isdigit()) or not 1 <= int(raw_limit) <= 1000:  # "²" is a digit too
        return error(f"limit={reprlib.repr(raw_limit)} is not an integer in [1, 1000]", "limit",
                     "an integer in [1, 1000]", 422)
    user = request.args.get("user")
    return _json(jobs.listing(status, user[:64] if user else None, int(raw_limit)))


def _job_or_404(job_id: str):
    job = jobs.get(job_id)
    principal = auth.current()
    if job is None or not (principal.allows("admin") or jobs.visible_to(job, _user())):
        return None, error(f"no job {job_id!r}", "id", "an id returned by POST /api/v1/jobs", 404)
    return job, None


@api.get("/jobs/<job_id>")
def get_job(job_id: str):
    job, missing = _job_or_404(job_id)
    return missing or _json(jobs.public(job))


@api.delete("/jobs/<job_id>")
def cancel_job(job_id: str):
    """Cancel and delete the job; a job other users asked for too goes on for them (this user no longer
    sees it), unless an admin deletes it."""
    job, missing = _job_or_404(job_id)
    if missing:
        return missing
    user = _user()
    if user is not None and not auth.current().allows("admin") and set(job.get("users") or []) - {user}:
        detached = jobs.detach(job_id, user) or job
        return _json({**jobs.public(detached, with_result=False), "status": "cancelled",
                      "message": "deleted for you; other users asked for it too and it goes on for them"})
    return _json(jobs.public(jobs.cancel(job_id), with_result=False))


_METHODS = {"/health": ("GET",), "/parameters": ("GET",), **{f"/{name}": ("POST",) for name in SYNC_ANALYSES},
            "/jobs": ("GET", "POST"), "/jobs/{id}": ("GET", "DELETE"), "/openapi.json": ("GET",)}


@api.get("/openapi.json")
def openapi():
    return _json(openapi_document())


def openapi_document() -> dict[str, Any]:
    refusal = {"content": {"application/json": {"schema": {"$ref": "#/components/schemas/Error"}}}}
    bad = {  # each status's answer as the API gives it (field names the part at fault)
        "400": {**refusal, "description": "the body is not JSON, not a JSON object, or has an unknown field"},
        "408": {**refusal, "description": "the body did not arrive within the read deadline"},
        "413": {**refusal, "description": f"the body is larger than {settings.MAX_BODY_BYTES} bytes"},
        "415": {**refusal, "description": "the body is not application/json"},
        "422": {**refusal, "description": "a field is missing, of the wrong type or out of its range (field names "
                "it, allowed says what is), a rule across fields is broken, or the solver did not converge"}}
    no_job = {**refusal, "description": "no job with this id (or not one of this user's jobs)"}
    unauthorised = {**refusal, "description": "no credential, or a wrong, expired or revoked one (the same answer "
                    "whatever was wrong; field: Authorization)",
                    "headers": {"WWW-Authenticate": {"schema": {"type": "string"}}}}
    forbidden = {**refusal, "description": "the credential's scope does not allow this request"}
    busy_headers = {"Retry-After": {"description": "seconds to wait before trying again",
                                    "schema": {"type": "integer"}},
                    "X-Shimmy-Limit": {"description": "the limit that refused the request: "
                                       + ", ".join(admission.LIMITS), "schema": {"type": "string",
                                                                                  "enum": list(admission.LIMITS)}}}
    comps: dict[str, Any] = {"Error": {"type": "object", "required": ["error", "field", "allowed"], "properties": {
        "error": {"type": "string"}, "field": {"type": ["string", "null"]}, "allowed": {"type": ["string", "null"]}}},
        "Job": {"type": "object", "properties": {
            "id": {"type": "string"}, "analysis": {"type": "string", "enum": list(JOB_ANALYSES)},
            "status": {"type": "string", "enum": ["queued", "running", "done", "failed", "cancelled"]},
            "progress": {"type": "number", "minimum": 0, "maximum": 1}, "message": {"type": "string"},
            "error": {"type": ["string", "null"]}, "user": {"type": ["string", "null"]},
            "request": {"type": "object", "description": "the canonical request (defaults filled, SI units)"},
            "result": {"type": "object", "description": "when done: the analysis's result (its schema: "
                                                          "ANALYSIS_result)"}}},
        "JobList": {"type": "object", "required": ["total", "jobs", "by_user"], "properties": {
            "total": {"type": "integer", "description": "records matching the filters"},
            "records": {"type": "integer", "description": "records kept in all"},
            "jobs": {"type": "array", "items": {"$ref": "#/components/schemas/Job"}},
            "queue": {"type": "array", "items": {"type": "string"}},
            "running": {"type": "array", "items": {"type": "string"}},
            "by_user": {"type": "object", "additionalProperties": {"type": "object", "properties": {
                "queued": {"type": "integer"}, "running": {"type": "integer"}}}},
            "draining": {"type": "boolean"}, "limits": {"type": "object"}}}}

    comps.update(result_schemas.COMPONENTS)
    comps.update(Health=result_schemas.HEALTH, ParameterTable=result_schemas.PARAMETERS)

    def answer(name: str) -> dict[str, Any]:
        return {"content": {"application/json": {"schema": {"$ref": f"#/components/schemas/{name}"}}}}
    comps.update({f"{name}_result": schema for name, schema in result_schemas.RESULTS.items()})

    def guarded(responses: dict[str, Any], scope: str) -> dict[str, Any]:
        return {**responses, "401": unauthorised, "403": {**forbidden, "description": forbidden["description"]
                                                            + f" (needs {scope})"}}

    paths: dict[str, Any] = {
        "/health": {"get": {"summary": "liveness and a working cache (open: no credential, nothing about users)",
                            "security": [], "responses": {
                                "200": {"description": "ok", **answer("Health")},
                                "503": {"description": "degraded: the cache cannot store results", **answer("Health")}}}},
        "/parameters": {"get": {"summary": "every parameter with unit, default, range and provenance (scope read)",
                                "responses": guarded({"200": {"description": "the parameter table",
                                                              **answer("ParameterTable")}}, "read")}},
        "/openapi.json": {"get": {"summary": "this document (scope read)",
                                  "responses": guarded({"200": {"description": "the OpenAPI document", "content": {
                                      "application/json": {"schema": {"type": "object"}}}}}, "read")}},
    }
    for name in SYNC_ANALYSES:
        s = schemas.SCHEMAS[name]
        comps[f"{name}_request"] = s.openapi()
        paths[f"/{name}"] = {"post": {
            "summary": s.summary + " (scope compute)", "requestBody": {"required": True, "content": {
                "application/json": {"schema": {"$ref": f"#/components/schemas/{name}_request"}}}},
            "responses": guarded({
                "200": {"description": "the result (X-Shimmy-Cache: hit|miss)", "content": {"application/json": {
                    "schema": {"$ref": f"#/components/schemas/{name}_result"}}}}, **bad,
                "429": {**refusal, "description": "not computed now: the worker's computations are all busy, or "
                        "this user's share of them or rate is spent (a cached answer is never refused)",
                        "headers": busy_headers}}, "compute")}}
    job_bodies = []
    for name in JOB_ANALYSES:
        s = schemas.SCHEMAS[name]
        body = s.openapi()
        body["properties"] = {"analysis": {"type": "string", "enum": [name]}, **body["properties"]}
        body["required"] = ["analysis", *body["required"]]
        comps[f"job_{name}"] = body
        job_bodies.append({"$ref": f"#/components/schemas/job_{name}"})
    job = {"description": "the job", "content": {"application/json": {"schema": {"$ref": "#/components/schemas/Job"}}}}
    for name in JOB_ANALYSES:  # a job of each analysis, its result typed (a typed client picks it by analysis)
        comps[f"Job_{name}"] = {"allOf": [{"$ref": "#/components/schemas/Job"}, {"type": "object", "properties": {
            "analysis": {"const": name}, "result": {"$ref": f"#/components/schemas/{name}_result"}}}]}
    job_with_result = {"description": "the job; its result when done", "content": {"application/json": {"schema": {
        "oneOf": [{"$ref": f"#/components/schemas/Job_{name}"} for name in JOB_ANALYSES],
        "discriminator": {"propertyName": "analysis", "mapping": {
            name: f"#/components/schemas/Job_{name}" for name in JOB_ANALYSES}}}}}}
    paths["/jobs"] = {
        "post": {
            "summary": "start a long analysis (" + ", ".join(JOB_ANALYSES) + ") (scope compute)",
            "requestBody": {"required": True, "content": {"application/json": {"schema": {"oneOf": job_bodies}}}},
            "responses": guarded({
                "202": {**job, "description": "accepted (no result yet)"}, **bad,
                "429": {**refusal, "description": "not queued: the job queue is full, this user has "
                        "SHIMMY_MAX_JOBS_PER_USER jobs queued or running, or the last places of the queue are kept "
                        "for other users' first jobs", "headers": busy_headers}}, "compute")},
        "get": {
            "summary": "every job record with who asked for it, the total, the queue and the jobs per user "
                       "(scope admin)",
            "parameters": [{"name": "status", "in": "query", "schema": {"type": "string", "enum": [
                "queued", "running", "done", "failed", "cancelled"]}},
                {"name": "user", "in": "query", "schema": {"type": "string"}},
                {"name": "limit", "in": "query", "schema": {"type": "integer", "minimum": 1, "maximum": 1000,
                                                            "default": 100}}],
            "responses": guarded({"200": {"description": "the records", "content": {"application/json": {
                "schema": {"$ref": "#/components/schemas/JobList"}}}},
                "422": {**refusal, "description": "status or limit out of its range"}}, "admin")}}
    paths["/jobs/{id}"] = {
        "parameters": [{"name": "id", "in": "path", "required": True, "schema": {"type": "string"}}],
        "get": {"summary": "status, progress and (when done) the result (scope read; one's own jobs, any with admin)",
                "responses": guarded({"200": job_with_result, "404": no_job}, "read")},
        "delete": {"summary": "cancel the job and delete it (later reads answer 404; a job other users asked for "
                              "too goes on for them) (scope compute)",
                   "responses": guarded({"200": {**job, "description": "the job as cancelled"}, "404": no_job},
                                        "compute")}}
    comps_security = {"bearer": {"type": "http", "scheme": "bearer", "description": (
        "An API token (python -m shimmy tokens create --user NAME --scope read|compute|admin) as "
        "Authorization: Bearer TOKEN. Required when the server runs with SHIMMY_AUTH=token (the default when it "
        "listens beyond loopback); with SHIMMY_AUTH=none (the default on loopback) every request is let in.")}}
    return {"openapi": "3.1.0",
            "info": {"title": "shimmy API", "version": __version__,
                     "description": "Nose-landing-gear shimmy with a torsional NES and a particle damper. Units: every "
                                    "number of a request and of a result is in SI units (loads Fz in N, lengths and "
                                    "the lateral displacement in m, angles in rad, speeds in m/s, time in s), "
                                    "whatever the workbench shows (kN, mm). Limits: "
                                    f"body <= {settings.MAX_BODY_BYTES} bytes, t_end <= {settings.MAX_T_END:g} s, "
                                    f"ntst <= {settings.MAX_NTST}, robustness samples <= "
                                    f"{settings.MAX_ROBUSTNESS_SAMPLES}; at most {settings.MAX_RUNNING_JOBS} jobs "
                                    "run and "
                                    f"{settings.MAX_QUEUED_JOBS} wait queued (then 429 with Retry-After); an identical "
                                    "request already queued or running is that job. POST bodies: application/json. "
                                    "Authentication: a bearer token (securitySchemes.bearer) when the server asks for "
                                    "one (401 without a good one, 403 for a scope too small); per user at most "
                                    f"{settings.MAX_JOBS_PER_USER} jobs queued or running and "
                                    f"{settings.FAST_PER_USER_PER_SECOND:g} quick computations a second; at most "
                                    f"{settings.MAX_FAST_COMPUTATIONS} quick computations at once per web worker "
                                    "(429 with Retry-After and X-Shimmy-Limit beyond any limit)."},
            "servers": [{"url": PREFIX}], "security": [{"bearer": []}], "paths": paths,
            "components": {"schemas": comps, "securitySchemes": comps_security}}
