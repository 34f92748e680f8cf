"""Time history at any operating point: psi and l_g delta against time, spectrum, phase portrait."""

from __future__ import annotations

import math

import dash
import numpy as np
from dash import Input, Output, State, dcc, html, no_update
from plotly.subplots import make_subplots

from shimmy.service import settings
from ui import components as ui
from ui import fields, ids, jobs
from ui import style
from ui.series import envelope
from ui.fields import Quantity
from ui.layout import page

dash.register_page(__name__, path="/time-history", name="Time history", order=2)

SPEED = Quantity("simulate", "V", "V", "m/s")
FZ = Quantity("simulate", "Fz", "Fz", "kN", 1e3)
T_END = Quantity("simulate", "t_end", "simulated time", "s")
PSI0 = Quantity("simulate", "psi0", "initial psi", "rad")
LATERAL0 = Quantity("simulate", "lateral0", "initial l_g delta", "m")
#: The starts offered: the standard one (psi = 0.001 rad), and ones large enough to reach each
#: attractor of a bistable point.
STARTS = {"standard": ("standard: psi = 0.001 rad", 0.001, 0.0),
          "torsional": ("large torsional: psi = 0.2 rad", 0.2, 0.0),
          "lateral": ("large lateral: l_g delta = 0.1 m", 0.0, 0.1),
          "typed": ("values typed below", None, None)}
WAITING = "Choose an operating point and press Run (a result already in the cache is shown at once)"


def _placeholders(text: str = WAITING) -> tuple:
    return (style.message_figure(text, 420), style.message_figure("The spectrum of the steady window appears here"),
            style.message_figure("The phase portrait appears here"), [])


def _start_of(psi0, lateral0) -> str:
    return next((k for k, (_, p, q) in STARTS.items() if p == psi0 and q == lateral0), "typed")


def layout(config: str | None = None, V: str | None = None, Fz: str | None = None, t_end: str | None = None,
           psi0: str | None = None, lateral0: str | None = None, run: str | None = None, **query):
    config, bad_config = fields.choice("config", config, list(ui.CONFIGS), "nes_pd", "a configuration")
    problems = [bad_config]
    v, problem_v = SPEED.from_url("V", V, 30)
    fz, problem_fz = FZ.from_url("Fz", Fz, 150)
    t, problem_t = T_END.from_url("t_end", t_end, 60)
    p0, problem_p = PSI0.from_url("psi0", psi0, 0.001)
    l0, problem_l = LATERAL0.from_url("lateral0", lateral0, 0.0)
    problems += [problem_v, problem_fz, problem_t, problem_p, problem_l]
    series, spectrum, phase, _ = _placeholders()
    return page(
        query, ids.TH,
        ui.header("Time history", "The gear at one operating point, from a start you choose (the standard "
                  "start is psi = 0.001 rad, the rest at rest): torsion and lateral bending against time, the "
                  "spectrum of the steady window with its dominant frequency, and the torsional phase portrait. A "
                  "bistable point settles on a different limit cycle from a large torsional or a large lateral "
                  "start. Runs in the background; repeated questions come from the cache."),
        html.Div([
            ui.field("Configuration", ui.configurations(ids.TH_CONFIG, config, width="160px")),
            ui.field("V (m/s)", SPEED.box(ids.TH_V, v, debounce=True)),
            ui.field("Fz (kN)", FZ.box(ids.TH_FZ, fz, debounce=True)),
            ui.field("Simulated time (s)", T_END.box(ids.TH_TEND, t)),
            ui.field("Start", dcc.Dropdown(id=ids.TH_START, value=_start_of(p0, l0), clearable=False,
                                           style={"width": "250px"}, options=[
                                               {"label": label, "value": k} for k, (label, _, _) in STARTS.items()])),
            html.Div([ui.field("psi0 (rad)", PSI0.box(ids.TH_PSI0, p0)),
                      ui.field("l_g delta0 (m)", LATERAL0.box(ids.TH_LAT0, l0))], className="pair"),
            *jobs.controls(ids.TH_GROUP, "Run"),
        ], className="controls"),
        html.Div([html.Span("Operating points: ", className="hint"),
                  *[html.Button(f"{name} ({v} m/s, {f} kN)", id=ids.th_op(name), className="secondary")
                    for name, (v, f) in ui.OPERATING_POINTS.items()]], className="op-buttons"),
        html.Div(" ".join(p for p in problems if p), id=ids.TH_GROUP.error, className="error", role="alert"),
        html.Div(id=ids.TH_SETTLED, className="settled", role="status"),
        html.Div(id=ids.TH_METRICS, className="metrics"),
        ui.graph(ids.TH_SERIES, figure=series),
        html.Div([ui.graph(ids.TH_SPECTRUM, figure=spectrum), ui.graph(ids.TH_PHASE, figure=phase)],
                 className="grid-2"),
        ui.downloads(ids.TH_GROUP),
        *jobs.stores(ids.TH_GROUP),
        # ?run=1 (a click on a map point): run once the page is drawn, as if Run had been pressed.
        dcc.Interval(id=ids.TH_AUTORUN, interval=200, max_intervals=1, disabled=run != "1"),
    )


