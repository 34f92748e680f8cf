"""Design decisions (a): which parameters move the shimmy boundaries, as tornado charts of the
sensitivities the service computes by implicit differentiation."""

from __future__ import annotations

import dash
from dash import Input, Output, State, dcc, html

from ui import components as ui
from ui import formats, ids, jobs, style
from ui.layout import DESIGN

from .common import DOWN, FZ, GRID, UP, placeholder, unit_suffix

#: The sensitivity quantities as the page names them: title, short symbol, unit shown, SI units per shown unit.
QUANTITIES = {"hopf_V1": ("Hopf speed V1 at {kN} kN", "V1", "m/s", 1.0),
              "hopf_V2": ("Hopf speed V2 at {kN} kN", "V2", "m/s", 1.0),
              "hopf_interval": ("Hopf interval width V2 − V1 at {kN} kN", "V2 − V1", "m/s", 1.0),
              "min_shimmy_Fz": ("Minimum shimmy load Fz,min", "Fz,min", "kN", 1e3),
              "max_psi": ("Largest stable |psi| at {kN} kN", "max |psi|", "rad", 1.0)}
BARS = {"per_half_range": "per half design range", "per_percent": "per +1 % of the value"}
SHOWN = {"device": "device parameters", "all": "all parameters"}
WAITING = "Press Compute: the tornado charts appear here (about 2 s; at once when the cache has them)."
COMPUTING = "Computing the sensitivities (about 2 s once a job slot is free)…"
#: What the charts' store holds while the job runs (in place of a result's rows).
RUNNING = {"computing": True}


def section(a) -> list:
    """The section's heading, controls, charts and downloads, as the address ``a`` (an
    :class:`~ui.decisions.address.Address`) sets them."""
    return [
        html.H2("Sensitivities", id=ids.SENSITIVITIES),
        html.P("Change of each quantity when one parameter moves by half its design range (or by 1 % of its value), "
               "the others held: the derivative by implicit differentiation times the step (linear). Largest effect "
               "on top; blue raises the quantity, vermilion lowers it. Parameters that cannot move a quantity are "
               "listed under its chart with the reason.", className="hint"),
        html.Div([
            ui.field("Bars", dcc.RadioItems(id=ids.SENS_BY, value=a.by, inline=True,
                                            options=[{"label": v, "value": k} for k, v in BARS.items()])),
            ui.field("Parameters", dcc.RadioItems(id=ids.SENS_SHOW, value=a.shown, inline=True,
                                                  options=[{"label": v, "value": k} for k, v in SHOWN.items()])),
            *jobs.controls(ids.SENS),
        ], className="controls"),
        html.Div(" ".join(p for p in (a.bad_bars, a.bad_show) if p), id=ids.SENS.error, className="error",
                 role="alert"),
        html.Div(id=ids.SENS.stale, className="hint", role="status"),
        html.Div(id=ids.SENS_SUMMARY, className="hint"),
        html.Div(placeholder(WAITING), id=ids.SENS_CHARTS),
        ui.downloads(ids.SENS),
        dcc.Store(id=ids.SENS_DATA),
        *jobs.stores(ids.SENS),
    ]


def _requests(config, fz_kn, design):
    return [{"config": config, "Fz": FZ.read(fz_kn), **design}]


def _data(results):
    """What the charts need of the result (the rows of every quantity, the reasons): kept in the page."""
    r = results[0]
    return {"config": r["config"], "Fz": r["Fz"], "quantities": r["quantities"], "max_psi": r["max_psi"],
            "min_shimmy_Fz": r["min_shimmy_Fz"] and {k: v for k, v in r["min_shimmy_Fz"].items() if k != "dFz_dp"},
            "hopf_points": [{"V": h["V"], "frequency_hz": h["frequency_hz"]} for h in r["hopf_points"]]}


def _summary(results):
    r = results[0]
    speeds = ", ".join(f"{h['V']:.4g} m/s ({h['frequency_hz']:.3g} Hz)" for h in r["hopf_points"]) or "none"
    low = r["min_shimmy_Fz"]
    text = (f"{style.CONFIG_LABELS[r['config']]} at {r['Fz'] / 1e3:g} kN: Hopf points at {speeds}; minimum shimmy "
            f"load {'–' if low is None else format(low['Fz'] / 1e3, '.4g') + ' kN'}; computed in "
            f"{sum(r['elapsed_s'].values()):.2f} s.")
    return text


def _csv(results):
    rows = [[q["key"], q["unit"], row["name"], row["unit"], row["value"], row["derivative"], row["per_percent"],
             row["per_half_range"], row["reason"] or ""] for q in results[0]["quantities"] for row in q["rows"]]
    return ["quantity", "quantity_unit", "parameter", "parameter_unit", "parameter_value", "derivative",
            "change_per_percent", "change_per_half_range", "no_effect_reason"], rows


