"""One component for a page's long computation: Compute and Cancel buttons, a progress bar,
an answer at once from the cache, jobs of the service otherwise, and CSV/JSON downloads.

A page lays out :func:`controls` (the run and cancel buttons, progress and poll of an
:class:`ui.ids.Group`) and :func:`ui.components.downloads`, then calls :func:`register` with what is
particular to it: how its controls become requests, how results become its outputs, and how
results become CSV rows.

Nothing is computed in the web worker and no process is started by Dash: a Compute submits
one job per uncached request through :mod:`shimmy.service.jobs`, the admission control the
API uses (bounded queue, identical requests shared, a full queue refused with a message), and
an interval reads the jobs' progress until every result is in the cache (a read that finds nothing
new waits briefly for the jobs to end, :data:`WAIT_S`, so that a result is drawn when it is ready
rather than at the next read). The interval's
callback only says so (a small answer that stops the interval); a second callback, triggered
once by that, draws the results. Dash drops the answer of a callback whose input changed again
while it ran (plotly/dash#1613), so a poll that drew a large figure more slowly than the
interval (a loaded machine, a long time history) was dropped on every tick and the page never
showed its result. Both answers reach the page through a check in the browser (:func:`landing`): one
that lands after a later action of the page (its answer already drawn) is dropped. At most
``MAX_PAGE_REQUESTS`` requests per action. The requests of the last answer are kept in a
store so that the downloads serialise exactly what is drawn, from the cache (a download never
computes).

A page computes nothing on opening: it shows the cached answer to its controls, or waits for its
run button. Its jobs are submitted on behalf of one action of this view of the page (a watcher
token, :func:`shimmy.service.jobs.release`), and let go as soon as the page waits for them no more:
when a later action of the page asks something else, when Cancel is pressed, and when the page is
left (``assets/jobs.js`` posts them to :data:`RELEASE_PATH` on a navigation or as the page goes).
The service then cancels the jobs nobody else waits for, so that they hold no job slot and nobody's
next job queues behind them; a job another page or an API client waits for goes on.
"""

from __future__ import annotations

import math
import time
import uuid
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import dash
import flask
from dash import ClientsideFunction, Input, Output, State, dcc, html, no_update

from shimmy.errors import InvalidParameterError
from shimmy.service import admission, cache, jobs, schemas, settings
from shimmy.service.api import RequestRefused, parse_json

from . import components, ids as shell_ids
from .ids import Group

#: Where a page that is left lets its jobs go (under the app's path prefix; assets/jobs.js posts there).
RELEASE_PATH = "_workbench/release"
#: (job, watcher) pairs one post may let go (assets/jobs.js keeps as many per page view).
MAX_RELEASED = 256


#: How often a page reads its jobs' progress while they run (ms).
POLL_MS = 400
#: A read that finds the page's jobs all running (or some done) and nothing new to show waits up to this
#: long (s) for something to show, reading the job store every WAIT_STEP_S: a job that ends meanwhile is
#: drawn at once instead of at the next read (on average half an interval later). Half the interval,
#: so that the answer is back before the next read is sent (Dash drops the answer of a callback whose
#: input changed while it was on its way, plotly/dash#1613) unless the round trip takes over 0.2 s; and
#: the wait ends at once when anything the answer shows changes (a status, the progress or its message,
#: the clock's second; a sketch due), so that an answer dropped so is one that showed nothing new. While
#: a page follows the design by itself (a step of a second or two) only a status ends it: the progress
#: line may then lag by a read. A queued job is not waited for.
WAIT_S = 0.5 * POLL_MS / 1000
WAIT_STEP_S = 0.02
#: While a page follows the design by itself (a warm map of a second or two): its sketch is redrawn at
#: most this often (s), and the veiled figure's clock only when its whole seconds change. Each redraw of
#: the map figure takes the browser ~0.1 s of CPU and the server some, from the two cores the job's
#: workers use: redrawn at every read (six to eight times a step) they made the nes warm job 2.4-2.5 s
#: instead of 2.1-2.2 s. The first sketch (the new Hopf curves) is drawn as soon as it is known.
LIVE_SKETCH_S = 1.0


