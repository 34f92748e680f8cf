"""Design decisions: which parameters move the shimmy boundaries (tornado charts of the sensitivities), the
optimiser over the device parameters, and robustness to tolerances, for the current design, a configuration
and a load. Every number comes from the service (jobs: sensitivity, optimise, robustness); the page draws."""

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
from ui import fields, formats, ids, jobs
from ui import style
from ui.fields import Quantity
from ui.layout import DESIGN, page

dash.register_page(__name__, path="/design", name="Decisions", title="Design decisions", order=5.5)

CONFIGS = ui.CONFIGS
FZ = Quantity("sensitivity", "Fz", "Fz", "kN", 1e3)
STARTS = Quantity("optimise", "starts", "start designs", "")
RUNS = Quantity("optimise", "local_runs", "local searches", "")
OPT_SEED = Quantity("optimise", "seed", "optimiser seed", "")
SAMPLES = Quantity("robustness", "samples", "samples", "")
ROB_SEED = Quantity("robustness", "seed", "sampling seed", "")

#: How the page shows each figure of merit: label, unit shown, SI units per shown unit.
FIGURES = {"min_shimmy_Fz": ("minimum shimmy load", "kN", 1e3),
           "interval": ("shimmy speed interval width at Fz", "m/s", 1.0),
           "max_psi": ("largest stable torsional amplitude at Fz", "rad", 1.0),
           "torsion_area": ("pure-torsion area, Fz ≤ 250 kN", "(m/s) kN", 1.0)}
OBJECTIVES = {"min_shimmy_Fz": "maximise the minimum shimmy load",
              "interval": "minimise the shimmy speed interval at Fz",
              "max_psi": "minimise the largest stable torsional amplitude at Fz",
              "torsion_area": "minimise the pure-torsion area (differential evolution: minutes)"}
OPS = {"<=": "≤", ">=": "≥"}
#: The sensitivity quantities as the page names them: title, short symbol, unit shown, SI units per shown unit.
QUANTITIES = {"hopf_V1": ("Hopf speed V1 at {kN} kN", "V1", "m/s", 1.0),
              "hopf_V2": ("Hopf speed V2 at {kN} kN", "V2", "m/s", 1.0),
              "hopf_interval": ("Hopf interval width V2 − V1 at {kN} kN", "V2 − V1", "m/s", 1.0),
              "min_shimmy_Fz": ("Minimum shimmy load Fz,min", "Fz,min", "kN", 1e3),
              "max_psi": ("Largest stable |psi| at {kN} kN", "max |psi|", "rad", 1.0)}
BARS = {"per_half_range": "per half design range", "per_percent": "per +1 % of the value"}
SHOWN = {"device": "device parameters", "all": "all parameters"}
TOLERABLE = [n for n, s in PARAMETER_SPECS.items() if not s.integer]
TOLERANCE_PCT = (100 * schemas.TOLERANCE_RANGE[0], 100 * schemas.TOLERANCE_RANGE[1])
SENS_WAITING = "The tornado charts appear here (about 2 s cold, at once from the cache)."
DEFAULT_TOLERANCES = "k_lam=0.05,c_psi=0.1,k_s=0.05:uniform"
UP, DOWN = "#0072B2", "#D55E00"  # Okabe–Ito blue and vermilion: raises / lowers
GRID = {"display": "grid", "gridTemplateColumns": "repeat(auto-fill, minmax(min(100%, 470px), 1fr))", "gap": "12px"}
TABLE_STYLE = {"style_table": {"overflowX": "auto", "maxWidth": "640px"},
               "style_cell": {"fontFamily": "inherit", "fontSize": "13px", "padding": "3px 8px", "textAlign": "left"},
               "style_header": {"backgroundColor": "#eef2f8", "fontWeight": "600"},
               "css": [{"selector": ".Select-menu-outer", "rule": "display: block !important"}]}


def _unit(name: str) -> str:
    unit = PARAMETER_SPECS[name].unit
    return f" ({unit})" if unit else ""


def _figure_option(name: str) -> str:
    """How the constraint table's dropdown names a figure: short, with the unit its value is typed in."""
    return {"min_shimmy_Fz": "minimum shimmy load (kN)", "interval": "shimmy speed interval at Fz (m/s)",
            "max_psi": "largest stable |psi| at Fz (rad)", "torsion_area": "pure-torsion area ((m/s) kN)"}[name]


# -- the address ------------------------------------------------------------------------------------------


