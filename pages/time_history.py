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
from shimmy.service import schemas
from ui import components as ui
from ui import fields, formats, ids, jobs
from ui import style
from ui.series import DETAIL_SAMPLES, band, detail, last_cycles
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
#: The margins' kicks offered: a component (the rest as it was), a mix, or any direction (the smallest energy).
KICKS = {"psi": "yaw angle psi", "dpsi": "yaw rate dpsi", "delta": "lateral bending delta",
         "ddelta": "lateral bending rate ddelta", "mix": "a mix (typed beside)", "energy": "any (smallest energy)"}
#: The kick's direction in the table's note.
KICK_NOTE = {**KICKS, "mix": "the mix", "energy": "any direction (the smallest energy)"}
ORIGIN_WORDS = {"straight_rolling": "straight rolling", "standard_attractor": "the standard start's attractor"}
ATTRACTOR_WORDS = {"equilibrium": "straight rolling", "torsional": "torsional limit cycle",
                   "lateral": "lateral limit cycle", "both": "limit cycle, torsion and lateral bending both large"}


def _placeholders(text: str = WAITING) -> tuple:
    return (style.message_figure(text, 420), style.message_figure("The spectrum of the steady window appears here"),
            style.message_figure("The phase portrait appears here"), [])


def _start_of(psi0, lateral0) -> str:
    return next((k for k, (_, p, q) in STARTS.items() if p == psi0 and q == lateral0), "typed")


def layout(config: str | None = None, V: str | None = None, Fz: str | None = None, t_end: str | None = None,
           psi0: str | None = None, lateral0: str | None = None, run: str | None = None, map_type: str | None = None,
           exact_nes: str | None = None, **query):
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
            ui.field("NES torque", ui.nes_torque(ids.TH_EXACT, "exact" if exact_nes == "1" else "cubic")),
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
        dcc.Store(id=ids.TH_WINDOW),
        html.H2("Disturbance margins"),
        html.P("The attractors at this operating point (the stable equilibrium and limit cycles of the bifurcation "
               "diagram at its load, and any motion the runs from the standard and two large starts settle on), "
               "and for each the smallest kick that ends on it, found by a scan of kicks and bisection, each "
               "checked by two runs just below and just above it. The kick is added to straight rolling, or to "
               "the attractor the standard start reaches (at eight phases of its period, the best one then located "
               "between them); along one component, a mix you type (each component in its unit, such as "
               "psi=0.01,dpsi=0.2; the size is searched), or any direction (the smallest energy). A row's Run "
               "button runs the time history above from just above its kick: the gear ends on that attractor.",
               className="hint"),
        html.Div([ui.field("Kick along", dcc.Dropdown(id=ids.THM_DIRECTION, value="psi", clearable=False,
                                                      style={"width": "220px"},
                                                      options=[{"label": v, "value": k} for k, v in KICKS.items()])),
                  ui.field("Mix", dcc.Input(id=ids.THM_MIX, type="text", placeholder=schemas.MIX_EXAMPLE, debounce=True,
                                            disabled=True, style={"width": "190px"})),
                  ui.field("Kick added to", dcc.Dropdown(id=ids.THM_ORIGIN, value="straight_rolling", clearable=False,
                                                         style={"width": "290px"}, options=[
                                                             {"label": v, "value": k}
                                                             for k, v in ORIGIN_WORDS.items()])),
                  *jobs.controls(ids.THM, "Compute margins")], className="controls"),
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
    """What the page says when it was opened from a point the map shades Bistable or Latent."""
    if map_type == "Bistable":
        return ("The stability map shades this point Bistable: a torsional and a lateral limit cycle coexist, and "
                "which one the gear ends on depends on the kick. Run runs the start chosen above and the two large "
                "starts, and says which cycle each ends on; compute the disturbance margins below to see how large "
                "a yaw kick reaches each, and run from there.")
    if map_type == "Latent":
        return ("The stability map shades this point Latent: straight rolling is stable, and a limit cycle is stable "
                "beside it. The standard start decays; a large enough kick starts shimmy. Run runs the start chosen "
                "above and the two large starts, and says where each ends; compute the disturbance margins below to "
                "see how large a kick reaches the cycle, and run from there.")
    return None