def controls(group: Group, label: str = "Compute") -> list:
    """The run and cancel buttons, the progress bar of a job and the interval that reads it."""
    return [html.Button(label, id=group.run),
            html.Button("Cancel", id=group.cancel, className="secondary", disabled=True),
            components.progress_bar(group),
            dcc.Interval(id=group.poll, interval=POLL_MS, disabled=True)]


def stores(group: Group) -> list:
    """The store of the shown results' requests, the ids of the jobs being waited for, the jobs
    whose results are ready to be drawn, what of the jobs' sketches is drawn, and the answers of a read
    of the jobs and of a draw of their results on their way to the page (:func:`landing`)."""
    return [dcc.Store(id=group.requests), dcc.Store(id=group.go), dcc.Store(id=group.ready),
            dcc.Store(id=group.sketched), dcc.Store(id=group.landed), dcc.Store(id=group.drawn)]


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
    out = []
    for body in wanted:  # the same request twice is one (two designs may still share a cached result)
        request = schemas.validate(analysis, body)
        if request not in out:
            out.append(request)
    if len(out) > settings.MAX_PAGE_REQUESTS:
        raise InvalidParameterError("configs", len(out), f"at most {settings.MAX_PAGE_REQUESTS} analyses at once",
                                    "asks for too many analyses")
    return out


