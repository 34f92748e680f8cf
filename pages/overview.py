"""Overview: the four configurations side by side at the current design."""

from __future__ import annotations

import dash
from dash import Input, Output, Patch, State, dcc, html, no_update

from shimmy.continuation.kinds import PointKind
from shimmy.errors import InvalidParameterError
import shimmy.model.units as units
from shimmy.service import admission, analyses, neighbours
from plotly.subplots import make_subplots

from ui import compare, designs, fields, formats, ids, jobs, live, markers
from ui import components as ui
from ui.fields import Quantity
from ui.layout import page
from ui import style

dash.register_page(__name__, path="/", name="Overview", order=0)

CONFIGS = ui.CONFIGS


FZ = Quantity("stability", "Fz", "Fz", "kN", units.KN)
V_MAX = Quantity("stability", "v_max", "highest speed", "m/s")


def layout(Fz: str | None = None, vmax: str | None = None, **query):
    fz, p_fz = FZ.from_url("Fz", Fz, 150)
    v_max, p_v = V_MAX.from_url("vmax", vmax, 200)
    return layout_page(query, [
        ui.header("Overview", "Linear stability of straight rolling for the four configurations at the current "
                  "design: the largest eigenvalue real part against speed (shimmy grows where it is positive), the "
                  "Hopf speed interval of each, and the (V, Fz) stability boundary."),
        html.Div([
            FZ.field("Vertical load Fz (kN)", ids.OV_FZ, fz),
            V_MAX.field("Highest speed (m/s)", ids.OV_VMAX, v_max),
        ], className="controls"),
        html.Div(" ".join(p for p in (p_fz, p_v) if p), id=ids.OV_GROUP.error, className="error", role="alert"),
        ui.graph(ids.OV_GROWTH),
        html.H2("Hopf speed interval at this load"),
        html.Div(id=ids.OV_TABLE),
        ui.downloads(ids.OV_GROUP),
        dcc.Store(id=ids.OV_DATA),
        html.H2("Hopf speed intervals of the compared designs"),
        html.P("The designs ticked under Compare in the design panel (2 to 4; the current one may be one of them) "
               "at this load: where straight rolling is unstable for each configuration, one colour per design, "
               "with the change of the onset speed against the first design.", className="hint"),
        html.Div(id=ids.OV_CMP.designs, className="compare-designs"),
        compare.follower(ids.OV),
        html.Div(id=ids.OV_CMP.error, className="error", role="alert"),
        ui.graph(ids.OV_CMP_GRAPH, figure=style.message_figure(
            f"Tick {designs.COMPARE[0]} to {designs.COMPARE[1]} designs under Compare in the design panel "
            "(instant: linear stability)", 200)),
        html.Div(id=ids.OV_CMP_TABLE, className="table-wrap"),
        html.H2("Stability boundary in (V, Fz)"),
        html.P("Hopf curves of straight rolling: inside a closed curve, or above the lateral one, x = 0 is "
               "unstable. Computed by two-parameter continuation; runs in the background.", className="hint"),
        html.Div(jobs.controls(ids.OV_BOUNDARY, "Compute boundary"), className="controls"),
        html.Div(id=ids.OV_BOUNDARY.error, className="error", role="alert"),
        ui.graph(ids.OV_BOUNDARY_GRAPH, figure=style.message_figure("Press 'Compute boundary' (about 3 s cold, "
                                                                   "instant when cached); it then follows the design")),
        ui.downloads(ids.OV_BOUNDARY_FILES, "Download boundary CSV", "Download boundary JSON"),
        *jobs.stores(ids.OV_BOUNDARY),
        html.H2("Regions and curves of cycles in (V, Fz)"),
        html.P("The stability maps of the four configurations: the regions of original shaded by shimmy type, "
               "bounded by its Hopf, fold-of-cycles and torus curves; every configuration's curves in its colour "
               "(the same maps as on the Stability map page, shared through the cache).", className="hint"),
        html.Div(jobs.controls(ids.OV_REGIONS, "Compute maps"), className="controls"),
        html.Div(id=ids.OV_REGIONS.error, className="error", role="alert"),
        ui.graph(ids.OV_REGIONS_GRAPH, figure=style.message_figure(REGIONS_WAITING)),
        ui.downloads(ids.OV_REGIONS_FILES, "Download regions CSV", "Download maps JSON"),
        *jobs.stores(ids.OV_REGIONS),
        live.settled(ids.OV),
    ])


