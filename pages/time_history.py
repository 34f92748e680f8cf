"""Time history at any operating point: psi and l_g delta against time, spectrum, phase portrait."""

from __future__ import annotations

import dash
import numpy as np
from dash import Input, Output, State, dcc, html, no_update
from plotly.subplots import make_subplots

from shimmy.errors import InvalidParameterError
from shimmy.service import analyses
from ui import components as ui
from ui import style
from ui.layout import design_id, page

dash.register_page(__name__, path="/time-history", name="Time history", order=2)

CONFIG_OPTIONS = [{"label": style.CONFIG_LABELS[c], "value": c} for c in style.CONFIG_COLOURS]



def layout(config: str = "nes_pd", V: str = "30", Fz: str = "150", t_end: str = "60", **query):
    config = config if config in style.CONFIG_COLOURS else "nes_pd"
    return page(
        query, "th",
        ui.header("Time history", "The gear at one operating point, started from psi = 0.001 rad (REFERENCE.md): "
                  "torsion and lateral bending against time, the spectrum of the steady window with its dominant "
                  "frequency, and the torsional phase portrait. Runs in the background; repeated questions come "
                  "from the cache."),
        html.Div([
            ui.field("Configuration", dcc.Dropdown(id="th-config", options=CONFIG_OPTIONS, value=config,
                                                   clearable=False, style={"width": "160px"})),
            ui.field("V (m/s)", dcc.Input(id="th-v", type="number", value=ui.number(V, 30), min=1, max=500, step="any",
                                          debounce=True)),
            ui.field("Fz (kN)", dcc.Input(id="th-fz", type="number", value=ui.number(Fz, 150), min=10, max=900,
                                          debounce=True, step="any")),
            ui.field("Simulated time (s)", dcc.Input(id="th-tend", type="number", value=ui.number(t_end, 60), min=1,
                                                     max=600, step="any")),
            html.Button("Run", id="th-run"),
            html.Button("Cancel", id="th-cancel", className="secondary", disabled=True),
            ui.progress_bar("th"),
        ], className="controls"),
        html.Div([html.Span("Operating points: ", className="hint"),
                  *[html.Button(f"{name} ({v} m/s, {f} kN)", id={"type": "th-op", "name": name}, className="secondary")
                    for name, (v, f) in ui.OPERATING_POINTS.items()]], className="op-buttons"),
        html.Div(id="th-error", className="error", role="alert"),
        html.Div(id="th-metrics", className="metrics"),
        ui.graph("th-series", figure=style.message_figure("Choose an operating point and press Run")),
        html.Div([ui.graph("th-spectrum"), ui.graph("th-phase")], className="grid-2"),
        ui.downloads("th"),
        dcc.Store(id="th-request"), dcc.Store(id="th-go"),
    )


@dash.callback(Output("th-v", "value"), Output("th-fz", "value"),
               Input({"type": "th-op", "name": dash.ALL}, "n_clicks"), prevent_initial_call=True)
def operating_point(_clicks):
    trigger = dash.ctx.triggered_id
    if not trigger or not any(_clicks):
        return no_update, no_update
    v, f = ui.OPERATING_POINTS[trigger["name"]]
    return v, f


def _request(V, fz_kn, config, t_end, design):
    return {"config": config, "V": V, "Fz": None if fz_kn is None else float(fz_kn) * 1e3, "t_end": t_end,
            "include_series": True, **design}


@dash.callback(
    Output("th-series", "figure"), Output("th-spectrum", "figure"), Output("th-phase", "figure"),
    Output("th-metrics", "children"), Output("th-error", "children"), Output("th-request", "data"),
    Output("th-csv", "disabled"), Output("th-json", "disabled"), Output("th-go", "data"),
    Input("th-run", "n_clicks"), Input("th-v", "value"), Input("th-fz", "value"),
    State("th-config", "value"), State("th-tend", "value"), State(design_id("th"), "data"),
)
def dispatch(n, V, fz_kn, config, t_end, design):
    """Answer at once from the cache; otherwise hand over to the background run."""
    request = _request(V, fz_kn, config, t_end, design)
    try:
        result = analyses.cached("simulate", request)
    except InvalidParameterError as exc:
        return (no_update,) * 4 + (_field_message(exc), no_update, True, True, no_update)
    if result is not None:
        return (*_figures(result), _metrics(result), "" if result["success"] else result["message"], request,
                False, False, no_update)
    return (no_update,) * 8 + ([n, V, fz_kn],)


@dash.callback(
    Output("th-series", "figure", allow_duplicate=True), Output("th-spectrum", "figure", allow_duplicate=True),
    Output("th-phase", "figure", allow_duplicate=True), Output("th-metrics", "children", allow_duplicate=True),
    Output("th-error", "children", allow_duplicate=True), Output("th-request", "data", allow_duplicate=True),
    Output("th-csv", "disabled", allow_duplicate=True), Output("th-json", "disabled", allow_duplicate=True),
    Input("th-go", "data"),
    State("th-v", "value"), State("th-fz", "value"), State("th-config", "value"), State("th-tend", "value"),
    State(design_id("th"), "data"),
    background=True, prevent_initial_call=True, interval=250,
    running=[(Output("th-run", "disabled"), True, False), (Output("th-cancel", "disabled"), False, True)],
    cancel=[Input("th-cancel", "n_clicks")],
    progress=[Output("th-progress", "value"), Output("th-status", "children")],
)
def run(set_progress, _go, V, fz_kn, config, t_end, design):
    set_progress(("5", "simulating"))
    request = _request(V, fz_kn, config, t_end, design)
    try:
        result, _ = analyses.run("simulate", request)
    except InvalidParameterError as exc:
        set_progress(("0", ""))
        return (no_update,) * 4 + (_field_message(exc), no_update, True, True)
    set_progress(("100", "done"))
    return (*_figures(result), _metrics(result), "" if result["success"] else result["message"], request,
            False, False)