def register(group: Group, analysis: str, *, requests: Callable[..., list[dict[str, Any]]],
             render: Callable[[list[dict[str, Any]]], tuple], outputs: Sequence[Output], states: Sequence[State],
             download: Download, lock: Sequence[str] = (), error: str | None = None,
             triggers: Sequence[Input] = (), follow: Sequence[Input] = (),
             notice: Callable[[list[dict[str, Any]]], str] | None = None,
             blank: Callable[[], tuple] | None = None, running: Callable[[], tuple] | None = None,
             waiting: Callable[[], tuple] | None = None,
             clock: Callable[[float, str], tuple] | None = None,
             warm: Callable[[list[dict[str, Any]]], bool] | None = None,
             fading: Callable[[float, str], tuple] | None = None, stale: str | None = None,
             labels: Callable[..., list[str]] | None = None,
             sketch: Callable[[list[dict[str, Any] | None], list[dict[str, Any]] | None, bool], tuple] | None = None
             ) -> None:
    """Wire the job of one page.

    ``requests(*trigger values, *follow values, *state values)`` -> the analysis requests (may raise
    InvalidParameterError); ``render(results)`` -> one value per entry of ``outputs``;
    ``lock`` are ids of controls disabled while the jobs run; ``error`` the id of the element
    that shows a refusal (the group's error line by default), ``notice(results)`` what it shows with a
    result; ``triggers`` inputs that start a computation besides the run button (a user's action
    on the page's own question: a typed speed, an operating point). ``follow`` are inputs the shown
    answer follows: the cached answer to the new controls is shown, and the jobs being waited for
    are asked again for them, but nothing starts from them alone (a choice the page shares with
    other sections, or of what to draw). When the page loads it shows the answer to its controls if
    the cache has it and computes nothing otherwise. ``blank()`` -> the
    outputs that replace a shown result when the controls are refused (the old result no longer
    answers them); ``running()`` -> the outputs shown while the jobs run (default: the old ones stay),
    and ``waiting()`` those of a page waiting for its button (as its layout has them), shown in their
    place when the jobs end without a result (cancelled, failed). ``clock(seconds, asked)`` -> the
    outputs shown while the jobs run, redrawn at every read of their progress with the seconds since
    they were asked for and what was asked, in words (a long run the user watches being made; in
    place of ``running()``).
    ``warm(uncached requests)`` -> whether a change of a ``follow`` input computes by itself (a map
    one slider step from a cached one, warmed from it in a second or two: the page follows the
    slider); the outputs then are ``fading(seconds, asked)`` while the jobs run (the previous answer
    kept, faint, for comparison until the new one lands) in place of ``clock``. Where ``warm`` says
    no, the status line says ``stale`` (the shown answer is of the previous controls), if given.
    ``labels(*values)`` -> a name for each request (the designs of a comparison): the results are then
    drawn by ``render(results, names)`` and tabulated by ``download.rows(results, names)``, and the
    requests store holds {"requests", "labels"}.
    ``sketch(sketches, previous, live)`` -> the outputs drawn from what the running jobs know so far
    (``job["sketch"]`` of each, None where a job has none; a map's curves before its shading), over
    ``previous``, the results shown until now (None if none), ``live`` where the run follows the design
    by itself; redrawn each time a sketch grows (while the page follows the design by itself, at most every
    LIVE_SKETCH_S), and in place of the clock and the fading once drawn.
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

    def stopped(message: str, status: str = "") -> tuple:
        """The jobs ended without a result: what running() put in place of the old outputs goes too."""
        if (running is not None or clock is not None or fading is not None) and waiting is not None:
            return (*waiting(), message, None, True, True) + idle + ("0", status)
        return refused(message, status)

    def shown(results: list[dict[str, Any]], wanted: list[dict[str, Any]], names: list[str] | None) -> tuple:
        drawn = render(results) if labels is None else render(results, names)
        kept = wanted if labels is None else {"requests": wanted, "labels": names}
        return (*drawn, notice(results) if notice else "", kept, False, False) + idle + ("100", "")

    following = {i.component_id for i in follow}
    nothing = (no_update,) * (n_out + len(tail) + len(state))

    @dash.callback(*outputs, *tail, *state, Input(group.run, "n_clicks"), *triggers, *follow, *states,
                   State(group.go, "data"), prevent_initial_call=False)
    def dispatch(_n, *values):
        """Answer at once when every result is cached; otherwise, on the run button or a trigger,
        submit jobs and start reading them. The jobs the page waited for until now and no longer
        asks for are let go (after the new ones are submitted: one both ask for is never cancelled)."""
        *values, previous = values
        trigger = dash.ctx.triggered_id
        loading = trigger is None  # the page's first call, not a user's action
        before, before_watcher = _waiting(previous)[0], _watcher(previous)
        waited = bool(before) and not previous.get("cancelled")
        try:
            wanted = canonical(analysis, requests(*values))
            names = None if labels is None else _names(labels(*values), wanted)
        except InvalidParameterError as exc:
            if loading:  # the layout already says what of the address could not be used
                return nothing
            _release(before, before_watcher)
            return refused(str(exc), clear=True)
        results = [cache.get(analysis, r) for r in wanted]
        if all(r is not None for r in results):
            _release(before, before_watcher)
            return shown(results, wanted, names)
        live = (not loading and trigger in following and warm is not None
                and warm([r for r, done in zip(wanted, results, strict=True) if done is None]))
        if loading:
            return nothing
        if trigger in following and not live and not (waited and not previous.get("live")):
            # nobody asked for a computation: a change followed by itself computes only where warm says
            if waited:  # a run the page started by itself for an earlier design: let it go
                _release(before, before_watcher)
                return stopped("", stale or "")
            return nothing[:-1] + (stale if stale is not None else no_update,)
        watcher, ids = uuid.uuid4().hex, []
        try:
            for r, done in zip(wanted, results, strict=True):
                if done is None:
                    ids.append(jobs.submit_canonical(analysis, r, watcher, user=admission.requester())["id"])
        except jobs.QueueFull as exc:
            _release(ids, watcher)
            _release(before, before_watcher)
            return refused(f"The service is busy: {exc}.")
        _release(before, before_watcher)
        busy = (fading(0.0, _asked(wanted)) if live and fading is not None else clock(0.0, _asked(wanted))
                if clock is not None else running() if running is not None else (no_update,) * n_out)
        go = {"jobs": ids, "requests": wanted, "watcher": watcher, "asked": time.time(), "live": bool(live),
              **({} if names is None else {"labels": names})}
        return (tuple(busy) + (no_update,) * len(tail) + (go, False, True, False)
                + tuple(True for _ in lock) + ("0", f"queued: {_asked(wanted)}"))

    # The answers of poll and show land through the page's check (landing); each through its own store, so that
    # the chain poll -> ready -> show -> page has no loop (Dash holds a callback back while any callback running
    # could still change one of its inputs: show, in a loop back to its own ready, would wait for ever).
    page = [_duplicate(o) for o in [*outputs, *tail, *state]]
    dash.clientside_callback(ClientsideFunction("jobs", "landed"), *page, Output(group.ready, "data"),
                             Output(group.sketched, "data"), Input(group.landed, "data"), State(group.go, "data"),
                             prevent_initial_call=True)
    dash.clientside_callback(ClientsideFunction("jobs", "landed"), *page,
                             Input(group.drawn, "data"), State(group.go, "data"), prevent_initial_call=True)

    @dash.callback(Output(group.landed, "data"), Input(group.poll, "n_intervals"),
                   State(group.go, "data"), State(group.progress, "value"), State(group.sketched, "data"),
                   State(store, "data"), prevent_initial_call=True)
    def poll(_n, go, shown_progress, sketched, kept):
        """Progress of the page's jobs; once every result is in the cache, the interval stops and
        the ready store tells :func:`show` to draw them. A poll that finds its jobs let go by a later
        action of the page changes nothing: that action wrote the page's state. While they run, what
        they know so far is drawn by ``sketch`` each time it grows. The answer lands through
        :func:`landing` (dropped there if a later action of the page came first)."""
        return landing(go, read(_n, go, shown_progress, sketched, kept))

    def read(_n, go, shown_progress, sketched, kept):
        """What :func:`poll` answers: the page's outputs, its state, the ready and sketched stores."""
        ids, wanted = _waiting(go)
        if not ids:
            return (no_update,) * (n_out + len(tail)) + idle + (no_update, no_update, no_update, no_update)
        watcher = _watcher(go)
        if go.get("cancelled"):  # the Cancel button let them go; the poll says so (no late progress line after it)
            return (*stopped("", "cancelled"), no_update, no_update)
        live = bool(go.get("live")) and fading is not None

        def shows(records) -> list:  # what this read's answer would show (a live step: its statuses)
            out = [None if job is None else job["status"] for job in records]
            if live:
                return out
            since_now = _since(go.get("asked")) if clock is not None else None
            return out + [None if job is None else (job.get("progress"), job.get("message")) for job in records] \
                + [None if since_now is None else int(since_now)]

        current = _awaited(ids, [jobs.get(i) for i in ids], shows,
                           lambda records: sketch is not None and _sketch_due(records, ids, sketched, live))
        if any(job is not None and _let_go(job, watcher) for job in current):
            return nothing + (no_update, no_update)
        for job in current:
            if job is None or job["status"] == "cancelled":
                _release(ids, watcher)
                return (*stopped("", "cancelled"), no_update, no_update)
            if job["status"] == "failed":
                _release(ids, watcher)
                return (*stopped(f"{job['request'].get('config') or analysis}: {job['error']}"), no_update,
                        no_update)
        if all(job["status"] == "done" for job in current):  # drawn by show(), not in this tick
            return ((no_update,) * (n_out + len(tail)) + (no_update, True, no_update, True)
                    + (no_update,) * len(lock) + ("100", "drawing the results…", {**go, "tick": _n}, no_update))
        # a finished job counts whole, a queued one nothing; the bar never goes back within a run
        fraction = sum(_fraction(job) for job in current) / len(current)
        fraction = max(fraction, min(_number(shown_progress) / 100, 1.0))
        first = next(job for job in current if job["status"] != "done")
        label = first["request"].get("config") or analysis
        done = sum(job["status"] == "done" for job in current)
        of = f" [{done} of {len(current)} analyses done]" if len(current) > 1 else ""
        status = (f"{label}: {first['message']}{of}" if first["status"] == "running"
                  else f"{label}: queued ({jobs.counts()['running']} analyses running){of}")
        since = _since(go.get("asked"))
        show_clock = fading if live else clock
        mark = no_update
        if live and since is not None:  # the veiled figure's clock: redrawn only when its whole seconds change
            second = _clock_drawn(sketched, ids)
            if int(since) == (0 if second is None else second):  # (the run's first answer drew 0 s)
                show_clock = None
            else:
                same = isinstance(sketched, dict) and sketched.get("jobs") == list(ids)
                mark = {**(sketched if same else {"jobs": ids}), "clock": int(since)}
        drawn = (show_clock(since, _asked(wanted)) if show_clock is not None and since is not None
                 else (no_update,) * n_out)
        if sketch is not None and _sketch_due(current, ids, sketched, live):
            sketches = [job.get("sketch") if job["status"] == "running" else None for job in current]
            drawn = sketch(sketches, _shown(analysis, kept), bool(go.get("live")))
            mark = {"jobs": ids, "sizes": [_size(s) for s in sketches], "at": time.time()}
        elif _sketch_drawn(sketched, ids):  # the sketch stays until the answer (no clock or veil over it)
            drawn, mark = (no_update,) * n_out, no_update
        return (*drawn, *(no_update,) * (len(tail) + len(state) - 2), str(int(100 * fraction)), status, no_update,
                mark)

    @dash.callback(Output(group.drawn, "data"), Input(group.ready, "data"), State(group.go, "data"),
                   prevent_initial_call=True)
    def show(ready, go):
        """The results of the jobs the poll found done, drawn (once per ready signal), unless a later action
        of the page let them go between the poll and this draw (a cached answer to new controls drawn
        already, or other jobs asked for): the page's store no longer waits for them, or the service says
        its watcher is gone. Drawn then, they would replace the newer answer with the older one. Where the
        store still names them and only the service saw them let go, the Cancel button raced the poll: the
        page says "cancelled" and its controls come back. A later action that comes while this draw is on
        its way is seen by :func:`landing`."""
        return landing(go, draw(ready, go))

    def draw(ready, go):
        """What :func:`show` answers: the page's outputs and state."""
        ids, wanted = _waiting(ready)
        if not ids or _waiting(go)[0] != ids or _watcher(go) != _watcher(ready):
            return nothing  # a later action of the page asked for other jobs or drew an answer: its state stands
        if not _still_awaited(ready, go):  # the page still names them, the service saw them let go: a Cancel
            return stopped("", "cancelled")  # that raced this poll (the poll is off: nobody else says so)
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
                   Output(group.go, "data", allow_duplicate=True),
                   Input(group.cancel, "n_clicks"), State(group.go, "data"), prevent_initial_call=True)
    def cancel(_n, go):
        """Let the jobs go (the service cancels those nobody else waits for); the poll's next read then says
        "cancelled" (a read already on its way may still say their progress, not after that one)."""
        ids, _ = _waiting(go)
        _release(ids, _watcher(go))
        if not ids:
            return True, "cancelled", no_update
        return True, "cancelling…", {**go, "cancelled": True}

    # The browser remembers the jobs the page waits for, to let them go when the page is left.
    dash.clientside_callback(ClientsideFunction("jobs", "watch"), Input(group.go, "data"))

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
    wanted = [r for r in wanted if isinstance(r, dict)]  # the poll's come back through the browser
    configs = [str(r["config"])[:40] for r in wanted if r.get("config")]
    slices = {str(r["resolution"])[:8] for r in wanted if r.get("resolution") is not None}
    what = ", ".join(configs) if configs else f"{len(wanted)} analysis" + ("" if len(wanted) == 1 else "es")
    each = " each" if len(wanted) > 1 else ""
    return what + (f", {slices.pop()} Fz slices{each}" if len(slices) == 1 else "")


