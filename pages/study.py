"""Parametric study: Hopf speeds and the largest torsional amplitude against a design parameter."""

from __future__ import annotations

import json

import dash
from dash import ALL, Input, Output, State, dcc, html
from plotly.subplots import make_subplots

from shimmy.errors import InvalidParameterError
import shimmy.model.units as units
from shimmy.model.configurations import affects
from shimmy.model.parameters import MATERIALS, PARAMETER_SPECS
from ui import components as ui
from ui import fields, formats, ids, jobs, markers, state
from ui import style
from ui.fields import Quantity
from ui.layout import page

dash.register_page(__name__, path="/study", name="Parametric study", order=5)

CONFIGS = ui.CONFIGS
DEFAULT_VALUES = "0.0005, 0.001, 0.002, 0.003, 0.004, 0.005"


def _unit(name: str) -> str:
    unit = PARAMETER_SPECS[name].unit
    return f" ({unit})" if unit else ""


FZ = Quantity("study", "Fz", "Fz", "kN", units.KN)
WAITING = "Press Compute: about 0.5-2 s per design and configuration cold, instant from the cache"
TABLE_VIEWS = {"long": "one row per value and configuration", "pivot": "one row per value, configurations side by side"}


def layout(parameter: str | None = None, values: str = DEFAULT_VALUES, configs: str | None = None,
           Fz: str | None = None, table: str | None = None, **query):
    parameter, bad_parameter = fields.choice("parameter", parameter, list(PARAMETER_SPECS), "e_p", "a parameter")
    chosen, bad_configs = fields.choices_list("configs", configs, CONFIGS, list(CONFIGS), "a configuration")
    fz, bad_fz = FZ.from_url("Fz", Fz, 150)
    view, bad_view = fields.choice("table", table, list(TABLE_VIEWS), "long", "a table layout")
    problems = " ".join(p for p in (bad_parameter, bad_configs, bad_fz, bad_view) if p)
    return page(
        query, ids.STUDY,
        ui.header("Parametric study", "Sweep one design parameter (the others at the current design) and tabulate, "
                  "per configuration, the first and last Hopf speed of straight rolling (shimmy onset and end of the "
                  "linear instability) and the largest torsional amplitude of a stable limit cycle, from a "
                  "bifurcation diagram per design. A device's parameter is studied only in the configurations that "
                  "have the device. Two-parameter grids: API and command line."),
        html.Div([
            ui.field("Parameter", dcc.Dropdown(id=ids.STUDY_PARAM, value=parameter, clearable=False,
                                               style={"width": "170px"},
                                               options=[{"label": f"{n}{_unit(n)}", "value": n}
                                                        for n in PARAMETER_SPECS])),
            html.Div([ui.field("Values (comma-separated)", dcc.Input(id=ids.STUDY_VALUES, type="text", value=values,
                                                                     debounce=True)),
                      fields.field_error(fields.error_id(ids.STUDY_VALUES))], className="wide"),
            FZ.field("Fz (kN)", ids.STUDY_FZ, fz),
            ui.field("Configurations", ui.configurations(ids.STUDY_CONFIGS, chosen, multi=True)),
            *jobs.controls(ids.STUDY_GROUP),
        ], className="controls"),
        html.Div(id=ids.STUDY_RANGE, className="hint"),
        html.Div(problems, id=ids.STUDY_GROUP.error, className="error", role="alert"),
        html.Div(id=ids.STUDY_SKIPPED, className="hint", role="status"),
        html.Div([ui.field("Amplitude axis", dcc.Checklist(id=ids.STUDY_LOG, value=[], inline=True,
                                                           options=[{"label": "logarithmic", "value": "log"}])),
                  ui.field("Table", dcc.RadioItems(id=ids.STUDY_VIEW, value=view, inline=True, options=[
                      {"label": label, "value": k} for k, label in TABLE_VIEWS.items()]))], className="controls"),
        ui.graph(ids.STUDY_GRAPH, figure=style.message_figure(WAITING, 560)),
        html.Div(id=ids.STUDY_TABLE, className=f"table-wrap view-{view}"),
        ui.downloads(ids.STUDY_GROUP),
        *jobs.stores(ids.STUDY_GROUP),
    )