def _constraint_rows(raw: str | None) -> tuple[list[dict], str | None]:
    """Table rows from the address's cons=max_psi<=0.2,min_shimmy_Fz>=80000 (values in the API's SI units)."""
    rows, bad = [], []
    for k, text in enumerate(t for t in (raw or "").split(",") if t.strip()):
        try:
            c = schemas.constraint(f"cons[{k}]", text, 150e3)
        except InvalidParameterError as exc:
            bad.append(str(exc))
            continue
        rows.append({"figure": c["figure"], "op": c["op"], "value": c["value"] / FIGURES[c["figure"]][2]})
    return rows, (f"The address gives cons={raw}: {'; '.join(bad)}." if bad else None)


def _tolerance_rows(raw: str | None) -> tuple[list[dict], str | None]:
    rows, bad = [], []
    for k, text in enumerate(t for t in (raw if raw is not None else DEFAULT_TOLERANCES).split(",") if t.strip()):
        try:
            t = schemas.tolerance(f"tols[{k}]", text)
        except InvalidParameterError as exc:
            bad.append(str(exc))
            continue
        rows.append({"name": t["name"], "pct": round(100 * t["relative"], 10), "distribution": t["distribution"]})
    return rows, (f"The address gives tols={raw}: {'; '.join(bad)}." if bad else None)


def _default_search(config: str) -> list[str]:
    chosen = [n for n in schemas.DEFAULT_SEARCH if affects(n, config)]
    return chosen or [n for n in DESIGN if affects(n, config)]


def _search_options(config: str) -> list[dict]:
    return [{"label": f"{n}{_unit(n)}", "value": n, "disabled": not affects(n, config)} for n in DESIGN]


def _error(element_id: str, text: str | None = None) -> html.Div:
    return html.Div(text, id=element_id, className="error field-error", role="alert")