def landing(go: Any, values: Sequence[Any]) -> dict[str, Any]:
    """A read of the page's jobs or a draw of their results on its way to the page: ``values`` (one per output
    of its check: the page's outputs, its state, after a read the ready and sketched stores), sent as the
    updated ones by their place, with the watcher of the jobs read (``go`` as the read found it). The page
    applies them only if its store still names that watcher when they land (``jobs.landed`` in
    ``assets/jobs.js``).

    Dash orders nothing between two callbacks that write the same outputs: a cached answer drawn at once by a
    later action (a typed speed back to one computed before) could land before the draw of the jobs it let go
    that was already on its way, and that draw, landing last, replaced the newer answer with the older one
    (the figure of 51 m/s under boxes saying 50). The page applies callbacks' answers one at a time, so the
    check there sees every action that landed before."""
    changed = [[k, v] for k, v in enumerate(values) if v is not no_update]
    return {"watcher": _watcher(go), "n": len(values), "set": changed, "id": uuid.uuid4().hex}


def _waiting(go: Any) -> tuple[list[str], list[dict[str, Any]]]:
    """The job ids and requests of the store (as the client sent it back: bounded, strings only)."""
    if not isinstance(go, dict):
        return [], []
    ids, wanted = go.get("jobs"), go.get("requests")
    if (not isinstance(ids, list) or not isinstance(wanted, list) or len(ids) > settings.MAX_PAGE_REQUESTS
            or len(wanted) > settings.MAX_PAGE_REQUESTS or not all(isinstance(i, str) and len(i) < 64 for i in ids)):
        return [], []
    return ids, wanted


