"""Ground runs: a take-off, landing roll, taxi or any (t, V, Fz) table for the four configurations, with a yaw kick
(a runway joint, a touchdown with yaw) if asked."""

from __future__ import annotations

import re

import dash
from dash import Input, Output, State, dash_table, dcc, html, no_update
from plotly.subplots import make_subplots

from shimmy.continuation.kinds import PointKind
from shimmy.errors import InvalidParameterError
import shimmy.model.units as units
from shimmy.model.parameters import FZ_RANGE, V_RANGE
from shimmy.service import analyses
from ui import components as ui
from ui import fields, formats, ids, jobs, markers
from ui.fields import Column, Quantity, SignedQuantity
from ui import style
from ui.layout import page

dash.register_page(__name__, path="/ground-run", name="Ground run", order=4.5)

CONFIGS = ui.CONFIGS
#: The scenarios (a profile preset with a kick) by name: label, preset, kick fields, description.
SCENARIOS = analyses.kick_presets()
PRESET_LABELS = {"takeoff": "Take-off", "landing": "Landing roll", "taxi": "Taxi",
                 **{name: s["label"] for name, s in SCENARIOS.items()}}
KICK_LABELS = {"none": "none", "psi": "yaw angle psi (rad)", "dpsi": "yaw rate dpsi (rad/s)"}
AT_LABELS = {"time": "at a time (s)", "speed": "at a speed (m/s)"}
SERIES_DT = 0.02  # s: the envelopes are smooth; 1500 points per configuration for a 30 s take-off
TABLE_STYLE = {"style_table": {"maxHeight": "290px", "overflowY": "auto"},
               "style_cell": {"fontFamily": "inherit", "fontSize": "13px", "padding": "3px 8px", "textAlign": "left",
                              "whiteSpace": "normal", "height": "auto"},
               "style_header": {"backgroundColor": "#eef2f8", "fontWeight": "600"}}


#: What the plane shows until the runs are drawn (the page opens on the cached runs, else on this).
WAITING = "Press Run: the four configurations' runs through this profile are drawn here."
RUNNING = "Running the four configurations through the profile (progress above the tables)…"


def _placeholders(text: str) -> tuple:
    """The plane saying ``text`` and the two envelope figures empty (no bare axes), for the four outputs."""
    empty = style.message_figure("", 40)
    return style.message_figure(text), empty, empty, ""

PSI_THR = Quantity("ground_run", "psi_threshold", "the shimmy threshold |psi|", "rad")
LAT_THR = Quantity("ground_run", "lateral_threshold", "the shimmy threshold |l_g delta|", "mm", units.MM)
#: The units the settings table shows a preset's setting in where they are not the package's: SI units per unit.
SHOWN_UNITS = {"N": ("kN", units.KN)}
#: The profile table's columns as the page shows them (the run refuses the same in SI units, by row).
PROFILE_COLUMNS = [Column("t", "t", "s", -1e5, 1e5), Column("V", "V", "m/s", *V_RANGE),
                   Column("Fz", "Fz", "kN", FZ_RANGE[0] / units.KN, FZ_RANGE[1] / units.KN)]
#: A cell keeps what was typed (a number column would drop text silently): the page refuses it, saying why.
KEEP_TYPED = {"action": "coerce", "failure": "accept"}
#: The kick's size as its box reads it, per kind: within that kind's range (rad for psi, rad/s for dpsi).
KICK_SIZES = {kind: SignedQuantity("ground_run", "kick_size", f"the kick size ({k['what']} {kind})", k["unit"],
                                   largest=k["largest"]) for kind, k in analyses.kick_kinds().items()}
#: When the kick comes, as its box reads it: a time on the profile's clock or a speed.
KICK_MOMENTS = {"time": Quantity("ground_run", "kick_at_time", "the kick's time", "s"),
                "speed": Quantity("ground_run", "kick_at_speed", "the kick's speed", "m/s")}


