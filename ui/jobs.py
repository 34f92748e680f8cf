"""One component for a page's long computation: Compute and Cancel buttons, a progress bar,
an answer at once from the cache, jobs of the service otherwise, and CSV/JSON downloads.

A page lays out :func:`controls` (the run and cancel buttons, progress and poll of an
:class:`ui.ids.Group`) and :func:`ui.components.downloads`, then calls :func:`register` with what is
particular to it: how its controls become requests, how results become its outputs, and how
results become CSV rows.

Nothing is computed in the web worker and no process is started by Dash: a Compute submits
one job per uncached request through :mod:`shimmy.service.jobs`, the admission control the
API uses (bounded queue, identical requests shared, a full queue refused with a message), and
an interval reads the jobs' progress until every result is in the cache. The interval's
callback only says so (a small answer that stops the interval); a second callback, triggered
once by that, draws the results. Dash drops the answer of a callback whose input changed again
while it ran (plotly/dash#1613), so a poll that drew a large figure more slowly than the
interval (a loaded machine, a long time history) was dropped on every tick and the page never
showed its result. At most
``MAX_PAGE_REQUESTS`` requests per action. The requests of the last answer are kept in a
store so that the downloads serialise exactly what is drawn, from the cache (a download never
computes).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Sequence

import dash
from dash import Input, Output, State, dcc, html, no_update

from shimmy.errors import InvalidParameterError
from shimmy.service import cache, jobs, schemas, settings

from . import components
from .ids import Group


def controls(group: Group, label: str = "Compute", interval: int = 400) -> list:
    """The run and cancel buttons, the progress bar of a job and the interval that reads it."""
    return [html.Button(label, id=group.run),
            html.Button("Cancel", id=group.cancel, className="secondary", disabled=True),
            components.progress_bar(group),
            dcc.Interval(id=group.poll, interval=interval, disabled=True)]


def stores(group: Group) -> list:
    """The store of the shown results' requests, the ids of the jobs being waited for and the
    jobs whose results are ready to be drawn."""
    return [dcc.Store(id=group.requests), dcc.Store(id=group.go), dcc.Store(id=group.ready)]


@dataclass(frozen=True)
class Download:
    """How a page's results become files: ``rows(results)`` -> (columns, rows) for the CSV."""

    files: Group  # the buttons and the dcc.Download (its csv, json and download ids)
    name: str  # file stem
    rows: Callable[[list[dict[str, Any]]], tuple[list[str], list[list[Any]]]]
    single: bool = False  # the page shows one result: its JSON is that result, not a list of one
    filename: Callable[[list[dict[str, Any]]], str] | None = None  # file stem from the results


def canonical(analysis: str, wanted: Any) -> list[dict[str, Any]]:
    """The page's requests validated (each refusal names its field), duplicates dropped, at most
    MAX_PAGE_REQUESTS."""
    if not isinstance(wanted, list) or not wanted:
        raise InvalidParameterError("requests", type(wanted).__name__, "a non-empty list of requests")
    out, keys = [], set()
    for body in wanted:
        request = schemas.validate(analysis, body)
        k = cache.key(analysis, request)
        if k not in keys:
            keys.add(k)
            out.append(request)
    if len(out) > settings.MAX_PAGE_REQUESTS:
        raise InvalidParameterError("configs", len(out), f"at most {settings.MAX_PAGE_REQUESTS} analyses at once",
                                    "asks for too many analyses")
    return out