def _still_awaited(ready: Any, go: Any) -> bool:
    """Whether the page still waits for the jobs the poll found done (``ready``): its store of the jobs it
    waits for (``go``) names the same jobs for the same watcher, and the service has not seen that watcher
    let any of them go (a later action of the page, whose answer the page may have drawn already)."""
    ids, watcher = _waiting(ready)[0], _watcher(ready)
    if not ids or _waiting(go)[0] != ids or _watcher(go) != watcher:
        return False
    return not any(job is not None and _let_go(job, watcher) for job in map(jobs.peek, ids))


def _size(sketch: Any) -> int:
    """How much a job's sketch holds (it only grows while the job runs): its lists' items, those of
    lists of lists (a map's curves: their points) counted one by one."""
    if not isinstance(sketch, dict):
        return 0
    return sum(len(item) if isinstance(item, list) else 1 for v in sketch.values() if isinstance(v, list)
               for item in v)


def _shown(analysis: str, kept: Any) -> list[dict[str, Any]] | None:
    """The results shown until now (the requests store's), from the cache; None if any is gone."""
    wanted = kept.get("requests") if isinstance(kept, dict) else kept
    if not wanted:
        return None
    try:
        results = [cache.get(analysis, r) for r in canonical(analysis, wanted)]
    except InvalidParameterError:
        return None
    return None if any(r is None for r in results) else results


