"""Bifurcation diagrams in V: amplitude of every branch, stable solid and unstable dashed."""

from __future__ import annotations

import math

import dash
from dash import Input, Output, State, html
from plotly.subplots import make_subplots

from shimmy.continuation.kinds import PointKind
from shimmy.errors import InvalidParameterError
import shimmy.model.units as units
from ui import compare, designs, fields, ids, jobs, markers
from ui import components as ui
from ui import style
from ui.fields import Quantity
from ui.layout import page

dash.register_page(__name__, path="/bifurcation", name="Bifurcation", order=3)

CONFIGS = ui.CONFIGS
#: The special points drawn (their markers: ui/markers.py, the legend in the vocabulary's order).
DRAWN = (PointKind.HOPF, PointKind.FOLD_OF_CYCLES, PointKind.TORUS, PointKind.PERIOD_DOUBLING,
         PointKind.BRANCH_POINT_OF_CYCLES, PointKind.BRANCH_POINT)
#: What the special points of cycles are (the summary table lists them).
CYCLE_POINTS = (PointKind.FOLD_OF_CYCLES, PointKind.TORUS, PointKind.PERIOD_DOUBLING,
                PointKind.BRANCH_POINT_OF_CYCLES)



FZ = Quantity("bifurcation", "Fz", "Fz", "kN", units.KN)
V_MIN = Quantity("bifurcation", "v_min", "lowest V", "m/s")
V_MAX = Quantity("bifurcation", "v_max", "highest V", "m/s")
WAITING = "Press Compute: about 1 s per configuration cold, instant from the cache"


def layout(Fz: str | None = None, v_min: str | None = None, v_max: str | None = None, configs: str | None = None,
           compare_config: str | None = None, **query):
    chosen, bad = fields.choices_list("configs", configs, CONFIGS, list(CONFIGS), "a configuration")
    compared, bad_compared = fields.choice("compare_config", compare_config, CONFIGS, "nes_pd", "a configuration")
    fz, p_fz = FZ.from_url("Fz", Fz, 150)
    lo, p_lo = V_MIN.from_url("v_min", v_min, 1)
    hi, p_hi = V_MAX.from_url("v_max", v_max, 200)
    problems = " ".join(p for p in (bad, p_fz, p_lo, p_hi) if p)
    return page(
        query, ids.BIF,
        ui.header("Bifurcation diagram", "Equilibrium and limit-cycle branches in the forward speed at one load, "
                  "by pseudo-arclength continuation with orthogonal collocation; stability from Floquet multipliers "
                  "(solid stable, dashed unstable); special points labelled as the continuation tools do: Hopf (H1, "
                  f"H2, ...), fold of cycles ({PointKind.FOLD_OF_CYCLES}), torus ({PointKind.TORUS}), period doubling "
                  f"({PointKind.PERIOD_DOUBLING}); hover one for its details. "
                  "The bottom strip shows where straight rolling is stable for each configuration."),
        html.Div([
            FZ.field("Fz (kN)", ids.BIF_FZ, fz),
            html.Div([V_MIN.field("V from (m/s)", ids.BIF_VMIN, lo),
                      V_MAX.field("to (m/s)", ids.BIF_VMAX, hi)], className="pair"),
            ui.field("Configurations", ui.configurations(ids.BIF_CONFIGS, chosen, multi=True)),
            ui.field("NES torque", ui.nes_torque(ids.BIF_EXACT)),
            *jobs.controls(ids.BIF_GROUP),
        ], className="controls"),
        html.Div(problems, id=ids.BIF_GROUP.error, className="error", role="alert"),
        ui.graph(ids.BIF_GRAPH, figure=style.message_figure(WAITING, 520)),
        html.Div(id=ids.BIF_TABLE, className="table-wrap"),
        ui.downloads(ids.BIF_GROUP),
        *jobs.stores(ids.BIF_GROUP),
        html.H2("Compare saved designs"),
        html.P("The designs ticked under Compare in the design panel (2 to 4; the current one may be one of them) "
               "at this page's load and speed range, for one configuration: one colour per design, the first the "
               "reference of the changes in the table. The x = 0 strip shows each design's Hopf interval (dashed: "
               "straight rolling unstable).", className="hint"),
        html.Div([ui.field("Configuration", ui.configurations(ids.BIFC_CONFIG, compared)),
                  *jobs.controls(ids.BIFC, "Compare")], className="controls"),
        html.Div(id=ids.BIFC.designs, className="compare-designs"),
        compare.follower(ids.BIF),
        html.Div(bad_compared, id=ids.BIFC.error, className="error", role="alert"),
        ui.graph(ids.BIFC_GRAPH, figure=style.message_figure(compare.waiting_text("about 2-5 s per design cold, "
                                                                                "instant from the cache"), 360)),
        html.Div(id=ids.BIFC_TABLE, className="table-wrap"),
        ui.downloads(ids.BIFC),
        *jobs.stores(ids.BIFC),
    )


