"""One component for a page's long computation: Compute and Cancel buttons, a progress bar,
an answer at once from the cache, a background job otherwise, and CSV/JSON downloads.

A page lays out :func:`controls` (ids PREFIX-run, PREFIX-cancel, PREFIX-progress, PREFIX-status)
and :func:`ui.components.downloads`, then calls :func:`register` with what is particular to it:
how its controls become requests, how results become its outputs, and how results become
CSV rows. The requests of the last answer are kept in a store so that the downloads serialise
exactly what is drawn, from the cache (a download never computes).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Sequence

import dash
from dash import Input, Output, State, dcc, html, no_update

from shimmy.errors import EXPECTED_ERRORS, InvalidParameterError
from shimmy.service import analyses

from . import components


def controls(prefix: str, label: str = "Compute") -> list:
    """The run and cancel buttons and the progress bar of a job."""
    return [html.Button(label, id=f"{prefix}-run"),
            html.Button("Cancel", id=f"{prefix}-cancel", className="secondary", disabled=True),
            components.progress_bar(prefix)]


def stores(prefix: str, store: str | None = None) -> list:
    """The store of the shown results' requests and the hand-over to the background job."""
    return [dcc.Store(id=store or f"{prefix}-requests"), dcc.Store(id=f"{prefix}-go")]


@dataclass(frozen=True)
class Download:
    """How a page's results become files: ``rows(results)`` -> (columns, rows) for the CSV."""

    prefix: str  # ids PREFIX-csv, PREFIX-json, PREFIX-download
    name: str  # file stem
    rows: Callable[[list[dict[str, Any]]], tuple[list[str], list[list[Any]]]]
    single: bool = False  # the page shows one result: its JSON is that result, not a list of one


def register(prefix: str, analysis: str, *, requests: Callable[..., list[dict[str, Any]]],
             render: Callable[[list[dict[str, Any]]], tuple], outputs: Sequence[Output], states: Sequence[State],
             download: Download, lock: Sequence[str] = (), store: str | None = None, interval: int = 250,
             error: str | None = None) -> None:
    """Wire the job of one page.

    ``requests(*state values)`` -> the analysis requests (may raise InvalidParameterError);
    ``render(results)`` -> one value per entry of ``outputs``; ``lock`` are ids of controls
    disabled while the job runs; ``error`` the id of the element that shows a refusal
    (PREFIX-error by default).
    """
    store = store or f"{prefix}-requests"
    error = error or f"{prefix}-error"
    n_out = len(outputs)
    tail = [Output(error, "children"), Output(store, "data"), Output(f"{download.prefix}-csv", "disabled"),
            Output(f"{download.prefix}-json", "disabled")]

    def refused(message: str) -> tuple:
        return (no_update,) * n_out + (message, no_update, True, True)

    @dash.callback(*outputs, *tail, Output(f"{prefix}-go", "data"), Input(f"{prefix}-run", "n_clicks"), *states,
                   prevent_initial_call=True)
    def dispatch(n, *values):
        """Answer at once when every result is cached; otherwise hand over to the background job."""
        try:
            wanted = requests(*values)
            results = [analyses.cached(analysis, r) for r in wanted]
        except InvalidParameterError as exc:
            return refused(str(exc)) + (no_update,)
        if all(r is not None for r in results):
            return (*render(results), "", wanted, False, False, no_update)
        return (no_update,) * (n_out + len(tail)) + (n,)

    running = [(Output(f"{prefix}-run", "disabled"), True, False),
               (Output(f"{prefix}-cancel", "disabled"), False, True),
               *((Output(name, "disabled"), True, False) for name in lock)]

    @dash.callback(*(_duplicate(o) for o in [*outputs, *tail]), Input(f"{prefix}-go", "data"), *states,
                   background=True, prevent_initial_call=True, interval=interval, running=running,
                   cancel=[Input(f"{prefix}-cancel", "n_clicks")],
                   progress=[Output(f"{prefix}-progress", "value"), Output(f"{prefix}-status", "children")])
    def compute(set_progress, _go, *values):
        try:
            wanted = requests(*values)
        except InvalidParameterError as exc:
            return refused(str(exc))
        results, message = run_each(analysis, wanted, set_progress)
        if message:
            return refused(message)
        return (*render(results), "", wanted, False, False)

    @dash.callback(Output(f"{download.prefix}-download", "data"), Input(f"{download.prefix}-csv", "n_clicks"),
                   Input(f"{download.prefix}-json", "n_clicks"), State(store, "data"), prevent_initial_call=True)
    def save(_csv, _json, shown):
        if not shown:
            return no_update
        results = [analyses.cached(analysis, r) for r in shown]
        if any(r is None for r in results):  # evicted from the cache since it was drawn: compute again first
            return no_update
        if dash.ctx.triggered_id == f"{download.prefix}-json":
            return {"content": components.json_text(results[0] if download.single else results),
                    "filename": f"{download.name}.json"}
        columns, rows = download.rows(results)
        return {"content": components.csv_text(columns, rows), "filename": f"{download.name}.csv"}


def _duplicate(output: Output) -> Output:
    return Output(output.component_id, output.component_property, allow_duplicate=True)


def run_each(analysis: str, requests: list[dict[str, Any]], set_progress) -> tuple[list[dict[str, Any]], str]:
    """Run ``analysis`` once per request inside a background callback, with one progress bar over
    all of them: (results, "") or ([], the error message naming the field)."""
    from . import style

    results = []
    for k, request in enumerate(requests):
        config = request.get("config")
        label = style.CONFIG_LABELS.get(config, analysis) if config else analysis

        def report(fraction, message, k=k, label=label):
            set_progress((str(int(100 * (k + fraction) / len(requests))), f"{label}: {message}"))

        report(0.0, "starting")
        try:
            result, _ = analyses.run(analysis, request, report)
        except InvalidParameterError as exc:
            return [], str(exc)
        except EXPECTED_ERRORS as exc:
            return [], f"{config or analysis}: {exc}"
        results.append(result)
    set_progress(("100", "done"))
    return results, ""
