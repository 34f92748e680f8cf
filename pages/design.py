"""Design decisions: which parameters move the shimmy boundaries (tornado charts of the sensitivities), the
optimiser over the device parameters, and robustness to tolerances, for the current design, a configuration
and a load. Every number comes from the service (jobs: sensitivity, optimise, robustness); the page draws.

The page lays out the controls its sections share (configuration and load) and the sections of
:mod:`ui.decisions`; the page's state in the address is :mod:`ui.decisions.address`."""

from __future__ import annotations

import dash
from dash import Input, Output, html

from ui import components as ui
from ui import ids
from ui.decisions import address, optimiser, robustness, sensitivity
from ui.decisions.common import FZ, check_field, field_error, stale
from ui.layout import page

dash.register_page(__name__, path="/design", name="Decisions", title="Design decisions", order=5.5)


def layout(**query):
    a, design = address.read(query)
    return page(
        design, ids.DES,
        ui.header("Design decisions", "For the current design, one configuration and one load: which parameters "
                  "move the shimmy boundaries and by how much (sensitivities by implicit differentiation), the best "
                  "device parameters for a figure of merit under constraints on the others (optimiser), and how "
                  "manufacturing and tyre tolerances spread the boundaries and the risk of shimmy at the nine "
                  "operating points (robustness). Methods: the documentation's Design decisions tutorial."),
        html.Div([
            html.Div([html.Label("Configuration", htmlFor=ids.DES_CONFIG),
                      ui.configurations(ids.DES_CONFIG, a.config),
                      field_error(ids.DES_CONFIG_ERROR, a.bad_config)], className="field"),
            html.Div([html.Label("Load Fz (kN)", htmlFor=ids.DES_FZ), FZ.box(ids.DES_FZ, a.fz, debounce=True),
                      field_error(ids.DES_FZ_ERROR, a.bad_fz)], className="field",
                     title=f"the load of the Hopf speeds and of the figures taken at a load; {FZ.allowed}"),
            html.Nav([html.A("Sensitivities", href=f"#{ids.SENSITIVITIES}"), " · ",
                      html.A("Optimiser", href=f"#{ids.OPTIMISER}"), " · ",
                      html.A("Robustness", href=f"#{ids.ROBUSTNESS}")], className="hint"),
        ], className="controls"),
        *sensitivity.section(a),
        *optimiser.section(a),
        *robustness.section(a),
    )


check_field(ids.DES_FZ, ids.DES_FZ_ERROR, FZ)
# Each section says when the result it shows no longer answers the page's configuration, load or design.
for _group in (ids.SENS, ids.OPT, ids.ROB):
    dash.callback(Output(_group.stale, "children"), Input(_group.requests, "data"), Input(ids.DES_CONFIG, "value"),
                  Input(ids.DES_FZ, "value"), Input(ids.design_store(ids.DES), "data"))(stale)
