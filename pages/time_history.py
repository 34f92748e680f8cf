"""Time history at any operating point: psi and l_g delta against time, spectrum, phase portrait."""

from __future__ import annotations

import math

import dash
import numpy as np
from dash import Input, Output, State, dcc, html, no_update
from plotly.subplots import make_subplots

from shimmy.errors import InvalidParameterError
import shimmy.model.units as units
from shimmy.model.configurations import STATE_NAMES, STATE_UNITS
from shimmy.service import analyses, settings
from ui import components as ui
from ui import fields, ids, jobs
from ui import style
from ui.series import envelope
from ui.fields import Quantity
from ui.layout import page

dash.register_page(__name__, path="/time-history", name="Time history", order=2)

SPEED = Quantity("simulate", "V", "V", "m/s")
FZ = Quantity("simulate", "Fz", "Fz", "kN", units.KN)
T_END = Quantity("simulate", "t_end", "simulated time", "s")
PSI0 = Quantity("simulate", "psi0", "initial psi", "rad")
LATERAL0 = Quantity("simulate", "lateral0", "initial l_g delta", "mm", units.MM)  # the address keeps m
#: The starts offered: the standard one (psi = 0.001 rad), and ones large enough to reach each
#: attractor of a bistable point (psi0 in rad, l_g delta0 in mm: the boxes' units).
STARTS = {"standard": ("standard: psi = 0.001 rad", 0.001, 0.0),
          "torsional": ("large torsional: psi = 0.2 rad", 0.2, 0.0),
          "lateral": ("large lateral: l_g delta = 100 mm", 0.0, 100.0),
          "typed": ("values typed below", None, None)}
WAITING = "Choose an operating point and press Run (a result already in the cache is shown at once)"
MARGINS_STALE = "Press Compute margins for this operating point (any margins shown are of the previous one)."
ATTRACTOR_WORDS = {"equilibrium": "straight rolling", "torsional": "torsional limit cycle",
                   "lateral": "lateral limit cycle", "both": "limit cycle, torsion and lateral bending both large"}


def _placeholders(text: str = WAITING) -> tuple:
    return (style.message_figure(text, 420), style.message_figure("The spectrum of the steady window appears here"),
            style.message_figure("The phase portrait appears here"), [])


def _start_of(psi0, lateral0) -> str:
    return next((k for k, (_, p, q) in STARTS.items() if p == psi0 and q == lateral0), "typed")


