"""The page shell: navigation, the design panel (always at hand) and the URL <-> design sync."""

from __future__ import annotations

import json

import dash
from dash import ALL, Input, Output, State, dcc, html

from shimmy.model.parameters import MATERIALS, PARAMETER_SPECS

from . import state

#: The design parameters with sliders (PRODUCT.md); every other one is in the advanced panel.
DESIGN = ("r2", "e_p", "k_s", "r3", "a_p", "rho_p")
ADVANCED = tuple(n for n in PARAMETER_SPECS if n not in DESIGN)
SLIDER_STEPS = 200


def _label(name: str) -> html.Label:
    spec = PARAMETER_SPECS[name]
    unit = f" ({spec.unit})" if spec.unit else ""
    return html.Label([html.Span(name, className="param-name"), html.Span(unit, className="param-unit")],
                      title=f"{spec.description}; {spec.allowed}; {spec.provenance}", htmlFor=f"param-{name}")


def _short(x: float) -> str:
    """1.4e+06 -> 1.4e6: slider end labels that fit the panel."""
    return f"{x:g}".replace("e+0", "e").replace("e-0", "e-").replace("e+", "e")


def _slider(name: str, value: float) -> html.Div:
    spec = PARAMETER_SPECS[name]
    return html.Div([
        _label(name),
        dcc.Slider(id={"type": "param", "name": name}, min=spec.low, max=spec.high,
                   step=(spec.high - spec.low) / SLIDER_STEPS, value=value, updatemode="drag",
                   marks={spec.low: _short(spec.low), spec.high: _short(spec.high)},
                   tooltip={"placement": "bottom", "always_visible": False}),
    ], className="slider-row")


def _number(name: str, value: float) -> html.Div:
    spec = PARAMETER_SPECS[name]
    return html.Div([
        _label(name),
        dcc.Input(id={"type": "param", "name": name}, type="number", value=value, min=spec.low, max=spec.high,
                  step="any", debounce=True, className="number-input"),
    ], className="number-row")


def design_id(page_id: str) -> dict[str, str]:
    """Id of a page's design store. Each page has its own so that its callbacks' inputs all live
    on that page (a callback with an input missing from the layout is an error in the browser)."""
    return {"type": "design", "page": page_id}


def design_panel(query: dict[str, str], page_id: str) -> html.Aside:
    material, values, problems = state.design_from_query(query)
    return html.Aside([
        dcc.Store(id=design_id(page_id), data=state.design_request(material, values)),
        dcc.Store(id="url-update"), html.Div(id="url-sink", hidden=True),
        html.H2("Design"),
        html.Div([html.Label("PD material", htmlFor="material"),
                  dcc.Dropdown(id="material", options=[{"label": m, "value": m} for m in MATERIALS],
                               value=material, clearable=False)], className="slider-row"),
        *[_slider(n, values[n]) for n in DESIGN],
        html.Details([html.Summary("Advanced parameters"),
                      html.Div([_number(n, values[n]) for n in ADVANCED], className="advanced-grid")],
                     id="advanced"),
        html.Div("; ".join(problems), id="design-error", className="error", role="alert"),
        html.Button("Reset design", id="reset-design", className="secondary"),
    ], className="design-panel", id="design-panel")


def page(query: dict[str, str], page_id: str, *children) -> html.Div:
    """A page: the design panel (always at hand, initialised from the URL) beside the content.

    Every page carries its own panel so that page callbacks reading the design never meet a
    layout without their inputs (Dash reports such callbacks as errors in the browser).
    """
    return html.Div([design_panel(query, page_id), html.Main(list(children), className="page")], className="body")


def navigation() -> html.Nav:
    # Plain links: their href is kept carrying the design by the clientside URL updater below.
    links = [html.A(p["name"], href=p["relative_path"], className="nav-link")
             for p in dash.page_registry.values()]
    return html.Nav([html.Span("shimmy", className="brand"), html.Span("workbench", className="brand-sub"), *links],
                    className="navbar")


def shell() -> html.Div:
    return html.Div([navigation(), dash.page_container])


