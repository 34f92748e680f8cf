"""gunicorn settings read by every ``gunicorn app:server`` started from this folder (README,
Dockerfile, tests, benchmarks): gunicorn loads ./gunicorn.conf.py by default.

The arbiter becomes the child subreaper of everything started below it: a job worker whose
web worker died (killed, timed out, restarted) is adopted by the arbiter instead of PID 1,
and the arbiter's SIGCHLD handler reaps every child it has (gunicorn reaps unknown children),
so no job process is left a zombie where PID 1 does not reap (a bare container or sandbox).

Who may use the server depends on where it listens: ``on_starting`` reads gunicorn's ``bind``
setting (``--bind``, ``GUNICORN_CMD_ARGS`` or this file) and passes it to the app and its workers
as ``SHIMMY_LISTEN`` (behind ``python -m shimmy serve``, the proxy's address ``SHIMMY_PROXY_LISTEN``
stands for gunicorn's Unix socket); an address beyond loopback makes ``SHIMMY_AUTH=token`` the default and
refuses ``SHIMMY_AUTH=none`` unless ``SHIMMY_ALLOW_ANONYMOUS=1`` (shimmy.service.settings.auth_mode).
The server refuses to start then, saying why, before it binds anything.

Restarts: ``on_starting`` queues again the jobs whose process ended with the previous server (or
fails them, saying why, past the restarts allowed); each web worker starts the queued jobs on free
slots once its kernels are loaded (``post_worker_init``); ``on_exit`` (a graceful stop) ends the
running jobs' processes and queues them again at the head of the queue (shimmy.service.jobs).
"""

import ctypes
import os
import sys

# gunicorn's threaded worker: SHIMMY_WEB_THREADS threads per worker run the app (the quick computations'
# admission control counts on that many, shimmy.service.settings). A thread reads the request it serves, so
# slow clients are held in front of gunicorn by nginx (`python -m shimmy serve`, the image), which passes on
# complete requests only; gunicorn alone is for one user on loopback.
worker_class = "gthread"
threads = int(os.environ.get("SHIMMY_WEB_THREADS", "32"))

PR_SET_CHILD_SUBREAPER = 36


def on_starting(server):
    if sys.platform.startswith("linux"):
        libc = ctypes.CDLL(None, use_errno=True)
        if libc.prctl(PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) != 0:
            server.log.warning("could not become the child subreaper (errno %d)", ctypes.get_errno())
    os.environ["SHIMMY_LISTEN"] = ",".join(server.cfg.bind or [])
    from shimmy.service import cache, jobs, settings

    mode = settings.auth_mode()  # AuthSettingError (a RuntimeError): gunicorn prints it and exits with status 1
    server.log.info("listening on %s (reached at %s): authentication %s", os.environ["SHIMMY_LISTEN"],
                    ",".join(settings.listen_addresses()), mode)
    recovered = jobs.server_started()
    if recovered["requeued"] or recovered["failed"]:
        server.log.warning("jobs whose process ended with the previous server: %d queued again, %d failed",
                           len(recovered["requeued"]), len(recovered["failed"]))
    cache.close_all()  # no database connection of the arbiter's is inherited by the workers it forks


def post_worker_init(worker):
    """Load the numba kernels before the worker takes requests (shimmy.service.warmup), so that no
    user's first answer waits for them; then start queued jobs on free slots (after a restart)."""
    from shimmy.service import jobs
    from shimmy.service.warmup import warm_kernels

    worker.log.info("kernels loaded in %.1f s", warm_kernels())
    try:
        jobs.pump()
    except Exception as exc:  # noqa: BLE001 - a broken store is reported by health; the worker must serve
        worker.log.error("queued jobs not started: %s", exc)


def on_exit(server):
    """A graceful stop: the running jobs' processes end and their jobs wait queued for the next start."""
    from shimmy.service import jobs

    try:
        again = jobs.server_stopping()
    except Exception as exc:  # noqa: BLE001 - the server stops anyway; the next start fails them or runs them
        server.log.error("running jobs not queued again: %s", exc)
        return
    if again:
        server.log.info("%d running job(s) queued again for the next start", len(again))
