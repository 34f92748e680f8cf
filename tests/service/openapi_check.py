"""Checks of answers against the OpenAPI document's schemas: JSON Schema validation (jsonschema,
the 2020-12 dialect of OpenAPI 3.1) and a walk that names every key an answer has but the schema
does not declare (a response schema that lags behind the code fails here)."""

from __future__ import annotations

import json
from typing import Any

import jsonschema
from referencing import Registry
from referencing.jsonschema import DRAFT202012

DOCUMENT_URI = "urn:shimmy-openapi"


def validator(document: dict[str, Any], schema: dict[str, Any]) -> jsonschema.Draft202012Validator:
    """A validator of ``schema`` whose ``#/components/schemas/...`` references resolve in ``document``."""
    registry = Registry().with_resource(DOCUMENT_URI, DRAFT202012.create_resource(document))
    text = json.dumps(schema).replace('"#/components/', f'"{DOCUMENT_URI}#/components/')
    return jsonschema.Draft202012Validator(json.loads(text), registry=registry)


def errors(document: dict[str, Any], schema: dict[str, Any], value: Any) -> list[str]:
    """Every way ``value`` breaks ``schema``, each as 'path: message'."""
    return [f"{'/'.join(map(str, e.absolute_path))}: {e.message[:200]}"
            for e in validator(document, schema).iter_errors(value)]


def _resolve(document: dict[str, Any], schema: dict[str, Any]) -> dict[str, Any]:
    while "$ref" in schema:
        target: Any = document
        for part in schema["$ref"].removeprefix("#/").split("/"):
            target = target[part]
        schema = target
    return schema


def undeclared(document: dict[str, Any], schema: dict[str, Any], value: Any, where: str = "") -> list[str]:
    """Paths of object keys in ``value`` that ``schema`` does not declare (objects with ``properties``
    and no ``additionalProperties`` are closed for this check; ``anyOf`` branches are tried in turn)."""
    schema = _resolve(document, schema)
    if "anyOf" in schema:
        return min((undeclared(document, s, value, where) for s in schema["anyOf"]), key=len)
    out: list[str] = []
    if isinstance(value, dict):
        props = schema.get("properties")
        extra = schema.get("additionalProperties")
        for key, item in value.items():
            if props is not None and key in props:
                out += undeclared(document, props[key], item, f"{where}.{key}")
            elif isinstance(extra, dict):
                out += undeclared(document, extra, item, f"{where}.{key}")
            elif props is not None and extra is None:
                out.append(f"{where}.{key}")
    elif isinstance(value, list) and isinstance(schema.get("items"), dict):
        for k, item in enumerate(value):
            out += undeclared(document, schema["items"], item, f"{where}[{k}]")
    return out