fields.check(ids.BIF_FZ, FZ)
fields.check(ids.BIF_VMIN, V_MIN)
fields.check(ids.BIF_VMAX, V_MAX)


def _requests(fz_kn, v_min, v_max, configs, torque, design):
    if not configs:
        raise InvalidParameterError("configs", "", ", ".join(CONFIGS), "is empty",
                                    "Configurations: none chosen; choose at least one")
    fz, lo, hi = FZ.read(fz_kn), V_MIN.read(v_min), V_MAX.read(v_max)
    if not hi > lo:
        raise InvalidParameterError("v_max", v_max, f"above {v_min:g} m/s",
                                    message=f"highest V = {v_max:g} m/s must exceed lowest V = {v_min:g} m/s")
    return [{"config": c, "Fz": fz, "v_min": lo, "v_max": hi, **ui.exact_nes(c, torque), **design} for c in configs]


def _csv_rows(results):
    rows = [[r["config"], i, b["kind"], p["V"], "" if p["period"] is None else p["period"], p["max_psi"],
             units.to_mm(p["max_lateral"]), int(p["stable"]), p["mode"] or ""]
            for r in results for i, b in enumerate(r["branches"]) for p in b["points"]]
    return ["config", "branch", "kind", "V_m_s", "period_s", "max_psi_rad", "max_lateral_mm", "stable", "mode"], rows


jobs.register(
    ids.BIF_GROUP, "bifurcation", requests=_requests, render=lambda results: (figure(results), summary(results)),
    outputs=[Output(ids.BIF_GRAPH, "figure"), Output(ids.BIF_TABLE, "children")],
    states=[State(ids.BIF_FZ, "value"), State(ids.BIF_VMIN, "value"), State(ids.BIF_VMAX, "value"),
            State(ids.BIF_CONFIGS, "value"), State(ids.BIF_EXACT, "value"), State(ids.design_store(ids.BIF), "data")],
    notice=ui.result_notice,
    lock=[ids.BIF_FZ, ids.BIF_VMIN, ids.BIF_VMAX], download=jobs.Download(ids.BIF_GROUP, "bifurcation", _csv_rows),
    blank=lambda: (style.message_figure("Refused: see the message above", 520), None))


def _compare_requests(fz_kn, v_min, v_max, config, selection, saved, current):
    """The page's request for one configuration, once per compared design (the requests a design's
    own diagram makes: the cache serves a design already drawn)."""
    common = _requests(fz_kn, v_min, v_max, [config], "cubic", {})[0]
    return [{**common, **d.request()} for d in compare.chosen(selection, saved, current)]


def _compare_names(*values):
    return [d.name for d in compare.chosen(*values[4:])]


def _compare_render(results, names):
    series = compare.series(names)
    table = designs.comparison(names, results, designs.bifurcation_figures())
    return figure(results, series, what="design"), compare.table(table, ids.BIFC_SUMMARY)