def layout(preset: str | None = None, config: str | None = None, psi_thr: str | None = None,
           lat_thr: str | None = None, kick: str | None = None, kick_size: str | None = None,
           kick_at: str | None = None, kick_when: str | None = None, **query):
    preset, bad_preset = fields.choice("preset", preset, list(PRESET_LABELS), "takeoff", "a preset")
    config, bad_config = fields.choice("config", config, list(CONFIGS), "original", "a configuration")
    psi_value, bad_psi = PSI_THR.from_url("psi_thr", psi_thr, 0.01)
    lat_value, bad_lat = LAT_THR.from_url("lat_thr", lat_thr, 1.0)
    default = _scenario_boxes(preset)
    kick, bad_kick = fields.choice("kick", kick, list(KICK_LABELS), default[0], "a kick")
    kick_at, bad_at = fields.choice("kick_at", kick_at, list(AT_LABELS), default[2], "time or speed")
    size_value, bad_size = (KICK_SIZES[kick].from_url("kick_size", kick_size, default[1]) if kick in KICK_SIZES
                            else (default[1], None))
    when_value, bad_when = KICK_MOMENTS[kick_at].from_url("kick_when", kick_when, default[3])
    address = " ".join(m for m in (bad_preset, bad_config, bad_psi, bad_lat, bad_kick, bad_at) if m)
    plane_figure, by_time, by_speed, _ = _placeholders(WAITING)
    return page(
        query, ids.GR,
        ui.header("Ground run", "The gear through a take-off, a landing roll or a taxi: forward speed and nose-gear "
                  "load change with time along a profile (a preset with its stated assumptions, or your own table, "
                  "linearly interpolated). Envelopes of the torsional and lateral amplitudes, time in shimmy, peaks, "
                  "where the run crosses the Hopf curves, and how long shimmy takes to build up after it does, for "
                  "the four configurations."),
        html.Div([
            ui.field("Profile preset", dcc.Dropdown(id=ids.GR_PRESET, value=preset, clearable=False,
                                                    style={"width": "160px"},
                                                    options=[{"label": v, "value": k}
                                                             for k, v in PRESET_LABELS.items()])),
            ui.field("Map and curves of", ui.configurations(ids.GR_CONFIG, config)),
            PSI_THR.field("Shimmy threshold |psi| (rad)", ids.GR_PSI_THR, psi_value, bad_psi),
            LAT_THR.field("Shimmy threshold |l_g delta| (mm)", ids.GR_LAT_THR, lat_value, bad_lat),
            ui.field("NES torque", ui.nes_torque(ids.GR_EXACT)),
            *jobs.controls(ids.GR_GROUP, "Run"),
        ], className="controls"),
        html.Div([
            ui.field("Kick (a jump of)", dcc.Dropdown(id=ids.GR_KICK, value=kick, clearable=False,
                                                      style={"width": "190px"},
                                                      options=[{"label": v, "value": k}
                                                               for k, v in KICK_LABELS.items()])),
            KICK_SIZES["psi"].field("Kick size (rad for psi, rad/s for dpsi)", ids.GR_KICK_SIZE, size_value, bad_size),
            ui.field("Kick comes", dcc.Dropdown(id=ids.GR_KICK_AT, value=kick_at, clearable=False,
                                                style={"width": "160px"},
                                                options=[{"label": v, "value": k} for k, v in AT_LABELS.items()])),
            KICK_MOMENTS["time"].field("Kick time (s) or speed (m/s)", ids.GR_KICK_WHEN, when_value, bad_when),
            html.P(_scenario_note(preset), id=ids.GR_KICK_NOTE, className="hint"),
        ], className="controls"),
        html.Div([
            html.Div([
                html.H2("Preset settings"),
                dash_table.DataTable(id=ids.GR_SETTINGS, editable=True, **TABLE_STYLE, columns=[
                    {"name": "setting", "id": "name", "editable": False},
                    {"name": "value", "id": "value", "type": "numeric", "on_change": KEEP_TYPED},
                    {"name": "unit", "id": "unit", "editable": False},
                    {"name": "range", "id": "range", "editable": False},
                    {"name": "meaning", "id": "description", "editable": False}]),
                html.Div(id=ids.GR_SETTINGS_ERROR, className="error", role="alert"),  # at the settings
                html.P(id=ids.GR_ASSUMPTIONS, className="hint"),
            ]),
            html.Div([
                html.H2("Profile table"),
                dash_table.DataTable(id=ids.GR_TABLE, editable=True, row_deletable=True, **TABLE_STYLE, columns=[
                    {"name": f"{c.id} ({c.unit})", "id": c.id, "type": "numeric", "on_change": KEEP_TYPED}
                    for c in PROFILE_COLUMNS]),
                html.Div(id=ids.GR_TABLE_ERROR, className="error field-error", role="alert"),  # at the cells
                html.Div([html.Button("Add row", id=ids.GR_ADD_ROW, className="secondary"),
                          html.Button("Back to the preset", id=ids.GR_RESET, className="secondary")],
                         className="downloads"),
                html.P(id=ids.GR_SOURCE, className="hint"),
            ]),
        ], className="gr-tables"),  # side by side where the settings' meanings fit, else stacked
        html.Div(address, id=ids.GR_ADDRESS, className="error", role="alert"),  # what of the address is unusable
        html.Div(id=ids.GR_GROUP.error, className="error", role="alert"),
        html.Div(id=ids.GR_SUMMARY),
        ui.graph(ids.GR_PLANE, figure=plane_figure),
        ui.graph(ids.GR_TIME, figure=by_time),
        ui.graph(ids.GR_SPEED, figure=by_speed),
        ui.downloads(ids.GR_GROUP),
        *jobs.stores(ids.GR_GROUP),
        dcc.Store(id=ids.GR_PRESET_ROWS),
    )


