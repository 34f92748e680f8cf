"""Ground runs: a take-off, landing roll, taxi or any (t, V, Fz) table for the four configurations."""

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
from ui.fields import Column, Quantity
from ui import style
from ui.layout import page

dash.register_page(__name__, path="/ground-run", name="Ground run", order=4.5)

CONFIGS = ui.CONFIGS
PRESET_LABELS = {"takeoff": "Take-off", "landing": "Landing roll", "taxi": "Taxi"}
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


def layout(preset: str | None = None, config: str | None = None, psi_thr: str | None = None,
           lat_thr: str | None = None, **query):
    preset, bad_preset = fields.choice("preset", preset, list(PRESET_LABELS), "takeoff", "a preset")
    config, bad_config = fields.choice("config", config, list(CONFIGS), "original", "a configuration")
    psi_value, bad_psi = PSI_THR.from_url("psi_thr", psi_thr, 0.01)
    lat_value, bad_lat = LAT_THR.from_url("lat_thr", lat_thr, 1.0)
    address = " ".join(m for m in (bad_preset, bad_config, bad_psi, bad_lat) if m)
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
    for f in analyses.preset_profile(name)["fields"]:
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
        profile = analyses.preset_profile(name, _settings(settings))
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
        return f"Runs the {PRESET_LABELS[name].lower()} preset ({len(rows)} points). Edit a cell to run your own table."
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


def _requests(config, name, settings, rows, preset_rows, psi_thr, lat_thr, torque, design):
    """One request per configuration, the one whose map is drawn first."""
    if rows and not (preset_rows and _same(rows, preset_rows)):
        profile = {"profile": [[r.get("t"), r.get("V"), _newtons(r.get("Fz"))] for r in rows]}
    else:
        profile = {"preset": name, "preset_options": _settings(settings)}
    psi, lateral = PSI_THR.read(psi_thr), LAT_THR.read(lat_thr)  # refused in the box's unit, never defaulted
    order = [config] + [c for c in CONFIGS if c != config]
    return [{"config": c, **profile, "psi_threshold": psi, "lateral_threshold": lateral, "series_dt": SERIES_DT,
             "hopf_curves": True, **ui.exact_nes(c, torque), **design} for c in order]


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
            State(ids.GR_EXACT, "value"), State(ids.design_store(ids.GR), "data")],
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
                        marker=markers.marker(PointKind.HOPF, "#D55E00"), meta={"kind": "H"},
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
        rows.append([style.CONFIG_LABELS[r["config"]], time_in, speeds, psi, lat, crossings, delay])
    return ui.table(["configuration", "time in shimmy (s, against original)", "speed range in shimmy (m/s)",
                     "peak |psi| (rad)", "peak |l_g delta| (mm)", "crosses the Hopf curves at", "onset delay (s)"],
                    rows, ids.GR_SUMMARY_TABLE)


@dash.callback(Output(ids.URL_UPDATE, "data", allow_duplicate=True), Input(ids.GR_PRESET, "value"),
               Input(ids.GR_CONFIG, "value"), Input(ids.GR_PSI_THR, "value"), Input(ids.GR_LAT_THR, "value"),
               prevent_initial_call=True)
def remember(preset, config, psi_thr, lat_thr):
    return {"preset": preset, "config": config, "psi_thr": psi_thr, "lat_thr": lat_thr}