def _awaited(ids: Sequence[str], current: list[dict[str, Any] | None], shows: Callable[[list], list],
             due: Callable[[list], bool]) -> list[dict[str, Any] | None]:
    """The jobs' records (``current``, as just read), read again (:func:`~shimmy.service.jobs.peek`) every
    WAIT_STEP_S for up to WAIT_S while all are running or done, not all done, and nothing is ``due`` to be
    drawn; as soon as what the answer ``shows`` changes, or a sketch is due."""
    statuses = [None if job is None else job["status"] for job in current]
    if not (all(s in ("running", "done") for s in statuses) and "running" in statuses):
        return current
    before = shows(current)
    deadline = time.monotonic() + WAIT_S
    while not due(current) and time.monotonic() < deadline:
        time.sleep(WAIT_STEP_S)
        current = [jobs.peek(i) for i in ids]
        if shows(current) != before:
            break
    return current


def _sketch_drawn(sketched: Any, ids: Sequence[str]) -> bool:
    """Whether the page drew a sketch of these jobs (the stamp of the last one it drew)."""
    return isinstance(sketched, dict) and sketched.get("jobs") == list(ids) and "sizes" in sketched


def _sketch_due(records: list[dict[str, Any] | None], ids: Sequence[str], sketched: Any, live: bool) -> bool:
    """Whether the running jobs' sketches grew since the page drew them (``sketched``: the stamp of the
    last one drawn) and may be drawn now: at once, but while the page follows the design by itself at
    most every LIVE_SKETCH_S."""
    if any(job is None for job in records):
        return False
    sizes = [_size(job.get("sketch")) if job["status"] == "running" else 0 for job in records]
    drawn = _sketch_drawn(sketched, ids)
    if not any(sizes) or (drawn and sketched.get("sizes") == sizes):
        return False
    last = _since(sketched.get("at")) if drawn else None
    return not (live and last is not None and last < LIVE_SKETCH_S)