def _profile_preset(name: str) -> str:
    """The profile preset of a preset or a scenario."""
    return SCENARIOS[name]["preset"] if name in SCENARIOS else name


def _scenario_boxes(name: str) -> tuple[str, float | None, str, float | None]:
    """(kick, size, at, time or speed) the kick boxes show for preset ``name``: a scenario's kick, else none."""
    if name not in SCENARIOS:
        return "none", None, "time", None
    k = SCENARIOS[name]["kick"]
    at = "time" if k.get("kick_at_time") is not None else "speed"
    return k["kick"], k["kick_size"], at, k["kick_at_time"] if at == "time" else k["kick_at_speed"]


def _scenario_note(name: str) -> str:
    return (f"{PRESET_LABELS[name]}: {SCENARIOS[name]['description']}. The kick boxes hold its kick; change them "
            "to ask another.") if name in SCENARIOS else ""


@dash.callback(Output(ids.GR_KICK, "value"), Output(ids.GR_KICK_SIZE, "value"), Output(ids.GR_KICK_AT, "value"),
               Output(ids.GR_KICK_WHEN, "value"), Output(ids.GR_KICK_NOTE, "children"), Input(ids.GR_PRESET, "value"),
               prevent_initial_call=True)
def scenario_kick(name):
    """A scenario puts its kick in the boxes; a plain preset leaves them as they are."""
    if name not in SCENARIOS:
        return no_update, no_update, no_update, no_update, ""
    return (*_scenario_boxes(name), _scenario_note(name))


def kick_size_refusal(kind, value) -> str:
    """Why the size box's value is refused for a kick of ``kind`` (its unit and range), '' if it is not."""
    return fields.refusal(KICK_SIZES[kind].read, value) if kind in KICK_SIZES else ""


def kick_moment_refusal(kind, at, value) -> str:
    """Why the time or speed box's value is refused, '' if it is not (or there is no kick)."""
    return fields.refusal(KICK_MOMENTS[at].read, value) if kind in KICK_SIZES and at in KICK_MOMENTS else ""


# The kick's boxes refuse at the field as the thresholds do, by the rules of the kick's kind and instant.
dash.callback(Output(fields.error_id(ids.GR_KICK_SIZE), "children"), Input(ids.GR_KICK, "value"),
              Input(ids.GR_KICK_SIZE, "value"), prevent_initial_call=True)(kick_size_refusal)
