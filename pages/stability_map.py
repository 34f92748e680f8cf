"""(V, Fz) stability maps: the plane shaded by shimmy type, with Hopf, fold and torus curves."""

from __future__ import annotations

from urllib.parse import urlencode

import dash
from dash import Input, Output, State, dcc, html, no_update

from ui import components as ui
from ui import jobs
from ui import style
from ui.layout import design_id, page

dash.register_page(__name__, path="/stability-map", name="Stability map", order=4)

CONFIGS = tuple(style.CONFIG_COLOURS)
TYPES = tuple(style.SHIMMY_TYPE_COLOURS)
CURVE_STYLES = {"hopf_curves": ("Hopf", "solid", 2.6), "fold_curves": ("fold of cycles", "dash", 2.2),
                "torus_curves": ("torus", "dot", 2.2)}


def layout(shade: str = "original", overlay: str = "", fz_min: str = "10", fz_max: str = "900", v_min: str = "1",
           v_max: str = "200", resolution: str = "40", **query):
    shade = shade if shade in CONFIGS else "original"
    others = [c for c in overlay.split(",") if c in CONFIGS and c != shade]
    return page(
        query, "map",
        ui.header("Stability map", "The (V, Fz) plane shaded by shimmy type, from the stable attractors on each load "
                  "slice (equilibrium, torsional and lateral limit cycles, including those reached from large "
                  "torsional and lateral starts; simulation where none is stable). Hopf, fold-of-cycles and torus "
                  "curves, GH and double-Hopf points by two-parameter continuation. Click a point to open its "
                  "time history."),
        html.Div([
            ui.field("Shade by", dcc.Dropdown(id="map-shade", value=shade, clearable=False, style={"width": "150px"},
                                              options=[{"label": style.CONFIG_LABELS[c], "value": c}
                                                       for c in CONFIGS])),
            ui.field("Overlay curves of", dcc.Checklist(id="map-overlay", value=others, inline=True, options=[
                {"label": style.CONFIG_LABELS[c], "value": c} for c in CONFIGS])),
            ui.field("Fz from (kN)", dcc.Input(id="map-fzmin", type="number", value=ui.number(fz_min, 10), min=10,
                                               max=900, step="any")),
            ui.field("to (kN)", dcc.Input(id="map-fzmax", type="number", value=ui.number(fz_max, 900), min=10,
                                          max=900, step="any")),
            ui.field("V from (m/s)", dcc.Input(id="map-vmin", type="number", value=ui.number(v_min, 1), min=1,
                                               max=500, step="any")),
            ui.field("to (m/s)", dcc.Input(id="map-vmax", type="number", value=ui.number(v_max, 200), min=1,
                                           max=500, step="any")),
            ui.field("Fz slices", dcc.Input(id="map-res", type="number", value=ui.number(resolution, 40), min=2,
                                            max=80, step=1)),
            *jobs.controls("map"),
        ], className="controls"),
        html.Div(id="map-error", className="error", role="alert"),
        ui.graph("map-graph", figure=style.message_figure("Press Compute: about 35 s per configuration at 40 slices "
                                                          "cold on 2 cores, instant from the cache", 600)),
        html.Div(id="map-hint", className="hint"),
        html.Div(id="map-table"),
        ui.downloads("map"),
        *jobs.stores("map"),
        dcc.Location(id="map-nav", refresh="callback-nav"),
    )


def _requests(shade, overlay, fz_min, fz_max, v_min, v_max, resolution, design):
    configs = [shade] + [c for c in overlay or [] if c != shade]

    def kn(x):
        return None if x is None else float(x) * 1e3

    return [{"config": c, "fz_min": kn(fz_min), "fz_max": kn(fz_max), "v_min": v_min, "v_max": v_max,
             "resolution": resolution, **design} for c in configs]