# The address bar carries the design and the page state. Callbacks send partial updates
# {key: value, or null to drop it} to the page's "url-update" store; this merges them into
# the current query with history.replaceState (no navigation, no page re-render) and keeps
# the navigation links carrying the design keys.
dash.clientside_callback(
    """
    function(update) {
        if (!update) { return window.dash_clientside.no_update; }
        const params = new URLSearchParams(window.location.search);
        for (const [k, v] of Object.entries(update)) {
            if (v === null || v === undefined || v === "") { params.delete(k); } else { params.set(k, String(v)); }
        }
        const s = params.toString();
        window.history.replaceState(window.history.state, "", window.location.pathname + (s ? "?" + s : ""));
        const design = new URLSearchParams();
        const keys = %s;
        for (const [k, v] of params.entries()) { if (keys.includes(k)) { design.set(k, v); } }
        const d = design.toString();
        document.querySelectorAll("a.nav-link").forEach(a => {
            a.href = a.getAttribute("href").split("?")[0] + (d ? "?" + d : "");
        });
        return s;
    }
    """ % json.dumps([*PARAMETER_SPECS, "material"]),
    Output("url-sink", "children"),
    Input("url-update", "data"),
)


# Controls -> the design store, the URL and the error line, in the browser (no server round trip
# before the page's own callbacks run: a slider move reaches the figure one request sooner).
# Ranges and presets come from the parameter definitions; the server validates again.
dash.clientside_callback(
    """
    function(values, material, reset, ids) {
        const C = window.dash_clientside, trig = C.callback_context.triggered_id;
        const SPEC = %(spec)s, PRESET = %(preset)s, BASE = %(base)s, DEFAULT = %(default)s;
        const names = ids.map(i => i.name);
        let cur = {};
        names.forEach((n, i) => { cur[n] = values[i]; });
        let outValues = names.map(() => C.no_update), outMaterial = C.no_update;
        if (trig === "reset-design") {
            material = DEFAULT; cur = Object.assign({}, BASE[DEFAULT]); outMaterial = DEFAULT;
            outValues = names.map(n => cur[n]);
        } else if (trig === "material") {
            Object.assign(cur, PRESET[material]); outValues = names.map(n => cur[n]);
        }
        const base = BASE[material], full = Object.assign({}, base), problems = [];
        for (const n of names) {
            const v = cur[n], s = SPEC[n];
            const ok = typeof v === "number" && isFinite(v) && v >= s.low && v <= s.high
                       && (!s.integer || Number.isInteger(v));
            if (ok) { full[n] = v; } else {
                problems.push(n + "=" + v + " is out of range; allowed: " + s.allowed + " (kept " + base[n] + ")");
            }
        }
        const params = {}, url = {};
        for (const n in SPEC) { url[n] = null; }
        for (const n in full) {
            if (Math.abs(full[n] - base[n]) > 1e-12 * Math.max(1, Math.abs(base[n]))) {
                params[n] = full[n]; url[n] = String(full[n]);
            }
        }
        url.material = material === DEFAULT ? null : material;
        return [outValues, outMaterial, url, [{material: material, params: params}], problems.join("; ")];
    }
    """ % {"spec": json.dumps({n: {"low": s.low, "high": s.high, "integer": s.integer, "allowed": s.allowed}
                               for n, s in PARAMETER_SPECS.items()}),
           "preset": json.dumps(MATERIALS),
           "base": json.dumps({m: state.material_params(m) for m in MATERIALS}),
           "default": json.dumps(state.DEFAULT_MATERIAL)},
    Output({"type": "param", "name": ALL}, "value"),
    Output("material", "value"),
    Output("url-update", "data", allow_duplicate=True),
    Output({"type": "design", "page": ALL}, "data"),
    Output("design-error", "children"),
    Input({"type": "param", "name": ALL}, "value"),
    Input("material", "value"),
    Input("reset-design", "n_clicks"),
    State({"type": "param", "name": ALL}, "id"),
    prevent_initial_call=True,
)
