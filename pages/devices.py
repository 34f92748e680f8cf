"""Devices: the NES restoring torque and stiffness (exact against cubic) and the PD damping."""

from __future__ import annotations

import dash
from dash import Input, Output, State, html, no_update

from shimmy.errors import InvalidParameterError
from shimmy.service import admission, analyses
from ui import components as ui
from ui import ids, style
from ui.layout import page

dash.register_page(__name__, path="/devices", name="Devices", order=1)

MATERIAL_COLOURS = {"design": "#009E73", "steel": "#0072B2", "tungsten": "#D55E00"}


def layout(**query):
    return page(query, ids.DEV,
                ui.header("Devices", "The torsional NES: restoring torque and stiffness of the roller-spring "
                          "geometry against the cubic fit the dynamics use, over the angle range where the roller "
                          "stays on its track (|a| < pi/6). The particle damper: equivalent torsional damping "
                          "against tangential speed for steel shot and tungsten powder at the current filling."),
                html.Div(id=ids.DEV_GROUP.error, className="error", role="alert"),
                html.Div(id=ids.DEV_METRICS, className="metrics"),
                html.Div([ui.graph(ids.DEV_TORQUE), ui.graph(ids.DEV_STIFFNESS)], className="grid-2"),
                ui.graph(ids.DEV_PD),
                ui.downloads(ids.DEV_GROUP))


@dash.callback(Output(ids.DEV_TORQUE, "figure"), Output(ids.DEV_STIFFNESS, "figure"), Output(ids.DEV_PD, "figure"),
               Output(ids.DEV_METRICS, "children"), Output(ids.DEV_GROUP.error, "children"), Output(ids.DEV_GROUP.csv,
                                                                                                    "disabled"),
               Output(ids.DEV_GROUP.json, "disabled"), Input(ids.design_store(ids.DEV), "data"))
def update(design):
    try:
        result, _ = analyses.run("devices", design)
    except InvalidParameterError as exc:
        return no_update, no_update, no_update, no_update, str(exc), True, True
    except admission.Busy as exc:
        return no_update, no_update, no_update, no_update, f"The service is busy: {exc}.", no_update, no_update
    nes = result["nes"]
    torque = style.figure("NES restoring torque", "relative rotation a = psi - psis (rad)", "torque M (N m)")
    torque.add_scatter(x=nes["angle"], y=nes["torque_exact"], name="exact geometry", line={"color": "#000"})
    torque.add_scatter(x=nes["angle"], y=nes["torque_cubic"], name="cubic fit k1 a + k3 a^3",
                       line={"color": "#E69F00", "dash": "dash"})
    stiff = style.figure("NES stiffness", "relative rotation a (rad)", "stiffness dM/da (N m/rad)")
    stiff.add_scatter(x=nes["angle"], y=nes["stiffness_exact"], name="exact geometry", line={"color": "#000"})
    stiff.add_scatter(x=nes["angle"], y=nes["stiffness_cubic"], name="cubic fit k1 + 3 k3 a^2",
                      line={"color": "#E69F00", "dash": "dash"})
    pd = style.figure("Particle damper: equivalent torsional damping", "tangential speed v = r |dpsi| (m/s)",
                      "c_eq = n r^2 c*(v) (N m s/rad)")
    # The current design first, as a wide translucent band, then the presets over it as thin lines: a
    # design equal to a preset shows both (the preset line runs inside the band), and says so.
    curves = sorted(result["pd"], key=lambda c: c["material"] != "design")
    design = next((c for c in curves if c["material"] == "design"), None)
    same = [c["material"] for c in curves if design is not None and c is not design
            and c["torsional_damping"] == design["torsional_damping"]]
    for curve in curves:
        current = curve is design
        name = ("current design" + (f" (= {same[0]} preset)" if same else "")) if current \
            else f"{curve['material']} preset"
        colour = MATERIAL_COLOURS.get(curve["material"], "#555")
        pd.add_scatter(x=curve["speed"], y=curve["torsional_damping"], name=name, opacity=0.45 if current else 1.0,
                       line={"color": colour, "width": 7 if current else 2, "dash": "solid" if current else "dot"})
    errors = result["nes_cubic_error"]
    metrics = [_metric("k1 (N m/rad)", f"{nes['k1']:.5g}"), _metric("k3 (N m/rad^3)", f"{nes['k3']:.5g}")]
    metrics += [_metric(f"cubic error, |a| <= {a} rad", f"{100 * e:.2f} %") for a, e in errors.items()]
    return torque, stiff, pd, metrics, "", False, False


def _metric(label: str, value: str) -> html.Div:
    return html.Div([html.Div(value, className="value"), html.Div(label, className="label")], className="metric")


@dash.callback(Output(ids.DEV_GROUP.download, "data"), Input(ids.DEV_GROUP.csv, "n_clicks"), Input(ids.DEV_GROUP.json,
                                                                                                   "n_clicks"),
               State(ids.design_store(ids.DEV), "data"), prevent_initial_call=True)
def download(_csv, _json, design):
    try:
        result = analyses.cached("devices", design)  # drawn by update() above: a download never computes
    except InvalidParameterError:
        return no_update
    if result is None:
        return no_update
    if dash.ctx.triggered_id == ids.DEV_GROUP.json:
        return {"content": ui.json_text(result), "filename": "devices.json"}
    nes = result["nes"]
    rows = zip(nes["angle"], nes["torque_exact"], nes["torque_cubic"], nes["stiffness_exact"], nes["stiffness_cubic"],
               strict=True)
    return {"content": ui.csv_text(["angle_rad", "torque_exact_Nm", "torque_cubic_Nm", "stiffness_exact_Nm_rad",
                                    "stiffness_cubic_Nm_rad"], rows), "filename": "nes_curves.csv"}
