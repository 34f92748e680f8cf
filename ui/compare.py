"""The pages' comparisons of saved designs: the designs ticked under Compare in the design panel,
one colour each, their analyses requested from the service like the page's own (same requests,
so the shared cache serves a design already drawn), and their figures side by side with the
changes against the first. The logic is :mod:`ui.designs`; this is the Dash side.
"""

from __future__ import annotations

import json
from html import escape
from typing import Any

import dash
from dash import Input, Output, State, dcc, html

from shimmy.errors import InvalidParameterError

from . import designs, ids, style
from .ids import Group

#: The inputs that say which designs are compared (the panel's, on every page).
SELECTION = (Input(ids.DESIGN_COMPARE, "value"), Input(ids.SAVED, "data"))


def follower_id(page: Any) -> str:
    return f"{page}-compare-follows-design"


def follower(page: Any) -> dcc.Store:
    """A store of ``page``'s layout that takes the page's design only while the current design is
    ticked for the comparison: a comparison of saved designs alone does not depend on it, so a slider
    step then sends no request for it (:func:`follows_design` registers its browser callback)."""
    return dcc.Store(id=follower_id(page))


def follows_design(page: Any) -> tuple[Input, State]:
    """Register the browser's callback that fills :func:`follower` of ``page``; (the Input that fires
    when the comparison may change with the design, the State of the design itself)."""
    dash.clientside_callback(
        """
        function(design, selection) {
            return (selection || []).includes(%s) ? design : window.dash_clientside.no_update;
        }
        """ % json.dumps(designs.CURRENT),
        Output(follower_id(page), "data"),
        Input(ids.design_store(page), "data"), State(ids.DESIGN_COMPARE, "value"),
        prevent_initial_call=True,
    )
    return Input(follower_id(page), "data"), State(ids.design_store(page), "data")


def chosen(selection: Any, saved: Any, current: Any) -> list[designs.Design]:
    """The compared designs, or InvalidParameterError saying what to tick (the pages' refusal type)."""
    try:
        return designs.compared(selection, saved, current)
    except designs.DesignError as exc:
        raise InvalidParameterError("designs", selection, f"{designs.COMPARE[0]} to {designs.COMPARE[1]} "
                                    "different, usable designs", message="; ".join(exc.problems)) from None


def colour(k: int) -> str:
    return style.DESIGN_COLOURS[k % len(style.DESIGN_COLOURS)]


def series(names: list[str]) -> list[tuple[str, str]]:
    """(name as a figure shows it, colour) per design: Plotly reads tags and entities in its texts,
    so a name (from someone's file, say) is escaped to show as typed."""
    return [(escape(name, quote=False), colour(k)) for k, name in enumerate(names)]


def swatches(names: list[str]) -> list:
    """'Comparing: ■ A  ■ B' with each design's colour."""
    out: list = [html.Span("Comparing: ")]
    for k, name in enumerate(names):
        out += [html.Span("■ ", style={"color": colour(k)}), html.Span(name, className="design-tag"),
                html.Span(" (reference)  " if k == 0 else "  ")]
    return out


def refusal(exc: InvalidParameterError) -> html.Span:
    """The line that says what to tick, in place of the compared designs' swatches."""
    return html.Span(str(exc), className="hint")


def shows(line: Any, exc: InvalidParameterError) -> bool:
    """True if ``line`` (the designs line's children as the browser holds them) already is
    :func:`refusal` of ``exc``: a design step that leaves the comparison refused for the same reason
    sends nothing, and nothing is drawn again (on the Overview that redraw delayed the growth figure's
    on every slider step)."""
    props = line.get("props", {}) if isinstance(line, dict) else {}
    return props.get("children") == str(exc) and props.get("className") == "hint"


def register_selection(group: Group, page_id: str) -> None:
    """The line that says which designs the page's comparison would show (or what to tick)."""

    @dash.callback(Output(group.designs, "children"), *SELECTION, *follows_design(page_id),
                   State(group.designs, "children"))
    def _designs(selection, saved, _design_step, current, line):
        try:
            return swatches([d.name for d in chosen(selection, saved, current)])
        except InvalidParameterError as exc:
            return dash.no_update if shows(line, exc) else refusal(exc)


def table(comparison: dict[str, Any], table_id: str) -> html.Table:
    """Figures as rows, designs as columns (each after the first with its change against the first)."""
    names = comparison["columns"][1:]
    head = [html.Th("figure")] + [html.Th([html.Span("■ ", style={"color": colour(k)}), name,
                                           html.Small(" (reference)" if k == 0 else "")])
                                  for k, name in enumerate(names)]
    body = []
    for label, *cells in comparison["rows"]:
        tds = [html.Td(label, className="figure-name")]
        for cell in cells:
            parts: list = [cell.text]
            if cell.change is not None:
                parts += [html.Br(), html.Small(f"Δ {cell.change}", className="change")]
            tds.append(html.Td(parts))
        body.append(html.Tr(tds))
    return html.Table([html.Thead(html.Tr(head)), html.Tbody(body)], id=table_id, className="data-table compare")


def waiting_text(what: str) -> str:
    return (f"Tick {designs.COMPARE[0]} to {designs.COMPARE[1]} designs under Compare in the design panel, then "
            f"press Compare: {what}")