@dash.callback(Output(ids.STUDY_RANGE, "children"), Input(ids.STUDY_PARAM, "value"))
def allowed(name):
    spec = PARAMETER_SPECS[name]
    return f"{name}: {spec.description}; {spec.allowed}; current default {spec.default:g}"


@dash.callback(Output(ids.STUDY_SKIPPED, "children"), Input(ids.STUDY_PARAM, "value"), Input(ids.STUDY_CONFIGS,
                                                                                             "value"))
def skipped(name, configs):
    """Which chosen configurations the parameter cannot affect (they are left out of the study)."""
    out = [c for c in configs or [] if not affects(name, c)]
    if not out:
        return ""
    device = {"nes": "the NES", "pd": "the particle damper"}.get(PARAMETER_SPECS[name].group, "")
    return (f"Skipped: {', '.join(style.CONFIG_LABELS[c] for c in out)} — {name} is a parameter of {device}, "
            f"which {'this configuration does' if len(out) == 1 else 'these configurations do'} not have "
            "(its curve would be a flat line).")


fields.check(ids.STUDY_FZ, FZ)


@dash.callback(Output(fields.error_id(ids.STUDY_VALUES), "children"), Input(ids.STUDY_VALUES, "value"),
               Input(ids.STUDY_PARAM, "value"), prevent_initial_call=True)
def check_values(text, parameter):
    """The values' box says at once (on Enter or leaving it) which value it refuses, as typed, and the range."""
    return fields.refusal(lambda t: _values(parameter, t), text)


def _request(parameter, text, fz_kn, configs, design):
    """The study request; a value that is not a number is reported by its position, like the API does."""
    values = _values(parameter, text)
    if not configs:
        raise InvalidParameterError("configs", "", ", ".join(CONFIGS), message="Configurations: none chosen; "
                                    "choose at least one")
    studied = [c for c in configs if affects(parameter, c)]
    if not studied:
        raise InvalidParameterError("configs", ",".join(configs), "a configuration the parameter enters",
                                    message=f"{parameter} enters none of the chosen configurations: choose one "
                                            "with its device")
    return {"parameter": parameter, "values": values, "configs": studied, "Fz": FZ.read(fz_kn), **design}


def _values(parameter, text) -> list[float]:
    """The typed values of ``parameter``, each refused by its position, as typed, in the parameter's unit."""
    spec = PARAMETER_SPECS[parameter]
    if not text or not text.strip():
        raise InvalidParameterError("values", text, spec.allowed,
                                    message=f"Values is empty: enter comma-separated values of {parameter}, "
                                            f"each {spec.allowed}")
    values = []
    for k, item in enumerate(t.strip() for t in text.split(",")):
        if not item:
            continue
        try:
            values.append(float(item))
        except ValueError:
            raise InvalidParameterError(f"values[{k}]", item, spec.allowed,
                                        message=f"value {k + 1} ({item!r}) is not a number; enter "
                                                f"{spec.allowed}") from None
        if not spec.low <= values[-1] <= spec.high:
            unit = f" {spec.unit}" if spec.unit else ""
            raise InvalidParameterError(f"values[{k}]", values[-1], spec.allowed,
                                        message=f"value {k + 1}: {parameter} = {item}{unit} is outside "
                                                f"[{spec.low:g}, {spec.high:g}]{unit}")
    return values


CONTROLS = (State(ids.STUDY_PARAM, "value"), State(ids.STUDY_VALUES, "value"), State(ids.STUDY_FZ, "value"),
            State(ids.STUDY_CONFIGS, "value"), State(ids.design_store(ids.STUDY), "data"))