fields.check(ids.OV_FZ, FZ)
fields.check(ids.OV_VMAX, V_MAX)


def layout_page(query, children):
    return page(query, ids.OV, *children)



@dash.callback(
    Output(ids.OV_GROWTH, "figure"), Output(ids.OV_TABLE, "children"), Output(ids.OV_DATA, "data"),
    Output(ids.OV_GROUP.error, "children"), Output(ids.OV_GROUP.csv, "disabled"), Output(ids.OV_GROUP.json, "disabled"),
    Output(ids.URL_UPDATE, "data", allow_duplicate=True),
    Input(ids.design_store(ids.OV), "data"), Input(ids.OV_FZ, "value"), Input(ids.OV_VMAX, "value"),
    State(ids.OV_DATA, "data"),
    prevent_initial_call="initial_duplicate",
)
def update(design, fz_kn, v_max, drawn):
    try:
        request = {"Fz": FZ.read(fz_kn), "v_max": V_MAX.read(v_max), "n_points": 120, **design}
        result, _ = analyses.run("stability", request)
    except InvalidParameterError as exc:
        if dash.ctx.triggered_id is None:  # the first drawing: the layout already says what of the address failed
            return no_update, no_update, no_update, no_update, True, True, no_update
        return no_update, no_update, no_update, str(exc), True, True, no_update
    except admission.Busy as exc:  # the service is busy: say so, keep what is drawn
        return no_update, no_update, no_update, f"The service is busy: {exc}.", no_update, no_update, no_update
    traces = growth_traces(result)
    title = f"Growth rate of straight rolling at Fz = {fz_kn:g} kN"
    if drawn:  # the figure is there: only what a design step changes (its traces' points, the title)
        fig = Patch()
        same_speeds = drawn.get("request", {}).get("v_max") == request["v_max"]  # the lines' V grid is drawn
        for k, trace in enumerate(traces):
            for key in ("x", "y", "hovertext"):
                if key in trace and not (key == "x" and trace["mode"] == "lines" and same_speeds):
                    fig["data"][k][key] = trace[key]
        fig["layout"]["title"]["text"] = title
    else:
        lay = style.layout(title, "forward speed V (m/s)", "largest eigenvalue real part (1/s)", x_log=True)
        lay["shapes"] = [{"type": "line", "xref": "paper", "x0": 0, "x1": 1, "y0": 0, "y1": 0,
                          "line": {"color": "#888", "width": 1}}]
        fig = {"data": traces, "layout": lay}
    rows = hopf_rows(result)
    table = ui.table(HOPF_COLUMNS, rows, ids.OV_HOPF_TABLE)
    return (fig, table, {"columns": HOPF_COLUMNS, "rows": rows, "request": request}, "", False, False,
            {"Fz": f"{float(fz_kn):g}", "vmax": f"{float(v_max):g}"})


HOPF_COLUMNS = ["configuration", "unstable for V in (m/s)", "onset (m/s)", "end (m/s)", "onset vs original (m/s)",
                "onset frequency (Hz)", "criticality"]