dash.callback(Output(fields.error_id(ids.GR_KICK_WHEN), "children"), Input(ids.GR_KICK, "value"),
              Input(ids.GR_KICK_AT, "value"), Input(ids.GR_KICK_WHEN, "value"),
              prevent_initial_call=True)(kick_moment_refusal)


def _shown(unit: str) -> tuple[str, float]:
    """(unit shown, SI units per unit shown) of a preset setting in ``unit``."""
    return SHOWN_UNITS.get(unit, (unit, 1.0))


def _in_kn(text: str) -> str:
    """A message of the package's, with its loads (N) written in kN as the table shows them."""
    return re.sub(r"(-?\d+(?:\.\d+)?(?:e[+-]?\d+)?) N\b", lambda m: units.kn(float(m[1])), text)


def _setting_refusal(exc: InvalidParameterError, rows) -> str:
    """A rule across settings refused (the package's message in N), written as the table shows it: a load
    as typed, in kN."""
    name = exc.field.removeprefix("preset_options.")
    row = next((r for r in rows or [] if r.get("name") == name), None)
    if row is not None and row.get("unit") == "kN":
        return f"{name} = {row.get('value')} kN is refused; allowed: {_in_kn(exc.allowed)}"
    return _in_kn(str(exc))


@dash.callback(Output(ids.GR_SETTINGS, "data"), Input(ids.GR_PRESET, "value"))
def preset_settings(name):
    """The preset's settings at their defaults (a new preset starts from its documented defaults), loads in kN."""
    rows = []
    for f in analyses.preset_profile(_profile_preset(name))["fields"]:
        unit, scale = _shown(f["unit"])
        rows.append({"name": f["name"], "value": f["default"] / scale, "unit": unit,
                     "range": f"{f['low'] / scale:g} – {f['high'] / scale:g}", "description": f["description"]})
    return rows


def settings_refusals(rows) -> list[tuple[int, str, str]]:
    """(row, "value", why) of each setting typed outside its range or not a number, in the table's unit."""
    out = []
    for i, r in enumerate(rows or []):
        low, high = (float(x) for x in r["range"].split(" – "))
        try:
            fields.typed_number(r["name"], r["name"], r.get("value"), low, high, r["unit"])
        except InvalidParameterError as exc:
            out.append((i, "value", str(exc)))
    return out


@dash.callback(Output(ids.GR_TABLE, "data"), Output(ids.GR_PRESET_ROWS, "data"), Output(ids.GR_ASSUMPTIONS, "children"),
               Output(ids.GR_SETTINGS_ERROR, "children"),
               Input(ids.GR_SETTINGS, "data"), Input(ids.GR_RESET, "n_clicks"), State(ids.GR_PRESET, "value"))
def preset_table(settings, _reset, name):
    """The preset's table for its settings (shown in the profile table, which may then be edited); a setting
    refused at its cell, in the table's unit (and the rules across settings, loads in kN)."""
    if not settings:
        return no_update, no_update, no_update, no_update
    refused = settings_refusals(settings)
    if refused:
        return no_update, no_update, no_update, "; ".join(why for _, _, why in refused)
    try:
        profile = analyses.preset_profile(_profile_preset(name), _settings(settings))
    except InvalidParameterError as exc:
        return no_update, no_update, no_update, _setting_refusal(exc, settings)
    rows = [{"t": round(t, 4), "V": round(v, 4), "Fz": round(f / units.KN, 3)} for t, v, f in profile["rows"]]
    return rows, rows, profile["assumptions"], ""


@dash.callback(Output(ids.GR_SETTINGS, "style_data_conditional"), Input(ids.GR_SETTINGS, "data"))
def mark_settings(settings):
    return fields.cell_styles(settings_refusals(settings))


