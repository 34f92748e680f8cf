"""The page shell: navigation, the design panel (always at hand) and the URL <-> design sync."""

from __future__ import annotations

import json

import dash
from dash import ALL, Input, Output, State, dcc, html

from shimmy.errors import InvalidParameterError
from shimmy.model.parameters import MATERIALS, PARAMETER_SPECS, Parameters
from shimmy.service import auth

from . import formats, ids, sessions, state

#: The design parameters with sliders (the six a device design moves); every other one is in the advanced panel.
DESIGN = ("r2", "e_p", "k_s", "r3", "a_p", "rho_p")
ADVANCED = tuple(n for n in PARAMETER_SPECS if n not in DESIGN)
assert all(PARAMETER_SPECS[n].step for n in DESIGN), "every slider's parameter has an engineering step"


def _label(name: str) -> html.Label:
    spec = PARAMETER_SPECS[name]
    unit = f" ({spec.unit})" if spec.unit else ""
    return html.Label([html.Span(name, className="param-name"), html.Span(unit, className="param-unit")],
                      title=f"{spec.description}; {spec.allowed}; {spec.provenance}", htmlFor=f"param-{name}")


def _field_error(name: str, problem: str | None) -> html.Div:
    return html.Div(problem, id=ids.param_error(name), className="error field-error", role="alert")


def _box(name: str, value: float) -> dcc.Input:
    spec = PARAMETER_SPECS[name]
    return html.Div(dcc.Input(id=ids.param_box(name), type="number", value=value, step="any",
                              debounce=True, className="param-box"), title=f"{name}: {spec.allowed}",
                    className="param-box-wrap")


def _slider(name: str, value: float, problem: str | None = None) -> html.Div:
    spec = PARAMETER_SPECS[name]
    return html.Div([
        _label(name),
        html.Div([
            # the parameter's engineering step; the tooltip shows the value without float noise
            # (assets/sliders.js), and the design keeps it rounded to the step (the sync below)
            html.Div(dcc.Slider(id=ids.param(name), min=spec.low, max=spec.high, step=spec.step, value=value,
                                updatemode="drag",
                                marks={spec.low: formats.compact(spec.low), spec.high: formats.compact(spec.high)},
                                tooltip={"placement": "bottom", "always_visible": False,
                                         "transform": "shimmyOnStep"}), className="slider-track"),
            _box(name, value),
        ], className="slider-line"),
        _field_error(name, problem),
    ], className="slider-row")


def _number(name: str, value: float, problem: str | None = None) -> html.Div:
    return html.Div([
        html.Div([_label(name),
                  html.Div(dcc.Input(id=ids.param(name), type="number", value=value, step="any",
                                     debounce=True, className="number-input"), title=PARAMETER_SPECS[name].allowed)],
                 className="number-line"),
        _field_error(name, problem),
    ], className="number-row")


def _url_problems(query: dict[str, str]) -> dict[str, str]:
    """Why a design key of the address was not applied, by field (shown at the field)."""
    out = {}
    material = query.get("material")
    if material is not None and material not in MATERIALS:
        out["material"] = (f"The address gives material={material}, which is not one of {', '.join(MATERIALS)}; "
                           f"showing {state.DEFAULT_MATERIAL}.")
    for name, raw in query.items():
        if name in PARAMETER_SPECS:
            try:
                Parameters().with_overrides({name: raw})
            except InvalidParameterError as exc:
                out[name] = f"The address gives {name}={raw}: {exc}; showing the default."
    return out