def _csv_rows(results):
    result = results[0]
    name = result["parameters"][0]
    rows = [[r[name], r["config"], r["hopf_start"], r["hopf_end"], r["max_psi"], r["max_psi_V"]]
            for r in result["rows"]]
    return [name, "config", "hopf_start_m_s", "hopf_end_m_s", "max_psi_rad", "max_psi_V_m_s"], rows


jobs.register(
    ids.STUDY_GROUP, "study", requests=lambda *controls: [_request(*controls)],
    render=lambda results: (figure(results[0]), summary(results[0])),
    outputs=[Output(ids.STUDY_GRAPH, "figure"), Output(ids.STUDY_TABLE, "children")], states=CONTROLS,
    lock=[ids.STUDY_PARAM, ids.STUDY_VALUES, ids.STUDY_FZ],
    download=jobs.Download(ids.STUDY_GROUP, "study", _csv_rows, single=True),
    blank=lambda: (style.message_figure("Refused: see the message above", 560), None))


HEIGHT, BOTTOM = 1020, 130
#: The vertical line at the current design's value of the parameter (drawn in the browser: it follows the panel).
CURRENT_DESIGN_LINE = {"color": "#555", "dash": "dot", "width": 1.5}
#: the panels: (key of a sampled row, quantity of an exact curve, axis title, scale of the values)
PANELS = (("hopf_start", "hopf_V_start", "first Hopf V (m/s)", 1.0),
          ("hopf_end", "hopf_V_end", "last Hopf V (m/s)", 1.0),
          (None, "min_shimmy_Fz", "lowest Hopf Fz (kN)", 1 / units.KN),
          ("max_psi", "max_psi", "max stable |psi| (rad)", 1.0))
#: the last panel: the loads of the GH and double-Hopf points of the Hopf curves in (V, Fz), each point a
#: line (its kind's marker on the line), the speed in the hover
POINT_PANEL = "GH, HH load (kN)"
POINT_KINDS = {"gh_Fz": ("gh_V", "GH", "dash"), "double_hopf_Fz": ("double_hopf_V", "HH", "dot")}