def _requests(V, fz_kn, _autorun, _kick, config, t_end, psi0, lateral0, torque, bistable, design):
    """The run from the start in the boxes; at a point the map shades Bistable (its note shown), the runs
    from the two large starts too, so that the page says which attractor each start ends on."""
    t = T_END.read(t_end)
    # The series is thinned for a long run: every t_end the field allows can be drawn.
    series_dt = max(0.002, math.ceil(1000 * t / (settings.MAX_SERIES_POINTS - 1)) / 1000)
    common = {"config": config, "V": SPEED.read(V), "Fz": FZ.read(fz_kn), "t_end": t, "include_series": True,
              "series_dt": series_dt, **ui.exact_nes(config, torque), **design}
    kick = _kick if isinstance(_kick, dict) else {}
    if kick.get("x0") and kick.get("point") == [config, common["V"], common["Fz"]] and \
            (psi0, lateral0) == (kick.get("psi0"), kick.get("lateral0")) and kick.get("design") == _params_of(design):
        return [{**common, "x0": kick["x0"]}]  # a margin's kick, its point, design and boxes unchanged since
    starts = [(PSI0.read(psi0), LATERAL0.read(lateral0))]
    if bistable:
        large = [(PSI0.read(p), LATERAL0.read(q)) for key in ("torsional", "lateral") for _, p, q in [STARTS[key]]]
        starts += [start for start in large if start not in starts]  # in SI, as the requests
    return [{**common, "psi0": p, "lateral0": q} for p, q in starts]


def _starts_table(results):
    """Which attractor each start ended on (the runs of a Bistable map point)."""
    rows = []
    for r in results:
        amp, f = r["amplitude"], r["frequency_hz"]
        rows.append([f"psi0 = {r['start']['psi0']:g} rad, l_g delta0 = {units.mm(r['start']['lateral0'])}",
                     MODE_WORDS.get(r["response_type"], r["response_type"])
                     + ("" if r["steady"] else " (not yet steady)"),
                     f"{amp['psi']:.4g}", f"{amp['lateral'] / units.MM:.4g}", "–" if f is None else f"{f:.3f}"])
    return html.Div([
        html.P("The map shades this point Bistable; the runs from the start above and from the two large starts "
               "ended on:", className="hint"),
        ui.table(["start", "settled on", "max |psi| (rad)", "max |l_g delta| (mm)", "frequency (Hz)"], rows,
                 ids.TH_STARTS),
        html.P("The figures show the first run; choose another start above to draw it (from the cache at once).",
               className="hint")])


def _settled_all(results):
    first = settled(results[0])
    return first if len(results) == 1 else html.Div([html.Div(first), _starts_table(results)])


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
    render=lambda results: (*_figures(results[0]), _metrics(results[0]), _settled_all(results)),
    notice=ui.result_notice,
    outputs=[Output(ids.TH_SERIES, "figure"), Output(ids.TH_SPECTRUM, "figure"), Output(ids.TH_PHASE, "figure"),
             Output(ids.TH_METRICS, "children"), Output(ids.TH_SETTLED, "children")],
    triggers=[Input(ids.TH_V, "value"), Input(ids.TH_FZ, "value"), Input(ids.TH_AUTORUN, "n_intervals"),
              Input(ids.TH_KICK, "data")],
    states=[State(ids.TH_CONFIG, "value"), State(ids.TH_TEND, "value"), State(ids.TH_PSI0, "value"),
            State(ids.TH_LAT0, "value"), State(ids.TH_EXACT, "value"), State(ids.TH_BISTABLE, "children"),
            State(ids.design_store(ids.TH), "data")],
    download=jobs.Download(ids.TH_GROUP, "time_history", _csv_rows, single=True, filename=_file_stem))


def _margin_requests(config, V, fz_kn, direction, mix, origin, design):
    return [{"config": config, "V": SPEED.read(V), "Fz": FZ.read(fz_kn), "direction": direction,
             "mix": (mix or "") if direction == "mix" else None, "origin": origin, **design}]