@dash.callback(Output(ids.TH_V, "value"), Output(ids.TH_FZ, "value"),
               Input(ids.th_op(dash.ALL), "n_clicks"), prevent_initial_call=True)
def operating_point(_clicks):
    trigger = dash.ctx.triggered_id
    if not trigger or not any(_clicks):
        return no_update, no_update
    v, f = ui.OPERATING_POINTS[trigger["name"]]
    return v, f


@dash.callback(Output(ids.TH_START, "value"), Output(ids.TH_PSI0, "value"), Output(ids.TH_LAT0, "value"),
               Input(ids.TH_START, "value"), Input(ids.TH_PSI0, "value"), Input(ids.TH_LAT0, "value"),
               prevent_initial_call=True)
def start(choice, psi0, lateral0):
    """A start chosen fills its values in; values typed in make the choice "typed" (unless they are a preset's)."""
    if dash.ctx.triggered_id == ids.TH_START:
        _, p, q = STARTS.get(choice, STARTS["typed"])
        return no_update, (psi0 if p is None else p), (lateral0 if q is None else q)
    return _start_of(psi0, lateral0), no_update, no_update


def _requests(V, fz_kn, _autorun, config, t_end, psi0, lateral0, design):
    t = T_END.read(t_end)
    # The series is thinned for a long run: every t_end the field allows can be drawn.
    series_dt = max(0.002, math.ceil(1000 * t / (settings.MAX_SERIES_POINTS - 1)) / 1000)
    return [{"config": config, "V": SPEED.read(V), "Fz": FZ.read(fz_kn), "t_end": t, "psi0": PSI0.read(psi0),
             "lateral0": LATERAL0.read(lateral0), "include_series": True, "series_dt": series_dt, **design}]


def _csv_rows(results):
    s = results[0]["series"]
    keys = list(s)
    return keys, zip(*(s[k] for k in keys), strict=True)


def _file_stem(results):
    r = results[0]
    return f"time_history_{r['config']}_V{r['V']:g}_Fz{r['Fz'] / 1e3:g}kN"


jobs.register(
    ids.TH_GROUP, "simulate", requests=_requests, blank=lambda: (*_placeholders("Refused: see the message above"), ""),
    running=lambda: (*_placeholders("Running the time history…"), ""), waiting=lambda: (*_placeholders(), ""),
    render=lambda results: (*_figures(results[0]), _metrics(results[0]), settled(results[0])),
    notice=lambda results: "" if results[0]["success"] else results[0]["message"],
    outputs=[Output(ids.TH_SERIES, "figure"), Output(ids.TH_SPECTRUM, "figure"), Output(ids.TH_PHASE, "figure"),
             Output(ids.TH_METRICS, "children"), Output(ids.TH_SETTLED, "children")],
    triggers=[Input(ids.TH_V, "value"), Input(ids.TH_FZ, "value"), Input(ids.TH_AUTORUN, "n_intervals")],
    states=[State(ids.TH_CONFIG, "value"), State(ids.TH_TEND, "value"), State(ids.TH_PSI0, "value"),
            State(ids.TH_LAT0, "value"), State(ids.design_store(ids.TH), "data")],
    download=jobs.Download(ids.TH_GROUP, "time_history", _csv_rows, single=True, filename=_file_stem))