def figure(result):
    """Per configuration: the exact curves over the parameter's whole range (lines; the points where
    the picture changes as crosses) with the sampled diagrams' values as markers on them; the largest
    amplitude on its grid of diagrams over the whole range (small dots joined by lines)."""
    name = result["parameters"][0]
    fig = make_subplots(rows=len(PANELS) + 1, cols=1, shared_xaxes=True, vertical_spacing=0.04)
    curves = {(c["config"], c["quantity"]): c for c in result.get("curves") or []}
    kinds: set[str] = set()
    largest = False
    for config in result["configs"]:
        rows = sorted((r for r in result["rows"] if r["config"] == config), key=lambda r: r[name])
        x = [r[name] for r in rows]
        colour, label = style.CONFIG_COLOURS[config], style.CONFIG_LABELS[config]
        shown = False
        for row, (key, quantity, _, scale) in enumerate(PANELS, start=1):
            curve = curves.get((config, quantity))
            hover = f"{label}<br>{name} %{{x:.4g}}<br>%{{y:.6g}}<extra>WHAT</extra>"
            if curve is not None:
                gridded = quantity == "max_psi"  # exact at its grid values (a diagram each), joined between them
                fig.add_scatter(x=curve["p"], y=[None if v is None else v * scale for v in curve["values"]],
                                mode="lines+markers" if gridded else "lines", name=label, legendgroup=config,
                                showlegend=not shown, line={"color": colour, "width": 2},
                                marker={"size": 4, "color": colour},
                                hovertemplate=hover.replace("WHAT", "diagram at a grid value" if gridded
                                                            else "exact curve"), row=row, col=1)
                shown = True
                marks = [q for q in curve["special_points"] if isinstance(q.get("value"), (int, float))]
                for kind in dict.fromkeys(q["kind"] for q in marks):  # one trace per kind: its own marker
                    m = markers.of(kind)
                    kinds.add(kind)
                    here = [q for q in marks if q["kind"] == kind]
                    fig.add_scatter(x=[q["p"] for q in here], y=[q["value"] * scale for q in here], mode="markers",
                                    name=f"{label}: {m.name}", legendgroup=config, showlegend=False,
                                    marker=markers.marker(kind, colour), meta={"kind": m.label}, row=row, col=1,
                                    hovertemplate=f"{label}: {m.legend}<br>{name} %{{x:.6g}}<br>%{{y:.6g}}"
                                                  "<extra></extra>")
            if key is not None:
                y = [r[key] for r in rows]
                angle = key == "max_psi"
                fig.add_scatter(x=x, y=y, name=label, legendgroup=config, showlegend=not shown,
                                mode="markers" if curve is not None else "lines+markers",
                                line={"color": colour, "width": 2},
                                marker={"size": 8, "color": colour, "line": {"width": 1.5, "color": "#fff"}},
                                customdata=style.in_degrees(y) if angle else None,
                                hovertemplate=(f"{label}<br>{name} %{{x:.4g}}<br>{style.ANGLE_HOVER}"
                                               "<extra>sampled diagram</extra>") if angle else
                                hover.replace("WHAT", "sampled diagram"), row=row, col=1)
                shown = True
                best = max((r for r in rows if r["max_psi"] is not None), key=lambda r: r["max_psi"], default=None)
                if angle and best is not None and best["max_psi"] > 0:  # the largest stable |psi| of the study
                    largest = True
                    fig.add_scatter(x=[best[name]], y=[best["max_psi"]], mode="markers", legendgroup=config,
                                    showlegend=False, customdata=style.in_degrees([best["max_psi"]]),
                                    marker={"symbol": markers.LARGEST_PSI.symbol, "size": markers.LARGEST_PSI.size,
                                            "color": colour, "line": {"width": 2, "color": colour}},
                                    meta={"mark": "largest stable |psi|", "config": config}, row=row, col=1,
                                    hovertemplate=f"<b>{label}: largest stable |psi|</b><br>{name} %{{x:.6g}}<br>"
                                                  f"{style.ANGLE_HOVER}<extra></extra>")
    kinds |= _codim2_points(fig, result, name, len(PANELS) + 1)
    markers.legend(fig, kinds, "legend2")
    if largest:
        style.legend_key(fig, markers.LARGEST_PSI.name, "legend2", mode="markers",
                         marker={"symbol": markers.LARGEST_PSI.symbol, "size": 11, "color": "#555",
                                 "line": {"width": 2, "color": "#555"}})
    style.legend_key(fig, markers.CURRENT_DESIGN.name, "legend2", mode="lines",
                     line={"color": CURRENT_DESIGN_LINE["color"], "dash": CURRENT_DESIGN_LINE["dash"], "width": 1.5})
    fig.update_layout(title=style.title(f"Study in {name} at Fz = {units.to_kn(result['Fz']):g} kN: exact curves "
                                        "(lines), sampled diagrams (markers)"), height=HEIGHT,
                      template=style.TEMPLATE, margin={**style.MARGIN, "l": 70, "b": BOTTOM},
                      meta={"study": {"parameter": name, "unit": PARAMETER_SPECS[name].unit}})
    style.legends(fig, ["configuration (colour)", "points, marks"], HEIGHT, BOTTOM)
    fig.update_xaxes(title_text=f"{name}{_unit(name)}", row=len(PANELS) + 1, col=1)
    for row, (_, _, title, _) in enumerate(PANELS, start=1):
        fig.update_yaxes(title_text=title, row=row, col=1)
    fig.update_yaxes(title_text=POINT_PANEL, row=len(PANELS) + 1, col=1)
    return fig


