"""Bifurcation diagrams in V: amplitude of every branch, stable solid and unstable dashed."""

from __future__ import annotations

import dash
from dash import Input, Output, State, dcc, html
from plotly.subplots import make_subplots

from shimmy.errors import InvalidParameterError
from ui import components as ui
from ui import jobs
from ui import style
from ui.layout import design_id, page

dash.register_page(__name__, path="/bifurcation", name="Bifurcation", order=3)

CONFIGS = tuple(style.CONFIG_COLOURS)
SYMBOLS = {"H": "diamond", "LPC": "triangle-up", "NS": "square", "PD": "x", "BPC": "cross", "BP": "circle-open"}



def layout(Fz: str = "150", v_min: str = "1", v_max: str = "200", configs: str = "original,nes,pd,nes_pd", **query):
    chosen = [c for c in configs.split(",") if c in CONFIGS] or list(CONFIGS)
    return page(
        query, "bif",
        ui.header("Bifurcation diagram", "Equilibrium and limit-cycle branches in the forward speed at one load, "
                  "by pseudo-arclength continuation with orthogonal collocation; stability from Floquet multipliers "
                  "(solid stable, dashed unstable); Hopf (H), fold of cycles (LPC), torus (NS) and period-doubling "
                  "(PD) points marked. All four configurations overlaid."),
        html.Div([
            ui.field("Fz (kN)", dcc.Input(id="bif-fz", type="number", value=ui.number(Fz, 150), min=10, max=900,
                                          step="any")),
            ui.field("lowest V (m/s)", dcc.Input(id="bif-vmin", type="number", value=ui.number(v_min, 1), min=1,
                                                 max=500, step="any")),
            ui.field("highest V (m/s)", dcc.Input(id="bif-vmax", type="number", value=ui.number(v_max, 200), min=1,
                                                  max=500, step="any")),
            ui.field("Configurations", dcc.Checklist(id="bif-configs", value=chosen, inline=True, options=[
                {"label": style.CONFIG_LABELS[c], "value": c} for c in CONFIGS])),
            *jobs.controls("bif"),
        ], className="controls"),
        html.Div(id="bif-error", className="error", role="alert"),
        ui.graph("bif-graph", figure=style.message_figure("Press Compute: about 1 s per configuration cold, "
                                                          "instant from the cache", 520)),
        html.Div(id="bif-table"),
        ui.downloads("bif"),
        *jobs.stores("bif"),
    )


def _requests(fz_kn, v_min, v_max, configs, design):
    if not configs:
        raise InvalidParameterError("configs", "", ", ".join(CONFIGS), "is empty",
                                    "choose at least one configuration")
    return [{"config": c, "Fz": None if fz_kn is None else float(fz_kn) * 1e3, "v_min": v_min, "v_max": v_max,
             **design} for c in configs]


def _csv_rows(results):
    rows = [[r["config"], i, b["kind"], p["V"], "" if p["period"] is None else p["period"], p["max_psi"],
             p["max_lateral"], int(p["stable"]), p["mode"] or ""]
            for r in results for i, b in enumerate(r["branches"]) for p in b["points"]]
    return ["config", "branch", "kind", "V_m_s", "period_s", "max_psi_rad", "max_lateral_m", "stable", "mode"], rows


jobs.register(
    "bif", "bifurcation", requests=_requests, render=lambda results: (figure(results), summary(results)),
    outputs=[Output("bif-graph", "figure"), Output("bif-table", "children")],
    states=[State("bif-fz", "value"), State("bif-vmin", "value"), State("bif-vmax", "value"),
            State("bif-configs", "value"), State(design_id("bif"), "data")],
    lock=["bif-fz", "bif-vmin", "bif-vmax"], download=jobs.Download("bif", "bifurcation", _csv_rows))