def layout(config: str | None = None, V: str | None = None, Fz: str | None = None, t_end: str | None = None,
           psi0: str | None = None, lateral0: str | None = None, run: str | None = None, map_type: str | None = None,
           **query):
    config, bad_config = fields.choice("config", config, list(ui.CONFIGS), "nes_pd", "a configuration")
    problems = [bad_config]
    v, problem_v = SPEED.from_url("V", V, 30)
    fz, problem_fz = FZ.from_url("Fz", Fz, 150)
    t, problem_t = T_END.from_url("t_end", t_end, 60)
    p0, problem_p = PSI0.from_url("psi0", psi0, 0.001)
    l0, problem_l = LATERAL0.from_url("lateral0", _mm_of(lateral0), 0.0)
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
            SPEED.field("V (m/s)", ids.TH_V, v),
            FZ.field("Fz (kN)", ids.TH_FZ, fz),
            T_END.field("Simulated time (s)", ids.TH_TEND, t),
            ui.field("Start", dcc.Dropdown(id=ids.TH_START, value=_start_of(p0, l0), clearable=False,
                                           style={"width": "250px"}, options=[
                                               {"label": label, "value": k} for k, (label, _, _) in STARTS.items()])),
            html.Div([PSI0.field("psi0 (rad)", ids.TH_PSI0, p0),
                      LATERAL0.field("l_g delta0 (mm)", ids.TH_LAT0, l0)], className="pair"),
            *jobs.controls(ids.TH_GROUP, "Run"),
        ], className="controls"),
        html.Div([html.Span("Operating points: ", className="hint"),
                  *[html.Button(f"{name} ({v} m/s, {f} kN)", id=ids.th_op(name), className="secondary")
                    for name, (v, f) in ui.OPERATING_POINTS.items()]], className="op-buttons"),
        html.Div(" ".join(p for p in problems if p), id=ids.TH_GROUP.error, className="error", role="alert"),
        html.Div(_bistable_note(map_type), id=ids.TH_BISTABLE, className="note map-note", role="note"),
        html.Div(id=ids.TH_SETTLED, className="settled", role="status"),
        html.Div(id=ids.TH_METRICS, className="metrics"),
        ui.graph(ids.TH_SERIES, figure=series),
        html.Div([ui.graph(ids.TH_SPECTRUM, figure=spectrum), ui.graph(ids.TH_PHASE, figure=phase)],
                 className="grid-2"),
        ui.downloads(ids.TH_GROUP),
        *jobs.stores(ids.TH_GROUP),
        dcc.Store(id=ids.TH_KICK),
        html.H2("Disturbance margins"),
        html.P("The attractors at this operating point (the stable equilibrium and limit cycles of the bifurcation "
               "diagram at its load, and any motion the runs from the standard and two large starts settle on), "
               "and for each the smallest yaw kick psi0 from straight rolling that ends on it, found by a scan of "
               "kicks and bisection, each checked by two runs just below and just above it. A row's Run button "
               "runs the time history above from just above its kick: the gear ends on that attractor.",
               className="hint"),
        html.Div(jobs.controls(ids.THM, "Compute margins"), className="controls"),
        html.Div(id=ids.THM.error, className="error", role="alert"),
        html.Div(id=ids.THM_TABLE, className="table-wrap"),
        ui.downloads(ids.THM),
        *jobs.stores(ids.THM),
        # ?run=1 (a click on a map point): run once the page is drawn, as if Run had been pressed.
        dcc.Interval(id=ids.TH_AUTORUN, interval=200, max_intervals=1, disabled=run != "1"),
    )


for _box, _quantity in ((ids.TH_V, SPEED), (ids.TH_FZ, FZ), (ids.TH_TEND, T_END), (ids.TH_PSI0, PSI0),
                        (ids.TH_LAT0, LATERAL0)):
    fields.check(_box, _quantity)


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


def _bistable_note(map_type):
    """What the page says when it was opened from a point the map shades Bistable (or Both)."""
    if map_type == "Bistable":
        return ("The stability map shades this point Bistable: a torsional and a lateral limit cycle coexist, and "
                "which one the gear ends on depends on the kick. Compute its disturbance margins below to see how "
                "large a yaw kick reaches each, and run from there.")
    return None


def _requests(V, fz_kn, _autorun, _kick, config, t_end, psi0, lateral0, design):
    t = T_END.read(t_end)
    # The series is thinned for a long run: every t_end the field allows can be drawn.
    series_dt = max(0.002, math.ceil(1000 * t / (settings.MAX_SERIES_POINTS - 1)) / 1000)
    return [{"config": config, "V": SPEED.read(V), "Fz": FZ.read(fz_kn), "t_end": t, "psi0": PSI0.read(psi0),
             "lateral0": LATERAL0.read(lateral0), "include_series": True, "series_dt": series_dt, **design}]


#: The downloaded series' columns: name with its unit, SI units per unit written (l_g delta in mm).
CSV_COLUMNS = {"t": ("t_s", 1.0), "lateral": ("lateral_mm", units.MM),
               **{n: (f"{n}_{u.replace('/', '_')}", 1.0) for n, u in zip(STATE_NAMES, STATE_UNITS, strict=True)}}


def _csv_rows(results):
    s = results[0]["series"]
    keys = list(s)
    columns = [CSV_COLUMNS.get(k, (k, 1.0)) for k in keys]
    values = [s[k] if scale == 1.0 else [v / scale for v in s[k]] for k, (_, scale) in zip(keys, columns, strict=True)]
    return [name for name, _ in columns], zip(*values, strict=True)


def _mm_of(lateral0_m):
    """The address's lateral0 (m, as the API takes it) in the box's mm; a value that is no number as it is."""
    try:
        return None if lateral0_m is None else float(f"{float(lateral0_m) / units.MM:.12g}")  # no float noise
    except (TypeError, ValueError):
        return lateral0_m