@dash.callback(Output(ids.GR_TABLE_ERROR, "children"), Output(ids.GR_TABLE, "style_data_conditional"),
               Input(ids.GR_TABLE, "data"))
def check_table(rows):
    """Each cell typed outside its column's range, or not a number, refused at the table, in its unit."""
    refused = fields.cell_refusals(rows, PROFILE_COLUMNS)
    return "; ".join(why for _, _, why in refused), fields.cell_styles(refused)


fields.check(ids.GR_PSI_THR, PSI_THR)
fields.check(ids.GR_LAT_THR, LAT_THR)


@dash.callback(Output(ids.GR_TABLE, "data", allow_duplicate=True), Input(ids.GR_ADD_ROW, "n_clicks"),
               State(ids.GR_TABLE, "data"), prevent_initial_call=True)
def add_row(_n, rows):
    rows = list(rows or [])
    last = rows[-1] if rows else {"t": 0.0, "V": 10.0, "Fz": 150.0}
    t = last.get("t") if isinstance(last.get("t"), (int, float)) else 0.0
    return [*rows, {"t": t + 1.0, "V": last.get("V"), "Fz": last.get("Fz")}]


@dash.callback(Output(ids.GR_SOURCE, "children"), Input(ids.GR_TABLE, "data"), State(ids.GR_PRESET_ROWS, "data"),
               State(ids.GR_PRESET, "value"))
def source(rows, preset_rows, name):
    if rows and preset_rows and _same(rows, preset_rows):
        what = PRESET_LABELS[_profile_preset(name)].lower()
        return f"Runs the {what} preset ({len(rows)} points). Edit a cell to run your own table."
    return f"Runs your table ({len(rows or [])} points; t in s, V in m/s, Fz in kN, linearly interpolated)."


def _settings(rows) -> dict:
    """The settings in the package's units (loads in N), for the request."""
    out = {}
    for r in rows or []:
        value = r.get("value")
        if value in (None, ""):
            continue
        scale = next((s for u, s in SHOWN_UNITS.values() if u == r.get("unit")), 1.0)
        out[r["name"]] = value * scale if isinstance(value, (int, float)) and not isinstance(value, bool) else value
    return out


def _same(rows, preset_rows) -> bool:
    if len(rows) != len(preset_rows):
        return False
    for a, b in zip(rows, preset_rows, strict=True):
        for k in ("t", "V", "Fz"):
            if not isinstance(a.get(k), (int, float)) or abs(a[k] - b[k]) > 1e-9 * max(1.0, abs(b[k])):
                return False
    return True


def _kick(kind, size, at, when) -> dict:
    """The kick's request fields from its boxes (none: no kick), each refused in its box's unit."""
    if kind not in KICK_SIZES:
        return {}
    moment = KICK_MOMENTS[at].read(when)
    return {"kick": kind, "kick_size": KICK_SIZES[kind].read(size),
            ("kick_at_time" if at == "time" else "kick_at_speed"): moment}


def _requests(config, name, settings, rows, preset_rows, psi_thr, lat_thr, torque, kind, size, at, when, design):
    """One request per configuration, the one whose map is drawn first."""
    if rows and not (preset_rows and _same(rows, preset_rows)):
        profile = {"profile": [[r.get("t"), r.get("V"), _newtons(r.get("Fz"))] for r in rows]}
    else:
        profile = {"preset": _profile_preset(name), "preset_options": _settings(settings)}
    psi, lateral = PSI_THR.read(psi_thr), LAT_THR.read(lat_thr)  # refused in the box's unit, never defaulted
    kick = _kick(kind, size, at, when)
    order = [config] + [c for c in CONFIGS if c != config]
    return [{"config": c, **profile, "psi_threshold": psi, "lateral_threshold": lateral, "series_dt": SERIES_DT,
             "hopf_curves": True, **ui.exact_nes(c, torque), **kick, **design} for c in order]


def _newtons(fz_kn):
    return fz_kn * units.KN if isinstance(fz_kn, (int, float)) and not isinstance(fz_kn, bool) else fz_kn