def _compare_csv(results, names):
    columns, rows = _csv_rows(results)
    by_result = [name for r, name in zip(results, names, strict=True)
                 for b in r["branches"] for _ in b["points"]]
    return ["design", *columns], [[name, *row] for name, row in zip(by_result, rows, strict=True)]


jobs.register(
    ids.BIFC, "bifurcation", requests=_compare_requests, labels=_compare_names, render=_compare_render,
    outputs=[Output(ids.BIFC_GRAPH, "figure"), Output(ids.BIFC_TABLE, "children")],
    states=[State(ids.BIF_FZ, "value"), State(ids.BIF_VMIN, "value"), State(ids.BIF_VMAX, "value"),
            State(ids.BIFC_CONFIG, "value"), State(ids.DESIGN_COMPARE, "value"), State(ids.SAVED, "data"),
            State(ids.design_store(ids.BIF), "data")],
    lock=[ids.BIFC_CONFIG], download=jobs.Download(ids.BIFC, "bifurcation_designs", _compare_csv),
    blank=lambda: (style.message_figure("Refused: see the message above", 360), None))
compare.register_selection(ids.BIFC, ids.BIF)


HEIGHT, BOTTOM = 780, 190


def _labelled(results):
    """Special points numbered per configuration and kind in order of V (H1, H2, LPC1, NS1, ...), as the
    continuation tools label them: [(result, branch, point, label)]."""
    out = []
    for result in results:
        found = [(b, sp) for b in result["branches"] for sp in b["special_points"] if sp["kind"] in DRAWN
                 and not (sp["kind"] == PointKind.HOPF and b["kind"] != "equilibrium")]
        count: dict[str, int] = {}
        for b, sp in sorted(found, key=lambda item: (item[1]["kind"], item[1]["V"])):
            count[sp["kind"]] = count.get(sp["kind"], 0) + 1
            out.append((result, b, sp, f"{sp['kind']}{count[sp['kind']]}"))
    return out


def _hover(label: str, config_label: str, sp: dict, hopf: dict | None) -> str:
    lines = [f"<b>{config_label}: {label}</b> ({markers.of(sp['kind']).name})", f"V = {sp['V']:.5g} m/s"]
    if "max_psi" in sp:
        lines += [f"max |psi| = {sp['max_psi']:.4g} rad ({units.degrees(sp['max_psi'])})",
                  f"max |l_g delta| = {units.mm(sp['max_lateral'], 4)}"]
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


