"""Parametric study: Hopf speeds and the largest torsional amplitude against a design parameter."""

from __future__ import annotations

import dash
from dash import Input, Output, State, dcc, html
from plotly.subplots import make_subplots

from shimmy.errors import InvalidParameterError
from shimmy.model.parameters import PARAMETER_SPECS
from ui import components as ui
from ui import jobs
from ui import style
from ui.layout import design_id, page

dash.register_page(__name__, path="/study", name="Parametric study", order=5)

CONFIGS = tuple(style.CONFIG_COLOURS)
DEFAULT_VALUES = "0.0005, 0.001, 0.002, 0.003, 0.004, 0.005"


def _unit(name: str) -> str:
    unit = PARAMETER_SPECS[name].unit
    return f" ({unit})" if unit else ""


def layout(parameter: str = "e_p", values: str = DEFAULT_VALUES, configs: str = "original,nes,pd,nes_pd",
           Fz: str = "150", **query):
    parameter = parameter if parameter in PARAMETER_SPECS else "e_p"
    chosen = [c for c in configs.split(",") if c in CONFIGS] or list(CONFIGS)
    return page(
        query, "study",
        ui.header("Parametric study", "Sweep one design parameter (the others at the current design) and tabulate, "
                  "per configuration, the first and last Hopf speed of straight rolling (shimmy onset and end of the "
                  "linear instability) and the largest torsional amplitude of a stable limit cycle, from a "
                  "bifurcation diagram per design. Two-parameter grids: API and command line."),
        html.Div([
            ui.field("Parameter", dcc.Dropdown(id="study-param", value=parameter, clearable=False,
                                               style={"width": "150px"},
                                               options=[{"label": f"{n}{_unit(n)}", "value": n}
                                                        for n in PARAMETER_SPECS])),
            ui.field("Values (comma-separated)", dcc.Input(id="study-values", type="text", value=values,
                                                           style={"width": "300px"}),
                     hint=""),
            ui.field("Fz (kN)", dcc.Input(id="study-fz", type="number", value=ui.number(Fz, 150), min=10, max=900,
                                          step="any")),
            ui.field("Configurations", dcc.Checklist(id="study-configs", value=chosen, inline=True, options=[
                {"label": style.CONFIG_LABELS[c], "value": c} for c in CONFIGS])),
            *jobs.controls("study"),
        ], className="controls"),
        html.Div(id="study-range", className="hint"),
        html.Div(id="study-error", className="error", role="alert"),
        ui.graph("study-graph", figure=style.message_figure("Press Compute: about 0.5-2 s per design and "
                                                            "configuration cold, instant from the cache", 560)),
        html.Div(id="study-table"),
        ui.downloads("study"),
        *jobs.stores("study", "study-request"),
    )


@dash.callback(Output("study-range", "children"), Input("study-param", "value"))
def allowed(name):
    spec = PARAMETER_SPECS[name]
    return f"{name}: {spec.description}; {spec.allowed}; current default {spec.default:g}"


def _request(parameter, text, fz_kn, configs, design):
    """The study request; a value that is not a number is reported by its position, like the API does."""
    values = []
    for k, item in enumerate(t.strip() for t in (text or "").split(",")):
        if not item:
            continue
        try:
            values.append(float(item))
        except ValueError:
            raise InvalidParameterError(f"values[{k}]", item, "a number", "is not a number") from None
    return {"parameter": parameter, "values": values, "configs": configs or [],
            "Fz": None if fz_kn is None else float(fz_kn) * 1e3, **design}


CONTROLS = (State("study-param", "value"), State("study-values", "value"), State("study-fz", "value"),
            State("study-configs", "value"), State(design_id("study"), "data"))


def _csv_rows(results):
    result = results[0]
    name = result["parameters"][0]
    rows = [[r[name], r["config"], r["hopf_start"], r["hopf_end"], r["max_psi"], r["max_psi_V"]]
            for r in result["rows"]]
    return [name, "config", "hopf_start_m_s", "hopf_end_m_s", "max_psi_rad", "max_psi_V_m_s"], rows


jobs.register(
    "study", "study", requests=lambda *controls: [_request(*controls)],
    render=lambda results: (figure(results[0]), summary(results[0])),
    outputs=[Output("study-graph", "figure"), Output("study-table", "children")], states=CONTROLS,
    lock=["study-param", "study-values", "study-fz"], store="study-request",
    download=jobs.Download("study", "study", _csv_rows, single=True))


def figure(result):
    name = result["parameters"][0]
    fig = make_subplots(rows=3, cols=1, shared_xaxes=True, vertical_spacing=0.06)
    for config in result["configs"]:
        rows = sorted((r for r in result["rows"] if r["config"] == config), key=lambda r: r[name])
        x = [r[name] for r in rows]
        colour, label = style.CONFIG_COLOURS[config], style.CONFIG_LABELS[config]
        for row, key in ((1, "hopf_start"), (2, "hopf_end"), (3, "max_psi")):
            fig.add_scatter(x=x, y=[r[key] for r in rows], mode="lines+markers", name=label, legendgroup=config,
                            showlegend=row == 1, line={"color": colour, "width": 2}, marker={"size": 7},
                            hovertemplate=f"{label}<br>{name} %{{x:.4g}}<br>%{{y:.5g}}<extra></extra>", row=row, col=1)
    fig.update_layout(title={"text": f"Study in {name} at Fz = {result['Fz'] / 1e3:g} kN", "x": 0.01}, height=640,
                      template="plotly_white", margin={"l": 70, "r": 16, "t": 44, "b": 48},
                      legend={"orientation": "h", "y": -0.1})
    fig.update_xaxes(title_text=f"{name}{_unit(name)}", row=3, col=1)
    fig.update_yaxes(title_text="first Hopf V (m/s)", row=1, col=1)
    fig.update_yaxes(title_text="last Hopf V (m/s)", row=2, col=1)
    fig.update_yaxes(title_text="max stable |psi| (rad)", row=3, col=1)
    return fig


def summary(result):
    name = result["parameters"][0]
    rows = [[f"{r[name]:.6g}", style.CONFIG_LABELS[r["config"]], ui.fmt(r["hopf_start"], 6), ui.fmt(r["hopf_end"], 6),
             ui.fmt(r["max_psi"], 5), ui.fmt(r["max_psi_V"], 4), "; ".join(r["warnings"]) or "–"]
            for r in sorted(result["rows"], key=lambda r: (r[name], CONFIGS.index(r["config"])))]
    return ui.table([f"{name}{_unit(name)}", "configuration", "first Hopf V (m/s)", "last Hopf V (m/s)",
                     "max stable |psi| (rad)", "at V (m/s)", "warnings"], rows, "study-summary")


@dash.callback(Output("url-update", "data", allow_duplicate=True),
               Input("study-param", "value"), Input("study-values", "value"), Input("study-fz", "value"),
               Input("study-configs", "value"), prevent_initial_call=True)
def remember(parameter, values, fz, configs):
    return {"parameter": parameter, "values": values, "Fz": fz, "configs": ",".join(configs or [])}