def growth_traces(result) -> list[dict]:
    """Per configuration, in order: its growth-rate line, then its Hopf points (a trace even when there
    are none: the figure keeps its traces from one design to the next, so a step patches their points)."""
    traces = []
    for config in CONFIGS:
        data = result["configs"][config]
        traces.append({"type": "scatter", "x": result["V"], "y": data["max_real"], "mode": "lines",
                       "name": style.CONFIG_LABELS[config],
                       "line": {"color": style.CONFIG_COLOURS[config], "width": 2}})
        hv = [h["V"] for h in data["hopf_points"]]
        traces.append({"type": "scatter", "x": hv, "y": [0] * len(hv), "mode": "markers", "showlegend": False,
                       "marker": markers.marker(PointKind.HOPF, style.CONFIG_COLOURS[config]),
                       "meta": {"kind": markers.of(PointKind.HOPF).label}, "hoverinfo": "text",
                       "hovertext": [f"{style.CONFIG_LABELS[config]} Hopf point (H) V = {v:.4g} m/s" for v in hv]})
    return traces


def hopf_rows(result) -> list[list[str]]:
    """The Hopf speed interval table's rows (HOPF_COLUMNS), one per configuration."""
    rows = []
    base = result["configs"]["original"]["unstable_intervals"]
    for config in CONFIGS:
        data = result["configs"][config]
        intervals = data["unstable_intervals"]
        onset = intervals[0][0] if intervals else None
        end = intervals[-1][1] if intervals else None
        d_onset = None if onset is None or not base else onset - base[0][0]
        freq = data["hopf_points"][0]["frequency_hz"] if data["hopf_points"] else None
        rows.append([style.CONFIG_LABELS[config],
                     ", ".join(f"{a:.4g}–{b:.4g}" for a, b in intervals) or "stable",
                     formats.significant(onset), formats.significant(end), formats.signed(d_onset),
                     formats.significant(freq),
                     ", ".join(h["criticality"] for h in data["hopf_points"]) or "–"])
    return rows


@dash.callback(Output(ids.OV_GROUP.download, "data"), Input(ids.OV_GROUP.csv, "n_clicks"), Input(ids.OV_GROUP.json,
                                                                                                 "n_clicks"),
               State(ids.OV_DATA, "data"), prevent_initial_call=True)
def download(_csv, _json, data):
    if not data:
        return no_update
    if dash.ctx.triggered_id == ids.OV_GROUP.csv:
        return {"content": ui.csv_text(data["columns"], data["rows"]), "filename": "overview_hopf.csv"}
    try:  # the answer drawn: the service's cached one for the same request
        result, _ = analyses.run("stability", data["request"])
    except (InvalidParameterError, admission.Busy) as exc:
        return {"content": str(exc), "filename": "overview_stability_refused.txt"}
    return {"content": ui.json_text(result), "filename": "overview_stability.json"}


@dash.callback(Output(ids.OV_CMP.designs, "children"), Output(ids.OV_CMP_GRAPH, "figure"),
               Output(ids.OV_CMP_TABLE, "children"), Output(ids.OV_CMP.error, "children"),
               *compare.SELECTION, Input(ids.OV_FZ, "value"), Input(ids.OV_VMAX, "value"),
               *compare.follows_design(ids.OV), State(ids.OV_CMP.designs, "children"))
def compare_designs(selection, saved, fz_kn, v_max, _design_step, current, line):
    """Linear stability of each compared design (quick: asked of the service at once, the current
    design's answer shared with the figure above through the cache)."""
    try:
        chosen = compare.chosen(selection, saved, current)
    except InvalidParameterError as exc:
        if compare.shows(line, exc):  # refused as before: nothing to send or draw again
            return no_update, no_update, no_update, no_update
        return compare.refusal(exc), style.message_figure(str(exc), 200), None, ""
    names = [d.name for d in chosen]
    try:
        body = {"Fz": FZ.read(fz_kn), "v_max": V_MAX.read(v_max), "n_points": 120}
        results = [analyses.run("stability", {**body, **d.request()})[0] for d in chosen]
    except InvalidParameterError as exc:
        return compare.swatches(names), no_update, no_update, str(exc)
    except admission.Busy as exc:
        return compare.swatches(names), no_update, no_update, f"The service is busy: {exc}."
    table = designs.comparison(names, results, designs.hopf_figures(CONFIGS, style.CONFIG_LABELS))
    shown = [name for name, _ in compare.series(names)]
    return compare.swatches(names), intervals_figure(results, shown), compare.table(table, ids.OV_CMP_SUMMARY), ""