@dash.callback(Output(ids.THM_MIX, "disabled"), Input(ids.THM_DIRECTION, "value"))
def mix_box(direction):
    """The mix is typed only for a kick along a mix."""
    return direction != "mix"


def _kick(m, max_size):
    """An attractor's smallest kick in words: its size and unit, with a mix the multiple of it, from an orbit the
    phase."""
    if not m["reached"]:
        return m.get("note") or f"none up to {max_size:g} rad"
    if m["value"] == 0.0:
        return f"0 (already from {m['upper']:.4g} {m['unit']})"
    text = (f"{formats.significant_or_whole(m['value'])} ± {formats.significant_or_whole(m['tolerance'], 2)} "
            f"{m['unit']}")
    if "factor" in m:
        text += f" ({m['factor']:.4g} × the mix)"
    if "phase" in m:
        text += f" at {m['phase']:.3g} of the period"
    return text


def _params_of(design) -> dict | None:
    """The complete parameters of the design store's data (as a result's ``params``), None if refused."""
    try:
        return schemas.design((design or {}).get("params") or {}, (design or {}).get("material"))
    except InvalidParameterError:
        return None


def _run_start(m):
    """The whole start of a row's run: that of its check run just above the smallest kick (None where no kick
    reaches the attractor)."""
    above = (m.get("check") or {}).get("above") if m["reached"] else None
    return None if above is None or "x0" not in above else above["x0"]


def _yaw_only(x0) -> bool:
    """A start the psi0 box says whole: a yaw angle, the rest at rest."""
    return all(x == 0.0 for x in x0[1:])


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
        x0 = _run_start(m)
        label = None if x0 is None else (f"Run from psi0 = {x0[0]:.5g} rad" if _yaw_only(x0) else
                                          "Run from this kick")
        button = "–" if x0 is None else html.Button(label, id=ids.thm_run(k), className="secondary")
        equilibrium = a["mode"] == "equilibrium"
        rows.append([what, "0" if equilibrium else f"{a['amplitude']['psi']:.4g}",
                     "0" if equilibrium else f"{units.to_mm(a['amplitude']['lateral']):.4g}",
                     _kick(m, result["options"]["max_size"]), _check(m), button])
    saddles = "; ".join(f"{s['mode']}, psi {s['amplitude']['psi']:.4g} rad" for s in result["saddles"])
    origin = result.get("origin") or {}
    kicked = (f"kicks along {KICK_NOTE.get(result['direction'], result['direction'])}"
              + (f" {result['options']['mix']}" if result["direction"] == "mix" else "")
              + (f" added to {origin['note']}" if origin.get("kind") == "standard_attractor" else
                 " from straight rolling" + (f" ({origin['note']})" if "standard start" in origin.get("note", "")
                                             else "")))
    note = (f"{style.CONFIG_LABELS[result['config']]} at V = {result['V']:g} m/s, Fz = {units.kn(result['Fz'])}: "
            f"{kicked}; straight rolling {'stable' if result['straight_rolling_stable'] else 'unstable'}"
            + (f"; saddle cycles between the basins: {saddles}" if saddles else "")
            + f". {result['runs']} runs in {result['elapsed_s']:.1f} s.")
    warnings = [html.P(f"Warning: {w}", className="hint") for w in result["warnings"]]
    return [html.P(note, className="hint"), ui.table(
        ["attractor", "max |psi| (rad)", "max |l_g delta| (mm)", "smallest kick", "checked (kick → end)",
         "time history"], rows, ids.THM_SUMMARY), *warnings]


def _margin_csv(results):
    """Each attractor with its smallest kick, in the kick's unit (rad, rad/s or J), the bracket, whether its check
    runs confirm it, with a mix the multiple of it, from an orbit the phase."""
    r = results[0]
    rows = []
    for a in r["attractors"]:
        m = a["min_disturbance"]
        rows.append([a["mode"], a["kind"], a["amplitude"]["psi"], units.to_mm(a["amplitude"]["lateral"]),
                     a["standard_start"], m["value"], m["tolerance"], m.get("lower"), m.get("upper"), m["unit"],
                     (m["check"] or {}).get("confirmed"), m.get("factor"), m.get("phase")])
    return ["mode", "kind", "psi_amplitude_rad", "lateral_amplitude_mm", "standard_start", "min_kick", "tolerance",
            "lower", "upper", "unit", "confirmed", "times_the_mix", "phase_of_period"], rows