def _codim2_points(fig, result, name: str, row: int) -> set[str]:
    """The GH and double-Hopf points' loads against the parameter (a line per point through its exact
    values, dashed for GH, dotted for double Hopf, the kind's marker at its first and last value; the
    speed in the hover); the kinds drawn."""
    speeds = {(c["config"], c["quantity"], c.get("point")): c for c in result.get("curves") or []}
    drawn: set[str] = set()
    for c in result.get("curves") or []:
        if c["quantity"] not in POINT_KINDS:
            continue
        v_name, kind, dash = POINT_KINDS[c["quantity"]]
        speed = speeds.get((c["config"], v_name, c.get("point")))
        colour, label = style.CONFIG_COLOURS[c["config"]], style.CONFIG_LABELS[c["config"]]
        m = markers.of(kind)
        drawn.add(kind)
        # the kind's marker at the first and last value, the exact values joined by the kind's dash
        known = [i for i, v in enumerate(c["values"]) if v is not None]
        ends_at = {known[0], known[-1]} if known else set()
        fig.add_scatter(x=c["p"], y=[None if v is None else units.to_kn(v) for v in c["values"]], mode="lines+markers",
                        line={"color": colour, "width": 1.5, "dash": dash}, legendgroup=c["config"], showlegend=False,
                        marker={**markers.marker(kind, colour, size=9),
                                "size": [9 if i in ends_at else 0 for i in range(len(c["p"]))]},
                        name=f"{label}: {m.name} {c.get('point')}",
                        customdata=None if speed is None else speed["values"], meta={"kind": m.label, "point": True},
                        hovertemplate=f"{label}: {m.name} point {c.get('point')}<br>{name} %{{x:.6g}}<br>"
                                      "Fz %{y:.6g} kN" + ("" if speed is None else ", V %{customdata:.5g} m/s")
                                      + "<extra>exact curve</extra>", row=row, col=1)
        ends = [q for q in c["special_points"] if q.get("kind") == "end" and q.get("value") is not None]
        if ends:
            drawn.add("EP")
            fig.add_scatter(x=[q["p"] for q in ends], y=[units.to_kn(q["value"]) for q in ends], mode="markers",
                            marker=markers.marker("EP", colour), legendgroup=c["config"], showlegend=False,
                            meta={"kind": markers.of("EP").label}, row=row, col=1,
                            customdata=[q.get("why", "") for q in ends],
                            hovertemplate=f"{label}: {m.name} point {c.get('point')} ends<br>{name} %{{x:.8g}}<br>"
                                          "Fz %{y:.6g} kN<br>%{customdata}<extra></extra>")
    return drawn


def summary(result):
    """Both layouts of the table (the page shows the one chosen): long, and pivoted by configuration."""
    name = result["parameters"][0]
    ordered = sorted(result["rows"], key=lambda r: (r[name], CONFIGS.index(r["config"])))
    rows = [[f"{r[name]:.6g}", style.CONFIG_LABELS[r["config"]], formats.significant(r["hopf_start"], 6),
             formats.significant(r["hopf_end"], 6), formats.significant(r["max_psi"], 5),
             formats.significant(r["max_psi_V"], 4), "; ".join(r["warnings"]) or "–"]
            for r in ordered]
    long = ui.table([f"{name}{_unit(name)}", "configuration", "first Hopf V (m/s)", "last Hopf V (m/s)",
                     "max stable |psi| (rad)", "at V (m/s)", "warnings"], rows, ids.STUDY_SUMMARY)
    configs = [c for c in CONFIGS if c in result["configs"]]
    by_value: dict[float, dict[str, dict]] = {}
    for r in ordered:
        by_value.setdefault(r[name], {})[r["config"]] = r
    columns = [f"{name}{_unit(name)}"]
    for what in ("first Hopf V (m/s)", "last Hopf V (m/s)", "max |psi| (rad)"):
        columns += [f"{what}, {style.CONFIG_LABELS[c]}" for c in configs]
    pivot_rows = []
    for value, per in by_value.items():
        row = [f"{value:.6g}"]
        for key, digits in (("hopf_start", 6), ("hopf_end", 6), ("max_psi", 5)):
            row += [formats.significant(per[c][key], digits) if c in per else "–" for c in configs]
        pivot_rows.append(row)
    pivot = ui.table(columns, pivot_rows, ids.STUDY_PIVOT)
    return [html.Div(long, className="study-long"), html.Div(pivot, className=ids.STUDY_PIVOT)]