def _field_message(exc: InvalidParameterError) -> str:
    if exc.field == "Fz":
        return f"Fz={exc.value!r} N is outside [10, 900] kN"
    return str(exc)


def _figures(result):
    s = result["series"]
    t = np.asarray(s["t"])
    title = (f"{style.CONFIG_LABELS[result['config']]} at V = {result['V']:g} m/s, Fz = {result['Fz'] / 1e3:g} kN")
    has_nes = "psis" in s
    rows = 4 if has_nes else 3
    series = make_subplots(rows=rows, cols=1, shared_xaxes=True, vertical_spacing=0.05)
    colour = style.CONFIG_COLOURS[result["config"]]
    series.add_scatter(x=t, y=s["psi"], name="torsion psi (rad)", line={"color": colour, "width": 1}, row=1, col=1)
    series.add_scatter(x=t, y=s["lateral"], name="lateral l_g delta (m)", line={"color": "#56B4E9", "width": 1},
                       row=2, col=1)
    series.add_scatter(x=t, y=s["lam"], name="tyre deformation lam (m)", line={"color": "#CC79A7", "width": 1},
                       row=3, col=1)
    if has_nes:
        relative = np.asarray(s["psi"]) - np.asarray(s["psis"])
        series.add_scatter(x=t, y=relative, name="NES relative rotation psi - psis (rad)",
                           line={"color": "#D55E00", "width": 1}, row=4, col=1)
        series.update_yaxes(title_text="psi - psis (rad)", row=4, col=1)
    series.update_layout(title={"text": title, "x": 0.01}, height=180 * rows + 100, template="plotly_white",
                         margin={"l": 70, "r": 16, "t": 44, "b": 48}, legend={"orientation": "h", "y": -0.08})
    series.update_xaxes(title_text="time t (s)", row=rows, col=1)
    series.update_yaxes(title_text="psi (rad)", row=1, col=1)
    series.update_yaxes(title_text="l_g delta (m)", row=2, col=1)
    series.update_yaxes(title_text="lam (m)", row=3, col=1)
    sp = result["spectrum"]
    spectrum = style.figure("Spectrum of the steady window", "frequency (Hz)", "power (normalised)")
    for key, name, c in (("psi", "torsion psi", colour), ("lateral", "lateral l_g delta", "#56B4E9")):
        p = np.asarray(sp[key])
        spectrum.add_scatter(x=sp["frequency_hz"], y=p / p.max() if p.max() > 0 else p, name=name,
                             line={"color": c})
    if sp["dominant_hz"] is not None:
        spectrum.add_vline(x=sp["dominant_hz"], line={"color": "#D55E00", "dash": "dash"},
                           annotation_text=f"{sp['dominant_hz']:.3f} Hz", annotation_position="top right")
    spectrum.update_yaxes(type="log")
    n_window = int(round(result["options"]["window"] / result["series_dt"]))
    phase = style.figure("Torsional phase portrait (steady window)", "psi (rad)", "dpsi/dt (rad/s)")
    phase.add_scatter(x=s["psi"][-n_window:], y=s["dpsi"][-n_window:], mode="lines", name="orbit",
                      line={"color": colour, "width": 1})
    return series, spectrum, phase


def _metrics(result):
    amp = result["amplitude"]
    f = result["frequency_hz"]
    items = [("response", result["response_type"] + ("" if result["steady"] else " (not yet steady)")),
             ("max |psi| (rad)", f"{amp['psi']:.4g}"), ("max |l_g delta| (m)", f"{amp['lateral']:.4g}"),
             ("dominant frequency (Hz)", "–" if f is None else f"{f:.3f}")]
    if "nes_relative" in amp:
        items.append(("NES relative rotation (rad)", f"{amp['nes_relative']:.4g}"))
    return [html.Div([html.Div(v, className="value"), html.Div(k, className="label")], className="metric")
            for k, v in items]


@dash.callback(Output("url-update", "data", allow_duplicate=True),
               Input("th-config", "value"), Input("th-v", "value"), Input("th-fz", "value"), Input("th-tend", "value"),
               prevent_initial_call=True)
def remember(config, V, fz, t_end):
    return {"config": config, "V": V, "Fz": fz, "t_end": t_end}


@dash.callback(Output("th-download", "data"), Input("th-csv", "n_clicks"), Input("th-json", "n_clicks"),
               State("th-request", "data"), prevent_initial_call=True)
def download(_csv, _json, request):
    if not request:
        return no_update
    result, _ = analyses.run("simulate", request)
    name = f"time_history_{result['config']}_V{result['V']:g}_Fz{result['Fz'] / 1e3:g}kN"
    if dash.ctx.triggered_id == "th-json":
        return {"content": ui.json_text(result), "filename": name + ".json"}
    s = result["series"]
    keys = list(s)
    return {"content": ui.csv_text(keys, zip(*(s[k] for k in keys), strict=True)), "filename": name + ".csv"}
