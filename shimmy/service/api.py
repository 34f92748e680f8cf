"""HTTP API under /api/v1 (a Flask blueprint mounted on the Dash app's server).

JSON in and out; errors as {"error", "field", "allowed"} with a 4xx status. The OpenAPI
document is generated from the request schemas (:mod:`shimmy.service.schemas`).
"""

from __future__ import annotations

import json
import math
import time
from typing import Any

from flask import Blueprint, Response, request

from .. import __version__
from ..continuation import errors as engine_errors
from ..errors import ConvergenceError, GeometryError, InvalidParameterError, ShimmyError
from ..model.parameters import PARAMETER_SPECS
from . import analyses, jobs, schemas, settings

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


def error(message: str, field: str | None, allowed: str | None, status: int = 400) -> Response:
    return _json({"error": message, "field": field, "allowed": allowed}, status)


def _body() -> Any:
    length = request.content_length
    if length is not None and length > settings.MAX_BODY_BYTES:
        raise _TooLarge()
    raw = request.get_data(cache=False)
    if len(raw) > settings.MAX_BODY_BYTES:
        raise _TooLarge()
    if not raw.strip():
        raise InvalidParameterError("body", "", "a JSON object", "is empty")
    try:
        return json.loads(raw)  # NaN/Infinity parse to floats and are refused by the field they are in
    except ValueError as exc:
        raise InvalidParameterError("body", raw[:80].decode("utf-8", "replace"), "a JSON object",
                                    f"is not valid JSON ({exc})") from None


class _TooLarge(Exception):
    pass


@api.errorhandler(InvalidParameterError)  # listed with the engine's class: Flask follows the MRO,
@api.errorhandler(engine_errors.InvalidInputError)  # where ShimmyError comes before the engine's class
def _invalid(exc: engine_errors.InvalidInputError):
    return _json(exc.to_dict(), 422 if exc.field != "body" else 400)


@api.errorhandler(GeometryError)
def _geometry(exc: GeometryError):
    return error(str(exc), "params", "a design whose NES roller stays on its track", 422)


@api.errorhandler(_TooLarge)
def _too_large(exc):
    return error(f"request body above the limit of {settings.MAX_BODY_BYTES} bytes", "body",
                 f"at most {settings.MAX_BODY_BYTES} bytes", 413)


@api.errorhandler(ConvergenceError)
@api.errorhandler(engine_errors.ConvergenceError)
def _convergence(exc: engine_errors.ConvergenceError):
    return error(f"the solver did not converge: {exc}", None, None, 422)


@api.errorhandler(ShimmyError)
@api.errorhandler(engine_errors.ContinuationError)
def _shimmy(exc: Exception):
    return error(str(exc), None, None, 422)


@api.route("/<path:anything>", methods=["GET", "POST", "PUT", "PATCH", "DELETE"])
def _unmatched(anything: str):
    """Everything under /api/v1 that no endpoint takes: 405 for a known path, else 404 (JSON)."""
    methods = sorted(m for m in _METHODS.get("/" + anything, ()) if m not in ("HEAD", "OPTIONS"))
    if methods:
        return error(f"method {request.method} not allowed on {request.path}", "method", ", ".join(methods), 405)
    return error(f"no such endpoint: {request.method} {request.path}", "path", f"see {PREFIX}/openapi.json", 404)


@api.get("/health")
def health():
    return _json({"status": "ok", "version": __version__, "time": time.time()})


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


@api.post("/jobs")
def submit_job():
    body = _body()
    if not isinstance(body, dict):
        raise InvalidParameterError("body", type(body).__name__, "a JSON object", "is not a JSON object")
    if "analysis" not in body:
        raise InvalidParameterError("analysis", None, "one of " + ", ".join(schemas.JOB_ANALYSES), "is required")
    analysis = body["analysis"]
    if not isinstance(analysis, str):
        raise InvalidParameterError("analysis", analysis, "one of " + ", ".join(schemas.JOB_ANALYSES),
                                    "is not a string")
    job = jobs.submit(analysis, body)
    return _json(jobs.public(job, with_result=False), 202, headers={"Location": f"{PREFIX}/jobs/{job['id']}"})


def _job_or_404(job_id: str):
    job = jobs.get(job_id)
    if job is None:
        return None, error(f"no job {job_id!r}", "id", "an id returned by POST /api/v1/jobs", 404)
    return job, None