def _file_stem(results):
    r = results[0]
    return f"time_history_{r['config']}_V{r['V']:g}_Fz{r['Fz'] / units.KN:g}kN"


jobs.register(
    ids.TH_GROUP, "simulate", requests=_requests, blank=lambda: (*_placeholders("Refused: see the message above"), ""),
    running=lambda: (*_placeholders("Running the time history…"), ""), waiting=lambda: (*_placeholders(), ""),
    render=lambda results: (*_figures(results[0]), _metrics(results[0]), settled(results[0])),
    notice=lambda results: "" if results[0]["success"] else results[0]["message"],
    outputs=[Output(ids.TH_SERIES, "figure"), Output(ids.TH_SPECTRUM, "figure"), Output(ids.TH_PHASE, "figure"),
             Output(ids.TH_METRICS, "children"), Output(ids.TH_SETTLED, "children")],
    triggers=[Input(ids.TH_V, "value"), Input(ids.TH_FZ, "value"), Input(ids.TH_AUTORUN, "n_intervals"),
              Input(ids.TH_KICK, "data")],
    states=[State(ids.TH_CONFIG, "value"), State(ids.TH_TEND, "value"), State(ids.TH_PSI0, "value"),
            State(ids.TH_LAT0, "value"), State(ids.design_store(ids.TH), "data")],
    download=jobs.Download(ids.TH_GROUP, "time_history", _csv_rows, single=True, filename=_file_stem))


def _margin_requests(config, V, fz_kn, design):
    return [{"config": config, "V": SPEED.read(V), "Fz": FZ.read(fz_kn), "direction": "psi", **design}]


def _kick(m, max_size):
    """An attractor's smallest yaw kick in words."""
    if not m["reached"]:
        return f"none up to {max_size:g} rad"
    if m["value"] == 0.0:
        return f"0 (already from {m['upper']:g})"
    return f"{m['value']:.4g} ± {m['tolerance']:.1g}"


def _check(m):
    c = m.get("check")
    if not c:
        return "–"
    sides = [f"{side['size']:.5g} → {side['mode']}" for side in (c["below"], c["above"]) if side is not None]
    return ("yes" if c["confirmed"] else "NO") + ": " + ", ".join(sides)


def margins_table(result):
    """Each attractor with its amplitudes, smallest yaw kick, its check and a button running from just above it."""
    rows = []
    for k, a in enumerate(result["attractors"]):
        m = a["min_disturbance"]
        what = ATTRACTOR_WORDS.get(a["mode"], a["mode"]) + (" (simulated)" if a["kind"] == "simulation" else "")
        if a["standard_start"]:
            what += " (the standard start ends here)"
        start = None if not m["reached"] else (STARTS["standard"][1] if m["value"] == 0.0 else m["upper"])
        button = "–" if start is None else html.Button(f"Run from psi0 = {start:.5g} rad", id=ids.thm_run(k),
                                                        className="secondary")
        equilibrium = a["mode"] == "equilibrium"
        rows.append([what, "0" if equilibrium else f"{a['amplitude']['psi']:.4g}",
                     "0" if equilibrium else f"{units.to_mm(a['amplitude']['lateral']):.4g}",
                     _kick(m, result["options"]["max_size"]), _check(m), button])
    saddles = "; ".join(f"{s['mode']}, psi {s['amplitude']['psi']:.4g} rad" for s in result["saddles"])
    note = (f"{style.CONFIG_LABELS[result['config']]} at V = {result['V']:g} m/s, Fz = {units.kn(result['Fz'])}: "
            f"straight rolling {'stable' if result['straight_rolling_stable'] else 'unstable'}"
            + (f"; saddle cycles between the basins: {saddles}" if saddles else "")
            + f". {result['runs']} runs in {result['elapsed_s']:.1f} s.")
    warnings = [html.P(f"Warning: {w}", className="hint") for w in result["warnings"]]
    return [html.P(note, className="hint"), ui.table(
        ["attractor", "max |psi| (rad)", "max |l_g delta| (mm)", "min yaw kick psi0 (rad)", "checked (psi0 → end)",
         "time history"], rows, ids.THM_SUMMARY), *warnings]


