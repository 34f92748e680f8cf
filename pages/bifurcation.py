"""Bifurcation diagrams in V: amplitude of every branch, stable solid and unstable dashed."""

from __future__ import annotations

import dash
from dash import Input, Output, State, dcc, html
from plotly.subplots import make_subplots

from shimmy.errors import InvalidParameterError
from ui import components as ui
from ui import fields, jobs
from ui import style
from ui.fields import Quantity
from ui.layout import design_id, page

dash.register_page(__name__, path="/bifurcation", name="Bifurcation", order=3)

CONFIGS = tuple(style.CONFIG_COLOURS)
SYMBOLS = {"H": "diamond", "LPC": "triangle-up", "NS": "square", "PD": "x", "BPC": "cross", "BP": "circle-open"}



FZ = Quantity("bifurcation", "Fz", "Fz", "kN", 1e3)
V_MIN = Quantity("bifurcation", "v_min", "lowest V", "m/s")
V_MAX = Quantity("bifurcation", "v_max", "highest V", "m/s")
WAITING = "Press Compute: about 1 s per configuration cold, instant from the cache"


def layout(Fz: str | None = None, v_min: str | None = None, v_max: str | None = None, configs: str | None = None,
           **query):
    chosen, bad = fields.choices_list("configs", configs, CONFIGS, list(CONFIGS), "a configuration")
    fz, p_fz = FZ.from_url("Fz", Fz, 150)
    lo, p_lo = V_MIN.from_url("v_min", v_min, 1)
    hi, p_hi = V_MAX.from_url("v_max", v_max, 200)
    problems = " ".join(p for p in (bad, p_fz, p_lo, p_hi) if p)
    return page(
        query, "bif",
        ui.header("Bifurcation diagram", "Equilibrium and limit-cycle branches in the forward speed at one load, "
                  "by pseudo-arclength continuation with orthogonal collocation; stability from Floquet multipliers "
                  "(solid stable, dashed unstable); special points labelled as the continuation tools do: Hopf (H1, "
                  "H2, ...), fold of cycles (LPC), torus (NS), period doubling (PD); hover one for its details. "
                  "The bottom strip shows where straight rolling is stable for each configuration."),
        html.Div([
            ui.field("Fz (kN)", FZ.box("bif-fz", fz)),
            html.Div([ui.field("V from (m/s)", V_MIN.box("bif-vmin", lo)),
                      ui.field("to (m/s)", V_MAX.box("bif-vmax", hi))], className="pair"),
            ui.field("Configurations", dcc.Checklist(id="bif-configs", value=chosen, inline=True, options=[
                {"label": style.CONFIG_LABELS[c], "value": c} for c in CONFIGS])),
            *jobs.controls("bif"),
        ], className="controls"),
        html.Div(problems, id="bif-error", className="error", role="alert"),
        ui.graph("bif-graph", figure=style.message_figure(WAITING, 520)),
        html.Div(id="bif-table", className="table-wrap"),
        ui.downloads("bif"),
        *jobs.stores("bif"),
    )


def _requests(fz_kn, v_min, v_max, configs, design):
    if not configs:
        raise InvalidParameterError("configs", "", ", ".join(CONFIGS), "is empty",
                                    "Configurations: none chosen; choose at least one")
    fz, lo, hi = FZ.read(fz_kn), V_MIN.read(v_min), V_MAX.read(v_max)
    if not hi > lo:
        raise InvalidParameterError("v_max", v_max, f"above {v_min:g} m/s",
                                    message=f"highest V = {v_max:g} m/s must exceed lowest V = {v_min:g} m/s")
    return [{"config": c, "Fz": fz, "v_min": lo, "v_max": hi, **design} for c in configs]


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
    lock=["bif-fz", "bif-vmin", "bif-vmax"], download=jobs.Download("bif", "bifurcation", _csv_rows),
    blank=lambda: (style.message_figure("Refused: see the message above", 520), None))


KIND_NAMES = {"H": "Hopf", "LPC": "fold of cycles", "NS": "torus", "PD": "period doubling",
              "BPC": "branch point of cycles", "BP": "branch point"}
