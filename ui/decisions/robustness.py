"""Design decisions (c): robustness to tolerances, how manufacturing and tyre tolerances spread the
boundaries and the risk of shimmy at the nine operating points (the service's robustness job)."""

from __future__ import annotations

import math

import dash
from dash import Input, Output, State, dash_table, html

from shimmy.errors import InvalidParameterError
from shimmy.model.parameters import PARAMETER_SPECS
from shimmy.service import schemas
from ui import components as ui
from ui import formats, ids, jobs, style
from ui.fields import Quantity

from .common import DOWN, FZ, GRID, TABLE_STYLE, UP, check_field, field_error, placeholder, refusal, unit_suffix

SAMPLES = Quantity("robustness", "samples", "samples", "")
ROB_SEED = Quantity("robustness", "seed", "sampling seed", "")
TOLERABLE = [n for n, s in PARAMETER_SPECS.items() if not s.integer]
TOLERANCE_PCT = (100 * schemas.TOLERANCE_RANGE[0], 100 * schemas.TOLERANCE_RANGE[1])
DEFAULT_TOLERANCES = "k_lam=0.05,c_psi=0.1,k_s=0.05:uniform"


def section(a) -> list:
    """The section's heading, tolerances, results and downloads, as the address ``a`` (an
    :class:`~ui.decisions.address.Address`) sets them."""
    return [
        html.H2("Robustness", id=ids.ROBUSTNESS),
        html.P("Each toleranced parameter varies around its design value: normal (the tolerance is one standard "
               "deviation) or uniform (± the tolerance). Quasi-Monte Carlo samples (scrambled Sobol, seeded) give "
               "the distributions; the curves are first-order propagation of the sensitivities. Shimmy at an "
               "operating point: straight rolling unstable there (bistable points not counted).", className="hint"),
        html.Div([
            html.Label("Tolerances", style={"fontSize": "13px", "color": "var(--muted)"}),
            dash_table.DataTable(
                id=ids.ROB_TOLERANCES, data=a.tolerance_rows, editable=True, row_deletable=True, **TABLE_STYLE,
                columns=[{"name": "parameter", "id": "name", "presentation": "dropdown"},
                         {"name": "tolerance (%)", "id": "pct", "type": "numeric",
                          "on_change": {"action": "coerce", "failure": "accept"}},
                         {"name": "distribution", "id": "distribution", "presentation": "dropdown"}],
                dropdown={"name": {"options": [{"label": f"{n}{unit_suffix(n)}", "value": n} for n in TOLERABLE],
                                   "clearable": False},
                          "distribution": {"options": [{"label": "normal (σ)", "value": "normal"},
                                                       {"label": "uniform (±)", "value": "uniform"}],
                                           "clearable": False}},
                style_cell_conditional=[{"if": {"column_id": "name"}, "width": "220px", "minWidth": "180px"},
                                        {"if": {"column_id": "pct"}, "width": "120px"},
                                        {"if": {"column_id": "distribution"}, "width": "160px"}]),
            html.Button("Add tolerance", id=ids.ROB_ADD, className="secondary", style={"marginTop": "6px"}),
            field_error(ids.ROB_TOLERANCES_ERROR, a.bad_tols),
        ]),
        html.Div([
            html.Div([ui.field(f"Samples ({SAMPLES.low:g}-{SAMPLES.high:g})",
                               SAMPLES.box(ids.ROB_SAMPLES, a.n_samples, debounce=True)),
                      field_error(ids.ROB_SAMPLES_ERROR, a.bad_samples)]),
            html.Div([ui.field("Seed", ROB_SEED.box(ids.ROB_SEED, a.r_seed, debounce=True)),
                      field_error(ids.ROB_SEED_ERROR, a.bad_rseed)]),
            *jobs.controls(ids.ROB, "Sample"),
        ], className="controls"),
        html.Div(id=ids.ROB.error, className="error", role="alert"),
        html.Div(id=ids.ROB.stale, className="hint", role="status"),
        html.Div(id=ids.ROB_WARNINGS, className="hint"),
        html.Div(placeholder("The histograms appear here (about 1 s per 100 samples cold)"), id=ids.ROB_HISTOGRAMS,
                 style=GRID),
        html.Div(id=ids.ROB_TABLE, className="table-wrap"),
        ui.graph(ids.ROB_SHIMMY, figure=style.message_figure("The probability of shimmy at A-I appears here", 300)),
        ui.downloads(ids.ROB),
        *jobs.stores(ids.ROB),
    ]


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


def _requests(config, fz_kn, rows, samples, seed, design):
    return [{"config": config, "Fz": FZ.read(fz_kn), "tolerances": _tolerances(rows),
             "samples": SAMPLES.read(samples), "seed": ROB_SEED.read(seed), **design}]


check_field(ids.ROB_SAMPLES, ids.ROB_SAMPLES_ERROR, SAMPLES)
check_field(ids.ROB_SEED, ids.ROB_SEED_ERROR, ROB_SEED)


@dash.callback(Output(ids.ROB_TOLERANCES_ERROR, "children"), Input(ids.ROB_TOLERANCES, "data"),
               prevent_initial_call=True)
def check_tolerances(rows):
    return refusal(_tolerances, rows)


@dash.callback(Output(ids.ROB_TOLERANCES, "data", allow_duplicate=True), Input(ids.ROB_ADD, "n_clicks"),
               State(ids.ROB_TOLERANCES, "data"), prevent_initial_call=True)
def add_tolerance(_n, rows):
    used = {r.get("name") for r in rows or []}
    name = next((n for n in ("k_s", "e_p", "r2", "r3", "k_lam", "c_psi", "I_nes", "c_nes") if n not in used), "Iz")
    return [*(rows or []), {"name": name, "pct": 5, "distribution": "normal"}]


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


def _csv(results):
    result = results[0]
    rows = [[title, unit, k, v / scale] for title, unit, scale, s, _ in _rob_quantities(result)
            for k, v in enumerate(s["samples"])]
    return ["quantity", "unit", "sample", "value"], rows


jobs.register(
    ids.ROB, "robustness", requests=_requests,
    render=lambda results: (rob_histograms(results[0]), rob_table(results[0]), rob_shimmy(results[0]),
                            rob_warnings(results[0])),
    outputs=[Output(ids.ROB_HISTOGRAMS, "children"), Output(ids.ROB_TABLE, "children"), Output(ids.ROB_SHIMMY,
                                                                                               "figure"),
             Output(ids.ROB_WARNINGS, "children")],
    states=[State(ids.DES_CONFIG, "value"), State(ids.DES_FZ, "value"), State(ids.ROB_TOLERANCES, "data"),
            State(ids.ROB_SAMPLES, "value"), State(ids.ROB_SEED, "value"), State(ids.design_store(ids.DES), "data")],
    lock=[ids.ROB_SAMPLES, ids.ROB_SEED],
    download=jobs.Download(ids.ROB, "robustness", _csv, single=True,
                           filename=lambda r: f"robustness_{r[0]['config']}_{r[0]['Fz'] / 1e3:g}kN"),
    blank=lambda: (None, None, style.message_figure("Refused: see the message above", 300), None))