def _figures(result):
    s = result["series"]
    t = np.asarray(s["t"])
    title = (f"{style.CONFIG_LABELS[result['config']]} at V = {result['V']:g} m/s, Fz = {result['Fz'] / 1e3:g} kN")
    has_nes = "psis" in s
    rows = 4 if has_nes else 3
    series = make_subplots(rows=rows, cols=1, shared_xaxes=True, vertical_spacing=0.05)
    colour = style.CONFIG_COLOURS[result["config"]]
    for row, values, name, c in ((1, s["psi"], "torsion psi (rad)", colour),
                                 (2, s["lateral"], "lateral l_g delta (m)", "#56B4E9"),
                                 (3, s["lam"], "tyre deformation lam (m)", "#CC79A7")):
        x, y = envelope(t, values)
        series.add_scatter(x=x, y=y, name=name, line={"color": c, "width": 1}, row=row, col=1)
    if has_nes:
        x, y = envelope(t, np.asarray(s["psi"]) - np.asarray(s["psis"]))
        series.add_scatter(x=x, y=y, name="NES relative rotation psi - psis (rad)",
                           line={"color": "#D55E00", "width": 1}, row=4, col=1)
        series.update_yaxes(title_text="psi - psis (rad)", row=4, col=1)
    series.update_layout(title=style.title(title), height=180 * rows + 110, template="plotly_white",
                         margin={**style.MARGIN, "l": 70}, legend={"orientation": "h", "y": -0.08})
    series.update_xaxes(title_text="time t (s)", row=rows, col=1)
    series.update_yaxes(title_text="psi (rad)", row=1, col=1)
    series.update_yaxes(title_text="l_g delta (m)", row=2, col=1)
    series.update_yaxes(title_text="lam (m)", row=3, col=1)
    sp = result["spectrum"]
    spectrum = style.figure("Spectrum of the steady window", "frequency (Hz)", "power (normalised)")
    floor = 1e-6  # six decades below the peak: the tones, not the round-off
    for key, name, c in (("psi", "torsion psi", colour), ("lateral", "lateral l_g delta", "#56B4E9")):
        p = np.asarray(sp[key])
        scale = p.max() if p.size and p.max() > 0 else 1.0
        spectrum.add_scatter(x=sp["frequency_hz"], y=np.maximum(p / scale, floor * 0.5), name=name,
                             line={"color": c})
    if sp["dominant_hz"] is not None:
        spectrum.add_vline(x=sp["dominant_hz"], line={"color": "#D55E00", "dash": "dash"},
                           annotation_text=f"{sp['dominant_hz']:.3f} Hz", annotation_position="top right")
    spectrum.update_yaxes(type="log", range=[np.log10(floor), 0.3], dtick=1, exponentformat="power",
                          showexponent="all")
    n_window = int(round(result["options"]["window"] / result["series_dt"]))
    phase = style.figure("Torsional phase portrait", "psi (rad), steady window", "dpsi/dt (rad/s)")
    phase.add_scatter(x=s["psi"][-n_window:], y=s["dpsi"][-n_window:], mode="lines", name="orbit",
                      line={"color": colour, "width": 1})
    return series, spectrum, phase


MODE_WORDS = {"Torsion": "a torsional limit cycle", "Lateral": "a lateral limit cycle",
              "Both": "a limit cycle with both torsion and lateral bending large",
              "Stable": "straight rolling (the motion decayed)"}


def settled(result):
    """Which attractor the run settled on, and from where it started."""
    o = result.get("options", {})
    start = result.get("start") or {}
    psi0, lat0 = start.get("psi0"), start.get("lateral0")
    where = "" if psi0 is None else f"From psi0 = {psi0:g} rad, l_g delta0 = {lat0:g} m the run "
    verb = "settled on" if result["steady"] else "was still approaching (not yet steady at t_end)"
    f = result["frequency_hz"]
    amp = result["amplitude"]
    detail = "" if result["response_type"] == "Stable" else (
        f": max |psi| {amp['psi']:.3g} rad, max |l_g delta| {amp['lateral']:.3g} m"
        + ("" if f is None else f", {f:.2f} Hz"))
    text = f"{where or 'The run '}{verb} {MODE_WORDS.get(result['response_type'], result['response_type'])}{detail}"
    return text + (f" after {o['t_end']:g} s." if "t_end" in o else ".")


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


@dash.callback(Output(ids.URL_UPDATE, "data", allow_duplicate=True),
               Input(ids.TH_CONFIG, "value"), Input(ids.TH_V, "value"), Input(ids.TH_FZ, "value"), Input(ids.TH_TEND,
                                                                                                         "value"),
               Input(ids.TH_PSI0, "value"), Input(ids.TH_LAT0, "value"), prevent_initial_call=True)
def remember(config, V, fz, t_end, psi0, lateral0):
    standard = psi0 == STARTS["standard"][1] and lateral0 == STARTS["standard"][2]
    return {"config": config, "V": V, "Fz": fz, "t_end": t_end, "psi0": None if standard else psi0,
            "lateral0": None if standard else lateral0, "run": None}