HEIGHT, BOTTOM = 780, 190


def _labelled(results):
    """Special points numbered per configuration and kind in order of V (H1, H2, LPC1, NS1, ...), as the
    continuation tools label them: [(result, branch, point, label)]."""
    out = []
    for result in results:
        found = [(b, sp) for b in result["branches"] for sp in b["special_points"] if sp["kind"] in SYMBOLS
                 and not (sp["kind"] == "H" and b["kind"] != "equilibrium")]
        count: dict[str, int] = {}
        for b, sp in sorted(found, key=lambda item: (item[1]["kind"], item[1]["V"])):
            count[sp["kind"]] = count.get(sp["kind"], 0) + 1
            out.append((result, b, sp, f"{sp['kind']}{count[sp['kind']]}"))
    return out


def _hover(label: str, config_label: str, sp: dict, hopf: dict | None) -> str:
    lines = [f"<b>{config_label}: {label}</b> ({KIND_NAMES.get(sp['kind'], sp['kind'])})", f"V = {sp['V']:.5g} m/s"]
    if "max_psi" in sp:
        lines += [f"max |psi| = {sp['max_psi']:.4g} rad", f"max |l_g delta| = {sp['max_lateral']:.4g} m"]
    if sp.get("period"):
        lines.append(f"period = {sp['period']:.4g} s ({1 / sp['period']:.3f} Hz)")
    if hopf is not None:
        lines.append(f"frequency = {hopf['frequency_hz']:.3f} Hz, {hopf['criticality']}")
    if sp.get("multipliers_abs"):
        mu = sorted((float(m) for m in sp["multipliers_abs"]), reverse=True)[:4]
        lines.append("|Floquet multipliers| = " + ", ".join(f"{m:.4f}" for m in mu))
    if sp.get("torus_angle") is not None:
        lines.append(f"torus angle = {sp['torus_angle']:.3f} rad")
    return "<br>".join(lines)