#: The downloaded columns: the result's key, the column's name with its unit, SI units per unit written.
CSV_COLUMNS = (("t", "t_s", 1.0), ("V", "V_m_s", 1.0), ("Fz", "Fz_kN", units.KN), ("psi", "psi_rad", 1.0),
               ("lateral", "lateral_mm", units.MM), ("envelope_psi", "envelope_psi_rad", 1.0),
               ("envelope_lateral", "envelope_lateral_mm", units.MM))


def _csv_rows(results):
    rows = [[r["config"], *values] for r in sorted(results, key=lambda r: CONFIGS.index(r["config"]))
            for values in zip(*([v / scale for v in r[k]] if scale != 1.0 else r[k] for k, _, scale in CSV_COLUMNS),
                              strict=True)]
    return ["config", *(name for _, name, _ in CSV_COLUMNS)], rows


def _file_stem(results):
    return f"ground_run_{results[0]['profile']['name']}"


jobs.register(
    ids.GR_GROUP, "ground_run", requests=_requests, notice=ui.result_notice, running=lambda: _placeholders(RUNNING),
    waiting=lambda: _placeholders(WAITING),
    render=lambda results: (plane(results[0]), envelopes(results, "t"), envelopes(results, "V"), summary(results)),
    outputs=[Output(ids.GR_PLANE, "figure"), Output(ids.GR_TIME, "figure"), Output(ids.GR_SPEED, "figure"),
             Output(ids.GR_SUMMARY, "children")],
    follow=[Input(ids.GR_CONFIG, "value")],  # which of the four runs' Hopf curves are drawn: starts nothing
    states=[State(ids.GR_PRESET, "value"), State(ids.GR_SETTINGS, "data"), State(ids.GR_TABLE, "data"),
            State(ids.GR_PRESET_ROWS, "data"), State(ids.GR_PSI_THR, "value"), State(ids.GR_LAT_THR, "value"),
            State(ids.GR_EXACT, "value"), State(ids.GR_KICK, "value"), State(ids.GR_KICK_SIZE, "value"),
            State(ids.GR_KICK_AT, "value"), State(ids.GR_KICK_WHEN, "value"), State(ids.design_store(ids.GR), "data")],
    lock=[ids.GR_PRESET],
    download=jobs.Download(ids.GR_GROUP, "ground_run", _csv_rows, filename=_file_stem))


def _ordered(results):
    return sorted(results, key=lambda r: CONFIGS.index(r["config"]))


def plane(result):
    """The trajectory on the (V, Fz) plane over the configuration's Hopf curves, its shimmy stretches and crossings."""
    config = result["config"]
    label, colour = style.CONFIG_LABELS[config], style.CONFIG_COLOURS[config]
    fig = style.figure(f"Trajectory over the Hopf curves of {label}",
                       "forward speed V (m/s)", "nose-gear load Fz (kN)", height=460)
    for i, curve in enumerate(result.get("hopf_curves") or []):
        fig.add_scatter(x=curve["V"], y=[f / units.KN for f in curve["Fz"]], mode="lines", name=f"Hopf curve ({label})",
                        legendgroup="hopf", showlegend=i == 0, line={"color": "#888", "width": 2},
                        hovertemplate="Hopf curve<br>V %{x:.4g} m/s<br>Fz %{y:.4g} kN<extra></extra>")
    rows = result["profile"]["rows"]
    fig.add_scatter(x=[r[1] for r in rows], y=[r[2] / units.KN for r in rows], mode="lines", name="trajectory",
                    line={"color": style.ACCENT, "width": 2}, customdata=[r[0] for r in rows],
                    hovertemplate="t %{customdata:.4g} s<br>V %{x:.4g} m/s<br>Fz %{y:.4g} kN<extra></extra>")
    thr_psi, thr_lat = result["options"]["psi_threshold"], result["options"]["lateral_threshold"]
    xs, ys = [], []
    for v, f, a, b in zip(result["V"], result["Fz"], result["envelope_psi"], result["envelope_lateral"], strict=True):
        inside = a > thr_psi or b > thr_lat
        xs.append(v if inside else None)
        ys.append(f / units.KN if inside else None)
    fig.add_scatter(x=xs, y=ys, mode="lines", name=f"{label} in shimmy", line={"color": colour, "width": 7},
                    opacity=0.55, hoverinfo="skip")
    fig.add_scatter(x=[rows[0][1]], y=[rows[0][2] / units.KN], mode="markers+text", text=["start"],
                    textposition="top right", name="start", showlegend=False,
                    marker={"symbol": "circle", "size": 10, "color": style.ACCENT})
    crossings = result["boundary_crossings"]
    if crossings:
        fig.add_scatter(x=[c["V"] for c in crossings], y=[c["Fz"] / units.KN for c in crossings], mode="markers",
                        name="crossings of the Hopf curves (H)", customdata=[c["t"] for c in crossings],
                        marker=markers.marker(PointKind.HOPF, "#D55E00"), meta={"kind": str(PointKind.HOPF)},
                        hovertemplate="crosses at t %{customdata:.4g} s<br>V %{x:.4g} m/s<br>Fz %{y:.4g} kN"
                                      "<extra></extra>")
    v_max = max(r[1] for r in rows)
    f_max = max(r[2] for r in rows) / units.KN
    fig.update_xaxes(range=[0, max(20.0, 1.25 * v_max)])
    fig.update_yaxes(range=[0, min(900.0, max(50.0, 1.4 * f_max))])
    return fig


