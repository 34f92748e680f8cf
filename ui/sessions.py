"""Saved designs in the design panel: name and save the design in the browser, reopen, rename or
delete a saved one, download it as a JSON file or open one, copy the link that reopens it, and
tick the designs the pages compare. The logic is :mod:`ui.designs`; these callbacks only carry it.

Opening a design (an entry, a file) goes through the address, like a shared link: its keys replace
the design keys of the address (the page's own keys stay) and the page loads from it, so a design
reopened any way shows what its link shows.
"""

from __future__ import annotations

import base64
import binascii
import json

import dash
from dash import ALL, Input, Output, State, dcc, html, no_update

from . import designs, ids


def section() -> html.Details:
    """The panel's block of saved designs (the ids are the same on every page: one panel at a time)."""
    return html.Details([
        html.Summary("Saved designs"),
        dcc.Store(id=ids.SAVED, storage_type="local"), dcc.Store(id=ids.DESIGNS_FOLLOW),
        dcc.Store(id=ids.DESIGN_ASK), dcc.Store(id=ids.DESIGN_UPLOAD_ASK), dcc.Store(id=ids.DESIGN_OPEN),
        html.Div(id=ids.DESIGN_OPEN_SINK, hidden=True),
        html.Div([dcc.Input(id=ids.DESIGN_NAME, type="text", placeholder="name this design", maxLength=designs.MAX_NAME,
                            className="design-name", debounce=False),
                  html.Button("Save design", id=ids.DESIGN_SAVE, title="Save the design in this browser")],
                 className="save-line"),
        html.Div(id=ids.DESIGNS_MESSAGE, className="designs-message", role="status"),
        html.Div(id=ids.DESIGNS_LIST, className="saved-list"),
        html.Div([html.Label("Compare (tick 2 to 4)", htmlFor=ids.DESIGN_COMPARE),
                  dcc.Checklist(id=ids.DESIGN_COMPARE, value=[], className="compare-list",
                                options=[{"label": designs.CURRENT_NAME, "value": designs.CURRENT}],
                                persistence=True, persistence_type="local"),
                  html.Small("The Overview, Bifurcation and Stability map pages overlay the ticked designs "
                             "(changes against the first).", className="hint")], className="compare-block"),
        html.Div([html.Button("Download JSON", id=ids.DESIGN_DOWNLOAD_JSON, className="secondary",
                              title="This design as a JSON file (name, material, every parameter value)"),
                  dcc.Upload(html.Button("Open JSON…", className="secondary", title="Open a design file"),
                             id=ids.DESIGN_UPLOAD, accept=".json,application/json"),
                  dcc.Download(id=ids.DESIGN_DOWNLOAD)], className="file-line"),
        html.Label("Link to this design", htmlFor=ids.DESIGN_LINK),
        html.Div([dcc.Input(id=ids.DESIGN_LINK, type="text", readOnly=True, className="design-link"),
                  dcc.Clipboard(target_id=ids.DESIGN_LINK, title="Copy the link", className="copy-link")],
                 className="link-line"),
    ], open=True, id=ids.DESIGNS, className="designs")


def _message(text: str, notes: list[str] | None = None) -> list:
    return [html.Span(text), *([html.Ul([html.Li(n) for n in notes])] if notes else [])]


def _refusal(exc: designs.DesignError) -> html.Div:
    return html.Div([html.Span(f"Refused ({exc.what}):"),
                     html.Ul([html.Li(p) for p in exc.problems])], className="error", role="alert")


def _decode(contents: str) -> bytes:
    """The bytes of a dcc.Upload's data URL."""
    head, _, body = contents.partition(",")
    if not head.endswith(";base64"):
        raise designs.DesignError("the file", ["did not arrive as a file (no base64 data)"])
    try:
        return base64.b64decode(body, validate=True)
    except (binascii.Error, ValueError):
        raise designs.DesignError("the file", ["did not arrive whole (its base64 data is damaged)"]) from None


def _open(design: designs.Design, message: str) -> dict:
    return {"query": design.query(), "message": message}


def _current(stores) -> object:
    return (stores or [None])[0]


@dash.callback(Output(ids.SAVED, "data"), Output(ids.DESIGN_OPEN, "data"), Output(ids.DESIGNS_MESSAGE, "children"),
               Input(ids.DESIGN_ASK, "data"), Input(ids.DESIGN_UPLOAD_ASK, "data"),
               Input(ids.saved(ids.SAVED_OPEN_TYPE, ALL), "n_clicks"),
               Input(ids.saved(ids.SAVED_DELETE_TYPE, ALL), "n_clicks"),
               Input(ids.saved(ids.SAVED_NAME_TYPE, ALL), "value"),
               State(ids.SAVED, "data"), State(ids.design_store(ALL), "data"), prevent_initial_call=True)
