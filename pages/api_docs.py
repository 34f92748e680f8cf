"""API: the HTTP endpoints, their request fields (from the same schemas that validate them) and examples."""

from __future__ import annotations

import json

import dash
from dash import html

from shimmy.service import schemas, settings
from shimmy.service.api import JOB_ANALYSES, PREFIX, SYNC_ANALYSES, openapi_document
from ui import components as ui
from ui import ids
from ui.layout import page

dash.register_page(__name__, path="/api", name="API", order=7)

EXAMPLES = {
    "simulate": {"config": "nes_pd", "V": 30, "Fz": 150000, "params": {"r2": 0.085}},
    "hopf": {"config": "nes", "Fz": 150000, "v_min": 1, "v_max": 200},
    "stability": {"Fz": 150000, "v_max": 200, "material": "tungsten"},
    "devices": {"params": {"e_p": 0.002}},
    "sensitivity": {"config": "nes", "Fz": 150000, "names": ["r2", "e_p", "k_s", "r3"]},
    "jobs": {"analysis": "bifurcation", "config": "original", "Fz": 150000, "v_min": 1, "v_max": 200},
    "optimise": {"analysis": "optimise", "config": "nes", "objective": "min_shimmy_Fz", "parameters": ["e_p", "k_s"],
                 "constraints": ["max_psi<=0.2"]},
    "robustness": {"analysis": "robustness", "config": "nes", "tolerances": ["k_lam=0.05", "k_s=0.05:uniform"],
                   "samples": 128},
}


def _fields(name: str) -> html.Table:
    rows = [[f.name, f.kind, "yes" if f.required else "no", "–" if f.default in (None, {}) else json.dumps(f.default),
             f.allowed, f.description] for f in schemas.SCHEMAS[name].fields]
    return ui.table(["field", "type", "required", "default", "allowed", "meaning"], rows)


def _curl(path: str, body: dict) -> html.Pre:
    return html.Pre(f"curl -s -X POST http://HOST{PREFIX}{path} -H 'Content-Type: application/json' \\\n"
                    f"     -d '{json.dumps(body)}'")


def layout(**query):
    doc = openapi_document()
    endpoint_rows = [[method.upper(), PREFIX + path, op.get("summary", "")]
                     for path, item in doc["paths"].items() for method, op in item.items() if method != "parameters"]
    sections = [ui.header("HTTP API", f"JSON over HTTP under {PREFIX}, described by the OpenAPI document at "
                          f"{PREFIX}/openapi.json (generated from the request schemas below). Every bad input gets "
                          "a 4xx answer {\"error\", \"field\", \"allowed\"} naming the field; long analyses run as "
                          "jobs. A server that asks for tokens (SHIMMY_AUTH=token) takes every request but health with "
                          "Authorization: Bearer TOKEN (python -m shimmy tokens create --user NAME --scope compute); "
                          "401 without a good one, 429 with Retry-After beyond a limit."),
                ui.table(["method", "path", "what"], endpoint_rows, ids.API_ENDPOINTS),
                html.P([html.A("openapi.json", href=f"{PREFIX}/openapi.json"), " · limits: body at most "
                        f"{settings.MAX_BODY_BYTES} bytes, t_end at most {settings.MAX_T_END:g} s, ntst at most "
                        f"{settings.MAX_NTST}, at most "
                        f"{settings.MAX_RUNNING_JOBS} jobs running at once (others queue)."], className="hint")]
    for name in SYNC_ANALYSES:
        sections += [html.H2(f"POST {PREFIX}/{name}"), html.P(schemas.SCHEMAS[name].summary), _fields(name),
                     _curl(f"/{name}", EXAMPLES[name])]
    sections += [html.H2(f"POST {PREFIX}/jobs"),
                 html.P("Body: {\"analysis\": " + " | ".join(f'"{a}"' for a in JOB_ANALYSES) + ", ...the "
                        "analysis' fields}. Answers 202 with the job; poll GET /jobs/{id} (status queued, running, "
                        "done, failed or cancelled; progress 0-1; the result when done); DELETE /jobs/{id} "
                        "cancels. A finished result is cached: the same request is done at once."),
                 _curl("/jobs", EXAMPLES["jobs"])]
    for name in JOB_ANALYSES:
        if name not in SYNC_ANALYSES:
            sections += [html.H2(f"job analysis \"{name}\""), html.P(schemas.SCHEMAS[name].summary), _fields(name)]
            if name in EXAMPLES:
                sections.append(_curl("/jobs", EXAMPLES[name]))
    sections += [html.H2("Errors"),
                 html.Pre(json.dumps({"error": "V=600 is out of range; allowed: a number in [1, 500] m/s",
                                      "field": "V", "allowed": "a number in [1, 500] m/s"}, indent=1)),
                 html.P("400 malformed body, 404 unknown endpoint or job, 405 wrong method, 413 body too large, "
                        "422 a field out of its range, of the wrong type, missing, NaN/inf, an unknown parameter or "
                        "configuration, or a solver that did not converge.", className="hint")]
    return page(query, ids.API, *sections, design=False)
