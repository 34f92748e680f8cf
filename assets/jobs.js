/* The jobs a workbench page waits for, let go when the page is left (ui/jobs.py).

Each computation of a page submits its jobs on behalf of this view of the page: its "go" store names
the jobs and the view's token ("watcher"). When the page is left (another page of the workbench, the
same page with another address, a reload, another site, the tab closed), the service is told that this
view waits for them no more; it cancels those nobody else waits for, so that they hold no job slot. A
pair told twice (already released by a later action of the page, or finished) changes nothing. */
(function () {
    const LIMIT = 256;  // pairs kept: a view submits a few jobs per action (ui/jobs.py: MAX_RELEASED)
    const waiting = new Map();  // "id watcher" -> {id, watcher}

    function releaseUrl() {
        const config = document.getElementById("_dash-config");
        const prefix = config ? JSON.parse(config.textContent).requests_pathname_prefix || "/" : "/";
        return prefix + "_workbench/release";
    }

    function leave() {
        if (!waiting.size) { return; }
        const body = JSON.stringify({jobs: Array.from(waiting.values())});
        waiting.clear();
        // keepalive: the request outlives the page that sends it
        fetch(releaseUrl(), {method: "POST", keepalive: true, headers: {"Content-Type": "application/json"},
                             body: body}).catch(function () { /* the page is gone: nobody to tell */ });
    }

    // the watcher of a go store (or of an answer on its way), as ui/jobs.py's _watcher reads it
    function watcherOf(go) {
        const w = go && typeof go === "object" ? go.watcher : null;
        return typeof w === "string" && w.length > 0 && w.length <= 64 ? w : null;
    }

    window.addEventListener("pagehide", leave);
    window.dash_clientside = window.dash_clientside || {};
    window.dash_clientside.jobs = {
        // a computation's go store changed: remember the jobs it waits for
        watch: function (go) {
            if (!go || !Array.isArray(go.jobs) || typeof go.watcher !== "string") { return; }
            go.jobs.forEach(function (id) {
                if (typeof id !== "string") { return; }
                waiting.delete(id + " " + go.watcher);
                waiting.set(id + " " + go.watcher, {id: id, watcher: go.watcher});
            });
            while (waiting.size > LIMIT) { waiting.delete(waiting.keys().next().value); }
        },
        // Dash Pages' router is replacing the page (a navigation inside the workbench)
        left: function () { leave(); },
        // A read of the page's jobs has landed (ui/jobs.py: landing): its updated values by their place, applied
        // only if the page still waits for the jobs that read was of (a later action of the page that landed
        // first, a cached answer drawn at once, stands).
        landed: function (landed, go) {
            // dropped whole, not answered no_update (Dash re-renders each output a clientside callback declares)
            if (!landed || !Number.isInteger(landed.n) || !Array.isArray(landed.set) || !landed.set.length
                    || watcherOf(landed) !== watcherOf(go)) {
                throw window.dash_clientside.PreventUpdate;
            }
            const out = new Array(landed.n).fill(window.dash_clientside.no_update);
            landed.set.forEach(function (pair) {
                if (Array.isArray(pair) && Number.isInteger(pair[0]) && pair[0] >= 0 && pair[0] < landed.n) {
                    out[pair[0]] = pair[1];
                }
            });
            return out;
        }
    };
})();