def design_panel(query: dict[str, str], page_id: str, shown: bool = True) -> html.Aside:
    material, values, problems = state.design_from_query(query)
    at_field = _url_problems(query)
    advanced_problem = any(n in at_field for n in ADVANCED)
    summary = "" if not at_field else ("Some values of the address were not applied: see the fields marked below."
                                       if shown else "; ".join(problems))
    return html.Aside([
        dcc.Store(id=ids.design_store(page_id), data=state.design_request(material, values)),
        dcc.Store(id=ids.URL_UPDATE), dcc.Store(id=ids.URL_DESIGN_UPDATE), html.Div(id=ids.URL_SINK, hidden=True),
        html.H2("Design"),
        html.Div(summary, id=ids.DESIGN_ERROR, className="error", role="alert"),
        html.Div([html.Label("PD material", htmlFor=ids.MATERIAL),
                  dcc.Dropdown(id=ids.MATERIAL, options=[{"label": m, "value": m} for m in MATERIALS],
                               value=material, clearable=False),
                  html.Div(at_field.get("material"), className="error field-error", role="alert")],
                 className="slider-row"),
        *[_slider(n, values[n], at_field.get(n)) for n in DESIGN],
        # rendered when first opened (or open already, for a refusal at one of them): ~30 boxes fewer on
        # the page while it is closed, and every slider step reaches its figure sooner (each of Dash's
        # updates runs every component's selector)
        html.Details([html.Summary("Advanced parameters", id=ids.ADVANCED_SUMMARY),
                      html.Div(advanced_boxes(values, at_field) if advanced_problem else [], id=ids.ADVANCED_GRID,
                               className="advanced-grid")],
                     id=ids.ADVANCED, open=advanced_problem),
        html.Button("Reset design", id=ids.RESET_DESIGN, className="secondary"),
        sessions.section(),
    ], className="design-panel", id=ids.DESIGN_PANEL, hidden=not shown)


def advanced_boxes(values: dict[str, float], at_field: dict[str, str] | None = None) -> list[html.Div]:
    """The advanced parameters' number boxes at ``values`` (complete), with refusals at their fields."""
    return [_number(n, values[n], (at_field or {}).get(n)) for n in ADVANCED]


@dash.callback(Output(ids.ADVANCED_GRID, "children"), Input(ids.ADVANCED_SUMMARY, "n_clicks"),
               State(ids.design_store(ALL), "data"), State(ids.param(ALL), "id"), prevent_initial_call=True)
def fill_advanced(clicks, stores, shown):
    """The advanced boxes, when their section is first opened (a click on its summary: the Details'
    ``open`` does not follow the user's toggle), at the design's values (its store)."""
    if not clicks or any(i["name"] in ADVANCED for i in shown) or not stores:
        return dash.no_update
    design = stores[0] or {}
    material = design.get("material", state.DEFAULT_MATERIAL)
    values = {**state.material_params(material if material in MATERIALS else state.DEFAULT_MATERIAL),
              **(design.get("params") or {})}
    return advanced_boxes(values)


def page(query: dict[str, str], page_id: str, *children, design: bool = True) -> html.Div:
    """A page: the design panel (always at hand, initialised from the URL) beside the content.

    Every page carries its own panel so that page callbacks reading the design never meet a
    layout without their inputs (Dash reports such callbacks as errors in the browser). A page
    that does not use the design (``design=False``) keeps the panel in its layout, hidden, so the
    design still travels with the links.
    """
    return html.Div([design_panel(query, page_id, design), html.Main(list(children), className="page")],
                    className="body" if design else "body no-design")


def navigation() -> html.Nav:
    # Plain links: their href is kept carrying the design by the clientside URL updater below.
    links = [html.A(p["name"], href=p["relative_path"], className="nav-link")
             for p in dash.page_registry.values()]
    toggle = html.Button("Design", id=ids.DESIGN_TOGGLE, className="nav-toggle",
                         title="Hide or show the design panel", **{"aria-pressed": "true"})
    # Signed in (SHIMMY_AUTH=token): a form that ends the session (a POST: no other site's link can).
    out = [html.Form(html.Button("Sign out", type="submit", className="secondary nav-signout"),
                     action=auth.LOGOUT_PATH, method="post", className="nav-signout-form")] if auth.enabled() else []
    return html.Nav([toggle, html.Span("shimmy", className="brand"), html.Span("workbench", className="brand-sub"),
                     *links, *out], className="navbar")


def shell() -> html.Div:
    return html.Div([navigation(), dash.page_container])