def _clock_drawn(sketched: Any, ids: Sequence[str]) -> int | None:
    """The whole seconds the veiled figure's clock last showed for these jobs (None: not drawn since)."""
    if not (isinstance(sketched, dict) and sketched.get("jobs") == list(ids)):
        return None
    shown = sketched.get("clock")
    return shown if isinstance(shown, int) and not isinstance(shown, bool) else None


def _fraction(job: dict[str, Any]) -> float:
    """How much of ``job`` is done: 1 once done, its reported progress while it runs, 0 queued."""
    return 1.0 if job["status"] == "done" else job["progress"] if job["status"] == "running" else 0.0


def _since(asked: Any) -> float | None:
    """Seconds since ``asked`` (a time the page's store sent back), or None if it is not one."""
    if isinstance(asked, bool) or not isinstance(asked, (int, float)) or not 0 < asked <= time.time():
        return None
    return time.time() - asked


def _number(value: Any) -> float:
    """A finite number the browser sent back (the progress bar's value, a time), else 0."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        return 0.0
    return x if math.isfinite(x) else 0.0


def _watcher(go: Any) -> str | None:
    """The token of the page view's action that submitted the store's jobs (None if there is none)."""
    watcher = go.get("watcher") if isinstance(go, dict) else None
    return watcher if isinstance(watcher, str) and 0 < len(watcher) <= 64 else None


def _let_go(job: dict[str, Any], watcher: str | None) -> bool:
    """The page view no longer waits for ``job``: a later action of the page let it go."""
    return watcher is not None and not job.get("pinned", True) and watcher not in job.get("watchers", [])


def _release(ids: Sequence[str], watcher: str | None) -> None:
    """The page waits for these jobs no more (the service cancels those nobody else waits for)."""
    if watcher is not None:
        for job_id in ids:
            jobs.release(job_id, watcher)


def released(body: Any) -> list[tuple[str, str]]:
    """The (job id, watcher) pairs of a release post (as the browser sent it: checked, never trusted)."""
    pairs = body.get("jobs") if isinstance(body, dict) else None
    if not isinstance(pairs, list) or len(pairs) > MAX_RELEASED:
        raise RequestRefused("jobs must list the jobs to let go", "jobs",
                             f"a list of at most {MAX_RELEASED} {{id, watcher}} objects")
    out = []
    for k, pair in enumerate(pairs):
        job_id = pair.get("id") if isinstance(pair, dict) else None
        watcher = _watcher(pair)
        if not (isinstance(job_id, str) and 0 < len(job_id) <= 64 and watcher is not None):
            raise RequestRefused(f"jobs[{k}] is not an {{id, watcher}} object of two short strings", f"jobs[{k}]",
                                 "an object with an id and a watcher of 1 to 64 characters")
        out.append((job_id, watcher))
    return out


def install(app) -> None:
    """The route by which a page that is left lets its jobs go (assets/jobs.js posts there), and the
    leave signal of a navigation inside the app (Dash Pages replaces the page without unloading it)."""

    def release_route():
        try:
            pairs = released(parse_json(flask.request))
        except RequestRefused as exc:
            return exc.response()
        for job_id, watcher in pairs:
            jobs.release(job_id, watcher)
        return flask.Response(status=204)

    app.server.add_url_rule(app.config.routes_pathname_prefix + RELEASE_PATH, "workbench_release", release_route,
                            methods=["POST"])
    app.clientside_callback(ClientsideFunction("jobs", "left"), Input(shell_ids.PAGES_LOCATION, "pathname"),
                            Input(shell_ids.PAGES_LOCATION, "search"), prevent_initial_call=True)


def _duplicate(output: Output) -> Output:
    return Output(output.component_id, output.component_property, allow_duplicate=True)