# The table layout and the amplitude axis are views of the shown result: switched in the browser.
dash.clientside_callback(
    """function(view) { return "table-wrap view-" + (view || "long"); }""",
    Output(ids.STUDY_TABLE, "className"), Input(ids.STUDY_VIEW, "value"))

dash.clientside_callback(
    """
    function(log, fig) {
        const C = window.dash_clientside;
        if (!fig || !fig.layout || !fig.layout.yaxis4) { return C.no_update; }
        const type = (log || []).includes("log") ? "log" : "linear";
        if ((fig.layout.yaxis4.type || "linear") === type) { return C.no_update; }
        const layout = Object.assign({}, fig.layout, {yaxis4: Object.assign({}, fig.layout.yaxis4, {type: type,
                                     autorange: true})});
        return Object.assign({}, fig, {layout: layout});
    }
    """,
    Output(ids.STUDY_GRAPH, "figure", allow_duplicate=True), Input(ids.STUDY_LOG, "value"), Input(ids.STUDY_GRAPH,
                                                                                                  "figure"),
    prevent_initial_call=True)


# The current design's value of the studied parameter, a dotted vertical line over every panel: drawn in the
# browser from the design panel's store, so that it follows a slider (the study itself is of the design it was
# asked for: each row says its values).
dash.clientside_callback(
    """
    function(stores, fig) {
        const C = window.dash_clientside, BASE = %(base)s, DEFAULT = %(default)s, LINE = %(line)s;
        if (!fig || !fig.layout || !fig.layout.meta || !fig.layout.meta.study) { return C.no_update; }
        const design = (stores || [])[0] || {}, study = fig.layout.meta.study, name = study.parameter;
        const params = design.params || {}, base = BASE[design.material || DEFAULT] || BASE[DEFAULT];
        const value = params[name] !== undefined ? params[name] : base[name];
        const others = (fig.layout.shapes || []).filter(s => s.name !== "current design");
        const old = (fig.layout.shapes || []).find(s => s.name === "current design");
        if (old && old.x0 === value) { return C.no_update; }
        const text = "current design: " + name + " = " + Number(value.toPrecision(6)) +
                     (study.unit ? " " + study.unit : "");
        const shapes = others.concat([{name: "current design", type: "line", xref: "x", yref: "paper", x0: value,
                                       x1: value, y0: 0, y1: 1, line: LINE}]);
        const notes = (fig.layout.annotations || []).filter(a => a.name !== "current design").concat([
            {name: "current design", text: text, xref: "x", yref: "paper", x: value, y: 1, yanchor: "top",
             xanchor: "left", xshift: 3, showarrow: false, bgcolor: "rgba(255,255,255,0.85)",
             font: {size: 11, color: LINE.color}}]);
        return Object.assign({}, fig, {layout: Object.assign({}, fig.layout, {shapes: shapes, annotations: notes})});
    }
    """ % {"base": json.dumps({m: state.material_params(m) for m in MATERIALS}),
           "default": json.dumps(state.DEFAULT_MATERIAL), "line": json.dumps(CURRENT_DESIGN_LINE)},
    Output(ids.STUDY_GRAPH, "figure", allow_duplicate=True), Input(ids.design_store(ALL), "data"),
    Input(ids.STUDY_GRAPH, "figure"), prevent_initial_call=True)


@dash.callback(Output(ids.URL_UPDATE, "data", allow_duplicate=True),
               Input(ids.STUDY_PARAM, "value"), Input(ids.STUDY_VALUES, "value"), Input(ids.STUDY_FZ, "value"),
               Input(ids.STUDY_CONFIGS, "value"), Input(ids.STUDY_VIEW, "value"), prevent_initial_call=True)
def remember(parameter, values, fz, configs, view):
    return {"parameter": parameter, "values": values, "Fz": fz, "configs": ",".join(configs or []),
            "table": None if view == "long" else view}
