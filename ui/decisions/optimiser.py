"""Design decisions (b): the optimiser over the device parameters, a figure of merit under
constraints on the others (the service's optimise job)."""

from __future__ import annotations

import math
from urllib.parse import urlencode

import dash
from dash import Input, Output, State, dash_table, dcc, html

from shimmy.errors import InvalidParameterError
from shimmy.model.configurations import affects
from shimmy.model.parameters import PARAMETER_SPECS
from shimmy.service import schemas
from ui import components as ui
from ui import formats, ids, jobs, style
from ui.fields import Quantity
from ui.layout import DESIGN

from .common import DOWN, FIGURES, FZ, GRID, OPS, TABLE_STYLE, UP, check_field, field_error, refusal, unit_suffix

STARTS = Quantity("optimise", "starts", "start designs", "")
RUNS = Quantity("optimise", "local_runs", "local searches", "")
OPT_SEED = Quantity("optimise", "seed", "optimiser seed", "")
#: Shorter names of the figures where a control has less room than a table (the objectives, the constraints).
SHORT = {"interval": "shimmy speed interval at Fz", "torsion_area": "pure-torsion area"}


def _objective(name: str) -> str:
    """'maximise the minimum shimmy load': the figure's sense and name; the slow method said."""
    verb = "maximise" if schemas.FIGURES[name].sense > 0 else "minimise"
    slow = "" if name in schemas.DIFFERENTIABLE else " (differential evolution: minutes)"
    return f"{verb} the {SHORT.get(name, FIGURES[name][0])}{slow}"


OBJECTIVES = {name: _objective(name) for name in FIGURES}


def figure_option(name: str) -> str:
    """How the constraint table's dropdown names a figure: short, with the unit its value is typed in."""
    short = {**SHORT, "max_psi": "largest stable |psi| at Fz"}
    return f"{short.get(name, FIGURES[name][0])} ({FIGURES[name][1]})"


def default_search(config: str) -> list[str]:
    """The parameters searched unless the address says otherwise: the service's default ones the configuration has."""
    chosen = [n for n in schemas.DEFAULT_SEARCH if affects(n, config)]
    return chosen or [n for n in DESIGN if affects(n, config)]


def search_options(config: str) -> list[dict]:
    """The device parameters as check boxes, those the configuration does not have greyed out."""
    return [{"label": f"{n}{unit_suffix(n)}", "value": n, "disabled": not affects(n, config)} for n in DESIGN]


def section(a) -> list:
    """The section's heading, controls, results and downloads, as the address ``a`` (an
    :class:`~ui.decisions.address.Address`) sets them."""
    return [
        html.H2("Optimiser", id=ids.OPTIMISER),
        html.P("Searches the chosen device parameters within their ranges (the others as in the design panel). "
               "Gradient method: Sobol start designs (the current design among them), then SLSQP with the "
               "sensitivities as gradients; differential evolution where a figure has no derivative.",
               className="hint"),
        html.Div([
            ui.field("Objective", dcc.Dropdown(id=ids.OPT_OBJECTIVE, value=a.goal, clearable=False,
                                               style={"width": "430px"},
                                               options=[{"label": v, "value": k} for k, v in OBJECTIVES.items()])),
            html.Div([html.Label("Parameters to search"),
                      dcc.Checklist(id=ids.OPT_SEARCH, value=a.chosen, inline=True,
                                    options=search_options(a.config)),
                      field_error(ids.OPT_SEARCH_ERROR, a.bad_search)], className="field"),
        ], className="controls"),
        html.Div([
            html.Label("Constraints (each value in the figure's unit; Fz: the load above)",
                       style={"fontSize": "13px", "color": "var(--muted)"}),
            dash_table.DataTable(
                id=ids.OPT_CONSTRAINTS, data=a.constraint_rows, editable=True, row_deletable=True, **TABLE_STYLE,
                columns=[{"name": "figure", "id": "figure", "presentation": "dropdown"},
                         {"name": "", "id": "op", "presentation": "dropdown"},
                         {"name": "value", "id": "value", "type": "numeric",
                          "on_change": {"action": "coerce", "failure": "accept"}}],
                dropdown={"figure": {"options": [{"label": figure_option(f), "value": f} for f in FIGURES],
                                     "clearable": False},
                          "op": {"options": [{"label": v, "value": k} for k, v in OPS.items()], "clearable": False}},
                style_cell_conditional=[{"if": {"column_id": "figure"}, "width": "270px", "minWidth": "270px"},
                                        {"if": {"column_id": "op"}, "width": "64px", "minWidth": "64px"},
                                        {"if": {"column_id": "value"}, "width": "110px", "minWidth": "110px"}]),
            html.Button("Add constraint", id=ids.OPT_ADD, className="secondary", style={"marginTop": "6px"}),
            field_error(ids.OPT_CONSTRAINTS_ERROR, a.bad_cons),
        ]),
        html.Div([
            html.Div([ui.field(f"Start designs ({STARTS.low:g}-{STARTS.high:g})",
                               STARTS.box(ids.OPT_STARTS, a.n_starts, debounce=True)),
                      field_error(ids.OPT_STARTS_ERROR, a.bad_starts)]),
            html.Div([ui.field(f"Local searches ({RUNS.low:g}-{RUNS.high:g})",
                               RUNS.box(ids.OPT_RUNS, a.n_runs, debounce=True)),
                      field_error(ids.OPT_RUNS_ERROR, a.bad_runs)]),
            html.Div([ui.field("Seed", OPT_SEED.box(ids.OPT_SEED, a.o_seed, debounce=True)),
                      field_error(ids.OPT_SEED_ERROR, a.bad_oseed)]),
            *jobs.controls(ids.OPT, "Optimise"),
        ], className="controls"),
        html.Div(id=ids.OPT.error, className="error", role="alert"),
        html.Div(id=ids.OPT.stale, className="hint", role="status"),
        html.Div(id=ids.OPT_SUMMARY),
        html.Div([html.Div(id=ids.OPT_DESIGN, className="table-wrap"), html.Div(id=ids.OPT_FIGURES,
                                                                               className="table-wrap")],
                 style={**GRID, "alignItems": "start"}),
        ui.graph(ids.OPT_HISTORY, figure=style.message_figure("The convergence history appears here", 300)),
        ui.downloads(ids.OPT),
        *jobs.stores(ids.OPT),
    ]