def act(ask, upload, _opens, _deletes, _names, saved, stores):
    """Save, open, rename, delete, open a file: the store, the design to open, what was done."""
    trig = dash.ctx.triggered_id
    value = dash.ctx.triggered[0]["value"] if dash.ctx.triggered else None
    try:
        if trig == ids.DESIGN_ASK:
            if not isinstance(ask, dict) or ask.get("action") != "save":
                return no_update, no_update, no_update
            design = designs.current_design(_current(stores), ask.get("name"))
            design = designs.Design(design.name, design.material, design.params,
                                    designs.config_from_search(ask.get("search")))
            new, _, text = designs.save(saved, design)
            return new, no_update, _message(text)
        if trig == ids.DESIGN_UPLOAD_ASK:
            if not isinstance(upload, dict) or not isinstance(upload.get("contents"), str):
                return no_update, no_update, no_update
            design, notes = designs.from_file(_decode(upload["contents"]), str(upload.get("filename") or "the file"))
            new, _, text = designs.save(saved, design)
            said = f"Opened {design.name!r} from {upload.get('filename') or 'the file'}. {text}"
            return new, _open(design, " ".join([said, *(f"Note: {n}." for n in notes)])), _message(said, notes)
        if not isinstance(trig, dict):
            return no_update, no_update, no_update
        entry_id = str(trig.get("id"))
        if trig.get("type") == ids.SAVED_OPEN_TYPE and value:
            entry = designs.find(saved, entry_id)
            if entry is None:
                return no_update, no_update, _message("That design is no longer saved.")
            design = designs.from_entry(entry)
            return no_update, _open(design, f"Opened {design.name!r}."), _message(f"Opening {design.name!r}…")
        if trig.get("type") == ids.SAVED_DELETE_TYPE and value:
            new, text = designs.delete(saved, entry_id)
            return new, no_update, _message(text)
        if trig.get("type") == ids.SAVED_NAME_TYPE:
            entry = designs.find(saved, entry_id)
            if entry is None or value == entry.get("name"):  # a list drawn again, not a rename
                return no_update, no_update, no_update
            new, text = designs.rename(saved, entry_id, value)
            return new, no_update, _message(text)
    except designs.DesignError as exc:  # a refused rename: the list is drawn again with the saved name
        return (saved if isinstance(trig, dict) else no_update), no_update, _refusal(exc)
    return no_update, no_update, no_update


@dash.callback(Output(ids.DESIGN_DOWNLOAD, "data"), Input(ids.DESIGN_ASK, "data"),
               State(ids.design_store(ALL), "data"), prevent_initial_call=True)
def download(ask, stores):
    """The design in the panel as a file, named by the name box (the page's configuration with it)."""
    if not isinstance(ask, dict) or ask.get("action") != "download":
        return no_update
    name = ask.get("name") if isinstance(ask.get("name"), str) and ask.get("name").strip() else "design"
    try:
        design = designs.current_design(_current(stores), name)
    except designs.DesignError:
        return no_update
    design = designs.Design(design.name, design.material, design.params, designs.config_from_search(ask.get("search")))
    return {"content": design.text(), "filename": design.filename(), "type": "application/json"}


# The saved list depends on the page's design only through which saved design it is ("shown now"):
# with nothing saved, a slider step sends no request for it.
dash.clientside_callback(
    """
    function(stores, saved) {
        const some = saved && Array.isArray(saved.designs) && saved.designs.length > 0;
        return some ? stores : window.dash_clientside.no_update;
    }
    """,
    Output(ids.DESIGNS_FOLLOW, "data"),
    Input(ids.design_store(ALL), "data"), State(ids.SAVED, "data"),
    prevent_initial_call=True,
)


@dash.callback(Output(ids.DESIGNS_LIST, "children"), Output(ids.DESIGN_COMPARE, "options"),
               Output(ids.DESIGN_NAME, "value"),
               Input(ids.SAVED, "data"), Input(ids.DESIGNS_FOLLOW, "data"), State(ids.design_store(ALL), "data"),
               State(ids.DESIGN_NAME, "value"), State(ids.DESIGNS_LIST, "children"))
def show(saved, _design_step, stores, name, shown):
    """The saved designs (the current one marked, one that can no longer be used says why) and the
    compare choices; an empty name box takes the name of the saved design shown."""
    entries = designs.saved_list(saved)
    if not entries and shown and dash.ctx.triggered_id != ids.SAVED:  # a design step, nothing saved: as shown
        return no_update, no_update, no_update
    try:
        match = designs.matching(saved, designs.current_design(_current(stores)))
    except designs.DesignError:
        match = None
    rows = []
    for e in entries:
        problem = designs.usable(e)
        is_current = match is not None and e["id"] == match["id"]
        detail = (f"not usable: {problem}" if problem else designs.from_entry(e).summary())
        rows.append(html.Div([
            html.Div([html.Div(dcc.Input(id=ids.saved(ids.SAVED_NAME_TYPE, e["id"]), type="text", value=e.get("name"),
                                         debounce=True, maxLength=designs.MAX_NAME, className="saved-name"),
                               title="Type a new name and press Enter to rename", className="saved-name-wrap"),
                      html.Button("Open", id=ids.saved(ids.SAVED_OPEN_TYPE, e["id"]), className="secondary small",
                                  disabled=bool(problem), title=f"Open {e.get('name')!r} on this page"),
                      html.Button("Delete", id=ids.saved(ids.SAVED_DELETE_TYPE, e["id"]), className="secondary small",
                                  title=f"Delete {e.get('name')!r} from this browser")], className="saved-line"),
            html.Div(("● shown now · " if is_current else "") + detail,
                     className="saved-detail error" if problem else "saved-detail"),
        ], className="saved-row current" if is_current else "saved-row"))
    if not rows:
        rows = [html.Div("No design saved in this browser yet.", className="hint")]
    options = [{"label": designs.CURRENT_NAME, "value": designs.CURRENT}]
    options += [{"label": e.get("name"), "value": e["id"], "disabled": designs.usable(e) is not None}
                for e in entries]
    fill = match.get("name") if match is not None and not (name or "").strip() else no_update
    return rows, options, fill