def envelopes(results, against: str):
    """Torsional and lateral envelopes of the four configurations against time or speed, with the thresholds."""
    x_title = "time t (s)" if against == "t" else "forward speed V (m/s)"
    fig = make_subplots(rows=2, cols=1, shared_xaxes=True, vertical_spacing=0.08)
    for r in _ordered(results):
        config = r["config"]
        common = {"mode": "lines", "line": {"color": style.CONFIG_COLOURS[config], "width": 1.6},
                  "legendgroup": config}
        label = style.CONFIG_LABELS[config]
        fig.add_scatter(x=r[against], y=r["envelope_psi"], name=label, row=1, col=1,
                        customdata=style.in_degrees(r["envelope_psi"]),
                        hovertemplate=f"{label}: |psi| {style.ANGLE_HOVER}<extra></extra>", **common)
        fig.add_scatter(x=r[against], y=[v / units.MM for v in r["envelope_lateral"]], name=label,
                        showlegend=False, row=2, col=1,
                        hovertemplate=f"{label}: |l_g delta| %{{y:.4g}} mm<extra></extra>", **common)
    kick = results[0].get("kick")
    if kick is not None:  # the same kick in every run
        for row in (1, 2):
            fig.add_vline(x=kick["t"] if against == "t" else kick["V"], line={"color": "#555", "dash": "dot",
                                                                                "width": 1.5},
                          annotation_text="kick" if row == 1 else None, annotation_position="top right", row=row,
                          col=1)
    options = results[0]["options"]
    for row, value, text in ((1, options["psi_threshold"], "threshold"),
                             (2, options["lateral_threshold"] / units.MM, "threshold")):
        fig.add_hline(y=value, line={"color": "#D55E00", "dash": "dash", "width": 1}, annotation_text=text,
                      annotation_position="top left", row=row, col=1)
    title = ("Amplitude envelopes against time" if against == "t" else
             "Amplitude envelopes against forward speed (along the run)")
    fig.update_layout(title={"text": title, "x": 0.01, "font": {"size": 15}}, height=520, template=style.TEMPLATE,
                      margin={"l": 70, "r": 16, "t": 44, "b": 48}, legend={"orientation": "h", "y": -0.14, "x": 0},
                      hovermode="x unified" if against == "t" else "closest")
    fig.update_yaxes(title_text="envelope of |psi| (rad)", row=1, col=1)
    fig.update_yaxes(title_text="envelope of |l_g delta| (mm)", row=2, col=1)
    fig.update_xaxes(title_text=x_title, row=2, col=1)
    fig.update_xaxes(showline=True, linecolor="#888", mirror=True)
    fig.update_yaxes(showline=True, linecolor="#888", mirror=True)
    return fig