def _constraints(rows) -> list[dict]:
    """The table's constraints as request items (SI units); refused by row, in the figure's unit."""
    out = []
    for k, row in enumerate(rows or []):
        figure, op, value = row.get("figure"), row.get("op"), row.get("value")
        where = f"constraint {k + 1}"
        if figure not in FIGURES:
            raise InvalidParameterError(f"constraints[{k}].figure", figure, "one of " + ", ".join(FIGURES),
                                        message=f"{where}: choose a figure")
        if op not in OPS:
            raise InvalidParameterError(f"constraints[{k}].op", op, "≤ or ≥", message=f"{where}: choose ≤ or ≥")
        label, unit, scale = FIGURES[figure]
        _, _, low, high = schemas.FIGURE_LIMITS[figure]
        allowed = f"a number in [{low / scale:g}, {high / scale:g}] {unit}"
        if value is None or isinstance(value, bool) or (isinstance(value, str) and not value.strip()):
            raise InvalidParameterError(f"constraints[{k}].value", value, allowed,
                                        message=f"{where} ({figure}): the value is empty; enter {allowed}")
        try:
            number = float(value)
        except (TypeError, ValueError):
            raise InvalidParameterError(f"constraints[{k}].value", value, allowed,
                                        message=f"{where} ({figure}): {value!s} is not a number; enter "
                                                f"{allowed}") from None
        if not (math.isfinite(number) and low / scale <= number <= high / scale):
            raise InvalidParameterError(f"constraints[{k}].value", value, allowed,
                                        message=f"{where}: {figure} {OPS[op]} {number:g} {unit} is outside "
                                                f"[{low / scale:g}, {high / scale:g}] {unit}")
        out.append({"figure": figure, "op": op, "value": number * scale})
    return out


def _search(config, names) -> list[str]:
    names = [n for n in names or [] if affects(n, config)]
    if not names:
        raise InvalidParameterError("parameters", [], "one or more device parameters of " + config,
                                    message=f"Parameters to search: none chosen that {style.CONFIG_LABELS[config]} "
                                            "has; tick at least one")
    return names


def _requests(config, fz_kn, objective, search, rows, starts, runs, seed, design):
    fz = FZ.read(fz_kn)
    names = _search(config, search)
    constraints = _constraints(rows)
    n_starts, n_runs = STARTS.read(starts), RUNS.read(runs)
    if n_runs > n_starts:
        raise InvalidParameterError("local_runs", runs, f"at most {n_starts}",
                                    message=f"local searches = {n_runs} exceeds start designs = {n_starts}")
    return [{"config": config, "objective": objective, "parameters": names, "Fz": fz, "constraints": constraints,
             "starts": n_starts, "local_runs": n_runs, "seed": OPT_SEED.read(seed), **design}]