def intervals_figure(results, names):
    """Where x = 0 is unstable, per configuration (one strip each) and design (one row each, its colour)."""
    n = len(names)
    rows = len(CONFIGS)
    fig = make_subplots(rows=rows, cols=1, shared_xaxes=True, vertical_spacing=0.09,
                        subplot_titles=[style.CONFIG_LABELS[c] for c in CONFIGS])
    v_lo, v_hi = results[0]["V"][0], results[0]["V"][-1]
    shown = [nm if len(nm) <= 18 else nm[:17] + "…" for nm in names]
    for row, config in enumerate(CONFIGS, start=1):
        for k, (result, name) in enumerate(zip(results, names, strict=True)):
            colour, data = compare.colour(k), result["configs"][config]
            fig.add_scatter(x=[v_lo, v_hi], y=[name, name], mode="lines", line={"color": "#d5d9e0", "width": 2},
                            hoverinfo="skip", showlegend=False, row=row, col=1)
            for a, b in data["unstable_intervals"]:
                fig.add_scatter(x=[a, b], y=[name, name], mode="lines", line={"color": colour, "width": 9},
                                legendgroup=f"design-{k}", showlegend=False, row=row, col=1,
                                hovertemplate=f"{name}, {style.CONFIG_LABELS[config]}: x = 0 unstable for V in "
                                              f"{a:.4g} – {b:.4g} m/s<extra></extra>")
            hv = [h["V"] for h in data["hopf_points"]]
            if hv:
                fig.add_scatter(x=hv, y=[name] * len(hv), mode="markers", legendgroup=f"design-{k}", showlegend=False,
                                marker=markers.marker(PointKind.HOPF, colour, outline="#fff"), row=row, col=1,
                                meta={"kind": markers.of(PointKind.HOPF).label},
                                hovertemplate=f"{name}, {style.CONFIG_LABELS[config]}: Hopf point V = %{{x:.4g}} m/s"
                                              "<extra></extra>")
        fig.update_yaxes(type="category", categoryorder="array", categoryarray=names[::-1], tickvals=names,
                         ticktext=shown, automargin=True, row=row, col=1)
    for k, name in enumerate(names):
        style.legend_key(fig, name, group=f"design-{k}", mode="lines", line={"color": compare.colour(k), "width": 6})
    markers.legend(fig, [PointKind.HOPF], "legend2", "#666")
    height = 120 + rows * (34 + 24 * n) + 90
    fz = units.to_kn(results[0]["Fz"])
    title = {**style.title(f"Where straight rolling is unstable at Fz = {fz:g} kN (thick: between Hopf points)"),
             "yref": "container", "y": 1 - 40 / height, "yanchor": "top"}  # above the first strip's title
    fig.update_layout(title=title, height=height, template=style.TEMPLATE, margin={**style.MARGIN, "t": 100, "b": 110},
                      hovermode="closest")
    fig.update_annotations(x=0, xanchor="left", font={"size": 13})  # the strips' titles, at their left
    style.legends(fig, ["design (colour)", "marker"], height, 110)
    fig.update_xaxes(**style.LOG_SPEED_AXIS, showline=True, linecolor="#888", mirror=True)
    fig.update_xaxes(title_text="forward speed V (m/s)", row=rows, col=1)
    return fig


def _boundary_requests(design):
    return [{"config": config, "v_max": 300.0, **design} for config in CONFIGS]