# The address bar carries the design and the page state. Callbacks send partial updates
# {key: value, or null to drop it} to the page's "url-update" store, the design panel to its own
# "url-design-update" (the design panel's update of a slider step and a page's answer to the step
# before, written to one store in one render, kept only the last: the address then missed the
# design's last step); this merges the ones that changed into the current query with
# history.replaceState (no navigation, no page re-render) and keeps the navigation links carrying
# the design keys.
dash.clientside_callback(
    """
    function(update, design) {
        const C = window.dash_clientside;
        const fired = ((C.callback_context && C.callback_context.triggered) || []).map(t => t.prop_id);
        const updates = [[%s, update], [%s, design]]
            .filter(([id, u]) => u && fired.includes(id + ".data")).map(([id, u]) => u);
        if (!updates.length) { return C.no_update; }
        // written in a task of its own: a slider step's requests are sent first, the address follows
        return new Promise(resolve => setTimeout(() => {
            let s = C.no_update;  // (resolved whatever happens: never left pending)
            try {
                const params = new URLSearchParams(window.location.search);
                for (const [k, v] of updates.flatMap(u => Object.entries(u))) {
                    if (v === null || v === undefined || v === "") { params.delete(k); } else { params.set(k, String(v)); }
                }
                s = params.toString();
                window.history.replaceState(window.history.state, "", window.location.pathname + (s ? "?" + s : ""));
                const design = new URLSearchParams();
                const keys = %s;
                for (const [k, v] of params.entries()) { if (keys.includes(k)) { design.set(k, v); } }
                const d = design.toString();
                document.querySelectorAll("a.nav-link").forEach(a => {
                    a.href = a.getAttribute("href").split("?")[0] + (d ? "?" + d : "");
                });
            } finally { resolve(s); }
        }, 0));
    }
    """ % (json.dumps(ids.URL_UPDATE), json.dumps(ids.URL_DESIGN_UPDATE), json.dumps([*PARAMETER_SPECS, "material"])),
    Output(ids.URL_SINK, "children"),
    Input(ids.URL_UPDATE, "data"),
    Input(ids.URL_DESIGN_UPDATE, "data"),
)


# The navigation's "Design panel" button hides or shows the panel on every page (a class on <body>,
# which survives page changes).
dash.clientside_callback(
    """
    function(n) {
        if (!n) { return window.dash_clientside.no_update; }
        const hidden = document.body.classList.toggle("design-hidden");
        window.dispatchEvent(new Event("resize"));  // the figures take the freed width
        return hidden ? "false" : "true";
    }
    """,
    Output(ids.DESIGN_TOGGLE, "aria-pressed"),
    Input(ids.DESIGN_TOGGLE, "n_clicks"),
)