def figure(results):
    fig = make_subplots(rows=2, cols=1, shared_xaxes=True, vertical_spacing=0.07)
    for result in results:
        config = result["config"]
        colour = style.CONFIG_COLOURS[config]
        label = style.CONFIG_LABELS[config]
        first = True
        for branch in result["branches"]:
            for seg_stable, seg in _segments(branch["points"]):
                for row, key in ((1, "max_psi"), (2, "max_lateral")):
                    fig.add_scatter(x=[p["V"] for p in seg], y=[p[key] for p in seg], mode="lines",
                                    name=label, legendgroup=config, showlegend=first and row == 1,
                                    line={"color": colour, "width": 2.5 if seg_stable else 1.5,
                                          "dash": "solid" if seg_stable else "dash"},
                                    hovertemplate=f"{label} {branch['kind']}<br>V %{{x:.4g}} m/s<br>%{{y:.4g}}"
                                                  "<extra></extra>", row=row, col=1)
                first = False
            for sp in branch["special_points"]:
                if sp["kind"] not in SYMBOLS:
                    continue
                for row, key in ((1, "max_psi"), (2, "max_lateral")):
                    fig.add_scatter(x=[sp["V"]], y=[sp.get(key, 0.0)], mode="markers", showlegend=False,
                                    legendgroup=config,
                                    marker={"symbol": SYMBOLS[sp["kind"]], "size": 10, "color": colour,
                                            "line": {"width": 1, "color": "#333"}},
                                    hovertext=f"{label} {sp['kind']} at V = {sp['V']:.5g} m/s", row=row, col=1)
    for kind, symbol in SYMBOLS.items():  # legend entries for the marker kinds
        fig.add_scatter(x=[None], y=[None], mode="markers", name=kind, marker={"symbol": symbol, "size": 9,
                                                                               "color": "#666"})
    fig.add_scatter(x=[None], y=[None], mode="lines", name="unstable", line={"color": "#666", "dash": "dash"})
    fz = results[0]["Fz"] / 1e3 if results else 0
    fig.update_layout(title={"text": f"Bifurcation diagram at Fz = {fz:g} kN", "x": 0.01}, height=620,
                      template="plotly_white", margin={"l": 70, "r": 16, "t": 44, "b": 48},
                      legend={"orientation": "h", "y": -0.1})
    fig.update_xaxes(title_text="forward speed V (m/s)", row=2, col=1)
    fig.update_yaxes(title_text="max |psi| (rad)", row=1, col=1)
    fig.update_yaxes(title_text="max |l_g delta| (m)", row=2, col=1)
    return fig


def _segments(points):
    """Runs of equal stability (each run shares its end point with the next, so lines join)."""
    out, start = [], 0
    for i in range(1, len(points) + 1):
        if i == len(points) or points[i]["stable"] != points[start]["stable"]:
            out.append((points[start]["stable"], points[start:min(i + 1, len(points))]))
            start = i
    return out


def summary(results):
    rows = []
    for r in results:
        hopf = ", ".join(f"{h['V']:.4g} ({h['criticality']})" for h in r["hopf_points"]) or "none in range"
        special = [f"{s['kind']} {s['V']:.4g}" for b in r["branches"] if b["kind"] == "periodic"
                   for s in b["special_points"] if s["kind"] in ("LPC", "NS", "PD", "BPC")]
        rows.append([style.CONFIG_LABELS[r["config"]], hopf, f"{r['max_psi']:.4g}",
                     "–" if r["max_psi_V"] is None else f"{r['max_psi_V']:.4g}", ", ".join(special) or "–",
                     "; ".join(r["warnings"]) or "–"])
    return ui.table(["configuration", "Hopf points V (m/s)", "max stable |psi| (rad)", "at V (m/s)",
                     "LPC / NS / PD points (m/s)", "warnings"], rows, "bif-summary")


@dash.callback(Output("url-update", "data", allow_duplicate=True),
               Input("bif-fz", "value"), Input("bif-vmin", "value"), Input("bif-vmax", "value"),
               Input("bif-configs", "value"), prevent_initial_call=True)
def remember(fz, v_min, v_max, configs):
    return {"Fz": fz, "v_min": v_min, "v_max": v_max, "configs": ",".join(configs or [])}