def layout(config: str | None = None, Fz: str | None = None, bars: str | None = None, show: str | None = None,
           objective: str | None = None, search: str | None = None, cons: str | None = None,
           starts: str | None = None, runs: str | None = None, opt_seed: str | None = None,
           tols: str | None = None, samples: str | None = None, seed: str | None = None, **query):
    config, bad_config = fields.choice("config", config, list(CONFIGS), "nes", "a configuration")
    fz, bad_fz = FZ.from_url("Fz", Fz, 150)
    by, bad_bars = fields.choice("bars", bars, list(BARS), "per_half_range", "a bar scale")
    shown, bad_show = fields.choice("show", show, list(SHOWN), "device", "a parameter set")
    goal, bad_objective = fields.choice("objective", objective, list(OBJECTIVES), "min_shimmy_Fz", "an objective")
    chosen, bad_search = fields.choices_list("search", search, DESIGN, _default_search(config), "a device parameter")
    chosen = [n for n in chosen if affects(n, config)]
    constraint_rows, bad_cons = _constraint_rows(cons)
    n_starts, bad_starts = STARTS.from_url("starts", starts, STARTS.spec.default)
    n_runs, bad_runs = RUNS.from_url("runs", runs, RUNS.spec.default)
    o_seed, bad_oseed = OPT_SEED.from_url("opt_seed", opt_seed, 0)
    tolerance_rows, bad_tols = _tolerance_rows(tols)
    n_samples, bad_samples = SAMPLES.from_url("samples", samples, 64)
    r_seed, bad_rseed = ROB_SEED.from_url("seed", seed, 0)
    return page(
        query, ids.DES,
        ui.header("Design decisions", "For the current design, one configuration and one load: which parameters "
                  "move the shimmy boundaries and by how much (sensitivities by implicit differentiation), the best "
                  "device parameters for a figure of merit under constraints on the others (optimiser), and how "
                  "manufacturing and tyre tolerances spread the boundaries and the risk of shimmy at the nine "
                  "operating points (robustness). Methods: the documentation's Design decisions tutorial."),
        html.Div([
            html.Div([html.Label("Configuration", htmlFor=ids.DES_CONFIG),
                      ui.configurations(ids.DES_CONFIG, config),
                      _error(ids.DES_CONFIG_ERROR, bad_config)], className="field"),
            html.Div([html.Label("Load Fz (kN)", htmlFor=ids.DES_FZ), FZ.box(ids.DES_FZ, fz, debounce=True),
                      _error(ids.DES_FZ_ERROR, bad_fz)], className="field",
                     title=f"the load of the Hopf speeds and of the figures taken at a load; {FZ.allowed}"),
            html.Nav([html.A("Sensitivities", href=f"#{ids.SENSITIVITIES}"), " · ",
                      html.A("Optimiser", href=f"#{ids.OPTIMISER}"), " · ",
                      html.A("Robustness", href=f"#{ids.ROBUSTNESS}")], className="hint"),
        ], className="controls"),
        # -- (a) sensitivities
        html.H2("Sensitivities", id=ids.SENSITIVITIES),
        html.P("Change of each quantity when one parameter moves by half its design range (or by 1 % of its value), "
               "the others held: the derivative by implicit differentiation times the step (linear). Largest effect "
               "on top; blue raises the quantity, vermilion lowers it. Parameters that cannot move a quantity are "
               "listed under its chart with the reason.", className="hint"),
        html.Div([
            ui.field("Bars", dcc.RadioItems(id=ids.SENS_BY, value=by, inline=True,
                                            options=[{"label": v, "value": k} for k, v in BARS.items()])),
            ui.field("Parameters", dcc.RadioItems(id=ids.SENS_SHOW, value=shown, inline=True,
                                                  options=[{"label": v, "value": k} for k, v in SHOWN.items()])),
            *jobs.controls(ids.SENS),
        ], className="controls"),
        html.Div(" ".join(p for p in (bad_bars, bad_show) if p), id=ids.SENS.error, className="error", role="alert"),
        html.Div(id=ids.SENS.stale, className="hint", role="status"),
        html.Div(id=ids.SENS_SUMMARY, className="hint"),
        html.Div(_placeholder(SENS_WAITING), id=ids.SENS_CHARTS),
        ui.downloads(ids.SENS),
        dcc.Store(id=ids.SENS_DATA),
        *jobs.stores(ids.SENS),
        # -- (b) optimiser
        html.H2("Optimiser", id=ids.OPTIMISER),
        html.P("Searches the chosen device parameters within their ranges (the others as in the design panel). "
               "Gradient method: Sobol start designs (the current design among them), then SLSQP with the "
               "sensitivities as gradients; differential evolution where a figure has no derivative.",
               className="hint"),
        html.Div([
            ui.field("Objective", dcc.Dropdown(id=ids.OPT_OBJECTIVE, value=goal, clearable=False,
                                               style={"width": "430px"},
                                               options=[{"label": v, "value": k} for k, v in OBJECTIVES.items()])),
            html.Div([html.Label("Parameters to search"),
                      dcc.Checklist(id=ids.OPT_SEARCH, value=chosen, inline=True, options=_search_options(config)),
                      _error(ids.OPT_SEARCH_ERROR, bad_search)], className="field"),
        ], className="controls"),
        html.Div([
            html.Label("Constraints (each value in the figure's unit; Fz: the load above)",
                       style={"fontSize": "13px", "color": "var(--muted)"}),
            dash_table.DataTable(
                id=ids.OPT_CONSTRAINTS, data=constraint_rows, editable=True, row_deletable=True, **TABLE_STYLE,
                columns=[{"name": "figure", "id": "figure", "presentation": "dropdown"},
                         {"name": "", "id": "op", "presentation": "dropdown"},
                         {"name": "value", "id": "value", "type": "numeric",
                          "on_change": {"action": "coerce", "failure": "accept"}}],
                dropdown={"figure": {"options": [{"label": _figure_option(f), "value": f} for f in FIGURES],
                                     "clearable": False},
                          "op": {"options": [{"label": v, "value": k} for k, v in OPS.items()], "clearable": False}},
                style_cell_conditional=[{"if": {"column_id": "figure"}, "width": "270px", "minWidth": "270px"},
                                        {"if": {"column_id": "op"}, "width": "64px", "minWidth": "64px"},
                                        {"if": {"column_id": "value"}, "width": "110px", "minWidth": "110px"}]),
            html.Button("Add constraint", id=ids.OPT_ADD, className="secondary", style={"marginTop": "6px"}),
            _error(ids.OPT_CONSTRAINTS_ERROR, bad_cons),
        ]),
        html.Div([
            html.Div([ui.field(f"Start designs ({STARTS.low:g}-{STARTS.high:g})",
                               STARTS.box(ids.OPT_STARTS, n_starts, debounce=True)),
                      _error(ids.OPT_STARTS_ERROR, bad_starts)]),
            html.Div([ui.field(f"Local searches ({RUNS.low:g}-{RUNS.high:g})",
                               RUNS.box(ids.OPT_RUNS, n_runs, debounce=True)),
                      _error(ids.OPT_RUNS_ERROR, bad_runs)]),
            html.Div([ui.field("Seed", OPT_SEED.box(ids.OPT_SEED, o_seed, debounce=True)),
                      _error(ids.OPT_SEED_ERROR, bad_oseed)]),
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
        # -- (c) robustness
        html.H2("Robustness", id=ids.ROBUSTNESS),
        html.P("Each toleranced parameter varies around its design value: normal (the tolerance is one standard "
               "deviation) or uniform (± the tolerance). Quasi-Monte Carlo samples (scrambled Sobol, seeded) give "
               "the distributions; the curves are first-order propagation of the sensitivities. Shimmy at an "
               "operating point: straight rolling unstable there (bistable points not counted).", className="hint"),
        html.Div([
            html.Label("Tolerances", style={"fontSize": "13px", "color": "var(--muted)"}),
            dash_table.DataTable(
                id=ids.ROB_TOLERANCES, data=tolerance_rows, editable=True, row_deletable=True, **TABLE_STYLE,
                columns=[{"name": "parameter", "id": "name", "presentation": "dropdown"},
                         {"name": "tolerance (%)", "id": "pct", "type": "numeric",
                          "on_change": {"action": "coerce", "failure": "accept"}},
                         {"name": "distribution", "id": "distribution", "presentation": "dropdown"}],
                dropdown={"name": {"options": [{"label": f"{n}{_unit(n)}", "value": n} for n in TOLERABLE],
                                   "clearable": False},
                          "distribution": {"options": [{"label": "normal (σ)", "value": "normal"},
                                                       {"label": "uniform (±)", "value": "uniform"}],
                                           "clearable": False}},
                style_cell_conditional=[{"if": {"column_id": "name"}, "width": "220px", "minWidth": "180px"},
                                        {"if": {"column_id": "pct"}, "width": "120px"},
                                        {"if": {"column_id": "distribution"}, "width": "160px"}]),
            html.Button("Add tolerance", id=ids.ROB_ADD, className="secondary", style={"marginTop": "6px"}),
            _error(ids.ROB_TOLERANCES_ERROR, bad_tols),
        ]),
        html.Div([
            html.Div([ui.field(f"Samples ({SAMPLES.low:g}-{SAMPLES.high:g})",
                               SAMPLES.box(ids.ROB_SAMPLES, n_samples, debounce=True)),
                      _error(ids.ROB_SAMPLES_ERROR, bad_samples)]),
            html.Div([ui.field("Seed", ROB_SEED.box(ids.ROB_SEED, r_seed, debounce=True)),
                      _error(ids.ROB_SEED_ERROR, bad_rseed)]),
            *jobs.controls(ids.ROB, "Sample"),
        ], className="controls"),
        html.Div(id=ids.ROB.error, className="error", role="alert"),
        html.Div(id=ids.ROB.stale, className="hint", role="status"),
        html.Div(id=ids.ROB_WARNINGS, className="hint"),
        html.Div(_placeholder("The histograms appear here (about 1 s per 100 samples cold)"), id=ids.ROB_HISTOGRAMS,
                 style=GRID),
        html.Div(id=ids.ROB_TABLE, className="table-wrap"),
        ui.graph(ids.ROB_SHIMMY, figure=style.message_figure("The probability of shimmy at A-I appears here", 300)),
        ui.downloads(ids.ROB),
        *jobs.stores(ids.ROB),
    )


def _placeholder(text: str) -> html.P:
    return html.P(text, className="hint placeholder")


# -- reading the fields -----------------------------------------------------------------------------------


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


def _tolerances(rows) -> list[dict]:
    """The table's tolerances as request items (relative, a fraction); refused by row, in %."""
    if not rows:
        raise InvalidParameterError("tolerances", [], "one or more rows", message="Tolerances: none; add a row")
    out, seen = [], {}
    lo, hi = TOLERANCE_PCT
    allowed = f"a number in [{lo:g}, {hi:g}] %"
    for k, row in enumerate(rows):
        name, pct, dist = row.get("name"), row.get("pct"), row.get("distribution") or "normal"
        where = f"tolerance {k + 1}"
        if name not in TOLERABLE:
            raise InvalidParameterError(f"tolerances[{k}].name", name, "a parameter", message=f"{where}: choose a "
                                        "parameter")
        if name in seen:
            raise InvalidParameterError(f"tolerances[{k}].name", name, "each parameter at most once",
                                        message=f"{where}: {name} is already tolerance {seen[name] + 1}")
        seen[name] = k
        if pct is None or isinstance(pct, bool) or (isinstance(pct, str) and not pct.strip()):
            raise InvalidParameterError(f"tolerances[{k}].relative", pct, allowed,
                                        message=f"{where} ({name}): the tolerance is empty; enter {allowed}")
        try:
            number = float(pct)
        except (TypeError, ValueError):
            raise InvalidParameterError(f"tolerances[{k}].relative", pct, allowed,
                                        message=f"{where} ({name}): {pct!s} is not a number; enter "
                                                f"{allowed}") from None
        if not (math.isfinite(number) and lo <= number <= hi):
            raise InvalidParameterError(f"tolerances[{k}].relative", pct, allowed,
                                        message=f"{where}: {name} ± {number:g} % is outside [{lo:g}, {hi:g}] %")
        if dist not in schemas.DISTRIBUTIONS:
            raise InvalidParameterError(f"tolerances[{k}].distribution", dist, "normal or uniform",
                                        message=f"{where} ({name}): choose normal or uniform")
        out.append({"name": name, "relative": number / 100, "distribution": dist})
    return out


def _search(config, names) -> list[str]:
    names = [n for n in names or [] if affects(n, config)]
    if not names:
        raise InvalidParameterError("parameters", [], "one or more device parameters of " + config,
                                    message=f"Parameters to search: none chosen that {style.CONFIG_LABELS[config]} "
                                            "has; tick at least one")
    return names


def _sens_requests(config, fz_kn, design):
    return [{"config": config, "Fz": FZ.read(fz_kn), **design}]


def _opt_requests(config, fz_kn, objective, search, rows, starts, runs, seed, design):
    fz = FZ.read(fz_kn)
    names = _search(config, search)
    constraints = _constraints(rows)
    n_starts, n_runs = STARTS.read(starts), RUNS.read(runs)
    if n_runs > n_starts:
        raise InvalidParameterError("local_runs", runs, f"at most {n_starts}",
                                    message=f"local searches = {n_runs} exceeds start designs = {n_starts}")
    return [{"config": config, "objective": objective, "parameters": names, "Fz": fz, "constraints": constraints,
             "starts": n_starts, "local_runs": n_runs, "seed": OPT_SEED.read(seed), **design}]


def _rob_requests(config, fz_kn, rows, samples, seed, design):
    return [{"config": config, "Fz": FZ.read(fz_kn), "tolerances": _tolerances(rows),
             "samples": SAMPLES.read(samples), "seed": ROB_SEED.read(seed), **design}]


def _check(read, value) -> str:
    try:
        read(value)
    except InvalidParameterError as exc:
        return str(exc)
    return ""


# Each field says at once what is wrong with it, in its unit (the run refuses the same, by the same rules).
for _box, _error_id, _quantity in ((ids.DES_FZ, ids.DES_FZ_ERROR, FZ), (ids.OPT_STARTS, ids.OPT_STARTS_ERROR, STARTS),
                                   (ids.OPT_RUNS, ids.OPT_RUNS_ERROR, RUNS), (ids.OPT_SEED, ids.OPT_SEED_ERROR,
                                                                              OPT_SEED),
                                   (ids.ROB_SAMPLES, ids.ROB_SAMPLES_ERROR, SAMPLES),
                                   (ids.ROB_SEED, ids.ROB_SEED_ERROR, ROB_SEED)):
    dash.callback(Output(_error_id, "children"), Input(_box, "value"), prevent_initial_call=True)(
        lambda value, q=_quantity: _check(q.read, value))


@dash.callback(Output(ids.OPT_CONSTRAINTS_ERROR, "children"), Input(ids.OPT_CONSTRAINTS, "data"),
               prevent_initial_call=True)
def check_constraints(rows):
    return _check(_constraints, rows)


@dash.callback(Output(ids.ROB_TOLERANCES_ERROR, "children"), Input(ids.ROB_TOLERANCES, "data"),
               prevent_initial_call=True)
def check_tolerances(rows):
    return _check(_tolerances, rows)


@dash.callback(Output(ids.OPT_SEARCH, "options"), Output(ids.OPT_SEARCH, "value"), Output(ids.OPT_SEARCH_ERROR,
                                                                                          "children"),
               Input(ids.DES_CONFIG, "value"), State(ids.OPT_SEARCH, "value"), prevent_initial_call=True)
def search_options(config, chosen):
    """The device parameters the configuration has can be ticked; the others are greyed out."""
    kept = [n for n in chosen or [] if affects(n, config)]
    return _search_options(config), kept or _default_search(config), ""


@dash.callback(Output(ids.OPT_CONSTRAINTS, "data", allow_duplicate=True), Input(ids.OPT_ADD, "n_clicks"),
               State(ids.OPT_CONSTRAINTS, "data"), prevent_initial_call=True)
def add_constraint(_n, rows):
    return [*(rows or []), {"figure": "max_psi", "op": "<=", "value": 0.2}]


@dash.callback(Output(ids.ROB_TOLERANCES, "data", allow_duplicate=True), Input(ids.ROB_ADD, "n_clicks"),
               State(ids.ROB_TOLERANCES, "data"), prevent_initial_call=True)
def add_tolerance(_n, rows):
    used = {r.get("name") for r in rows or []}
    name = next((n for n in ("k_s", "e_p", "r2", "r3", "k_lam", "c_psi", "I_nes", "c_nes") if n not in used), "Iz")
    return [*(rows or []), {"name": name, "pct": 5, "distribution": "normal"}]


# -- (a) sensitivities ------------------------------------------------------------------------------------


def _sens_data(results):
    """What the charts need of the result (the rows of every quantity, the reasons): kept in the page."""
    r = results[0]
    return {"config": r["config"], "Fz": r["Fz"], "quantities": r["quantities"], "max_psi": r["max_psi"],
            "min_shimmy_Fz": r["min_shimmy_Fz"] and {k: v for k, v in r["min_shimmy_Fz"].items() if k != "dFz_dp"},
            "hopf_points": [{"V": h["V"], "frequency_hz": h["frequency_hz"]} for h in r["hopf_points"]]}


def _sens_summary(results):
    r = results[0]
    speeds = ", ".join(f"{h['V']:.4g} m/s ({h['frequency_hz']:.3g} Hz)" for h in r["hopf_points"]) or "none"
    low = r["min_shimmy_Fz"]
    text = (f"{style.CONFIG_LABELS[r['config']]} at {r['Fz'] / 1e3:g} kN: Hopf points at {speeds}; minimum shimmy "
            f"load {'–' if low is None else format(low['Fz'] / 1e3, '.4g') + ' kN'}; computed in "
            f"{sum(r['elapsed_s'].values()):.2f} s.")
    return text


def _sens_csv(results):
    rows = [[q["key"], q["unit"], row["name"], row["unit"], row["value"], row["derivative"], row["per_percent"],
             row["per_half_range"], row["reason"] or ""] for q in results[0]["quantities"] for row in q["rows"]]
    return ["quantity", "quantity_unit", "parameter", "parameter_unit", "parameter_value", "derivative",
            "change_per_percent", "change_per_half_range", "no_effect_reason"], rows


jobs.register(
    ids.SENS, "sensitivity", requests=_sens_requests, initial=True,
    render=lambda results: (_sens_data(results), _sens_summary(results)),
    outputs=[Output(ids.SENS_DATA, "data"), Output(ids.SENS_SUMMARY, "children")],
    triggers=[Input(ids.DES_CONFIG, "value"), Input(ids.DES_FZ, "value")], states=[State(ids.design_store(ids.DES),
                                                                                         "data")],
    download=jobs.Download(ids.SENS, "sensitivities", _sens_csv, single=True,
                           filename=lambda r: f"sensitivities_{r[0]['config']}_{r[0]['Fz'] / 1e3:g}kN"),
    blank=lambda: (None, ""))


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
    fig.add_bar(x=x, y=[f"{r['name']}{_unit(r['name'])}" for r in active], orientation="h",
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
        return _placeholder(SENS_WAITING)
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


# -- (b) optimiser ----------------------------------------------------------------------------------------


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
    rows = []
    for name in result["parameters"]:
        spec = PARAMETER_SPECS[name]
        old, new = base[name], result["design"][name]
        rows.append([name, spec.unit or "–", f"{formats.compact(spec.low)} – {formats.compact(spec.high)}",
                     formats.compact(old), formats.compact(new),
                     formats.signed_percent(100 * (new - old) / old if old else None)])
    return ui.table(["parameter", "unit", "range", "current design", "optimum", "change"], rows, ids.OPT_DESIGN_TABLE)


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


def _opt_csv(results):
    history = results[0]["history"]
    names = results[0]["parameters"]
    rows = [[h["evaluation"], h["stage"], *[h["design"][n] for n in names], h["objective"], h["violation"],
             h["feasible"]] for h in history]
    return ["evaluation", "stage", *names, "objective", "violation", "feasible"], rows


jobs.register(
    ids.OPT, "optimise", requests=_opt_requests,
    render=lambda results: (opt_summary(results[0]), opt_design(results[0]), opt_figures(results[0]),
                            opt_history(results[0])),
    outputs=[Output(ids.OPT_SUMMARY, "children"), Output(ids.OPT_DESIGN, "children"), Output(ids.OPT_FIGURES,
                                                                                             "children"),
             Output(ids.OPT_HISTORY, "figure")],
    states=[State(ids.DES_CONFIG, "value"), State(ids.DES_FZ, "value"), State(ids.OPT_OBJECTIVE, "value"),
            State(ids.OPT_SEARCH, "value"), State(ids.OPT_CONSTRAINTS, "data"), State(ids.OPT_STARTS, "value"),
            State(ids.OPT_RUNS, "value"), State(ids.OPT_SEED, "value"), State(ids.design_store(ids.DES), "data")],
    lock=[ids.OPT_OBJECTIVE, ids.OPT_SEARCH, ids.OPT_STARTS, ids.OPT_RUNS, ids.OPT_SEED],
    download=jobs.Download(ids.OPT, "optimisation", _opt_csv, single=True,
                           filename=lambda r: f"optimisation_{r[0]['config']}_{r[0]['objective_figure']['name']}"),
    blank=lambda: (None, None, None, style.message_figure("Refused: see the message above", 300)),
    running=lambda: (None, None, None, style.message_figure("Optimising…", 300)))


# -- (c) robustness ---------------------------------------------------------------------------------------


def _normal_curve(mean: float, std: float | None, low: float, high: float) -> tuple[list[float], list[float]]:
    """The linear-propagation density N(mean, std) on [low, high] (for drawing)."""
    if not std or std <= 0:
        return [], []
    lo, hi = min(low, mean - 4 * std), max(high, mean + 4 * std)
    xs = [lo + (hi - lo) * k / 120 for k in range(121)]
    return xs, [math.exp(-0.5 * ((x - mean) / std) ** 2) / (std * math.sqrt(2 * math.pi)) for x in xs]


def histogram(title: str, unit: str, stats: dict, scale: float, graph_id: str):
    samples = [v / scale for v in stats["samples"]]
    fig = style.figure(title, f"{title.split(' at ')[0]} ({unit})", f"probability density (1/({unit}))",
                       height=340)
    fig.add_histogram(x=samples, histnorm="probability density", name=f"{len(samples)} samples",
                      marker={"color": "#9ecae1", "line": {"color": UP, "width": 1}}, opacity=0.85,
                      hovertemplate="%{x}<br>density %{y:.3g}<extra></extra>")
    xs, ys = _normal_curve(stats["nominal"] / scale, None if stats["linear_std"] is None
                           else stats["linear_std"] / scale, min(samples), max(samples))
    if xs:
        fig.add_scatter(x=xs, y=ys, mode="lines", line={"color": DOWN, "width": 2},
                        name=f"linear propagation (σ = {stats['linear_std'] / scale:.3g} {unit})", hoverinfo="skip")
    fig.add_vline(x=stats["nominal"] / scale, line={"color": "#000", "dash": "dot", "width": 1})
    fig.update_layout(legend={"orientation": "h", "y": -0.3, "x": 0}, bargap=0.02,
                      margin={**style.MARGIN, "b": 90})
    return ui.graph(graph_id, figure=fig)


def _rob_quantities(result):
    """(title, unit, SI per shown unit, stats, id) of every sampled quantity."""
    out = [(f"Hopf speed {k + 1} at {result['Fz'] / 1e3:g} kN", "m/s", 1.0, h, ids.rob_histogram(f"V{k + 1}"))
           for k, h in enumerate(result["hopf_points"])]
    if result["min_shimmy_Fz"] is not None:
        out.append(("Minimum shimmy load", "kN", 1e3, result["min_shimmy_Fz"], ids.rob_histogram("Fzmin")))
    return out


def rob_histograms(result):
    items = _rob_quantities(result)
    if not items:
        return html.P("No Hopf point at this load and no minimum shimmy load: nothing to draw.", className="note")
    return [histogram(title, unit, stats, scale, graph_id) for title, unit, scale, stats, graph_id in items]


def rob_table(result):
    rows = []
    for title, unit, scale, s, _ in _rob_quantities(result):
        lp = "–" if s.get("linear_p05") is None else f"{s['linear_p05'] / scale:.5g} – {s['linear_p95'] / scale:.5g}"
        rows.append([f"{title} ({unit})", f"{s['nominal'] / scale:.5g}", f"{s['mean'] / scale:.5g}",
                     f"{s['std'] / scale:.3g}", f"{s['p05'] / scale:.5g}", f"{s['p95'] / scale:.5g}",
                     formats.significant(None if s["linear_std"] is None else s["linear_std"] / scale, 3), lp,
                     len(s["samples"])])
    return ui.table(["quantity", "nominal", "mean", "std", "p05", "p95", "linear std", "linear p05 – p95",
                     "samples"], rows, ids.ROB_STATS)


def rob_shimmy(result):
    points = list(result["p_shimmy"])
    where = [f"{p}: V = {result['operating_points'][p]['V']:g} m/s, Fz = {result['operating_points'][p]['Fz'] / 1e3:g}"
             " kN" for p in points]
    fig = style.figure(f"Probability of shimmy at the operating points ({style.CONFIG_LABELS[result['config']]})",
                       "operating point", "probability that straight rolling is unstable (%)", height=380)
    fig.add_bar(x=points, y=[100 * result["p_shimmy"][p] for p in points], name=f"sampled ({result['samples']})",
                marker={"color": UP}, customdata=where, hovertemplate="%{customdata}<br>sampled %{y:.3g} %"
                                                                      "<extra></extra>")
    fig.add_bar(x=points, y=[None if result["p_shimmy_linear"][p] is None else 100 * result["p_shimmy_linear"][p]
                             for p in points], name="linear propagation", marker={"color": "#E69F00"},
                customdata=where, hovertemplate="%{customdata}<br>linear %{y:.3g} %<extra></extra>")
    fig.update_yaxes(range=[0, 105])
    fig.update_layout(barmode="group", legend={"orientation": "h", "y": -0.22, "x": 0})
    return fig


def rob_warnings(result):
    tolerances = ", ".join(f"{t['name']} {100 * t['relative']:g} % {t['distribution']}" for t in result["tolerances"])
    text = [html.P(f"{result['samples']} samples (seed {result['seed']}) of {tolerances}; "
                   f"{result['elapsed_s']:.1f} s ({result['executor']}).")]
    return text + [html.P(w, className="note") for w in result["warnings"]]


def _rob_csv(results):
    result = results[0]
    rows = [[title, unit, k, v / scale] for title, unit, scale, s, _ in _rob_quantities(result)
            for k, v in enumerate(s["samples"])]
    return ["quantity", "unit", "sample", "value"], rows


jobs.register(
    ids.ROB, "robustness", requests=_rob_requests,
    render=lambda results: (rob_histograms(results[0]), rob_table(results[0]), rob_shimmy(results[0]),
                            rob_warnings(results[0])),
    outputs=[Output(ids.ROB_HISTOGRAMS, "children"), Output(ids.ROB_TABLE, "children"), Output(ids.ROB_SHIMMY,
                                                                                               "figure"),
             Output(ids.ROB_WARNINGS, "children")],
    states=[State(ids.DES_CONFIG, "value"), State(ids.DES_FZ, "value"), State(ids.ROB_TOLERANCES, "data"),
            State(ids.ROB_SAMPLES, "value"), State(ids.ROB_SEED, "value"), State(ids.design_store(ids.DES), "data")],
    lock=[ids.ROB_SAMPLES, ids.ROB_SEED],
    download=jobs.Download(ids.ROB, "robustness", _rob_csv, single=True,
                           filename=lambda r: f"robustness_{r[0]['config']}_{r[0]['Fz'] / 1e3:g}kN"),
    blank=lambda: (None, None, style.message_figure("Refused: see the message above", 300), None))


# -- what the shown results answer -----------------------------------------------------------------------


def _stale(shown, config, fz_kn, design) -> str:
    """Why a shown result no longer answers the page's configuration, load or design ('' if it does)."""
    if not shown:
        return ""
    request = shown[0]
    try:
        fz = FZ.read(fz_kn)
        params = schemas.design(design.get("params") or {}, design.get("material"))
    except (InvalidParameterError, AttributeError):
        return ""
    changed = [what for what, same in (("configuration", request.get("config") == config),
                                       ("load", abs(float(request.get("Fz", 0)) - fz) < 1e-6),
                                       ("design", request.get("params") == params)) if not same]
    if not changed:
        return ""
    return (f"Shown for {style.CONFIG_LABELS.get(request.get('config'), request.get('config'))} at "
            f"{float(request.get('Fz', 0)) / 1e3:g} kN; the {' and the '.join(changed)} changed since: press the "
            "button to update.")


for _group in (ids.SENS, ids.OPT, ids.ROB):
    dash.callback(Output(_group.stale, "children"), Input(_group.requests, "data"),
                  Input(ids.DES_CONFIG, "value"), Input(ids.DES_FZ, "value"), Input(ids.design_store(ids.DES),
                                                                                    "data"))(_stale)


@dash.callback(Output(ids.URL_UPDATE, "data", allow_duplicate=True),
               Input(ids.DES_CONFIG, "value"), Input(ids.DES_FZ, "value"), Input(ids.SENS_BY, "value"),
               Input(ids.SENS_SHOW, "value"), Input(ids.OPT_OBJECTIVE, "value"), Input(ids.OPT_SEARCH, "value"),
               Input(ids.OPT_CONSTRAINTS, "data"), Input(ids.OPT_STARTS, "value"), Input(ids.OPT_RUNS, "value"),
               Input(ids.OPT_SEED, "value"), Input(ids.ROB_TOLERANCES, "data"), Input(ids.ROB_SAMPLES, "value"),
               Input(ids.ROB_SEED, "value"), prevent_initial_call=True)
def remember(config, fz, by, shown, objective, search, constraints, starts, runs, opt_seed, tolerances, samples,
             seed):
    """The page's state in the address (constraints and tolerances in the API's string form, SI units)."""
    cons = []
    for row in constraints or []:
        if row.get("figure") in FIGURES and row.get("op") in OPS and isinstance(row.get("value"), (int, float)):
            cons.append(f"{row['figure']}{row['op']}{row['value'] * FIGURES[row['figure']][2]:g}")
    tols = []
    for row in tolerances or []:
        if row.get("name") in TOLERABLE and isinstance(row.get("pct"), (int, float)):
            dist = row.get("distribution") or "normal"
            tols.append(f"{row['name']}={row['pct'] / 100:g}" + ("" if dist == "normal" else f":{dist}"))
    return {"config": config, "Fz": fz, "bars": None if by == "per_half_range" else by,
            "show": None if shown == "device" else shown, "objective": objective, "search": ",".join(search or []),
            "cons": ",".join(cons), "starts": starts, "runs": runs, "opt_seed": opt_seed,
            "tols": ",".join(tols), "samples": samples, "seed": seed}
