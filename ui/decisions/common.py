"""What the three sections of the Design decisions page share: the configuration and load they are
computed for, the figures of merit as the page shows them, the tables' and charts' style, and the
line that says a shown result no longer answers the page's controls."""

from __future__ import annotations

from dash import html

from shimmy.errors import InvalidParameterError
from shimmy.model.parameters import PARAMETER_SPECS
from shimmy.service import schemas
from ui import components as ui
from ui import fields, merits, style
from ui.fields import Quantity, field_error, refusal  # noqa: F401 - the sections' names for them

CONFIGS = ui.CONFIGS
FZ = Quantity("sensitivity", "Fz", "Fz", "kN", 1e3)

#: The units the page shows a figure of merit in where they are not the package's: unit, SI units per shown unit.
SHOWN_UNITS = {"min_shimmy_Fz": ("kN", 1e3)}
#: How the page shows each figure of merit: label (the package's, "at Fz" for one taken at the load), unit
#: shown, SI units per shown unit.
FIGURES = {name: (merits.label(name) + (" at Fz" if f.at_load else ""), *SHOWN_UNITS.get(name, (f.unit, 1.0)))
           for name, f in schemas.FIGURES.items()}
OPS = {"<=": "≤", ">=": "≥"}
UP, DOWN = "#0072B2", "#D55E00"  # Okabe–Ito blue and vermilion: raises / lowers
GRID = {"display": "grid", "gridTemplateColumns": "repeat(auto-fill, minmax(min(100%, 470px), 1fr))", "gap": "12px"}
TABLE_STYLE = {"style_table": {"overflowX": "auto", "maxWidth": "640px"},
               "style_cell": {"fontFamily": "inherit", "fontSize": "13px", "padding": "3px 8px", "textAlign": "left"},
               "style_header": {"backgroundColor": "#eef2f8", "fontWeight": "600"},
               "css": [{"selector": ".Select-menu-outer", "rule": "display: block !important"}]}


def unit_suffix(name: str) -> str:
    """" (m)" after a parameter's name: its unit, if it has one."""
    unit = PARAMETER_SPECS[name].unit
    return f" ({unit})" if unit else ""


def placeholder(text: str) -> html.P:
    """What stands where a result will be drawn."""
    return html.P(text, className="hint placeholder")


def check_field(box: str, error_id: str, quantity: Quantity) -> None:
    """The field says at once what is wrong with it, in its unit (:func:`ui.fields.check`)."""
    fields.check(box, quantity, error_id)


def stale(shown, config, fz_kn, design) -> str:
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