CONTROLS = (State("map-shade", "value"), State("map-overlay", "value"), State("map-fzmin", "value"),
            State("map-fzmax", "value"), State("map-vmin", "value"), State("map-vmax", "value"),
            State("map-res", "value"), State(design_id("map"), "data"))


def _csv_rows(results):
    rows = [[r["config"], Fz, V, t] for r in results for Fz, row in zip(r["Fz"], r["types"], strict=True)
            for V, t in zip(r["V"], row, strict=True)]
    return ["config", "Fz_N", "V_m_s", "shimmy_type"], rows


jobs.register(
    "map", "map", requests=_requests, render=lambda results: (figure(results), summary(results)),
    outputs=[Output("map-graph", "figure"), Output("map-table", "children")], states=CONTROLS,
    lock=["map-shade", "map-res", "map-fzmin", "map-fzmax", "map-vmin", "map-vmax"],
    download=jobs.Download("map", "stability_map", _csv_rows))


def figure(results):
    """The first map shaded by type; the curves of every map in its configuration's colour."""
    shaded = results[0]
    grid = shaded.get("shading") or shaded  # read off the curves; a map without it: its slices
    V, Fz = grid["V"], [f / 1e3 for f in grid["Fz"]]
    codes = [[TYPES.index(t) for t in row] for row in grid["types"]]
    n = len(TYPES)
    scale = []
    for k, t in enumerate(TYPES):  # a stepped scale: code k -> its type's colour
        scale += [[k / n, style.SHIMMY_TYPE_COLOURS[t]], [(k + 1) / n, style.SHIMMY_TYPE_COLOURS[t]]]
    fig = style.figure(f"Shimmy type of {style.CONFIG_LABELS[shaded['config']]} (shaded)",
                       "forward speed V (m/s)", "vertical load Fz (kN)", height=640)
    fig.add_heatmap(x=V, y=Fz, z=codes, zmin=0, zmax=n, colorscale=scale, showscale=False, opacity=0.55,
                    customdata=grid["types"], name="shimmy type",
                    hovertemplate="V %{x:.4g} m/s<br>Fz %{y:.4g} kN<br>%{customdata}<extra>click: time history</extra>")
    for t in TYPES:  # legend entries for the shading
        fig.add_scatter(x=[None], y=[None], mode="markers", name=t, legendgroup="types",
                        marker={"symbol": "square", "size": 13, "color": style.SHIMMY_TYPE_COLOURS[t],
                                "line": {"width": 1, "color": "#888"}})
    for result in results:
        config = result["config"]
        colour, label = style.CONFIG_COLOURS[config], style.CONFIG_LABELS[config]
        for key, (kind, dash_style, width) in CURVE_STYLES.items():
            for i, curve in enumerate(result[key]):
                fig.add_scatter(x=[p["V"] for p in curve], y=[p["Fz"] / 1e3 for p in curve], mode="lines",
                                name=f"{label}: {kind}", legendgroup=f"{config}-{key}", showlegend=i == 0,
                                line={"color": colour, "dash": dash_style, "width": width},
                                marker={"size": 4, "color": colour},
                                hovertemplate=f"{label} {kind}<br>V %{{x:.4g}} m/s<br>Fz %{{y:.4g}} kN<extra></extra>")
        if result["gh_points"]:
            fig.add_scatter(x=[g["V"] for g in result["gh_points"]], y=[g["Fz"] / 1e3 for g in result["gh_points"]],
                            mode="markers", name=f"{label}: GH", legendgroup=f"{config}-gh",
                            marker={"symbol": "diamond", "size": 12, "color": colour,
                                    "line": {"width": 1.5, "color": "#fff"}},
                            hovertemplate=f"{label} GH point<br>V %{{x:.4g}} m/s<br>Fz %{{y:.4g}} kN<extra></extra>")
        hh = result.get("double_hopf_points") or []
        if hh:  # where two Hopf curves cross and torus curves are born
            fig.add_scatter(x=[g["V"] for g in hh], y=[g["Fz"] / 1e3 for g in hh], mode="markers",
                            name=f"{label}: double Hopf", legendgroup=f"{config}-hh",
                            marker={"symbol": "star", "size": 13, "color": colour,
                                    "line": {"width": 1.5, "color": "#fff"}},
                            hovertemplate=f"{label} double-Hopf point<br>V %{{x:.4g}} m/s<br>Fz %{{y:.4g}} kN"
                                          "<extra></extra>")
    fig.update_xaxes(range=[min(V), max(V)])
    fig.update_yaxes(range=[min(Fz), max(Fz)])
    fig.update_layout(legend={"orientation": "h", "y": -0.13, "x": 0})
    return fig