@api.get("/jobs/<job_id>")
def get_job(job_id: str):
    job, missing = _job_or_404(job_id)
    return missing or _json(jobs.public(job))


@api.delete("/jobs/<job_id>")
def cancel_job(job_id: str):
    job, missing = _job_or_404(job_id)
    if missing:
        return missing
    return _json(jobs.public(jobs.cancel(job_id), with_result=False))


_METHODS = {"/health": ("GET",), "/parameters": ("GET",), "/simulate": ("POST",), "/hopf": ("POST",),
            "/stability": ("POST",), "/devices": ("POST",), "/jobs": ("POST",), "/openapi.json": ("GET",)}


@api.get("/openapi.json")
def openapi():
    return _json(openapi_document())


def openapi_document() -> dict[str, Any]:
    err = {"description": "bad input",
           "content": {"application/json": {"schema": {"$ref": "#/components/schemas/Error"}}}}
    comps: dict[str, Any] = {"Error": {"type": "object", "required": ["error", "field", "allowed"], "properties": {
        "error": {"type": "string"}, "field": {"type": ["string", "null"]}, "allowed": {"type": ["string", "null"]}}},
        "Job": {"type": "object", "properties": {
            "id": {"type": "string"}, "analysis": {"type": "string", "enum": list(schemas.JOB_ANALYSES)},
            "status": {"type": "string", "enum": ["queued", "running", "done", "failed", "cancelled"]},
            "progress": {"type": "number", "minimum": 0, "maximum": 1}, "message": {"type": "string"},
            "error": {"type": ["string", "null"]}, "request": {"type": "object"}, "result": {"type": "object"}}}}
    paths: dict[str, Any] = {
        "/health": {"get": {"summary": "liveness", "responses": {"200": {"description": "ok"}}}},
        "/parameters": {"get": {"summary": "every parameter with unit, default, range and provenance",
                                "responses": {"200": {"description": "the parameter table"}}}},
    }
    for name in ("simulate", "hopf", "stability", "devices"):
        s = schemas.SCHEMAS[name]
        comps[f"{name}_request"] = s.openapi()
        paths[f"/{name}"] = {"post": {
            "summary": s.summary, "requestBody": {"required": True, "content": {"application/json": {
                "schema": {"$ref": f"#/components/schemas/{name}_request"}}}},
            "responses": {"200": {"description": "the result (X-Shimmy-Cache: hit|miss)"}, "400": err, "413": err,
                          "422": err}}}
    job_bodies = []
    for name in schemas.JOB_ANALYSES:
        s = schemas.SCHEMAS[name]
        body = s.openapi()
        body["properties"] = {"analysis": {"type": "string", "enum": [name]}, **body["properties"]}
        body["required"] = ["analysis", *body["required"]]
        comps[f"job_{name}"] = body
        job_bodies.append({"$ref": f"#/components/schemas/job_{name}"})
    paths["/jobs"] = {"post": {
        "summary": "start a long analysis (" + ", ".join(schemas.JOB_ANALYSES) + ")",
        "requestBody": {"required": True, "content": {"application/json": {"schema": {"oneOf": job_bodies}}}},
        "responses": {"202": {"description": "accepted", "content": {"application/json": {
            "schema": {"$ref": "#/components/schemas/Job"}}}}, "400": err, "413": err, "422": err}}}
    paths["/jobs/{id}"] = {
        "parameters": [{"name": "id", "in": "path", "required": True, "schema": {"type": "string"}}],
        "get": {"summary": "status, progress and (when done) the result", "responses": {
            "200": {"description": "the job", "content": {"application/json": {
                "schema": {"$ref": "#/components/schemas/Job"}}}}, "404": err}},
        "delete": {"summary": "cancel", "responses": {"200": {"description": "the cancelled job"}, "404": err}}}
    return {"openapi": "3.1.0",
            "info": {"title": "shimmy API", "version": __version__,
                     "description": "Nose-landing-gear shimmy with a torsional NES and a particle damper. Limits: "
                                    f"body <= {settings.MAX_BODY_BYTES} bytes, t_end <= {settings.MAX_T_END:g} s, "
                                    f"ntst <= {settings.MAX_NTST}."},
            "servers": [{"url": PREFIX}], "paths": paths, "components": {"schemas": comps}}