def summary(results):
    ordered = _ordered(results)
    base = next((r for r in ordered if r["config"] == "original"), None)
    rows = []
    for r in ordered:
        speeds = "–" if r["speed_range"] is None else f"{r['speed_range'][0]:.4g} – {r['speed_range'][1]:.4g}"
        p, q = r["peak_psi"], r["peak_lateral"]
        psi = f"{p['value']:.4g} at {p['t']:.3g} s, {p['V']:.3g} m/s"
        lat = f"{q['value'] / units.MM:.4g} at {q['t']:.3g} s"
        time_in = f"{r['time_in_shimmy_s']:.2f}"
        if base is not None and r is not base:
            time_in += f" ({r['time_in_shimmy_s'] - base['time_in_shimmy_s']:+.2f})"
            if base["peak_psi"]["value"] > 0:
                psi += f" (×{p['value'] / base['peak_psi']['value']:.2f})"
        crossings = ", ".join(f"{c['V']:.4g} m/s" for c in r["boundary_crossings"]) or "none"
        delay = formats.significant(r["onset_delay_s"], 3)
        rows.append([style.CONFIG_LABELS[r["config"]], time_in, speeds, psi, lat, crossings, delay,
                     kick_outcome(r.get("kick"))])
    kick = ordered[0].get("kick")
    after = "after the kick" if kick is None else (f"after the kick ({kick['kind']} {kick['size']:+g} {kick['unit']} "
                                                     f"at {kick['t']:.4g} s, {kick['V']:.4g} m/s)")
    return ui.table(["configuration", "time in shimmy (s, against original)", "speed range in shimmy (m/s)",
                     "peak |psi| (rad)", "peak |l_g delta| (mm)", "crosses the Hopf curves at", "onset delay (s)",
                     after], rows, ids.GR_SUMMARY_TABLE)


def kick_outcome(kick) -> str:
    """What followed the kick, in a few words: the mode of the shimmy it started, or none."""
    if kick is None:
        return formats.MISSING + " (no kick)"
    if not kick.get("applied", True):
        return "not applied (the run stopped before it)"
    if kick["shimmy_started"] is None:
        return "undecided (the run ends first)"
    other = kick["without_kick"]
    plain = f"{other['mode']} shimmy" if other["in_shimmy"] else "no shimmy"
    added = f"; {formats.signed(kick['extra_time_in_shimmy_s'])} s in shimmy against no kick"
    if not kick["shimmy_started"]:
        return f"no shimmy started (back on the run without it by {kick['t_judged']:.3g} s){added}"
    return (f"{kick['mode']} shimmy by {kick['t_judged']:.3g} s ({kick['V_judged']:.3g} m/s), |psi| up to "
            f"{kick['peak']['psi']:.3g} rad; without the kick: {plain}{added}")


@dash.callback(Output(ids.URL_UPDATE, "data", allow_duplicate=True), Input(ids.GR_PRESET, "value"),
               Input(ids.GR_CONFIG, "value"), Input(ids.GR_PSI_THR, "value"), Input(ids.GR_LAT_THR, "value"),
               Input(ids.GR_KICK, "value"), Input(ids.GR_KICK_SIZE, "value"), Input(ids.GR_KICK_AT, "value"),
               Input(ids.GR_KICK_WHEN, "value"), prevent_initial_call=True)
def remember(preset, config, psi_thr, lat_thr, kick, kick_size, kick_at, kick_when):
    kicked = kick != "none"  # without a kick its boxes leave the address (null drops a key)
    return {"preset": preset, "config": config, "psi_thr": psi_thr, "lat_thr": lat_thr,
            "kick": kick if kicked else None, "kick_size": kick_size if kicked else None,
            "kick_at": kick_at if kicked else None, "kick_when": kick_when if kicked else None}