def figure(results):
    """Amplitude of the periodic branches (rows 1-2) and the stability of straight rolling x = 0, one
    strip per configuration (row 3, where every equilibrium branch would otherwise lie on the zero line).
    Colour: configuration; line style: stability; marker: special-point kind, each with its own legend."""
    fig = make_subplots(rows=3, cols=1, shared_xaxes=True, vertical_spacing=0.05, row_heights=[0.4, 0.4, 0.2])
    for result in results:
        config = result["config"]
        colour, label = style.CONFIG_COLOURS[config], style.CONFIG_LABELS[config]
        for branch in result["branches"]:
            for seg_stable, seg in _segments(branch["points"]):
                line = {"color": colour, "width": 2.5 if seg_stable else 1.5, "dash": "solid" if seg_stable else "dash"}
                what = "stable" if seg_stable else "unstable"
                if branch["kind"] == "equilibrium":
                    fig.add_scatter(x=[p["V"] for p in seg], y=[label] * len(seg), mode="lines", line=line,
                                    legendgroup=config, showlegend=False, row=3, col=1,
                                    hovertemplate=f"{label}: straight rolling x = 0, {what}<br>V %{{x:.4g}} m/s"
                                                  "<extra></extra>")
                    continue
                for row, key, unit in ((1, "max_psi", "rad"), (2, "max_lateral", "m")):
                    fig.add_scatter(x=[p["V"] for p in seg], y=[p[key] for p in seg], mode="lines", line=line,
                                    legendgroup=config, showlegend=False, row=row, col=1,
                                    hovertemplate=f"{label}: limit cycle, {what}<br>V %{{x:.4g}} m/s<br>"
                                                  f"%{{y:.4g}} {unit}<extra></extra>")
    hopf_of = {(r["config"], round(h["V"], 6)): h for r in results for h in r["hopf_points"]}
    for result, branch, sp, name in _labelled(results):
        config = result["config"]
        colour, label = style.CONFIG_COLOURS[config], style.CONFIG_LABELS[config]
        hover = _hover(name, label, sp, hopf_of.get((config, round(sp["V"], 6))))
        marker = {"symbol": SYMBOLS[sp["kind"]], "size": 10, "color": colour, "line": {"width": 1, "color": "#333"}}
        spots = ([(3, label)] if branch["kind"] == "equilibrium"
                 else [(1, sp.get("max_psi", 0.0)), (2, sp.get("max_lateral", 0.0))])
        for row, y in spots:
            fig.add_scatter(x=[sp["V"]], y=[y], mode="markers+text", text=[name], textposition="top center",
                            textfont={"size": 10, "color": colour}, marker=marker, legendgroup=config,
                            showlegend=False, hovertext=[hover], hoverinfo="text", row=row, col=1,
                            meta={"special_point": name, "config": config})
    for config in dict.fromkeys(r["config"] for r in results):
        style.legend_key(fig, style.CONFIG_LABELS[config], "legend", group=config, mode="lines",
                         line={"color": style.CONFIG_COLOURS[config], "width": 3})
    style.legend_key(fig, "stable", "legend2", mode="lines", line={"color": "#555", "width": 2.5})
    style.legend_key(fig, "unstable", "legend2", mode="lines", line={"color": "#555", "width": 1.5, "dash": "dash"})
    present = {sp["kind"] for _, _, sp, _ in _labelled(results)} or {"H"}
    for kind, symbol in SYMBOLS.items():
        if kind not in present:
            continue
        style.legend_key(fig, f"{kind}: {KIND_NAMES[kind]}", "legend3", mode="markers",
                         marker={"symbol": symbol, "size": 9, "color": "#777", "line": {"width": 1, "color": "#333"}})
    fz = results[0]["Fz"] / 1e3 if results else 0
    fig.update_layout(title=style.title(f"Bifurcation diagram at Fz = {fz:g} kN"), height=HEIGHT,
                      template="plotly_white", margin={**style.MARGIN, "l": 70, "b": BOTTOM}, hovermode="closest")
    style.legends(fig, ["configuration (colour)", "stability (line)", "special points (marker)"], HEIGHT, BOTTOM)
    fig.update_xaxes(title_text="forward speed V (m/s)", row=3, col=1)
    fig.update_yaxes(title_text="max |psi| (rad)", row=1, col=1)
    fig.update_yaxes(title_text="max |l_g delta| (m)", row=2, col=1)
    fig.update_yaxes(title_text="x = 0", type="category", row=3, col=1,
                     categoryorder="array", categoryarray=[style.CONFIG_LABELS[r["config"]] for r in results][::-1])
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
    labelled = _labelled(results)
    rows = []
    for r in results:
        names = {(round(sp["V"], 9), sp["kind"]): name for res, _, sp, name in labelled if res is r}
        hopf = ", ".join(f"{names.get((round(h['V'], 9), 'H'), 'H')} {h['V']:.4g} ({h['criticality']})"
                         for h in r["hopf_points"]) or "none in range"
        special = [f"{name} {sp['V']:.4g}" for res, b, sp, name in labelled
                   if res is r and b["kind"] == "periodic" and sp["kind"] in ("LPC", "NS", "PD", "BPC")]
        rows.append([style.CONFIG_LABELS[r["config"]], hopf, f"{r['max_psi']:.4g}",
                     "–" if r["max_psi_V"] is None else f"{r['max_psi_V']:.4g}", ", ".join(special) or "–",
                     "; ".join(r["warnings"]) or "–"])
    return ui.table(["configuration", "Hopf points V (m/s)", "max stable |psi| (rad)", "at V (m/s)",
                     "fold (LPC) / torus (NS) / period-doubling (PD) points, V (m/s)", "warnings"], rows,
                    "bif-summary")


@dash.callback(Output("url-update", "data", allow_duplicate=True),
               Input("bif-fz", "value"), Input("bif-vmin", "value"), Input("bif-vmax", "value"),
               Input("bif-configs", "value"), prevent_initial_call=True)
def remember(fz, v_min, v_max, configs):
    return {"Fz": fz, "v_min": v_min, "v_max": v_max, "configs": ",".join(configs or [])}