def figure(results, series=None, what="configuration"):
    """Amplitude of the periodic branches (rows 1-2) and the stability of straight rolling x = 0, one
    strip per result (row 3, where every equilibrium branch would otherwise lie on the zero line).
    Colour: the result's configuration, or ``series`` [(name, colour)] one per result (compared
    designs); line style: stability; marker: special-point kind, each with its own legend."""
    if series is None:
        series = [(style.CONFIG_LABELS[r["config"]], style.CONFIG_COLOURS[r["config"]]) for r in results]
    fig = make_subplots(rows=3, cols=1, shared_xaxes=True, vertical_spacing=0.05, row_heights=[0.4, 0.4, 0.2])
    for k, (result, (label, colour)) in enumerate(zip(results, series, strict=True)):
        group = f"{what}-{k}"
        for branch in result["branches"]:
            for seg_stable, seg in _segments(branch["points"], [sp["V"] for sp in branch["special_points"]]):
                line = {"color": colour, "width": 2.5 if seg_stable else 1.5, "dash": "solid" if seg_stable else "dash"}
                kind = "stable" if seg_stable else "unstable"
                if branch["kind"] == "equilibrium":
                    fig.add_scatter(x=[p["V"] for p in seg], y=[label] * len(seg), mode="lines", line=line,
                                    legendgroup=group, showlegend=False, row=3, col=1,
                                    hovertemplate=f"{label}: straight rolling x = 0, {kind}<br>V %{{x:.4g}} m/s"
                                                  "<extra></extra>")
                    continue
                psi = [p["max_psi"] for p in seg]
                fig.add_scatter(x=[p["V"] for p in seg], y=psi, mode="lines", line=line, legendgroup=group,
                                showlegend=False, row=1, col=1, customdata=style.in_degrees(psi),
                                hovertemplate=f"{label}: limit cycle, {kind}<br>V %{{x:.4g}} m/s<br>"
                                              f"max |psi| {style.ANGLE_HOVER}<extra></extra>")
                fig.add_scatter(x=[p["V"] for p in seg], y=[units.to_mm(p["max_lateral"]) for p in seg], mode="lines",
                                line=line, legendgroup=group, showlegend=False, row=2, col=1,
                                hovertemplate=f"{label}: limit cycle, {kind}<br>V %{{x:.4g}} m/s<br>"
                                              "max |l_g delta| %{y:.4g} mm<extra></extra>")
    index = {id(r): k for k, r in enumerate(results)}
    hopf_of = {(k, round(h["V"], 6)): h for k, r in enumerate(results) for h in r["hopf_points"]}
    for result, branch, sp, name in _labelled(results):
        k = index[id(result)]
        label, colour = series[k]
        hover = _hover(name, label, sp, hopf_of.get((k, round(sp["V"], 6))))
        marker = markers.marker(sp["kind"], colour)
        spots = ([(3, label)] if branch["kind"] == "equilibrium"
                 else [(1, sp.get("max_psi", 0.0)), (2, units.to_mm(sp.get("max_lateral", 0.0)))])
        for row, y in spots:
            fig.add_scatter(x=[sp["V"]], y=[y], mode="markers+text", text=[name], textposition="top center",
                            textfont={"size": 10, "color": colour}, marker=marker, legendgroup=f"{what}-{k}",
                            showlegend=False, hovertext=[hover], hoverinfo="text", row=row, col=1,
                            meta={"kind": markers.of(sp["kind"]).label, "special_point": name,
                                  "config": result["config"], "series": label})
    for k, result in enumerate(results):  # the largest stable torsional amplitude of each diagram
        label, colour = series[k]
        if result.get("max_psi_V") is not None and result.get("max_psi"):
            fig.add_scatter(x=[result["max_psi_V"]], y=[result["max_psi"]], mode="markers", row=1, col=1,
                            marker={"symbol": markers.LARGEST_PSI.symbol, "size": markers.LARGEST_PSI.size,
                                    "color": colour, "line": {"width": 2, "color": colour}},
                            legendgroup=f"{what}-{k}", showlegend=False, customdata=[math.degrees(result["max_psi"])],
                            meta={"mark": "largest stable |psi|", "series": label},
                            hovertemplate=f"<b>{label}: largest stable |psi|</b><br>V %{{x:.4g}} m/s<br>"
                                          f"{style.ANGLE_HOVER}<extra></extra>")
    for k, (label, colour) in enumerate(series):
        if (label, colour) not in series[:k]:
            style.legend_key(fig, label, "legend", group=f"{what}-{k}", mode="lines",
                             line={"color": colour, "width": 3})
    style.legend_key(fig, "stable", "legend2", mode="lines", line={"color": "#555", "width": 2.5})
    style.legend_key(fig, "unstable", "legend2", mode="lines", line={"color": "#555", "width": 1.5, "dash": "dash"})
    present = {sp["kind"] for _, _, sp, _ in _labelled(results)} or {PointKind.HOPF}
    markers.legend(fig, present, "legend3")
    if any(r.get("max_psi_V") is not None and r.get("max_psi") for r in results):
        style.legend_key(fig, markers.LARGEST_PSI.name, "legend3", mode="markers",
                         marker={"symbol": markers.LARGEST_PSI.symbol, "size": 11, "color": "#555",
                                 "line": {"width": 2, "color": "#555"}})
    fz = units.to_kn(results[0]["Fz"]) if results else 0
    head = ("Bifurcation diagram" if what == "configuration"
            else f"Bifurcation diagrams of {style.CONFIG_LABELS[results[0]['config']]}, {len(results)} designs")
    fig.update_layout(title=style.title(f"{head} at Fz = {fz:g} kN"), template=style.TEMPLATE,
                      margin={**style.MARGIN, "l": 70}, hovermode="closest")
    # long design names wrap the first legend row at 1024 px: the figure grows by the lines they take
    style.legends(fig, [f"{what} (colour)", "stability (line)", "special points (marker)"], HEIGHT, BOTTOM,
                  first_names=list(dict.fromkeys(label for label, _ in series)))
    fig.update_xaxes(title_text="forward speed V (m/s)", row=3, col=1)
    fig.update_yaxes(title_text="max |psi| (rad)", row=1, col=1)
    fig.update_yaxes(title_text="max |l_g delta| (mm)", row=2, col=1)
    names = list(dict.fromkeys(label for label, _ in series))[::-1]
    fig.update_yaxes(title_text="x = 0", type="category", row=3, col=1, categoryorder="array", categoryarray=names,
                     tickvals=names, ticktext=[n if len(n) <= 16 else n[:15] + "…" for n in names], automargin=True,
                     range=[-0.5, len(names) - 0.15])  # room above the top strip for its points' labels
    return fig