def register(group: Group, analysis: str, *, requests: Callable[..., list[dict[str, Any]]],
             render: Callable[[list[dict[str, Any]]], tuple], outputs: Sequence[Output], states: Sequence[State],
             download: Download, lock: Sequence[str] = (), error: str | None = None,
             triggers: Sequence[Input] = (), initial: bool | str = "cached",
             notice: Callable[[list[dict[str, Any]]], str] | None = None,
             blank: Callable[[], tuple] | None = None, running: Callable[[], tuple] | None = None,
             labels: Callable[..., list[str]] | None = None) -> None:
    """Wire the job of one page.

    ``requests(*trigger values, *state values)`` -> the analysis requests (may raise
    InvalidParameterError); ``render(results)`` -> one value per entry of ``outputs``;
    ``lock`` are ids of controls disabled while the jobs run; ``error`` the id of the element
    that shows a refusal (the group's error line by default), ``notice(results)`` what it shows with a
    result; ``triggers`` inputs that start a computation besides the run button. When the page
    loads, ``initial="cached"`` shows the answer to the page's controls if the cache has it (and
    computes nothing otherwise), ``True`` computes it, ``False`` does nothing. ``blank()`` -> the
    outputs that replace a shown result when the controls are refused (the old result no longer
    answers them); ``running()`` -> the outputs shown while the jobs run (default: the old ones stay).
    ``labels(*values)`` -> a name for each request (the designs of a comparison): the results are then
    drawn by ``render(results, names)`` and tabulated by ``download.rows(results, names)``, and the
    requests store holds {"requests", "labels"}.
    """
    store, files = group.requests, download.files
    error = error or group.error
    n_out = len(outputs)
    tail = [Output(error, "children"), Output(store, "data"), Output(files.csv, "disabled"), Output(files.json,
                                                                                                    "disabled")]
    state = [Output(group.go, "data"), Output(group.poll, "disabled"), Output(group.run, "disabled"),
             Output(group.cancel, "disabled"), *(Output(name, "disabled") for name in lock),
             Output(group.progress, "value"), Output(group.status, "children")]
    idle = (None, True, False, True, *(False for _ in lock))

    def refused(message: str, status: str = "", clear: bool = False) -> tuple:
        if clear and blank is not None:
            return (*blank(), message, None, True, True) + idle + ("0", status)
        return (no_update,) * n_out + (message, no_update, no_update, no_update) + idle + ("0", status)

    def shown(results: list[dict[str, Any]], wanted: list[dict[str, Any]], names: list[str] | None) -> tuple:
        drawn = render(results) if labels is None else render(results, names)
        kept = wanted if labels is None else {"requests": wanted, "labels": names}
        return (*drawn, notice(results) if notice else "", kept, False, False) + idle + ("100", "")

    @dash.callback(*outputs, *tail, *state, Input(group.run, "n_clicks"), *triggers, *states,
                   prevent_initial_call=not initial)
    def dispatch(_n, *values):
        """Answer at once when every result is cached; otherwise submit jobs and start reading them."""
        loading = dash.ctx.triggered_id is None  # the page's first call, not a user's action
        try:
            wanted = canonical(analysis, requests(*values))
            names = None if labels is None else _names(labels(*values), wanted)
        except InvalidParameterError as exc:
            if loading:  # the layout already says what of the address could not be used
                return (no_update,) * (n_out + len(tail) + len(state))
            return refused(str(exc), clear=True)
        results = [cache.get(analysis, r) for r in wanted]
        if all(r is not None for r in results):
            return shown(results, wanted, names)
        if loading and initial == "cached":
            return (no_update,) * (n_out + len(tail) + len(state))
        try:
            ids = [jobs.submit_canonical(analysis, r)["id"] for r, done in zip(wanted, results, strict=True)
                   if done is None]
        except jobs.QueueFull as exc:
            return refused(f"The service is busy: {exc}.")
        busy = running() if running is not None else (no_update,) * n_out
        go = {"jobs": ids, "requests": wanted, **({} if names is None else {"labels": names})}
        return (tuple(busy) + (no_update,) * len(tail) + (go, False, True, False)
                + tuple(True for _ in lock) + ("0", f"queued: {_asked(wanted)}"))

    @dash.callback(*(_duplicate(o) for o in [*outputs, *tail, *state]), Output(group.ready, "data"),
                   Input(group.poll, "n_intervals"), State(group.go, "data"), prevent_initial_call=True)
    def poll(_n, go):
        """Progress of the page's jobs; once every result is in the cache, the interval stops and
        the ready store tells :func:`show` to draw them."""
        ids, wanted = _waiting(go)
        if not ids:
            return (no_update,) * (n_out + len(tail)) + idle + (no_update, no_update, no_update)
        current = [jobs.get(i) for i in ids]
        for job in current:
            if job is None or job["status"] == "cancelled":
                return (*refused("", "cancelled"), no_update)
            if job["status"] == "failed":
                return (*refused(f"{job['request'].get('config') or analysis}: {job['error']}"), no_update)
        if all(job["status"] == "done" for job in current):  # drawn by show(), not in this tick
            return ((no_update,) * (n_out + len(tail)) + (no_update, True, no_update, True)
                    + (no_update,) * len(lock) + ("100", "drawing the results…", {**go, "tick": _n}))
        fraction = sum(job["progress"] if job["status"] == "running" else 0.0 for job in current) / len(current)
        first = next(job for job in current if job["status"] != "done")
        label = first["request"].get("config") or analysis
        done = sum(job["status"] == "done" for job in current)
        of = f" [{done} of {len(current)} analyses done]" if len(current) > 1 else ""
        status = (f"{label}: {first['message']}{of}" if first["status"] == "running"
                  else f"{label}: queued ({jobs.counts()['running']} analyses running){of}")
        return (no_update,) * (n_out + len(tail) + len(state) - 2) + (str(int(100 * fraction)), status, no_update)

    @dash.callback(*(_duplicate(o) for o in [*outputs, *tail, *state]), Input(group.ready, "data"),
                   prevent_initial_call=True)
    def show(ready):
        """The results of the jobs the poll found done, drawn (once per ready signal)."""
        ids, wanted = _waiting(ready)
        if not ids:
            return (no_update,) * (n_out + len(tail) + len(state))
        try:  # the requests came back through the browser's JSON (150000.0 as 150000): canonical again
            wanted = canonical(analysis, wanted)
            names = None if labels is None else _names(ready.get("labels"), wanted)
        except InvalidParameterError as exc:
            return refused(str(exc))
        results = [cache.get(analysis, r) for r in wanted]
        if any(r is None for r in results):
            return refused("A result left the cache before it could be shown; press Compute again.")
        return shown(results, wanted, names)

    @dash.callback(Output(group.cancel, "disabled", allow_duplicate=True),
                   Output(group.status, "children", allow_duplicate=True),
                   Input(group.cancel, "n_clicks"), State(group.go, "data"), prevent_initial_call=True)
    def cancel(_n, go):
        """Cancel the jobs; the poll, the one writer of the page's job state, then says "cancelled" (a
        poll already on its way cannot overwrite it with a progress line)."""
        ids, _ = _waiting(go)
        for job_id in ids:
            jobs.cancel(job_id, remove=False)
        return True, "cancelling…" if ids else "cancelled"

    @dash.callback(Output(files.download, "data"), Input(files.csv, "n_clicks"), Input(files.json, "n_clicks"),
                   State(store, "data"), prevent_initial_call=True)
    def save(_csv, _json, kept):
        wanted, names = (kept.get("requests"), kept.get("labels")) if isinstance(kept, dict) else (kept, None)
        if not wanted:
            return no_update
        try:
            wanted = canonical(analysis, wanted)
            names = None if labels is None else _names(names, wanted)
            results = [cache.get(analysis, r) for r in wanted]
        except InvalidParameterError:
            return no_update
        if any(r is None for r in results):  # evicted from the cache since it was drawn: compute again first
            return no_update
        name = download.filename(results) if download.filename else download.name
        if dash.ctx.triggered_id == files.json:
            return {"content": components.json_text(results[0] if download.single else results),
                    "filename": f"{name}.json"}
        columns, rows = download.rows(results) if labels is None else download.rows(results, names)
        return {"content": components.csv_text(columns, rows), "filename": f"{name}.csv"}