check_field(ids.OPT_STARTS, ids.OPT_STARTS_ERROR, STARTS)
check_field(ids.OPT_RUNS, ids.OPT_RUNS_ERROR, RUNS)
check_field(ids.OPT_SEED, ids.OPT_SEED_ERROR, OPT_SEED)


@dash.callback(Output(ids.OPT_CONSTRAINTS_ERROR, "children"), Input(ids.OPT_CONSTRAINTS, "data"),
               prevent_initial_call=True)
def check_constraints(rows):
    return refusal(_constraints, rows)


@dash.callback(Output(ids.OPT_SEARCH, "options"), Output(ids.OPT_SEARCH, "value"),
               Output(ids.OPT_SEARCH_ERROR, "children"), Input(ids.DES_CONFIG, "value"), State(ids.OPT_SEARCH, "value"),
               prevent_initial_call=True)
def search_for_config(config, chosen):
    """The device parameters the configuration has can be ticked; the others are greyed out."""
    kept = [n for n in chosen or [] if affects(n, config)]
    return search_options(config), kept or default_search(config), ""


@dash.callback(Output(ids.OPT_CONSTRAINTS, "data", allow_duplicate=True), Input(ids.OPT_ADD, "n_clicks"),
               State(ids.OPT_CONSTRAINTS, "data"), prevent_initial_call=True)
def add_constraint(_n, rows):
    return [*(rows or []), {"figure": "max_psi", "op": "<=", "value": 0.2}]


def _figure_key(key: str) -> tuple[str, str, float]:
    """'max_psi@150000' -> (label with its load, unit, SI units per shown unit)."""
    name, _, at = key.partition("@")
    label, unit, scale = FIGURES.get(name, (name, "", 1.0))
    if at:
        label = label.replace(" at Fz", "") + f" at {float(at) / 1e3:g} kN"
    return label, unit, scale


def opt_summary(result):
    f = result["objective_figure"]
    label, unit, scale = _figure_key(f["name"] + (f"@{f['Fz']:g}" if f["Fz"] is not None else ""))
    change = result["objective"] - result["nominal_objective"]
    link = "/?" + urlencode(result["link_query"])
    status = "" if result["feasible"] else " No design met every constraint: the least violating one is shown."
    return [
        html.P([html.Strong(f"{f['sense'].capitalize()} {label}: "),
                f"{result['objective'] / scale:.5g} {unit} at the optimum against "
                f"{result['nominal_objective'] / scale:.5g} {unit} for the current design ({change / scale:+.4g} "
                f"{unit}); {result['evaluations']} evaluations ({result['method']}), {result['elapsed_s']:.1f} s. "
                f"{result['message']}.{status}"],
               id=ids.OPT_RESULT_LINE),
        html.P([html.A("Open the optimum in the workbench", href=link, id=ids.OPT_LINK),
                html.Span(f"  ({link})", className="hint")]),
        *[html.P(w, className="note") for w in result["warnings"]],
    ]


def opt_design(result):
    base = result["params"]
    bounds = {b["name"]: b["bound"] for b in result.get("at_bounds", ())}
    rows = []
    for name in result["parameters"]:
        spec = PARAMETER_SPECS[name]
        old, new = base[name], result["design"][name]
        rows.append([name, spec.unit or "–", f"{formats.compact(spec.low)} – {formats.compact(spec.high)}",
                     formats.compact(old), formats.compact(new),
                     formats.signed_percent(100 * (new - old) / old if old else None),
                     {"low": "lower bound: the range limits it", "high": "upper bound: the range limits it"}.get(
                         bounds.get(name), "inside the range")])
    return ui.table(["parameter", "unit", "range", "current design", "optimum", "change", "optimum in the range"],
                    rows, ids.OPT_DESIGN_TABLE)


def opt_figures(result):
    tables = result["figures"]
    keys = list(tables["optimum"]) if "error" not in tables["optimum"] else list(tables["nominal"])
    rows = []
    for key in keys:
        label, unit, scale = _figure_key(key)
        cells = []
        for which in ("optimum", "nominal", "original"):
            value = tables[which].get(key) if "error" not in tables[which] else None
            cells.append("–" if value is None else f"{value / scale:.5g}")
        rows.append([f"{label} ({unit})", *cells])
    return ui.table(["figure", "optimum", "current design", "original"], rows, ids.OPT_FIGURES_TABLE)