jobs.register(
    ids.SENS, "sensitivity", requests=_requests,
    render=lambda results: (_data(results), _summary(results)),
    outputs=[Output(ids.SENS_DATA, "data"), Output(ids.SENS_SUMMARY, "children")],
    # the page's configuration and load (the optimiser's and robustness's too): shown from the cache, else stale
    follow=[Input(ids.DES_CONFIG, "value"), Input(ids.DES_FZ, "value")],
    states=[State(ids.design_store(ids.DES), "data")],
    download=jobs.Download(ids.SENS, "sensitivities", _csv, single=True,
                           filename=lambda r: f"sensitivities_{r[0]['config']}_{r[0]['Fz'] / 1e3:g}kN"),
    blank=lambda: (None, ""), running=lambda: (RUNNING, ""), waiting=lambda: (None, ""))


def _no_effect(rows) -> html.Div | None:
    """The parameters without effect, grouped by reason."""
    by_reason: dict[str, list[str]] = {}
    for r in rows:
        if r["reason"] is not None:
            by_reason.setdefault(r["reason"], []).append(r["name"])
    if not by_reason:
        return None
    return html.Div([html.Strong("No effect: "), html.Ul([html.Li([html.Code(", ".join(names)), f": {reason}"])
                                                          for reason, names in by_reason.items()])],
                    className="hint no-effect")


def _quantity(q, Fz) -> tuple[str, str, str, float]:
    """(title with its value, symbol, unit shown, SI units per shown unit) of a sensitivity quantity."""
    title, symbol, unit, scale = QUANTITIES.get(q["key"], (q["label"], q["key"], q["unit"], 1.0))
    return f"{title.format(kN=f'{Fz / 1e3:g}')} = {q['value'] / scale:.4g} {unit}", symbol, unit, scale


def tornado(q, rows, by, Fz):
    """One quantity's horizontal bars, largest effect on top."""
    title, symbol, unit, scale = _quantity(q, Fz)
    active = [r for r in rows if r["reason"] is None]
    active.sort(key=lambda r: abs(r[by]))  # plotly draws the first category at the bottom
    step = "half its design range" if by == "per_half_range" else "+1 % of its value"
    height = max(240, 120 + 24 * len(active))
    fig = style.figure(title, f"change of {symbol} ({unit}) per {step}", "", height=height)
    x = [r[by] / scale for r in active]
    hover = []
    for r in active:
        u = f" {r['unit']}" if r["unit"] else ""
        hover.append(f"{r['name']} = {formats.compact(r['value'])}{u} "
                     f"(range {formats.compact(r['low'])} – {formats.compact(r['high'])}{u})<br>"
                     f"d{symbol}/d{r['name']} = {r['derivative'] / scale:.4g} {unit} per {r['unit'] or 'unit'}<br>"
                     f"half range: {r['per_half_range'] / scale:+.4g} {unit}<br>"
                     f"+1 %: {r['per_percent'] / scale:+.4g} {unit}")
    fig.add_bar(x=x, y=[f"{r['name']}{unit_suffix(r['name'])}" for r in active], orientation="h",
                marker={"color": [UP if v >= 0 else DOWN for v in x]}, hovertext=hover, hoverinfo="text",
                showlegend=False, name=symbol)
    fig.update_layout(margin={**style.MARGIN, "l": 120, "t": 60, "b": 56}, bargap=0.25)
    fig.update_yaxes(automargin=True, title_text="")
    fig.update_xaxes(zeroline=True, zerolinecolor="#888", automargin=True)
    return fig


@dash.callback(Output(ids.SENS_CHARTS, "children"), Input(ids.SENS_DATA, "data"), Input(ids.SENS_BY, "value"),
               Input(ids.SENS_SHOW, "value"))
def draw_sensitivities(data, by, shown):
    """One tornado chart per quantity, the parameters without effect under it."""
    if not data:
        return placeholder(WAITING)
    if data == RUNNING:
        return placeholder(COMPUTING)
    by = by if by in BARS else "per_half_range"
    charts = []
    for q in data["quantities"]:
        rows = [r for r in q["rows"] if shown == "all" or r["name"] in DESIGN]
        active = [r for r in rows if r["reason"] is None]
        body = [ui.graph(ids.sens_chart(q["key"]), figure=tornado(q, rows, by, data["Fz"]))] if active else [
            html.H3(_quantity(q, data["Fz"])[0], style={"fontSize": "15px"}),
            html.P(f"None of the {SHOWN[shown]} moves it: show all parameters.", className="hint")]
        charts.append(html.Div([*body, _no_effect(rows)], className="tornado"))
    notes = []
    amp = data.get("max_psi")
    if amp is not None and amp.get("dA_dp") is None:
        notes.append(f"Largest stable torsional amplitude at {data['Fz'] / 1e3:g} kN = {amp['value']:.4g} rad: "
                     f"no derivative ({amp['reason']}).")
    low = data.get("min_shimmy_Fz")
    if low is not None and low.get("reason"):
        notes.append(f"Minimum shimmy load: {low['reason']}; its sensitivities are not meaningful.")
    if not data["hopf_points"]:
        notes.append(f"No Hopf point at {data['Fz'] / 1e3:g} kN between 1 and 200 m/s: no Hopf-speed charts.")
    return [html.Div([html.P(n, className="note") for n in notes]), html.Div(charts, style=GRID)]
