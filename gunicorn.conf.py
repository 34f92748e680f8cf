"""gunicorn settings read by every ``gunicorn app:server`` started from this folder (README,
Dockerfile, tests, benchmarks): gunicorn loads ./gunicorn.conf.py by default.

The arbiter becomes the child subreaper of everything started below it: a job worker whose
web worker died (killed, timed out, restarted) is adopted by the arbiter instead of PID 1,
and the arbiter's SIGCHLD handler reaps every child it has (gunicorn reaps unknown children),
so no job process is left a zombie where PID 1 does not reap (a bare container or sandbox).
"""

import ctypes
import sys

# Slow clients: gunicorn's asyncio worker reads every connection in its event loop and the WSGI
# app runs on complete requests only (shimmy/service/buffered.py).
worker_class = "shimmy.service.buffered.BufferingWorker"

PR_SET_CHILD_SUBREAPER = 36


def on_starting(server):
    if sys.platform.startswith("linux"):
        libc = ctypes.CDLL(None, use_errno=True)
        if libc.prctl(PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) != 0:
            server.log.warning("could not become the child subreaper (errno %d)", ctypes.get_errno())


def post_worker_init(worker):
    """Load the numba kernels before the worker takes requests (shimmy.service.warmup), so that no
    user's first answer waits for them."""
    from shimmy.service.warmup import warm_kernels

    worker.log.info("kernels loaded in %.1f s", warm_kernels())