def _margin_csv(results):
    r = results[0]
    rows = [[a["mode"], a["kind"], a["amplitude"]["psi"], units.to_mm(a["amplitude"]["lateral"]), a["standard_start"],
             a["min_disturbance"]["value"], a["min_disturbance"]["tolerance"], a["min_disturbance"].get("lower"),
             a["min_disturbance"].get("upper"), (a["min_disturbance"]["check"] or {}).get("confirmed")]
            for a in r["attractors"]]
    return ["mode", "kind", "psi_amplitude_rad", "lateral_amplitude_mm", "standard_start", "min_yaw_kick_rad",
            "tolerance_rad", "lower_rad", "upper_rad", "confirmed"], rows


jobs.register(
    ids.THM, "margins", requests=_margin_requests, render=lambda results: (margins_table(results[0]),),
    outputs=[Output(ids.THM_TABLE, "children")],
    follow=[Input(ids.TH_CONFIG, "value"), Input(ids.TH_V, "value"), Input(ids.TH_FZ, "value")],
    states=[State(ids.design_store(ids.TH), "data")], stale=MARGINS_STALE,
    download=jobs.Download(ids.THM, "disturbance_margins", _margin_csv, single=True,
                           filename=lambda results: f"margins_{results[0]['config']}_V{results[0]['V']:g}_Fz"
                                                    f"{results[0]['Fz'] / units.KN:g}kN"),
    blank=lambda: (None,))


@dash.callback(Output(ids.TH_PSI0, "value", allow_duplicate=True), Output(ids.TH_LAT0, "value", allow_duplicate=True),
               Output(ids.TH_TEND, "value"), Output(ids.TH_CONFIG, "value"),
               Output(ids.TH_V, "value", allow_duplicate=True), Output(ids.TH_FZ, "value", allow_duplicate=True),
               Output(ids.TH_KICK, "data"), Input(ids.thm_run(dash.ALL), "n_clicks"),
               State(ids.THM.requests, "data"), State(ids.TH_TEND, "value"), State(ids.TH_CONFIG, "value"),
               State(ids.TH_V, "value"), State(ids.TH_FZ, "value"), prevent_initial_call=True)
def run_from_kick(clicks, requests, t_end, config, V, fz_kn):
    """A row's Run: the time history from just above that attractor's smallest yaw kick (the start of its check
    run), for at least as long as the check ran, at the margins' point (the boxes go back to it if they moved)."""
    nothing = (no_update,) * 7
    trigger = dash.ctx.triggered_id
    if not trigger or not any(clicks) or not isinstance(requests, list) or not requests:
        return nothing
    try:
        result = analyses.cached("margins", requests[0])
    except InvalidParameterError:
        return nothing
    k = trigger["index"]
    if result is None or not isinstance(k, int) or not 0 <= k < len(result["attractors"]):
        return nothing
    m = result["attractors"][k]["min_disturbance"]
    if not m["reached"]:
        return nothing
    psi0 = STARTS["standard"][1] if m["value"] == 0.0 else float(f"{m['upper']:.5g}")
    longest = result["options"]["t_max"]
    t = t_end if isinstance(t_end, (int, float)) and t_end >= longest else longest
    point = (result["config"], result["V"], result["Fz"] / units.KN)
    moved = [new if new != old else no_update for new, old in zip(point, (config, V, fz_kn), strict=True)]
    return psi0, 0.0, t, *moved, {"attractor": k, "psi0": psi0, "clicks": sum(c or 0 for c in clicks)}


# A run asked from the margins' table is drawn at the top of the page: it scrolls up there (the start in the boxes,
# the run's progress, then where it ends).
dash.clientside_callback(
    """
    function(kick) {
        if (kick) { window.scrollTo({top: 0, behavior: "smooth"}); }
    }
    """,
    Input(ids.TH_KICK, "data"), prevent_initial_call=True)