# Controls -> the design store, the URL and the errors at the fields, in the browser (no server
# round trip before the page's own callbacks run: a slider move reaches the figure one request
# sooner). Each slider has a number box beside it: either one moves the other. A value that is
# refused is named at its field, in its unit, and the design keeps the last accepted value (never
# a default in its place). Ranges and presets come from the parameter definitions; the server
# validates again.
dash.clientside_callback(
    """
    function(values, boxes, material, reset, ids, boxIds, errorIds, stores, shown, shownSummary) {
        const C = window.dash_clientside, trig = C.callback_context.triggered_id;
        const SPEC = %(spec)s, PRESET = %(preset)s, BASE = %(base)s, DEFAULT = %(default)s, ADVANCED = %(advanced)s;
        const ID = %(ids)s;
        const names = ids.map(i => i.name), boxNames = boxIds.map(i => i.name);
        // the design as stored: what a refused value keeps, and the values of parameters whose fields are
        // not on the page (the advanced section until it is first opened)
        const storedMaterial = ((stores || [])[0] || {}).material;
        const stored = Object.assign({}, BASE[BASE[storedMaterial] ? storedMaterial : DEFAULT],
                                     ((stores || [])[0] || {}).params || {});
        let cur = {};
        names.forEach((n, i) => { cur[n] = values[i]; });
        const boxOf = {};
        boxNames.forEach((n, i) => { boxOf[n] = boxes[i]; });
        let outValues = names.map(() => C.no_update), outBoxes = boxNames.map(() => C.no_update);
        let outMaterial = C.no_update;
        const typed = trig && typeof trig === "object" && trig.type === ID.box ? trig.name : null;
        // a typed value, a material or a reset is committed: the pages following the design take it at once
        window.shimmyDesignCommitted = Boolean(typed) || trig === ID.reset || trig === ID.material;
        if (trig === ID.reset) {
            material = DEFAULT; cur = Object.assign({}, BASE[DEFAULT]); outMaterial = DEFAULT;
            outValues = names.map(n => cur[n]); outBoxes = boxNames.map(n => cur[n]);
        } else if (trig === ID.material) {
            Object.assign(cur, PRESET[material]); outValues = names.map(n => cur[n]);
            outBoxes = boxNames.map(n => cur[n]);
        } else if (typed) {
            cur[typed] = boxOf[typed];
        } else if (trig && typeof trig === "object" && trig.type === ID.param) {
            const n = trig.name, s = SPEC[n];
            if (s.step && typeof cur[n] === "number" && isFinite(cur[n])) {  // moved: onto the step grid
                const onGrid = Number((s.low + Math.round((cur[n] - s.low) / s.step) * s.step).toFixed(s.decimals));
                if (onGrid !== cur[n]) { cur[n] = onGrid; outValues[names.indexOf(n)] = onGrid; }  // else: as it is
            }
            if (boxNames.includes(n)) { outBoxes[boxNames.indexOf(n)] = cur[n]; }
        }
        const base = BASE[material], full = Object.assign({}, base), problems = {};
        for (const n of names) {
            const v = cur[n], s = SPEC[n];
            const unit = s.unit ? " " + s.unit : "";
            const kept = stored[n] !== undefined ? stored[n] : base[n];
            if (v === null || v === undefined || v === "" || typeof v !== "number" || !isFinite(v)) {
                problems[n] = n + " is empty or not a number; enter " + s.allowed + " (kept " + kept + unit + ")";
            } else if (v < s.low || v > s.high) {
                problems[n] = n + " = " + v + unit + " is outside " + s.range + " (kept " + kept + unit + ")";
            } else if (s.integer && !Number.isInteger(v)) {
                problems[n] = n + " = " + v + unit + " is not a whole number; enter " + s.allowed
                              + " (kept " + kept + unit + ")";
            }
            if (problems[n]) { full[n] = kept; } else {
                full[n] = v;
                if (n === typed) { outValues[names.indexOf(n)] = v; }
            }
        }
        for (const n in SPEC) {  // no field on the page: as stored, a reset's or a preset's value aside
            if (!names.includes(n) && trig !== ID.reset) {
                full[n] = trig === ID.material && n in PRESET[material] ? PRESET[material][n] : stored[n];
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
        const refused = Object.keys(problems);
        const summary = refused.length ? "Not applied: " + refused.join(", ") + " (see the field" +
                        (refused.length > 1 ? "s" : "") + ")" : "";
        // The messages are set only where they change (a slider step sets none), through set_props: as
        // declared outputs they cost every step ~10-20 ms of the renderer's time, nearly all no_update.
        errorIds.forEach((i, k) => {
            const message = problems[i.name] || "";
            if (message !== (shown[k] || "")) { C.set_props(i, {children: message}); }
        });
        if (summary !== (shownSummary || "")) { C.set_props(ID.summary, {children: summary}); }
        if (refused.some(n => ADVANCED.includes(n))) { C.set_props(ID.advanced, {open: true}); }
        return [outValues, outBoxes, outMaterial, url, stores.map(() => ({material: material, params: params}))];
    }
    """ % {"spec": json.dumps({n: {"low": s.low, "high": s.high, "integer": s.integer, "allowed": s.allowed,
                                   "unit": s.unit, "range": f"[{s.low:g}, {s.high:g}] {s.unit}".rstrip(),
                                   "step": s.step, "decimals": s.decimals}
                               for n, s in PARAMETER_SPECS.items()}),
           "preset": json.dumps(MATERIALS),
           "base": json.dumps({m: state.material_params(m) for m in MATERIALS}),
           "default": json.dumps(state.DEFAULT_MATERIAL), "advanced": json.dumps(list(ADVANCED)),
           "ids": json.dumps({"box": ids.PARAM_BOX_TYPE, "param": ids.PARAM_TYPE, "reset": ids.RESET_DESIGN,
                              "material": ids.MATERIAL, "summary": ids.DESIGN_ERROR, "advanced": ids.ADVANCED})},
    Output(ids.param(ALL), "value"),
    Output(ids.param_box(ALL), "value"),
    Output(ids.MATERIAL, "value"),
    Output(ids.URL_DESIGN_UPDATE, "data"),
    Output(ids.design_store(ALL), "data"),
    Input(ids.param(ALL), "value"),
    Input(ids.param_box(ALL), "value"),
    Input(ids.MATERIAL, "value"),
    Input(ids.RESET_DESIGN, "n_clicks"),
    State(ids.param(ALL), "id"),
    State(ids.param_box(ALL), "id"),
    State(ids.param_error(ALL), "id"),
    State(ids.design_store(ALL), "data"),
    State(ids.param_error(ALL), "children"),
    State(ids.DESIGN_ERROR, "children"),
    prevent_initial_call=True,
)