def _names(names: Any, wanted: list[dict[str, Any]]) -> list[str]:
    """One short name per request (as the client sent them back: checked, never trusted)."""
    if (not isinstance(names, list) or len(names) != len(wanted)
            or not all(isinstance(n, str) and 0 < len(n) <= 120 for n in names)):
        raise InvalidParameterError("labels", names, f"{len(wanted)} names, one per analysis",
                                    message="two of the designs ask for the same analysis" if isinstance(names, list)
                                    and len(names) > len(wanted) else "the names of the analyses are missing")
    return names


def _asked(wanted: list[dict[str, Any]]) -> str:
    """What was asked, in the page's words: the configurations (and a map's slices as asked)."""
    configs = [r.get("config") for r in wanted if r.get("config")]
    slices = {r.get("resolution") for r in wanted if r.get("resolution") is not None}
    what = ", ".join(configs) if configs else f"{len(wanted)} analysis" + ("" if len(wanted) == 1 else "es")
    return what + (f", {slices.pop()} Fz slices each" if len(slices) == 1 else "")


def _waiting(go: Any) -> tuple[list[str], list[dict[str, Any]]]:
    """The job ids and requests of the store (as the client sent it back: bounded, strings only)."""
    if not isinstance(go, dict):
        return [], []
    ids, wanted = go.get("jobs"), go.get("requests")
    if (not isinstance(ids, list) or not isinstance(wanted, list) or len(ids) > settings.MAX_PAGE_REQUESTS
            or len(wanted) > settings.MAX_PAGE_REQUESTS or not all(isinstance(i, str) and len(i) < 64 for i in ids)):
        return [], []
    return ids, wanted


def _duplicate(output: Output) -> Output:
    return Output(output.component_id, output.component_property, allow_duplicate=True)