def boundary_figure(results):
    fig = style.figure("Hopf curves of straight rolling", "forward speed V (m/s)", "vertical load Fz (kN)", 460)
    kinds = set()
    for result in results:
        config = result["config"]
        label = style.CONFIG_LABELS[config]
        for i, curve in enumerate(result["curves"]):
            fig.add_scatter(x=[p["V"] for p in curve["points"]], y=[units.to_kn(p["Fz"]) for p in curve["points"]],
                            mode="lines", name=label, legendgroup=config, showlegend=i == 0,
                            line={"color": style.CONFIG_COLOURS[config], "width": 2},
                            hovertemplate=f"{label} Hopf curve<br>V %{{x:.4g}} m/s<br>Fz %{{y:.4g}} kN<extra></extra>")
        for key, kind in (("gh_points", PointKind.GENERALISED_HOPF), ("double_hopf_points", PointKind.DOUBLE_HOPF)):
            points = result.get(key) or []
            if points:
                kinds.add(kind)
                m = markers.of(kind)
                fig.add_scatter(x=[g["V"] for g in points], y=[units.to_kn(g["Fz"]) for g in points], mode="markers",
                                name=f"{label} {m.label}", legendgroup=config, showlegend=False,
                                marker=markers.marker(kind, style.CONFIG_COLOURS[config]), meta={"kind": m.label},
                                hovertemplate=f"{label} {m.legend}<br>V %{{x:.4g}} m/s<br>Fz %{{y:.4g}} kN"
                                              "<extra></extra>")
    markers.legend(fig, kinds, "legend")
    fig.update_xaxes(**style.LOG_SPEED_AXIS)
    return fig


def _boundary_rows(results):
    rows = [[r["config"], i, p["V"], units.to_kn(p["Fz"]), p["frequency_hz"],
             "" if p["lyapunov"] is None else p["lyapunov"]]
            for r in results for i, c in enumerate(r["curves"]) for p in c["points"]]
    return ["config", "curve", "V_m_s", "Fz_kN", "frequency_hz", "lyapunov"], rows


#: the design once it stood still (a slider released): the boundary and the maps follow it
SETTLED = live.follow_settled(ids.OV)

jobs.register(
    ids.OV_BOUNDARY, "hopf_curves", requests=lambda _settled, design: _boundary_requests(design),
    render=lambda results: (boundary_figure(results),),
    follow=[SETTLED], warm=lambda requests: True,  # a few tenths of a second per configuration: always
    fading=lambda seconds, asked: (live.fading("New design's Hopf curves", seconds),),
    outputs=[Output(ids.OV_BOUNDARY_GRAPH, "figure")], states=[State(ids.design_store(ids.OV), "data")],
    download=jobs.Download(ids.OV_BOUNDARY_FILES, "hopf_curves", _boundary_rows))


REGIONS_WAITING = ("Press 'Compute maps' (about 15-25 s per configuration cold, instant when cached; then they "
                   "follow the design where a nearby design's maps are cached)")


def _regions_requests(design):
    return [{"config": config, **design} for config in CONFIGS]


def _regions_figure(results):
    from pages.stability_map import figure  # the map page's drawing: regions, curves, points

    return figure(results)


def _region_rows(results):
    rows = [[r["config"], k, region["type"], V, units.to_kn(Fz)] for r in results
            for k, region in enumerate(r["regions"]) for V, Fz in zip(region["V"], region["Fz"], strict=True)]
    return ["config", "region", "shimmy_type", "V_m_s", "Fz_kN"], rows


jobs.register(
    ids.OV_REGIONS, "map", requests=lambda _settled, design: _regions_requests(design),
    render=lambda results: (_regions_figure(results),),
    follow=[SETTLED], warm=lambda requests: all(neighbours.within_reach("map", r) for r in requests),
    fading=lambda seconds, asked: (live.fading("New design's maps", seconds),),
    stale="The design changed: the maps shown are of the previous design. Press 'Compute maps' for this one (no "
          "maps of a nearby design are cached to start from).",
    waiting=lambda: (style.message_figure(REGIONS_WAITING),),
    outputs=[Output(ids.OV_REGIONS_GRAPH, "figure")], states=[State(ids.design_store(ids.OV), "data")],
    download=jobs.Download(ids.OV_REGIONS_FILES, "stability_maps", _region_rows))