# Save and Download read the page's address (a configuration it names goes into the design).
dash.clientside_callback(
    """
    function(save, down, name) {
        const trig = window.dash_clientside.callback_context.triggered_id;
        if (!trig) { return window.dash_clientside.no_update; }
        return {action: trig === %s ? "save" : "download", name: name || "",
                search: window.location.search, t: Date.now()};
    }
    """ % json.dumps(ids.DESIGN_SAVE),
    Output(ids.DESIGN_ASK, "data"),
    Input(ids.DESIGN_SAVE, "n_clicks"), Input(ids.DESIGN_DOWNLOAD_JSON, "n_clicks"), State(ids.DESIGN_NAME, "value"),
    prevent_initial_call=True,
)

# A file goes to the server only if it can be a design file (the callback's body is bounded).
dash.clientside_callback(
    """
    function(contents, filename) {
        const C = window.dash_clientside;
        if (!contents) { return [C.no_update, C.no_update, C.no_update]; }
        const input = document.querySelector("#%s input[type=file]");
        if (input) { input.value = ""; }  // the same file chosen again (edited) is read again
        const bytes = Math.floor((contents.length - contents.indexOf(",") - 1) * 3 / 4);
        if (bytes > %d) {  // emptied again, so that choosing the same file once more is seen
            return [C.no_update, filename + " is refused: it is " + Math.round(bytes / 1024) +
                    " kB; a design file is a few kB (at most %d kB).", null];
        }
        return [{contents: contents, filename: filename, t: Date.now()}, C.no_update, null];
    }
    """ % (ids.DESIGN_UPLOAD, designs.MAX_FILE_BYTES, designs.MAX_FILE_BYTES // 1024),
    Output(ids.DESIGN_UPLOAD_ASK, "data"), Output(ids.DESIGNS_MESSAGE, "children", allow_duplicate=True),
    Output(ids.DESIGN_UPLOAD, "contents"),
    Input(ids.DESIGN_UPLOAD, "contents"), State(ids.DESIGN_UPLOAD, "filename"),
    prevent_initial_call=True,
)

# Open: the design's keys replace those of the address (the page's own keys stay), then the page
# loads from the address, as from a shared link (a moment first, for the saved list to reach storage).
dash.clientside_callback(
    """
    function(open) {
        if (!open || !open.query) { return window.dash_clientside.no_update; }
        const params = new URLSearchParams(window.location.search);
        for (const [k, v] of Object.entries(open.query)) {
            if (v === null || v === undefined || v === "") { params.delete(k); } else { params.set(k, String(v)); }
        }
        const s = params.toString();
        const url = window.location.pathname + (s ? "?" + s : "");
        try { sessionStorage.setItem("shimmy-opened", JSON.stringify(open.message || "")); } catch (e) {}
        setTimeout(() => window.location.assign(url), 150);
        return url;
    }
    """,
    Output(ids.DESIGN_OPEN_SINK, "children"),
    Input(ids.DESIGN_OPEN, "data"),
    prevent_initial_call=True,
)

# The link box shows the address (design and page state) when the page loads and whenever the
# address changes (the loading call is its own: the address updater's first call changes nothing,
# and Dash then skips what depends on it).
LINK = """
    function(_s) { return window.location.href; }
"""
dash.clientside_callback(LINK, Output(ids.DESIGN_LINK, "value"), Input(ids.DESIGN_LINK, "id"))
dash.clientside_callback(LINK, Output(ids.DESIGN_LINK, "value", allow_duplicate=True), Input(ids.URL_SINK, "children"),
                         prevent_initial_call=True)

# After an open, the page that loaded says what was opened (and what the file left to the preset).
dash.clientside_callback(
    """
    function(_s) {
        let text = "";
        try { text = JSON.parse(sessionStorage.getItem("shimmy-opened") || '""');
              sessionStorage.removeItem("shimmy-opened"); } catch (e) {}
        return text || window.dash_clientside.no_update;
    }
    """,
    Output(ids.DESIGNS_MESSAGE, "children", allow_duplicate=True),
    Input(ids.DESIGN_OPEN_SINK, "id"),
    prevent_initial_call="initial_duplicate",
)