def _pct(value, base):
    """Relative change against original, for the table."""
    return "–" if value is None or not base else f"{100 * (value - base) / base:+.1f} %"


def summary(results):
    base = next((r for r in results if r["config"] == "original"), None)
    rows = []
    for r in results:
        m = r["metrics"]
        at = m["at_Fz"]
        hull = at["shimmy_speed_range"]
        low = None if r["min_shimmy_Fz"] is None else r["min_shimmy_Fz"] / 1e3
        speeds = "–" if hull is None else f"{hull[0]:.4g} – {hull[1]:.4g}"
        row = [style.CONFIG_LABELS[r["config"]], ui.fmt(low), ui.fmt(m["torsion_area"], 5), speeds,
               ui.fmt(at["max_psi"]), len(r["gh_points"]), len(r["fold_curves"]), len(r["torus_curves"])]
        if base is not None and r is not base:
            b = base["metrics"]
            row[1] += f" ({_pct(r['min_shimmy_Fz'], base['min_shimmy_Fz'])})"
            row[2] += f" ({_pct(m['torsion_area'], b['torsion_area'])})"
            row[4] += f" ({_pct(at['max_psi'], b['at_Fz']['max_psi'])})"
        rows.append(row)
    fz = results[0]["metrics"]["at_Fz"]["Fz"] / 1e3
    return ui.table(["configuration", "min shimmy Fz (kN)", "pure-torsion area, Fz ≤ 250 kN ((m/s) kN)",
                     f"shimmy V at {fz:g} kN (m/s)", f"max stable |psi| at {fz:g} kN (rad)", "GH points",
                     "fold curves", "torus curves"], rows, "map-summary")


@dash.callback(Output("map-nav", "href"), Output("map-hint", "children"),
               Input("map-graph", "clickData"), State("map-requests", "data"), prevent_initial_call=True)
def open_time_history(click, requests):
    """A click on the map opens the time history at that point (same configuration and design)."""
    if not click or not requests or not click.get("points"):
        return no_update, no_update
    point = click["points"][0]
    V, fz_kn = float(point["x"]), float(point["y"])
    request = requests[0]
    query = {"config": request["config"], "V": f"{V:.6g}", "Fz": f"{fz_kn:.6g}"}
    query.update({k: f"{v:.10g}" for k, v in (request.get("params") or {}).items()})
    if request.get("material") not in (None, "steel"):
        query["material"] = request["material"]
    return "/time-history?" + urlencode(query), f"Opening the time history at V = {V:.4g} m/s, Fz = {fz_kn:.4g} kN"


@dash.callback(Output("url-update", "data", allow_duplicate=True),
               Input("map-shade", "value"), Input("map-overlay", "value"), Input("map-fzmin", "value"),
               Input("map-fzmax", "value"), Input("map-vmin", "value"), Input("map-vmax", "value"),
               Input("map-res", "value"), prevent_initial_call=True)
def remember(shade, overlay, fz_min, fz_max, v_min, v_max, resolution):
    return {"shade": shade, "overlay": ",".join(overlay or []), "fz_min": fz_min, "fz_max": fz_max, "v_min": v_min,
            "v_max": v_max, "resolution": resolution}
