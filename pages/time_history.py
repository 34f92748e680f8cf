"""Time history at any operating point: psi and l_g delta against time, spectrum, phase portrait."""

from __future__ import annotations

import dash
import numpy as np
from dash import Input, Output, State, dcc, html, no_update
from plotly.subplots import make_subplots

from shimmy.errors import InvalidParameterError
from shimmy.service import schemas
from ui import components as ui
from ui import jobs
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
            *jobs.controls("th", "Run"),
        ], className="controls"),
        html.Div([html.Span("Operating points: ", className="hint"),
                  *[html.Button(f"{name} ({v} m/s, {f} kN)", id={"type": "th-op", "name": name}, className="secondary")
                    for name, (v, f) in ui.OPERATING_POINTS.items()]], className="op-buttons"),
        html.Div(id="th-error", className="error", role="alert"),
        html.Div(id="th-metrics", className="metrics"),
        ui.graph("th-series", figure=style.message_figure("Choose an operating point and press Run")),
        html.Div([ui.graph("th-spectrum"), ui.graph("th-phase")], className="grid-2"),
        ui.downloads("th"),
        *jobs.stores("th", "th-request"),
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


def _requests(V, fz_kn, config, t_end, design):
    request = _request(V, fz_kn, config, t_end, design)
    try:
        schemas.validate("simulate", request)
    except InvalidParameterError as exc:
        if exc.field == "Fz":
            raise InvalidParameterError("Fz", fz_kn, "a number in [10, 900] kN",
                                        message=f"Fz={fz_kn!r} kN is outside [10, 900] kN") from None
        raise
    return [request]


def _csv_rows(results):
    s = results[0]["series"]
    keys = list(s)
    return keys, zip(*(s[k] for k in keys), strict=True)


def _file_stem(results):
    r = results[0]
    return f"time_history_{r['config']}_V{r['V']:g}_Fz{r['Fz'] / 1e3:g}kN"


jobs.register(
    "th", "simulate", requests=_requests, initial=True,
    render=lambda results: (*_figures(results[0]), _metrics(results[0])),
    notice=lambda results: "" if results[0]["success"] else results[0]["message"],
    outputs=[Output("th-series", "figure"), Output("th-spectrum", "figure"), Output("th-phase", "figure"),
             Output("th-metrics", "children")],
    triggers=[Input("th-v", "value"), Input("th-fz", "value")],
    states=[State("th-config", "value"), State("th-tend", "value"), State(design_id("th"), "data")],
    store="th-request", download=jobs.Download("th", "time_history", _csv_rows, single=True, filename=_file_stem))


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
