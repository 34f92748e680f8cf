"""The page shell: navigation, the design panel (always at hand) and the URL <-> design sync."""

from __future__ import annotations

import json

import dash
from dash import ALL, Input, Output, State, ctx, dcc, html, no_update

from shimmy.errors import InvalidParameterError
from shimmy.parameters import MATERIALS, PARAMETER_SPECS, Parameters

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


def _slider(name: str, value: float) -> html.Div:
    spec = PARAMETER_SPECS[name]
    return html.Div([
        _label(name),
        dcc.Slider(id={"type": "param", "name": name}, min=spec.low, max=spec.high,
                   step=(spec.high - spec.low) / SLIDER_STEPS, value=value, updatemode="drag",
                   marks={spec.low: f"{spec.low:g}", spec.high: f"{spec.high:g}"},
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


@dash.callback(
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
def sync_design(values, material, _reset, ids):
    """Controls -> the design store and the URL on every change (the page layout set them from the URL)."""
    names = [i["name"] for i in ids]
    trigger = ctx.triggered_id
    if trigger == "reset-design":
        material = state.DEFAULT_MATERIAL
        full = state.material_params(material)
        return ([full[n] for n in names], material, _url_keys(material, full),
                [state.design_request(material, full)], "")
    current = dict(zip(names, values, strict=True))
    if trigger == "material":
        current.update(MATERIALS[material])
    problems = []
    full = state.material_params(material)
    for name, value in current.items():
        if value is None:
            spec = PARAMETER_SPECS[name]
            problems.append(f"{name}: not a number in range; allowed: {spec.allowed} (kept {full[name]:g})")
            continue
        try:
            Parameters().with_overrides({name: value})
            full[name] = float(value)
        except InvalidParameterError as exc:
            problems.append(f"{exc} (kept {full[name]:g})")
    try:
        Parameters().with_overrides(full)
    except (InvalidParameterError, ValueError) as exc:  # e.g. an NES geometry off its track
        return no_update, no_update, no_update, no_update, f"design not applied: {exc}"
    outputs = [full[n] for n in names] if trigger == "material" else [no_update] * len(names)
    return (outputs, no_update, _url_keys(material, full), [state.design_request(material, full)],
            "; ".join(problems))


def _url_keys(material: str, full: dict[str, float]) -> dict[str, str | None]:
    keys: dict[str, str | None] = {name: None for name in PARAMETER_SPECS}
    keys.update(state.design_query(material, full))
    return keys