def _figures(result):
    s = result["series"]
    t = np.asarray(s["t"])
    title = f"{style.CONFIG_LABELS[result['config']]} at V = {result['V']:g} m/s, Fz = {units.kn(result['Fz'])}"
    has_nes = "psis" in s
    rows = 4 if has_nes else 3
    series = make_subplots(rows=rows, cols=1, shared_xaxes=True, vertical_spacing=0.05)
    colour = style.CONFIG_COLOURS[result["config"]]
    for row, values, name, c in ((1, s["psi"], "torsion psi (rad)", colour),
                                 (2, np.asarray(s["lateral"]) / units.MM, "lateral l_g delta (mm)", "#56B4E9"),
                                 (3, s["lam"], "tyre deformation lam (m)", "#CC79A7")):
        x, y = envelope(t, values)
        angle = row == 1
        series.add_scatter(x=x, y=y, name=name, line={"color": c, "width": 1}, row=row, col=1,
                           customdata=style.in_degrees(y) if angle else None,
                           hovertemplate=f"t %{{x:.4g}} s<br>{style.ANGLE_HOVER if angle else '%{y:.4g}'}"
                                         "<extra></extra>")
    if has_nes:
        x, y = envelope(t, np.asarray(s["psi"]) - np.asarray(s["psis"]))
        series.add_scatter(x=x, y=y, name="NES relative rotation psi - psis (rad)",
                           line={"color": "#D55E00", "width": 1}, row=4, col=1, customdata=style.in_degrees(y),
                           hovertemplate=f"t %{{x:.4g}} s<br>{style.ANGLE_HOVER}<extra></extra>")
        series.update_yaxes(title_text="psi - psis (rad)", row=4, col=1)
    series.update_layout(title=style.title(title), height=180 * rows + 110, template=style.TEMPLATE,
                         margin={**style.MARGIN, "l": 70}, legend={"orientation": "h", "y": -0.08})
    series.update_xaxes(title_text="time t (s)", row=rows, col=1)
    series.update_yaxes(title_text="psi (rad)", row=1, col=1)
    series.update_yaxes(title_text="l_g delta (mm)", row=2, col=1)
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
    where = "" if psi0 is None else f"From psi0 = {psi0:g} rad, l_g delta0 = {units.mm(lat0)} the run "
    verb = "settled on" if result["steady"] else "was still approaching (not yet steady at t_end)"
    f = result["frequency_hz"]
    amp = result["amplitude"]
    detail = "" if result["response_type"] == "Stable" else (
        f": max |psi| {amp['psi']:.3g} rad ({units.degrees(amp['psi'])}), max |l_g delta| {units.mm(amp['lateral'], 3)}"
        + ("" if f is None else f", {f:.2f} Hz"))
    text = f"{where or 'The run '}{verb} {MODE_WORDS.get(result['response_type'], result['response_type'])}{detail}"
    return text + (f" after {o['t_end']:g} s." if "t_end" in o else ".")


def _metrics(result):
    amp = result["amplitude"]
    f = result["frequency_hz"]
    items = [("response", result["response_type"] + ("" if result["steady"] else " (not yet steady)")),
             ("max |psi| (rad)", f"{amp['psi']:.4g}"), ("max |l_g delta| (mm)", f"{units.to_mm(amp['lateral']):.4g}"),
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
    moved = dash.ctx.triggered_id in (ids.TH_CONFIG, ids.TH_V, ids.TH_FZ)  # the map's note is of the point opened
    # the address keeps m (as the API), without float noise: 7 mm is lateral0=0.007
    lateral_m = float(f"{lateral0 * units.MM:.12g}") if isinstance(lateral0, (int, float)) else lateral0
    return {"config": config, "V": V, "Fz": fz, "t_end": t_end, "psi0": None if standard else psi0,
            "lateral0": None if standard else lateral_m, "run": None, **({"map_type": None} if moved else {})}


@dash.callback(Output(ids.TH_BISTABLE, "children"), Input(ids.TH_CONFIG, "value"), Input(ids.TH_V, "value"),
               Input(ids.TH_FZ, "value"), prevent_initial_call=True)
def forget_map_point(_config, _V, _fz):
    """The note on the map's point goes once another point is chosen."""
    return None