def opt_history(result):
    """Objective of every evaluation, the best feasible so far, infeasible designs marked."""
    f = result["objective_figure"]
    label, unit, scale = _figure_key(f["name"] + (f"@{f['Fz']:g}" if f["Fz"] is not None else ""))
    fig = style.figure("Convergence: objective of each evaluated design", "evaluation",
                       f"{label} ({unit})", height=400)
    history = result["history"]
    stages = {"start": ("start designs", "#999999"), "local": ("local search (SLSQP)", UP),
              "global": ("differential evolution", "#E69F00")}
    for stage, (name, colour) in stages.items():
        points = [h for h in history if h["stage"] == stage and h["feasible"]]
        if points:
            fig.add_scatter(x=[h["evaluation"] for h in points], y=[h["objective"] / scale for h in points],
                            mode="markers", name=f"feasible: {name}", marker={"color": colour, "size": 8},
                            customdata=[_design_text(h["design"]) for h in points],
                            hovertemplate="evaluation %{x}<br>%{y:.5g} " + unit + "<br>%{customdata}<extra></extra>")
    bad = [h for h in history if not h["feasible"]]
    if bad:
        known = [h for h in bad if h["objective"] is not None]
        fig.add_scatter(x=[h["evaluation"] for h in known], y=[h["objective"] / scale for h in known],
                        mode="markers", name="infeasible (violates a constraint)",
                        marker={"symbol": "x", "color": DOWN, "size": 9, "line": {"width": 1}},
                        customdata=[f"violation {h['violation']:.3g} (scaled); " + _design_text(h["design"])
                                    for h in known],
                        hovertemplate="evaluation %{x}<br>%{y:.5g} " + unit + "<br>%{customdata}<extra></extra>")
    best, xs, ys = None, [], []
    sign = 1 if f["sense"] == "maximise" else -1
    for h in history:
        if h["feasible"] and (best is None or sign * h["objective"] > sign * best):
            best = h["objective"]
        if best is not None:
            xs.append(h["evaluation"])
            ys.append(best / scale)
    if xs:
        fig.add_scatter(x=xs, y=ys, mode="lines", line={"color": "#000", "width": 2, "shape": "hv"},
                        name="best feasible so far", hoverinfo="skip")
    fig.add_hline(y=result["nominal_objective"] / scale, line={"color": "#888", "dash": "dot", "width": 1},
                  annotation_text="current design", annotation_position="bottom right")
    fig.update_layout(legend={"orientation": "h", "y": -0.2, "x": 0})
    fig.update_xaxes(tick0=1, dtick=max(1, math.ceil(len(history) / 12)))  # whole evaluations
    refused = len(bad) - len([h for h in bad if h["objective"] is not None])
    if refused:
        fig.add_annotation(text=f"{refused} design(s) refused by the model (not plotted)", xref="paper", yref="paper",
                           x=1, y=1.02, xanchor="right", yanchor="bottom", showarrow=False, font={"size": 11})
    return fig


def _design_text(design) -> str:
    return ", ".join(f"{n} = {v:.5g}" for n, v in design.items())


def _csv(results):
    history = results[0]["history"]
    names = results[0]["parameters"]
    rows = [[h["evaluation"], h["stage"], *[h["design"][n] for n in names], h["objective"], h["violation"],
             h["feasible"]] for h in history]
    return ["evaluation", "stage", *names, "objective", "violation", "feasible"], rows


jobs.register(
    ids.OPT, "optimise", requests=_requests,
    render=lambda results: (opt_summary(results[0]), opt_design(results[0]), opt_figures(results[0]),
                            opt_history(results[0])),
    outputs=[Output(ids.OPT_SUMMARY, "children"), Output(ids.OPT_DESIGN, "children"), Output(ids.OPT_FIGURES,
                                                                                             "children"),
             Output(ids.OPT_HISTORY, "figure")],
    states=[State(ids.DES_CONFIG, "value"), State(ids.DES_FZ, "value"), State(ids.OPT_OBJECTIVE, "value"),
            State(ids.OPT_SEARCH, "value"), State(ids.OPT_CONSTRAINTS, "data"), State(ids.OPT_STARTS, "value"),
            State(ids.OPT_RUNS, "value"), State(ids.OPT_SEED, "value"), State(ids.design_store(ids.DES), "data")],
    lock=[ids.OPT_OBJECTIVE, ids.OPT_SEARCH, ids.OPT_STARTS, ids.OPT_RUNS, ids.OPT_SEED],
    download=jobs.Download(ids.OPT, "optimisation", _csv, single=True,
                           filename=lambda r: f"optimisation_{r[0]['config']}_{r[0]['objective_figure']['name']}"),
    blank=lambda: (None, None, None, style.message_figure("Refused: see the message above", 300)),
    running=lambda: (None, None, None, style.message_figure("Optimising…", 300)))
