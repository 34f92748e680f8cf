"""Small building blocks shared by the pages."""

from __future__ import annotations

import csv
import io
import json
from typing import Any, Iterable

from dash import dcc, html

from shimmy.model.configurations import OPERATING_POINTS as _OPERATING_POINTS_N, Configuration

from . import style
from .ids import Group


def _whole(x: float) -> float | int:
    return int(x) if float(x).is_integer() else x


#: The study's nine operating points A-I: name -> (V m/s, Fz kN), from the package's definition in N.
OPERATING_POINTS = {name: (_whole(v), _whole(fz / 1e3)) for name, (v, fz) in _OPERATING_POINTS_N.items()}

GRAPH_CONFIG = {"displaylogo": False, "toImageButtonOptions": {"format": "png", "scale": 2}}
#: The four configurations in the order the pages list them (original, NES, PD, NES + PD).
CONFIGS = tuple(style.CONFIG_LABELS)


def header(title: str, lead: str) -> html.Div:
    return html.Div([html.H1(title), html.P(lead, className="lead")], className="page-header")


def graph(graph_id: str, **kwargs) -> dcc.Graph:
    return dcc.Graph(id=graph_id, config=GRAPH_CONFIG, **kwargs)


def downloads(group: Group, csv_label: str = "Download CSV", json_label: str = "Download JSON") -> html.Div:
    """CSV and JSON download buttons (the group's csv and json ids) and their dcc.Download."""
    return html.Div([
        html.Button(csv_label, id=group.csv, className="secondary", disabled=True),
        html.Button(json_label, id=group.json, className="secondary", disabled=True),
        dcc.Download(id=group.download),
    ], className="downloads")


def progress_bar(group: Group) -> html.Div:
    return html.Div([html.Progress(id=group.progress, value="0", max="100"),
                     html.Span(id=group.status, className="status")], className="progress-row")


def configurations(component_id: str, value, multi: bool = False, width: str = "150px") -> dcc.Dropdown | dcc.Checklist:
    """The configuration picker, labelled as the pages name the configurations: a dropdown of one
    (``value`` a configuration) or, ``multi``, a row of check boxes (``value`` a list of them)."""
    options = [{"label": style.CONFIG_LABELS[c], "value": c} for c in CONFIGS]
    if multi:
        return dcc.Checklist(id=component_id, value=value, inline=True, options=options)
    return dcc.Dropdown(id=component_id, value=value, clearable=False, style={"width": width}, options=options)


def field(label: str, control, hint: str | None = None) -> html.Div:
    return html.Div([html.Label(label), control, html.Small(hint) if hint else None], className="field")


def table(columns: list[str], rows: Iterable[Iterable[Any]], table_id: str | None = None) -> html.Table:
    kwargs = {"id": table_id} if table_id else {}
    return html.Table([html.Thead(html.Tr([html.Th(c) for c in columns])),
                       html.Tbody([html.Tr([html.Td(c) for c in r]) for r in rows])], className="data-table",
                      **kwargs)


def csv_text(columns: list[str], rows: Iterable[Iterable[Any]]) -> str:
    out = io.StringIO()
    w = csv.writer(out)
    w.writerow(columns)
    for r in rows:
        w.writerow(r)
    return out.getvalue()


def json_text(payload: Any) -> str:
    return json.dumps(payload, indent=1, allow_nan=False)


def number(raw, default: float) -> float:
    """A URL value as a number for a control's initial value (the default if it is not one)."""
    try:
        return float(raw)
    except (TypeError, ValueError):
        return default



#: The NES torque choices of the pages that integrate or continue the NES (Time history, Ground run,
#: Bifurcation): the cubic fit the study uses, or the exact torque of the roller on its track.
NES_TORQUES = {"cubic": "cubic fit (the study's; within 1 % for small NES rotations)",
               "exact": "exact torque (slower)"}


def nes_torque(component_id: str, value: str = "cubic") -> dcc.RadioItems:
    """The NES torque choice (``value`` "cubic" or "exact")."""
    return dcc.RadioItems(id=component_id, value=value, inline=True,
                          options=[{"label": label, "value": k} for k, label in NES_TORQUES.items()])


def exact_nes(config: str, torque: str | None) -> dict[str, bool]:
    """The request's exact_nes for ``config`` with the torque chosen: only a configuration with an NES
    asks for it (the others' answers do not depend on it and stay one cache entry)."""
    return {"exact_nes": True} if torque == "exact" and Configuration.parse(config).has_nes else {}


def result_notice(results: list[dict[str, Any]]) -> str:
    """What the results say the user must know, by configuration: a run that failed (its message) and
    every warning (an NES rotation beyond the cubic's range, ...)."""
    said = [f"{r['config']}: {r['message']}" for r in results if r.get("success") is False]
    said += [f"Warning ({r['config']}): {w}" for r in results for w in r.get("warnings", ())]
    return " ".join(dict.fromkeys(said))