def _segments(points, boundaries=()):
    """Runs of equal stability, each sharing its end point with the next so that lines join. Where
    the last point of a run is a point where stability changes (``boundaries``: the branch's special
    points, a Hopf point on x = 0), the next run starts there; elsewhere the run reaches on to the
    next one's first point."""
    at = {round(v, 9) for v in boundaries}
    if not points:
        return []
    out, start, stable = [], 0, points[0]["stable"]
    for i in range(1, len(points) + 1):
        if i == len(points) or points[i]["stable"] != stable:
            if i < len(points) and i - 1 > start and round(points[i - 1]["V"], 9) in at:
                out.append((stable, points[start:i]))
                start = i - 1
            else:
                out.append((stable, points[start:min(i + 1, len(points))]))
                start = i
            stable = points[i]["stable"] if i < len(points) else stable
    return out


def summary(results):
    labelled = _labelled(results)
    rows = []
    for r in results:
        names = {(round(sp["V"], 9), sp["kind"]): name for res, _, sp, name in labelled if res is r}
        hopf = ", ".join(f"{names.get((round(h['V'], 9), PointKind.HOPF), PointKind.HOPF)} {h['V']:.4g} "
                         f"({h['criticality']})" for h in r["hopf_points"]) or "none in range"
        special = [f"{name} {sp['V']:.4g}" for res, b, sp, name in labelled
                   if res is r and b["kind"] == "periodic" and sp["kind"] in CYCLE_POINTS]
        rows.append([style.CONFIG_LABELS[r["config"]], hopf, f"{r['max_psi']:.4g}",
                     "–" if r["max_psi_V"] is None else f"{r['max_psi_V']:.4g}", ", ".join(special) or "–",
                     "; ".join(r["warnings"]) or "–"])
    return ui.table(["configuration", "Hopf points V (m/s)", "max stable |psi| (rad)", "at V (m/s)",
                     f"fold ({PointKind.FOLD_OF_CYCLES}) / torus ({PointKind.TORUS}) / period-doubling "
                     f"({PointKind.PERIOD_DOUBLING}) points, V (m/s)", "warnings"], rows,
                    ids.BIF_SUMMARY)


@dash.callback(Output(ids.URL_UPDATE, "data", allow_duplicate=True),
               Input(ids.BIF_FZ, "value"), Input(ids.BIF_VMIN, "value"), Input(ids.BIF_VMAX, "value"),
               Input(ids.BIF_CONFIGS, "value"), Input(ids.BIFC_CONFIG, "value"), prevent_initial_call=True)
def remember(fz, v_min, v_max, configs, compared):
    return {"Fz": fz, "v_min": v_min, "v_max": v_max, "configs": ",".join(configs or []),
            "compare_config": None if compared == "nes_pd" else compared}