jobs.register(
    ids.THM, "margins", requests=_margin_requests, render=lambda results: (margins_table(results[0]),),
    outputs=[Output(ids.THM_TABLE, "children")],
    follow=[Input(ids.TH_CONFIG, "value"), Input(ids.TH_V, "value"), Input(ids.TH_FZ, "value"),
            Input(ids.THM_DIRECTION, "value"), Input(ids.THM_MIX, "value"), Input(ids.THM_ORIGIN, "value")],
    states=[State(ids.design_store(ids.TH), "data")], stale=MARGINS_STALE,
    download=jobs.Download(ids.THM, "disturbance_margins", _margin_csv, single=True,
                           filename=lambda results: f"margins_{results[0]['config']}_V{results[0]['V']:g}_Fz"
                                                    f"{results[0]['Fz'] / units.KN:g}kN_{results[0]['direction']}"),
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
    x0 = _run_start(result["attractors"][k]["min_disturbance"])
    if x0 is None:
        return nothing
    longest = result["options"]["t_max"]
    t = t_end if isinstance(t_end, (int, float)) and t_end >= longest else longest
    point = (result["config"], result["V"], result["Fz"] / units.KN)
    moved = [new if new != old else no_update for new, old in zip(point, (config, V, fz_kn), strict=True)]
    kick = {"attractor": k, "clicks": sum(c or 0 for c in clicks)}
    if _yaw_only(x0):  # the boxes say the whole start
        psi0 = float(f"{x0[0]:.5g}")
        return psi0, 0.0, t, *moved, {**kick, "psi0": psi0}
    # a start the boxes cannot say: run from x0 while the boxes hold the values set here (its psi and l_g delta)
    psi0, lateral0 = float(f"{x0[0]:.6g}"), float(f"{result['params']['l_g'] * x0[2] / units.MM:.6g}")
    return psi0, lateral0, t, *moved, {**kick, "x0": x0, "psi0": psi0, "lateral0": lateral0,
                                       "point": [result["config"], result["V"], result["Fz"]],
                                       "design": result["params"]}


# A run asked from the margins' table is drawn at the top of the page: it scrolls up there (the start in the boxes,
# the run's progress, then where it ends).
dash.clientside_callback(
    """
    function(kick) {
        if (kick) { window.scrollTo({top: 0, behavior: "smooth"}); }
    }
    """,
    Input(ids.TH_KICK, "data"), prevent_initial_call=True)


#: Where a run's series traces are (three per row: the band's top, its bottom filled to the top, the
#: detail line), for the detail window's redraw.
PER_ROW = 3


def _rows(result) -> list[tuple[str, list[float], str, str]]:
    """(legend name, values, colour, axis title) of each row of the series figure."""
    s = result["series"]
    rows = [("torsion psi (rad)", s["psi"], style.CONFIG_COLOURS[result["config"]], "psi (rad)"),
            ("lateral l_g delta (mm)", list(np.asarray(s["lateral"]) / units.MM), "#56B4E9", "l_g delta (mm)"),
            ("tyre deformation lam (m)", s["lam"], "#CC79A7", "lam (m)")]
    if "psis" in s:
        rows.append(("NES relative rotation psi - psis (rad)", list(np.asarray(s["psi"]) - np.asarray(s["psis"])),
                     "#D55E00", "psi - psis (rad)"))
    return rows


def _translucent(colour: str, alpha: float = 0.3) -> str:
    r, g, b = (int(colour[k:k + 2], 16) for k in (1, 3, 5))
    return f"rgba({r},{g},{b},{alpha})"


def _series_figure(result):
    """The run's rows against time: the whole run as a band (each time bucket's lowest and highest
    sample; a line through them would be a solid block with aliasing stripes at 10-16 Hz), every sample
    as a line in the window shown (by default the last cycles; the range slider below moves it over
    the whole run, and the line follows it from the cached result)."""
    t = np.asarray(result["series"]["t"])
    title = f"{style.CONFIG_LABELS[result['config']]} at V = {result['V']:g} m/s, Fz = {units.kn(result['Fz'])}"
    rows = _rows(result)
    fig = make_subplots(rows=len(rows), cols=1, shared_xaxes=True, vertical_spacing=0.04)
    t0, t1 = last_cycles(float(t[-1]), result["frequency_hz"])
    for k, (name, values, colour, axis) in enumerate(rows, start=1):
        mid, low, high = band(t, values, min_span=1.25 / result["frequency_hz"] if result["frequency_hz"] else 0.0)
        fig.add_scatter(x=mid, y=high, mode="lines", line={"width": 0, "color": colour}, hoverinfo="skip",
                        showlegend=False, legendgroup=name, row=k, col=1)
        fig.add_scatter(x=mid, y=low, mode="lines", line={"width": 0, "color": colour}, fill="tonexty",
                        fillcolor=_translucent(colour), hoverinfo="skip", name=f"{name}: range over the run",
                        showlegend=k == 1, legendgroup="band", row=k, col=1)
        x, y = detail(t, values, t0, t1) or ([], [])
        angle = axis.endswith("(rad)")  # psi and psi - psis: degrees on hover
        fig.add_scatter(x=list(map(float, x)), y=list(map(float, y)), mode="lines",  # lists, as the redraw sends
                        line={"width": 1.2, "color": colour}, name=name, row=k, col=1,
                        customdata=style.in_degrees(y) if angle else None,
                        hovertemplate=f"t %{{x:.4g}} s<br>{style.ANGLE_HOVER if angle else '%{y:.4g}'}"
                                      "<extra></extra>")
        fig.update_yaxes(title_text=axis, row=k, col=1)
    fig.update_layout(title=style.title(title), height=170 * len(rows) + 170, template=style.TEMPLATE,
                      margin={**style.MARGIN, "l": 70}, legend={"orientation": "h", "y": -0.22},
                      annotations=[_zoom_note(False)])  # no uirevision: the redraw itself carries the window
    fig.update_xaxes(range=[t0, t1])
    fig.update_xaxes(title_text="time t (s): the slider below moves the window over the whole run",
                     rangeslider={"visible": True, "thickness": 0.07}, row=len(rows), col=1)
    return fig


def _zoom_note(visible: bool) -> dict:
    return {"text": f"more than {DETAIL_SAMPLES} samples in this window: the band only; zoom in to see every sample",
            "xref": "paper", "yref": "paper", "x": 1, "y": 1.0, "xanchor": "right", "yanchor": "bottom",
            "showarrow": False, "font": {"size": 11, "color": "#555"}, "visible": visible}


def _window(relayout, t_end: float) -> tuple[float, float] | None:
    """The time window a zoom, a pan or the range slider asked for (None if the event is not one)."""
    if not relayout:
        return None
    if any(k.endswith(".autorange") and v for k, v in relayout.items() if k.startswith("xaxis")):
        return 0.0, t_end
    for key, value in relayout.items():
        if key.startswith("xaxis") and key.endswith(".range") and isinstance(value, list) and len(value) == 2:
            return float(value[0]), float(value[1])
    ends = {k.split(".")[0]: [relayout.get(f"{k.split('.')[0]}.range[0]"), relayout.get(f"{k.split('.')[0]}.range[1]")]
            for k in relayout if k.startswith("xaxis") and ".range[" in k}
    for lo, hi in ends.values():
        if lo is not None and hi is not None:
            return float(lo), float(hi)
    return None


# Only a change of the time window reaches the server: Plotly also reports a redraw's autosize, and a
# second call of the callback in flight would make Dash drop the first one's answer (the window's line).
dash.clientside_callback(
    """
    function(relayout) {
        const keys = Object.keys(relayout || {});
        const window = keys.some(k => k.startsWith('xaxis') && (k.includes('.range') || k.endsWith('.autorange')));
        return window ? relayout : window_no_update();
        function window_no_update() { return dash_clientside.no_update; }
    }
    """,
    Output(ids.TH_WINDOW, "data"), Input(ids.TH_SERIES, "relayoutData"), prevent_initial_call=True)


@dash.callback(Output(ids.TH_SERIES, "figure", allow_duplicate=True), Input(ids.TH_WINDOW, "data"),
               State(ids.TH_GROUP.requests, "data"), prevent_initial_call=True)
def follow_window(relayout, requests):
    """Every sample of the window shown, from the cached result (a zoom, a pan, the range slider)."""
    if not requests:
        return no_update
    try:
        result = analyses.cached("simulate", requests[0])
    except InvalidParameterError:
        return no_update
    if result is None or "series" not in result:
        return no_update
    t = np.asarray(result["series"]["t"])
    window = _window(relayout, float(t[-1]))
    if window is None:
        return no_update
    patched = dash.Patch()
    too_many = False
    for k, (_, values, _, axis) in enumerate(_rows(result)):
        shown = detail(t, values, *window)
        too_many = too_many or shown is None
        x, y = shown if shown is not None else ([], [])
        patched["data"][PER_ROW * k + 2]["x"] = list(map(float, x))
        patched["data"][PER_ROW * k + 2]["y"] = list(map(float, y))
        if axis.endswith("(rad)"):
            patched["data"][PER_ROW * k + 2]["customdata"] = style.in_degrees(list(map(float, y)))
    patched["layout"]["annotations"][0]["visible"] = too_many
    for k in range(len(_rows(result))):  # the figure itself says the window shown: the redraw keeps it
        axis = patched["layout"][f"xaxis{k + 1 if k else ''}"]
        axis["autorange"] = False
        axis["range"] = [float(window[0]), float(window[1])]
    return patched


def _figures(result):
    s = result["series"]
    colour = style.CONFIG_COLOURS[result["config"]]
    series = _series_figure(result)
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
    if "x0" in start:
        state = ", ".join(f"{name} {x:.4g} {unit}" for name, unit, x in zip(STATE_NAMES, STATE_UNITS, start["x0"]))
        where = f"From the margins' kick ({state}) the run "
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
        items.append(("NES torque", "exact" if result["options"].get("exact_nes") else "cubic fit"))
    return [html.Div([html.Div(v, className="value"), html.Div(k, className="label")], className="metric")
            for k, v in items]


@dash.callback(Output(ids.URL_UPDATE, "data", allow_duplicate=True),
               Input(ids.TH_CONFIG, "value"), Input(ids.TH_V, "value"), Input(ids.TH_FZ, "value"), Input(ids.TH_TEND,
                                                                                                         "value"),
               Input(ids.TH_PSI0, "value"), Input(ids.TH_LAT0, "value"), Input(ids.TH_EXACT, "value"),
               prevent_initial_call=True)
def remember(config, V, fz, t_end, psi0, lateral0, torque):
    standard = psi0 == STARTS["standard"][1] and lateral0 == STARTS["standard"][2]
    moved = dash.ctx.triggered_id in (ids.TH_CONFIG, ids.TH_V, ids.TH_FZ)  # the map's note is of the point opened
    # the address keeps m (as the API), without float noise: 7 mm is lateral0=0.007
    lateral_m = float(f"{lateral0 * units.MM:.12g}") if isinstance(lateral0, (int, float)) else lateral0
    return {"config": config, "V": V, "Fz": fz, "t_end": t_end, "psi0": None if standard else psi0,
            "lateral0": None if standard else lateral_m, "exact_nes": "1" if torque == "exact" else None, "run": None,
            **({"map_type": None} if moved else {})}


@dash.callback(Output(ids.TH_BISTABLE, "children"), Input(ids.TH_CONFIG, "value"), Input(ids.TH_V, "value"),
               Input(ids.TH_FZ, "value"), prevent_initial_call=True)
def forget_map_point(_config, _V, _fz):
    """The note on the map's point goes once another point is chosen."""
    return None
